"""Stability chart of the damped Mathieu equation (linear pendulum, vertical pivot drive).
=======================================================================================

With the linear model and sweep.PivotDrive the pendulum obeys
theta'' + c theta' + (g/L - (a nu^2 / L) cos(nu t)) theta = 0: the damped Mathieu
equation, y'' + 2 mu y' + (A - 2 q cos 2s) y = 0 with s = nu t / 2, A = 4 g / (L nu^2),
q = 2 a / L. Its parametric-resonance tongues grow from nu = 2 sqrt(g/L) / n. This
example maps bounded versus growing motion over (pivot_amplitude, pivot_frequency)
from theta0 = 1 rad, and draws the undamped tongue edges (SciPy's Mathieu
characteristic values b_n(q), a_n(q)) when SciPy is installed; damping lifts the
tongues off the q = 0 axis.

Usage::

    python examples/mathieu_chart.py [--size N] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np

import sweep

matplotlib.use("Agg")

C = 0.1  # damping [1/s]; g = L = 1


def compute(size: int):
    """a in [0, 1] m (q up to 2), nu in [0.4, 4] rad/s; 150 s transient, 50 s observed."""
    scene = sweep.Scene(gravity=1.0, length=1.0, model="linear",
                        effects=(sweep.Damping(C), sweep.PivotDrive(0.1, 2.0)))
    grid = sweep.Grid(pivot_amplitude=np.linspace(0.0, 1.0, size),
                      pivot_frequency=np.linspace(0.4, 4.0, size), theta0=[1.0],
                      omega0=[0.0])
    with np.errstate(all="ignore"):
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the fastest-growing runs overflow: flagged
            return sweep.run(scene, grid, t_end=200.0, dt=0.01, t_transient=150.0,
                             observe=("theta_max",))


def growing(ds):
    """1 where theta_max over the steady window exceeds the start (or overflowed)."""
    grows = (ds["theta_max"] > 1.0) | (ds["status"] != int(sweep.Status.OK))
    grows = grows.squeeze(drop=True).astype(np.int8)
    grows.attrs = {"long_name": "growing (1) or bounded (0)"}
    return grows.rename("growing")


def tongue_edges(n_max: int = 4):
    """[(label, a, nu)] of the undamped tongue edges A = b_n(q), a_n(q), or [] without
    SciPy."""
    try:
        from scipy.special import mathieu_a, mathieu_b
    except ImportError:
        return []
    q = np.linspace(1e-3, 2.0, 200)
    edges = []
    for n in range(1, n_max + 1):
        for name, fn in (("b", mathieu_b), ("a", mathieu_a)):
            big_a = fn(n, q)
            ok = big_a > 0
            edges.append((f"{name}_{n}", q[ok] / 2, 2.0 / np.sqrt(big_a[ok])))
    return edges


def main(argv=None) -> int:
    """Write mathieu_chart.png into the output folder; print the growing share."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=161, help="grid points per axis")
    parser.add_argument("--out", type=Path, default=Path("examples/output/mathieu_chart"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    grows = growing(compute(args.size))
    fig = sweep.plot.map(grows, degrees=False,
                         title=f"Damped Mathieu equation (c = {C} 1/s, g/L = 1)")
    ax = fig.axes[0]
    edges = tongue_edges()
    for k, (_label, a, nu) in enumerate(edges):
        ax.plot(a, nu, "w-", lw=0.8, label="undamped tongue edges" if k == 0 else None)
    if edges:
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.4, 4.0)
    sweep.plot.save_figure(fig, args.out / "mathieu_chart.png", dpi=80)
    print(f"growing: share {float(grows.mean()):.3f}; tongue edges drawn: {len(edges)}")
    print(f"wrote {args.out / 'mathieu_chart.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
