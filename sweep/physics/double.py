"""The double pendulum: two point masses on massless rods, in a plane, under gravity.

Angles ``theta1`` and ``theta2`` are measured from the downward vertical, ``theta2``
*absolute* (not relative to the first rod). Its Lagrangian (`sweep.physics.systems.
double_pendulum`) is derived into the equations of motion once
(`sweep.physics.derive`) and compiled into the same SIMD kernels as the single
pendulum's (`sweep.kernels.system`).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

from .effect import Parameter
from .system import (
    DerivedSystem,
    System,
    SystemDeclaration,
    register_system,
    system_columns,
    system_parameters,
)

__all__ = ["DoublePendulum"]


@functools.cache
def _declaration(joint_damping: bool = False, pivot: bool = False) -> SystemDeclaration:
    from .systems import double_pendulum

    return double_pendulum(damping=joint_damping, pivot=pivot)


#: The optional terms: constructor arguments (None: absent) by term.
_OPTIONAL = {"joint_damping": ("damping1", "damping2"),
             "pivot": ("pivot_amplitude", "pivot_frequency")}


@register_system
@dataclass(frozen=True)
class DoublePendulum(System):
    """Two point masses on massless rods: the textbook chaotic pendulum.

    Parameters
    ----------
    mass1, mass2 : float, default 1.0
        The masses [kg], finite and > 0. Only their ratio ``mass2 / mass1`` enters the
        motion as long as every generalized force scales with the masses: no joint
        damping ``damping1``/``damping2`` and no effect on one angle (``on=``), whose
        torques [N m] are absolute; gravity, the pivot drive and the mass-proportional
        `sweep.Damping(c)` scale with them. The energy [J] scales with the masses
        always.
    length1, length2 : float, default 1.0
        The rods' lengths [m], finite and > 0.
    gravity : float, default 9.81
        ``g`` [m/s^2], finite and > 0.
    damping1, damping2 : float, optional
        Viscous damping at the joints [N m s], >= 0: a torque ``- c1 omega1`` at the
        pivot and ``- c2 (omega2 - omega1)`` at the middle joint. Either given (or a grid
        axis ``damping1``/``damping2``) adds both terms (the other 0); neither: none.
    pivot_amplitude, pivot_frequency : float, optional
        The pivot driven vertically, ``a cos(nu t)`` [m, rad/s], >= 0 (the double
        Kapitza pendulum). Either given (or a grid axis) adds the drive (the other 0).
    effects : tuple, default ()
        `sweep.Damping(c)`: mass-proportional damping, every angular acceleration gains
        ``- c theta_i'`` (the generalized force ``- c M(q) q'``; c in 1/s).
        ``sweep.Damping(c, on="theta1")``, ``sweep.Torque(tau, on="theta2")``,
        ``sweep.Forcing(A, W, on="theta1")``, ``sweep.QuadraticDrag(k, on="theta2")``: a
        generalized force on that angle alone, ``-c omega1`` [N m, c in N m s], ``tau``
        [N m], ``A sin(W t)`` [N m], ``-k omega2 |omega2|`` [N m, k in N m s^2]
        (`sweep.physics.coordinate_effects`; grid axes ``damping_theta1``, ...).
        ``Damping(c1, on="theta1")`` is the pivot's damping ``damping1`` without the
        middle joint's.

    Notes
    -----
    Grid axes: ``theta1_0``, ``theta2_0`` [rad], ``omega1_0``, ``omega2_0`` [rad/s]
    (the initial state); ``mass1``, ``mass2``, ``length1``, ``length2``, ``gravity``;
    ``damping1``, ``damping2`` (an axis switches the joint damping on),
    ``pivot_amplitude``, ``pivot_frequency`` (an axis switches the pivot drive on);
    ``damping`` (the rate of `sweep.Damping(c)`); ``damping_theta1``, ``drag_theta1``,
    ``damping_theta2``, ``drag_theta2`` (an axis switches that effect on that angle on,
    its other parameters 0). An effect on one angle given in ``effects`` adds its own
    axes, ``<effect axis>_<angle>`` (``sweep.Torque(tau, on="theta2")``: the axis
    ``torque_theta2``). `accepted_axes` lists them all.

    Outputs (`sweep.system_observables`), by ``observe``:

    - ``"final"``: ``theta1_final``, ``theta2_final`` [rad, unwrapped],
      ``omega1_final``, ``omega2_final`` [rad/s] at ``t_end``;
    - ``"winding"``: ``winding_theta1``, ``winding_theta2``: the wells each angle
      crossed from ``t0`` to ``t_end``;
    - ``"energy"``: ``energy_initial``, ``energy_final`` [J] (zero hanging at rest);
    - ``"flip"``: ``flip_time`` [s], the first time either angle passes upright (NaN if
      none did before ``t_end``); with ``stop_early`` a trajectory stops there;
    - ``"lyapunov"``: ``lyapunov_max`` [1/s], the largest Lyapunov exponent;
    - ``"strobe"``: ``theta1_strobe``, ... ``omega2_strobe`` over a dimension
      ``strobe``: samples once per drive period (needs a drive: the pivot's or a
      forcing on an angle);
    - ``"attractor"``: ``attractor``, the index in the catalogue passed as
      ``attractors=`` that the trajectory settled on, -1 if none (needs a drive).

    With ``save_every``: ``theta1``, ``theta2``, ``omega1``, ``omega2`` over ``time``.

    Examples
    --------
    >>> import numpy as np, sweep
    >>> system = sweep.DoublePendulum(mass1=1.0, mass2=1.0, length1=1.0, length2=1.0)
    >>> grid = sweep.Grid(theta1_0=np.linspace(-3, 3, 5), theta2_0=np.linspace(-3, 3, 5))
    >>> ds = sweep.run(system, grid, t_end=10.0, dt=0.01, observe=("final", "flip"))
    >>> ds["flip_time"].shape
    (5, 5)
    """

    mass1: float = 1.0
    mass2: float = 1.0
    length1: float = 1.0
    length2: float = 1.0
    gravity: float = 9.81
    damping1: float | None = None
    damping2: float | None = None
    pivot_amplitude: float | None = None
    pivot_frequency: float | None = None
    effects: tuple = field(default=())

    def __post_init__(self) -> None:
        for names in _OPTIONAL.values():  # a term given by one of its parameters: on
            if any(getattr(self, name) is not None for name in names):
                for name in names:
                    if getattr(self, name) is None:
                        object.__setattr__(self, name, 0.0)
        self._check_parameters()

    @property
    def flip_energy(self) -> str | None:
        """With V = 0 hanging at rest: the first arm upright needs V >= 2 (m1 + m2) g l1
        (second arm down), the second arm upright V >= 2 m2 g l2 (first arm down).
        Energy never grows (damping only removes it), so below the smaller no angle can
        ever be upright; a driven pivot, a torque or a forcing on a coordinate feed
        energy in: then None."""
        if self.pivot_amplitude is not None or self.feeds_energy:
            return None
        return "2.0 * min((m1 + m2) * grav * l1, m2 * grav * l2)"

    @property
    def drive_frequency_parameter(self) -> Parameter | None:
        """``pivot_frequency`` when the pivot is driven (``a cos(nu t)``), else the
        frequency of a forcing on one coordinate (`System.drive_frequency_parameter`)."""
        if self.pivot_amplitude is None:
            return super().drive_frequency_parameter
        return {p.axis: p for p in self.declaration.parameters}["pivot_frequency"]

    def derived(self, jacobian: bool = False) -> DerivedSystem:
        """Its equations as kernel source, its effects on coordinates included
        (`sweep.physics.derive.derive_system`)."""
        from .derive import derive_system

        return derive_system(self, jacobian)

    @property
    def declaration(self) -> SystemDeclaration:
        """The double pendulum's declaration (`sweep.physics.systems.double_pendulum`),
        with the joint damping and the pivot drive if given."""
        return _declaration(*(any(getattr(self, name) is not None for name in names)
                              for names in _OPTIONAL.values()))

    def accepted_axes(self) -> tuple[str, ...]:
        """Every axis of any double pendulum (a joint damping or pivot axis switches
        its term on), and those of its effects on a coordinate."""
        axes = system_columns(_declaration(True, True), True)
        return axes + tuple(a for a in super().accepted_axes() if a not in axes)

    def switched_on(self, axes) -> DoublePendulum:
        """With the terms whose parameters are among ``axes`` switched on (and the
        effects on a coordinate: `sweep.physics.System.switched_on`)."""
        given = {name: 0.0 for names in _OPTIONAL.values() for name in names
                 if name in axes and getattr(self, name) is None}
        return super(DoublePendulum, dataclasses.replace(self, **given) if given
                     else self).switched_on(axes)

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:
        return {p.axis: p for p in system_parameters(_declaration(True, True),
                                                     True)}.get(name)
