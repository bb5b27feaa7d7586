"""Time the forced-pendulum basin map of the maps issue on this machine.

Workload: 1200 x 1200 starts (theta0 in [-pi, pi], omega0 in [-4, 4]), damping 0.2,
forcing amplitude 1.66, frequency 1, cos forcing, 300 transient forcing periods plus 20
observed (stroboscopic samples for the attractor search), RK4 with 100 steps per period.

By default the whole map is run, end to end (``sweep.run`` then ``maps.basins``), once
as specified, once with ``stop_early`` and once with ``stop_early`` and an attractor
catalogue from a coarse pilot run (``--pilot N``: N x N starts; its time is counted);
then with the catalogue and known cells (issue 37): ``known``, coarse maps of the
window first (`sweep.maps.known.background`) and the map stopping on their settled
cells (``sweep.run(..., known_cells=...)``), and ``refine_known``,
``maps.refine(..., known_cells=True)`` (``--variants`` picks some of the five);
``--rows N`` runs a band of N theta0 rows (all omega0 columns) and extrapolates the
full map's time linearly (trajectories are independent, the time per trajectory-step is
flat in the number of trajectories).

The end-to-end time is set against the C limit (`run_all.py`'s fastest C of the same
algorithm, built with the flags of the last ``run_all.py`` search in
``results/run_all.json``, or its 512-bit candidate) timed in the same run on
``run_all.py``'s full-scene workload: the map's effective throughput is the
trajectory-steps of the full-length run (size^2 x 32,000) per second of its end-to-end
time, and the issue asks for at least 5x the C limit's. ``--no-c-limit`` skips it
(and it is skipped without gcc).

Each variant's process CPU time (all threads) is recorded beside its wall time: on a
machine shared with other work the CPU time's ratios move less.

Writes ``benchmarks/results/forced_basins.json`` and ``.md``.

Usage::

    python benchmarks/forced_basins.py [--size 1200] [--rows N] [--no-c-limit]
        [--variants full,stop_early,catalogue,known,refine_known]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps
from sweep.maps.known import background, known_map

from _c_builds import c_limit
from _machine import machine

STEPS_PER_PERIOD = 100
TRANSIENT_PERIODS = 300
OBSERVED_PERIODS = 20
VARIANTS = ("full", "stop_early", "catalogue", "known", "refine_known")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1200)
    parser.add_argument("--rows", type=int, default=None,
                        help="run a band of this many theta0 rows and extrapolate "
                             "(default: the whole map)")
    parser.add_argument("--pilot", type=int, default=41,
                        help="the catalogue's pilot run: pilot x pilot starts")
    parser.add_argument("--no-c-limit", action="store_true",
                        help="do not build and time the C limit")
    parser.add_argument("--variants", default=None,
                        help="comma-separated, from " + ", ".join(VARIANTS) +
                             " (labels are compared with the first; default: all, the "
                             "first three with --rows)")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    args.rows = args.size if args.rows is None else args.rows
    band = args.rows != args.size
    chosen = (args.variants or ",".join(VARIANTS[:3] if band else VARIANTS)).split(",")
    if any(v not in VARIANTS for v in chosen):
        parser.error(f"--variants: {args.variants!r}; accepted: some of {', '.join(VARIANTS)}")
    if band and {"known", "refine_known"} & set(chosen):
        parser.error("--variants known and refine_known need the whole, evenly spaced "
                     "map; accepted: without --rows")
    args.out.mkdir(parents=True, exist_ok=True)
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
    early = dict(kwargs, t_transient=20 * period, stop_early=True)
    variants = {"full": dict(kwargs), "stop_early": early, "catalogue": early, "known": early,
                "refine_known": early}
    variants = {name: variants[name] for name in chosen}
    labels = {}
    for name, options in variants.items():
        pilot_s, catalogue, extra = 0.0, None, {}
        if name in ("catalogue", "known", "refine_known"):
            # a pilot on a coarse grid finds the attractors first
            pilot = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, args.pilot),
                               omega0=np.linspace(-4.0, 4.0, args.pilot))
            sweep.engine.warm_up(scene, pilot, **options)
            start, cpu = time.perf_counter(), time.process_time()
            catalogue = maps.attractor_catalogue(sweep.run(scene, pilot, **options))
            pilot_s, pilot_cpu = time.perf_counter() - start, time.process_time() - cpu
            options = dict(options, attractors=catalogue)
        if name == "known":  # compile (or load) the known-cells kernel first
            extra["known_cells"] = known_map(
                np.full(grid.shape, -1), grid.axes["theta0"], grid.axes["omega0"])
        if name != "refine_known":
            sweep.engine.warm_up(scene, grid, **options, **extra)  # compile (or load)
        start, cpu = time.perf_counter(), time.process_time()
        if name == "refine_known":
            labels[name] = maps.refine(scene, grid, pilot=None, known_cells=True, **options)
            ds = None
        else:
            if name == "known":
                extra["known_cells"] = background(scene, grid.axes["theta0"],
                                                  grid.axes["omega0"], catalogue, **early)[0]
            ds = sweep.run(scene, grid, **options, **extra)
        run_s, run_cpu = time.perf_counter() - start, time.process_time() - cpu
        start, cpu = time.perf_counter(), time.process_time()
        if ds is not None:
            labels[name] = maps.basins(ds)
        label_s, label_cpu = time.perf_counter() - start, time.process_time() - cpu
        result[name] = {
            "run_seconds": run_s + pilot_s,
            "pilot_seconds": pilot_s,
            "matched_fraction": float((ds.attractor >= 0).mean()) if catalogue and ds
            is not None else 0.0,
            "stopped_known_fraction": labels[name].attrs.get(
                "cells_stopped_known", ds.attrs.get("cells_stopped_known", 0)
                if ds is not None else 0) / grid.size,
            "labelling_seconds": label_s,
            "cpu_seconds": run_cpu + label_cpu + (pilot_cpu if catalogue else 0.0),
            "full_map_seconds_extrapolated": (run_s + pilot_s + label_s) * scale,
            "attractors": len(labels[name].attrs["attractor_size"]),
            "unresolved_fraction": float((labels[name] == maps.UNRESOLVED).mean()),
        }
    first = chosen[0]
    if first == "full":
        result["full"]["trajectory_steps_per_second"] = grid.size * steps / result["full"][
            "run_seconds"]
    resolved = labels[first].values != maps.UNRESOLVED
    for name in chosen[1:]:
        differ = labels[first].values != labels[name].values
        result[name]["labels_differing"] = int(differ.sum())
        result[name]["labels_differing_where_full_resolves"] = int((differ & resolved).sum())
        result[name]["cpu_over_" + first] = result[first]["cpu_seconds"] / result[name][
            "cpu_seconds"]
        n = differ.size
        result[name]["fraction_shift_over_standard_error"] = [
            abs(float((labels[name].values == k).mean()) - p) / np.sqrt(p * (1 - p) / n)
            for k in range(len(labels[first].attrs["attractor_size"]))
            for p in [float((labels[first].values == k).mean())]]
        if differ.any():
            np.save(args.out / f"forced_basins_differ_{name}.npy", differ)
    full_steps = args.size**2 * steps  # trajectory-steps of the full-length map
    result["c_limit"] = None if args.no_c_limit else c_limit()
    result["variants"] = chosen
    for name in variants:
        seconds = result[name]["full_map_seconds_extrapolated"]
        result[name]["effective_traj_steps_per_s"] = full_steps / seconds
        if result["c_limit"]:
            result[name]["over_c_limit"] = full_steps / seconds / result["c_limit"][
                "traj_steps_per_s"]
    (args.out / "forced_basins.json").write_text(json.dumps(result, indent=2))
    (args.out / "forced_basins.md").write_text(markdown(result, args, steps, scale))
    print(markdown(result, args, steps, scale))
    return 0


TITLES = {"full": "full run ({steps} RK4 steps each)", "stop_early": "stop_early",
          "catalogue": "stop_early with an attractor catalogue ({pilot} x {pilot} pilot)",
          "known": "... and known cells (coarse maps first)",
          "refine_known": "maps.refine(known_cells=True), step 16"}


def markdown(result: dict, args, steps: int, scale: float) -> str:
    """The results as a Markdown page."""
    names = result["variants"]
    runs = [result[name] for name in names]
    whole = args.rows == args.size
    how = "the whole map, end to end" if whole else \
        f"band run: {args.rows} x {args.size} starts (full map extrapolated x{scale:g})"

    def integration(name, r):
        if name == "full" and "trajectory_steps_per_second" in r:
            return (f"{r['run_seconds']:.1f} s "
                    f"({r['trajectory_steps_per_second'] / 1e6:.1f} M trajectory-steps/s)")
        return f"{r['run_seconds']:.1f} s"

    rows = [
        ("integration (pilot included)", [integration(n, r) for n, r in zip(names, runs)]),
        ("... of which the pilot and its catalogue",
         [f"{r['pilot_seconds']:.2f} s" if r["pilot_seconds"] else "" for r in runs]),
        ("attractor labelling (`maps.basins`; refine: in the integration)",
         [f"{r['labelling_seconds']:.2f} s" for r in runs]),
        ("full map, end to end" + ("" if whole else " (extrapolated)"),
         [f"{r['full_map_seconds_extrapolated']:.1f} s" for r in runs]),
        ("process CPU time (all threads)", [f"{r['cpu_seconds']:.1f} s" for r in runs]),
        (f"... {names[0]}'s over this one's", [""] + [
            f"{r['cpu_over_' + names[0]]:.2f}" for r in runs[1:]]),
        ("effective throughput (full-length trajectory-steps / end-to-end time)",
         [f"{r['effective_traj_steps_per_s'] / 1e6:.0f} M/s" for r in runs]),
    ]
    c = result["c_limit"]
    if c:
        rows.append(("... over the C limit's throughput",
                     [f"**{r['over_c_limit']:.2f}**" for r in runs]))
    rows += [
        ("attractors found", [f"{r['attractors']}" for r in runs]),
        ("unresolved", [f"{r['unresolved_fraction']:.4f}" for r in runs]),
        ("trajectories stopped by a catalogue match or on known cells",
         [f"{r['matched_fraction']:.4f}" if r["matched_fraction"] else "" for r in runs]),
        ("... of which on known cells",
         [f"{r['stopped_known_fraction']:.4f}" if r["stopped_known_fraction"] else ""
          for r in runs]),
        (f"starts labelled differently from {names[0]} (where it resolves one)",
         [""] + [f"{r['labels_differing']} ({r['labels_differing_where_full_resolves']})"
                 f" of {args.rows * args.size}" for r in runs[1:]]),
        ("largest shift of an attractor's fraction, in standard errors",
         [""] + [f"{max(r['fraction_shift_over_standard_error']):.2f}" for r in runs[1:]]),
    ]
    titles = [TITLES[n].format(steps=steps, pilot=args.pilot) for n in names]
    lines = [f"# Forced-pendulum basin map, {args.size} x {args.size}", "",
             f"Machine: {result['machine']}", "", f"{how[0].upper()}{how[1:]}.", "",
             "| | " + " | ".join(titles) + " |", "|---|" + "---|" * len(names)]
    lines += [f"| {label} | " + " | ".join(cells) + " |" for label, cells in rows]
    if c:
        lines += ["", f"The C limit, timed in the same run on run_all.py's full-scene "
                  f"workload (2^17 x 2000): {c['traj_steps_per_s'] / 1e6:.0f} M "
                  f"trajectory-steps/s (`gcc -O3 -march=native -fopenmp {c['flags']}`)."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
