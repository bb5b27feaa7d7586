"""The effects a scene can call for, each declared once (see `sweep.physics.effect`).

The equation of motion is ``theta'' = - (g/L) f(theta)`` plus the terms of the effects
present, in the order they are registered here::

    theta'' = - (g/L) f(theta) - c theta' + A sin(W t + phase) + tau - k theta'|theta'|
              + (a nu^2 / L) cos(nu t + psi) f(theta)

On a system of several coordinates (`sweep.DoublePendulum`, ...), `Damping`, `Forcing`,
`Torque` and `QuadraticDrag` given ``on="<coordinate>"`` are a generalized force ``Q`` on that
coordinate (``M(q) q'' = F + Q``; their ``generalized_force``), in the units of a
generalized force (N m on an angle) rather than per unit ``m L^2``; see
`sweep.physics.coordinate_effects`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .effect import Drive, Effect, EffectDeclaration, Parameter, on_field, register

__all__ = ["Damping", "Forcing", "PivotDrive", "QuadraticDrag", "Torque"]


@register
@dataclass(frozen=True, repr=False)
class Damping(Effect):
    """Linear viscous damping, the term ``-c theta'``.

    Parameters
    ----------
    coefficient : float
        ``c = C/m`` in 1/s (the seed's ``ksi``); finite and >= 0. With ``on``: the
        damping coefficient of that coordinate, in N m s on an angle.
    on : str, optional, keyword only
        Only on a system: the coordinate it acts on (``"theta1"``), as the generalized
        force ``Q = -c v`` on it (damping at that joint; grid axis
        ``damping_<coordinate>``). Without it, on a system: mass-proportional damping
        (every acceleration gains ``- c v_i``, c in 1/s).
    """

    coefficient: float
    on: str | None = on_field()

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="damping",
        parameters=(Parameter("damping", "coefficient", "c", "s-1", "1/s",
                              "viscous damping coefficient c = C/m", minimum=0.0),),
        term="- c * om",
        equation="- c theta'",
        conservative=False,
        linear_damping="c",
        switched_on_by_grid=True,
        jacobian_omega="- c",
        generalized_force="-c*v",
    )


@register
@dataclass(frozen=True, repr=False)
class Forcing(Effect):
    """Harmonic forcing, the term ``A sin(W t + phase)``.

    Parameters
    ----------
    amplitude : float
        ``A`` in rad/s^2 (force per unit ``m L``); finite.
    frequency : float
        ``W`` in rad/s; finite and >= 0.
    phase : float, default 0
        In rad; ``phase = pi/2`` gives ``A cos(W t)``, the convention of most literature.
    on : str, optional, keyword only
        Only on a system (and there required): the coordinate it drives, as the
        generalized force ``Q = A sin(W t + phase)`` on it, ``A`` in N m on an angle
        (grid axes ``forcing_amplitude_<coordinate>``, ...).
    """

    amplitude: float
    frequency: float
    phase: float = 0.0
    on: str | None = on_field()

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="forcing",
        parameters=(
            Parameter("forcing_amplitude", "amplitude", "A", "rad s-2", "rad/s^2",
                      "forcing amplitude A (angular acceleration)"),
            Parameter("forcing_frequency", "frequency", "W", "rad s-1", "rad/s",
                      "forcing angular frequency W", minimum=0.0),
            Parameter("forcing_phase", "phase", "phi", "rad", "rad",
                      "forcing phase (A sin(W t + phase))", default=0.0, angle=True),
        ),
        term="+ f",
        equation="+ A sin(W t + phase)",
        conservative=False,
        drive=Drive(value="f", amplitude="A", frequency="W", phase="phi"),
        force_bound="abs(A)",
        generalized_force="A*sin(W*t + phi)",
    )


@register
@dataclass(frozen=True, repr=False)
class Torque(Effect):
    """A constant applied torque per unit ``m L^2``, the term ``+ tau``.

    The tilted-washboard pendulum: the same equation as the RCSJ model of a Josephson
    junction (angle = phase, torque = bias current, mean angular velocity = DC voltage).
    With damping it has locked states (rest at ``sin(theta) = tau L/g``, only for
    ``|tau| <= g/L``) and running states (rotation), which coexist between the
    retrapping torque (``4 c sqrt(g/L) / pi`` for small damping) and ``g/L``.

    Parameters
    ----------
    value : float
        ``tau`` in rad/s^2; finite (either sign).
    on : str, optional, keyword only
        Only on a system (and there required): the coordinate it acts on, as the
        constant generalized force ``Q = tau`` on it, in N m on an angle (grid axis
        ``torque_<coordinate>``).
    """

    value: float
    on: str | None = on_field()

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="torque",
        parameters=(Parameter("torque", "value", "tau", "rad s-2", "rad/s^2",
                              "constant applied torque per unit m L^2"),),
        term="+ tau",
        equation="+ tau",
        conservative=True,  # the potential -tau theta: energy is conserved without damping
        force_bound="abs(tau)",  # conservative, but its potential has no floor
        generalized_force="tau",
    )


@register
@dataclass(frozen=True, repr=False)
class QuadraticDrag(Effect):
    """Air drag, the term ``- k theta' |theta'|``.

    Parameters
    ----------
    coefficient : float
        ``k`` in 1/rad; finite and >= 0.
    on : str, optional, keyword only
        Only on a system (and there required): the coordinate it acts on, as the
        generalized force ``Q = -k v |v|`` on it, ``k`` in N m s^2 on an angle (grid
        axis ``drag_<coordinate>``).
    """

    coefficient: float
    on: str | None = on_field()

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="drag",
        parameters=(Parameter("drag", "coefficient", "kd", "rad-1", "1/rad",
                              "quadratic drag coefficient k", minimum=0.0),),
        term="- kd * om * abs(om)",
        equation="- k theta' |theta'|",
        conservative=False,
        # d/d(theta') of -k theta'|theta'| is -2 k |theta'|: stiff for fast motion
        linear_damping="2.0 * kd * omega_max",
        jacobian_omega="- 2.0 * kd * abs(om)",
        # faster than the terminal speed, drag beats every force: theta'' opposes theta'
        speed_bound="math.sqrt(force_max / kd) if kd > 0 else math.inf",
        switched_on_by_grid=True,  # like damping: a drag axis alone switches it on
        generalized_force="-kd*v*abs(v)",
    )


@register
@dataclass(frozen=True)
class PivotDrive(Effect):
    """The pivot moves vertically as ``y = a cos(nu t + psi)`` (upward positive).

    In the pendulum's frame gravity becomes ``g + y''``, so ``theta'' = -(g/L - (a nu^2 /
    L) cos(nu t + psi)) f(theta)``: with the nonlinear model Kapitza's pendulum (the
    inverted position is stable for a fast enough drive, ``a nu > sqrt(2 g L)`` at
    leading order), with the linear model the damped Mathieu equation (parametric
    resonance tongues at ``nu = 2 sqrt(g/L) / n``).

    Parameters
    ----------
    amplitude : float
        ``a`` in m; finite and >= 0.
    frequency : float
        ``nu`` in rad/s; finite and >= 0.
    phase : float, default 0
        ``psi`` in rad.
    """

    amplitude: float
    frequency: float
    phase: float = 0.0

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="pivot",
        parameters=(
            Parameter("pivot_amplitude", "amplitude", "a", "m", "m",
                      "pivot drive amplitude a (pivot height a cos(nu t + psi))", minimum=0.0),
            Parameter("pivot_frequency", "frequency", "nu", "rad s-1", "rad/s",
                      "pivot drive angular frequency nu", minimum=0.0),
            Parameter("pivot_phase", "phase", "psi", "rad", "rad",
                      "pivot drive phase psi", default=0.0, angle=True),
        ),
        term="+ p * FTH",
        equation="+ (a nu^2 / L) cos(nu t + psi) f(theta)",
        conservative=False,  # energy is pumped in and out by the moving pivot
        drive=Drive(value="p", amplitude="a * nu * nu / L", frequency="nu", phase="psi",
                    function="cos"),
        # the stiffness g/L - (a nu^2/L) cos(...) reaches g/L + a nu^2/L
        linear_stiffness="a * nu * nu / L",
        jacobian_theta="+ p * DFTH",
        force_bound="a * nu * nu / L",  # times |sin theta| <= 1
        # the pivot's acceleration y'' = -a nu^2 cos(nu t + psi) adds to gravity
        tension="- a * nu * nu * vcos(nu * TIME + psi) * vcos(th)",
    )
