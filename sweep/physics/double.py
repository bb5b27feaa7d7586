"""The double pendulum: two point masses on massless rods, in a plane, under gravity.

Angles ``theta1`` and ``theta2`` are measured from the downward vertical, ``theta2``
*absolute* (not relative to the first rod). Its Lagrangian (`sweep.physics.systems.
double_pendulum`) is derived into the equations of motion once
(`sweep.physics.derive`) and compiled into the same SIMD kernels as the single
pendulum's (`sweep.kernels.system`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

from .._validate import check_real
from .effect import Parameter
from .system import (
    DerivedSystem,
    System,
    SystemDeclaration,
    register_system,
    system_parameters,
)

__all__ = ["DoublePendulum"]


@functools.cache
def _declaration() -> SystemDeclaration:
    from .systems import double_pendulum

    return double_pendulum()


@register_system
@dataclass(frozen=True)
class DoublePendulum(System):
    """Two point masses on massless rods: the textbook chaotic pendulum.

    Parameters
    ----------
    mass1, mass2 : float, default 1.0
        The masses [kg], finite and > 0 (only their ratio enters the motion).
    length1, length2 : float, default 1.0
        The rods' lengths [m], finite and > 0.
    gravity : float, default 9.81
        ``g`` [m/s^2], finite and > 0.
    effects : tuple, default ()
        `sweep.Damping(c)`: mass-proportional damping, every angular acceleration gains
        ``- c theta_i'`` (the generalized force ``- c M(q) q'``; c in 1/s).

    Notes
    -----
    Grid axes: ``theta1_0``, ``theta2_0`` [rad], ``omega1_0``, ``omega2_0`` [rad/s], and
    ``mass1``, ``mass2``, ``length1``, ``length2``, ``gravity``, ``damping``. Outputs:
    ``theta1_final`` ... with ``observe=("final",)``, ``theta1`` ... over ``time`` with
    ``save_every``, ``flip_time`` with ``observe=("flip",)``
    (`sweep.system_observables`).

    Examples
    --------
    >>> import numpy as np, sweep
    >>> system = sweep.DoublePendulum(mass1=1.0, mass2=1.0, length1=1.0, length2=1.0)
    >>> grid = sweep.Grid(theta1_0=np.linspace(-3, 3, 5), theta2_0=np.linspace(-3, 3, 5))
    """

    mass1: float = 1.0
    mass2: float = 1.0
    length1: float = 1.0
    length2: float = 1.0
    gravity: float = 9.81
    effects: tuple = field(default=())

    def __post_init__(self) -> None:
        for p in self.declaration.parameters:
            object.__setattr__(self, p.axis, check_real(
                p.axis, getattr(self, p.axis), minimum=p.minimum, strict=p.strict,
                accepted=p.accepted()))
        object.__setattr__(self, "effects", self._check_effects())

    #: With V = 0 hanging at rest: the first arm upright needs V >= 2 (m1 + m2) g l1
    #: (second arm down), the second arm upright V >= 2 m2 g l2 (first arm down). Energy
    #: never grows (damping only removes it), so below the smaller no angle can ever be
    #: upright.
    flip_energy = "2.0 * min((m1 + m2) * grav * l1, m2 * grav * l2)"

    @property
    def declaration(self) -> SystemDeclaration:
        """The double pendulum's declaration (`sweep.physics.systems.double_pendulum`)."""
        return _declaration()

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:
        return {p.axis: p for p in system_parameters(_declaration(), True)}.get(name)

    def derived(self, jacobian: bool = False) -> DerivedSystem:
        """Its equations of motion and energy (with ``jacobian``: and the Jacobian of
        the accelerations) as kernel source (`sweep.physics.derive`; SymPy only on the
        first derivation on a machine, then read from the cache)."""
        from .derive import derive

        return derive(self.declaration, jacobian=jacobian)
