"""A system: coordinates, parameters and dynamics, declared once as plain data.

The single pendulum (`sweep.Scene`) has one coordinate, ``theta``; a *system* has
any number: a double pendulum ``theta1, theta2``, a chain of coupled pendula, a swing
network. A `SystemDeclaration` says, once, everything the kernel generator, the grid,
the dataset and the maps need:

- its coordinates (`Coordinate`): names, kernel symbols, units, angular or not;
- its parameters (`sweep.physics.Parameter`, as an effect's): grid axis, kernel symbol,
  units, bounds, default;
- its dynamics, as a **Lagrangian** (a SymPy expression written as a string in the
  coordinates' and velocities' kernel symbols, the parameters' symbols and ``t``) plus
  generalized forces per coordinate (damping at a joint, a drive), or directly as
  **accelerations** (one expression per coordinate).

`derive` turns a declaration into a `DerivedSystem`: plain kernel-source strings for
the accelerations (mass matrix solved in closed form), the energy and, where asked,
the Jacobian of the accelerations. SymPy is imported only there; everything else is
strings, numbers and tuples, so declarations hash, compare and pickle (a kernel spec
carries one; a Dask worker needs no SymPy).

Kernel-source conventions of `DerivedSystem` (what the generator relies on):

- names: position ``<coordinate.symbol>`` (``th1``), velocity
  ``<coordinate.velocity_symbol>`` (``om1``), each parameter's ``symbol``, time ``t``;
- functions: ``vsin``, ``vcos``, ``vsincos`` (returns ``(sin x, cos x)`` from one
  argument reduction), ``vfma(a, b, c)`` (``a * b + c``, one rounding), ``math.sqrt``;
  no other call;
- ``accel_lines``: statements; temporaries are named ``x<k>`` (SymPy's ``cse``); the
  last statements assign ``acc_<symbol>`` for every coordinate, in coordinate order;
- ``energy_lines``: statements ending with ``energy_value = ...`` (kinetic plus
  potential energy, the Lagrangian's units);
- ``jacobian_lines`` (empty when not derived): statements ending with
  ``jac_<a>_<b> = ...``, the derivative of ``acc_<a>`` with respect to state
  variable ``<b>`` (a position or velocity symbol), for every pair.
"""

from __future__ import annotations

from dataclasses import dataclass

from .._validate import check_real
from .effect import Parameter

__all__ = ["Coordinate", "DerivedSystem", "SYSTEMS", "SYSTEM_DAMPING", "System",
           "SystemDeclaration", "initial_parameters", "register_system", "system_axis",
           "system_columns", "system_parameters"]


@dataclass(frozen=True)
class Coordinate:
    """One generalized coordinate of a system.

    Attributes
    ----------
    name : str
        Its name in datasets (``"theta1"``): grid axes ``<name>_0`` and
        ``<velocity>_0``, outputs ``<name>_final``, saved variable ``<name>``.
    velocity : str
        Name of its velocity in datasets (``"omega1"``).
    symbol, velocity_symbol : str
        Kernel variables of the position and the velocity (``"th1"``, ``"om1"``).
    units, velocity_units : str
        UDUNITS strings (``"rad"``, ``"rad s-1"``).
    long_name : str
        What it is (``"angle of the first rod from the downward vertical"``).
    angular : bool
        An angle (winding, flips, sines of it are meaningful; TOML accepts degrees).
    """

    name: str
    velocity: str
    symbol: str
    velocity_symbol: str
    units: str = "rad"
    velocity_units: str = "rad s-1"
    long_name: str = ""
    angular: bool = True


@dataclass(frozen=True)
class DerivedSystem:
    """A system's dynamics as kernel source (see the module docstring's conventions).

    Attributes
    ----------
    accel_lines : tuple of str
    energy_lines : tuple of str
    jacobian_lines : tuple of str
    """

    accel_lines: tuple[str, ...]
    energy_lines: tuple[str, ...]
    jacobian_lines: tuple[str, ...] = ()


@dataclass(frozen=True)
class SystemDeclaration:
    """Everything sweep needs to know about a system, as plain data.

    Attributes
    ----------
    name : str
        Identifier (``"double_pendulum"``).
    coordinates : tuple of Coordinate
    parameters : tuple of sweep.physics.Parameter
        Per-trajectory parameters (grid axes), in table-column order after the initial
        state.
    lagrangian : str, optional
        The Lagrangian as a SymPy-parsable string in the kernel symbols.
    forces : tuple of str, optional
        Generalized force on each coordinate (same symbols; ``"0"`` for none), added to
        the Euler-Lagrange equations' right-hand side.
    accelerations : tuple of str, optional
        Instead of a Lagrangian: each coordinate's acceleration, as a SymPy-parsable
        string.
    potential : str, optional
        With ``accelerations``: the potential energy (kinetic energy is then taken as
        ``sum(v**2) / 2``); None: no energy.
    """

    name: str
    coordinates: tuple[Coordinate, ...]
    parameters: tuple[Parameter, ...]
    lagrangian: str | None = None
    forces: tuple[str, ...] = ()
    accelerations: tuple[str, ...] = ()
    potential: str | None = None


def initial_parameters(system: SystemDeclaration) -> tuple[Parameter, ...]:
    """The initial-state parameters of ``system``: every coordinate's initial value
    (axis ``<name>_0``), then every initial velocity (``<velocity>_0``)."""
    positions = tuple(Parameter(f"{c.name}_0", f"{c.name}_0", f"{c.symbol}_0", c.units,
                                c.units, f"initial {c.long_name or c.name}", default=0.0,
                                angle=c.angular) for c in system.coordinates)
    velocities = tuple(Parameter(f"{c.velocity}_0", f"{c.velocity}_0", f"{c.velocity_symbol}_0",
                                 c.velocity_units, c.velocity_units, f"initial {c.velocity}",
                                 default=0.0, angle=c.angular) for c in system.coordinates)
    return positions + velocities


#: The parameter of `sweep.Damping` on a system (mass-proportional damping: every
#: coordinate's acceleration gains ``- c v_i``).
SYSTEM_DAMPING = Parameter("damping", "coefficient", "damping_c", "s-1", "1/s",
                           "mass-proportional damping rate c (every acceleration gains "
                           "- c times its velocity)", minimum=0.0, default=0.0)


def system_parameters(system: SystemDeclaration, damping: bool) -> tuple[Parameter, ...]:
    """Every column of a system's parameter table, in order: the initial state, the
    system's parameters, then the damping rate where damping is present."""
    return initial_parameters(system) + tuple(system.parameters) + \
        ((SYSTEM_DAMPING,) if damping else ())


def system_columns(system: SystemDeclaration, damping: bool) -> tuple[str, ...]:
    """Names (grid axes, table columns) of `system_parameters`."""
    return tuple(p.axis for p in system_parameters(system, damping))


#: The user-facing system classes (`register_system`), for the grid's axis names.
SYSTEMS: dict[str, type] = {}


def register_system(cls: type) -> type:
    """Add a `System` subclass to `SYSTEMS` (a class decorator); returns the class."""
    SYSTEMS[cls.__name__] = cls
    return cls


def system_axis(name: str) -> Parameter | None:
    """The parameter of any registered system whose axis is ``name``, or None."""
    for cls in SYSTEMS.values():
        found = cls.axis_parameter(name)
        if found is not None:
            return found
    return None


class System:
    """Base of the systems with several coordinates (`DoublePendulum`, ...), what
    `sweep.run` takes where it takes a `sweep.Scene`.

    A subclass is a frozen dataclass with a field per parameter of its declaration
    (same names as the `Parameter` fields) and ``effects``; it defines `declaration`
    (a `SystemDeclaration`, which may depend on the instance, e.g. on a number of
    pendula) and `axis_parameter`.
    """

    #: Effects a system accepts (only `sweep.Damping` so far: mass-proportional).
    ACCEPTED_EFFECTS = ("Damping",)

    #: UDUNITS units of its energy (its Lagrangian's).
    energy_units = "J"

    #: The lowest energy at which any angle can be upright (an odd multiple of pi), as
    #: kernel source in the parameters' symbols, or None if unknown: with
    #: ``stop_early`` a start below it is known never to flip and is not integrated.
    flip_energy: str | None = None

    @property
    def drive_frequency_parameter(self) -> Parameter | None:
        """The parameter that is the angular frequency [rad/s] of the system's periodic
        drive, or None without one: the ``strobe`` observable samples the state once per
        its period ``2 pi / nu``. None here; a subclass with a drive says which."""
        return None

    @property
    def title(self) -> str:
        """What a dataset's title calls it (its class name)."""
        return type(self).__name__

    @property
    def declaration(self) -> SystemDeclaration:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:  # pragma: no cover
        """The parameter of any instance of this class whose grid axis is ``name``."""
        raise NotImplementedError

    def _check_parameters(self) -> None:
        """Each parameter of the declaration checked against its bounds (set back as a
        float), and the effects (`_check_effects`): the subclasses' ``__post_init__``."""
        for p in self.declaration.parameters:
            object.__setattr__(self, p.axis, check_real(
                p.axis, getattr(self, p.axis), minimum=p.minimum, strict=p.strict,
                accepted=p.accepted()))
        object.__setattr__(self, "effects", self._check_effects())

    def _check_effects(self) -> tuple:
        """``effects`` as a tuple, each accepted, at most one of each kind."""
        from .effects import Damping

        effects = self.effects
        if not isinstance(effects, (tuple, list)):
            effects = (effects,)
        seen = set()
        for effect in effects:
            if not isinstance(effect, Damping):
                raise TypeError(f"{type(self).__name__} accepts the effects "
                                f"{', '.join(self.ACCEPTED_EFFECTS)} (Damping(coefficient): "
                                f"mass-proportional, every acceleration gains - c v_i); got "
                                f"{effect!r}")
            if type(effect) in seen:
                raise ValueError(f"{type(self).__name__} got {type(effect).__name__} twice; "
                                 "accepted: at most one of each effect")
            seen.add(type(effect))
        return tuple(effects)

    @property
    def damping(self) -> float | None:
        """The damping rate c [1/s] of its `sweep.Damping`, or None without one."""
        found = [e for e in self.effects if type(e).__name__ == "Damping"]
        return found[0].coefficient if found else None

    def parameters(self) -> dict[str, float]:
        """Values of every table column except the initial state (the damping rate
        0 where there is no damping: read only where a grid axis switches it on)."""
        values = {p.axis: float(getattr(self, p.axis)) for p in self.declaration.parameters}
        values["damping"] = self.damping or 0.0
        return values

    def columns(self, damping: bool) -> tuple[str, ...]:
        """The parameter table's columns (`system_columns`)."""
        return system_columns(self.declaration, damping)

    def accepted_axes(self) -> tuple[str, ...]:
        """Every grid axis a run of this system accepts (some switch a term on:
        `switched_on`)."""
        return self.columns(True)

    def switched_on(self, axes) -> System:
        """This system with the terms that the grid ``axes`` (names) switch on; itself
        when they switch nothing on."""
        return self

    def to_dict(self) -> dict:
        """A JSON-able description (dataset attribute ``system``)."""
        return {"system": type(self).__name__,
                **{p.axis: float(getattr(self, p.axis))
                   for p in self.declaration.parameters},
                "effects": [{"effect": type(e).__name__, **e.values()} for e in self.effects]}
