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
  argument reduction), ``vfma(a, b, c)`` (``a * b + c``, one rounding), ``math.sqrt``,
  ``abs`` (a quadratic drag's); no other call;
- ``accel_lines``: statements; temporaries are named ``x<k>`` (SymPy's ``cse``); the
  last statements assign ``acc_<symbol>`` for every coordinate, in coordinate order;
- ``energy_lines``: statements ending with ``energy_value = ...`` (kinetic plus
  potential energy, the Lagrangian's units);
- ``jacobian_lines`` (empty when not derived): statements ending with
  ``jac_<a>_<b> = ...``, the derivative of ``acc_<a>`` with respect to state
  variable ``<b>`` (a position or velocity symbol), for every pair.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .._validate import check_real
from .effect import Parameter

__all__ = ["Coordinate", "DerivedSystem", "SYSTEMS", "SYSTEM_DAMPING", "System",
           "SystemDeclaration", "angle_parameter", "initial_parameters", "register_system",
           "system_axis", "system_columns", "system_parameters"]


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
    """The parameter of any registered system whose axis is ``name``, or None; an axis
    of an effect on one coordinate (``damping_theta1``:
    `sweep.physics.coordinate_effects`) too."""
    for cls in SYSTEMS.values():
        found = cls.axis_parameter(name)
        if found is not None:
            return found
    from .coordinate_effects import coordinate_axis

    return coordinate_axis(name)


def angle_parameter(name: str) -> Parameter | None:
    """The parameter of grid axis ``name`` where it is an angle or an angular velocity
    (declared ``angle``): the single pendulum's (`sweep.physics.parameters`, its effects'
    included) or a registered system's (`system_axis`); None otherwise. The axes a run
    file accepts in degrees and ``sweep plot`` draws in degrees."""
    from .scene import parameters

    found = {p.axis: p for p in parameters()}.get(name) or system_axis(name)
    return found if found is not None and found.angle else None


class System:
    """Base of the systems with several coordinates (`DoublePendulum`, ...), what
    `sweep.run` takes where it takes a `sweep.Scene`.

    A subclass is a frozen dataclass with a field per parameter of its declaration
    (same names as the `Parameter` fields) and ``effects``; it defines `declaration`
    (a `SystemDeclaration`, which may depend on the instance, e.g. on a number of
    pendula) and `axis_parameter`.
    """

    #: Effects a system accepts: `sweep.Damping` without ``on`` (mass-proportional) and,
    #: with ``on="<coordinate>"``, every effect of
    #: `sweep.physics.coordinate_effects.acting_effects` (a generalized force on it).
    ACCEPTED_EFFECTS = ("Damping", "Damping(on=...)", "Forcing(on=...)", "Torque(on=...)",
                        "QuadraticDrag(on=...)")

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
        its period ``2 pi / nu``. Here: the frequency of a `sweep.Forcing` on one
        coordinate (``forcing_frequency_<coordinate>``) when it is the only one; a
        subclass with a drive of its own (the double pendulum's pivot) says which."""
        from .coordinate_effects import parameters_on

        forcings = [e for e in self.effects if e.coordinate is not None
                    and type(e).declaration.name == "forcing"]
        if len(forcings) != 1:
            return None
        coordinate = {c.name: c for c in self.declaration.coordinates}[forcings[0].coordinate]
        found = parameters_on(type(forcings[0]), coordinate, self.energy_units)
        return next(p for p in found if p.axis.startswith("forcing_frequency_"))

    @property
    def title(self) -> str:
        """What a dataset's title calls it (its class name)."""
        return type(self).__name__

    @property
    def declaration(self) -> SystemDeclaration:  # pragma: no cover - abstract
        raise NotImplementedError

    @property
    def declaration_with_effects(self) -> SystemDeclaration:
        """`declaration` with the generalized forces of its effects on one coordinate
        (`sweep.physics.coordinate_effects.with_effects`): what is derived and run;
        `declaration` itself when no effect names a coordinate."""
        from .coordinate_effects import with_effects

        return with_effects(self.declaration, self.effects, self.energy_units)

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

    def _coordinate_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.declaration.coordinates)

    def _check_effects(self) -> tuple:
        """``effects`` as a tuple, each accepted, at most one of each kind per
        coordinate (and one mass-proportional `sweep.Damping`), in canonical order (the
        mass-proportional damping, then by coordinate, then in `sweep.physics.EFFECTS`
        order), so that equal systems compare and hash equal."""
        from .coordinate_effects import acting_effects
        from .effect import EFFECTS, Effect
        from .effects import Damping

        who = type(self).__name__
        names = self._coordinate_names()
        listed = ", ".join(map(repr, names))
        acting = acting_effects()
        accepted = (f"Damping(coefficient) (mass-proportional: every acceleration gains "
                    f"- c v_i) and, on one coordinate (on= one of {listed}), "
                    + ", ".join(f"{cls.__name__}(..., on=...)" for cls in acting))
        effects = self.effects
        if not isinstance(effects, (tuple, list)):
            effects = (effects,)
        seen = set()
        for effect in effects:
            if not isinstance(effect, Effect) or (type(effect) not in acting):
                raise TypeError(f"{who} accepts the effects {accepted}; got {effect!r}")
            on = effect.coordinate
            if on is None and type(effect) is not Damping:
                raise TypeError(
                    f"{who} accepts the effects {accepted}; got {effect!r} without on=: on "
                    f"a system a {type(effect).__name__} acts on one coordinate; accepted: "
                    f"{type(effect).__name__}(..., on=...) with on one of {listed}")
            if on is not None and on not in names:
                raise ValueError(f"{who}: {effect!r} acts on {on!r}, which is not a "
                                 f"coordinate of {who}; accepted: on= one of {listed}")
            if (type(effect), on) in seen:
                where = f" on {on!r}" if on is not None else " (mass-proportional)"
                raise ValueError(f"{who} got {type(effect).__name__}{where} twice; "
                                 "accepted: at most one of each effect per coordinate")
            seen.add((type(effect), on))
        order = list(EFFECTS.values())
        return tuple(sorted(effects, key=lambda e: (
            -1 if e.coordinate is None else names.index(e.coordinate),
            order.index(type(e)))))

    def _with_effects(self, effects: tuple) -> System:
        """This system with ``effects`` instead of its own."""
        return dataclasses.replace(self, effects=tuple(effects))

    @property
    def feeds_energy(self) -> bool:
        """True where an effect on a coordinate can feed energy in (a torque, a forcing:
        their declarations' ``force_bound``), so that the energy can grow."""
        return any(e.coordinate is not None and e.declaration.force_bound
                   for e in self.effects)

    @property
    def damping(self) -> float | None:
        """The rate c [1/s] of its mass-proportional `sweep.Damping` (without ``on``),
        or None without one."""
        found = [e for e in self.effects
                 if type(e).__name__ == "Damping" and e.coordinate is None]
        return found[0].coefficient if found else None

    def parameters(self) -> dict[str, float]:
        """Values of every table column except the initial state (the damping rate
        0 where there is no damping: read only where a grid axis switches it on), the
        effects on coordinates' parameters included (``damping_theta1``)."""
        values = {p.axis: float(getattr(self, p.axis)) for p in self.declaration.parameters}
        values["damping"] = self.damping or 0.0
        for effect in self.effects:
            if effect.coordinate is not None:
                values.update({f"{axis}_{effect.coordinate}": float(value)
                               for axis, value in effect.values().items()})
        return values

    def columns(self, damping: bool) -> tuple[str, ...]:
        """The parameter table's columns (`system_columns` of
        `declaration_with_effects`)."""
        return system_columns(self.declaration_with_effects, damping)

    def accepted_axes(self) -> tuple[str, ...]:
        """Every grid axis a run of this system accepts (some switch a term on:
        `switched_on`)."""
        return self.columns(True) + self._coordinate_axes()

    def _coordinate_axes(self) -> tuple[str, ...]:
        """The axes of effects on coordinates that a grid may name beyond `columns`:
        those that switch their effect on (``damping_theta1`` switches on a
        ``Damping(0, on="theta1")``; `switched_on`)."""
        from .coordinate_effects import acting_effects

        present = set(self.columns(True))
        return tuple(f"{p.axis}_{name}" for name in self._coordinate_names()
                     for cls in acting_effects() if cls.declaration.switched_on_by_grid
                     for p in cls.declaration.parameters
                     if f"{p.axis}_{name}" not in present)

    def axis_hint(self, name: str) -> str | None:
        """Why ``name``, an axis of an effect on a coordinate that this system does not
        accept, is refused (for the grid's message), or None for another axis."""
        from .coordinate_effects import split_axis

        found = split_axis(name)
        if found is None:
            return None
        cls, _, on = found
        who, names = type(self).__name__, self._coordinate_names()
        if on not in names:
            return (f"names {on!r}, which is not a coordinate of {who}; accepted: "
                    f"{name[:-len(on)]}<coordinate> with a coordinate among "
                    f"{', '.join(names)}")
        arguments = ", ".join(p.field for p in cls.declaration.parameters
                              if p.default is None)
        return (f"needs a sweep.{cls.__name__}({arguments}, on={on!r}) in the effects of "
                f"{who} to supply its other parameters (the axis alone does not switch it "
                f"on); accepted: add sweep.{cls.__name__}({arguments}, on={on!r}) to its "
                "effects")

    def switched_on(self, axes) -> System:
        """This system with the terms that the grid ``axes`` (names) switch on (an
        effect on a coordinate whose axis switches it on, ``damping_theta1``: added
        with its parameters 0); itself when they switch nothing on."""
        from .coordinate_effects import split_axis

        present = set(self.columns(True))
        added = []
        for name in axes:
            found = split_axis(name)
            if found is None or name in present:
                continue
            cls, _, on = found
            if cls.declaration.switched_on_by_grid and on in self._coordinate_names() \
                    and all(type(e) is not cls or e.coordinate != on for e in added):
                added.append(cls(**{p.field: 0.0 if p.default is None else p.default
                                    for p in cls.declaration.parameters}, on=on))
        return self._with_effects(self.effects + tuple(added)) if added else self

    def derived(self, jacobian: bool = False):  # pragma: no cover - abstract
        """Its equations of motion and energy (with ``jacobian``: and the Jacobian of
        the accelerations) as kernel source, its effects on coordinates included:
        `sweep.physics.derive.derive_system` (each system's class calls it; derive
        imports this module, so this one does not import derive).

        Raises
        ------
        ImportError
            Where the equations must be derived and SymPy is not installed.
        """
        raise NotImplementedError

    def to_dict(self) -> dict:
        """A JSON-able description (dataset attribute ``system``)."""
        return {"system": type(self).__name__,
                **{p.axis: float(getattr(self, p.axis))
                   for p in self.declaration.parameters},
                "effects": [{"effect": type(e).__name__, **e.values(),
                             **({"on": e.coordinate} if e.coordinate is not None else {})}
                            for e in self.effects]}
