"""Period doubling and periodicity: an orbit diagram and a periodicity map.
========================================================================

Left: the orbit (bifurcation) diagram of Taylor's damped driven pendulum (Classical
Mechanics, ch. 12: phi'' + 2 beta phi' + w0^2 sin phi = gamma w0^2 cos(w t), w = 2 pi,
w0 = 1.5 w, beta = w0 / 4, from phi(0) = -pi/2): the angle at 64 successive drive
periods after a 400-period transient, against gamma, one run over the gamma axis. The
cascade 1 -> 2 -> 4 -> 8 and chaos appear at the book's thresholds (dashed).

Right: the period of the attractor over forcing amplitude x forcing frequency from one
start (g/L = 1, c = 0.5), with the chaotic cells (largest Lyapunov exponent > 0.01 /s)
in black: the "isoperiodic" picture of the literature.

Usage::

    python examples/orbit_diagram.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib
import numpy as np
import xarray

import sweep
from sweep import maps

matplotlib.use("Agg")

DRIVE = 2 * np.pi
W0 = 1.5 * DRIVE
BETA = W0 / 4
THRESHOLDS = (1.0663, 1.0793, 1.0821)  # Taylor: 1 -> 2, 2 -> 4, 4 -> 8
DT = 0.05  # s, for the periodicity map: every forcing period a whole number of steps
FREQUENCIES = (0.4, 1.0)  # rad/s, the periodicity map's forcing frequencies


def cascade(size: int) -> xarray.Dataset:
    """Taylor's pendulum over ``size`` gammas in [1.06, 1.087]: 64 strobe samples."""
    scene = sweep.Scene(gravity=W0 ** 2, length=1.0, effects=(
        sweep.Damping(2 * BETA), sweep.Forcing(W0 ** 2, DRIVE, np.pi / 2)))
    grid = sweep.Grid(forcing_amplitude=np.linspace(1.06, 1.087, size) * W0 ** 2,
                      theta0=[-np.pi / 2], omega0=[0.0])
    return sweep.run(scene, grid, t_end=464.0, dt=1 / 200, t_transient=400.0,
                     observe=("strobe",), strobe_samples=64, progress=False)


def time_step(size: int) -> float:
    """The periodicity map's step [s]: DT, or DT / k with the least whole k that fits
    ``size`` distinct forcing periods, each a whole number of steps, between those of
    FREQUENCIES (with DT alone only 189 fit)."""
    low, high = FREQUENCIES
    span = 2 * np.pi / low - 2 * np.pi / high  # s, from the shortest period to the longest
    return DT / max(1, math.ceil((size - 1) * DT / span))


def frequencies(size: int, dt: float = DT) -> np.ndarray:
    """``size`` forcing frequencies about FREQUENCIES [rad/s] whose periods are distinct
    whole numbers of steps ``dt``, increasing.

    Raises
    ------
    ValueError
        If ``dt`` is too coarse for ``size`` distinct periods (see `time_step`).
    """
    low, high = FREQUENCIES
    steps = np.unique(np.round(np.linspace(2 * np.pi / (high * dt), 2 * np.pi / (low * dt),
                                           size)))
    if steps.size != size:
        raise ValueError(f"only {steps.size} forcing periods in {FREQUENCIES} rad/s are "
                         f"distinct whole numbers of steps dt = {dt!r}, not size = {size}; "
                         "accepted: dt <= time_step(size)")
    return np.sort(2 * np.pi / (steps * dt))


def periodicity_run(size: int, observe=("strobe", "lyapunov")) -> tuple:
    """The periodicity map's ``(scene, grid, run keyword arguments)``: A in [0.8, 1.6]
    x W in FREQUENCIES, ``size`` values each, from rest; 500 s of transient and 16
    forcing periods observed, step `time_step` (size)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3)))
    dt = time_step(size)
    grid = sweep.Grid(forcing_amplitude=np.linspace(0.8, 1.6, size),
                      forcing_frequency=frequencies(size, dt), theta0=[0.0], omega0=[0.0])
    longest = 2 * np.pi / FREQUENCIES[0]
    n_steps = int(round((500.0 + 16 * longest) / dt))  # noqa: RUF046 - NumPy 1.x
    return scene, grid, dict(t_end=n_steps * dt, dt=dt, t_transient=500.0,
                             observe=tuple(observe), progress=False)


def periodicity(size: int) -> xarray.Dataset:
    """Strobe samples and lambda_max of `periodicity_run` (size)."""
    scene, grid, kwargs = periodicity_run(size)
    return sweep.run(scene, grid, **kwargs)


def main(argv=None) -> int:
    """Write orbit_diagram.png; print the share of each period on the map."""
    import matplotlib.pyplot as plt

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=161, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/orbit_diagram"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    line = cascade(3 * args.size)
    chart = periodicity(args.size)
    periods = maps.period(chart)

    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 4.8), layout="constrained")
    sweep.plot.orbit_diagram(line.assign_coords(
        forcing_amplitude=line.forcing_amplitude / W0 ** 2), along="forcing_amplitude",
        ax=left, title="Taylor's pendulum: orbit diagram", markersize=0.8)
    for gamma in THRESHOLDS:
        left.axvline(gamma, color="tab:red", lw=0.6, ls="--")
    left.set_xlabel(r"drive strength $\gamma$ (A = $\gamma\,\omega_0^2$)")
    sweep.plot.period_map(periods, lyapunov=chart["lyapunov_max"], ax=right, threshold=0.01,
                          title="period from rest (g/L = 1, c = 0.5)")
    sweep.plot.save_figure(fig, args.out / "orbit_diagram.png", dpi=80)
    values, counts = np.unique(periods.values, return_counts=True)
    print("periods on the map: " + ", ".join(f"{v}: {c / periods.size:.3f}"
                                             for v, c in zip(values, counts)))
    print(f"wrote {args.out / 'orbit_diagram.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
