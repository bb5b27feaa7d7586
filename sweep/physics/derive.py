"""From a system's declaration to kernel source: equations of motion, energy, Jacobian.

`derive` reads a `sweep.physics.system.SystemDeclaration` and returns a
`sweep.physics.system.DerivedSystem` whose strings follow that module's kernel-source
conventions. It is the only place in sweep that imports SymPy (an optional
dependency, ``pip install -e ".[systems]"`` in a checkout), and only when a declaration is derived
for the first time: results are memoised in the process and kept on disk, as JSON
beside the kernel modules (`sweep._config.kernel_folder`, checked as the kernels are).

The derivation is written here rather than taken from ``sympy.physics.mechanics``: a
declaration gives a Lagrangian in generalized coordinates already, so the
Euler-Lagrange equations are a few derivatives, and the result keeps the form the
kernels want (the mass matrix apart, solved in closed form with its determinant
computed once), which ``LagrangesMethod`` would hand back as a general linear solve.

For coordinates q, velocities v, time t and generalized forces Q::

    M_ij = d2L / dv_i dv_j                                     (mass matrix)
    b_i  = dL/dq_i - sum_j d2L/(dv_i dq_j) v_j - d2L/(dv_i dt) + Q_i
    M a  = b                                                    (accelerations a)
    E    = sum_i v_i dL/dv_i - L                                (energy)

``M a = b`` is solved by division when M is diagonal, and by Cramer's rule (adjugate
over the determinant, the determinant computed once) for two and three coordinates; a
non-diagonal mass matrix of more coordinates is refused. The energy function E is the
kinetic plus the potential energy when the kinetic energy is quadratic in the
velocities (every built-in system). The Jacobian of the accelerations differentiates
``M a = b``: ``da/dz = M^-1 (db/dz - (dM/dz) a)`` for each state variable z, the same
derivative as differentiating the solved expressions, but with the accelerations and
the inverse determinant shared instead of differentiated through.

The kernel source: SymPy's ``cse`` names the common subexpressions ``x0, x1, ...``;
where both the sine and the cosine of one argument u occur, they come from one
``s_<k>, c_<k> = vsincos(u)``; integer powers are written as products (``x**2`` ->
``x*x``, ``x**-2`` -> ``1.0/(x*x)``), half-integer ones with ``math.sqrt``, and every
number as a Python float literal. Each block (accelerations, energy, Jacobian) reads
only the state, the parameters and ``t`` and assigns its temporaries before reading
them, so blocks may follow one another in one function.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import keyword
import math
import os
import random
import re
import tempfile
from pathlib import Path

from .. import _config
from .effect import RESERVED_SYMBOLS, Parameter
from .system import Coordinate, DerivedSystem, SystemDeclaration

__all__ = ["DERIVE_VERSION", "FUNCTIONS", "derive", "derive_system"]

#: Version of the derivation and of the source it writes: part of the disk cache's key,
#: so a change here (a different printer, another simplification) misses old entries.
DERIVE_VERSION = 1

#: The built-in systems' derivations shipped with sweep (package data; written by
#: `sweep.physics.shipped`), read before the disk cache.
SHIPPED_FOLDER = Path(__file__).parent / "derived"

#: Functions a declaration's expressions may call (and the constant ``pi``); ``abs``
#: serves a quadratic drag ``-k*v*abs(v)`` (the kernels' ``abs``): where its derivative
#: ``sign(x)`` multiplies ``x`` (a drag's Jacobian) it is written ``abs(x)``, and a
#: ``sign`` left over is refused.
FUNCTIONS = ("sin", "cos", "sqrt", "abs")

#: Names a declaration's symbols must not take: the conventions' functions and outputs,
#: the expressions' functions and constants, time.
_TAKEN = frozenset({"vsin", "vcos", "vsincos", "vfma", "math", "energy_value", "pi", "t",
                    *FUNCTIONS})
#: Patterns of the names `derive` writes (temporaries, sincos pairs, outputs).
_WRITTEN = re.compile(r"x\d+|[sc]_\d+|acc_\w*|jac_\w*")
#: Largest mass matrix solved in closed form when it is not diagonal.
_MOST_COUPLED = 3


def derive(declaration: SystemDeclaration, *, jacobian: bool = False) -> DerivedSystem:
    """The kernel source of a system: its accelerations, its energy and, if asked, the
    Jacobian of its accelerations.

    Parameters
    ----------
    declaration : SystemDeclaration
        The system (see `sweep.physics.system`).
    jacobian : bool
        Also derive ``jacobian_lines`` (the tangent dynamics of ``lyapunov`` read them).

    Returns
    -------
    DerivedSystem
        Source following the conventions of `sweep.physics.system`: ``accel_lines``
        ending with ``acc_<symbol> = ...`` per coordinate, ``energy_lines`` ending with
        ``energy_value = ...`` (empty when an ``accelerations`` declaration gives no
        ``potential``), ``jacobian_lines`` ending with ``jac_<a>_<b> = ...`` for each
        coordinate symbol a and each state variable b (positions first, then
        velocities, in coordinate order); empty unless ``jacobian``.

    Raises
    ------
    ValueError
        For a bad declaration, before anything is derived or compiled, naming the
        declaration, what is wrong and what is accepted: duplicate or reserved names,
        a symbol that is not a coordinate, velocity, parameter or ``t``, an expression
        that does not parse or calls a function other than `FUNCTIONS`, the wrong
        number of forces or accelerations, a mass matrix with a zero row (a velocity
        the Lagrangian has no kinetic term in) or a zero determinant, a non-diagonal
        mass matrix of more than three coordinates, a power the kernels cannot
        evaluate.
    TypeError
        If ``declaration`` is not a `SystemDeclaration`.
    ImportError
        If SymPy is not installed and the declaration is neither shipped nor in the disk
        cache.

    Notes
    -----
    The built-in systems' common declarations are shipped derived
    (`sweep.physics.shipped`: the double pendulum, coupled pendula of 2 to 4), so they
    need no SymPy. Memoised in the process (``derive.cache_clear()`` empties it) and
    cached on disk:
    ``<kernel folder>/system_<hash>.json``, keyed by the declaration's ``repr``, the
    ``jacobian`` flag and `DERIVE_VERSION`, written atomically. The disk cache is not
    used when the kernel folder could be changed by another user (the kernels then warn).
    """
    if not isinstance(declaration, SystemDeclaration):
        raise TypeError(f"derive: expected a SystemDeclaration, got "
                        f"{type(declaration).__name__}")
    _check_structure(declaration)
    return _derive(declaration, bool(jacobian))


def derive_system(system, jacobian: bool = False) -> DerivedSystem:
    """A system's equations of motion and energy (with ``jacobian``: and the Jacobian of
    the accelerations) as kernel source, its effects on coordinates included: `derive`
    of ``system.declaration_with_effects`` (SymPy only on the first derivation on a
    machine, then read from the cache; the built-in systems' common declarations are
    shipped derived). `sweep.physics.System.derived` of every system.

    Raises
    ------
    ImportError
        Where the equations must be derived and SymPy is not installed (naming the
        effects on coordinates that made a derivation necessary).
    """
    declaration = system.declaration_with_effects
    try:
        return derive(declaration, jacobian=jacobian)
    except ImportError as error:
        if declaration is system.declaration:
            raise
        acting = ", ".join(repr(e) for e in system.effects if e.coordinate is not None)
        raise ImportError(
            f"{type(system).__name__} with {acting}: an effect on one coordinate changes "
            "the equations of motion, which sweep derives again with SymPy (once per "
            "machine and combination, then cached); " + str(error)) from error


@functools.cache
def _derive(declaration: SystemDeclaration, jacobian: bool) -> DerivedSystem:
    """`derive` after the structure checks: shipped with sweep (`sweep.physics.shipped`),
    from the disk cache, or derived and stored."""
    key = _key(declaration, jacobian)
    shipped = _read(SHIPPED_FOLDER / f"system_{key}.json", declaration, jacobian)
    if shipped is not None:
        return shipped
    folder = _folder()
    if folder is not None:
        found = _read(folder / f"system_{key}.json", declaration, jacobian)
        if found is not None:
            return found
    derived = _derive_now(declaration, jacobian)
    if folder is not None:
        _write(folder / f"system_{key}.json", declaration, jacobian, derived)
    return derived


derive.cache_clear = _derive.cache_clear  # the memo's reset and statistics (tests)
derive.cache_info = _derive.cache_info


# ---------------------------------------------------------------- checks without SymPy
def _who(declaration: SystemDeclaration) -> str:
    return f"system {declaration.name!r}"


def _check_structure(declaration: SystemDeclaration) -> None:
    """Types, counts and names of a declaration (no SymPy): ValueError if wrong."""
    who = _who(declaration)
    if not isinstance(declaration.name, str) or not declaration.name:
        raise ValueError(f"system declaration: name {declaration.name!r} is not accepted; "
                         "accepted: a non-empty string")
    coordinates, parameters = declaration.coordinates, declaration.parameters
    if not isinstance(coordinates, tuple) or not coordinates or not all(
            isinstance(c, Coordinate) for c in coordinates):
        raise ValueError(f"{who}: coordinates {coordinates!r} are not accepted; accepted: "
                         "a non-empty tuple of Coordinate")
    if not isinstance(parameters, tuple) or not all(isinstance(p, Parameter)
                                                     for p in parameters):
        raise ValueError(f"{who}: parameters {parameters!r} are not accepted; accepted: a "
                         "tuple of Parameter")
    _check_names(declaration)
    n = len(coordinates)
    lagrangian, accelerations = declaration.lagrangian, declaration.accelerations
    if (lagrangian is None) == (not accelerations):
        raise ValueError(f"{who}: give either a lagrangian or accelerations (one per "
                         "coordinate), not " + ("both" if lagrangian is not None else "neither"))
    if lagrangian is not None:
        _check_strings(who, "lagrangian", (lagrangian,))
        _check_count(who, "forces", declaration.forces, n, allow_none=True)
        if declaration.potential is not None:
            raise ValueError(f"{who}: a potential is read only with accelerations; with a "
                             "lagrangian, the energy comes from the lagrangian (leave "
                             "potential None)")
    else:
        _check_count(who, "accelerations", accelerations, n, allow_none=False)
        if declaration.forces:
            raise ValueError(f"{who}: forces are read only with a lagrangian; with "
                             "accelerations, write them into the accelerations (leave "
                             "forces empty)")
        if declaration.potential is not None:
            _check_strings(who, "potential", (declaration.potential,))


def _check_count(who: str, what: str, texts, n: int, allow_none: bool) -> None:
    accepted = f"a tuple of {n} strings, one per coordinate" + (
        " (or an empty tuple for none)" if allow_none else "")
    if not isinstance(texts, tuple):
        raise ValueError(f"{who}: {what} is a {type(texts).__name__}; accepted: {accepted}")
    if len(texts) != n and not (allow_none and not texts):
        raise ValueError(f"{who}: {what} has {len(texts)} entries; accepted: {accepted}")
    _check_strings(who, what, texts)


def _check_strings(who: str, what: str, texts) -> None:
    for text in texts:
        if not isinstance(text, str) or not text.strip():
            raise ValueError(f"{who}: {what} entry {text!r} is not accepted; accepted: a "
                             "non-empty string holding an expression")


def _check_names(declaration: SystemDeclaration) -> None:
    """Unique dataset names, grid axes and kernel symbols, none reserved."""
    who = _who(declaration)
    names: dict[str, str] = {}
    for c in declaration.coordinates:
        for name, what in ((c.name, "coordinate name"), (c.velocity, "velocity name")):
            _unique(who, names, name, what)
    axes = {f"{name}_0": what for name, what in names.items()}
    for p in declaration.parameters:
        _unique(who, axes, p.axis, "parameter axis")
    fields: dict[str, str] = {}
    for p in declaration.parameters:
        _unique(who, fields, p.field, "parameter field")
    symbols: dict[str, str] = {}
    for c in declaration.coordinates:
        _unique(who, symbols, c.symbol, f"symbol of coordinate {c.name!r}")
        _unique(who, symbols, c.velocity_symbol, f"velocity symbol of coordinate {c.name!r}")
    for p in declaration.parameters:
        _unique(who, symbols, p.symbol, f"symbol of parameter {p.axis!r}")
    for symbol, what in symbols.items():
        if (not isinstance(symbol, str) or not symbol.isidentifier()
                or keyword.iskeyword(symbol) or symbol in RESERVED_SYMBOLS
                or symbol in _TAKEN or _WRITTEN.fullmatch(symbol)):
            raise ValueError(
                f"{who}: the {what}, {symbol!r}, is not accepted; accepted: a Python "
                "identifier that is not a keyword, not one of sweep's reserved kernel "
                f"names ({', '.join(sorted(RESERVED_SYMBOLS | _TAKEN))}) and not of the "
                "form of a derived name (x<k>, s_<k>, c_<k>, acc_..., jac_...)")


def _unique(who: str, seen: dict, name, what: str) -> None:
    if not isinstance(name, str) or not name:
        raise ValueError(f"{who}: the {what} {name!r} is not accepted; accepted: a "
                         "non-empty string")
    if name in seen:
        raise ValueError(f"{who}: the {what} {name!r} is also the {seen[name]}; accepted: "
                         "names that differ")
    seen[name] = what


# ---------------------------------------------------------------- the disk cache
def _key(declaration: SystemDeclaration, jacobian: bool) -> str:
    text = f"{DERIVE_VERSION}\n{jacobian}\n{declaration!r}"
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _folder() -> Path | None:
    """The checked kernel folder, or None when it is unsafe (not used then)."""
    try:
        folder, problem = _config.kernel_folder()
    except OSError:  # pragma: no cover - not even the temporary folder could be made
        return None
    return None if problem else folder


def _read(path: Path, declaration: SystemDeclaration, jacobian: bool) -> DerivedSystem | None:
    """The derived system stored at ``path``, or None if absent, unreadable or another's."""
    try:
        with open(path, encoding="utf-8") as handle:
            stored = json.load(handle)
    except (OSError, ValueError):
        return None
    if not isinstance(stored, dict) or stored.get("derive_version") != DERIVE_VERSION \
            or stored.get("declaration") != repr(declaration) \
            or stored.get("jacobian") is not jacobian:
        return None
    blocks = []
    for name in ("accel_lines", "energy_lines", "jacobian_lines"):
        lines = stored.get(name)
        if not isinstance(lines, list) or not all(isinstance(line, str) for line in lines):
            return None
        blocks.append(tuple(lines))
    return DerivedSystem(*blocks)


def _write(path: Path, declaration: SystemDeclaration, jacobian: bool,
           derived: DerivedSystem) -> None:
    """Store ``derived`` at ``path`` atomically (a temporary file renamed over it); a
    failure (a full disk) leaves no file and is not an error: the next process derives
    again."""
    stored = {"derive_version": DERIVE_VERSION, "declaration": repr(declaration),
              "jacobian": jacobian, "accel_lines": list(derived.accel_lines),
              "energy_lines": list(derived.energy_lines),
              "jacobian_lines": list(derived.jacobian_lines)}
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            json.dump(stored, handle, indent=1)
        os.replace(tmp, path)
    except OSError:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass


# ---------------------------------------------------------------- the derivation
def _sympy():
    try:
        import sympy
    except ImportError as error:  # pragma: no cover - sympy is in the test extra
        raise ImportError("deriving a system's equations needs SymPy: pip install "
                          "'sympy>=1.12' (or, in a checkout of sweep, pip install -e "
                          "\".[systems]\")") from error
    return sympy


def _derive_now(declaration: SystemDeclaration, jacobian: bool) -> DerivedSystem:
    """The derivation itself (SymPy): parse, differentiate, check, solve, print."""
    sp = _sympy()
    who = _who(declaration)
    q = [sp.Symbol(c.symbol, real=True) for c in declaration.coordinates]
    v = [sp.Symbol(c.velocity_symbol, real=True) for c in declaration.coordinates]
    params = [sp.Symbol(p.symbol, real=True) for p in declaration.parameters]
    t = sp.Symbol("t", real=True)
    names = {s.name: s for s in (*q, *v, *params, t)}
    parse = functools.partial(_parse, sp, declaration, names)

    if declaration.lagrangian is not None:
        lagrangian = parse("lagrangian", declaration.lagrangian)
        forces = [parse(f"force on {c.name!r}", text) for c, text in
                  zip(declaration.coordinates, declaration.forces)] or [sp.S.Zero] * len(q)
        mass, rhs, energy = _euler_lagrange(sp, lagrangian, forces, q, v, t)
        _check_mass(sp, declaration, mass, q, v, params, t)
        accelerations, inverse = _solve(sp, mass, rhs)
        energies = [energy]
    else:
        accelerations = [parse(f"acceleration of {c.name!r}", text) for c, text in
                         zip(declaration.coordinates, declaration.accelerations)]
        energies = [] if declaration.potential is None else [
            sum((vi * vi for vi in v), sp.S.Zero) / 2 + parse("potential",
                                                              declaration.potential)]
        mass = rhs = inverse = None

    printer = _Printer(sp, who)
    accel_lines = printer.block(accelerations, [f"acc_{s}" for s in q])
    energy_lines = printer.block(energies, ["energy_value"]) if energies else ()
    jacobian_lines = ()
    if jacobian:
        state = [*q, *v]
        if mass is None:
            entries = [sp.diff(a, z) for a in accelerations for z in state]
        else:
            entries = _jacobian(sp, mass, rhs, inverse, accelerations, state)
        jacobian_lines = printer.block(entries, [f"jac_{a}_{z}" for a in q for z in state])
    return DerivedSystem(accel_lines, energy_lines, jacobian_lines)


def _parse(sp, declaration: SystemDeclaration, names: dict, what: str, text: str):
    """``text`` as a SymPy expression, read from Python's syntax tree (never evaluated as
    Python): numbers, ``+ - * / **``, `FUNCTIONS`, ``pi`` and ``names``."""
    who = _who(declaration)
    accepted = ("accepted: numbers, + - * / ** and parentheses, the functions "
                f"{', '.join(FUNCTIONS)}, the constant pi, and the names "
                + ", ".join(names))
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as error:
        raise ValueError(f"{who}: the {what}, {text!r}, does not parse ({error.msg}); "
                         f"{accepted}") from None
    called = {id(node.func) for node in ast.walk(tree) if isinstance(node, ast.Call)}
    unknown = sorted({node.id for node in ast.walk(tree) if isinstance(node, ast.Name)
                      and id(node) not in called and node.id not in names
                      and node.id not in ("pi", *FUNCTIONS)})
    if unknown:
        raise ValueError(
            f"{who}: the {what}, {text!r}, names {', '.join(map(repr, unknown))}, which "
            "is neither a coordinate ("
            + ", ".join(c.symbol for c in declaration.coordinates) + "), a velocity ("
            + ", ".join(c.velocity_symbol for c in declaration.coordinates)
            + "), a parameter (" + (", ".join(p.symbol for p in declaration.parameters)
                                    or "none") + ") nor t; " + accepted)
    operators = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
                 ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
                 ast.Pow: lambda a, b: a ** b}

    def bad(node, why):
        return ValueError(f"{who}: the {what}, {text!r}, {why} "
                          f"({ast.unparse(node)!r}); {accepted}")

    def convert(node):
        if isinstance(node, ast.Expression):
            return convert(node.body)
        if isinstance(node, ast.BinOp):
            if type(node.op) not in operators:
                why = "uses ^ (write powers with **)" if isinstance(node.op, ast.BitXor) \
                    else "uses an operator that is not accepted"
                raise bad(node, why)
            return operators[type(node.op)](convert(node.left), convert(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            operand = convert(node.operand)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            if not math.isfinite(node.value):
                raise bad(node, "holds a number that is not finite")
            # a decimal literal as the exact rational it reads as (0.5 -> 1/2), so that
            # terms cancel exactly; printed back as the same float literal
            return sp.Rational(repr(node.value))
        if isinstance(node, ast.Name):
            if node.id in FUNCTIONS:
                raise bad(node, "uses a function without calling it")
            return sp.pi if node.id == "pi" else names[node.id]
        if isinstance(node, ast.Call):
            if (not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS
                    or len(node.args) != 1 or node.keywords):
                raise bad(node, "calls a function that is not accepted (or not with one "
                                "argument)")
            function = sp.Abs if node.func.id == "abs" else getattr(sp, node.func.id)
            return function(convert(node.args[0]))
        raise bad(node, "holds something that is not accepted")

    expr = convert(tree)
    if expr.has(sp.zoo, sp.nan, sp.oo, -sp.oo, sp.I):
        raise ValueError(f"{who}: the {what}, {text!r}, is {expr} (a division by zero or "
                         f"the root of a negative number); {accepted}")
    return expr


def _euler_lagrange(sp, lagrangian, forces, q, v, t):
    """Mass matrix M, right-hand side b and energy function E of a Lagrangian.

    The Lagrangian is split into ``L0 = L(v=0)`` (minus the potential) and the rest
    ``K = L - L0`` (the kinetic part). What comes from K is `_simplified` (a Lagrangian
    written in Cartesian terms has products of sums there); what comes from L0 is left
    as differentiation gives it, in the declaration's form: ``kappa/2*(th1 - th2)**2``
    gives ``kappa*(th1 - th2)``, a difference exact for close angles, where a simplified
    ``kappa*th1 - kappa*th2`` would lose digits to rounding. Likewise
    ``E = sum v_i dK/dv_i - K - L0`` keeps a potential written ``(1 - cos(th))``, which
    loses no digits near rest as its expansion would.
    """
    n = len(q)
    rest = lagrangian.xreplace({vi: sp.S.Zero for vi in v})
    kinetic = lagrangian - rest
    momenta = [sp.diff(kinetic, vi) for vi in v]
    mass = [[None] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            mass[i][j] = mass[j][i] = _simplified(sp, sp.diff(momenta[i], v[j]))
    rhs = []
    for i in range(n):
        moving = sp.diff(kinetic, q[i]) - sp.diff(momenta[i], t) - sum(
            (sp.diff(momenta[i], q[j]) * v[j] for j in range(n)), sp.S.Zero)
        rhs.append(_simplified(sp, moving) + sp.diff(rest, q[i]) + forces[i])
    moving = sum((vi * p for vi, p in zip(v, momenta)), sp.S.Zero) - kinetic
    return mass, rhs, _simplified(sp, moving) - rest


#: Largest expression (SymPy's count_ops) that `_simplified` tries to simplify:
#: ``trigsimp`` takes long on large ones.
_SIMPLIFY_OPS = 400


def _simplified(sp, expr):
    """A moderately simplified form of ``expr``: expanded, then ``trigsimp`` (which
    turns ``cos(a) cos(b) + sin(a) sin(b)`` into ``cos(a - b)``: a Lagrangian written in
    Cartesian terms gives a triple pendulum's accelerations in 120 operations instead of
    340), then ``factor_terms``; kept if it has fewer operations than ``expr`` (on a tie
    ``expr`` stays: ``kappa*(th1 - th2)`` keeps its difference, exact for close angles,
    where ``kappa*th1 - kappa*th2`` would lose digits to rounding).
    Expressions over `_SIMPLIFY_OPS` operations are left as they are."""
    before = sp.count_ops(expr)
    if before > _SIMPLIFY_OPS:
        return expr
    simpler = sp.factor_terms(sp.trigsimp(sp.expand(expr)))
    return simpler if sp.count_ops(simpler) < before else expr


def _check_mass(sp, declaration, mass, q, v, params, t) -> None:
    """Refuse a mass matrix with a zero row or a zero determinant (identically, or at a
    random point of the parameters' declared ranges), and a non-diagonal one of more
    than three coordinates."""
    who = _who(declaration)
    n = len(q)
    accepted = ("accepted: a Lagrangian whose mass matrix d2L/dv_i dv_j is invertible "
                "(a kinetic energy in every velocity, e.g. m*v**2/2)")
    for i, c in enumerate(declaration.coordinates):
        if all(_is_zero(sp, mass[i][j]) for j in range(n)):
            raise ValueError(
                f"{who}: the lagrangian has no kinetic term in {c.velocity_symbol} (its "
                f"second derivatives in {c.velocity_symbol} and every velocity are 0), so "
                f"the acceleration of {c.name!r} is not determined; {accepted}")
    diagonal = all(_is_zero(sp, mass[i][j]) for i in range(n) for j in range(n) if i != j)
    if not diagonal and n > _MOST_COUPLED:
        raise ValueError(
            f"{who}: the mass matrix of its {n} coordinates is not diagonal, and sweep "
            f"solves a non-diagonal mass matrix in closed form only for 2 or 3 "
            "coordinates; accepted: a Lagrangian whose kinetic energy couples at most 3 "
            "coordinates' velocities, or accelerations given directly")
    matrix = sp.Matrix(mass)
    if not diagonal and _is_zero(sp, matrix.det(method="berkowitz")):
        raise ValueError(f"{who}: the mass matrix {matrix.tolist()} is singular (its "
                         f"determinant is 0 for every state); {accepted}")
    point = _random_point(declaration, q, v, params, t)
    where = ", ".join(f"{s}={x:.6g}" for s, x in point.items())
    entries = [mass[i][i] for i in range(n)] if diagonal else [e for row in mass for e in row]
    values = [complex(e.evalf(subs=point)) for e in entries]
    if not all(math.isfinite(x.real) and x.imag == 0 for x in values):
        raise ValueError(f"{who}: the mass matrix {matrix.tolist()} is not finite and real "
                         f"at {where}; {accepted}")
    numeric = [x.real for x in values]
    if diagonal:  # only the diagonal: its entries must not vanish
        value, bound = math.prod(numeric), math.prod(map(abs, numeric))
    else:
        rows = [numeric[i * n:(i + 1) * n] for i in range(n)]
        value = float(sp.Matrix(rows).det())
        bound = math.prod(math.sqrt(sum(x * x for x in row)) for row in rows)
    # Hadamard's inequality: |det| <= the product of the rows' lengths; a determinant
    # below 1e-10 of that bound at a random point is zero but for rounding
    if not abs(value) > 1e-10 * bound:
        raise ValueError(f"{who}: the mass matrix {matrix.tolist()} is singular at "
                         f"{where} (determinant {value:.3g}); {accepted}")


def _is_zero(sp, expr) -> bool:
    return expr == 0 or sp.simplify(expr) == 0


def _random_point(declaration, q, v, params, t) -> dict:
    """A state, a time and parameter values within their declared lower bounds, drawn
    from a generator seeded by the declaration (so the check is reproducible)."""
    draw = random.Random(hashlib.sha256(repr(declaration).encode()).digest())
    point = {}
    for symbol, p in zip(params, declaration.parameters):
        typical = p.default if p.default is not None and p.default != 0 else 1.0
        value = abs(typical) * draw.uniform(0.5, 2.0)
        if p.minimum is not None and not value > p.minimum:
            value = p.minimum + abs(p.minimum) * draw.uniform(0.1, 1.0) + draw.uniform(0.1, 1)
        point[symbol] = value
    for symbol in q:
        point[symbol] = draw.uniform(-math.pi, math.pi)
    for symbol in v:
        point[symbol] = draw.uniform(-2.0, 2.0)
    point[t] = draw.uniform(0.0, 10.0)
    return point


def _solve(sp, mass, rhs):
    """``M a = b`` in closed form: the accelerations and the inverse of M (a matrix of
    expressions), with ``1/det`` one shared subexpression (Cramer's rule: the adjugate
    times the inverse determinant, the determinant expanded along the first row and
    factored)."""
    n = len(mass)
    if all(mass[i][j] == 0 for i in range(n) for j in range(n) if i != j):
        inverse = [[1 / mass[i][i] if i == j else sp.S.Zero for j in range(n)]
                   for i in range(n)]
        return [rhs[i] / mass[i][i] for i in range(n)], inverse
    matrix = sp.Matrix(mass)
    adjugate = matrix.adjugate()
    det = sp.factor(sum((matrix[0, j] * adjugate[j, 0] for j in range(n)), sp.S.Zero))
    scale = sp.Pow(det, -1)
    accelerations = [sp.Mul(sum((adjugate[i, j] * rhs[j] for j in range(n)), sp.S.Zero),
                            scale) for i in range(n)]
    inverse = [[sp.Mul(adjugate[i, j], scale) for j in range(n)] for i in range(n)]
    return accelerations, inverse


def _jacobian(sp, mass, rhs, inverse, accelerations, state):
    """``d a_i / d z`` for every coordinate i and state variable z, as
    ``M^-1 (db/dz - (dM/dz) a)`` with the accelerations a substituted (only M's entries
    that depend on some state variable are differentiated: n^2 of them for a diagonal
    mass matrix of n coordinates would cost n^3 derivatives)."""
    n = len(mass)
    free = set(state)
    moving = [(j, k) for j in range(n) for k in range(n) if mass[j][k].free_symbols & free]
    entries = []
    columns = {}
    for z in state:
        column = [sp.diff(rhs[j], z) for j in range(n)]
        for j, k in moving:
            column[j] -= sp.diff(mass[j][k], z) * accelerations[k]
        columns[z] = [_unsigned(sp, entry) for entry in column]
    for i in range(n):
        for z in state:
            entries.append(sum((inverse[i][j] * columns[z][j] for j in range(n)
                                if inverse[i][j] != 0), sp.S.Zero))
    return entries


def _unsigned(sp, expr):
    """``expr`` with every product ``x * sign(x)`` written ``abs(x)`` (equal for every
    real x, 0 included): the derivative of a drag ``-k*v*abs(v)`` is
    ``-k*abs(v) - k*v*sign(v)``, which the kernels then evaluate without a sign."""
    if not expr.has(sp.sign):
        return expr

    def paired(e):
        return e.is_Mul and any(isinstance(f, sp.sign) and f.args[0] in e.args
                                for f in e.args)

    def unsign(e):
        factors = list(e.args)
        for f in list(factors):
            if isinstance(f, sp.sign) and f.args[0] in factors:
                factors.remove(f)
                factors.remove(f.args[0])
                factors.append(sp.Abs(f.args[0]))
        return sp.Mul(*factors)

    return sp.expand(expr).replace(paired, unsign)


# ---------------------------------------------------------------- printing
class _Printer:
    """Kernel source of SymPy expressions (the module docstring's conventions)."""

    ADD, MUL, ATOM = 1, 2, 3

    def __init__(self, sp, who: str):
        self.sp, self.who = sp, who

    def block(self, exprs: list, targets: list[str]) -> tuple[str, ...]:
        """Statements computing ``exprs`` into ``targets``: sincos pairs, then the
        common subexpressions ``x<k>``, then the targets in order."""
        sp = self.sp
        pairs, replaced = self._sincos(exprs)
        temporaries, reduced = sp.cse(replaced, symbols=sp.numbered_symbols("x"),
                                      order="canonical")
        lines = [f"{s}, {c} = vsincos({self(u)})" for u, s, c in pairs]
        lines += [f"{name} = {self(expr)}" for name, expr in temporaries]
        lines += [f"{target} = {self(expr)}" for target, expr in zip(targets, reduced)]
        return tuple(lines)

    def _sincos(self, exprs):
        """Replace sin(u) and cos(u), where both occur, by symbols ``s_<k>, c_<k>``."""
        sp = self.sp
        calls = set().union(*(sp.sympify(e).atoms(sp.sin, sp.cos) for e in exprs))
        sines = {f.args[0] for f in calls if isinstance(f, sp.sin)}
        cosines = {f.args[0] for f in calls if isinstance(f, sp.cos)}
        pairs, mapping = [], {}
        for k, u in enumerate(sorted(sines & cosines, key=sp.default_sort_key)):
            s, c = sp.Symbol(f"s_{k}", real=True), sp.Symbol(f"c_{k}", real=True)
            pairs.append((u, s.name, c.name))
            mapping[sp.sin(u)], mapping[sp.cos(u)] = s, c
        return pairs, [sp.sympify(e).xreplace(mapping) for e in exprs]

    def __call__(self, expr) -> str:
        return self._print(expr)[0]

    def _print(self, e) -> tuple[str, int]:
        sp = self.sp
        if e.is_Symbol:
            return e.name, self.ATOM
        if e.is_Number or e.is_NumberSymbol:
            if not e.is_real or not e.is_finite:
                raise ValueError(f"{self.who}: the derived equations hold {e} (a division "
                                 "by zero in the declaration?); accepted: expressions "
                                 "finite for some state")
            value = float(e)
            return (repr(value), self.ATOM) if value >= 0 else (repr(value), self.ADD)
        if e.is_Add:
            text = ""
            for k, term in enumerate(e.args):
                negative, body = self._signed(term)
                if k == 0:
                    text = ("-" + body) if negative else body
                else:
                    text += (" - " if negative else " + ") + body
            return text, self.ADD
        if e.is_Mul:
            negative, body = self._signed(e)
            return ("-" + body, self.ADD) if negative else (body, self.MUL)
        if e.is_Pow:
            return self._power(e)
        if isinstance(e, sp.sin):
            return f"vsin({self(e.args[0])})", self.ATOM
        if isinstance(e, sp.cos):
            return f"vcos({self(e.args[0])})", self.ATOM
        if isinstance(e, sp.Abs):
            return f"abs({self(e.args[0])})", self.ATOM
        raise ValueError(f"{self.who}: the derived equations hold {e}, which the kernels "
                         f"cannot evaluate; accepted: {', '.join(FUNCTIONS)}, integer and "
                         "half-integer powers")

    def _signed(self, e) -> tuple[bool, str]:
        """(negative, the text of ``|e|`` at product level) of a term."""
        coeff, factors = e.as_coeff_mul()
        negative = coeff < 0
        coeff = -coeff if negative else coeff
        numerator, denominator = [], []
        for f in factors:
            if f.is_Pow and f.exp.is_Number and f.exp < 0:
                denominator.append(f.base if f.exp == -1 else self.sp.Pow(f.base, -f.exp))
            else:
                numerator.append(f)
        parts = [] if coeff == 1 and numerator else [self._print(coeff)[0]]
        parts += [self._wrap(f, self.MUL) for f in numerator]
        text = "*".join(parts)
        if denominator:
            below = "*".join(self._wrap(f, self.MUL) for f in denominator)
            single = len(denominator) == 1 and self._print(denominator[0])[1] == self.ATOM
            text += "/" + (below if single else f"({below})")
        return negative, text

    def _wrap(self, e, level: int) -> str:
        text, precedence = self._print(e)
        return text if precedence >= level else f"({text})"

    def _power(self, e) -> tuple[str, int]:
        base, exp = e.base, e.exp
        if not (exp.is_Integer or (exp.is_Rational and exp.q == 2)):
            raise ValueError(f"{self.who}: the derived equations hold the power {e}, "
                             "which the kernels cannot evaluate; accepted: integer and "
                             "half-integer powers (** n, sqrt)")
        if exp < 0:
            return "1.0/" + self._wrap(self.sp.Pow(base, -exp), self.ATOM), self.MUL
        whole = int(exp) if exp.is_Integer else int(exp - self.sp.Rational(1, 2))
        parts = [self._wrap(base, self.ATOM)] * whole
        if not exp.is_Integer:
            parts.append(f"math.sqrt({self(base)})")
        if len(parts) == 1:
            return parts[0], self.ATOM if not exp.is_Integer else self._print(base)[1]
        return "*".join(parts), self.MUL
