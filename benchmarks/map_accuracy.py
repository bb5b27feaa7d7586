"""What the forced Wada map's accuracy costs: labels differing against RK4's step.

Scene: theta'' = A cos(t) - c theta' - sin(theta), c = 0.2 1/s, A = 1.66 rad/s^2 (g = L
= 1, W = 1 rad/s): three periodic attractors with a fractal (Wada) boundary. Starts:
``--samples`` scrambled Sobol points in theta0 in [-pi, pi], omega0 in [-4, 4]
(`sweep.sample`). Runs: 320 forcing periods, 20 of them transient, ``strobe`` with
``stop_early`` and one 41 x 41 pilot catalogue for every level (`sweep.map_accuracy`).

Ladders: RK4 with 25, 50, 100 and 200 steps per forcing period against 400 (the
reference), and float32 against float64 at 400. The fraction of labels differing
should fall like (trajectory error)^alpha = dt^(4 alpha), alpha the map's uncertainty
exponent; alpha is measured on a ``--size`` x ``--size`` map of the same box at 100
steps per period (`sweep.maps.metrics.uncertainty_exponent`, all cells), and the
measured rate is reported beside 4 alpha, not forced to it.

Writes ``benchmarks/results/map_accuracy.json`` and ``.md`` and the figure
``docs/images/map_accuracy_wada.png``.

Usage::

    python benchmarks/map_accuracy.py [--samples 20000] [--size 400] [--quick]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps
from sweep.maps import metrics

from _machine import machine, write_results

SCENE = sweep.Scene(gravity=1.0, length=1.0,
                    effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
PERIOD = 2 * np.pi
RUN = dict(t_end=320 * PERIOD, t_transient=20 * PERIOD, observe=("strobe",),
           stop_early=True)
BOX = dict(theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))
STEPS = (25, 50, 100, 200, 400)  # per forcing period; the last is the reference
ROOT = Path(__file__).resolve().parent


def alpha_of_map(size: int) -> tuple[float, dict]:
    """The uncertainty exponent of a size x size basins map at 100 steps per period."""
    grid = sweep.Grid(theta0=np.linspace(*BOX["theta0"], size),
                      omega0=np.linspace(*BOX["omega0"], size))
    catalogue = maps.pilot_catalogue(SCENE, grid, 41, dt=PERIOD / 100, **RUN)
    labels = maps.basins(sweep.run(SCENE, grid, dt=PERIOD / 100, attractors=catalogue,
                                   progress=False, **RUN))
    found = metrics.uncertainty_exponent(labels.values)
    return float(found.alpha), {"epsilons": np.asarray(found.epsilons).tolist(),
                                "fractions": np.asarray(found.fractions).tolist()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20000)
    parser.add_argument("--size", type=int, default=400)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--quick", action="store_true",
                        help="500 samples, a 64 x 64 map (a smoke test)")
    parser.add_argument("--out", type=Path, default=ROOT / "results")
    parser.add_argument("--figure", type=Path,
                        default=ROOT.parent / "docs" / "images" / "map_accuracy_wada.png")
    args = parser.parse_args(argv)
    samples, size = (500, 64) if args.quick else (args.samples, args.size)

    points = sweep.sample(samples, seed=args.seed, **BOX)
    began = time.perf_counter()
    acc = sweep.map_accuracy(SCENE, points, maps.basins,
                             {"dt": [PERIOD / s for s in STEPS],
                              "dtype": ["float32", "float64"]}, repeats=1, **RUN)
    seconds = time.perf_counter() - began
    rate = acc.rate("dt")
    alpha, exponent = alpha_of_map(size)
    ds = acc.dataset

    rows = ["| setting | value | steps / period | differing | std. error | max fraction "
            "shift | unresolved | wall time [s] | trajectory-steps (bound) |",
            "|---|---|---|---|---|---|---|---|---|"]
    for k in range(ds.sizes["level"]):
        rows.append(f"| {ds.setting.values[k]} | {ds.value.values[k] or '-'} | "
                    f"{PERIOD / float(ds.dt[k]):.0f} | {float(ds.differing[k]):.4f} | "
                    f"{float(ds.differing_error[k]):.4f} | {float(ds.max_shift[k]):.4f} | "
                    f"{float(ds.unresolved_fraction[k]):.4f} | "
                    f"{float(ds.wall_time[k]):.3f} | {float(ds.trajectory_steps[k]):.3g} |")
    text = "\n".join([
        "# Map accuracy: the forced Wada map's labels against RK4's step",
        "",
        f"- machine: {machine()}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- {samples} Sobol starts (seed {args.seed}), {seconds:.1f} s end to end "
        "(pilot, compilation, every level)",
        "",
        *rows,
        "",
        f"- rate of differing against dt (log-log slope over the dt levels): {rate:.3f}",
        f"- uncertainty exponent alpha of a {size} x {size} map (100 steps per period, "
        f"radii {exponent['epsilons']} cells): {alpha:.3f}; 4 alpha = {4 * alpha:.3f}",
        "",
    ])
    write_results(args.out / "map_accuracy", {
        "machine": machine(), "samples": samples, "seed": args.seed,
        "steps_per_period": list(STEPS), "seconds": seconds, "rate_dt": rate,
        "alpha": alpha, "alpha_map_size": size, "uncertainty": exponent,
        "table": {name: ds[name].values.tolist() for name in
                  ("differing", "differing_error", "max_shift", "unresolved_fraction",
                   "wall_time", "trajectory_steps")},
        "setting": ds.setting.values.tolist(), "value": ds.value.values.tolist()},
        text)
    if not args.quick:
        import matplotlib

        matplotlib.use("Agg")
        # wall time: with stop_early, trajectory-steps only bound what the runs took
        sweep.plot.save_figure(sweep.plot.map_accuracy(
            acc, title=f"Wada map, {samples} starts: labels differing from RK4 at "
                       "400 steps/period"), args.figure)
    return 0


if __name__ == "__main__":
    main()
