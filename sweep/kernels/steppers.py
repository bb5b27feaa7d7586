"""One step of a method, from its data: an explicit Runge-Kutta step from its Butcher
tableau, a kick-drift sequence from a splitting method's coefficients.

RK4 included: the generated code performs exactly the operations of the classical
hand-written step, ``th + (dt/6) * (k1 + 2 k2 + 2 k3 + k4)`` etc., with each
``base + factor * sum`` a fused multiply-add written explicitly (``vfma``: LLVM is
allowed to fuse nothing itself, so the bits cannot depend on the code around the step),
so there is no separate fast path.
"""

from __future__ import annotations

from fractions import Fraction
from math import lcm

from .spec import KernelSpec, check_method_fits, tangent
from .terms import accel_call, drive_nodes, float_literal

__all__ = ["STEPPERS", "TANGENT", "at_node", "combination", "explicit_stepper", "fused",
           "rk_stages", "symplectic_stepper"]

#: Lane variables of the tangent dynamics (``spec`` observing ``lyapunov``): two
#: tangent vectors (theta and theta' components), integrated beside the state.
TANGENT = ("ly_u1", "ly_v1", "ly_u2", "ly_v2")


def at_node(drives: dict, c) -> dict[str, str]:
    """``{effect name: variable}`` of every drive's value at node ``c``."""
    return {name: nodes[c] for name, nodes in drives.items() if c in nodes}


# Rows whose exact (Fraction) coefficients share a denominator up to this size are
# written as (dt / D) * (n1 k1 + n2 k2 + ...), with small integers n: for RK4 that is
# exactly the classical hand-written step, operation for operation.
_MAX_COMMON_DENOMINATOR = 1000


def _sum(parts: list[tuple[str | None, str]]) -> str:
    """Source of the sum of ``parts`` (``(coefficient, name)``, the coefficient a signed
    float literal, or None for +1, or "-" for -1), left to right, each term with a
    coefficient fused onto the sum so far: ``vfma(c3, x3, vfma(c2, x2, c1 * x1))``.

    One rounding per term, as LLVM's contraction used to give (it is written out
    because the kernels let LLVM fuse nothing, `sweep._config.FASTMATH`); where the
    products are exact (RK4's ``2.0 * k2``) the result is the same as unfused.
    """
    coefficient, name = parts[0]
    text = name if coefficient is None else \
        f"-{name}" if coefficient == "-" else f"{coefficient} * {name}"
    for coefficient, name in parts[1:]:
        if coefficient is None:
            text = f"{text} + {name}"
        elif coefficient == "-":
            text = f"{text} - {name}"
        else:
            text = f"vfma({coefficient}, {name}, {text})"
    return text if len(parts) == 1 else f"({text})"


def _factored(coeffs, names, scale: str, constants: dict[str, str] | None):
    """``(factor, sum)`` with ``factor * sum`` = ``scale * sum(coeffs[j] * names[j])``
    over the non-zero coefficients, or None when they are all zero (see
    `combination`)."""
    terms = [(x, name) for x, name in zip(coeffs, names) if x != 0]
    if not terms:
        return None
    exact = all(isinstance(x, Fraction) for x, _ in terms)
    if constants is not None and exact:
        denominator = lcm(*(x.denominator for x, _ in terms))
        if denominator <= _MAX_COMMON_DENOMINATOR:
            if denominator == 1:
                factor = scale
            else:
                factor = f"{scale}_{denominator}"
                constants[factor] = f"{factor} = {scale} / {float(denominator)!r}"
            parts = []
            for x, name in terms:
                n = int(x * denominator)
                parts.append((None if n == 1 else "-" if n == -1 else repr(float(n)), name))
            return factor, _sum(parts)
    text = _sum([(float_literal(x), name) for x, name in terms])
    return scale, text if len(terms) > 1 else f"({text})"  # one term: scale * (c * x)


def combination(coeffs, names, scale: str, constants: dict[str, str] | None):
    """Source of ``scale * sum(coeffs[j] * names[j])`` over the non-zero coefficients,
    or None when they are all zero.

    With ``constants`` (a dict filled with preamble lines), exact rows with a small
    common denominator D become ``dt_D * (n1 * x1 + ...)`` with ``dt_D = dt / D``
    computed once per kernel call; otherwise ``scale * (c1 * x1 + ...)`` with the
    coefficients as float literals.
    """
    parts = _factored(coeffs, names, scale, constants)
    return None if parts is None else f"{parts[0]} * {parts[1]}"


def fused(base: str, coeffs, names, scale: str, constants: dict[str, str] | None) -> str:
    """Source of ``base + scale * sum(coeffs[j] * names[j])`` (see `combination`) with
    the last multiply-add fused: ``vfma(factor, sum, base)``, one rounding, written
    explicitly (the kernels let LLVM fuse nothing itself: `sweep._config.FASTMATH`);
    ``base`` alone when every coefficient is zero."""
    parts = _factored(coeffs, names, scale, constants)
    return base if parts is None else f"vfma({parts[0]}, {parts[1]}, {base})"


def rk_stages(spec: KernelSpec, tableau, scale: str, constants, drives: dict) -> list[str]:
    """Stage lines k_it, k_io (k_it = omega at stage i, since theta' = omega).

    With tangent dynamics (`sweep.kernels.spec.tangent`), every stage also gives the
    Jacobian entries ``j_it = d theta''/d theta``, ``j_io = d theta''/d theta'`` at the
    stage state, and the stages ``q_iu<m>, q_iv<m>`` of each tangent vector m (the same
    tableau applied to the variational equations ``u' = v, v' = j_t u + j_o v``: for an
    explicit Runge-Kutta method that is exactly the derivative of its step map, so the
    exponents measured are those of the map the kernel iterates).
    """
    lines = []
    with_tangent = tangent(spec)
    for i in range(tableau.stages):
        row = tableau.a[i][:i]
        kt = [f"k{j + 1}t" for j in range(i)]
        ko = [f"k{j + 1}o" for j in range(i)]
        lines.append(f"k{i + 1}t = " + fused("om", row, ko, scale, constants))
        th_stage = fused("th", row, kt, scale, constants)
        if not with_tangent:
            lines.append(f"k{i + 1}o = " + accel_call(
                spec, th_stage, f"k{i + 1}t", at_node(drives, tableau.c[i])))
            continue
        lines.append(f"k{i + 1}o, j{i + 1}t, j{i + 1}o = " + accel_call(
            spec, th_stage, f"k{i + 1}t", at_node(drives, tableau.c[i]), jacobian=True))
        for m in (1, 2):
            u = fused(f"ly_u{m}", row, [f"q{j + 1}u{m}" for j in range(i)], scale, constants)
            v = fused(f"ly_v{m}", row, [f"q{j + 1}v{m}" for j in range(i)], scale, constants)
            lines.append(f"q{i + 1}u{m} = {v}")
            lines.append(f"q{i + 1}v{m} = vfma(j{i + 1}t, {u}, j{i + 1}o * q{i + 1}u{m})")
    return lines


def explicit_stepper(spec: KernelSpec, tableau) -> dict[str, list]:
    """One fixed step of an explicit Runge-Kutta method, from its tableau.

    Returns the parts `sweep.kernels.fixed` assembles: ``preamble`` (constants, once
    per call), ``drive_init`` and ``drive_step`` ((effect, variable, time) triples
    evaluated before the first step and at the start of every step), ``drive_carry``
    ((destination, source) pairs copied at the end of every step), ``before`` (lane
    lines before the first step), ``step`` (lane lines of one step) and ``carried``
    (lane variables that live from one step to the next besides th, om).
    """
    constants: dict[str, str] = {}
    c = tableau.c
    drives, nodes = drive_nodes(spec, c, time="", step="step", scale="dt",
                                constants=constants)
    init, pairs = [], []
    if 0 in c and 1 in c:  # a drive's value at t_{n+1} is the next step's value at t_n
        for effect in spec.drives:
            first = drives[effect.name][Fraction(0)]
            nodes = [node for node in nodes if node[1] != first]  # from the last step
            init.append((effect, first, "t0"))
            pairs.append((first, drives[effect.name][Fraction(1)]))
    step = rk_stages(spec, tableau, "dt", constants, drives)
    kt = [f"k{j + 1}t" for j in range(tableau.stages)]
    ko = [f"k{j + 1}o" for j in range(tableau.stages)]
    step.append(f"th = {fused('th', tableau.b, kt, 'dt', constants)}")
    step.append(f"om = {fused('om', tableau.b, ko, 'dt', constants)}")
    if tangent(spec):
        for m in (1, 2):
            for x, q in (("u", "u"), ("v", "v")):
                names = [f"q{j + 1}{q}{m}" for j in range(tableau.stages)]
                step.append(f"ly_{x}{m} = {fused(f'ly_{x}{m}', tableau.b, names, 'dt', constants)}")
    return {"preamble": list(constants.values()), "drive_init": init,
            "drive_step": nodes, "drive_carry": pairs, "before": [], "step": step,
            "carried": list(TANGENT) if tangent(spec) else []}


def symplectic_stepper(spec: KernelSpec, method) -> dict[str, list[str]]:
    """One kick-drift step; the force is re-evaluated only after a drift moved theta."""
    check_method_fits(method, spec.effects, where="the kernel spec")  # a guard
    constants, step, stale = {}, [], False
    force = f"acc = {accel_call(spec, 'th', 'om', {})}"

    def scaled(kind, x):
        if x == 1:
            return "dt"
        line = f"dt * {float_literal(x)}"
        for name, known in constants.items():
            if known.endswith(f" = {line}"):
                return name
        name = f"{kind}{len(constants)}"
        constants[name] = f"{name} = {line}"
        return name

    for kick, drift in zip(method.kick, method.drift):
        if kick != 0:
            if stale:
                step.append(force)
                stale = False
            step.append(f"om = vfma({scaled('kick', kick)}, acc, om)")
        if drift != 0:
            step.append(f"th = vfma({scaled('drift', drift)}, om, th)")
            stale = True
    if stale:
        step.append(force)
    return {"preamble": list(constants.values()), "drive_init": [], "drive_step": [],
            "drive_carry": [], "before": [force], "step": step, "carried": ["acc"]}


#: How each kind of fixed-step method becomes kernel source (keyed by ``method.kind``).
STEPPERS = {"explicit": explicit_stepper, "symplectic": symplectic_stepper}
