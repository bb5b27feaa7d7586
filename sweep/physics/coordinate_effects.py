"""Effects on one coordinate of a system: generalized forces added to its declaration.

On a system of several coordinates, an effect given ``on="<coordinate>"``
(``sweep.Damping(0.1, on="theta1")``) is a generalized force ``Q`` on that coordinate,
its declaration's ``generalized_force`` (`sweep.physics.EffectDeclaration`) written for
the coordinate. `with_effects` adds these forces to the system's declaration, so that
`sweep.physics.derive.derive` writes them into the equations of motion::

    M(q) q'' = F(q, v, t) + Q

(a declaration given as accelerations has no mass matrix: there ``Q`` adds to the
coordinate's acceleration, as with ``M = 1``, the mass its energy assumes). Through
``M`` a force on one coordinate moves the others: the physics of a coupled system.

Names, per effect parameter and coordinate:

- grid axis (and parameter-table column, dataset attribute) ``<axis>_<coordinate>``:
  ``damping_theta1``, ``torque_theta2``, ``forcing_amplitude_theta1``;
- kernel symbol ``<symbol>_<coordinate symbol>``: ``c_th1``, ``tau_th2``;
- units: those of a generalized force on the coordinate, ``Q`` in N m on an angle (in
  the energy's units per coordinate unit otherwise), so that a damping coefficient is in
  N m s, a torque and a forcing amplitude in N m; frequencies and phases keep theirs.

An effect of this kind changes the equations, so a system with one is derived again
(SymPy, once per machine and combination: the derivation is cached on disk as every
derivation is); the built-in systems without such effects need no SymPy.
"""

from __future__ import annotations

import dataclasses
import functools
import re

from .effect import EFFECTS, Effect, Parameter

# Coordinates and declarations are sweep.physics.system's (`Coordinate`,
# `SystemDeclaration`), named in the docstrings only: system imports this module.

__all__ = ["acting_effects", "coordinate_axis", "force_source", "parameters_on",
           "split_axis", "with_effects"]

_IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")

#: For the parameters whose units become a generalized force's: the power k of the
#: velocity they multiply (``Q / v^k``): a torque and a forcing amplitude are Q, a
#: damping coefficient Q / v, a drag coefficient Q / v^2. Others keep their units.
_FORCE_POWER = {("damping", "coefficient"): 1, ("torque", "value"): 0,
                ("forcing", "amplitude"): 0, ("drag", "coefficient"): 2}

#: Generalized force units (UDUNITS, message text) with the energy in J, by the power
#: k of `_FORCE_POWER`, on an angle and on a length.
_SI = {("rad", 0): ("kg m2 s-2", "N m"), ("rad", 1): ("kg m2 s-1", "N m s"),
       ("rad", 2): ("kg m2", "N m s^2"), ("m", 0): ("kg m s-2", "N"),
       ("m", 1): ("kg s-1", "N s/m"), ("m", 2): ("kg m-1", "N s^2/m^2")}


def acting_effects() -> tuple[type[Effect], ...]:
    """The registered effects that can act on one coordinate of a system (those that
    declare a ``generalized_force``), in registration order."""
    return tuple(cls for cls in EFFECTS.values() if cls.declaration.generalized_force)


def _units(p: Parameter, effect: str, coordinate,
           energy_units: str) -> tuple[str, str]:
    k = _FORCE_POWER.get((effect, p.field))
    if k is None:
        return p.units, p.unit_text
    unit = "rad" if coordinate.units in ("rad", "1", "") else coordinate.units
    if energy_units == "J" and (unit, k) in _SI:
        return _SI[unit, k]
    seconds = ("", " s", " s2")[k]
    if unit == "rad":
        return f"{energy_units}{seconds}", f"{energy_units}{seconds.replace('s2', 's^2')}"
    return (f"{energy_units}{seconds} {unit}-{k + 1}",
            f"{energy_units}{seconds.replace('s2', 's^2')}/{unit}^{k + 1}")


def parameters_on(effect_type: type[Effect], coordinate,
                  energy_units: str = "J") -> tuple[Parameter, ...]:
    """The parameters of ``effect_type`` acting on ``coordinate``.

    Parameters
    ----------
    effect_type : type
        An effect class of `acting_effects`.
    coordinate : Coordinate
    energy_units : str, default "J"
        The system's energy units (its Lagrangian's).

    Returns
    -------
    tuple of Parameter
        Axis (and field) ``<axis>_<coordinate.name>``, symbol
        ``<symbol>_<coordinate.symbol>``, the units of a generalized force on the
        coordinate (module docstring), the effect's bounds and defaults.
    """
    declaration = effect_type.declaration
    found = []
    for p in declaration.parameters:
        units, text = _units(p, declaration.name, coordinate, energy_units)
        axis = f"{p.axis}_{coordinate.name}"
        found.append(dataclasses.replace(
            p, axis=axis, field=axis, symbol=f"{p.symbol}_{coordinate.symbol}", units=units,
            unit_text=text, long_name=f"{p.field} {p.symbol} of {effect_type.__name__} on "
            f"{coordinate.name}, the generalized force {declaration.generalized_force} on it "
            f"(q = {coordinate.name}, v = {coordinate.velocity})"))
    return tuple(found)


def force_source(effect_type: type[Effect], coordinate) -> str:
    """The generalized force of ``effect_type`` on ``coordinate`` as a declaration
    expression: its ``generalized_force`` with ``q``, ``v`` and its symbols renamed
    (``"-c*v"`` on theta1 -> ``"-c_th1*om1"``)."""
    declaration = effect_type.declaration
    names = {p.symbol: f"{p.symbol}_{coordinate.symbol}" for p in declaration.parameters}
    names.update(q=coordinate.symbol, v=coordinate.velocity_symbol)
    return _IDENTIFIER.sub(lambda m: names.get(m.group(0), m.group(0)),
                           declaration.generalized_force)


def with_effects(declaration, effects: tuple,
                 energy_units: str = "J"):
    """``declaration`` with the generalized forces of the ``effects`` that name a
    coordinate (``on``) added; ``declaration`` itself when none does.

    Parameters
    ----------
    declaration : SystemDeclaration
    effects : tuple of sweep.physics.Effect
        Checked already (`sweep.physics.System`): each ``on`` a coordinate's name, at
        most one of each kind per coordinate. Those without ``on`` are left out.
    energy_units : str, default "J"

    Returns
    -------
    SystemDeclaration
        The same name and coordinates; the effects' parameters (`parameters_on`) after
        the declaration's, in the order of ``effects``; each force added to the
        coordinate's force (a Lagrangian) or acceleration.
    """
    return _with_effects(declaration, tuple(e for e in effects if e.coordinate is not None),
                         energy_units)


@functools.lru_cache(maxsize=256)
def _with_effects(declaration, effects: tuple,
                  energy_units: str):
    if not effects:
        return declaration
    by_name = {c.name: c for c in declaration.coordinates}
    parameters = list(declaration.parameters)
    added: dict[str, list[str]] = {c.name: [] for c in declaration.coordinates}
    for effect in effects:
        coordinate = by_name[effect.coordinate]
        parameters += parameters_on(type(effect), coordinate, energy_units)
        added[coordinate.name].append(force_source(type(effect), coordinate))

    def plus(base: str, terms: list[str]) -> str:
        if not terms:
            return base
        extra = " + ".join(f"({term})" for term in terms)
        return extra if base.strip() == "0" else f"({base}) + {extra}"

    names = [c.name for c in declaration.coordinates]
    if declaration.lagrangian is not None:
        forces = declaration.forces or ("0",) * len(names)
        return dataclasses.replace(declaration, parameters=tuple(parameters), forces=tuple(
            plus(force, added[name]) for force, name in zip(forces, names)))
    return dataclasses.replace(declaration, parameters=tuple(parameters), accelerations=tuple(
        plus(acceleration, added[name])
        for acceleration, name in zip(declaration.accelerations, names)))


def split_axis(name: str) -> tuple[type[Effect], Parameter, str] | None:
    """``(effect class, its parameter, coordinate name)`` of an axis
    ``<effect axis>_<coordinate>`` (``"forcing_amplitude_theta1"``), or None."""
    for cls in acting_effects():
        for p in cls.declaration.parameters:
            rest = name[len(p.axis) + 1:]
            if name.startswith(p.axis + "_") and rest.isidentifier():
                return cls, p, rest
    return None


def coordinate_axis(name: str) -> Parameter | None:
    """The parameter of an axis ``<effect axis>_<coordinate>`` of any system (its
    bounds; the units are the coordinate's, known once the system is), or None."""
    found = split_axis(name)
    if found is None:
        return None
    cls, p, _ = found
    k = _FORCE_POWER.get((cls.declaration.name, p.field))
    text = p.unit_text if k is None else f"{_SI['rad', k][1]} on an angle"
    return dataclasses.replace(p, axis=name, field=name, unit_text=text)
