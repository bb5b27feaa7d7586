"""A system's derived source (`sweep.physics.system.DerivedSystem` lines) rewritten for
the lanes of `sweep.kernels.system`: what depends on the parameters alone is computed
once per trajectory instead of at every stage, and ``a*b + c`` is one fused
multiply-add.

Three rewrites of each statement's expression, on Python's syntax tree:

1. **products regrouped**: a chain of multiplications ``a*b*c*...`` is evaluated with
   its factors that depend on the parameters alone first, as one sub-product
   (``x3*x5*m2`` becomes ``(x3*m2)*x5``), and a minus sign of a varying factor moves
   to that sub-product (``-x1*x3*c`` becomes ``(-x3)*x1*c``);
2. **fused**: ``u + a*b``, ``a*b + u``, ``u - a*b`` and ``a*b - u`` become
   ``vfma(a, b, u)``, ``vfma(a, b, u)``, ``vfma(-a, b, u)`` and ``vfma(a, b, -u)``
   (one rounding instead of two; the last factor of a regrouped chain is ``b``, and
   a minus sign goes on the first factor of ``a``);
3. **hoisted**: every largest subexpression of parameters and constants alone (and a
   statement whose whole value is one) becomes a new temporary ``x<k>``, numbered
   past every ``x<k>`` the lines use (a name no declaration may take), assigned once
   per trajectory before the time loop.

Products are reassociated and sums fused, so the results differ from the lines'
literal evaluation by rounding (a few ulps of each term); every lane evaluates the
same operations, so the results still do not depend on blocks, chunks or threads.
Only the accelerations (and the Jacobian beside them) are rewritten: they run at
every stage; the energy is read once or twice per trajectory and keeps its form.
Measured on the double pendulum (2 cores of an AMD EPYC Zen 5, 2**17 trajectories):
`benchmarks/double_pendulum.py`.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass

__all__ = ["Rewritten", "rewrite"]

_TEMPORARY = re.compile(r"\bx(\d+)\b")
#: Calls whose value depends on their arguments alone (may be hoisted with them).
_PURE = {"vsin", "vcos", "vsincos", "math.sqrt"}


@dataclass(frozen=True)
class Rewritten:
    """Derived lines split for the lanes.

    Attributes
    ----------
    hoisted : tuple of str
        Statements of the parameters alone, in order: once per trajectory.
    lines : tuple of str
        The rest, rewritten: at every evaluation.
    names : tuple of str
        The temporaries ``hoisted`` assigns that ``lines`` read (the extra arguments
        of the function that runs ``lines``).
    """

    hoisted: tuple[str, ...]
    lines: tuple[str, ...]
    names: tuple[str, ...]


def rewrite(lines, parameters, outputs=()) -> Rewritten:
    """Rewrite derived ``lines`` (statements, as `DerivedSystem` holds them; blocks may
    follow one another and reuse their temporaries' names) given the names of the
    ``parameters`` (the values that do not change along a trajectory); the names in
    ``outputs`` stay assigned by the lines (``acc_th1 = x12`` where the value is hoisted)."""
    lines = list(lines)
    outputs = set(outputs)
    numbers = [int(k) for line in lines for k in _TEMPORARY.findall(line)]
    state = _State(set(parameters), max(numbers, default=-1) + 1)
    body = []
    for line in lines:
        (statement,) = ast.parse(line).body
        value = _fuse(_regroup(state.rename(statement.value), state), state)
        targets = [n.id for n in ast.walk(statement.targets[0]) if isinstance(n, ast.Name)]
        if state.invariant(value) and not outputs & set(targets):
            fresh = [state.fresh() for _ in targets]
            state.hoisted.append(f"{', '.join(fresh)} = {ast.unparse(value)}")
            state.renamed.update(zip(targets, fresh))
            continue
        value = state.hoist(value)
        for name in targets:  # a varying value now: no longer the hoisted one
            state.renamed.pop(name, None)
        body.append(f"{ast.unparse(statement.targets[0])} = {ast.unparse(value)}")
    text = "\n".join(body)
    used = [name for name in state.names if re.search(rf"\b{name}\b", text)]
    return Rewritten(tuple(state.hoisted), tuple(body), tuple(used))


class _State:
    """The rewrite's bookkeeping: which names are invariant, the hoisted statements,
    the renaming of hoisted temporaries, the next free ``x<k>``."""

    def __init__(self, parameters: set[str], first: int) -> None:
        self.parameters = parameters
        self.next = first
        self.hoisted: list[str] = []
        self.names: list[str] = []
        self.renamed: dict[str, str] = {}
        self.seen: dict[str, str] = {}  # a hoisted expression's text -> its name

    def fresh(self) -> str:
        name = f"x{self.next}"
        self.next += 1
        self.names.append(name)
        return name

    def rename(self, node):
        """``node`` with the names of hoisted temporaries replaced by their new ones."""
        renamed = self.renamed

        class Rename(ast.NodeTransformer):
            def visit_Name(self, name):
                return ast.Name(renamed.get(name.id, name.id), ast.Load())

        return Rename().visit(node)

    def invariant(self, node) -> bool:
        """Whether ``node`` reads parameters, hoisted temporaries and constants only
        (and calls nothing but `_PURE`)."""
        if isinstance(node, ast.Constant):
            return True
        if isinstance(node, ast.Name):
            return node.id in self.parameters or node.id in self.names
        if isinstance(node, ast.Call):
            return ast.unparse(node.func) in _PURE and all(map(self.invariant, node.args))
        if isinstance(node, ast.BinOp):
            return self.invariant(node.left) and self.invariant(node.right)
        if isinstance(node, ast.UnaryOp):
            return self.invariant(node.operand)
        return False

    def hoist(self, node):
        """``node`` with each largest invariant subexpression (other than a name or a
        constant) replaced by a hoisted temporary."""
        if isinstance(node, (ast.Name, ast.Constant)) or _literal(node):
            return node
        if self.invariant(node):
            text = ast.unparse(node)
            if text not in self.seen:
                self.seen[text] = name = self.fresh()
                self.hoisted.append(f"{name} = {text}")
            return ast.Name(self.seen[text], ast.Load())
        return _map_children(node, self.hoist)


def _map_children(node, fn):
    """``node`` with each child expression replaced by ``fn(child)``."""
    for field, value in ast.iter_fields(node):
        if isinstance(value, ast.AST) and not isinstance(value, (ast.operator, ast.unaryop,
                                                                 ast.expr_context)):
            setattr(node, field, fn(value))
        elif isinstance(value, list):
            setattr(node, field, [fn(v) for v in value])
    return node


def _literal(node) -> bool:
    """A number, or a negated one."""
    return isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) and \
        isinstance(node.operand, ast.Constant)


def _negated(node):
    """``-node``, the sign put on a product's first factor (a regrouped product's
    parameters: hoisted with them), a double negation undone."""
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return ast.BinOp(_negated(node.left), ast.Mult(), node.right)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return node.operand
    return ast.UnaryOp(ast.USub(), node)


def _factors(node) -> list:
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
        return _factors(node.left) + _factors(node.right)
    return [node]


def _product(factors):
    node = factors[0]
    for factor in factors[1:]:
        node = ast.BinOp(node, ast.Mult(), factor)
    return node


def _regroup(node, state: _State):
    """Rewrite 1 on ``node`` and everything below it."""
    _map_children(node, lambda child: _regroup(child, state))
    if not (isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult)):
        return node
    fixed, varying, negative = [], [], False
    for factor in _factors(node):
        if state.invariant(factor):
            fixed.append(factor)
        elif isinstance(factor, ast.UnaryOp) and isinstance(factor.op, ast.USub):
            varying.append(factor.operand)
            negative = not negative
        else:
            varying.append(factor)
    if not fixed or not varying:
        return node  # nothing to regroup
    group = _product(fixed)
    if negative:
        group = _negated(group)
    return _product([group, *varying])


def _fuse(node, state: _State):
    """Rewrite 2 on ``node`` and everything below it."""
    _map_children(node, lambda child: _fuse(child, state))
    if not (isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub))) \
            or state.invariant(node):
        return node
    left, right = node.left, node.right
    add = isinstance(node.op, ast.Add)

    def product(x):
        return isinstance(x, ast.BinOp) and isinstance(x.op, ast.Mult)

    if product(right):
        a, b, c = right.left, right.right, left
        if not add:
            a = _negated(a)
    elif product(left):
        a, b, c = left.left, left.right, right if add else _negated(right)
    else:
        return node
    return ast.Call(ast.Name("vfma", ast.Load()), [a, b, c], [])
