"""The effects a scene can call for, each declared once (see `sweep.physics.effect`).

The equation of motion is ``theta'' = - (g/L) f(theta)`` plus the terms of the effects
present, in the order they are registered here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from .effect import Drive, Effect, EffectDeclaration, Parameter, register

__all__ = ["Damping", "Forcing"]


@register
@dataclass(frozen=True)
class Damping(Effect):
    """Linear viscous damping, the term ``-c theta'``.

    Parameters
    ----------
    coefficient : float
        ``c = C/m`` in 1/s (the seed's ``ksi``); finite and >= 0.
    """

    coefficient: float

    declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
        name="damping",
        parameters=(Parameter("damping", "coefficient", "c", "s-1", "1/s",
                              "viscous damping coefficient c = C/m", minimum=0.0),),
        term="- c * om",
        equation="- c theta'",
        conservative=False,
        linear_damping="c",
    )


@register
@dataclass(frozen=True)
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
    """

    amplitude: float
    frequency: float
    phase: float = 0.0

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
    )
