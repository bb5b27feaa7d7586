"""Time the forced-pendulum basin map of the maps issue on this machine.

Workload: 1200 x 1200 starts (theta0 in [-pi, pi], omega0 in [-4, 4]), damping 0.2,
forcing amplitude 1.66, frequency 1, cos forcing, 300 transient forcing periods plus 20
observed (stroboscopic samples for the attractor search), RK4 with 100 steps per period.

By default a band of ``--rows`` theta0 rows (all 1200 omega0 columns) is run and the
full map's time is extrapolated linearly (trajectories are independent, the time per
trajectory-step is flat in the number of trajectories); ``--rows 1200`` runs it all.
Writes ``benchmarks/results/forced_basins.json`` and ``.md``.

Usage::

    python benchmarks/forced_basins.py [--rows N] [--size 1200]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numba
import numpy as np

import sweep
from sweep import maps

STEPS_PER_PERIOD = 100
TRANSIENT_PERIODS = 300
OBSERVED_PERIODS = 20


def machine() -> str:
    """A one-line description of this machine."""
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, numba {numba.__version__}, " \
           f"{numba.get_num_threads()} threads"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1200)
    parser.add_argument("--rows", type=int, default=60)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    period = 2 * np.pi
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    theta0 = np.linspace(-np.pi, np.pi, args.size)
    rows = theta0[np.linspace(0, args.size - 1, args.rows).round().astype(int)]
    grid = sweep.Grid(theta0=rows, omega0=np.linspace(-4.0, 4.0, args.size))
    kwargs = dict(t_end=(TRANSIENT_PERIODS + OBSERVED_PERIODS) * period,
                  dt=period / STEPS_PER_PERIOD, t_transient=TRANSIENT_PERIODS * period,
                  observe=("strobe",), progress=False)
    steps = (TRANSIENT_PERIODS + OBSERVED_PERIODS) * STEPS_PER_PERIOD
    scale = args.size / args.rows
    result = {"machine": machine(), "grid": [args.rows, args.size],
              "full_grid": [args.size, args.size]}
    # the run as specified, then with stop_early (a trajectory ends once its
    # 16 stroboscopic samples repeat; the transient is then at least 20 periods)
    variants = {"full": dict(kwargs),
                "stop_early": dict(kwargs, t_transient=20 * period, stop_early=True)}
    labels = {}
    for name, options in variants.items():
        sweep.engine.warm_up(scene, grid, **options)  # compile (or load) first
        start = time.perf_counter()
        ds = sweep.run(scene, grid, **options)
        run_s = time.perf_counter() - start
        start = time.perf_counter()
        labels[name] = maps.basins(ds)
        label_s = time.perf_counter() - start
        result[name] = {
            "run_seconds": run_s,
            "labelling_seconds": label_s,
            "full_map_seconds_extrapolated": (run_s + label_s) * scale,
            "attractors": int(len(labels[name].attrs["attractor_size"])),
            "unresolved_fraction": float((labels[name] == maps.UNRESOLVED).mean()),
        }
    result["full"]["trajectory_steps_per_second"] = grid.size * steps / result["full"][
        "run_seconds"]
    result["labels_differing"] = int((labels["full"].values != labels["stop_early"].values
                                      ).sum())
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "forced_basins.json").write_text(json.dumps(result, indent=2))
    full, early = result["full"], result["stop_early"]
    md = (f"# Forced-pendulum basin map, {args.size} x {args.size}\n\n"
          f"Machine: {result['machine']}\n\n"
          f"Band run: {args.rows} x {args.size} starts (full map extrapolated x{scale:g}).\n\n"
          f"| | full run ({steps} RK4 steps each) | stop_early |\n|---|---|---|\n"
          f"| integration | {full['run_seconds']:.1f} s "
          f"({full['trajectory_steps_per_second'] / 1e6:.1f} M trajectory-steps/s) | "
          f"{early['run_seconds']:.1f} s |\n"
          f"| attractor labelling | {full['labelling_seconds']:.2f} s | "
          f"{early['labelling_seconds']:.2f} s |\n"
          f"| full map (extrapolated) | {full['full_map_seconds_extrapolated']:.0f} s | "
          f"{early['full_map_seconds_extrapolated']:.0f} s |\n"
          f"| attractors found | {full['attractors']} | {early['attractors']} |\n"
          f"| unresolved | {full['unresolved_fraction']:.4f} | "
          f"{early['unresolved_fraction']:.4f} |\n"
          f"| starts labelled differently from the full run | | "
          f"{result['labels_differing']} of {grid.size} |\n")
    (args.out / "forced_basins.md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
