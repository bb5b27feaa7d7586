"""A system declared in a run file: ``[system] kind = "DeclaredSystem"`` -> a
`sweep.DeclaredSystem`.

The table gives the declaration in text, in the user's own names::

    [system]
    kind = "DeclaredSystem"
    name = "pendulum_on_cart"           # the system's name (dataset title)
    lagrangian = "(M + m)*v**2/2 + m*l*v*omega*cos(theta) + m*l**2*omega**2/2 ..."
    drive_frequency_axis = "nu"         # optional: the parameter that is the angular
                                        # frequency [rad/s] of a periodic drive in t
                                        # (strobe, attractor catalogues)

    [[system.coordinates]]              # one table per coordinate, in order
    name = "x"                          # grid axis x_0, output x_final
    velocity = "v"                      # grid axis v_0, output v_final
    units = "m"                         # default "rad" for an angle
    angular = false                     # default true (winding, flips, degrees)
    force = "-c*v"                      # optional generalized force on x

    [[system.coordinates]]
    name = "theta"
    velocity = "omega"

    [system.parameters]                 # name = value, or a table
    M = {value = 2.0, units = "kg"}     # value (required), units, minimum, long_name
    g = 9.81

    [system.damping]                    # optional: every acceleration gains - c v_i
    coefficient = 0.1

Instead of ``lagrangian``, every coordinate's table may give its ``acceleration`` (an
expression), with an optional ``potential`` in ``[system]`` for the energy (kinetic
energy ``sum(v**2) / 2``).

Expressions (the Lagrangian, the forces) name the coordinates, their velocities, the
parameters and ``t`` (time), with numbers, ``+ - * / **``, ``sin``, ``cos``, ``sqrt``
and ``pi``. They are read from Python's syntax tree into SymPy
(`sweep.physics.derive`), never evaluated as Python. Every name is given to the kernels
as ``u_<name>`` (`kernel_symbol`), so a name may be one the kernels reserve (``g``,
``k``, ``L``); messages speak of the names as written.
"""

from __future__ import annotations

import ast
import math
import re
from typing import Any

from ._validate import check_keys
from .physics.derive import FUNCTIONS
from .physics.effect import Parameter
from .physics.system import Coordinate, SystemDeclaration

__all__ = ["COORDINATE_KEYS", "PARAMETER_KEYS", "SYSTEM_KEYS", "declaration_from_table",
           "declared_system", "kernel_symbol", "system_lines"]

#: Keys of ``[system]`` for a declared system.
SYSTEM_KEYS = ("kind", "name", "lagrangian", "potential", "coordinates", "parameters",
               "drive_frequency_axis", "damping", "torque", "forcing", "drag")
#: Keys of one ``[[system.coordinates]]`` table.
COORDINATE_KEYS = ("name", "velocity", "units", "velocity_units", "angular", "long_name",
                   "force", "acceleration")
#: Keys of a parameter given as a table in ``[system.parameters]``.
PARAMETER_KEYS = ("value", "units", "minimum", "long_name")
#: Names an expression reads that no declaration may take.
_TAKEN = ("t", "pi", *FUNCTIONS)


def kernel_symbol(name: str) -> str:
    """The kernel variable of a run file's name (a coordinate, velocity or parameter):
    ``u_<name>`` (never one of the kernels' reserved names)."""
    return f"u_{name}"


def declared_system(table: dict[str, Any]):
    """``[system]`` of ``kind = "DeclaredSystem"`` -> a `sweep.DeclaredSystem` (checked
    and derived: a bad declaration raises here, before any grid or compile).

    Parameters
    ----------
    table : dict
        The ``[system]`` table as `tomllib` reads it (see the module docstring).

    Returns
    -------
    sweep.DeclaredSystem
        With the parameters' values and ``[system.damping]`` as `sweep.Damping`.

    Raises
    ------
    ValueError, TypeError
        One line naming the key, the bad value and what is accepted: an unknown or
        missing key, a duplicate name, a name that is not an identifier or is taken
        (``t``, ``pi``, ``sin``, ``cos``, ``sqrt``), an expression naming an unknown
        symbol, a Lagrangian without a kinetic term in some velocity, a singular mass
        matrix, a value outside a parameter's bound.
    """
    from .physics import DeclaredSystem
    from .physics.coordinate_effects import acting_effects
    from .toml_effects import system_effects

    declaration, values = declaration_from_table(table)
    kinds = {cls.declaration.name: cls for cls in acting_effects()}
    effects = system_effects({k: v for k, v in table.items() if k in kinds}, kinds)
    names = _names(declaration)
    drive = table.get("drive_frequency_axis")
    if drive is not None and not isinstance(drive, str):
        raise TypeError(f"drive_frequency_axis = {drive!r}; accepted: the name of the "
                        "parameter that is the drive's angular frequency [rad/s], as in "
                        "[system.parameters]")
    try:
        return DeclaredSystem(declaration, effects=effects, drive_frequency_axis=drive,
                              **values)
    except ValueError as error:
        raise ValueError(_as_written(str(error), names)) from None


def declaration_from_table(table: dict[str, Any]) -> tuple[SystemDeclaration, dict]:
    """The `SystemDeclaration` a ``[system]`` table declares and its parameters' values
    (by name); the names' checks here, the expressions' in `sweep.physics.derive`."""
    check_keys(table, SYSTEM_KEYS, label="accepted for DeclaredSystem")
    for key in ("name", "coordinates"):
        if key not in table:
            raise ValueError(f"DeclaredSystem needs {key}; accepted: name = \"...\", "
                             "lagrangian = \"...\" (an expression), [[system.coordinates]] "
                             "tables, [system.parameters]")
    name = table["name"]
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z][\w\-]*", name):
        raise ValueError(f"name = {name!r}; accepted: a word of letters, digits, _ and - "
                         "starting with a letter")
    coordinates, forces, accelerations = _coordinates(table["coordinates"])
    given = [a is not None for a in accelerations]
    if ("lagrangian" in table) == all(given) or (any(given) and not all(given)):
        raise ValueError("DeclaredSystem takes either lagrangian = \"...\" or an "
                         "acceleration = \"...\" in every [[system.coordinates]] table; "
                         f"got {'both' if 'lagrangian' in table and any(given) else 'neither'}"
                         f" (accelerations on {sum(given)} of {len(given)} coordinates)")
    lagrangian = (_expression("lagrangian", table["lagrangian"]) if "lagrangian" in table
                  else None)
    potential = (_expression("potential", table["potential"]) if "potential" in table
                 else None)
    parameters, values = _parameters(table.get("parameters", {}))
    seen: dict[str, str] = {}
    for what, items in [*((f"coordinate {c.name!r}", (c.name, c.velocity)) for c in coordinates),
                        *((f"parameter {p.axis!r}", (p.axis,)) for p in parameters)]:
        for item in items:
            if item in seen:
                raise ValueError(f"the name {item!r} is given twice (by {seen[item]} and "
                                 f"{what}); accepted: distinct names for the coordinates, "
                                 "their velocities and the parameters")
            seen[item] = what
    names = list(seen)
    for what, text in [("lagrangian", lagrangian), ("potential", potential),
                       *((f"force on {c.name!r}", f) for c, f in zip(coordinates, forces)),
                       *((f"acceleration of {c.name!r}", a)
                         for c, a in zip(coordinates, accelerations))]:
        if text is not None:
            _check_names(what, text, names)
    rename = {n: kernel_symbol(n) for n in names}
    declaration = SystemDeclaration(
        name=name, coordinates=coordinates, parameters=parameters,
        lagrangian=None if lagrangian is None else _renamed(lagrangian, rename),
        forces=tuple(_renamed(f or "0", rename) for f in forces)
        if any(f is not None for f in forces) else (),
        accelerations=tuple(_renamed(a, rename) for a in accelerations)
        if all(given) else (),
        potential=None if potential is None else _renamed(potential, rename))
    return declaration, values


def system_lines(system, value_text) -> list[str]:
    """The ``[system]`` table (and its subtables) that declares ``system`` in a run
    file: the inverse of `declared_system`, for the explorer's run files.

    Parameters
    ----------
    system : sweep.DeclaredSystem
        Its declaration's kernel symbols are written back as the names (a declaration
        made in Python with other symbols reads back as the same equations with the
        symbols ``u_<name>``).
    value_text : callable
        A value (str, float, bool, dict) as TOML text.

    Returns
    -------
    list of str
        Lines, from ``[system]`` to the last subtable.
    """
    declaration = system.declaration
    names = _names(declaration)
    out = ["[system]", f"kind = {value_text('DeclaredSystem')}",
           f"name = {value_text(declaration.name)}"]
    if declaration.lagrangian is not None:
        out.append(f"lagrangian = {value_text(_renamed(declaration.lagrangian, names))}")
    if declaration.potential is not None:
        out.append(f"potential = {value_text(_renamed(declaration.potential, names))}")
    drive = system.to_dict().get("drive_frequency_axis")
    if drive is not None:
        out.append(f"drive_frequency_axis = {value_text(drive)}")
    for k, c in enumerate(declaration.coordinates):
        out += ["", "[[system.coordinates]]", f"name = {value_text(c.name)}",
                f"velocity = {value_text(c.velocity)}", f"units = {value_text(c.units)}",
                f"velocity_units = {value_text(c.velocity_units)}",
                f"angular = {value_text(c.angular)}"]
        if c.long_name:
            out.append(f"long_name = {value_text(c.long_name)}")
        if declaration.forces:
            out.append(f"force = {value_text(_renamed(declaration.forces[k], names))}")
        if declaration.accelerations:
            out.append("acceleration = "
                       f"{value_text(_renamed(declaration.accelerations[k], names))}")
    if declaration.parameters:
        out += ["", "[system.parameters]"]
    for p in declaration.parameters:
        entry = {"value": float(getattr(system, p.axis)), "units": p.units}
        if p.minimum is not None:
            entry["minimum"] = float(p.minimum)
        if p.long_name:
            entry["long_name"] = p.long_name
        out.append(f"{p.axis} = {value_text(entry)}")
    from .toml_effects import system_effects_lines

    return out + system_effects_lines(system.effects, value_text)


# ----------------------------------------------------------------------------- helpers
def _identifier(what: str, value: Any) -> str:
    if not isinstance(value, str) or not value.isidentifier() or value in _TAKEN \
            or value.startswith("_"):
        raise ValueError(f"{what} = {value!r}; accepted: an identifier (letters, digits "
                         "and _, not starting with a digit or _) other than "
                         f"{', '.join(_TAKEN)}")
    return value


def _expression(what: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip():
        raise TypeError(f"{what} must be an expression in a string, got {value!r}")
    return value


def _coordinates(value: Any) -> tuple[tuple[Coordinate, ...], list[str | None],
                                      list[str | None]]:
    accepted = ("one [[system.coordinates]] table per coordinate with name, velocity "
                "(and units, velocity_units, angular, long_name, force or acceleration)")
    if not isinstance(value, list) or not value or not all(isinstance(c, dict)
                                                          for c in value):
        raise TypeError(f"coordinates = {value!r}; accepted: {accepted}")
    coordinates, forces, accelerations = [], [], []
    for index, entry in enumerate(value):
        where = f"coordinates[{index}]"
        check_keys(entry, COORDINATE_KEYS, f" in {where}")
        for key in ("name", "velocity"):
            if key not in entry:
                raise ValueError(f"{where} needs {key}; accepted: {accepted}")
        name = _identifier(f"{where} name", entry["name"])
        velocity = _identifier(f"{where} velocity", entry["velocity"])
        angular = entry.get("angular", True)
        if not isinstance(angular, bool):
            raise TypeError(f"{where} angular must be true or false, got {angular!r}")
        if not angular and "units" not in entry:
            raise ValueError(f"{where} ({name!r}) is not angular and gives no units; "
                             "accepted: units = \"m\" (a UDUNITS string)")
        units = entry.get("units", "rad")
        velocity_units = entry.get("velocity_units", f"{units} s-1")
        long_name = entry.get("long_name", "")
        for key, text in (("units", units), ("velocity_units", velocity_units),
                          ("long_name", long_name)):
            if not isinstance(text, str):
                raise TypeError(f"{where} {key} must be a string, got {text!r}")
        coordinates.append(Coordinate(name, velocity, kernel_symbol(name),
                                      kernel_symbol(velocity), units=units,
                                      velocity_units=velocity_units, long_name=long_name,
                                      angular=angular))
        forces.append(_expression(f"{where} force", entry["force"])
                      if "force" in entry else None)
        accelerations.append(_expression(f"{where} acceleration", entry["acceleration"])
                             if "acceleration" in entry else None)
    return tuple(coordinates), forces, accelerations


def _parameters(value: Any) -> tuple[tuple[Parameter, ...], dict[str, float]]:
    accepted = ("name = value, or name = {value = ..., units = \"...\", minimum = ..., "
                "long_name = \"...\"}")
    if not isinstance(value, dict):
        raise TypeError(f"parameters must be a table [system.parameters] of {accepted}, "
                        f"got {value!r}")
    parameters, values = [], {}
    for name, entry in value.items():
        _identifier(f"parameters {name!r}", name)
        entry = {"value": entry} if not isinstance(entry, dict) else entry
        check_keys(entry, PARAMETER_KEYS, f" in parameters.{name}")
        if "value" not in entry:
            raise ValueError(f"parameters.{name} needs value; accepted: {accepted}")
        number = entry["value"]
        minimum = entry.get("minimum")
        for key, item in (("value", number), ("minimum", minimum)):
            if item is not None and (isinstance(item, bool) or not isinstance(item, (int, float))
                                     or not math.isfinite(item)):
                raise TypeError(f"parameters.{name} {key} must be a finite number, "
                                f"got {item!r}")
        units = entry.get("units", "1")
        long_name = entry.get("long_name", name)
        for key, text in (("units", units), ("long_name", long_name)):
            if not isinstance(text, str):
                raise TypeError(f"parameters.{name} {key} must be a string, got {text!r}")
        parameters.append(Parameter(name, name, kernel_symbol(name), units, units, long_name,
                                    minimum=None if minimum is None else float(minimum)))
        values[name] = float(number)
    return tuple(parameters), values


def _check_names(what: str, text: str, names: list[str]) -> None:
    """Refuse an expression naming anything but ``names``, ``t``, ``pi`` and calling
    anything but `FUNCTIONS` (the rest of its syntax is checked by the derivation)."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as error:
        raise ValueError(f"the {what}, {text!r}, does not parse ({error.msg}); accepted: "
                         "an expression with numbers, + - * / ** and parentheses") from None
    called = {id(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and not (isinstance(node.func, ast.Name)
                                               and node.func.id in FUNCTIONS):
            raise ValueError(f"the {what}, {text!r}, calls {ast.unparse(node.func)!r}; "
                             f"accepted: the functions {', '.join(FUNCTIONS)}")
        if isinstance(node, ast.Name) and id(node) not in called \
                and node.id not in names and node.id not in ("t", "pi"):
            raise ValueError(f"the {what}, {text!r}, names {node.id!r}, which is no "
                             f"coordinate, velocity or parameter; accepted: "
                             f"{', '.join(names)}, t, pi and the functions "
                             f"{', '.join(FUNCTIONS)}")


def _renamed(text: str, rename: dict[str, str]) -> str:
    """``text`` with every declared name replaced by its kernel symbol (syntax tree)."""
    tree = ast.parse(text.strip(), mode="eval")
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and node.id in rename:
            node.id = rename[node.id]
    return ast.unparse(tree)


def _names(declaration: SystemDeclaration) -> dict[str, str]:
    """Kernel symbol -> name as written, for messages."""
    found = {c.symbol: c.name for c in declaration.coordinates}
    found.update({c.velocity_symbol: c.velocity for c in declaration.coordinates})
    found.update({p.symbol: p.axis for p in declaration.parameters})
    return found


def _as_written(message: str, names: dict[str, str]) -> str:
    """A derivation's message with the kernel symbols put back as the names written."""
    if not names:
        return message
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, names)) + r")\b")
    return pattern.sub(lambda match: names[match.group(1)], message)
