"""Kapitza's pendulum: a fast vertical pivot drive makes the upside-down position stable.
======================================================================================

The pivot moves as y = a cos(nu t) (sweep.PivotDrive); averaging over the fast drive
gives an effective potential whose maximum at the top turns into a minimum when
a nu > sqrt(2 g L) (leading order in sqrt(g/L)/nu). This example starts the pendulum
0.1 rad from the top, at rest, with light damping, and maps `sweep.maps.inverted` (does
it stay within 0.5 rad of the top after the transient?) over (pivot_amplitude,
pivot_frequency), with Kapitza's threshold curve a nu = sqrt(2 g L) drawn on it.

Usage::

    python examples/kapitza.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib
import numpy as np

import sweep
from sweep import maps

matplotlib.use("Agg")

G, L = 9.81, 1.0


def compute(size: int):
    """a in [0, 0.25] m, nu in [20, 200] rad/s (nu / w0 from 6 to 64), c = 0.2 1/s;
    64 steps per period of the fastest drive; 5 s of transient, 5 s observed."""
    scene = sweep.Scene(gravity=G, length=L,
                        effects=(sweep.Damping(0.2), sweep.PivotDrive(0.1, 100.0)))
    grid = sweep.Grid(pivot_amplitude=np.linspace(0.0, 0.25, size),
                      pivot_frequency=np.linspace(20.0, 200.0, size),
                      theta0=[math.pi - 0.1], omega0=[0.0])
    dt = 2 * math.pi / 200.0 / 64
    return sweep.run(scene, grid, t_end=round(10.0 / dt) * dt, dt=dt, t_transient=5.0,
                     observe=("top_distance",))


def main(argv=None) -> int:
    """Write kapitza.png into the output folder; print the share that stays up."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=121, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/kapitza"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    ds = compute(args.size)
    up = maps.inverted(ds, tolerance=0.5).squeeze(drop=True).astype(np.int8)
    up.attrs = {"long_name": "stays inverted (1) or falls (0)"}
    fig = sweep.plot.map(up, degrees=False,
                         title="Kapitza's pendulum: start 0.1 rad from the top")
    ax = fig.axes[0]
    a = np.linspace(math.sqrt(2 * G * L) / 200.0, 0.25, 200)
    ax.plot(a, math.sqrt(2 * G * L) / a, "w--", lw=1.5, label="a nu = sqrt(2 g L)")
    ax.set_ylim(20.0, 200.0)
    ax.legend(loc="upper right", fontsize=8)
    sweep.plot.save_figure(fig, args.out / "kapitza.png", dpi=80)
    print(f"stays up: share {float(up.mean()):.3f}")
    print(f"wrote {args.out / 'kapitza.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
