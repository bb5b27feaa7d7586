"""Where the driven pendulum is chaotic: Lyapunov exponents along a drive and over a map.
======================================================================================

Left: both exponents of Taylor's damped driven pendulum (Classical Mechanics, ch. 12:
phi'' + 2 beta phi' + w0^2 sin phi = gamma w0^2 cos(w t), w = 2 pi, w0 = 1.5 w,
beta = w0 / 4) from phi(0) = phi'(0) = 0 against the drive strength gamma. They sum to
-2 beta (the mean divergence); on a periodic orbit with complex Floquet multipliers
both sit at -beta, they split at each period doubling (one touches 0 there), and
lambda_max > 0 where the motion is chaotic (past gamma ~ 1.083).

Right: lambda_max over forcing amplitude x forcing frequency from one start, for the
pendulum with g/L = 1, c = 0.5 (Baker & Gollub's): red is chaos, blue periodic motion.

Usage::

    python examples/lyapunov_map.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np
import xarray

import sweep

matplotlib.use("Agg")

DRIVE = 2 * np.pi            # w [rad/s]: period 1 s
W0 = 1.5 * DRIVE             # natural frequency [rad/s]
BETA = W0 / 4                # damping constant [1/s]: c = 2 beta


def taylor(gammas) -> xarray.Dataset:
    """Both exponents against gamma, from rest; 100 periods of transient, 200 observed,
    200 steps per period."""
    scene = sweep.Scene(gravity=W0 ** 2, length=1.0,
                        effects=(sweep.Damping(2 * BETA),
                                 sweep.Forcing(W0 ** 2, DRIVE, np.pi / 2)))
    grid = sweep.Grid(forcing_amplitude=np.asarray(gammas) * W0 ** 2, theta0=[0.0],
                      omega0=[0.0])
    return sweep.run(scene, grid, t_end=300.0, dt=1 / 200, t_transient=100.0,
                     observe=("lyapunov",), progress=False)


def chaos_map(size: int) -> xarray.Dataset:
    """lambda_max over A in [0.8, 1.6] rad/s^2 x W in [0.4, 1.0] rad/s from rest."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3)))
    grid = sweep.Grid(forcing_amplitude=np.linspace(0.8, 1.6, size),
                      forcing_frequency=np.linspace(0.4, 1.0, size), theta0=[0.0],
                      omega0=[0.0])
    return sweep.run(scene, grid, t_end=1000.0, dt=0.05, t_transient=500.0,
                     observe=("lyapunov",), progress=False)


def main(argv=None) -> int:
    """Write lyapunov_map.png; print the chaotic share of each panel."""
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=161, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/lyapunov_map"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    gammas = np.linspace(1.0, 1.1, 2 * args.size)
    line = taylor(gammas)
    chart = chaos_map(args.size)

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    lam_max = line["lyapunov_max"].values.ravel()
    lam_min = line["lyapunov_min"].values.ravel()
    left.plot(gammas, lam_max, lw=0.8, label=r"$\lambda_{max}$")
    left.plot(gammas, lam_min, lw=0.8, label=r"$\lambda_{min}$")
    left.axhline(0.0, color="k", lw=0.5)
    left.axhline(-BETA, color="grey", lw=0.5, ls="--", label=r"$-\beta$")
    left.set_xlabel(r"drive strength $\gamma$ (A = $\gamma\,\omega_0^2$)")
    left.set_ylabel("Lyapunov exponent [1/s]")
    left.set_title("Taylor's driven pendulum from rest")
    left.legend(fontsize=8, loc="lower left")

    exponent = chart["lyapunov_max"].squeeze(drop=True)
    limit = float(np.nanmax(np.abs(exponent)))
    mesh = right.pcolormesh(exponent["forcing_amplitude"], exponent["forcing_frequency"],
                            exponent.transpose("forcing_frequency", "forcing_amplitude"),
                            cmap="RdBu_r", vmin=-limit, vmax=limit, shading="nearest")
    fig.colorbar(mesh, ax=right, label=r"$\lambda_{max}$ [1/s]")
    right.set_xlabel("forcing amplitude A [rad/s$^2$]")
    right.set_ylabel("forcing frequency W [rad/s]")
    right.set_title("Largest exponent from rest (g/L = 1, c = 0.5)")
    fig.tight_layout()
    sweep.plot.save_figure(fig, args.out / "lyapunov_map.png", dpi=80)
    print(f"chaotic (lambda_max > 0.01 /s): {np.mean(lam_max > 0.01):.3f} of the gamma "
          f"line, {float((exponent > 0.01).mean()):.3f} of the map")
    print(f"wrote {args.out / 'lyapunov_map.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
