"""Basins of the damped pendulum: which well each start ends in (the spiral bands).
================================================================================

An unforced pendulum with damping c loses energy until it is captured in one of the
wells theta = 2 pi k. Which well depends on how many turns it makes first, so the
basins in the (theta0, omega0) plane are bands that wind around the origin. The run
observes only what the map needs: ``capture``, the well at the moment the energy first
drops below the separatrix energy 2 g/L (after which the well can never change), and
with ``stop_early=True`` each trajectory stops right there.

Usage::

    python examples/damped_basins.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sweep
from sweep import maps


def compute(size: int):
    """Run the sweep: theta0 in [-pi, pi], omega0 in [-12, 12] rad/s, c = 0.25 1/s.

    Returns
    -------
    xarray.Dataset
    """
    scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.25),))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-12.0, 12.0, size))
    return sweep.run(scene, grid, t_end=40.0, dt=0.02, observe=("capture",),
                     stop_early=True)


def main(argv=None) -> int:
    """Write basins.png and basins.nc into the output folder."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=401, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/damped_basins"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    ds = compute(args.size)
    wells = maps.well(ds)
    fig = sweep.plot.map(wells, title="Damped pendulum: final well (c = 0.25 1/s)")
    sweep.plot.save_figure(fig, args.out / "basins.png")
    sweep.save(ds, args.out / "basins.nc")
    labels = maps.basins(ds)
    fractions = sweep.metrics.basin_fractions(labels.values)
    well_of = np.round(labels.attrs["attractor_theta"] / (2 * np.pi)).astype(int)
    print("basin fraction per well k: " + ", ".join(
        f"{'unresolved' if label < 0 else int(well_of[label])}: {share:.4f}"
        for label, share in sorted(fractions.items())))
    print(f"wrote {args.out / 'basins.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
