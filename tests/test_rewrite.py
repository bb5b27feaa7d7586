"""The systems' derived source rewritten for the lanes (`sweep.kernels.rewrite`):
parameter-only subexpressions hoisted out of the step, products regrouped, sums of
products fused; the same values to rounding, and none of the step's work left that
depends on the parameters alone."""

from __future__ import annotations

import ast

import numpy as np
import pytest

pytest.importorskip("sympy")

import sweep
from sweep.engine_systems import prepare_system
from sweep.kernels.rewrite import rewrite
from sweep.kernels.source import source
from sweep.physics.derive import derive
from sweep.physics.systems import coupled_pendula, double_pendulum

from test_systems_derive import run_lines, sample

DECLARATIONS = [double_pendulum(damping=True), coupled_pendula(3, "spring", "ring", True),
                coupled_pendula(2, "torsion", "chain")]


def run(lines, values):
    """Execute lines with NumPy standing in for the kernel functions (``vfma`` as a
    product and a sum, rounded twice); the namespace after them."""
    return run_lines(lines, dict(values, vfma=lambda a, b, c: a * b + c))


@pytest.mark.parametrize("declaration", DECLARATIONS, ids=lambda d: d.name)
def test_rewritten_lines_compute_what_the_lines_compute(declaration):
    """Accelerations and Jacobian (one block after the other, as the kernel runs them)
    from the hoisted statements and the rewritten lines equal the derived lines' at
    random states and parameters, to rounding: the rewrite reassociates products and
    fuses sums, a few ulps of each of a few dozen terms, so 1e-13 of the largest
    output bounds it."""
    derived = derive(declaration, jacobian=True)
    lines = derived.accel_lines + derived.jacobian_lines
    parameters = [p.symbol for p in declaration.parameters]
    coords = [c.symbol for c in declaration.coordinates]
    state = coords + [c.velocity_symbol for c in declaration.coordinates]
    outputs = [f"acc_{a}" for a in coords] + [f"jac_{a}_{z}" for a in coords for z in state]
    fast = rewrite(lines, parameters, outputs)
    values = sample(declaration)
    expected = run(lines, values)
    hoisted = run(fast.hoisted, {k: values[k] for k in parameters})
    got = run(fast.lines, {**values, **{x: hoisted[x] for x in fast.names}})
    for name in outputs:
        want = np.broadcast_to(expected[name], values["t"].shape)
        scale = max(1.0, float(np.max(np.abs(want))))
        assert np.allclose(got[name], want, rtol=0, atol=1e-13 * scale), name


def test_hoisted_statements_read_parameters_only_and_names_do_not_clash():
    """A temporary hoisted, then reassigned with a varying value in a later block:
    the later reads get the varying one; new names are past every x<k> used."""
    lines = ["x0 = a*b", "y0 = x0*th + 2.0*a*th*b", "x0 = th*th", "x3 = x0*a*b",
             "y1 = x3 - a*b*om"]
    fast = rewrite(lines, ["a", "b"])
    for line in fast.hoisted:
        names = {n.id for n in ast.walk(ast.parse(line).body[0].value)
                 if isinstance(n, ast.Name)}
        assert names <= {"a", "b"} | set(fast.names), line
    assert all(int(x[1:]) > 3 for x in fast.names)
    values = {"a": 1.5, "b": -0.7, "th": 0.3, "om": 2.0}
    want = run(lines, values)
    hoisted = run(fast.hoisted, {"a": 1.5, "b": -0.7})
    got = run(fast.lines, {**values, **{x: hoisted[x] for x in fast.names}})
    for name in ("y0", "y1"):
        assert got[name] == pytest.approx(want[name], rel=1e-15, abs=1e-15)


def step_physics(system, **options):
    """The generated source's physics function for the step (accel or accel_jac) as
    a syntax tree, and the kernel's parameter symbols."""
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 64), theta2_0=[0.5])
    spec = prepare_system(system, grid, t_end=1.0, dt=0.01, **options)[1]
    tree = ast.parse(source(spec))
    name = "accel_jac" if "lyapunov" in spec.observe else "accel"
    (function,) = [f for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == name]
    parameters = {p.symbol for p in spec.system.parameters} | (
        {"damping_c"} if spec.damping else set())
    return function, parameters


@pytest.mark.parametrize("options", [{"observe": ("final",)}, {"observe": ("lyapunov",)}],
                         ids=["accel", "accel_jac"])
def test_the_step_computes_nothing_of_the_parameters_alone(options):
    """In the double pendulum's step (damped: the damping rate is a parameter too),
    no operation reads only parameters, constants and hoisted values: they are
    computed once per trajectory (before: l2*m2, l1*l1, m1 + m2, ... at every stage)."""
    system = sweep.DoublePendulum(effects=(sweep.Damping(0.1),))
    function, parameters = step_physics(system, **options)
    hoisted = {s.targets[0].id for s in function.body
               if isinstance(s, ast.Assign) and isinstance(s.value, ast.Subscript)}
    assert hoisted  # the function reads hoisted values
    fixed = parameters | hoisted
    for statement in function.body:
        if not isinstance(statement, ast.Assign) or isinstance(statement.value, ast.Subscript):
            continue
        for node in ast.walk(statement.value):
            if isinstance(node, (ast.BinOp, ast.UnaryOp, ast.Call)):
                names = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
                called = {n.func.id for n in ast.walk(node) if isinstance(n, ast.Call)}
                leaves = names - called
                negated_literal = isinstance(node, ast.UnaryOp) and isinstance(
                    node.operand, ast.Constant)
                assert negated_literal or not leaves <= fixed, ast.unparse(statement)


def test_sums_of_products_are_fused():
    """The double pendulum's accelerations use fused multiply-adds: its derived lines
    have none (SymPy prints a*b + c), the step's physics at least one per
    acceleration and one in the determinant."""
    function, _ = step_physics(sweep.DoublePendulum(), observe=("final",))
    calls = [n.func.id for n in ast.walk(function) if isinstance(n, ast.Call)]
    assert calls.count("vfma") >= 3
    assert "vfma" not in "".join(derive(double_pendulum()).accel_lines)


@pytest.mark.parametrize("case", [
    (sweep.DoublePendulum(effects=(sweep.Damping(0.2),)), ("final", "energy", "lyapunov")),
    (sweep.CoupledPendula(2, coupling=2.0, kind="torsion"), ("final", "lyapunov")),
    (sweep.CoupledPendula(3, coupling=2.0, kind="spring", topology="ring"), ("final",)),
], ids=["double_damped", "torsion_chain", "spring_ring"])
def test_kernels_with_and_without_the_rewrite_agree(case, monkeypatch):
    """`sweep.run` with the rewrite and with the derived lines as they are (the kernels
    before it): the same results to rounding after 100 steps. The rewrite changes each
    acceleration by a few ulps; the double pendulum's chaos grows such differences to
    ~1e-13 over 100 steps from these starts (measured), so 1e-10 leaves room, while a
    wrongly hoisted or stale value changes the states by far more. (The torsion
    chain's Jacobian has entries of the parameters alone: returned by name.)"""
    from sweep.kernels import build
    from sweep.kernels import system as kernel_system
    from sweep.kernels.rewrite import Rewritten

    system, observe = case
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 24), theta2_0=[-1.0, 0.5, 2.0])
    kw = dict(t_end=1.0, dt=0.01, observe=observe, progress=False)
    fast = sweep.run(system, grid, **kw)
    build.cache_clear()
    monkeypatch.setattr(kernel_system, "rewrite",
                        lambda lines, parameters, outputs=(): Rewritten((), tuple(lines), ()))
    try:
        plain = sweep.run(system, grid, **kw)
    finally:
        build.cache_clear()
    for name in fast.data_vars:
        if name == "status":
            assert (fast.status == plain.status).all()
            continue
        assert np.allclose(fast[name], plain[name], rtol=0, atol=1e-10), name
