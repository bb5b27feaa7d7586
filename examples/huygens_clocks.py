"""Huygens' two clocks: in-phase and anti-phase synchronization basins.
================================================================================

Two pendulum clocks hang from one beam that can slide (Huygens' "odd sympathy", 1665).
The beam (mass ``M``, position ``x``) is held by a spring ``k`` and a damper ``c``; each
pendulum (bob ``m`` on a rod ``l``, angle ``theta_i`` from the downward vertical) is
kept swinging by its escapement, modelled as a van der Pol torque
``-eps (theta_i^2 - theta_a^2) omega_i``: it pushes small swings up and brakes large
ones, so a lone clock settles at an amplitude near ``2 theta_a``. This is the model of
Czolczynski, Perlikowski, Stefanski and Kapitaniak (Physica A 388, 5013 (2009);
"Huygens' odd sympathy experiment revisited", Int. J. Bifurcation Chaos 21, 2047
(2011)), with a van der Pol escapement in place of their discrete one; Bennett,
Schatz, Rockwood and Wiesenfeld (Proc. R. Soc. A 458, 563 (2002)) give the experiment
and a beam-coupled model of the same kind. The system is declared by its Lagrangian
and generalized forces (``sweep.DeclaredSystem``)::

    L = (M + 2 m) v^2 / 2 + m l v (omega1 cos theta1 + omega2 cos theta2)
        + m l^2 (omega1^2 + omega2^2) / 2 - k x^2 / 2 + m g l (cos theta1 + cos theta2)

With the parameters below both synchronized states exist and are stable: the clocks
swing **in phase** (amplitude 0.18 rad; the beam moves and its damper takes energy) or
**in anti-phase** (amplitude 0.20 rad; the beam stays at rest). Which one a start
reaches is read from the final state: the relative phase of the two clocks, with the
phase ``phi_i = atan2(-omega_i / Omega, theta_i)`` at the pendula's frequency
``Omega = sqrt(g / l)``; ``|phi1 - phi2| < pi/2`` is in phase. The map colours each
start ``(theta1_0, theta2_0)`` (from rest, the beam at rest) by the state it reaches.
``tests/test_huygens_clocks.py`` checks the labels of a few starts against SciPy's
DOP853 and that both states persist.

Usage::

    python examples/huygens_clocks.py [--size N] [--t-end T] [--out FOLDER]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import sweep
from sweep.physics import Coordinate, Parameter, SystemDeclaration

#: The parameters [SI]: a beam 10 times a bob, on a soft spring (its own frequency
#: sqrt(k / (M + 2 m)) = 0.91 rad/s, well below the pendula's 3.13 rad/s), lightly
#: damped; a weak escapement (eps theta_a^2 / Omega = 0.016: close to harmonic swings).
VALUES = {"M": 10.0, "m": 1.0, "l": 1.0, "g": 9.81, "k": 10.0, "c": 0.5, "eps": 5.0,
          "theta_a": 0.1}

#: The two synchronized states (label values of `phase_label`).
IN_PHASE, ANTI_PHASE = 1, -1


def declaration() -> SystemDeclaration:
    """The beam and the two clocks: coordinates x [m], theta1, theta2 [rad]."""
    def parameter(name, symbol, units, long_name, minimum=0.0):
        return Parameter(name, name, symbol, units, units, long_name, minimum=minimum,
                         strict=minimum is not None)
    return SystemDeclaration(
        name="huygens_clocks",
        coordinates=(
            Coordinate("x", "v", "xb", "vb", units="m", velocity_units="m s-1",
                       long_name="beam position", angular=False),
            Coordinate("theta1", "omega1", "th_1", "om_1", long_name="first clock's angle"),
            Coordinate("theta2", "omega2", "th_2", "om_2", long_name="second clock's angle")),
        parameters=(
            parameter("M", "Mb", "kg", "beam mass"),
            parameter("m", "mp", "kg", "bob mass"),
            parameter("l", "lp", "m", "rod length"),
            parameter("g", "gr", "m s-2", "gravity"),
            parameter("k", "kb", "N m-1", "beam spring constant", minimum=None),
            parameter("c", "cb", "N s m-1", "beam damping", minimum=None),
            parameter("eps", "es", "N m s", "escapement gain", minimum=None),
            parameter("theta_a", "tha", "rad", "escapement amplitude scale")),
        lagrangian="(Mb + 2*mp)*vb**2/2 + mp*lp*vb*(om_1*cos(th_1) + om_2*cos(th_2))"
                   " + mp*lp**2*(om_1**2 + om_2**2)/2 - kb*xb**2/2"
                   " + mp*gr*lp*(cos(th_1) + cos(th_2))",
        forces=("-cb*vb", "-es*(th_1**2 - tha**2)*om_1", "-es*(th_2**2 - tha**2)*om_2"))


def clocks(**values) -> sweep.DeclaredSystem:
    """The system with `VALUES`, changed by ``values``."""
    return sweep.DeclaredSystem(declaration(), **{**VALUES, **values})


def phase_label(theta1, omega1, theta2, omega2, frequency: float):
    """`IN_PHASE` (1) where the two clocks' phases differ by less than pi/2, else
    `ANTI_PHASE` (-1); phases ``atan2(-omega / frequency, theta)`` [rad]."""
    phi1 = np.arctan2(-np.asarray(omega1) / frequency, theta1)
    phi2 = np.arctan2(-np.asarray(omega2) / frequency, theta2)
    difference = np.angle(np.exp(1j * (phi1 - phi2)))
    return np.where(np.abs(difference) < math.pi / 2, IN_PHASE, ANTI_PHASE)


def compute(size: int, t_end: float, dt: float = 0.01, extent: float = 0.6):
    """The final states of ``size x size`` starts ``theta1_0, theta2_0`` in
    ``[-extent, extent]`` rad, from rest, and their labels.

    Returns
    -------
    ds : xarray.Dataset
        `sweep.run`'s final state, with ``sync`` (`phase_label`) added.
    """
    angles = np.linspace(-extent, extent, size)
    ds = sweep.run(clocks(), sweep.Grid(theta1_0=angles, theta2_0=angles), t_end=t_end,
                   dt=dt, observe=("final",))
    frequency = math.sqrt(VALUES["g"] / VALUES["l"])
    ds["sync"] = (ds.theta1_final.dims,
                  phase_label(ds.theta1_final.values, ds.omega1_final.values,
                              ds.theta2_final.values, ds.omega2_final.values, frequency),
                  {"long_name": "synchronized state", "units": "1",
                   "flag_values": [ANTI_PHASE, IN_PHASE],
                   "flag_meanings": "anti_phase in_phase"})
    return ds


def main(argv=None) -> int:
    """Write huygens_clocks.png and huygens_clocks.nc into the output folder."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=151, help="grid points per axis")
    parser.add_argument("--t-end", type=float, default=300.0,
                        help="integration time [s] (about 150 swings)")
    parser.add_argument("--out", type=Path, default=Path("examples/output/huygens_clocks"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    ds = compute(args.size, args.t_end)
    elapsed = time.perf_counter() - start
    from matplotlib.colors import ListedColormap

    fig = sweep.plot.map(ds.sync, degrees=False,
                         cmap=ListedColormap(["#d95f02", "#1b9e77"]),
                         title="Huygens' clocks: the synchronized state each start reaches")
    sweep.plot.save_figure(fig, args.out / "huygens_clocks.png")
    sweep.save(ds, args.out / "huygens_clocks.nc")
    share = float((ds.sync == IN_PHASE).mean())
    print(f"{ds.sync.size} starts in {elapsed:.1f} s: {share:.1%} end in phase, "
          f"{1 - share:.1%} in anti-phase")
    print(f"wrote {args.out / 'huygens_clocks.png'}")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
