"""Systems of more than one coordinate: the built-in declarations (`sweep.physics.systems`)
and their derivation into kernel source (`sweep.physics.derive`), each output against an
oracle written out here: the double pendulum's textbook accelerations, energies written
by hand in Cartesian terms, normal-mode frequencies from the linearised equations,
SymPy's own ``euler_equations`` solved numerically, and central finite differences.

The derived lines are executed as Python with NumPy's sine and cosine standing in for
the kernels' ``vsin``/``vcos``/``vsincos`` (and once compiled by numba); every
declaration is derived into a private cache folder, so no test reads what an older
version stored.
"""

import ast
import dataclasses
import json
import math
import os
import subprocess
import sys
import types

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import sweep.physics.derive as D  # noqa: E402  (after the importorskip)
from sweep.physics.derive import derive  # noqa: E402
from sweep.physics.effect import EFFECTS, RESERVED_SYMBOLS, Parameter  # noqa: E402
from sweep.physics.system import Coordinate, SystemDeclaration  # noqa: E402
from sweep.physics.systems import coupled_pendula, double_pendulum  # noqa: E402

KERNEL_CALLS = {"vsin", "vcos", "vsincos", "vfma"}


@pytest.fixture(autouse=True, scope="module")
def private_cache(tmp_path_factory):
    """A cache folder of this module's own (SWEEP_CACHE_DIR), the memo emptied."""
    folder = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SWEEP_CACHE_DIR", str(folder))
        derive.cache_clear()
        yield folder
    derive.cache_clear()


def run_lines(lines, values):
    """Execute derived lines with NumPy standing in for the kernel functions; the
    namespace after them (``values`` may hold arrays: one state per element)."""
    names = dict(values, vsin=np.sin, vcos=np.cos,
                 vsincos=lambda x: (np.sin(x), np.cos(x)),
                 math=types.SimpleNamespace(sqrt=np.sqrt))
    exec("\n".join(lines), names)
    return names


def sample(declaration, n=100, seed=35):
    """``n`` random states, times and parameter sets: angles in [-pi, pi], velocities in
    [-2, 2] (rad/s), each parameter 0.5 to 2 times its default (0 to 1 for a default
    of 0)."""
    rng = np.random.default_rng(seed)
    values = {"t": rng.uniform(0.0, 10.0, n)}
    for c in declaration.coordinates:
        values[c.symbol] = rng.uniform(-np.pi, np.pi, n)
        values[c.velocity_symbol] = rng.uniform(-2.0, 2.0, n)
    for p in declaration.parameters:
        values[p.symbol] = (p.default * rng.uniform(0.5, 2.0, n) if p.default
                            else rng.uniform(0.0, 1.0, n))
    return values


def accelerations(declaration, values):
    """The derived accelerations at ``values``, shape (coordinates, states)."""
    names = run_lines(derive(declaration).accel_lines, values)
    return stack([names[f"acc_{c.symbol}"] for c in declaration.coordinates])


def energy(declaration, values):
    return run_lines(derive(declaration).energy_lines, values)["energy_value"]


def jacobian(declaration, values):
    """The derived Jacobian, shape (coordinates, state variables, states)."""
    names = run_lines(derive(declaration, jacobian=True).jacobian_lines, values)
    return stack([[names[f"jac_{c.symbol}_{z}"] for z in state_symbols(declaration)]
                  for c in declaration.coordinates])


def stack(nested):
    """An array of nested lists of arrays and numbers (a constant entry broadcast)."""
    flat = np.broadcast_arrays(*np.ravel(np.array(nested, dtype=object)))
    return np.array(flat).reshape(np.shape(np.array(nested, dtype=object)) + flat[0].shape)


def state_symbols(declaration):
    coords = declaration.coordinates
    return [c.symbol for c in coords] + [c.velocity_symbol for c in coords]


def central_differences(function, values, symbols, h=1e-5):
    """d function / d symbol by central differences, shape (outputs, symbols, states)."""
    columns = []
    for z in symbols:
        up, down = dict(values), dict(values)
        up[z], down[z] = values[z] + h, values[z] - h
        columns.append((function(up) - function(down)) / (2 * h))
    return np.stack(columns, axis=1)


# ------------------------------------------------------------------ double pendulum
def textbook_double_pendulum(v):
    """The double pendulum's accelerations for absolute angles from the downward vertical,
    as myphysicslab.com (and Wikipedia's "Double pendulum") write them; also each one's
    scale: the sum of its numerator's terms' magnitudes over its denominator."""
    th1, th2, om1, om2 = v["th1"], v["th2"], v["om1"], v["om2"]
    m1, m2, l1, l2, g = v["m1"], v["m2"], v["l1"], v["l2"], v["grav"]
    d = th1 - th2
    den = 2 * m1 + m2 - m2 * np.cos(2 * th1 - 2 * th2)
    terms1 = [-g * (2 * m1 + m2) * np.sin(th1), -m2 * g * np.sin(th1 - 2 * th2),
              -2 * np.sin(d) * m2 * (om2 ** 2 * l2 + om1 ** 2 * l1 * np.cos(d))]
    terms2 = [2 * np.sin(d) * om1 ** 2 * l1 * (m1 + m2),
              2 * np.sin(d) * g * (m1 + m2) * np.cos(th1),
              2 * np.sin(d) * om2 ** 2 * l2 * m2 * np.cos(d)]
    acc = np.array([sum(terms1) / (l1 * den), sum(terms2) / (l2 * den)])
    scale = np.array([sum(map(abs, terms1)) / (l1 * den), sum(map(abs, terms2)) / (l2 * den)])
    return acc, scale


def damped_double_pendulum(v):
    """The damped double pendulum's accelerations from its equations of motion written by
    hand (the docstring of `double_pendulum`), ``M a = b`` solved by NumPy."""
    th1, th2, om1, om2 = v["th1"], v["th2"], v["om1"], v["om2"]
    m1, m2, l1, l2, g, c1, c2 = (v[s] for s in ("m1", "m2", "l1", "l2", "grav", "c1", "c2"))
    d = th1 - th2
    q1 = -c1 * om1 + c2 * (om2 - om1)
    q2 = -c2 * (om2 - om1)
    mass = np.array([[(m1 + m2) * l1 ** 2, m2 * l1 * l2 * np.cos(d)],
                     [m2 * l1 * l2 * np.cos(d), m2 * l2 ** 2 + 0 * d]])
    rhs = np.array([-m2 * l1 * l2 * om2 ** 2 * np.sin(d) - (m1 + m2) * g * l1 * np.sin(th1) + q1,
                    m2 * l1 * l2 * om1 ** 2 * np.sin(d) - m2 * g * l2 * np.sin(th2) + q2])
    solved = np.linalg.solve(np.moveaxis(mass, -1, 0), np.moveaxis(rhs, -1, 0)[..., None])
    return np.moveaxis(solved[..., 0], 0, -1)


def test_double_pendulum_accelerations_are_the_textbook_ones():
    declaration = double_pendulum()
    values = sample(declaration)
    expected, scale = textbook_double_pendulum(values)
    got = accelerations(declaration, values)
    # both sides round ~50 operations (1.1e-16 each) on terms of at most `scale`, and
    # the derived determinant m1 + m2 - m2 cos^2 loses up to a factor (m1 + m2) / m1 <= 5
    # more against the textbook's 2 m1 + m2 - m2 cos(2 d): <= 3e-14 * scale; a wrong term
    # would be off by O(scale)
    assert np.all(np.abs(got - expected) <= 1e-12 * scale)


def test_damped_double_pendulum_solves_its_hand_written_equations():
    declaration = double_pendulum(damping=True)
    values = sample(declaration)
    expected = damped_double_pendulum(values)
    got = accelerations(declaration, values)
    # LAPACK's solve and Cramer's rule, each a few dozen roundings (1.1e-16) of terms no
    # larger than the largest acceleration: 1e-13 of it is ~30x the rounding
    assert np.max(np.abs(got - expected)) <= 1e-13 * np.max(np.abs(expected))
    undamped = dict(values, c1=0.0 * values["c1"], c2=0.0 * values["c2"])
    expected, scale = textbook_double_pendulum(undamped)
    got = accelerations(declaration, undamped)
    assert np.all(np.abs(got - expected) <= 1e-12 * scale)  # as in the test above


def test_double_pendulum_energy_is_kinetic_plus_potential_by_hand():
    declaration = double_pendulum(damping=True)
    v = sample(declaration)
    m1, m2, l1, l2, g = v["m1"], v["m2"], v["l1"], v["l2"], v["grav"]
    # bob velocities and heights in Cartesian terms; potential zero hanging at rest
    vx1, vy1 = l1 * v["om1"] * np.cos(v["th1"]), l1 * v["om1"] * np.sin(v["th1"])
    vx2 = vx1 + l2 * v["om2"] * np.cos(v["th2"])
    vy2 = vy1 + l2 * v["om2"] * np.sin(v["th2"])
    y1 = -l1 * np.cos(v["th1"])
    y2 = y1 - l2 * np.cos(v["th2"])
    kinetic = m1 * (vx1 ** 2 + vy1 ** 2) / 2 + m2 * (vx2 ** 2 + vy2 ** 2) / 2
    potential = m1 * g * (y1 + l1) + m2 * g * (y2 + l1 + l2)
    scale = kinetic + m1 * g * l1 + m2 * g * (l1 + l2)
    # two sums of ~20 roundings of terms bounded by `scale`: 1e-13 of it is ~40x that
    assert np.all(np.abs(energy(declaration, v) - (kinetic + potential)) <= 1e-13 * scale)


def test_double_pendulum_jacobian_is_the_textbook_ones_derivative():
    declaration = double_pendulum()
    values = sample(declaration)
    expected = central_differences(lambda v: textbook_double_pendulum(v)[0], values,
                                   state_symbols(declaration))
    got = jacobian(declaration, values)
    # central differences with h = 1e-5: truncation h^2/6 |f'''| ~ 2e-11 |f'''| and
    # rounding 1e-16 |f| / h ~ 1e-11 |f|, with |f'''| up to ~10 times the largest entry
    # here: ~2e-10 of it (measured: 2e-11 to 2e-10 for every system in this file); 1e-8
    # leaves a margin of 50, and a wrong entry is off by O(1)
    assert np.max(np.abs(got - expected)) <= 1e-8 * np.max(np.abs(expected))


def test_damped_double_pendulum_jacobian_matches_differences():
    declaration = double_pendulum(damping=True)
    values = sample(declaration)
    expected = central_differences(damped_double_pendulum, values,
                                   state_symbols(declaration))
    got = jacobian(declaration, values)
    assert np.max(np.abs(got - expected)) <= 1e-8 * np.max(np.abs(expected))  # as above


# ------------------------------------------------------------------ coupled pendula
def hand_coupled(n, coupling, topology, v):
    """Accelerations and energy of `coupled_pendula` written out by hand."""
    th = [v[f"th{i}"] for i in range(1, n + 1)]
    om = [v[f"om{i}"] for i in range(1, n + 1)]
    m, ell, g, cd = v["m"], v["l"], v["grav"], v.get("cd", 0.0)
    pairs = [(i, i + 1) for i in range(n - 1)] + ([(n - 1, 0)] if topology == "ring" else [])
    acc = [-g / ell * np.sin(th[i]) - cd * om[i] / (m * ell ** 2) for i in range(n)]
    energy = sum(m * ell ** 2 * om[i] ** 2 / 2 + m * g * ell * (1 - np.cos(th[i]))
                 for i in range(n))
    for i, j in pairs:
        if coupling == "spring":  # force ks l (sin i - sin j) along the horizontal
            stretch = np.sin(th[i]) - np.sin(th[j])
            acc[i] = acc[i] - v["ks"] / m * stretch * np.cos(th[i])
            acc[j] = acc[j] + v["ks"] / m * stretch * np.cos(th[j])
            energy = energy + v["ks"] / 2 * ell ** 2 * stretch ** 2
        else:
            twist = th[i] - th[j]
            acc[i] = acc[i] - v["kappa"] / (m * ell ** 2) * twist
            acc[j] = acc[j] + v["kappa"] / (m * ell ** 2) * twist
            energy = energy + v["kappa"] / 2 * twist ** 2
    return np.array(acc), energy


COUPLED = [(2, "spring", "chain", False), (4, "spring", "ring", True),
           (3, "torsion", "ring", True), (5, "torsion", "chain", False)]


@pytest.mark.parametrize("case", COUPLED, ids=lambda c: "-".join(map(str, c)))
def test_coupled_pendula_match_their_hand_written_equations(case):
    declaration = coupled_pendula(*case)
    values = sample(declaration)
    expected_acc, expected_energy = hand_coupled(*case[:3], values)
    # sums of a few terms no larger than the largest value, each side rounded ~10-30
    # times (1.1e-16 each): 1e-13 of the largest value is ~30x that
    assert np.max(np.abs(accelerations(declaration, values) - expected_acc)) \
        <= 1e-13 * np.max(np.abs(expected_acc))
    assert np.max(np.abs(energy(declaration, values) - expected_energy)) \
        <= 1e-13 * np.max(np.abs(expected_energy))
    fd = central_differences(lambda v: hand_coupled(*case[:3], v)[0], values,
                             state_symbols(declaration))
    # central differences (see the double pendulum's Jacobian test)
    assert np.max(np.abs(jacobian(declaration, values) - fd)) <= 1e-8 * np.max(np.abs(fd))


def normal_modes(declaration, values):
    """Squared normal-mode frequencies of the equations linearised at rest: the
    eigenvalues of K = -d acc / d theta at theta = omega = 0 (mass-normalised stiffness)."""
    rest = dict(values)
    for c in declaration.coordinates:
        rest[c.symbol] = rest[c.velocity_symbol] = 0.0
    n = len(declaration.coordinates)
    stiffness = -jacobian(declaration, rest)[:, :n]
    return np.linalg.eigvalsh(stiffness)


@pytest.mark.parametrize("coupling", ["spring", "torsion"])
def test_two_coupled_pendula_have_the_textbook_normal_modes(coupling):
    """Two pendula (m, l) with a spring k between the bobs: linearised,
    m l^2 theta1'' = -m g l theta1 - k l^2 (theta1 - theta2) and the same with 1 and 2
    swapped, so theta1 + theta2 oscillates with omega^2 = g/l and theta1 - theta2 with
    g/l + 2k/m. With a torsion spring kappa, k l^2 becomes kappa: g/l + 2 kappa/(m l^2)."""
    declaration = coupled_pendula(2, coupling, "chain", damping=True)
    m, ell, g, k, cd = 0.7, 1.3, 9.81, 2.9, 0.4
    values = {"m": m, "l": ell, "grav": g, "ks": k, "kappa": k, "cd": cd, "t": 0.0}
    coupling_term = 2 * k / m if coupling == "spring" else 2 * k / (m * ell ** 2)
    expected = [g / ell, g / ell + coupling_term]
    # a symmetric 2x2 eigenproblem with entries ~10 s^-2: LAPACK's eigenvalues are good
    # to a few ulp of the largest; 1e-12 relative is 100x that
    assert np.allclose(normal_modes(declaration, values), expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("topology", ["chain", "ring"])
def test_n_coupled_pendula_have_the_lattice_normal_modes(topology):
    """n pendula with torsion coupling kappa: the linearised stiffness is
    g/l + kappa/(m l^2) times the graph Laplacian of the chain (eigenvalues
    2 - 2 cos(pi j / n), j = 0..n-1) or of the ring (2 - 2 cos(2 pi j / n))."""
    n = 6
    declaration = coupled_pendula(n, "torsion", topology)
    m, ell, g, kappa = 1.1, 0.8, 9.81, 3.0
    values = {"m": m, "l": ell, "grav": g, "kappa": kappa, "t": 0.0}
    j = np.arange(n)
    laplacian = 2 - 2 * np.cos((np.pi if topology == "chain" else 2 * np.pi) * j / n)
    expected = np.sort(g / ell + kappa / (m * ell ** 2) * laplacian)
    assert np.allclose(normal_modes(declaration, values), expected, rtol=1e-12, atol=0)  # as above


@pytest.mark.parametrize("arguments, message", [
    ((1,), "n=1 is not accepted; accepted: an integer >= 2"),
    ((True,), "n=True is not accepted"),
    ((2.0,), "n=2.0 is not accepted"),
    ((3, "rope"), "coupling='rope' is not accepted; accepted: 'spring', 'torsion'"),
    ((3, "spring", "star"), "topology='star' is not accepted; accepted: 'chain', 'ring'"),
    ((2, "spring", "ring"), "n=2 is not accepted for a ring .* accepted: n >= 3"),
])
def test_coupled_pendula_refuse_bad_arguments(arguments, message):
    with pytest.raises(ValueError, match=message):
        coupled_pendula(*arguments)


def test_built_in_symbols_avoid_reserved_and_effect_names():
    effects = {p.symbol for cls in EFFECTS.values() for p in cls.declaration.parameters}
    for declaration in (double_pendulum(), double_pendulum(True), coupled_pendula(3),
                        coupled_pendula(4, "torsion", "ring", True)):
        symbols = set(state_symbols(declaration)) | {p.symbol for p in declaration.parameters}
        assert not symbols & (RESERVED_SYMBOLS | effects), declaration.name


# ------------------------------------------------------------------ any declaration
def _parameter(symbol, default=1.0):
    return Parameter(symbol, symbol, symbol, "1", "1", symbol, minimum=0.0, strict=True,
                     default=default)


def _coordinates(n):
    return tuple(Coordinate(f"theta{i}", f"omega{i}", f"th{i}", f"om{i}")
                 for i in range(1, n + 1))


def triple_pendulum():
    """Three equal masses m on rods of length l, its Lagrangian in Cartesian terms (the
    bobs' velocities as sums): a full 3 x 3 mass matrix."""
    vx = vy = y = "0"
    kinetic, heights = [], []
    for i in (1, 2, 3):
        vx, vy = f"({vx} + l*cos(th{i})*om{i})", f"({vy} + l*sin(th{i})*om{i})"
        y = f"({y} - l*cos(th{i}))"
        kinetic.append(f"m/2*({vx}**2 + {vy}**2)")
        heights.append(y)
    return SystemDeclaration(
        "triple_pendulum", _coordinates(3),
        (_parameter("m"), _parameter("l"), _parameter("grav", 9.81)),
        lagrangian=" + ".join(kinetic) + f" - m*grav*({' + '.join(heights)})")


def soft_springs():
    """Two unit masses given by their accelerations: softening springs
    k x / sqrt(1 + x^2) to the walls, a linear spring between them, damping (non-angular
    coordinates, half-integer powers)."""
    coordinates = (Coordinate("x", "vx", "xa", "va", "m", "m s-1", angular=False),
                   Coordinate("y", "vy", "xb", "vb", "m", "m s-1", angular=False))
    return SystemDeclaration(
        "soft_springs", coordinates,
        (_parameter("kw"), _parameter("kc"), _parameter("cd", 0.1)),
        accelerations=("-kw*xa/sqrt(1 + xa**2) + kc*(xb - xa) - cd*va",
                       "-kw*xb/sqrt(1 + xb**2) - kc*(xb - xa) - cd*vb"),
        potential="kw*(sqrt(1 + xa**2) - 1) + kw*(sqrt(1 + xb**2) - 1) + kc/2*(xb - xa)**2")


def shaken_pendulum():
    """One pendulum whose pivot moves sideways as ``a sin(w t)``: a Lagrangian with a
    term linear in the velocity that depends on time (the ``d2L/(dv dt)`` term), one
    coordinate."""
    return SystemDeclaration(
        "shaken_pendulum", _coordinates(1),
        (_parameter("m"), _parameter("l"), _parameter("grav", 9.81), _parameter("a", 0.3),
         _parameter("w", 2.0)),
        lagrangian="m/2*((a*w*cos(w*t) + l*cos(th1)*om1)**2 + (l*sin(th1)*om1)**2)"
                   " + m*grav*l*cos(th1)")


DECLARATIONS = [shaken_pendulum(), double_pendulum(damping=True), triple_pendulum(),
                coupled_pendula(3, "spring", "ring", damping=True), soft_springs()]


def reference(declaration):
    """Accelerations and energy by SymPy alone: its ``euler_equations`` of the
    Lagrangian (plus the forces), M and b lambdified and ``M a = b`` solved by NumPy; or
    the declared accelerations lambdified. Shares nothing with `derive` but SymPy."""
    t = sp.Symbol("t")
    coords = declaration.coordinates
    q = [sp.Symbol(c.symbol) for c in coords]
    v = [sp.Symbol(c.velocity_symbol) for c in coords]
    params = [sp.Symbol(p.symbol) for p in declaration.parameters]
    arguments = [*q, *v, *params, t]
    names = {s.name: s for s in arguments}

    def call(function, values):
        return function(*(values[s.name] for s in arguments))

    if declaration.lagrangian is None:
        accs = [sp.sympify(a, locals=names) for a in declaration.accelerations]
        kinetic = sum(x ** 2 for x in v) / 2
        e = kinetic + sp.sympify(declaration.potential, locals=names)
        acc_f, e_f = sp.lambdify(arguments, accs), sp.lambdify(arguments, e)
        return (lambda values: np.array(call(acc_f, values)) + 0 * values["t"],
                lambda values: call(e_f, values))
    paths = [sp.Function(c.symbol)(t) for c in coords]
    moving = dict(names)
    moving.update({c.symbol: f for c, f in zip(coords, paths)})
    moving.update({c.velocity_symbol: f.diff(t) for c, f in zip(coords, paths)})
    lagrangian = sp.sympify(declaration.lagrangian, locals=moving)
    forces = [sp.sympify(f, locals=moving) for f in declaration.forces] or [0] * len(q)
    a = sp.symbols(f"a0:{len(q)}")
    plain = {f.diff(t, 2): ai for f, ai in zip(paths, a)}
    plain.update({f.diff(t): vi for f, vi in zip(paths, v)})
    equations = [(eq.lhs + force).subs(plain).subs(dict(zip(paths, q)))
                 for eq, force in zip(sp.euler_equations(lagrangian, paths, t), forces)]
    mass = sp.Matrix([[-sp.diff(e, ai) for ai in a] for e in equations])
    rhs = sp.Matrix([e.subs(dict.fromkeys(a, 0)) for e in equations])
    plain_l = lagrangian.subs(plain).subs(dict(zip(paths, q)))
    e = sum(vi * sp.diff(plain_l, vi) for vi in v) - plain_l
    mass_f, rhs_f, e_f = (sp.lambdify(arguments, x) for x in (mass.tolist(), rhs.tolist(), e))

    def acc(values):
        size = np.size(values["t"])
        m = np.array([[np.broadcast_to(x, size) for x in row] for row in call(mass_f, values)])
        b = np.array([np.broadcast_to(x[0], size) for x in call(rhs_f, values)])
        solved = np.linalg.solve(np.moveaxis(m, -1, 0), np.moveaxis(b, -1, 0)[..., None])
        return np.moveaxis(solved[..., 0], 0, -1)

    return acc, lambda values: call(e_f, values)


@pytest.mark.parametrize("declaration", DECLARATIONS, ids=lambda d: d.name)
def test_derived_source_computes_what_sympy_alone_computes(declaration):
    values = sample(declaration)
    acc_ref, energy_ref = reference(declaration)
    expected, got = acc_ref(values), accelerations(declaration, values)
    # the same functions evaluated in different orders (CSE, Cramer's rule against
    # LAPACK's LU) from states and parameters of order 1: ~100 roundings of terms no
    # larger than the largest result, 1e-16 each, so ~1e-14 of it; the triple
    # pendulum's determinant (a sum of ~10 products cancelling to m^3 l^6 (1 + ...))
    # costs a factor of ~10 more, hence 1e-13 of the largest value
    assert np.max(np.abs(got - expected)) <= 1e-13 * np.max(np.abs(expected))
    assert np.max(np.abs(energy(declaration, values) - energy_ref(values))) \
        <= 1e-13 * np.max(np.abs(energy_ref(values)))  # as above
    fd = central_differences(acc_ref, values, state_symbols(declaration))
    # central differences (see the double pendulum's Jacobian test)
    assert np.max(np.abs(jacobian(declaration, values) - fd)) <= 1e-8 * np.max(np.abs(fd))


IDENTIFIER_CALLS = {"vsin", "vcos", "vsincos"}


@pytest.mark.parametrize("declaration", DECLARATIONS + [double_pendulum()],
                         ids=lambda d: d.name)
def test_derived_source_keeps_the_kernel_conventions(declaration):
    """Statements only (assignments; ``s_k, c_k = vsincos(u)``), calls only to the
    kernel functions and math.sqrt, names only the state, parameters, t and earlier
    temporaries, float literals only, no ``**``; the outputs last, in order."""
    derived = derive(declaration, jacobian=True)
    given = set(state_symbols(declaration)) | {p.symbol for p in declaration.parameters}
    given.add("t")
    coords = [c.symbol for c in declaration.coordinates]
    outputs = {"accel_lines": [f"acc_{a}" for a in coords], "energy_lines": ["energy_value"],
               "jacobian_lines": [f"jac_{a}_{z}" for a in coords
                                  for z in state_symbols(declaration)]}
    for block, targets in outputs.items():
        lines = getattr(derived, block)
        defined = set(given)
        assigned = []
        for line in lines:
            (statement,) = ast.parse(line).body
            assert isinstance(statement, ast.Assign) and len(statement.targets) == 1, line
            for node in ast.walk(statement.value):
                if isinstance(node, ast.Call):
                    function = ast.unparse(node.func)
                    assert function in KERNEL_CALLS | {"math.sqrt"}, line
                    if function == "vsincos":
                        assert isinstance(statement.targets[0], ast.Tuple), line
                elif isinstance(node, ast.Name) and node.id not in KERNEL_CALLS | {"math"}:
                    assert node.id in defined, (line, node.id)
                elif isinstance(node, ast.Constant):
                    assert type(node.value) is float, line
                elif isinstance(node, ast.BinOp):
                    assert not isinstance(node.op, ast.Pow), line
            names = [n.id for n in ast.walk(statement.targets[0]) if isinstance(n, ast.Name)]
            assert not set(names) & given, line
            defined.update(names)
            assigned += names
        assert assigned[-len(targets):] == targets, block
        temporaries = assigned[:-len(targets)]
        assert all(name[0] == "x" or name[:2] in ("s_", "c_") for name in temporaries)


def test_derived_source_compiles_with_numba():
    """Each block of the damped double pendulum and the triple pendulum as the body of
    an njit function (numba's own sine and cosine behind vsin, vcos, vsincos): it
    compiles, and gives what the same lines give in Python with NumPy."""
    numba = pytest.importorskip("numba")
    helpers = {"vsin": numba.njit(lambda x: math.sin(x)),
               "vcos": numba.njit(lambda x: math.cos(x)),
               "vsincos": numba.njit(lambda x: (math.sin(x), math.cos(x))),
               "math": math}
    for declaration in (double_pendulum(damping=True), triple_pendulum()):
        derived = derive(declaration, jacobian=True)
        values = {k: float(x[0]) for k, x in sample(declaration, n=1).items()}
        arguments = list(values)
        coords = [c.symbol for c in declaration.coordinates]
        for lines, outputs in (
                (derived.accel_lines, [f"acc_{a}" for a in coords]),
                (derived.energy_lines, ["energy_value"]),
                (derived.jacobian_lines, [f"jac_{a}_{z}" for a in coords
                                          for z in state_symbols(declaration)])):
            source = (f"def block({', '.join(arguments)}):\n"
                      + "".join(f"    {line}\n" for line in lines)
                      + f"    return ({', '.join(outputs)},)\n")
            namespace = dict(helpers)
            exec(source, namespace)
            compiled = numba.njit(namespace["block"])(*values.values())
            python = run_lines(lines, values)
            # libm's sine (numba) and NumPy's differ by at most an ulp or two, carried
            # through a few dozen operations: 1e-13 of the largest output
            expected = np.array([python[name] for name in outputs])
            assert np.allclose(compiled, expected, rtol=0,
                               atol=1e-13 * np.max(np.abs(expected)))


# ------------------------------------------------------------------ bad declarations
TOY = SystemDeclaration(
    "toy", _coordinates(2), (_parameter("m"),),
    lagrangian="m*om1**2/2 + m*om2**2/2 + m*cos(th1) + m*cos(th2)")


@pytest.mark.parametrize("changes, message", [
    (dict(lagrangian="m*om1**2/2 + cos(th2)"),
     r"no kinetic term in om2 .* acceleration of 'theta2' is not determined; accepted: a "
     r"Lagrangian whose mass matrix"),
    (dict(lagrangian="m*(om1 + om2)**2/2 + cos(th1)"),
     r"mass matrix .* is singular \(its determinant is 0 for every state\); accepted"),
    (dict(lagrangian="m*om1**2/2 + m*om2**2/2 + foo*th1"),
     r"names 'foo', which is neither a coordinate \(th1, th2\), a velocity \(om1, om2\), "
     r"a parameter \(m\) nor t; accepted"),
    (dict(lagrangian="m*om1**2/2 + m*om2**2/2 +"), r"does not parse .*; accepted"),
    (dict(lagrangian="m*om1^2/2 + m*om2**2/2"), r"write powers with \*\*"),
    (dict(lagrangian="m*om1**2/2 + m*om2**2/2 + exp(th1)"),
     r"calls a function that is not accepted .*'exp\(th1\)'.*accepted: .*sin, cos, sqrt"),
    (dict(lagrangian="m*om1**2/2 + m*om2**2/2 + th1**(1/3)"),
     r"power .* which the kernels cannot evaluate; accepted: integer and half-integer"),
    (dict(lagrangian="m*om1**2/2 + m*om2**2/2 + 1/(th1 - th1)"),
     r"the lagrangian, .*, is zoo \(a division by zero or the root of a negative number\)"),
    (dict(lagrangian="m*om1**2*sqrt(m - 2) + m*om2**2"),  # m is drawn in (0.5, 2) here
     r"the mass matrix .* is not finite and real at m=.*; accepted: a Lagrangian whose"),
    (dict(forces=("-c*om1", "0")), r"force on 'theta1', '-c\*om1', names 'c'"),
    (dict(forces=("0",)), r"forces has 1 entries; accepted: a tuple of 2 strings"),
    (dict(forces=["0", "0"]), r"forces is a list; accepted: a tuple of 2 strings"),
    (dict(potential="m*th1"), r"potential is read only with accelerations"),
    (dict(lagrangian=None, accelerations=("-th1",)),
     r"accelerations has 1 entries; accepted: a tuple of 2 strings, one per coordinate$"),
    (dict(accelerations=("-th1", "-th2")), r"give either a lagrangian or accelerations .*"
                                           r"not both"),
    (dict(lagrangian=None), r"give either .* not neither"),
    (dict(lagrangian=None, accelerations=("-th1", "-th2"), forces=("0", "0")),
     r"forces are read only with a lagrangian"),
    (dict(coordinates=(Coordinate("theta1", "omega1", "th1", "om1"),
                       Coordinate("theta1", "omega2", "th2", "om2"))),
     r"coordinate name 'theta1' is also the coordinate name; accepted: names that differ"),
    (dict(parameters=(Parameter("mass", "mass", "th1", "kg", "kg", "mass"),)),
     r"symbol of parameter 'mass' 'th1' is also the symbol of coordinate 'theta1'"),
    (dict(parameters=(Parameter("theta1_0", "m", "m", "kg", "kg", "mass"),)),
     r"parameter axis 'theta1_0' is also the coordinate name"),
    (dict(parameters=(Parameter("gravity", "gravity", "g", "m s-2", "m/s^2", "g"),)),
     r"the symbol of parameter 'gravity', 'g', is not accepted; accepted: a Python "
     r"identifier .* not one of sweep's reserved"),
    (dict(parameters=(Parameter("mass", "mass", "x1", "kg", "kg", "mass"),)),
     r"'x1', is not accepted.* not of the form of a derived name"),
    (dict(coordinates=()), r"coordinates \(\) are not accepted; accepted: a non-empty tuple"),
])
def test_bad_declarations_are_refused_with_what_is_accepted(changes, message):
    declaration = dataclasses.replace(TOY, **changes)
    with pytest.raises(ValueError, match=message) as caught:
        derive(declaration)
    assert str(caught.value).startswith("system 'toy': ")


def test_more_than_three_coupled_velocities_are_refused():
    lagrangian = " + ".join(f"om{i}**2/2 - cos(th{i})" for i in range(1, 5)) + " + om1*om2/4"
    declaration = SystemDeclaration("four", _coordinates(4), (), lagrangian=lagrangian)
    with pytest.raises(ValueError, match=r"system 'four': the mass matrix of its 4 "
                                         r"coordinates is not diagonal.* only for 2 or 3"):
        derive(declaration)
    diagonal = dataclasses.replace(declaration, lagrangian=lagrangian.replace(" + om1*om2/4", ""))
    assert len(derive(diagonal).accel_lines) >= 4  # four uncoupled ones are accepted


def test_a_singular_mass_matrix_is_refused_at_a_random_point(monkeypatch):
    """The numeric check alone (the symbolic simplification switched off): the mass
    matrix [[1, 1], [1, sin^2 + cos^2]] is singular, which only simplification shows
    symbolically."""
    monkeypatch.setattr(D, "_simplified", lambda sp, expr: expr)
    monkeypatch.setattr(D, "_is_zero", lambda sp, expr: expr == 0)
    declaration = dataclasses.replace(
        TOY, lagrangian="om1**2/2 + om1*om2 + (sin(th1)**2 + cos(th1)**2)*om2**2/2")
    with pytest.raises(ValueError, match=r"system 'toy': the mass matrix .* is singular "
                                         r"at m=.*, th1=.* \(determinant .*\); accepted"):
        derive(declaration)


def test_derive_refuses_what_is_not_a_declaration():
    with pytest.raises(TypeError, match="expected a SystemDeclaration, got dict"):
        derive({"name": "toy"})


# ------------------------------------------------------------------ caches and imports
def test_importing_sweep_and_the_declarations_imports_no_sympy():
    code = ("import sys, sweep, sweep.physics.derive, sweep.physics.systems; "
            "sweep.physics.systems.double_pendulum(); print('sympy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False"]


def _stored(folder):
    return sorted((folder / "kernels").glob("system_*.json"))


def test_derived_source_is_cached_on_disk_and_read_back(private_cache, monkeypatch):
    declaration = dataclasses.replace(coupled_pendula(3, "torsion", "chain"), name="stored")
    before = set(_stored(private_cache))
    first = derive(declaration)
    (path,) = set(_stored(private_cache)) - before
    stored = json.loads(path.read_text())
    assert stored["accel_lines"] == list(first.accel_lines)
    assert stored["declaration"] == repr(declaration)
    assert derive(declaration) is first  # the memo

    def derive_again(*args):
        raise AssertionError("derived again")

    monkeypatch.setattr(D, "_derive_now", derive_again)
    derive.cache_clear()
    assert derive(declaration) == first  # from the JSON, not derived
    changed = dataclasses.replace(declaration, name="other")
    with pytest.raises(AssertionError, match="derived again"):
        derive(changed)  # another declaration: a miss
    with pytest.raises(AssertionError, match="derived again"):
        derive(declaration, jacobian=True)  # another output: a miss
    monkeypatch.setattr(D, "DERIVE_VERSION", D.DERIVE_VERSION + 1)
    derive.cache_clear()
    with pytest.raises(AssertionError, match="derived again"):
        derive(declaration)  # another version of the derivation: a miss


def test_a_second_process_reads_the_cache_without_sympy(private_cache):
    declaration = double_pendulum(damping=True)
    derived = derive(declaration, jacobian=True)
    code = ("import json, sys; from sweep.physics.derive import derive; "
            "from sweep.physics.systems import double_pendulum; "
            "d = derive(double_pendulum(damping=True), jacobian=True); "
            "print(json.dumps([list(d.accel_lines), list(d.jacobian_lines), "
            "'sympy' in sys.modules]))")
    env = dict(os.environ, SWEEP_CACHE_DIR=str(private_cache))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env).stdout
    assert json.loads(out) == [list(derived.accel_lines), list(derived.jacobian_lines), False]


def test_a_damaged_cache_entry_is_derived_again(private_cache):
    declaration = dataclasses.replace(coupled_pendula(2, "spring", "chain"), name="damaged")
    before = set(_stored(private_cache))
    first = derive(declaration)
    (path,) = set(_stored(private_cache)) - before
    for damage in ('{"accel_lines": ', json.dumps(dict(json.loads(path.read_text()),
                                                       accel_lines=[1, 2]))):
        path.write_text(damage)
        derive.cache_clear()
        assert derive(declaration) == first
        assert json.loads(path.read_text())["accel_lines"] == list(first.accel_lines)


def test_a_cache_folder_others_can_write_is_not_used(tmp_path, monkeypatch):
    """A SWEEP_CACHE_DIR of mode 0777 (its kernels folder the user's, 0700): derived
    source is not stored there (another user could put code in it that a kernel runs)."""
    shared = tmp_path / "shared"
    (shared / "kernels" / "__pycache__").mkdir(parents=True, mode=0o700)
    shared.chmod(0o777)
    monkeypatch.setenv("SWEEP_CACHE_DIR", str(shared))
    derive.cache_clear()
    try:
        derived = derive(coupled_pendula(2, "torsion", "chain"))
    finally:
        derive.cache_clear()
    assert derived.accel_lines[-1].startswith("acc_th2 = ")
    assert not list(shared.rglob("system_*.json"))


def test_derived_source_does_not_depend_on_the_hash_seed(tmp_path):
    """Two processes with different string hashing derive the same text (so the kernels
    built from it are the same module, compiled once)."""
    code = ("import json; from sweep.physics.derive import derive; "
            "from sweep.physics import systems; "
            "d = [derive(systems.double_pendulum(True), jacobian=True), "
            "derive(systems.coupled_pendula(3, 'spring', 'ring', True), jacobian=True)]; "
            "print(json.dumps([[list(b) for b in x.__dict__.values()] for x in d]))")
    outputs = []
    for seed in ("1", "2"):
        env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path / seed), PYTHONHASHSEED=seed)
        outputs.append(subprocess.run([sys.executable, "-c", code], capture_output=True,
                                      text=True, check=True, env=env).stdout)
    assert outputs[0] == outputs[1]
