"""The Wada test (`sweep.maps.wada`, `sweep.maps.wada_merging`) of the forced pendulum's
basin maps, with its cost, on this machine.

Two scenes, g = L = 1, damping 0.2, cos forcing of frequency 1: amplitude 1.66 (three
attractors, the maps issue's Wada map) and 1.71 (four attractors, partially Wada:
Wagemakers, Daza, Sanjuán, Discrete Contin. Dyn. Syst. B 26, 717 (2021), Fig. 2a).
Each: a ``--size`` x ``--size`` map (theta0 in [-pi, pi], omega0 in [-4, 4]; RK4 with
100 steps per period, ``stop_early`` from period 20 on, at most 320 periods) labelled
by the attractor catalogue of a ``--pilot`` x ``--pilot`` pilot, the grid method with
``--steps`` refinement steps (the same labelling), and the merging method on the map.

Writes ``benchmarks/results/wada.json`` and ``.md``; ``--figure PNG`` draws each map and
its boundary cells coloured by the number of basins they touch.

Usage::

    python benchmarks/wada.py [--size 200] [--steps 8] [--pilot 41] [--figure PNG]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps
from sweep.maps.wada import _scene_labels

from _machine import machine

AMPLITUDES = (1.66, 1.71)


def run_kwargs() -> dict:
    period = 2 * np.pi
    return dict(t_end=320 * period, dt=period / 100, t_transient=20 * period,
                observe=("strobe",), stop_early=True, progress=False)


def case(amplitude: float, size: int, steps: int, pilot: int) -> tuple[dict, dict]:
    """One scene's map, grid-method and merging-method results and their times."""
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(amplitude, 1.0, np.pi / 2)))
    x, y = np.linspace(-np.pi, np.pi, size), np.linspace(-4.0, 4.0, size)
    grid = sweep.Grid(theta0=x, omega0=y)
    kwargs = run_kwargs()
    catalogue = maps.pilot_catalogue(scene, grid, pilot, **kwargs)
    labels_of = _scene_labels(scene, catalogue, **kwargs)
    starts = np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1).reshape(-1, 2)
    for count in (3, 100, 1000, 2100):  # compile (or load) each block size's kernel
        labels_of(starts[:count])
    start = time.perf_counter()
    labels = labels_of(starts).reshape(size, size)
    map_s = time.perf_counter() - start
    start = time.perf_counter()
    grid_result = maps.wada(labels, labels_of, x, y, max_steps=steps)
    grid_s = time.perf_counter() - start
    start = time.perf_counter()
    merging = maps.wada_merging(labels)
    merging_s = time.perf_counter() - start
    out = {"amplitude": amplitude, "size": size, "basins": grid_result.basins,
           "map_seconds": map_s,
           "grid_method": {"seconds": grid_s, "steps": grid_result.steps,
                           "boundary_cells": grid_result.boundary_cells,
                           "trajectories": grid_result.trajectories,
                           "W": grid_result.history.tolist(),
                           "verdict": grid_result.verdict,
                           "tolerance": grid_result.tolerance},
           "merging_method": {"seconds": merging_s, "distances": merging.distances.tolist(),
                              "shares": merging.shares.tolist(), "radius": merging.radius,
                              "verdict": merging.verdict}}
    return out, {"labels": labels, "touching": grid_result.touching, "x": x, "y": y,
                 "result": grid_result}


def markdown(results: list[dict], tables: list[str], stamp: str) -> str:
    lines = ["# The Wada test of the forced pendulum's basin maps", "",
             f"Machine: {stamp}. Script: `benchmarks/wada.py`.", ""]
    for run, table in zip(results, tables):
        grid = run["grid_method"]
        merging = run["merging_method"]
        lines += [f"## A = {run['amplitude']}: {run['basins']} basins, "
                  f"{run['size']} x {run['size']} map", "",
                  f"Map: {run['map_seconds']:.2f} s. Grid method: {grid['verdict']} "
                  f"(tolerance {grid['tolerance']}), {grid['boundary_cells']} boundary "
                  f"cells, {grid['trajectories']} new trajectories, {grid['seconds']:.2f} s. "
                  f"Merging method: {merging['verdict']} (distances "
                  f"{merging['distances']} cells, shares beyond {merging['radius']} cells "
                  f"{[round(s, 4) for s in merging['shares']]}), "
                  f"{merging['seconds']:.3f} s.", "",
                  "W_m, the share of boundary cells touching m basins, on the grid and "
                  "after each refinement step:", "", table, ""]
    return "\n".join(lines)


def figure(path: Path, maps_: list[dict], results: list[dict]) -> None:
    """Per scene: the map (top) and its boundary cells by the basins they miss
    (bottom: dark, all of them; orange, one missing; blue, two)."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    fig, axes = plt.subplots(2, len(maps_), figsize=(5 * len(maps_), 8.5), squeeze=False,
                             layout="constrained")
    basin_colours = ListedColormap(["#4477aa", "#ee6677", "#228833", "#ccbb44"])
    missing_colours = ListedColormap(["#ffffff", "#222222", "#ee7733", "#33bbee"])
    for k, (data, run) in enumerate(zip(maps_, results)):
        extent = (data["x"][0], data["x"][-1], data["y"][0], data["y"][-1])
        n = run["basins"]
        touching = data["touching"].astype(int)
        missing = np.where(touching > 0, 1 + n - touching, 0)  # 1: none missing
        top, bottom = axes[0, k], axes[1, k]
        top.imshow(data["labels"].T, origin="lower", extent=extent, aspect="auto",
                   cmap=basin_colours, vmin=0, vmax=3, interpolation="nearest")
        top.set_title(f"A = {run['amplitude']}: {n} basins ({run['size']} x {run['size']})")
        image = bottom.imshow(np.minimum(missing, 3).T, origin="lower", extent=extent,
                              aspect="auto", cmap=missing_colours, vmin=-0.5, vmax=3.5,
                              interpolation="nearest")
        w = data["result"].fractions[n - 1]
        bottom.set_title(f"boundary cells: W_{n} = {w:.3f}, {run['grid_method']['verdict']}")
        for ax in (top, bottom):
            ax.set_xlabel("theta0 (rad)")
            ax.set_ylabel("omega0 (rad/s)")
    colorbar = fig.colorbar(image, ax=axes[1, :].tolist(), ticks=[0, 1, 2, 3], shrink=0.9)
    colorbar.ax.set_yticklabels(["interior", "all basins", "one missing", "two missing"])
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=200, help="starts per axis")
    parser.add_argument("--steps", type=int, default=8, help="the grid method's max_steps")
    parser.add_argument("--pilot", type=int, default=41)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    parser.add_argument("--figure", type=Path, default=None)
    args = parser.parse_args(argv)
    results, data, tables = [], [], []
    for amplitude in AMPLITUDES:
        out, arrays = case(amplitude, args.size, args.steps, args.pilot)
        results.append(out)
        data.append(arrays)
        tables.append(arrays["result"].table())
        grid = out["grid_method"]
        print(f"A = {amplitude}: {grid['verdict']}, W = {np.round(grid['W'][-1], 3)}, "
              f"{grid['trajectories']} trajectories in {grid['seconds']:.2f} s")
    stamp = f"{machine()}, {time.strftime('%Y-%m-%d')}"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "wada.json").write_text(json.dumps({"machine": stamp, "cases": results},
                                                   indent=1) + "\n")
    (args.out / "wada.md").write_text(markdown(results, tables, stamp))
    if args.figure is not None:
        figure(args.figure, data, results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
