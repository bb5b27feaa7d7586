"""Locked versus running: the pendulum with a constant torque (tilted washboard).
==============================================================================

theta'' = tau - c theta' - (g/L) sin(theta) is also the RCSJ model of a Josephson
junction (angle = phase, torque = bias current, mean angular velocity = DC voltage).
A locked state (rest at sin(theta) = tau L/g) exists for tau < g/L; a running state
(rotation) exists above the retrapping torque, 4 c sqrt(g/L) / pi for small damping
(Melnikov; Strogatz sec. 8.5). In between both exist, and which one the pendulum ends
in depends on where it starts: this is the hysteresis of the junction's I-V curve.

The figure has three panels: the steady motion over (torque, damping) from rest and
from a running start (omega0 = 10 rad/s), with the lines tau = g/L and tau = 4 c/pi;
and over (theta0, omega0) at tau = 0.5, c = 0.1, where both states coexist.

Usage::

    python examples/torque_locked_running.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np

import sweep
from sweep import maps

matplotlib.use("Agg")

RUN = dict(t_end=300.0, dt=0.05, t_transient=200.0, observe=("omega_mean",))


def parameter_map(size: int, omega0: float):
    """Steady motion over torque in [0, 1.2] and damping in [0.02, 0.5] (g = L = 1)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.1), sweep.Torque(0.5)))
    grid = sweep.Grid(torque=np.linspace(0.0, 1.2, size),
                      damping=np.linspace(0.02, 0.5, size), theta0=[0.0], omega0=[omega0])
    return maps.motion(sweep.run(scene, grid, **RUN))


def phase_map(size: int, torque: float = 0.5, damping: float = 0.1):
    """Steady motion over (theta0, omega0) where locked and running states coexist."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(damping), sweep.Torque(torque)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-4.0, 4.0, size))
    return maps.motion(sweep.run(scene, grid, **RUN))


def main(argv=None) -> int:
    """Write torque_locked_running.png into the output folder; print the shares."""
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=161, help="grid points per axis")
    parser.add_argument("--out", type=Path,
                        default=Path("examples/output/torque_locked_running"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), layout="constrained")
    rest = parameter_map(args.size, 0.0).squeeze(drop=True)
    running = parameter_map(args.size, 10.0).squeeze(drop=True)
    for ax, motion, title in ((axes[0], rest, "from rest"),
                              (axes[1], running, "from omega0 = 10 rad/s")):
        sweep.plot.map(motion, ax=ax, degrees=False,
                       title=f"locked (0) / running (1), {title}")
        c = motion["damping"].values
        ax.plot(4 * c / np.pi, c, "w--", lw=1.5, label="4 c / pi (retrapping)")
        ax.axvline(1.0, color="w", ls=":", lw=1.5, label="g/L (locked limit)")
        ax.legend(loc="upper right", fontsize=8)
    phase = phase_map(args.size).squeeze(drop=True)
    sweep.plot.map(phase, ax=axes[2], title="tau = 0.5, c = 0.1: both coexist")
    sweep.plot.save_figure(fig, args.out / "torque_locked_running.png", dpi=80)
    for name, motion in (("from rest", rest), ("running start", running),
                         ("phase plane", phase)):
        print(f"{name}: running share {float((motion == 1).mean()):.3f}")
    print(f"wrote {args.out / 'torque_locked_running.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
