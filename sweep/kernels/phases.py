"""The drive phases of a system's float32 kernel (`sweep.kernels.source._system_single`):
the arguments of the sines and cosines that read the time ``t``, kept in float64.

A system whose dynamics read the time (a driven pivot ``a nu^2 cos(nu t)``, a
``sweep.Forcing(A, W, phase, on=...)``'s ``A sin(W t + phase)``, a declared Lagrangian
in ``t``) evaluates ``sin`` or ``cos`` of a phase that grows with ``t``. In float32 that
phase would be known only to ulp(nu t) / 2 (2e-3 rad at nu t = 4e4), and a frequency
rounded to float32 shifts it by ``t`` times the rounding of ``nu`` (2e-3 rad after 1e4 s
at nu = 2 pi). So, as the single pendulum's drives (`sweep.kernels.precision`):

- a **phase** is the argument of a ``vsin``, ``vcos`` or ``vsincos`` call that reads
  ``t`` (directly or through the physics function's temporaries); it is computed in
  float64 from the float64 stage time ``t0 + (step + c) dt`` (`sweep.kernels.precision.
  clock`), its literals float64;
- whatever it reads is float64: the **parameters** (their loads and lanes stay float64),
  the physics function's **temporaries** (their statements evaluate in float64) and the
  **hoisted** values (`sweep.kernels.rewrite`, stored once per trajectory in a float32
  array: those a phase reads are recomputed in the physics function instead, from the
  float64 parameters, a few float64 products per stage);
- `sweep.kernels.vecmath.sin32` reduces the float64 phase in float64 and rounds the
  reduced argument to float32 once; its value, and everything after it, is float32;
- everywhere else, a float64 name is read as ``F(name)`` (rounded to float32 once), so
  that the rest of the step stays float32 arithmetic (a product of a float32 and a
  float64 is float64 in numba, and would make the accelerations float64).

Only the syntax is read (each statement parsed with `ast`): the analysis is the same on
the generated float64 lines and on their float32 text (``F(...)`` calls change no name).
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass

__all__ = ["Phases", "bodies", "find", "float64_function", "float64_phases"]

#: The sine and cosine calls of the generated physics (`sweep.kernels.vecmath`).
TRIG = frozenset({"vsin", "vcos", "vsincos"})
#: The time argument of a physics function that reads it (`sweep.kernels.system.uses_time`).
TIME = "t"
#: The physics functions' array of hoisted values (`sweep.kernels.system`).
HOISTED = "hoisted_values"


@dataclass(frozen=True)
class Phases:
    """What the phases of a system's physics functions read (see the module notes).

    Attributes
    ----------
    parameters : frozenset of str
        Parameter symbols a phase reads: loaded, laned and passed in float64.
    hoisted : tuple of str
        Hoisted statements (float64 source, in order) a phase reads, directly or
        through another: recomputed in float64 inside the physics function.
    """

    parameters: frozenset
    hoisted: tuple


def _parse(line: str):
    (statement,) = ast.parse(line.strip()).body
    return statement


def _targets(statement) -> list[str]:
    if isinstance(statement, ast.Assign):
        return [n.id for n in ast.walk(statement.targets[0]) if isinstance(n, ast.Name)]
    return []


def _value(statement):
    return statement.value


def _reads(node) -> list[str]:
    return [n.id for n in ast.walk(node) if isinstance(n, ast.Name)
            and isinstance(n.ctx, ast.Load)]


def _hoisted_read(statement) -> str | None:
    """``x`` for the statement ``x = hoisted_values[k, j]``, else None."""
    value = _value(statement)
    if isinstance(statement, ast.Assign) and isinstance(value, ast.Subscript) and \
            isinstance(value.value, ast.Name) and value.value.id == HOISTED:
        return _targets(statement)[0]
    return None


def _is_trig(node) -> bool:
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and \
        node.func.id in TRIG and len(node.args) == 1


class _Flow:
    """One physics function's statements: where each read name is defined, which
    statements read the time, and which definitions the phases need in float64.

    A definition is ``("body", i)`` (statement i), ``("hoisted", x)``, ``("parameter",
    p)`` or ``("time",)``; names it cannot place (functions, ``math``) are ignored."""

    def __init__(self, lines, hoisted: dict, parameters) -> None:
        self.statements = [_parse(line) for line in lines]
        self.hoisted = hoisted  # name -> (its statement, {read name -> definition})
        where: dict[str, tuple] = {}
        self.resolved: list[dict[str, tuple]] = []
        self.timed: list[bool] = []
        for i, statement in enumerate(self.statements):
            seen = {}
            for name in _reads(_value(statement)):
                if name in where:
                    seen[name] = where[name]
                elif name == TIME:
                    seen[name] = ("time",)
                elif name in parameters:
                    seen[name] = ("parameter", name)
            self.resolved.append(seen)
            self.timed.append(any(d == ("time",) or (d[0] == "body" and self.timed[d[1]])
                                  for d in seen.values()))
            read = _hoisted_read(statement)
            for name in _targets(statement):
                where[name] = ("hoisted", name) if read else ("body", i)

    def phase(self, i: int, node) -> bool:
        """Whether ``node`` (in statement i) is a sine or cosine of a time-dependent
        argument."""
        if not _is_trig(node):
            return False
        seen = self.resolved[i]
        return any(seen.get(name) == ("time",) or (seen.get(name, ("",))[0] == "body"
                                                   and self.timed[seen[name][1]])
                   for name in _reads(node.args[0]))

    def needed(self) -> set[tuple]:
        """Every definition a phase reads, directly or through others."""
        todo = []
        for i, statement in enumerate(self.statements):
            for node in ast.walk(_value(statement)):
                if self.phase(i, node):
                    todo += [self.resolved[i][name] for name in _reads(node.args[0])
                             if name in self.resolved[i]]
        need: set[tuple] = set()
        while todo:
            definition = todo.pop()
            if definition in need:
                continue
            need.add(definition)
            if definition[0] == "body":
                todo += self.resolved[definition[1]].values()
            elif definition[0] == "hoisted":
                todo += self.hoisted[definition[1]][1].values()
        return need


def _hoisted_table(hoisted, parameters) -> dict:
    """Hoisted statements by target: (statement, {read name -> definition})."""
    table: dict = {}
    for line in hoisted:
        statement = _parse(line)
        seen = {name: ("hoisted", name) if name in table else ("parameter", name)
                for name in _reads(_value(statement)) if name in table or name in parameters}
        for name in _targets(statement):
            table[name] = (line, seen)
    return table


def find(functions, hoisted, parameters) -> Phases:
    """The parameters and hoisted statements the phases of ``functions`` read.

    Parameters
    ----------
    functions : sequence of sequence of str
        Each physics function's body, one statement a line (its ``return`` included).
    hoisted : sequence of str
        The hoisted statements (`sweep.kernels.rewrite.Rewritten.hoisted`), in order.
    parameters : collection of str
        The parameter symbols (the values that do not change along a trajectory).

    Returns
    -------
    Phases
    """
    parameters = set(parameters)
    table = _hoisted_table(hoisted, parameters)
    need: set[tuple] = set()
    for lines in functions:
        need |= _Flow(lines, table, parameters).needed()
    names = {d[1] for d in need if d[0] == "hoisted"}
    # in order, once each (a statement may assign two names)
    return Phases(frozenset(d[1] for d in need if d[0] == "parameter"),
                  tuple(dict.fromkeys(table[name][0] for name in table if name in names)))


class _Unwrap(ast.NodeTransformer):
    """``F(<number>)`` back to the float64 literal ``<number>``."""

    def visit_Call(self, node):
        self.generic_visit(node)
        if isinstance(node.func, ast.Name) and node.func.id == "F" and \
                len(node.args) == 1 and isinstance(node.args[0], ast.Constant):
            return node.args[0]
        return node


def _float32(name: str):
    return ast.Call(ast.Name("F", ast.Load()), [ast.Name(name, ast.Load())], [])


def float64_function(lines, hoisted, parameters) -> list[str]:
    """A float32 physics function's body (``lines``: one statement a line, literals and
    loads as float32, `sweep.kernels.precision`) with its phases in float64 (the module
    notes): the phases' literals and the statements they read in float64, the hoisted
    values they read recomputed (``hoisted``: float64 source) in place of their reads,
    and every other read of a float64 value written ``F(name)``. Lines that need no
    change keep their text."""
    parameters = set(parameters)
    table = _hoisted_table(hoisted, parameters)
    flow = _Flow(lines, table, parameters)
    need = flow.needed()
    # the hoisted statements the phases read (`needed` follows them to the ones they
    # read), in order, once each (a statement may assign two names)
    closure = {d[1] for d in need if d[0] == "hoisted"}
    again = list(dict.fromkeys(line for name, (line, _) in table.items() if name in closure))
    closure |= {name for line in again for name in _targets(_parse(line))}
    # the float64 definitions
    wide = need | {("hoisted", name) for name in closure} | {("time",)}
    out: list[str] = []
    placed = False
    for i, (line, statement) in enumerate(zip(lines, flow.statements)):
        lead = line[:len(line) - len(line.lstrip())]
        read = _hoisted_read(statement)
        if read is not None and read in closure:
            if not placed:
                out += [lead + x for x in again]
                placed = True
            continue
        if ("body", i) in need:
            new = _Unwrap().visit(statement)
        else:
            new = _narrow(statement, i, flow, wide)
        text = ast.unparse(new)
        out.append(line if text == ast.unparse(_parse(line)) else lead + text)
    return out


def _narrow(statement, i: int, flow: _Flow, wide: set):
    """Statement i (not read by a phase): its phases' literals float64, every other
    read of a float64 definition (``wide``) rounded to float32."""
    seen = flow.resolved[i]

    class Narrow(ast.NodeTransformer):
        def visit_Call(self, node):
            if flow.phase(i, node):
                node.args = [_Unwrap().visit(node.args[0])]
                return node
            self.generic_visit(node)
            return node

        def visit_Name(self, node):
            if isinstance(node.ctx, ast.Load) and seen.get(node.id) in wide:
                return _float32(node.id)
            return node

    return Narrow().visit(statement)


_FUNCTION = re.compile(r"^def \w+\((?P<arguments>[^)]*)\):\n(?P<body>(?:[ \t]+.*\n)+)",
                       re.MULTILINE)


def bodies(text: str) -> list[list[str]]:
    """The bodies (lines) of the functions in ``text`` that take the time ``t`` (the
    physics functions of a time-dependent system, `sweep.kernels.system._physics`)."""
    return [m.group("body").splitlines() for m in _FUNCTION.finditer(text)
            if TIME in [a.strip() for a in m.group("arguments").split(",")]]


def float64_phases(text: str, phases: Phases) -> str:
    """``text`` (a float32 module) with `float64_function` applied to each function
    that takes the time ``t`` (the parameters other than ``phases.parameters`` need not
    be named: they stay float32 and nothing is done to their reads)."""
    def edit(m):
        arguments = [a.strip() for a in m.group("arguments").split(",")]
        if TIME not in arguments:
            return m.group(0)
        lines = float64_function(m.group("body").splitlines(), phases.hoisted,
                                 phases.parameters)
        return m.group(0)[:m.start("body") - m.start(0)] + "\n".join(lines) + "\n"

    return _FUNCTION.sub(edit, text)
