"""The new effects (`Torque`, `QuadraticDrag`, `PivotDrive`) against physics.

Every expected value here comes from outside sweep: closed forms (the locked
equilibrium, Melnikov's retrapping torque, Kapitza's threshold, the quadratic-drag
envelope), SciPy (DOP853 Floquet multipliers, Mathieu characteristic values) or the
slow pure-Python reference `naive.py`. Each tolerance says why it has its size.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from shared_kernels import EVERY

import sweep
from sweep import kernels, maps, toml_spec
from sweep.kernels import KernelSpec

import naive

scipy_integrate = pytest.importorskip("scipy.integrate")
scipy_special = pytest.importorskip("scipy.special")


# ============================================================== constant torque
# g/L = 1 1/s^2 throughout: the dimensionless washboard theta'' + c theta' + sin theta = tau
UNIT = dict(gravity=1.0, length=1.0)


def test_locked_state_exists_only_below_g_over_l():
    """Rest at sin(theta*) = tau L/g exists only for tau < g/L. Starting 0.05 rad from
    where that rest would be (the nearest point for tau >= 1), with c = 0.5, the
    pendulum settles there for tau < 1 and runs away for tau > 1.

    tau = 0.98 is 2 % below the saddle-node: the well between theta* = 1.37 and the
    saddle pi - theta* = 1.77 is still 0.4 rad wide, so a start 0.05 rad from the bottom
    of it with no speed stays in it (damping only lowers the energy). Its slowest mode
    decays at about cos(theta*)/c = 0.4 1/s, so after 100 s the angle is at rest to
    exp(-40): 1e-6 rad bounds it with room for the RK4 error (dt = 0.05, ~1e-8).
    tau = 1.02: no rest exists; the bottleneck passage takes ~ pi/sqrt(tau - 1) ~ 22 s,
    so 200 s give several turns (omega_mean > 0.1 rad/s, the running state's mean
    speed being ~ tau/c = 2 rad/s)."""
    locked, running = [0.3, 0.7, 0.98], [1.02, 1.3]
    scene = sweep.Scene(**UNIT, effects=(sweep.Damping(0.5), sweep.Torque(0.5)))
    for tau in locked:
        start = math.asin(tau) + 0.05
        ds = sweep.run(scene, sweep.Grid(theta0=[start], omega0=[0.0], torque=[tau]),
                       t_end=200.0, dt=0.05, t_transient=100.0,
                       observe=("final", "omega_mean"))
        assert abs(float(ds.theta_final.squeeze()) - math.asin(tau)) < 1e-6, tau
        assert abs(float(ds.omega_final.squeeze())) < 1e-6, tau
        assert int(maps.motion(ds).squeeze()) == 0, tau
    ds = sweep.run(scene, sweep.Grid(theta0=[math.pi / 2 + 0.05], omega0=[0.0],
                                     torque=running),
                   t_end=200.0, dt=0.05, t_transient=100.0, observe=("omega_mean",))
    assert np.all(ds.omega_mean.values > 0.1)
    assert np.all(maps.motion(ds).values == 1)


def test_retrapping_torque_tends_to_melnikov_value():
    """From a fast running start (omega0 = 3 rad/s, above the running orbit, which it
    therefore cannot cross), the pendulum keeps running iff a running orbit exists,
    i.e. iff tau > tau_r. For small damping Melnikov's method gives tau_r = 4 c
    sqrt(g/L) / pi (Strogatz sec. 8.5: 4 alpha / pi) = 0.0637 at c = 0.05.

    Tolerance: the Melnikov value is the first term of an expansion in c; the next term
    is O(c^2) absolute, i.e. O(c) = 5 % relative at c = 0.05, so we allow c * tau_r,
    plus the torque grid step (0.001). Runs: the energy relaxes at rate ~ c, so 600 s
    (30 / c) of transient leave the running/locked decision settled; near tau_r the
    orbit's period grows only logarithmically."""
    c = 0.05
    tau_r = 4.0 * c / math.pi
    taus = np.round(np.linspace(0.050, 0.080, 31), 6)
    scene = sweep.Scene(**UNIT, effects=(sweep.Damping(c), sweep.Torque(0.05)))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.0], omega0=[3.0], torque=taus),
                   t_end=800.0, dt=0.05, t_transient=600.0, observe=("omega_mean",))
    running = maps.motion(ds).values.ravel() == 1
    # a single switch from locked to running along the torque axis
    assert not running[0] and running[-1]
    switch = int(np.argmax(running))
    assert np.all(running[switch:]) and not np.any(running[:switch])
    found = 0.5 * (taus[switch - 1] + taus[switch])
    assert abs(found - tau_r) <= c * tau_r + 0.001, (found, tau_r)
    # the running state's mean speed is ~ tau / c (the damping balances the torque)
    # well above tau_r: 0.08 / 0.05 = 1.6 rad/s, to within the O(1/omega^2) ripple
    # of the washboard (here <~ 20 %)
    assert abs(float(ds.omega_mean.values.ravel()[-1]) - taus[-1] / c) < 0.2 * taus[-1] / c


def test_motion_from_omega_mean_or_final_alone_on_a_torque_scene():
    """tau = +-0.5 with c = 0.05 (g/L = 1): running states exist (|tau| > tau_r = 0.064)
    and locked states too (|tau| < 1). From rest at theta = 0 the potential -cos theta -
    tau theta is -1, below its value at the saddle pi - asin(0.5) (-0.44): locked. From
    omega0 = 3 rad/s in the torque's sense (energy above the running orbit): running in
    that sense. Both maps must say so, from either variable alone."""
    scene = sweep.Scene(**UNIT, effects=(sweep.Damping(0.05), sweep.Torque(0.5)))
    grid = sweep.Grid(theta0=[0.0], omega0=[0.0, 3.0, -3.0], torque=[0.5, -0.5])
    expected = np.array([[0, 0], [1, 0], [0, -1]])  # (omega0, torque)
    # omega0 = 3 against tau = -0.5 and -3 against +0.5 decelerate and get trapped
    # (they start above the running orbit of the *other* sense only after reversing,
    # which damping forbids); the tests below only use the unambiguous cells
    known = np.array([[True, True], [True, False], [False, True]])
    for observe in (("omega_mean",), ("final",)):
        ds = sweep.run(scene, grid, t_end=300.0, dt=0.05, t_transient=200.0,
                       observe=observe)
        got = maps.motion(ds).values[0]
        np.testing.assert_array_equal(got[known], expected[known], err_msg=str(observe))


def test_torque_is_conservative_for_symplectic_methods():
    """Verlet and Yoshida4 accept a torque (it derives from the potential -tau theta):
    without damping E = omega^2/2 + (g/L)(1 - cos theta) - tau theta is conserved up to
    the method's error, which must shrink at its order (2 and 4) when dt is halved.
    The rotating start accelerates to 17 rad/s by t = 50 s (omega dt up to 0.17), so
    the absolute errors are bounded loosely (2e-3, 1e-5; measured 1.0e-3, 1.6e-6) and
    the ratio checks the order (4 and 16, within [3, 5] and [10, 22]). A wrong torque
    term (sign, missing, applied once per step) leaves an O(tau theta) = O(1) error that
    does not shrink."""
    tau = 0.3
    scene = sweep.Scene(**UNIT, effects=(sweep.Torque(tau),))
    grid = sweep.Grid(theta0=[0.5], omega0=[0.0, 2.5])

    def energy(th, om):
        return om ** 2 / 2 + (1 - np.cos(th)) - tau * th

    for method, tol, ratio in (("verlet", 2e-3, (3, 5)), ("yoshida4", 1e-5, (10, 22))):
        errors = []
        for dt in (0.01, 0.005):
            # final and winding: test_methods' symplectic kernel with a torque term
            ds = sweep.run(scene, grid, t_end=50.0, dt=dt, observe=("final", "winding"),
                           method=method)
            e0 = energy(0.5, ds.omega0.values)
            e1 = energy(ds.theta_final.values[0], ds.omega_final.values[0])
            errors.append(abs(e1[1] - e0[1]))
            assert np.all(np.abs(e1 - e0) < tol), (method, dt, e1 - e0)
        assert ratio[0] < errors[0] / errors[1] < ratio[1], (method, errors)


# ================================================================= pivot drive
def test_kapitza_threshold_for_the_inverted_pendulum():
    """Kapitza: with a fast vertical pivot drive the top is stable iff a nu > sqrt(2 g L)
    (leading order in w0/nu). g = 9.81, L = 1, nu = 20 w0 and 40 w0.

    Tolerance +-5 % in a: the next-order correction is that of Mathieu's a_0(q) =
    -q^2/2 + 7 q^4/128 (q = 2 a/L ~ 0.07-0.15 here), a shift of 7 q^2/128 < 0.2 % in a.
    The rest of the margin is for the finite run: at 0.95 x threshold the top is a
    saddle of the averaged potential with growth rate sqrt(1 - 0.95^2) w0 - c/2 ~ 0.9
    1/s, so a start 0.1 rad from the top leaves the 0.5 rad tolerance within ~2 s of
    the 10 s transient; at 1.05 x the averaged well around the top has frequency
    ~ 0.32 w0 and its edge at arccos(1/1.05^2) = 0.43 rad (> 0.1), and c = 0.2 damps
    the slow swing. psi = 0 and omega0 = 0 start without the fast micromotion's speed
    (it is ~ (a nu / L) sin(nu t) theta)."""
    g, L, c = 9.81, 1.0, 0.2
    w0 = math.sqrt(g / L)
    threshold = math.sqrt(2 * g * L)
    ratios = np.array([0.8, 0.95, 1.05, 1.3])
    for nu in (20 * w0, 40 * w0):
        scene = sweep.Scene(gravity=g, length=L,
                            effects=(sweep.Damping(c), sweep.PivotDrive(0.05, nu)))
        period = 2 * math.pi / nu
        dt = period / 64
        ds = sweep.run(scene, sweep.Grid(theta0=[math.pi - 0.1], omega0=[0.0],
                                         pivot_amplitude=ratios * threshold / nu),
                       t_end=round(20.0 / dt) * dt, dt=dt, t_transient=10.0,
                       observe=("top_distance",))
        up = maps.inverted(ds, tolerance=0.5).values.ravel()
        np.testing.assert_array_equal(up, ratios > 1, err_msg=f"nu = {nu / w0:g} w0")


def _floquet_multipliers(c, w0sq, a_over_l, nu):
    """Multipliers of theta'' + c theta' + (w0^2 - (a nu^2/L) cos(nu t)) theta = 0 over
    one drive period: eigenvalues of the fundamental matrix (SciPy DOP853)."""
    def rhs(t, y):
        k = w0sq - a_over_l * nu * nu * math.cos(nu * t)
        return [y[1], -c * y[1] - k * y[0], y[3], -c * y[3] - k * y[2]]

    sol = scipy_integrate.solve_ivp(rhs, (0.0, 2 * math.pi / nu), [1.0, 0.0, 0.0, 1.0],
                                    method="DOP853", rtol=1e-12, atol=1e-12)
    m = sol.y[:, -1].reshape(2, 2).T
    return np.linalg.eigvals(m)


def test_damped_mathieu_bounded_versus_growing_matches_floquet():
    """Linear model, c = 0.1, g/L = 1: the largest Floquet multiplier |mu| decides
    growing (> 1) versus decaying (< 1). Over the t = 150 s before the steady window
    an amplitude changes by |mu|^(t nu / 2 pi); the points kept are those where that
    factor is > 100 or < 1/100, far from the tongue edges, so that sweep's theta_max
    over the window, relative to theta0 = 1, is unambiguous: > 1 (growing) or < 1
    (decaying) allows a transient (non-normal) factor of up to 100 either way."""
    c, t_transient, t_end = 0.1, 150.0, 200.0
    amplitudes = np.array([0.05, 0.15, 0.3, 0.45])
    frequencies = np.array([0.9, 1.4, 1.8, 2.0, 2.2, 2.8, 3.5])
    growth = np.empty((amplitudes.size, frequencies.size))
    for i, a in enumerate(amplitudes):
        for j, nu in enumerate(frequencies):
            mu = np.max(np.abs(_floquet_multipliers(c, 1.0, a, nu)))
            growth[i, j] = math.log(mu) * t_transient * nu / (2 * math.pi)
    decisive = np.abs(growth) > math.log(100.0)
    assert np.sum(decisive & (growth > 0)) >= 3 and np.sum(decisive & (growth < 0)) >= 3
    scene = sweep.Scene(**UNIT, model="linear",
                        effects=(sweep.Damping(c), sweep.PivotDrive(0.1, 2.0)))
    ds = sweep.run(scene, sweep.Grid(theta0=[1.0], omega0=[0.0], pivot_amplitude=amplitudes,
                                     pivot_frequency=frequencies),
                   t_end=t_end, dt=0.01, t_transient=t_transient, observe=("theta_max",))
    theta_max = ds.theta_max.values[0, 0]
    np.testing.assert_array_equal((theta_max > 1.0)[decisive], (growth > 0)[decisive])


def test_undamped_mathieu_first_tongue_edges_against_scipy():
    """theta'' + (w0^2 - (a nu^2/L) cos(nu t)) theta = 0 is Mathieu's y'' + (A - 2 q
    cos 2s) y = 0 with s = nu t/2, A = 4 w0^2/nu^2, q = 2 a/L. The first tongue (period-2
    parametric resonance, nu ~ 2 w0) is unstable for b_1(q) < A < a_1(q).

    Points 15 % of the tongue's width inside and outside each edge. Inside, the Floquet
    exponent (per unit s) is at least ~ q sqrt(0.15) / 2 ~ 0.04 (q = 0.2) and 0.08
    (q = 0.4): over the 300 s before the steady window (s ~ 300) theta grows by > e^12,
    so theta_max > 100 theta0 is unambiguous. Outside, solutions are bounded
    quasi-periodic; their modulation grows like 1/sqrt(distance to the edge) but stays
    a small factor at 15 % of the width: theta_max < 10 theta0. RK4 at dt = 0.01
    changes amplitudes by (w dt)^6 / 144 per step, ~ 1e-11 over the run."""
    w0 = 1.0
    for q in (0.2, 0.4):
        a = q / 2  # L = 1
        lower = scipy_special.mathieu_b(1, q)
        upper = scipy_special.mathieu_a(1, q)
        width = upper - lower
        cases = {lower + 0.15 * width: True, upper - 0.15 * width: True,
                 lower - 0.15 * width: False, upper + 0.15 * width: False}
        big_a = np.array(sorted(cases))
        nus = 2 * w0 / np.sqrt(big_a)
        scene = sweep.Scene(**UNIT, model="linear", effects=(sweep.PivotDrive(a, 2.0),))
        ds = sweep.run(scene, sweep.Grid(theta0=[1.0], omega0=[0.0], pivot_frequency=nus),
                       t_end=400.0, dt=0.01, t_transient=300.0, observe=("theta_max",))
        theta_max = ds.theta_max.values.ravel()
        for value, A in zip(theta_max, big_a):
            if cases[A]:
                assert value > 100.0, (q, A, value)
            else:
                assert value < 10.0, (q, A, value)


def test_tension_with_a_moving_pivot_from_the_saved_trajectory():
    """T/m = L theta'^2 + (g - a nu^2 cos(nu t + psi)) cos theta evaluated on the saved
    trajectory (every step) over the steady window: its min and max must be the
    kernel's. Tolerance 1e-12 relative to the largest |T/m|: the same states, and cos
    evaluated by libm here and by sweep's polynomial (a few ulp)."""
    g, L, a, nu, psi = 9.81, 0.8, 0.03, 25.0, 0.7
    scene = sweep.Scene(gravity=g, length=L,
                        effects=(sweep.Damping(0.1), sweep.PivotDrive(a, nu, psi)))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.3, 2.9], omega0=[0.0, 4.0]), t_end=4.0,
                   dt=0.002, t0=0.3, t_transient=1.0, observe=("tension",), save_every=1)
    t = ds.time.values
    steady = t >= 0.3 + 1.0 - 1e-9
    for index in np.ndindex(2, 2):
        th, om = ds.theta.values[index][steady], ds.omega.values[index][steady]
        tension = L * om ** 2 + (g - a * nu ** 2 * np.cos(nu * t[steady] + psi)) * np.cos(th)
        scale = np.max(np.abs(tension))
        assert abs(float(ds.tension_min.values[index]) - tension.min()) <= 1e-12 * scale
        assert abs(float(ds.tension_max.values[index]) - tension.max()) <= 1e-12 * scale
        # the pivot's acceleration matters here: without it the extremes differ by O(a nu^2)
        without = L * om ** 2 + g * np.cos(th)
        assert abs(without.max() - tension.max()) > 0.1 * a * nu ** 2


# ============================================================== quadratic drag
def test_quadratic_drag_small_angle_envelope():
    """theta'' = -w0^2 theta - k theta'|theta'| (linear model): averaging over a swing
    gives A' = -(4 / 3 pi) k w0 A^2, so A(t) = A0 / (1 + (4 / 3 pi) k w0 A0 t).

    The amplitude is read as sqrt(theta^2 + theta'^2/w0^2) (exact for the undamped
    swing). Averaging is exact to first order in eps = k A0 (the small parameter: drag
    over restoring force); its error, both the ripple within a swing and the slow drift,
    is O(eps) relative. eps = 0.05 here, so 2 eps = 10 % bounds it; the checked decay
    is much larger (A falls to ~ 1/3 by t = 100 s) and a wrong coefficient (a missing
    factor 2, |theta'| dropped) misses by far more."""
    k, a0, w0 = 0.5, 0.1, 1.0
    scene = sweep.Scene(**UNIT, model="linear", effects=(sweep.QuadraticDrag(k),))
    ds = sweep.run(scene, sweep.Grid(theta0=[a0], omega0=[0.0]), t_end=100.0, dt=0.01,
                   observe=("final",), save_every=100)
    t = ds.time.values
    amp = np.hypot(ds.theta.values.ravel(), ds.omega.values.ravel() / w0)
    envelope = a0 / (1 + 4 / (3 * math.pi) * k * w0 * a0 * t)
    for when in (25.0, 50.0, 100.0):
        i = int(np.argmin(np.abs(t - when)))
        assert abs(amp[i] - envelope[i]) <= 2 * k * a0 * envelope[i], (when, amp[i])
    assert envelope[-1] < 0.35 * a0   # the decay is real, not within the tolerance


def test_quadratic_drag_nonlinear_against_dop853():
    """Nonlinear pendulum with drag, damping, torque and a large swing, against SciPy's
    DOP853 (rtol = atol = 1e-12). RK4 at dt = 0.005 over 20 s: the global error is
    ~ C dt^4 ~ 1e-8 for these frequencies; the drag term is only C^1 at theta' = 0, which
    lowers the order of the step across each turning point (a local error O(k dt^3 *
    |theta''|) ~ 1e-7 per crossing, a dozen crossings). 1e-5 rad bounds both; a wrong
    sign or a missing |.| is off by O(1)."""
    g, L, k, c, tau = 9.81, 1.0, 0.3, 0.05, 0.2
    w0sq = g / L

    def rhs(t, y):
        return [y[1], -w0sq * math.sin(y[0]) - c * y[1] + tau - k * y[1] * abs(y[1])]

    starts = [(2.5, 1.0), (-0.5, 7.0)]
    scene = sweep.Scene(gravity=g, length=L, effects=(sweep.Damping(c), sweep.Torque(tau),
                                                      sweep.QuadraticDrag(k)))
    for th0, om0 in starts:
        ref = scipy_integrate.solve_ivp(rhs, (0.0, 20.0), [th0, om0], method="DOP853",
                                        rtol=1e-12, atol=1e-12)
        ds = sweep.run(scene, sweep.Grid(theta0=[th0], omega0=[om0]), t_end=20.0, dt=0.005,
                       observe=("final",))
        assert abs(float(ds.theta_final.squeeze()) - ref.y[0, -1]) < 1e-5
        assert abs(float(ds.omega_final.squeeze()) - ref.y[1, -1]) < 1e-5


# ====================================================== against the naive loop
NAIVE_OBSERVE = EVERY  # tests/shared_kernels.py
NAIVE_SCALARS = ("theta_final", "omega_final", "theta_max", "amplitude", "omega_mean",
                 "tension_min", "tension_max", "energy_initial", "energy_final",
                 "top_distance_max")

NAIVE_SCENES = {
    "torque": (sweep.Torque(0.7),),
    "drag": (sweep.QuadraticDrag(0.4),),
    "pivot": (sweep.PivotDrive(0.05, 14.0, 0.3),),
    "all": (sweep.Damping(0.2), sweep.Forcing(0.8, 1.3, 0.2), sweep.Torque(-0.4),
            sweep.QuadraticDrag(0.15), sweep.PivotDrive(0.04, 11.0, -1.0)),
}


NAIVE_CASES = [("torque", "nonlinear"), ("drag", "nonlinear"), ("pivot", "nonlinear"),
               ("all", "nonlinear"), ("all", "linear")]


@pytest.mark.parametrize("name,model", NAIVE_CASES, ids=[f"{n}-{m}" for n, m in NAIVE_CASES])
def test_each_effect_equals_naive_rk4(name, model):
    """Every fixed observable against the pure-Python RK4 of `naive.py`, which states
    the new terms independently. Same scheme and time convention, so only rounding may
    differ: 1e-12 * (1 + scale) as in `test_naive.py` (500 steps; ~ulp per operation)."""
    scene = sweep.Scene(gravity=9.0, length=1.2, model=model, effects=NAIVE_SCENES[name])
    grid = sweep.Grid(theta0=[-2.5, 1.0], omega0=[0.5, -4.0])
    kw = dict(t_end=5.7, dt=0.01, t0=0.7, t_transient=1.234)
    ds = sweep.run(scene, grid, observe=NAIVE_OBSERVE, **kw)
    params = scene.parameters()
    for index in np.ndindex(grid.shape):
        th0, om0 = grid.axes["theta0"][index[0]], grid.axes["omega0"][index[1]]
        ref = naive.integrate(th0, om0, model=model, **params, **kw)
        scale = (np.max(np.abs(ref["theta_all"])) + np.max(np.abs(ref["omega_all"]))
                 + abs(ref["tension_max"]) + abs(ref["tension_min"])
                 + abs(ref["energy_initial"]) + abs(ref["energy_final"]))
        for var in NAIVE_SCALARS:
            np.testing.assert_allclose(ds[var].values[index], ref[var], rtol=0,
                                       atol=1e-12 * (1 + scale), err_msg=f"{name} {var}")


def test_new_parameter_axes_reach_the_kernel():
    """torque, drag and the three pivot parameters as grid axes (two values each): each
    trajectory must read its own row (against naive.py, round-off tolerance)."""
    scene = sweep.Scene(gravity=9.81, length=1.0,
                        effects=(sweep.Torque(0.1), sweep.QuadraticDrag(0.1),
                                 sweep.PivotDrive(0.02, 10.0)))
    grid = sweep.Grid(theta0=[0.4], omega0=[1.5], torque=[-0.6, 0.9], drag=[0.0, 0.5],
                      pivot_amplitude=[0.01, 0.06], pivot_frequency=[8.0, 17.0],
                      pivot_phase=[0.0, 2.0])
    kw = dict(t_end=2.0, dt=0.01, t_transient=0.5)
    ds = sweep.run(scene, grid, observe=("final", "tension", "top_distance"), **kw)
    names = list(grid.axes)
    for index in np.ndindex(grid.shape):
        point = {n: float(grid.axes[n][k]) for n, k in zip(names, index)}
        params = {**scene.parameters(), **point}
        th0, om0 = params.pop("theta0"), params.pop("omega0")
        ref = naive.integrate(th0, om0, model="nonlinear", **params, **kw)
        scale = np.max(np.abs(ref["omega_all"])) + abs(ref["tension_max"]) + 10
        for var in ("theta_final", "omega_final", "tension_min", "tension_max",
                    "top_distance_max"):
            np.testing.assert_allclose(ds[var].values[index], ref[var], rtol=0,
                                       atol=1e-12 * scale, err_msg=f"{point} {var}")


def test_a_drag_axis_alone_switches_drag_on():
    """Like damping, drag has one parameter: a grid axis gives all of it. k = 0 keeps the
    undamped energy (RK4, 5 s, dt = 0.01: drift ~1e-9); k = 1 dissipates most of it
    (a swing of 2 rad loses a fraction ~ (4/3pi) k A w0 t >> 1 by averaging)."""
    # omega_mean too: the kernel of the drag-only run below
    ds = sweep.run(sweep.Scene(), sweep.Grid(drag=[0.0, 1.0], theta0=[2.0]), t_end=5.0,
                   dt=0.01, observe=("omega_mean", "energy"))
    assert ds.attrs["effects"] == "drag"
    lost = (ds.energy_initial - ds.energy_final).values.ravel()
    assert abs(lost[0]) < 1e-7 and lost[1] > 0.5 * float(ds.energy_initial.values.ravel()[1])


def test_stability_guard_bounds_the_speed_by_drag_under_torque():
    """Drag's stiffness 2 k |theta'| needs a bound on the speed over the run. Under a
    torque the starts' energy is no bound: tau = 100, k = 1 drive the pendulum to the
    terminal speed sqrt(tau / k) = 10 rad/s (the energy bound from rest says 6.3), where
    RK4's real stability limit 2.785 / (2 k 10) is 0.14 s. dt = 0.2 passed the old
    guard; it is now refused, and integrating anyway gives a finite but wrong rotation
    (the oracle: the mean speed sqrt(tau / k) up to the gravity term's second-order
    effect, ((g/L) / tau)^2 ~ 1 %, hence the 2 % tolerance); the accepted step gets it."""
    scene = sweep.Scene(effects=(sweep.Torque(100.0), sweep.QuadraticDrag(1.0)))
    grid = sweep.Grid(theta0=[0.0, 1.0])
    kwargs = dict(t_end=24.0, t_transient=12.0, observe=("omega_mean",))
    with pytest.raises(ValueError, match=r"dt = 0\.2 exceeds RK4's stability limit 0\.13"):
        sweep.run(scene, grid, dt=0.2, **kwargs)
    wrong = sweep.run(scene, grid, dt=0.2, check_stability=False, **kwargs)
    right = sweep.run(scene, grid, dt=0.1, **kwargs)
    np.testing.assert_allclose(right.omega_mean, 10.0, rtol=0.02)
    assert (abs(wrong.omega_mean - 10.0) > 1.0).all()
    # without a force the energy bound (smaller than the terminal speed) still holds
    # (energy too: the kernel of test_a_drag_axis_alone_switches_drag_on)
    sweep.run(sweep.Scene(effects=(sweep.QuadraticDrag(1.0),)), grid, dt=0.2,
              **{**kwargs, "observe": ("omega_mean", "energy")})


# ================================================================== bad input
NAN, INF = float("nan"), float("inf")

BAD_EFFECTS = [
    (lambda: sweep.Torque(NAN), ValueError, r"Torque\.value must be a finite number, got nan"),
    (lambda: sweep.Torque(INF), ValueError, r"Torque\.value must be a finite number, got inf"),
    (lambda: sweep.Torque("1"), TypeError, r"Torque\.value must be a finite number, got '1'"),
    (lambda: sweep.Torque(True), TypeError, r"Torque\.value .* got True"),
    (lambda: sweep.QuadraticDrag(-0.1), ValueError,
     r"QuadraticDrag\.coefficient must be a finite number >= 0 \(1/rad\), got -0\.1"),
    (lambda: sweep.QuadraticDrag(NAN), ValueError, r"QuadraticDrag\.coefficient .* got nan"),
    (lambda: sweep.QuadraticDrag(None), TypeError, r"QuadraticDrag\.coefficient .* got None"),
    (lambda: sweep.PivotDrive(-0.01, 10.0), ValueError,
     r"PivotDrive\.amplitude must be a finite number >= 0 \(m\), got -0\.01"),
    (lambda: sweep.PivotDrive(0.01, -10.0), ValueError,
     r"PivotDrive\.frequency must be a finite number >= 0 \(rad/s\), got -10\.0"),
    (lambda: sweep.PivotDrive(INF, 10.0), ValueError, r"PivotDrive\.amplitude .* got inf"),
    (lambda: sweep.PivotDrive(0.01, NAN), ValueError, r"PivotDrive\.frequency .* got nan"),
    (lambda: sweep.PivotDrive(0.01, 10.0, phase=INF), ValueError,
     r"PivotDrive\.phase must be a finite number, got inf"),
    (lambda: sweep.PivotDrive(0.01, 10.0, phase="0"), TypeError,
     r"PivotDrive\.phase .* got '0'"),
]


@pytest.mark.parametrize("call,exception,message", BAD_EFFECTS,
                         ids=[str(i) for i in range(len(BAD_EFFECTS))])
def test_bad_effect_parameters_are_refused(call, exception, message):
    with pytest.raises(exception, match=message):
        call()


PIVOT_SCENE = sweep.Scene(effects=(sweep.PivotDrive(0.01, 10.0),))
TORQUE_SCENE = sweep.Scene(effects=(sweep.Torque(0.5),))
BAD_RUNS = [
    ("negative drag axis", sweep.Scene(effects=(sweep.QuadraticDrag(0.1),)),
     dict(drag=[0.1, -0.2]), {}, ValueError,
     r"grid axis 'drag' has value -0\.2 at index 1; accepted: finite numbers >= 0 \(1/rad\)"),
    ("nan torque axis", TORQUE_SCENE, dict(torque=[0.1, NAN]), {}, ValueError,
     r"grid axis 'torque' has non-finite value nan at index 1; accepted: finite numbers"),
    ("negative pivot amplitude axis", PIVOT_SCENE, dict(pivot_amplitude=[-0.01]), {},
     ValueError, r"grid axis 'pivot_amplitude' has value -0\.01 at index 0; accepted: "
     r"finite numbers >= 0 \(m\)"),
    ("inf pivot frequency axis", PIVOT_SCENE, dict(pivot_frequency=[INF]), {}, ValueError,
     r"grid axis 'pivot_frequency' has non-finite value inf at index 0; accepted: finite numbers"),
    ("torque axis without the effect", sweep.Scene(), dict(torque=[0.1]), {}, ValueError,
     r"grid axis 'torque' needs a torque in the scene.*accepted: add sweep\.Torque\(value\)"),
    ("pivot axis without the effect", sweep.Scene(), dict(pivot_frequency=[10.0]), {},
     ValueError, r"grid axis 'pivot_frequency' needs a pivot in the scene.*sweep\.PivotDrive\("),
    ("verlet with drag", sweep.Scene(effects=(sweep.QuadraticDrag(0.1),)), {},
     dict(method="verlet"), ValueError, r"symplectic.*drag"),
    ("yoshida4 with pivot", PIVOT_SCENE, {}, dict(method="yoshida4"), ValueError,
     r"symplectic.*pivot"),
    ("drag axis with verlet", sweep.Scene(), dict(drag=[0.1]), dict(method="verlet"),
     ValueError, r"symplectic.*drag"),
]


@pytest.mark.parametrize("label,scene,axes,kwargs,exception,message", BAD_RUNS,
                         ids=[c[0] for c in BAD_RUNS])
def test_bad_runs_are_refused_before_compute(label, scene, axes, kwargs, exception, message,
                                             no_compute):
    with pytest.raises(exception, match=message):
        sweep.run(scene, sweep.Grid(theta0=[0.1], **axes), t_end=1.0, dt=0.01, **kwargs)


def test_toml_accepts_the_new_tables_and_axes():
    spec = {
        "scene": {"gravity": 9.81, "length": 1.0,
                  "torque": {"value": 0.3}, "drag": {"coefficient": 0.1},
                  "pivot": {"amplitude": 0.02, "frequency": 50.0, "phase": 0.5}},
        "grid": {"theta0": [3.0], "torque": [0.1, 0.2], "drag": {"values": [0.0, 0.2]},
                 "pivot_amplitude": {"start": 0.01, "stop": 0.03, "num": 3},
                 "pivot_frequency": 60.0,
                 "pivot_phase": {"values": [0, 90], "units": "deg"}},
        "run": {"t_end": 1.0, "dt": 0.01},
    }
    scene, grid, run_kwargs = toml_spec.parse_run(spec)
    assert sweep.Torque(0.3) in scene.effects and sweep.QuadraticDrag(0.1) in scene.effects
    assert sweep.PivotDrive(0.02, 50.0, 0.5) in scene.effects
    np.testing.assert_allclose(grid.axes["pivot_phase"], [0.0, math.pi / 2], rtol=1e-15)
    np.testing.assert_allclose(grid.axes["pivot_amplitude"], [0.01, 0.02, 0.03])
    assert run_kwargs["t_end"] == 1.0


@pytest.mark.parametrize("table,key", [("torque", "tau"), ("drag", "k"),
                                       ("pivot", "amplitud")])
def test_toml_refuses_unknown_keys_in_the_new_tables(table, key):
    good = {"torque": {"value": 0.3}, "drag": {"coefficient": 0.1},
            "pivot": {"amplitude": 0.02, "frequency": 50.0}}
    good[table] = {**good[table], key: 1.0}
    spec = {"scene": good, "grid": {"theta0": [0.1]}, "run": {"t_end": 1.0, "dt": 0.01}}
    with pytest.raises(ValueError, match=rf"scene\.{table}: unknown key\(s\) '{key}'; accepted: "):
        toml_spec.parse_run(spec)


def test_toml_refuses_a_negative_drag_axis():
    spec = {"scene": {"drag": {"coefficient": 0.1}}, "grid": {"drag": [-1.0]},
            "run": {"t_end": 1.0, "dt": 0.01}}
    with pytest.raises(ValueError, match=r"drag"):
        toml_spec.parse_run(spec)


# ======================================================= only the scene's terms
@pytest.mark.parametrize("model", ["nonlinear", "linear"])
def test_kernel_has_an_effects_term_only_when_the_scene_has_it(model):
    all_names = ("torque", "drag", "pivot")
    for mask in range(8):
        names = tuple(n for bit, n in enumerate(all_names) if mask >> bit & 1)
        text = kernels.source(KernelSpec(model, names, ("final", "tension")))
        assert ("+ tau" in text) == ("torque" in names), names
        assert ("kd * om * abs(om)" in text) == ("drag" in names), names
        assert ("p * " in text) == ("pivot" in names), names
        assert ("vcos(nu" in text) == ("pivot" in names), names
        assert ("a * nu * nu" in text) == ("pivot" in names), names  # tension and drive
