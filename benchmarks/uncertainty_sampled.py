"""Measure the uncertainty exponent below the grid's scale (`sweep.maps.uncertainty_sampled`)
and the basin-entropy fractality test (`sweep.maps.metrics.fractality_test`), on this
machine.

Cases:

- the McDonald-Grebogi-Ott-Yorke map x -> 3x mod 1, y -> 1.5y + cos(2 pi x) (a plain
  NumPy labelling; exact alpha = ln 1.5 / ln 3 = 0.3691), box [0, 1] x [-2, 2];
- the map of Grebogi et al. (1983), theta' = theta + 1.32 sin 2 theta - 0.9 sin 4 theta
  - x sin theta (mod 2 pi), x' = -0.3 cos theta (published alpha ~ 0.2), box
  [0, 2 pi] x [-0.5, 0.5];
- the damped pendulum's wells (g = L = 1, c = 0.2, t_end = 40 s, dt = 0.02 s,
  ``capture`` with ``stop_early``), box theta0 in [-pi, pi], omega0 in [-4, 4];
- the forced Wada scene (c = 0.2, A = 1.66, W = 1, cos forcing, RK4 with 100 steps per
  period, at most 320 periods, ``stop_early`` with a 21 x 21 pilot's attractor catalogue),
  same box.

For each: alpha, its standard error, the reduced chi-square, the smallest and largest
eps, pairs per level and the wall time (labels included; the pilot is timed apart,
kernels are compiled before anything is timed). Then the fractality test on a
``--size`` x ``--size`` map of each pendulum scene (radius 3) and on the MGOY map
rendered on 400 x 400 cells (radius 10), and `box_counting_dimension` of the MGOY map
rendered on 1024 x 1024 cells.

Writes ``benchmarks/results/uncertainty_sampled.json`` and ``.md``.

Usage::

    python benchmarks/uncertainty_sampled.py [--pairs 1000] [--size 201]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps
from sweep.maps.metrics import box_counting_dimension, fractality_test

from _machine import machine, write_results

BOX = ((-np.pi, np.pi), (-4.0, 4.0))
WADA = sweep.Scene(gravity=1.0, length=1.0,
                   effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
WADA_RUN = dict(t_end=320 * 2 * np.pi, dt=2 * np.pi / 100, t_transient=20 * 2 * np.pi,
                observe=("strobe",), stop_early=True, progress=False)
DAMPED = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.2),))
WELLS_RUN = dict(t_end=40.0, dt=0.02, observe=("capture",), stop_early=True, progress=False)


def mgoy_labels(starts):
    x, y = starts[:, 0].copy(), starts[:, 1].copy()
    for _ in range(80):
        y = 1.5 * y + np.cos(2 * np.pi * x)
        x = (3.0 * x) % 1.0
    return (y > 0).astype(np.int64)


def grebogi_labels(starts):
    theta, x = starts[:, 0].copy(), starts[:, 1].copy()
    for _ in range(100):
        theta, x = (np.mod(theta + 1.32 * np.sin(2 * theta) - 0.9 * np.sin(4 * theta)
                           - x * np.sin(theta), 2 * np.pi), -0.3 * np.cos(theta))
    return np.cos(theta) > 0


def mgoy_map(n):
    x = (np.arange(n) + 0.5) / n
    y = -2.0 + 4.0 * (np.arange(n) + 0.5) / n
    starts = np.column_stack([a.ravel() for a in np.meshgrid(x, y, indexing="ij")])
    return mgoy_labels(starts).reshape(n, n)


def phase_grid(n):
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n), omega0=np.linspace(-4.0, 4.0, n))


def sampled(name, labels_of, box, eps, pairs, exact=None):
    start = time.perf_counter()
    result = maps.uncertainty_sampled(labels_of, box, eps=eps, n=pairs, seed=0)
    seconds = time.perf_counter() - start
    return dict(case=name, alpha=result.alpha, alpha_error=result.alpha_error,
                reduced_chi2=result.reduced_chi2, exact=exact, eps_min=min(eps),
                eps_max=max(eps), pairs=pairs, levels=len(eps), seconds=seconds,
                f=list(result.f), uncertain=list(result.uncertain))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=1000,
                        help="pairs per eps level for the pendulum scenes")
    parser.add_argument("--size", type=int, default=201, help="side of the rendered maps")
    args = parser.parse_args()

    start = time.perf_counter()
    grid = phase_grid(21)
    catalogue = maps.attractor_catalogue(sweep.run(WADA, grid, **WADA_RUN))
    pilot_seconds = time.perf_counter() - start
    wada_labels = maps.scene_labels(WADA, attractors=catalogue, **WADA_RUN)
    well_labels = maps.scene_labels(DAMPED, maps.well, **WELLS_RUN)
    # compile (or load) the kernels before timing
    wada_labels(np.zeros((3000, 2)))
    well_labels(np.zeros((3000, 2)))

    rows = [
        sampled("MGOY map", mgoy_labels, ((0.0, 1.0), (-2.0, 2.0)),
                list(10.0 ** -np.arange(3, 10)), 20000, f"{math.log(1.5) / math.log(3.0):.4f}"),
        sampled("Grebogi et al. (1983) map", grebogi_labels, ((0.0, 2 * np.pi), (-0.5, 0.5)),
                list(10.0 ** -np.arange(2, 10)), 20000, "~0.2 (published)"),
        sampled("pendulum wells", well_labels, BOX, [1e-2, 3e-3, 1e-3, 3e-4],
                20 * args.pairs, "1"),
        sampled("forced Wada scene", wada_labels, BOX, list(10.0 ** -np.arange(2, 10)),
                args.pairs),
    ]

    tests = []
    for name, labels, radius in (
            ("MGOY map, 400 x 400", mgoy_map(400), 10),
            (f"pendulum wells, {args.size} x {args.size}",
             maps.basins(sweep.run(DAMPED, phase_grid(args.size), **WELLS_RUN)), 3),
            (f"forced Wada scene, {args.size} x {args.size}",
             maps.basins(sweep.run(WADA, phase_grid(args.size), attractors=catalogue,
                                   **WADA_RUN)), 3)):
        begin = time.perf_counter()
        result = fractality_test(labels, radius=radius, rng=0)
        tests.append(dict(case=name, radius=radius, sbb=result.sbb,
                          sbb_error=result.sbb_error, smooth_low=result.smooth_low,
                          smooth_high=result.smooth_high, fractal=result.fractal,
                          seconds=time.perf_counter() - begin))
    box = box_counting_dimension(mgoy_map(1024))

    text = [f"# Uncertainty exponent below the grid's scale\n\nMachine: {machine()}\n",
            f"Wada pilot (21 x 21 starts, attractor catalogue): {pilot_seconds:.1f} s\n",
            "| case | alpha | standard error | exact | reduced chi2 | eps | pairs per level "
            "| labels | time [s] |", "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        exact = row["exact"] or "-"
        text.append(f"| {row['case']} | {row['alpha']:.3f} | {row['alpha_error']:.3f} | "
                    f"{exact} | {row['reduced_chi2']:.2f} | {row['eps_min']:.0e} to "
                    f"{row['eps_max']:.0e} | {row['pairs']} | "
                    f"{2 * row['pairs'] * row['levels']} | {row['seconds']:.2f} |")
    text += ["", "| map | radius [cells] | Sbb | standard error | smooth interval | verdict "
             "| time [s] |", "|---|---|---|---|---|---|---|"]
    for row in tests:
        text.append(f"| {row['case']} | {row['radius']} | {row['sbb']:.3f} | "
                    f"{row['sbb_error']:.3f} | {row['smooth_low']:.3f} to "
                    f"{row['smooth_high']:.3f} | "
                    f"{'fractal' if row['fractal'] else 'smooth'} | {row['seconds']:.2f} |")
    text += ["", f"box_counting_dimension of the MGOY map on 1024 x 1024 cells: "
             f"{box.dimension:.3f} (exact {2 - math.log(1.5) / math.log(3.0):.3f}; box "
             f"sizes {box.box_sizes})", ""]
    out = Path(__file__).resolve().parent / "results" / "uncertainty_sampled"
    write_results(out, dict(machine=machine(), pilot_seconds=pilot_seconds, sampled=rows,
                            fractality=tests, mgoy_box_counting=box.dimension),
                  "\n".join(text))


if __name__ == "__main__":
    main()
