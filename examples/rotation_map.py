"""Where does the driven pendulum rotate instead of librate?
=========================================================

A damped pendulum driven by A sin(W t) settles, after a transient, into a steady
motion: a libration (bounded oscillation) or a rotation (net turns every period, in
either sense). This example maps that steady motion over forcing amplitude and
frequency, from the mean angular velocity over the steady window (observable
``omega_mean``), for one start at rest at the bottom.

Usage::

    python examples/rotation_map.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sweep
from sweep import maps


def compute(size: int):
    """Sweep forcing amplitude in [0.2, 2.5] rad/s^2 and frequency in [0.3, 2] rad/s.

    g = L = 1 (omega_n = 1 rad/s), damping 0.2 1/s; 150 s of transient, 100 s observed.
    """
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.0, 1.0)))
    grid = sweep.Grid(forcing_amplitude=np.linspace(0.2, 2.5, size),
                      forcing_frequency=np.linspace(0.3, 2.0, size), theta0=[0.0])
    return sweep.run(scene, grid, t_end=250.0, dt=0.02, t_transient=150.0,
                     observe=("amplitude", "omega_mean"))


def main(argv=None) -> int:
    """Write rotation.png, amplitude.png and rotation.nc into the output folder."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=201, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/rotation_map"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    ds = compute(args.size)
    motion = maps.motion(ds).squeeze("theta0", drop=True)
    fig = sweep.plot.map(motion, title="Driven pendulum: steady motion (c = 0.2 1/s)")
    sweep.plot.save_figure(fig, args.out / "rotation.png")
    amplitude = maps.amplitude(ds).squeeze("theta0", drop=True)
    fig = sweep.plot.map(amplitude, title="Steady amplitude (blank: rotation)")
    sweep.plot.save_figure(fig, args.out / "amplitude.png")
    sweep.save(ds, args.out / "rotation.nc")
    shares = {name: float((motion == code).mean()) for code, name in
              ((-1, "rotation -"), (0, "libration"), (1, "rotation +"))}
    print("shares: " + ", ".join(f"{k} {v:.3f}" for k, v in shares.items()))
    print(f"wrote {args.out / 'rotation.png'} and {args.out / 'amplitude.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
