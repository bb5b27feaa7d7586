"""The double pendulum: how long until either arm flips over the top.
================================================================================

Two equal masses on equal rods (``sweep.DoublePendulum``), released from rest at angles
``(theta1_0, theta2_0)`` from the downward vertical (``theta2`` absolute). For each
start the map shows the time until either arm first passes an upright position
(``observe=("flip",)``, interpolated within the step), in units of ``sqrt(l/g)``. Starts
with too little energy can never flip (blank: the region around the origin bounded by
``3 cos(theta1) + cos(theta2) = 2``); near it the flip times form the double
pendulum's best-known fractal. With ``stop_early=True`` each trajectory stops at its
flip, so the map costs only the time each start takes to flip.

Usage::

    python examples/double_pendulum_flip.py [--size N] [--t-max T] [--out FOLDER]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import sweep

GRAVITY, LENGTH = 9.81, 1.0


def compute(size: int, t_max: float):
    """Flip times over theta1_0, theta2_0 in [-3, 3] rad, from rest, up to ``t_max``
    natural time units sqrt(l/g).

    Returns
    -------
    xarray.Dataset
    """
    unit = math.sqrt(LENGTH / GRAVITY)
    system = sweep.DoublePendulum(length1=LENGTH, length2=LENGTH, gravity=GRAVITY)
    angles = np.linspace(-3.0, 3.0, size)
    grid = sweep.Grid(theta1_0=angles, theta2_0=angles)
    dt = unit / 100  # 100 steps per natural time unit
    n_steps = round(t_max * 100)
    return sweep.run(system, grid, t_end=n_steps * dt, dt=dt, observe=("flip",),
                     stop_early=True)


def main(argv=None) -> int:
    """Write flip_time.png and flip_time.nc into the output folder."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=401, help="grid points per axis")
    parser.add_argument("--t-max", type=float, default=100.0,
                        help="longest flip time computed [sqrt(l/g)]")
    parser.add_argument("--out", type=Path, default=Path("examples/output/double_pendulum"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    ds = compute(args.size, args.t_max)
    elapsed = time.perf_counter() - start
    flip = ds.flip_time / math.sqrt(LENGTH / GRAVITY)
    shown = np.log10(flip).rename("log10_flip_time")
    shown.attrs = {"long_name": "log10 of the time to the first flip [sqrt(l/g)]",
                   "units": "1"}
    fig = sweep.plot.map(shown, degrees=False, cmap="magma",
                         title="Double pendulum: time to the first flip (blank: none)")
    sweep.plot.save_figure(fig, args.out / "flip_time.png")
    sweep.save(ds, args.out / "flip_time.nc")
    never = float(ds.flip_time.isnull().mean())
    print(f"{ds.flip_time.size} starts in {elapsed:.1f} s; {never:.1%} never flip "
          f"within {args.t_max:g} sqrt(l/g)")
    print(f"wrote {args.out / 'flip_time.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
