"""Integrators as data: tableau invariants, every method through the one kernel builder,
observed orders against the exact elliptic solution, energy behaviour over 1e6 steps,
and the adaptive pair's tolerance, step control and refusals.

Oracles: the Jacobi-elliptic exact solution (`sweep.accuracy.exact`, itself checked
against SciPy in test_accuracy.py), the exact RK4 propagator of the linear oscillator,
and a pure-Python replica of the classical RK4 step.
"""

import itertools
import math
from fractions import Fraction

import numba
import numpy as np
import pytest
from shared_kernels import EVERY, EVERY_ADAPTIVE

import sweep
from sweep import Status, _config, maps, methods
from sweep import kernels as _kernels
from sweep.accuracy import ellipk, exact, state_error
from sweep.kernels import vecmath as _vecmath
from sweep.methods import METHODS, ButcherTableau, SplittingMethod

TABLEAUX = [m for m in METHODS.values() if isinstance(m, ButcherTableau)]
SPLITTINGS = [m for m in METHODS.values() if isinstance(m, SplittingMethod)]
FIXED = [name for name, m in METHODS.items() if not m.adaptive]


# =========================================================================== data
def test_registry_has_the_methods_of_the_issue_and_rk4_is_default():
    assert set(METHODS) == {"euler", "heun", "rk4", "rk38", "dopri5", "verlet", "yoshida4"}
    assert methods.DEFAULT_METHOD == "rk4"
    for name, method in METHODS.items():
        assert method.name == name
        assert method.source.strip()  # every method says where it comes from
    orders = {name: m.order for name, m in METHODS.items()}
    assert orders == {"euler": 1, "heun": 2, "rk4": 4, "rk38": 4, "dopri5": 5, "verlet": 2,
                      "yoshida4": 4}


@pytest.mark.parametrize("tableau", TABLEAUX, ids=lambda t: t.name)
def test_tableau_invariants(tableau):
    s = tableau.stages
    a, b, c = tableau.a, tableau.b, tableau.c
    assert len(a) == s and all(len(row) == s for row in a)
    for i, j in itertools.product(range(s), repeat=2):
        if j >= i:
            assert a[i][j] == 0  # strictly lower-triangular: explicit
    # all coefficients of the registry are rational, so these identities are exact
    assert all(isinstance(x, Fraction) for row in a for x in row)
    for i in range(s):
        assert sum(a[i]) == c[i]
    assert sum(b) == 1
    for p in range(1, tableau.order + 1):  # every order condition up to the order holds
        for tree in methods.rooted_trees(p):
            assert methods._condition_residual(tree, a, b) == 0, (p, tree)
    # ... and the claimed order is sharp: some condition of order + 1 fails
    assert any(methods._condition_residual(t, a, b) != 0
               for t in methods.rooted_trees(tableau.order + 1))
    if tableau.adaptive:
        assert sum(tableau.b_hat) == 1
        assert methods._order_of(a, tableau.b_hat, tableau.order) == tableau.embedded_order
        assert sum(tableau.error_weights) == 0  # the estimate vanishes on constants


@pytest.mark.parametrize("method", SPLITTINGS, ids=lambda m: m.name)
def test_splitting_invariants(method):
    # Yoshida's coefficients are irrational (cube roots): their sums are 1 to rounding,
    # a few ulps (8 eps covers the 4-term float sum).
    assert abs(float(sum(method.kick)) - 1.0) <= 8 * np.finfo(float).eps
    assert abs(float(sum(method.drift)) - 1.0) <= 8 * np.finfo(float).eps
    # symmetric compositions (palindromic kick/drift layout) are of even order
    assert method.order % 2 == 0
    assert method.conservative_only and not method.adaptive


def test_rooted_tree_counts():
    # OEIS A000081: 1, 1, 2, 4, 9, 20 rooted trees with 1..6 nodes
    assert [len(methods.rooted_trees(n)) for n in range(1, 7)] == [1, 1, 2, 4, 9, 20]


def test_rhs_evaluations_per_step():
    per_step = {name: m.rhs_per_step for name, m in METHODS.items()}
    assert per_step == {"euler": 1, "heun": 2, "rk4": 4, "rk38": 4, "dopri5": 6,
                        "verlet": 1, "yoshida4": 3}  # dopri5 and the splittings reuse a stage


BAD_TABLEAUX = [
    (dict(a=((0, 1), (0, 0)), b=(F := Fraction(1, 2), F), c=(0, 1), order=2),
     r"must be strictly lower-triangular \(explicit method\), but a\[0\]\[1\] = 1"),
    (dict(a=((0, 0), (1, 0)), b=(Fraction(1, 2), Fraction(1, 2)), c=(0, Fraction(1, 2)),
          order=2), r"row sum of a\[1\] is 1 but c\[1\] = 0\.5"),
    (dict(a=((0, 0), (1, 0)), b=(Fraction(1, 2), Fraction(1, 3)), c=(0, 1), order=2),
     r"sum\(b\) = 0\.83333333333333337; it must be 1"),
    (dict(a=((0, 0), (1, 0)), b=(Fraction(1, 2), Fraction(1, 2)), c=(0, 1), order=3),
     r"claimed order 3 but its weights b satisfy the order conditions up to order 2"),
    (dict(a=((0, 0), (1, 0)), b=("1/2", "1/2"), c=(0, 1), order=2, b_hat=(1, 0)),
     r"embedded_order must be an int in \[1, order\)"),
    (dict(a=((0,),), b=(1,), c=(0,), order=1, source=" "), r"source must say where"),
]


@pytest.mark.parametrize("kwargs,message", BAD_TABLEAUX)
def test_bad_tableaux_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ButcherTableau(**{"name": "bad", "source": "test", **kwargs})


def test_bad_splitting_is_refused():
    with pytest.raises(ValueError, match=r"sum\(drift\) = 0\.5; it must be 1"):
        SplittingMethod(name="bad", kick=(1, 0), drift=(0.5, 0), order=1, source="test")


# =========================================================================== the kernel
def _classical_rk4(th, om, n, t0, dt, w0sq, c, amp, freq, phase):
    """The textbook RK4 step, written out by hand (the seed's form), with the fused
    multiply-adds the kernels write explicitly (``vfma``): each stage's ``base + h k``,
    the update ``base + (dt/6) (k1 + 2 k2 + 2 k3 + k4)`` and gravity onto the other
    terms."""
    fma, sin = _vecmath.fma, _vecmath.sin
    half, sixth = 0.5 * dt, dt / 6.0
    fa = amp * sin(freq * t0 + phase)
    for step in range(n):
        fb = amp * sin(freq * (t0 + step * dt + half) + phase)
        fc = amp * sin(freq * (t0 + (step + 1) * dt) + phase)
        k1t, k1o = om, fma(-w0sq, sin(th), -c * om + fa)
        k2t = fma(half, k1o, om)
        k2o = fma(-w0sq, sin(fma(half, k1t, th)), -c * k2t + fb)
        k3t = fma(half, k2o, om)
        k3o = fma(-w0sq, sin(fma(half, k2t, th)), -c * k3t + fb)
        k4t = fma(dt, k3o, om)
        k4o = fma(-w0sq, sin(fma(dt, k3t, th)), -c * k4t + fc)
        th = fma(sixth, k1t + 2.0 * k2t + 2.0 * k3t + k4t, th)
        om = fma(sixth, k1o + 2.0 * k2o + 2.0 * k3o + k4o, om)
        fa = fc
    return th, om


def test_rk4_is_generated_from_its_tableau_and_is_the_classical_step():
    """No hand-written fast path: the tableau-driven step performs exactly the
    operations of the classical RK4 step (written out above), so the two, compiled
    with the same flags and sine, agree bit for bit -- not merely to ~1e-15. (Plain
    Python with math.sin agrees to ~1e-15: another sine, and no fused multiply-adds.)"""
    scene = sweep.Scene(effects=(sweep.Damping(0.3), sweep.Forcing(1.1, 0.9, 0.4)))
    dt, n, t0 = 0.01, 300, 0.5
    ds = sweep.run(scene, sweep.Grid(theta0=[1.2], omega0=[-0.4]), t0=t0,
                   t_end=t0 + n * dt, dt=dt, observe=EVERY)  # test_engine's kernel
    compiled = numba.njit(**_config.jit_options())(_classical_rk4)
    args = (1.2, -0.4, n, t0, dt, 9.81, 0.3, 1.1, 0.9, 0.4)
    th, om = compiled(*args)
    assert ds.theta_final.item() == th and ds.omega_final.item() == om


def _scene_for(method, model="nonlinear"):
    if METHODS[method].conservative_only:
        return sweep.Scene(model=model)
    return sweep.Scene(model=model, effects=(sweep.Damping(0.3), sweep.Forcing(1.1, 0.9)))


@pytest.mark.parametrize("method", list(METHODS))
def test_every_method_runs_through_the_kernel_builder_with_all_observables(method):
    scene = _scene_for(method)
    grid = sweep.Grid(theta0=np.linspace(-2.0, 2.0, 3), omega0=[0.0, 7.0])
    # every observable the method takes: test_blocks' kernels (tests/shared_kernels.py)
    observe = EVERY_ADAPTIVE if METHODS[method].adaptive else EVERY
    kwargs = dict(t_end=4.0, dt=0.01, t_transient=1.0, observe=observe, method=method)
    ds = sweep.run(scene, grid, **kwargs)
    assert ds.attrs["method"] == method
    assert (ds.status == sweep.Status.OK).all()
    for name in ("theta_final", "omega_final", "winding", "theta_max", "amplitude",
                 "tension_min", "tension_max", "energy_initial", "energy_final"):
        assert name in ds and np.isfinite(ds[name]).all(), name
    # the observables are consistent with one another whatever the method
    # the winding is the wells crossed, round (half to even, as np.round) of the end's
    # well index minus the start's (theta0 = +-2 rad: well 0)
    np.testing.assert_array_equal(ds.winding, np.round(ds.theta_final / (2 * np.pi))
                                  - np.round(ds.theta0 / (2 * np.pi)))
    assert (ds.theta_max >= np.abs(ds.theta_final) - 1e-12).all()
    assert (ds.tension_max >= ds.tension_min).all()
    # The end state against a 4x finer RK4 run (error ~1e-9): catches a wrong stage,
    # sign or forcing time. Tolerances are the methods' own error sizes at dt = 0.01
    # over 4 s on these rotations and librations, with a ~2-7x margin: measured 6
    # (Euler: no accuracy here, but finite), 0.05 (order 2), 1.5e-6 (order >= 4).
    # (Maxima over steps, e.g. tension_max, also carry a sampling error of the step
    # grid, ~1e-2 at dt = 0.01, so they are not compared.)
    fine = sweep.run(scene, grid, **{**kwargs, "dt": 0.0025, "method": "rk4", "observe": EVERY})
    atol = {1: 20.0, 2: 0.1}.get(METHODS[method].order, 1e-5)
    for name in ("theta_final", "omega_final", "energy_final"):
        np.testing.assert_allclose(ds[name], fine[name], rtol=0, atol=atol, err_msg=name)


@pytest.mark.parametrize("method", list(METHODS))
def test_generated_kernels_contain_only_the_scene_terms(method):
    conservative = METHODS[method].conservative_only
    for model, damping, forcing in itertools.product(("nonlinear", "linear"), (False, True),
                                                     (False, True)):
        if conservative and (damping or forcing):
            continue
        spec = _kernels.KernelSpec(model, ("damping",) * damping + ("forcing",) * forcing,
                                   ("final",), method=method)
        text = _kernels.source(spec)
        assert ("vsin(th)" in text) == (model == "nonlinear")
        assert ("vsin(W" in text) == forcing
        assert ("c * om" in text) == damping
        assert "acc_" not in text and "tension" not in text


def test_a_method_by_name_or_by_object_is_the_same_kernel_and_run():
    spec_name = _kernels.KernelSpec("nonlinear", (), ("final",), method="rk38")
    spec_object = _kernels.KernelSpec("nonlinear", (), ("final",),
                                      method=methods.RK38)
    assert spec_name == spec_object and _kernels.build(spec_name) is _kernels.build(spec_object)
    grid = sweep.Grid(theta0=[0.5, 1.5])
    a = sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, method="rk38")
    b = sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, method=methods.RK38)
    assert a.identical(b.assign_attrs(history=a.attrs["history"]))


def test_a_user_tableau_runs_and_equal_data_gives_equal_numbers():
    # RK4 given as floats and under another name: the generator writes the same
    # arithmetic up to the form of the weights, so agreement is to rounding (1e-13 over
    # 100 steps of a state of size ~1)
    mine = ButcherTableau(name="my-rk4", a=((0, 0, 0, 0), (0.5, 0, 0, 0), (0, 0.5, 0, 0),
                                           (0, 0, 1.0, 0)),
                          b=(1 / 6, 1 / 3, 1 / 3, 1 / 6), c=(0, 0.5, 0.5, 1.0), order=4,
                          source="test: classical RK4 as floats")
    grid = sweep.Grid(theta0=[0.5, 1.5])
    a = sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, method=mine)
    b = sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, method="rk4")
    assert a.attrs["method"] == "my-rk4"
    np.testing.assert_allclose(a.theta_final, b.theta_final, rtol=0, atol=1e-13)


# =========================================================================== refusals
REFUSALS = [
    ("verlet with damping", dict(scene=sweep.Scene(effects=(sweep.Damping(0.1),)),
                                 method="verlet"),
     r"method 'verlet' is symplectic and integrates only conservative scenes \(no damping, "
     r"no forcing, no drag, no pivot\), but the scene has damping; accepted: a scene \(and "
     r"grid\) without damping, forcing, drag and pivot, or one of 'euler', 'heun', 'rk4', "
     r"'rk38', 'dopri5'"),
    ("yoshida4 with forcing", dict(scene=sweep.Scene(effects=(sweep.Forcing(1.0, 1.0),)),
                                   method="yoshida4"),
     r"method 'yoshida4' is symplectic .* but the scene has forcing; accepted"),
    ("verlet with both", dict(scene=sweep.Scene(effects=(sweep.Damping(0.1),
                                                         sweep.Forcing(1.0, 1.0))),
                              method=methods.VERLET),
     r"method 'verlet' .* has damping and forcing"),
    ("verlet with a damping axis", dict(grid=dict(theta0=[0.1], damping=[0.0, 0.1]),
                                        method="verlet"),
     r"method 'verlet' is symplectic .* has damping"),
    ("save_every with dopri5", dict(method="dopri5", save_every=10),
     r"save_every = 10 cannot be used with the adaptive method 'dopri5': .*accepted: "
     r"save_every=None, or a fixed-step method \('euler', 'heun', 'rk4'"),
    ("rtol with rk4", dict(rtol=1e-6),
     r"rtol = 1e-06 applies only to adaptive methods \('dopri5'\), but method 'rk4' takes "
     r"fixed steps dt; accepted: rtol=None"),
    ("atol with verlet", dict(method="verlet", atol=1e-6), r"atol = 1e-06 applies only"),
    ("rtol too small", dict(method="dopri5", rtol=1e-17),
     r"rtol must be a finite number >= 2\.22e-14 \(100 machine epsilons\), got 1e-17"),
    ("zero atol", dict(method="dopri5", atol=0.0),
     r"atol must be a finite number > 0 \(rad and rad/s\), got 0\.0"),
    ("nan rtol", dict(method="dopri5", rtol=float("nan")), r"rtol must be .* got nan"),
    ("method object of another type", dict(method=len),
     r"method must be one of 'euler', .*'yoshida4' \(or a sweep\.methods\.ButcherTableau"),
]


@pytest.mark.parametrize("label,kwargs,message", REFUSALS, ids=[r[0] for r in REFUSALS])
def test_methods_that_do_not_fit_are_refused_before_compute(label, kwargs, message,
                                                            no_compute):
    kwargs = dict(kwargs)
    scene = kwargs.pop("scene", sweep.Scene())
    grid = sweep.Grid(**kwargs.pop("grid", dict(theta0=[0.1])))
    with pytest.raises(ValueError, match=message):
        sweep.run(scene, grid, t_end=1.0, dt=0.1, **kwargs)


def test_kernel_spec_refuses_symplectic_with_effects():
    spec = _kernels.KernelSpec("nonlinear", ("damping",), ("final",), method="verlet")
    with pytest.raises(ValueError, match=r"method 'verlet' is symplectic .* kernel spec has "
                                         r"damping"):
        _kernels.source(spec)


def test_symplectic_general_kernel_is_the_conservative_one():
    grid = sweep.Grid(theta0=[0.5, 2.0])
    a = sweep.run(sweep.Scene(), grid, t_end=2.0, dt=0.01, method="verlet")
    b = sweep.run(sweep.Scene(), grid, t_end=2.0, dt=0.01, method="verlet", specialize=False)
    assert a.drop_attrs().identical(b.drop_attrs())


# =========================================================================== orders
W0 = math.sqrt(9.81)
K_HALF = ellipk(0.25)  # libration with k = 0.5: theta_max = 60 degrees
PERIOD = 4.0 * K_HALF / W0  # 2.1529 s
STARTS = dict(theta0=[math.pi / 3, -0.4], omega0=[0.0, 2.5])  # libration, all phases

# Ladders in each method's asymptotic range: dt = T_end / 2^k with the error well above
# round-off (>= 1e-10 at the finest step, so 1e-16 rounding per step over <= 1e5 steps
# stays 1e4 times smaller) and small enough that the next term of the error expansion
# is < ~5% (measured local slopes settle to within 0.05 of the order).
LADDERS = {
    "euler": range(12, 16),
    "heun": range(8, 12),
    "rk4": range(6, 10),
    "rk38": range(6, 10),
    "verlet": range(7, 11),
    "yoshida4": range(5, 9),
}


def _order_on_exact_solution(method, exponents, t_end=2.0, floor=1e-10):
    grid = sweep.Grid(**STARTS)
    table = grid.table(sweep.Scene())
    theta_ref, omega_ref = (v[:, 0] for v in exact(sweep.Scene(), table[:, 0], table[:, 1],
                                                   [t_end]))
    dts, errors = [], []
    for k in exponents:
        dt = t_end / 2 ** k
        ds = sweep.run(sweep.Scene(), grid, t_end=t_end, dt=dt, method=method,
                       observe=("final",))
        err = state_error(sweep.Scene(), ds.theta_final.values.ravel(),
                          ds.omega_final.values.ravel(), theta_ref, omega_ref)
        dts.append(dt)
        errors.append(err.max())
    assert min(errors) > floor, "finest step reaches round-off: ladder not asymptotic"
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0]), errors


@pytest.mark.parametrize("method", sorted(LADDERS))
def test_observed_order_is_nominal(method):
    order, errors = _order_on_exact_solution(method, LADDERS[method])
    # +-0.1: the issue's requirement; the ladders are chosen asymptotic (see LADDERS)
    assert abs(order - METHODS[method].order) <= 0.1, (order, errors)


def test_dopri5_weights_are_fifth_order_as_a_fixed_step_method():
    """The propagated solution of the adaptive pair, run at fixed steps, is of order 5
    (the tableau's order conditions say so exactly; this checks the generated code)."""
    d = methods.DOPRI5
    fixed = ButcherTableau(name="dopri5-fixed", a=d.a, b=d.b, c=d.c, order=5,
                           source=d.source)
    # Its error has a large 6th-order term (local slopes 5.8, 5.3, 5.1 from dt = 0.125
    # down over 2 s), so the ladder is taken over 20 s (~9 periods), where the phase
    # error growing linearly in time dominates and the slopes are 5.04, 5.01 at
    # dt = 0.0195 .. 0.0049; the finest error, 7e-11, is 50x above the round-off of
    # ~4000 steps (~1e-12)
    order, errors = _order_on_exact_solution(fixed, range(10, 13), t_end=20.0, floor=1e-11)
    # +-0.1 as for every method
    assert abs(order - 5) <= 0.1, (order, errors)


# =========================================================================== energy
N_LONG = 10 ** 6
DT_LONG = 0.05  # w0 dt = 0.157: 20 steps per small-amplitude period


def _energy_history(scene, method, theta0=(1.0, 2.5)):
    ds = sweep.run(scene, sweep.Grid(theta0=list(theta0)), t_end=N_LONG * DT_LONG,
                   dt=DT_LONG, method=method, save_every=N_LONG // 1000, observe=("energy",))
    th, om = ds.theta.values, ds.omega.values
    w0sq = scene.gravity / scene.length
    pot = w0sq * (1 - np.cos(th)) if scene.model == "nonlinear" else 0.5 * w0sq * th * th
    energy = 0.5 * om * om + pot
    return (energy - energy[:, :1]) / energy[:, :1], ds.time.values


@pytest.mark.parametrize("method", [n for n, m in METHODS.items() if m.conservative_only])
@pytest.mark.parametrize("model", ["nonlinear", "linear"])
def test_symplectic_energy_error_stays_bounded_over_a_million_steps(method, model):
    rel, _ = _energy_history(sweep.Scene(model=model), method)
    tenth = rel.shape[1] // 10
    early, late = np.abs(rel[:, :tenth]).max(axis=1), np.abs(rel[:, -tenth:]).max(axis=1)
    # No secular drift: the oscillation of the energy error over the last 1e5 steps is
    # as large as over the first 1e5, not larger (measured: equal to 3 digits; 5%
    # allows for the sampling of an oscillation every 1000 steps).
    assert np.all(late <= 1.05 * early), (early, late)
    # ...and it is the method's O(dt^p) size: (w0 dt)^p with w0 dt = 0.157 gives 0.025
    # (order 2) and 6e-4 (order 4); measured 0.006 and 5e-5
    assert np.all(early < (W0 * DT_LONG) ** METHODS[method].order)


def test_rk4_energy_drifts_at_its_known_rate_on_the_linear_oscillator():
    """RK4 on x'' = -w^2 x multiplies the scaled state by a normal matrix with
    |R(i w dt)|^2 = (1 - x^2/2 + x^4/24)^2 + (x - x^3/6)^2 = 1 - x^6/72 + x^8/576 per
    step (x = w dt): the energy after n steps is exactly |R|^(2n) times the initial."""
    rel, _ = _energy_history(sweep.Scene(model="linear"), "rk4")
    x = W0 * DT_LONG
    r2 = (1 - x ** 2 / 2 + x ** 4 / 24) ** 2 + (x - x ** 3 / 6) ** 2
    n = np.arange(rel.shape[1]) * (N_LONG // 1000)
    predicted = r2 ** n - 1.0  # -0.185 after 1e6 steps: a clear secular decay
    # 1e-9: rounding of 1e6 steps (~1e6 * 1e-16 relative per step, random-walk and
    # systematic alike stay below 1e-9) on an energy change of 0.18
    np.testing.assert_allclose(rel, np.broadcast_to(predicted, rel.shape), rtol=0, atol=1e-9)
    assert predicted[-1] < -0.18


def test_rk4_energy_drifts_linearly_on_the_nonlinear_pendulum_unlike_verlet():
    rel_rk4, _ = _energy_history(sweep.Scene(), "rk4")
    rel_verlet, _ = _energy_history(sweep.Scene(), "verlet")
    mid = rel_rk4.shape[1] // 2
    # secular drift: the loss at the end is twice the loss at half time (linear in t,
    # to 5%: measured ratio 1.95-2.0), and it dominates the bounded oscillation
    np.testing.assert_allclose(rel_rk4[:, -1] / rel_rk4[:, mid], 2.0, rtol=0.05)
    assert np.all(rel_rk4[:, -1] < -0.05)  # measured -0.14, -0.09: RK4 loses energy
    assert np.all(np.abs(rel_verlet).max(axis=1) < 0.2 * np.abs(rel_rk4[:, -1]))


# =========================================================================== adaptive
def test_dopri5_meets_its_tolerance_against_the_exact_solution():
    grid = sweep.Grid(theta0=[math.pi / 3, 0.3, 3.0], omega0=[0.0, 7.0])  # libration,
    table = grid.table(sweep.Scene())  # near-separatrix libration (k = 0.9975), rotation
    t_end = PERIOD
    theta_ref, omega_ref = (v[:, 0] for v in exact(sweep.Scene(), table[:, 0], table[:, 1],
                                                   [t_end]))
    ratios = []
    for tol in (1e-6, 1e-8, 1e-10, 1e-12):
        ds = sweep.run(sweep.Scene(), grid, t_end=t_end, dt=0.5, method="dopri5", rtol=tol,
                       atol=tol, observe=EVERY_ADAPTIVE)  # the kernel of the tests below
        err = state_error(sweep.Scene(), ds.theta_final.values.ravel(),
                          ds.omega_final.values.ravel(), theta_ref, omega_ref)
        scale = 1.0 + np.maximum(np.abs(theta_ref), np.abs(omega_ref) / W0)
        # Over one period the global error is a sum of ~20-400 local errors each held
        # below tol * scale, which partly cancel: measured err / (tol * scale) <= 7;
        # 20 leaves room without accepting a controller that ignores tol (an order-of-
        # magnitude miss fails)
        ratio = err / (tol * scale)
        assert np.all(ratio < 20.0), (tol, ratio)
        ratios.append(ratio.max())
    # tolerance proportionality: tighter tol, proportionally smaller error (within 10x
    # over six decades)
    assert max(ratios) / min(ratios) < 10.0, ratios


def test_dopri5_steps_per_trajectory_and_hits_t_end_exactly():
    scene = sweep.Scene(effects=(sweep.Damping(0.2), sweep.Forcing(1.2, 2 / 3)))
    # 1.2345 is not a whole number of steps 0.1: an adaptive run does not need it to be
    grid = sweep.Grid(theta0=[0.1, 3.0], omega0=[0.0, 9.0], damping=[0.2, 0.4])
    # every observable dopri5 takes: the kernel of every method's test above
    kw = dict(t_end=1.2345, dt=0.1, method="dopri5", rtol=1e-9, atol=1e-9,
              observe=EVERY_ADAPTIVE)
    ds = sweep.run(scene, grid, **kw)
    steps = ds.steps_accepted.values
    assert steps.min() >= 12  # at least (t_end - t0) / dt_max steps
    assert len(np.unique(steps)) > 1  # each trajectory chose its own steps
    assert ds.attrs["rtol"] == 1e-9 and "n_steps" not in ds.attrs
    # every trajectory alone gives exactly the same numbers: no step is shared
    for idx in [(0, 0, 0), (1, 1, 1)]:
        point = ds.isel(theta0=[idx[0]], omega0=[idx[1]], damping=[idx[2]])
        alone = sweep.run(scene, sweep.Grid(theta0=point.theta0.values,
                                            omega0=point.omega0.values,
                                            damping=point.damping.values), **kw)
        assert alone.drop_attrs().identical(point.drop_attrs())
    # t_end is hit exactly: the final state equals a tight fixed-step RK4 run to t_end
    # (1.2345 = 24690 steps of 5e-5: RK4 error ~1e-16) within the dopri5 tolerance
    # times the ~40 steps taken (global accumulation; measured ~1e-9)
    fine = sweep.run(scene, grid, t_end=1.2345, dt=5e-5, observe=EVERY)  # test_naive's kernel
    np.testing.assert_allclose(ds.theta_final, fine.theta_final, rtol=0, atol=1e-7)


def test_dopri5_observables_update_at_accepted_steps():
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[1.0]), t_end=3 * PERIOD / 2 + 0.1,
                   dt=0.05, t_transient=0.5, method="dopri5", rtol=1e-10, atol=1e-10,
                   observe=EVERY_ADAPTIVE)  # theta_max, amplitude and energy among them
    # libration from rest at 1 rad: the maxima are sampled at accepted steps (no dense
    # output), which never exceed the true amplitude and come within the curvature of
    # theta over half a step of at most 0.05 s: 1.0 * (w0 * 0.025)^2 / 2 ~ 3e-3
    assert 1.0 - 3e-3 <= ds.theta_max.item() <= 1.0 + 1e-9
    assert 1.0 - 3e-3 <= ds.amplitude.item() <= 1.0 + 1e-9
    # energy kept to ~ the tolerance times the number of steps (~100)
    assert abs(ds.energy_final.item() - ds.energy_initial.item()) < 1e-7


def test_dopri5_step_underflow_is_flagged_not_raised():
    # damping 1e300 makes the explicit step stable only for h < ~3e-300: the step size
    # underflows below 16 eps t, which is reported as its own kind of failure
    scene = sweep.Scene(effects=(sweep.Damping(0.1),))
    with pytest.warns(RuntimeWarning,
                      match=r"^1 of 2 trajectories failed \(1 step_underflow\)"):
        ds = sweep.run(scene, sweep.Grid(theta0=[1.0], damping=[0.1, 1e300]), t_end=1.0,
                       dt=0.1, method="dopri5", observe=("final", "theta_max"))
    assert list(ds.status.values.ravel()) == [Status.OK, Status.STEP_UNDERFLOW]
    assert np.isnan(ds.theta_final.values[0, 1]) and np.isnan(ds.theta_max.values[0, 1])
    assert ds.status.attrs["flag_meanings"].split()[Status.STEP_UNDERFLOW] == "step_underflow"
    assert "adaptive step shrank" in ds.status.attrs["comment"]
    assert maps.motion(ds).values[0, 1] == -127  # unresolved in every map


def test_a_blow_up_under_dopri5_is_a_step_underflow_and_under_rk4_non_finite():
    """A torque of 1e306 rad/s^2 spins the pendulum up as theta ~ tau t^2 / 2, past the
    largest double (1.8e308) at t ~ 19 s: the fixed step overflows to inf (non-finite);
    the adaptive step is rejected there and shrinks until it underflows. The two
    failures are told apart."""
    scene = sweep.Scene(effects=(sweep.Torque(1e306),))
    grid = sweep.Grid(theta0=[0.0, 1.0])
    with pytest.warns(RuntimeWarning, match="became non-finite"):
        fixed = sweep.run(scene, grid, t_end=20.0, dt=0.1, observe=("final",))
    assert (fixed.status == Status.NONFINITE).all()
    with pytest.warns(RuntimeWarning, match=r"failed \(2 step_underflow\)"):
        adaptive = sweep.run(scene, grid, t_end=20.0, dt=0.1, method="dopri5",
                             observe=("final",))
    assert (adaptive.status == Status.STEP_UNDERFLOW).all()


def test_observables_on_the_step_grid_are_refused_with_an_adaptive_method(no_compute):
    grid_bound = [name for name, obs in sweep.observables.OBSERVABLES.items()
                  if _kernels.spec.STEP_GRID_NAMES.search(obs.init + obs.update + obs.final)]
    if not grid_bound:
        pytest.skip("no observable samples the fixed step grid")
    name = grid_bound[0]
    obs = sweep.observables.OBSERVABLES[name]
    scene = sweep.Scene(effects=(sweep.Forcing(1.0, 1.0),)) if getattr(
        obs, "requires_forcing", False) else sweep.Scene()
    with pytest.raises(ValueError, match=rf"observable '{name}' is defined on the fixed step "
                                         rf"grid .* adaptive method 'dopri5'"):
        sweep.run(scene, sweep.Grid(theta0=[0.1]), t_end=1.0, dt=0.1, method="dopri5",
                  observe=("final", name))
