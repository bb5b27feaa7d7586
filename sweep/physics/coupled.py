"""Coupled pendula: ``n`` identical pendula side by side, neighbours joined by springs
(at the bobs) or torsion springs (between the rods), in a chain or a ring. Their
Lagrangian (`sweep.physics.systems.coupled_pendula`) is derived once
(`sweep.physics.derive`) and compiled into the same kernels as the double pendulum's."""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field

from .effect import Parameter
from .system import (
    DerivedSystem,
    System,
    SystemDeclaration,
    initial_parameters,
    register_system,
    system_parameters,
)

__all__ = ["CoupledPendula"]

_INITIAL = re.compile(r"^(theta|omega)([1-9]\d*)_0$")


@functools.cache
def _declaration(n: int, kind: str, topology: str) -> SystemDeclaration:
    from .systems import coupled_pendula

    return coupled_pendula(n, coupling=kind, topology=topology)


@register_system
@dataclass(frozen=True)
class CoupledPendula(System):
    """``n`` identical pendula whose neighbours are coupled by springs.

    Parameters
    ----------
    n : int, default 2
        Number of pendula (>= 2; >= 3 for a ring). Coordinates ``theta1`` ... ``theta<n>``.
    mass : float, default 1.0
        Each bob's mass m [kg], > 0.
    length : float, default 1.0
        Each rod's length l [m], > 0.
    gravity : float, default 9.81
        [m/s^2], > 0.
    coupling : float, default 1.0
        The springs' stiffness, >= 0: ``k`` [N/m] between the bobs for ``kind="spring"``,
        ``kappa`` [N m/rad] between the rods for ``kind="torsion"``.
    kind : {"spring", "torsion"}
    topology : {"chain", "ring"}
    effects : tuple
        `sweep.Damping(c)`: every pendulum's acceleration gains ``- c theta_i'`` (c in
        1/s; the same as a damping torque ``- c m l^2 theta_i'`` at each pivot).
        With ``on="theta<i>"``, `sweep.Damping`, `sweep.Torque`, `sweep.Forcing` and
        `sweep.QuadraticDrag` act on
        pendulum i alone, as a torque at its pivot [N m]
        (`sweep.physics.coordinate_effects`; grid axes ``damping_theta<i>``, ...).

    Notes
    -----
    Linearised at rest, two pendula have the normal modes ``omega^2 = g/l`` (in phase)
    and ``g/l + 2 k/m`` (spring) or ``g/l + 2 kappa/(m l^2)`` (torsion) in anti-phase:
    started in one pendulum alone, the energy beats between them at the difference of
    the two frequencies.
    """

    n: int = 2
    mass: float = 1.0
    length: float = 1.0
    gravity: float = 9.81
    coupling: float = 1.0
    kind: str = "spring"
    topology: str = "chain"
    effects: tuple = field(default=())

    def __post_init__(self) -> None:
        from .systems import COUPLINGS

        if self.kind not in COUPLINGS:  # named as this class takes it (`coupling` is k)
            raise ValueError(f"CoupledPendula: kind={self.kind!r} is not accepted; accepted: "
                             f"{', '.join(map(repr, COUPLINGS))}")
        _declaration(self.n, self.kind, self.topology)  # checks n and topology
        self._check_parameters()

    def derived(self, jacobian: bool = False) -> DerivedSystem:
        """Its equations as kernel source, its effects on coordinates included
        (`sweep.physics.derive.derive_system`)."""
        from .derive import derive_system

        return derive_system(self, jacobian)

    @property
    def declaration(self) -> SystemDeclaration:
        """Its declaration (`sweep.physics.systems.coupled_pendula`)."""
        return _declaration(self.n, self.kind, self.topology)

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:
        """Initial angles and velocities of any pendulum (``theta7_0``), the pendula's
        parameters and the damping rate."""
        match = _INITIAL.match(name)
        if match:
            k = int(match.group(2))
            found = {p.axis: p for p in initial_parameters(_declaration(max(k, 2), "spring",
                                                                        "chain"))}
            return found[name]
        return {p.axis: p for p in system_parameters(_declaration(2, "spring", "chain"),
                                                     True)}.get(name)
