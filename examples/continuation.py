"""Attractors continued along the forcing amplitude
================================================

Which attractors survive along the forcing amplitude, and how their basins grow
and shrink.

The damped driven pendulum below resonance (g/L = 1, c = 0.1, W = 0.8 rad/s) has a
softening spring: as the forcing amplitude A grows, a large oscillation is born at a
saddle-node next to the small one, and a little later the small one vanishes. One run
over theta0 x omega0 x A, then `sweep.maps.continuation` matches the attractors found
at each A to those at the previous A (by the distance between their stroboscopic
points), so each keeps its label; the figure stacks their basin fractions.

Usage::

    python examples/continuation.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np
import xarray

import sweep
from sweep import maps

matplotlib.use("Agg")

FREQUENCY = 0.8  # rad/s


def compute(size: int) -> xarray.Dataset:
    """size x size starts in [-pi, pi] x [-2, 2] rad/s at 2 size amplitudes in
    [0.02, 0.4] rad/s^2; 184 periods of transient, 16 observed."""
    period = 2 * np.pi / FREQUENCY
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.1), sweep.Forcing(0.1, FREQUENCY)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-2.0, 2.0, size),
                      forcing_amplitude=np.linspace(0.02, 0.4, 2 * size))
    return sweep.run(scene, grid, t_end=200 * period, dt=period / 100,
                     t_transient=184 * period, observe=("strobe",), progress=False)


def main(argv=None) -> int:
    """Write continuation.png; print where each attractor exists."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=41, help="starts per phase-plane axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/continuation"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    _labels, fractions = maps.continuation(compute(args.size), along="forcing_amplitude")
    fig = sweep.plot.basin_fractions(
        fractions, title="damped driven pendulum (g/L = 1, c = 0.1, W = 0.8): basins")
    sweep.plot.save_figure(fig, args.out / "continuation.png", dpi=80)
    for a in fractions.attractor.values:
        print(f"attractor {a} (period {int(fractions.period[a])}): A from "
              f"{float(fractions.first[a]):.3f} to {float(fractions.last[a]):.3f} rad/s^2")
    print(f"wrote {args.out / 'continuation.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
