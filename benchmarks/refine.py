"""Time adaptive boundary refinement (`sweep.maps.refine`) against the full run of the
same grid, on this machine.

Two maps:

- the forced Wada map of ``forced_basins.py`` (``--size`` x ``--size`` starts, theta0 in
  [-pi, pi], omega0 in [-4, 4], damping 0.2, A = 1.66, W = 1, cos forcing, RK4 with 100
  steps per period, ``stop_early`` from period 20 on, at most 320 periods): the full run
  is ``forced_basins.py``'s fastest, stop_early with a 41 x 41 pilot's attractor
  catalogue (its labels are those of the full-length run on every start of the
  1200 x 1200 map: ``results/forced_basins.md``); refine uses the same pilot and
  catalogue. Both are timed end to end (pilot, runs, labels);
- the damped-well map of ``examples/damped_basins.py`` (``--well-size``, default 4096:
  g = 9.81, L = 1, c = 0.25, theta0 in [-pi, pi], omega0 in [-12, 12], t_end = 40 s,
  dt = 0.02 s, ``capture`` with ``stop_early``), labelled by `sweep.maps.well`.

For each: cells computed, wall time, effective throughput (all cells / wall time) and
the cells whose label differs from the full run's. The forced map's throughput is also
given as the issue counts it: the trajectory-steps of the full-length run (size^2 x
32,000) per second of end-to-end time, over the C limit's rate timed in the same run
(``forced_basins.c_limit``; ``--no-c-limit`` skips it). Kernels are compiled (or loaded)
before anything is timed.

Writes ``benchmarks/results/refine.json`` and ``.md``.

Usage::

    python benchmarks/refine.py [--size 1200] [--step 16] [--well-size 4096]
                                [--no-c-limit] [--no-full-well] [--figure PNG]

``--figure docs/images/refine.png`` also draws the README's figure from the two refined
maps: the forced map, its computed cells, and the damped-well map's computed cells.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps

from _c_builds import c_limit
from _machine import machine
from forced_basins import OBSERVED_PERIODS, STEPS_PER_PERIOD, TRANSIENT_PERIODS


def forced_case(size: int):
    """The forced Wada map's scene, grid and run arguments."""
    period = 2 * np.pi
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-4.0, 4.0, size))
    kwargs = dict(t_end=(TRANSIENT_PERIODS + OBSERVED_PERIODS) * period,
                  dt=period / STEPS_PER_PERIOD, t_transient=20 * period,
                  observe=("strobe",), stop_early=True, progress=False)
    return scene, grid, kwargs


def well_case(size: int):
    """The damped-well map's scene, grid and run arguments."""
    scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.25),))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-12.0, 12.0, size))
    return scene, grid, dict(t_end=40.0, dt=0.02, observe=("capture",), stop_early=True,
                             progress=False)


def _timed(fn):
    start = time.perf_counter()
    value = fn()
    return time.perf_counter() - start, value


def differing(refined, full) -> int:
    """Cells whose labels differ (NaN equal to NaN)."""
    a, b = refined.values, full.values
    same = (a == b) | (np.isnan(a) & np.isnan(b) if a.dtype.kind == "f" else False)
    return int((~same).sum())


def compare(scene, grid, kwargs, label, step, pilot, full=True, repeats=2) -> dict:
    """Refine and (``full``) the full run of one map, each end to end, alternately
    ``repeats`` times (this machine's rates drift with its other load): the best time
    of each."""
    out = {"grid": list(grid.shape), "cells": int(grid.size), "step": step,
           "repeats": repeats}

    def run_full():
        options = dict(kwargs)
        if label is maps.basins and pilot:
            options["attractors"] = maps.pilot_catalogue(scene, grid, pilot, **kwargs)
        return label(sweep.run(scene, grid, **options))

    refine_s = full_s = np.inf
    for _ in range(repeats):
        seconds, refined = _timed(lambda: maps.refine(scene, grid, label, step=step,
                                                      pilot=pilot, **kwargs))
        refine_s = min(refine_s, seconds)
        if full:
            seconds, labels = _timed(run_full)
            full_s = min(full_s, seconds)
    out["refine"] = {"seconds": refine_s, "cells_computed": refined.attrs["cells_computed"],
                     "computed_fraction": refined.attrs["cells_computed"] / grid.size,
                     "cells_per_level": refined.attrs["cells_per_level"].tolist(),
                     "pilot_cells": refined.attrs["pilot_cells"],
                     "cells_per_second": grid.size / refine_s}
    if full:
        out["full"] = {"seconds": full_s, "cells_per_second": grid.size / full_s}
        out["labels_differing"] = differing(refined, labels)
        out["differing_fraction"] = out["labels_differing"] / grid.size
        out["speedup"] = full_s / refine_s
    return out, refined


def warm(scene, grid, kwargs, forced: bool, pilot: int) -> None:
    """Compile (or load) every kernel the timed runs use."""
    sweep.engine.warm_up(scene, grid, **kwargs)
    if forced and pilot:
        catalogue = maps.pilot_catalogue(scene, grid, pilot, **kwargs)
        sweep.engine.warm_up(scene, grid, attractors=catalogue, **kwargs)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1200, help="forced map: starts per axis")
    parser.add_argument("--step", type=int, default=16, help="refine's lattice step")
    parser.add_argument("--pilot", type=int, default=41)
    parser.add_argument("--well-size", type=int, default=4096,
                        help="damped-well map: starts per axis")
    parser.add_argument("--well-step", type=int, default=32)
    parser.add_argument("--no-full-well", action="store_true",
                        help="do not run the full well map (only refine)")
    parser.add_argument("--repeats", type=int, default=2,
                        help="alternate refine and the full run this many times; best of each")
    parser.add_argument("--no-c-limit", action="store_true")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    parser.add_argument("--figure", type=Path, default=None,
                        help="also draw the refined maps into this PNG")
    args = parser.parse_args(argv)
    result = {"machine": machine()}
    scene, grid, kwargs = forced_case(args.size)
    warm(scene, grid, kwargs, True, args.pilot)
    result["forced"], refined = compare(scene, grid, kwargs, maps.basins, args.step,
                                        args.pilot, repeats=args.repeats)
    steps = (TRANSIENT_PERIODS + OBSERVED_PERIODS) * STEPS_PER_PERIOD
    full_steps = grid.size * steps
    for name in ("refine", "full"):
        run = result["forced"][name]
        run["effective_traj_steps_per_s"] = full_steps / run["seconds"]
    scene_w, grid_w, kwargs_w = well_case(args.well_size)
    warm(scene_w, grid_w, kwargs_w, False, 0)
    result["well"], refined_well = compare(scene_w, grid_w, kwargs_w, maps.well,
                                           args.well_step, None, full=not args.no_full_well,
                                           repeats=args.repeats)
    result["c_limit"] = None if args.no_c_limit else c_limit()
    if result["c_limit"]:
        for name in ("refine", "full"):
            run = result["forced"][name]
            run["over_c_limit"] = run["effective_traj_steps_per_s"] / result["c_limit"][
                "traj_steps_per_s"]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "refine.json").write_text(json.dumps(result, indent=2))
    (args.out / "refine.md").write_text(markdown(result, steps))
    print(markdown(result, steps))
    if args.figure:
        figure(refined, refined_well, result, args.figure)
    return 0


def figure(forced, well, result: dict, path: Path) -> None:
    """The refined forced map, its computed cells, and the well map's computed cells."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 5), layout="constrained")
    f, w = result["forced"], result["well"]
    sweep.plot.basins(forced, ax=axes[0], degrees=False,
                      title=f"forced map by refine, {f['grid'][0]} x {f['grid'][1]}")
    for ax, refined, case, what in ((axes[1], forced, f, "forced map"),
                                    (axes[2], well, w, "damped wells")):
        mask = refined["computed"].transpose(*refined.dims).values
        dims = refined.dims
        x, y = refined[dims[0]].values, refined[dims[1]].values
        ax.imshow(mask.T, origin="lower", aspect="auto", cmap="Greys", vmin=0, vmax=1.3,
                  extent=(x[0], x[-1], y[0], y[-1]), interpolation="antialiased")
        ax.set_xlabel("initial angle theta0 [rad]")
        ax.set_ylabel("initial angular velocity omega0 [rad/s]")
        differ = ("" if "labels_differing" not in case
                  else f"; {case['labels_differing']} labels differ from the full run")
        ax.set_title(f"{what} ({case['grid'][0]} x {case['grid'][1]}, step {case['step']}): "
                     f"computed cells dark,\n"
                     f"{100 * case['refine']['computed_fraction']:.1f} % of the cells{differ}",
                     fontsize=10)
    sweep.plot.save_figure(fig, path)


def markdown(result: dict, steps: int) -> str:
    """The results as a Markdown page."""
    forced, well = result["forced"], result["well"]
    n, m = forced["grid"]
    lines = ["# Adaptive boundary refinement (`sweep.maps.refine`)", "",
             f"Machine: {result['machine']}", "",
             f"Times: the best of {forced['repeats']} alternating runs of each, end to end "
             "(kernels compiled first).", ""]

    def table(case, title, full_name):
        refine = case["refine"]
        full = case.get("full")
        rows = [
            ("cells computed (level 0 is the lattice)",
             f"{refine['cells_computed']} of {case['cells']} "
             f"({100 * refine['computed_fraction']:.1f} %; per level "
             f"{', '.join(str(c) for c in refine['cells_per_level'])}"
             + (f"; pilot {refine['pilot_cells']}" if refine["pilot_cells"] else "") + ")",
             f"{case['cells']}"),
            ("end to end", f"{refine['seconds']:.2f} s",
             f"{full['seconds']:.2f} s" if full else "not run"),
            ("effective throughput (all cells / wall time)",
             f"{refine['cells_per_second'] / 1e6:.2f} M cells/s",
             f"{full['cells_per_second'] / 1e6:.2f} M cells/s" if full else ""),
        ]
        if "effective_traj_steps_per_s" in refine:
            rows.append(("full-length trajectory-steps (cells x "
                         f"{steps}) / end-to-end time",
                         f"{refine['effective_traj_steps_per_s'] / 1e6:.0f} M/s",
                         f"{full['effective_traj_steps_per_s'] / 1e6:.0f} M/s"))
            if "over_c_limit" in refine:
                rows.append(("... over the C limit's throughput (target: >= 5)",
                             f"**{refine['over_c_limit']:.2f}**",
                             f"{full['over_c_limit']:.2f}"))
        if full:
            rows.append(("speed-up (full run's time / refine's)", f"{case['speedup']:.2f}x",
                         ""))
            rows.append(("cells labelled differently from the full run",
                         f"{case['labels_differing']} ({case['differing_fraction']:.1e})",
                         ""))
        out = [f"## {title}", "", f"| | refine (step {case['step']}) | {full_name} |",
               "|---|---|---|"]
        out += [f"| {a} | {b} | {c} |" for a, b, c in rows]
        return out + [""]

    lines += table(forced, f"Forced Wada map, {n} x {m} (`maps.basins`)",
                   "full run (stop_early + 41 x 41 pilot catalogue)")
    wn, wm = well["grid"]
    lines += table(well, f"Damped-well map, {wn} x {wm} (`maps.well`)",
                   "full run (capture, stop_early)")
    c = result["c_limit"]
    if c:
        lines += [f"The C limit, timed in the same run on run_all.py's full-scene workload "
                  f"(2^17 x 2000): {c['traj_steps_per_s'] / 1e6:.0f} M trajectory-steps/s "
                  f"(`gcc -O3 -march=native -fopenmp {c['flags']}`).", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
