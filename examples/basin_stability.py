"""Basin stability of the driven pendulum: basin fractions from sampled starts.
============================================================================

theta'' = A cos(t) - c theta' - sin(theta), c = 0.2 1/s, A = 1.66 rad/s^2 (g = L = 1,
forcing frequency 1 rad/s; cos forcing is phase = pi/2): three coexisting periodic
attractors whose basins share a fractal (Wada) boundary. The full 1200 x 1200 map of
theta0 in [-pi, pi], omega0 in [-4, 4] gives them 0.396 / 0.384 / 0.220 of the box;
``--samples`` starts drawn by `sweep.sample` (scrambled Sobol by default) estimate the
same fractions with standard errors (`sweep.maps.fractions`), for 1/70th of the
trajectories at 20,000. Each start stops once it follows an attractor of the pilot
catalogue (`sweep.maps.pilot_catalogue`, 41 x 41 starts), as in examples/forced_basins.py.

With ``--replicates R`` the sample is drawn R times with seeds seed .. seed + R - 1, and
the standard error is the replicates' spread (randomised QMC) beside the binomial one.

Usage::

    python examples/basin_stability.py [--samples 20000] [--seed 1] [--method sobol]
                                       [--replicates R]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import xarray as xr

import sweep
from sweep import maps

#: The full 1200 x 1200 map's basin fractions (benchmarks/forced_basins.py), in the
#: pilot catalogue's label order.
FULL_MAP = (0.396, 0.384, 0.220)

SCENE = sweep.Scene(gravity=1.0, length=1.0,
                    effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
PERIOD = 2 * np.pi
RUN = dict(t_end=320 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD,
           observe=("strobe",), stop_early=True, progress=False)
BOX = dict(theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))


def catalogue(pilot: int = 41) -> dict:
    """The attractors of a pilot x pilot grid of the box."""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, pilot),
                      omega0=np.linspace(-4.0, 4.0, pilot))
    return maps.pilot_catalogue(SCENE, grid, pilot, **RUN)


def labels(n: int, seed: int, method: str = "sobol", attractors=None) -> xr.DataArray:
    """Basin labels of ``n`` starts sampled in the box."""
    points = sweep.sample(n, seed=seed, method=method, **BOX)
    attractors = catalogue() if attractors is None else attractors
    return maps.basins(sweep.run(SCENE, points, attractors=attractors, **RUN))


def wada_fractions(n: int, seed: int, method: str = "sobol", replicates: int = 1):
    """``(fractions table, seconds)``: `sweep.maps.fractions` of ``replicates`` samples
    of ``n`` starts (seeds ``seed`` ...), and the wall time end to end (pilot,
    compilation if not cached, runs, labels)."""
    began = time.perf_counter()
    attractors = catalogue()
    found = [labels(n, seed + r, method, attractors) for r in range(replicates)]
    stacked = found[0] if replicates == 1 else xr.concat(found, "replicate")
    return maps.fractions(stacked), time.perf_counter() - began


def main(argv=None) -> int:
    """Print the fractions, their standard errors and the full map's values."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--method", choices=("sobol", "random"), default="sobol")
    parser.add_argument("--replicates", type=int, default=1)
    args = parser.parse_args(argv)
    table, seconds = wada_fractions(args.samples, args.seed, args.method, args.replicates)
    print(f"{args.replicates} x {args.samples} {args.method} samples, {seconds:.2f} s end "
          f"to end; standard error: {table.attrs['standard_error_method'][:60]}...")
    print("label  fraction  standard error  full map  difference / standard error")
    resolved = table.where(~table.unresolved, drop=True)
    for k, full in enumerate(FULL_MAP[:resolved.sizes["label"]]):
        p = float(resolved.fraction[k])
        se = float(resolved.standard_error[k])
        print(f"{int(resolved.label[k]):5d}  {p:8.4f}  {se:14.4f}  {full:8.3f}  "
              f"{(p - full) / se:+10.2f}")
    unresolved = float(table.fraction.where(table.unresolved).sum())
    print(f"unresolved: {unresolved:.4f}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
