"""Basins of the driven pendulum: coexisting periodic attractors with fractal boundaries.
======================================================================================

theta'' = A cos(t) - c theta' - sin(theta) with c = 0.2 1/s, A = 1.66 rad/s^2 (g = L = 1,
forcing frequency 1 rad/s; cos forcing is phase = pi/2). After a transient, each start
is sampled once per forcing period (observable ``strobe``); `sweep.maps.basins` finds
the periodic orbit the samples sit on (period, turns per period) and labels the start
by it. With ``stop_early=True`` each start stops as soon as its 16 latest samples repeat,
so ``--periods`` is only an upper bound; with a pilot (``--pilot N``, default 41: N x N
starts find the attractors first, `sweep.maps.pilot_catalogue`) a start stops as soon
as it follows one of them, about 2.4x sooner on this map. The boundaries between basins
are fractal: the boundary basin entropy exceeds log 2 (Daza et al. 2016).

Usage::

    python examples/forced_basins.py [--size N] [--periods P] [--out FOLDER]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import sweep
from sweep import maps, metrics

STEPS_PER_PERIOD = 100


def compute(size: int, periods: int, pilot: int = 41):
    """Run the sweep on a size x size grid of theta0 in [-pi, pi], omega0 in [-4, 4]
    (``pilot`` > 0: with the attractor catalogue of a pilot x pilot pilot run)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-4.0, 4.0, size))
    period = 2 * np.pi
    kwargs = dict(t_end=periods * period, dt=period / STEPS_PER_PERIOD,
                  t_transient=20 * period, observe=("strobe",), stop_early=True)
    if pilot:
        kwargs["attractors"] = maps.pilot_catalogue(scene, grid, pilot, **kwargs)
    return sweep.run(scene, grid, **kwargs)


def main(argv=None) -> int:
    """Write forced_basins.png and forced_basins.nc; print the attractor catalogue."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=301, help="grid points per axis")
    parser.add_argument("--periods", type=int, default=300,
                        help="most forcing periods a start is integrated (from period 20 "
                             "on it stops once its stroboscopic samples repeat)")
    parser.add_argument("--pilot", type=int, default=41,
                        help="points per axis of the pilot run that catalogues the "
                             "attractors (0: none, stop on the strobe test alone)")
    parser.add_argument("--out", type=Path, default=Path("examples/output/forced_basins"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    ds = compute(args.size, args.periods, args.pilot)
    labels = maps.basins(ds)
    fig = sweep.plot.basins(labels, title="Driven pendulum basins (c = 0.2, A = 1.66, "
                                          "W = 1, cos forcing)")
    sweep.plot.save_figure(fig, args.out / "forced_basins.png")
    sweep.save(ds, args.out / "forced_basins.nc")
    a = labels.attrs
    print("label  period  turns/period  theta [rad]  omega [rad/s]  basin fraction")
    for k in range(len(a["attractor_size"])):
        print(f"{k:5d}  {a['attractor_period'][k]:6d}  {a['attractor_turns_per_period'][k]:12.2f}"
              f"  {a['attractor_theta'][k]:11.4f}  {a['attractor_omega'][k]:13.4f}"
              f"  {a['attractor_size'][k] / labels.size:14.4f}")
    print(f"unresolved: {float((labels == maps.UNRESOLVED).mean()):.4f}")
    entropy = metrics.basin_entropy(labels.values, box_size=5)
    print(f"basin entropy Sb = {entropy.sb:.3f}, boundary basin entropy Sbb = {entropy.sbb:.3f}"
          f" ({'> log 2: fractal boundary' if entropy.fractal_boundary else '<= log 2'})")
    print(f"wrote {args.out / 'forced_basins.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
