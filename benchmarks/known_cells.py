"""Where stopping on known cells changes a forced basin map's labels: a figure and a
table (issue 37).

For the Wada map of the maps guide (c = 0.2, A = 1.66, W = 1, cos forcing, theta0 in
[-pi, pi], omega0 in [-4, 4]) and the Baker-Gollub scene of ``examples/forced.toml``
(c = 0.5, A = 1.35, W = 2/3, theta0 and omega0 in [-pi, pi], dt = period / 1000), each
on its own grid, the labels of

- the full-length run (no early stop; the reference),
- ``known``: coarse maps of the window first (`sweep.maps.known.background`), then the
  map with ``stop_early``, the 41 x 41 pilot's catalogue and ``known_cells``,
- ``refine_known``: ``maps.refine(..., known_cells=True)``,

are compared start by start; the figure draws the reference's labels with the starts
each route labels differently. Process CPU times (all threads) of the catalogue route
(``stop_early`` with the catalogue) and of the two known-cells routes are set side by
side, each the best of two runs (the first compiles).

Usage::

    python benchmarks/known_cells.py [--wada 400] [--baker 200] [--figure PATH]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps
from sweep.maps.known import background

from _machine import machine


def scenes(wada: int, baker: int) -> dict:
    """The two scenes: (scene, grid, run arguments of the full run, of the early runs)."""
    period = 2 * np.pi
    wada_scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    wada_grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, wada),
                           omega0=np.linspace(-4.0, 4.0, wada))
    wada_full = dict(t_end=320 * period, dt=period / 100, t_transient=300 * period,
                     observe=("strobe",), progress=False)
    frequency = 2 / 3
    turn = 2 * np.pi / frequency
    baker_scene = sweep.Scene(gravity=9.81, length=9.81, effects=(
        sweep.Damping(0.5), sweep.Forcing(1.35, frequency, 0.0)))
    baker_grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, baker),
                            omega0=np.linspace(-np.pi, np.pi, baker))
    baker_full = dict(t_end=60 * turn, dt=turn / 1000, t_transient=44 * turn,
                      observe=("strobe",), progress=False)
    return {
        "Wada map": (wada_scene, wada_grid, wada_full,
                     dict(wada_full, t_transient=20 * period, stop_early=True)),
        "Baker-Gollub (examples/forced.toml)": (
            baker_scene, baker_grid, baker_full,
            dict(baker_full, t_transient=10 * turn, stop_early=True)),
    }


def best_cpu(function, repeats: int = 2):
    """``(result, least process CPU seconds, its wall seconds)`` over ``repeats`` calls."""
    best = None
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        result = function()
        took = (time.process_time() - cpu, time.perf_counter() - wall)
        if best is None or took[0] < best[0]:
            best = took
    return result, best[0], best[1]


def measure(scene, grid, full_kwargs, early) -> dict:
    """Labels and times of the routes on one scene."""
    full = maps.basins(sweep.run(scene, grid, **full_kwargs))
    catalogue = maps.pilot_catalogue(scene, grid, 41, **early)
    early = dict(early, attractors=catalogue)
    theta, omega = grid.axes["theta0"], grid.axes["omega0"]

    def known():
        cells = background(scene, theta, omega, catalogue,
                           **{k: v for k, v in early.items() if k != "attractors"})[0]
        return maps.basins(sweep.run(scene, grid, known_cells=cells, **early))

    routes = {
        "catalogue": lambda: maps.basins(sweep.run(scene, grid, **early)),
        "known": known,
        "refine_known": lambda: maps.refine(scene, grid, pilot=None, known_cells=True,
                                            **early),
    }
    out = {"full": full, "routes": {}}
    n = full.size
    for name, route in routes.items():
        labels, cpu, wall = best_cpu(route)
        differ = labels.values != full.values
        shifts = [abs(float((labels.values == a).mean()) - p) / np.sqrt(p * (1 - p) / n)
                  for a in range(len(full.attrs["attractor_size"]))
                  for p in [float((full.values == a).mean())]]
        out["routes"][name] = {"cpu_seconds": cpu, "wall_seconds": wall,
                               "differing": int(differ.sum()),
                               "differing_fraction": float(differ.mean()),
                               "largest_shift_in_standard_errors": max(shifts),
                               "differ": differ}
    return out


def figure(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(6 * len(results), 5.4))
    for ax, (title, found) in zip(np.atleast_1d(axes), results.items()):
        full = found["full"]
        theta, omega = full["theta0"].values, full["omega0"].values
        ax.imshow(full.values.T, origin="lower", aspect="auto", cmap="Pastel1",
                  extent=(theta[0], theta[-1], omega[0], omega[-1]), interpolation="none")
        for name, marker, colour in (("known", "x", "red"), ("refine_known", "o", "black")):
            rows, cols = np.nonzero(found["routes"][name]["differ"])
            style = dict(facecolors="none", edgecolors=colour) if marker == "o" else \
                dict(c=colour)
            ax.scatter(theta[rows], omega[cols], marker=marker, s=14, linewidths=0.8,
                       label=f"{name}: {rows.size} of {full.size} differ", **style)
        ax.set_title(f"{title}, {theta.size} x {omega.size}")
        ax.set_xlabel("theta0 [rad]")
        ax.set_ylabel("omega0 [rad/s]")
        ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wada", type=int, default=400, help="Wada map: points per axis")
    parser.add_argument("--baker", type=int, default=200,
                        help="Baker-Gollub map: points per axis")
    parser.add_argument("--figure", type=Path,
                        default=Path(__file__).parent / "results" / "known_cells.png")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    results = {title: measure(*parts) for title, parts in scenes(args.wada,
                                                                args.baker).items()}
    args.out.mkdir(parents=True, exist_ok=True)
    figure(results, args.figure)
    table = {"machine": machine(), "scenes": {
        title: {name: {k: v for k, v in route.items() if k != "differ"}
                for name, route in found["routes"].items()}
        for title, found in results.items()}}
    (args.out / "known_cells.json").write_text(json.dumps(table, indent=2))
    print(json.dumps(table, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
