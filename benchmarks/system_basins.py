"""A driven double pendulum's basin map by the attractor catalogue, end to end, against
the full stroboscopic run and `sweep.maps.basins` (issue 35, item 5).

The damped double pendulum on a fast-driven pivot (the systems guide's example: a =
0.1 m, nu = 60 rad/s, c = 0.5/s; coexisting attractors of periods 1 and 4), a
``--size`` x ``--size`` grid of (theta1_0, theta2_0) in [-3, 3]^2 from rest, RK4 with
40 steps per drive period, ``--periods`` drive periods.

- **full**: ``observe=("strobe",)`` (the last 16 periods sampled) for every start,
  then ``sweep.maps.basins``;
- **catalogue**: a pilot of ``--pilot`` x ``--pilot`` starts over the same box (the
  same run as full, then ``sweep.maps.attractor_catalogue``), then the map with
  ``observe=("attractor",)``, ``attractors=catalogue``, ``stop_early=True`` and no
  transient: each start stops once its stroboscopic point met the successive points of
  one catalogued orbit ``ATTRACTOR_MATCHES`` periods running (within 1e-3 in each
  coordinate and velocity, angles modulo 2 pi).

Both kernels are compiled (or loaded from the disk cache) first by a run of the same
grid over a few periods, not timed. The two maps' labels are compared: the catalogue's
attractor k is mapped to the full run's label most of its starts have; the starts whose
labels then differ, and those either leaves unresolved (-1), are counted.

Writes ``benchmarks/results/system_basins.json`` and ``.md``.

Usage::

    python benchmarks/system_basins.py               # 200 x 200, ~1 min on 2 cores
    python benchmarks/system_basins.py --size 8      # seconds
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import sweep  # noqa: E402
from sweep import maps  # noqa: E402

from _machine import stamp, write_results  # noqa: E402

NU = 60.0                    # the pivot's angular frequency [rad/s]
PERIOD = 2 * np.pi / NU      # the drive period [s]
STEPS_PER_PERIOD = 40
SAMPLES = 16                 # strobe samples of the full run (sweep's default)


def system():
    return sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=NU,
                                effects=(sweep.Damping(0.5),))


def grid(size: int) -> sweep.Grid:
    axis = np.linspace(-3.0, 3.0, size)
    return sweep.Grid(theta1_0=axis, theta2_0=axis)


def run_kwargs(periods: int) -> dict:
    return dict(t_end=periods * PERIOD, dt=PERIOD / STEPS_PER_PERIOD,
                t_transient=(periods - SAMPLES) * PERIOD, progress=False)


def full_map(size: int, periods: int):
    ds = sweep.run(system(), grid(size), observe=("strobe",), **run_kwargs(periods))
    return ds, maps.basins(ds)


def catalogue_map(size: int, pilot: int, periods: int, catalogue=None):
    """The pilot's catalogue (unless given) and the map by it."""
    if catalogue is None:
        catalogue = maps.attractor_catalogue(full_map(pilot, periods)[0])
    ds = sweep.run(system(), grid(size), observe=("attractor",), attractors=catalogue,
                   stop_early=True, **dict(run_kwargs(periods), t_transient=0.0))
    return catalogue, ds


def compare(full_labels: np.ndarray, index: np.ndarray) -> dict:
    """Counts of the starts whose labels differ (catalogue attractor k -> the full
    run's label most of its starts have) and of the unresolved ones in each map."""
    mapped = np.full(index.shape, -1)
    for k in np.unique(index[index >= 0]):
        values, counts = np.unique(full_labels[index == k], return_counts=True)
        mapped[index == k] = values[np.argmax(counts)]
    return {"starts": int(index.size),
            "differing": int(np.sum(mapped != full_labels)),
            "differing_where_both_resolve": int(np.sum((mapped != full_labels)
                                                       & (mapped >= 0)
                                                       & (full_labels >= 0))),
            "unresolved_full": int(np.sum(full_labels < 0)),
            "unresolved_catalogue": int(np.sum(index < 0)), "mapped": mapped}


def recheck(starts: np.ndarray, index: np.ndarray, catalogue: dict, periods: int) -> dict:
    """The starts whose labels differ, run again by the full route over ``periods``
    (twice the map's): how many of them then settle on the catalogue's attractor for
    them (a point of its last orbit within 10 tol = 1e-2 of the long run's attractor
    point in every coordinate and velocity, angles modulo 2 pi), how many on another,
    how many the long run leaves unresolved, and how many the catalogue left unresolved
    that the long run resolves."""
    counts = {"starts": int(starts.shape[0]), "agree_with_catalogue": 0, "other": 0,
              "unresolved": 0, "catalogue_unresolved": 0}
    if starts.size == 0:
        return counts
    points = sweep.Points(theta1_0=starts[:, 0], theta2_0=starts[:, 1])
    ds = sweep.run(system(), points, observe=("strobe",), **run_kwargs(periods))
    labels = maps.basins(ds)
    names = ("theta1", "theta2", "omega1", "omega2")
    for label, k in zip(labels.values, index):
        if label < 0:
            counts["unresolved"] += 1
            continue
        if k < 0:
            counts["catalogue_unresolved"] += 1
            continue
        point = np.array([labels.attrs[f"attractor_{name}"][label] for name in names])
        p = int(catalogue["period"][k])
        orbit = np.concatenate([catalogue["theta"][k][:, -p:],
                                catalogue["omega"][k][:, -p:]]).T
        difference = np.abs(orbit - point)
        difference[:, :2] = np.mod(difference[:, :2], 2 * np.pi)
        difference[:, :2] = np.minimum(difference[:, :2], 2 * np.pi - difference[:, :2])
        found = bool((difference < 1e-2).all(axis=1).any())
        counts["agree_with_catalogue" if found else "other"] += 1
    return counts


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=200, help="starts per axis")
    parser.add_argument("--pilot", type=int, default=21, help="pilot starts per axis")
    parser.add_argument("--periods", type=int, default=800, help="drive periods (t_end)")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)

    # compile (or load) every kernel first: the same grids, a few periods
    warm = SAMPLES + 4
    full_map(args.size, warm)
    full_map(args.pilot, warm)
    # any catalogue compiles the map's kernel: its source does not depend on it
    rest = np.zeros((1, 2, SAMPLES))
    catalogue_map(args.size, args.pilot, warm, {"theta": rest, "omega": rest, "period": [1]})

    began = time.perf_counter()
    _, full_labels = full_map(args.size, args.periods)
    full_s = time.perf_counter() - began

    began = time.perf_counter()
    pilot_ds, _ = full_map(args.pilot, args.periods)
    catalogue = maps.attractor_catalogue(pilot_ds)
    pilot_s = time.perf_counter() - began
    began = time.perf_counter()
    _, ds = catalogue_map(args.size, args.pilot, args.periods, catalogue)
    map_s = time.perf_counter() - began

    index = ds["attractor"].values.astype(np.int64)
    counts = compare(full_labels.values, index)
    differing = np.flatnonzero(counts.pop("mapped").ravel() != full_labels.values.ravel())
    axes = np.meshgrid(ds["theta1_0"].values, ds["theta2_0"].values, indexing="ij")
    starts = np.stack([a.ravel()[differing] for a in axes], axis=1)
    rechecked = recheck(starts, index.ravel()[differing], catalogue, 2 * args.periods)
    catalogue_s = pilot_s + map_s
    result = {
        **stamp(),
        "grid": [args.size, args.size], "pilot": [args.pilot, args.pilot],
        "periods": args.periods, "steps_per_period": STEPS_PER_PERIOD,
        "full_seconds": full_s, "pilot_seconds": pilot_s, "map_seconds": map_s,
        "catalogue_seconds": catalogue_s, "speedup": full_s / catalogue_s,
        "attractors_full": len(full_labels.attrs["attractor_period"]),
        "attractors_catalogue": len(catalogue["period"]),
        "periods_full": full_labels.attrs["attractor_period"].tolist(),
        "periods_catalogue": catalogue["period"].tolist(),
        **counts,
        "differing_rerun_twice_as_long": rechecked,
    }
    n = args.size * args.size
    text = (f"# A driven double pendulum's basin map by the attractor catalogue\n\n"
            f"{result['machine']}. A shared 2-core machine: timings are noisy (one run "
            f"each).\n\n"
            f"Damped double pendulum, pivot a = 0.1 m at nu = {NU:g} rad/s, c = 0.5/s; "
            f"{args.size} x {args.size} starts at rest in [-3, 3]^2, RK4 with "
            f"{STEPS_PER_PERIOD} steps per drive period, {args.periods} periods.\n\n"
            "| route | seconds | of which |\n|---|---|---|\n"
            f"| full strobe run + maps.basins | {full_s:.2f} | |\n"
            f"| catalogue: pilot + map | {catalogue_s:.2f} | pilot {args.pilot} x "
            f"{args.pilot} (full run + attractor_catalogue) {pilot_s:.2f}, map "
            f"(stop_early) {map_s:.2f} |\n\n"
            f"Speed-up end to end: **{result['speedup']:.1f} x**.\n\n"
            f"Attractors: full run {result['attractors_full']} (periods "
            f"{result['periods_full']}), pilot catalogue {result['attractors_catalogue']} "
            f"(periods {result['periods_catalogue']}).\n\n"
            f"Labels (catalogue attractor -> the full run's label most of its starts "
            f"have): {counts['differing']} of {n} starts differ, "
            f"{counts['differing_where_both_resolve']} where both maps resolve the start; "
            f"unresolved: full {counts['unresolved_full']}, catalogue "
            f"{counts['unresolved_catalogue']}.\n\n"
            f"The differing starts run again by the full route over {2 * args.periods} "
            f"periods: {rechecked['agree_with_catalogue']} then settle on the catalogue's "
            f"attractor for them, {rechecked['other']} on another, "
            f"{rechecked['unresolved']} stay unresolved, and "
            f"{rechecked['catalogue_unresolved']} that the catalogue left at -1 (an "
            f"attractor the pilot missed, or not settled by t_end) settle.\n")
    write_results(args.out / "system_basins", result, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
