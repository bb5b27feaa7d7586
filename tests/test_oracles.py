"""sweep against independent numerical oracles (never against sweep itself).

Oracles: closed forms of the linear model (homogeneous + particular solution, and the
exact RK4 propagator of a linear system), the Jacobi elliptic solution and elliptic
period of the nonlinear pendulum, and scipy's DOP853 at rtol = atol = 1e-12.

How the tolerances are made
---------------------------
RK4's global error at step dt is C dt^4 + O(dt^5). Running the same case at dt and at
dt/2 gives the difference D = y_dt - y_{dt/2} = (1 - 1/16) C dt^4 + ..., so the error of
the dt run is D * 16/15 ~ 1.07 D in the asymptotic regime. Tolerances below are
``2 * max|D|`` (the max over the saved samples of that trajectory): ~1.9 times the
expected error, room for the higher-order terms, yet an error that does not shrink
with dt (a wrong term, sign, parameter or forcing phase) leaves D small and fails at
once. A consistent scheme of lower order would have errors of 1.33 D (order 2) to
2 D (order 1), which this factor alone would not reject: test_convergence_order_is_4
pins the order. To that we add a round-off floor and, for DOP853, the reference's own
error. Every check also asserts that its tolerance is small
(``_assert_resolved``), so no test passes vacuously because the step was too coarse.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk, ellipkm1
from shared_kernels import EVERY

import sweep

ALL_OBSERVE = EVERY  # the kernels of test_naive's runs (tests/shared_kernels.py)
EPS = np.finfo(np.float64).eps


# =========================================================================== helpers
def _roundoff(n_steps, scale):
    """Worst-case round-off of an n-step integration of a state of size ``scale``:
    each RK4 step rounds a handful of operations, each off by <= 1/2 ulp; allowing
    4 eps of ``scale`` per step, added up linearly (no cancellation assumed), bounds
    what floating point alone can do over a non-chaotic run."""
    return 4.0 * n_steps * EPS * scale


def _assert_resolved(tol, cap, what):
    """The tolerance itself must be small: a bound of ``cap`` says the step resolves
    the motion, so that a pass means something."""
    assert np.all(tol < cap), f"{what}: tolerance {np.max(tol):.3g} >= {cap:.3g}; dt too coarse"


def _pair(scene, grid, *, dt, save_every, t_end, t0=0.0, t_transient=0.0):
    """The same run at dt (sampled every ``save_every`` steps) and at dt/2 (sampled at
    the same times), for the RK4 error estimate."""
    kwargs = {"t_end": t_end, "t0": t0, "t_transient": t_transient, "observe": ALL_OBSERVE}
    coarse = sweep.run(scene, grid, dt=dt, save_every=save_every, **kwargs)
    fine = sweep.run(scene, grid, dt=dt / 2, save_every=2 * save_every, **kwargs)
    np.testing.assert_array_equal(coarse["time"].values, fine["time"].values)
    return coarse, fine


def _rk4_bound(coarse, fine, name):
    """2 * max over the samples of |y_dt - y_{dt/2}| per trajectory (see the module
    docstring): ~1.9 times RK4's error at dt."""
    diff = np.abs(coarse[name].values - fine[name].values)
    return 2.0 * diff.max(axis=-1)


def _dop853(theta0, omega0, times, *, model="nonlinear", gravity=9.81, length=1.0,
            damping=0.0, forcing_amplitude=0.0, forcing_frequency=0.0, forcing_phase=0.0,
            rtol=1e-12):
    """Reference trajectory at ``times`` (first entry = start time) by DOP853.

    Returns (theta, omega) arrays and an error allowance for them: the difference to a
    run 10 times tighter (rtol 1e-13), doubled. DOP853's error scales about linearly
    with rtol, so the tighter run is ~10 times more accurate and the difference is
    ~ the error of the rtol run; the factor 2 covers the imperfect scaling.
    """
    w0sq = gravity / length
    restoring = np.sin if model == "nonlinear" else (lambda th: th)

    def f(t, y):
        return (y[1], forcing_amplitude * math.sin(forcing_frequency * t + forcing_phase)
                - damping * y[1] - w0sq * restoring(y[0]))

    times = np.asarray(times, dtype=float)
    solutions = [solve_ivp(f, (times[0], times[-1]), [theta0, omega0], method="DOP853",
                           rtol=r, atol=r, t_eval=times) for r in (rtol, rtol / 10)]
    for s in solutions:
        assert s.success, s.message
    ref, tight = solutions
    allowance = 2.0 * np.abs(ref.y - tight.y).max(axis=1)
    return ref.y[0], ref.y[1], allowance


# ------------------------------------------------------------------ exact solutions
def libration(t, theta0, w0):
    """Exact nonlinear pendulum from rest at theta0 in (0, pi) at t = 0.

    theta(t) = 2 arcsin(k sn(K - w0 t | m)), omega(t) = -2 k w0 cn(K - w0 t | m), with
    k = sin(theta0/2), m = k^2 and K = K(m). At t = 0, sn(K) = 1 and cn(K) = 0; for
    t > 0 the pendulum swings toward theta = 0 (omega < 0); sn has period 4K, so the
    period is 4K/w0. test_elliptic_oracle_solves_the_pendulum checks all of this
    against DOP853. K is computed as ellipkm1(1 - m) with 1 - m = cos^2(theta0/2), which
    keeps its full accuracy as theta0 -> pi (m -> 1).
    """
    k = math.sin(theta0 / 2)
    m = k * k
    big_k = ellipkm1(math.cos(theta0 / 2) ** 2)
    sn, cn, _, _ = ellipj(big_k - w0 * np.asarray(t, dtype=float), m)
    return 2.0 * np.arcsin(k * sn), -2.0 * k * w0 * cn


def libration_period(theta0, w0):
    """T = 4 K(m) / w0 with m = sin^2(theta0/2)."""
    return 4.0 * ellipkm1(math.cos(theta0 / 2) ** 2) / w0


def rotation_period(omega0, w0):
    """Time for one full turn of the undamped pendulum started at theta = 0 with
    |omega0| > 2 w0: with k = |omega0| / (2 w0) > 1, theta = 2 am(k w0 t | 1/k^2), so
    a turn (am advances by pi) takes 2 K(1/k^2) / (k w0)."""
    k = abs(omega0) / (2.0 * w0)
    return 2.0 * ellipk(1.0 / k ** 2) / (k * w0)


def linear_homogeneous(tau, x0, v0, w0, c):
    """x'' + c x' + w0^2 x = 0 from x(0) = x0, x'(0) = v0: (x(tau), x'(tau)).

    Underdamped (c < 2 w0), critical (c = 2 w0) and overdamped (c > 2 w0) closed forms.
    """
    tau = np.asarray(tau, dtype=float)
    gamma = c / 2.0
    disc = w0 * w0 - gamma * gamma
    decay = np.exp(-gamma * tau)
    if disc > 0:  # underdamped (gamma = 0 is the free undamped oscillator)
        wd = math.sqrt(disc)
        a, b = x0, (v0 + gamma * x0) / wd
        cos, sin = np.cos(wd * tau), np.sin(wd * tau)
        x = decay * (a * cos + b * sin)
        v = decay * ((b * wd - gamma * a) * cos - (a * wd + gamma * b) * sin)
    elif disc == 0:  # critical
        a, b = x0, v0 + gamma * x0
        x = decay * (a + b * tau)
        v = decay * (b - gamma * (a + b * tau))
    else:  # overdamped
        s = math.sqrt(-disc)
        r1, r2 = -gamma + s, -gamma - s
        a, b = (v0 - r2 * x0) / (r1 - r2), (r1 * x0 - v0) / (r1 - r2)
        x = a * np.exp(r1 * tau) + b * np.exp(r2 * tau)
        v = a * r1 * np.exp(r1 * tau) + b * r2 * np.exp(r2 * tau)
    return x, v


def linear_solution(t, theta0, omega0, *, w0, c=0.0, A=0.0, W=0.0, phase=0.0, t0=0.0):
    """theta'' + c theta' + w0^2 theta = A sin(W t + phase), theta(t0) = theta0,
    theta'(t0) = omega0: homogeneous + particular solution (W != w0 when c = 0).

    Particular solution P sin(W t + phase) + Q cos(W t + phase): substituting gives
    (w0^2 - W^2) P - c W Q = A and c W P + (w0^2 - W^2) Q = 0, so with
    D = (w0^2 - W^2)^2 + (c W)^2: P = A (w0^2 - W^2) / D, Q = -A c W / D.
    """
    t = np.asarray(t, dtype=float)
    xp0, vp0 = linear_particular(t0, w0=w0, c=c, A=A, W=W, phase=phase)
    xh, vh = linear_homogeneous(t - t0, theta0 - xp0, omega0 - vp0, w0, c)
    xp, vp = linear_particular(t, w0=w0, c=c, A=A, W=W, phase=phase)
    return xh + xp, vh + vp


def linear_particular(t, *, w0, c, A, W, phase):
    """The particular solution P sin(W t + phase) + Q cos(W t + phase) and its
    derivative (see `linear_solution`)."""
    d = (w0 ** 2 - W ** 2) ** 2 + (c * W) ** 2
    p, q = (A * (w0 ** 2 - W ** 2) / d, -A * c * W / d) if A else (0.0, 0.0)
    arg = W * np.asarray(t, dtype=float) + phase
    return p * np.sin(arg) + q * np.cos(arg), W * (p * np.cos(arg) - q * np.sin(arg))


# ====================================================== the oracles check themselves
@pytest.mark.parametrize("degrees", [5, 30, 90, 150, 170, 179])
def test_elliptic_oracle_solves_the_pendulum(degrees):
    """The Jacobi formula (sign convention included) and 4K/w0 against DOP853."""
    w0, theta0 = math.sqrt(9.81), math.radians(degrees)
    period = libration_period(theta0, w0)
    times = np.linspace(0.0, 1.5 * period, 13)
    theta, omega, allowance = _dop853(theta0, 0.0, times)
    exact_theta, exact_omega = libration(times, theta0, w0)
    # DOP853's allowance (measured, ~1e-10 near the separatrix at 179 deg) plus 1e-12
    # for ellipj/arcsin (ellipj agrees with mpmath to ~1e-15 even at m -> 1; arcsin
    # amplifies that by 1/cos(theta0/2) <= 115 at 179 deg)
    np.testing.assert_allclose(exact_theta, theta, rtol=0, atol=allowance[0] + 1e-12)
    np.testing.assert_allclose(exact_omega, omega, rtol=0, atol=allowance[1] + 1e-12)
    # and the textbook limits: the period tends to 2 pi / w0 for small swings, and
    # the formula's quarter points are exact
    if degrees == 5:
        # the series T = T0 (1 + theta0^2/16 + ...): the next term, 11/3072 theta0^4, is
        # 2.1e-7 at 5 deg, so the truncated series is good to ~3e-7 relative
        assert period == pytest.approx(2 * math.pi / w0 * (1 + theta0 ** 2 / 16), rel=3e-7)
    quarter = libration([0.0, period / 4, period / 2], theta0, w0)
    # 1e-12: K and sn/cn at K, 2K, 0 are accurate to ~1e-15 and the arcsin of k sn
    # near sn = +-1 amplifies that by at most 1/cos(theta0/2) ~ 115
    np.testing.assert_allclose(quarter[0], [theta0, 0.0, -theta0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(quarter[1], [0.0, -2 * w0 * math.sin(theta0 / 2), 0.0],
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("c,A", [(0.0, 0.0), (0.7, 0.0), (4.0, 0.0), (9.0, 0.0),
                                 (0.0, 1.3), (0.7, 1.3), (9.0, 1.3)],
                         ids=["free", "underdamped", "critical", "overdamped",
                              "forced-undamped", "forced-underdamped", "forced-overdamped"])
def test_linear_oracle_solves_the_linear_ode(c, A):
    """The closed forms (all three damping regimes, with and without forcing) against
    DOP853; w0 = 2 makes c = 4 exactly critical."""
    w0, W, phase, t0 = 2.0, 2.9, 0.4, 0.3
    times = t0 + np.linspace(0.0, 8.0, 17)
    theta, omega, allowance = _dop853(0.2, -0.5, times, model="linear", gravity=4.0,
                                      damping=c, forcing_amplitude=A, forcing_frequency=W,
                                      forcing_phase=phase)
    exact_theta, exact_omega = linear_solution(times, 0.2, -0.5, w0=w0, c=c, A=A, W=W,
                                               phase=phase, t0=t0)
    # the closed forms are a few roundings (1e-15); DOP853 carries its allowance
    np.testing.assert_allclose(exact_theta, theta, rtol=0, atol=allowance[0] + 1e-13)
    np.testing.assert_allclose(exact_omega, omega, rtol=0, atol=allowance[1] + 1e-13)


# ==================================================== 1. linear model, closed forms
LINEAR_CASES = {
    # name: (damping c, forcing (A, W, phase) or None); w0 = 2
    "free-undamped": (0.0, None),
    "free-underdamped": (0.6, None),
    "free-critical": (4.0, None),
    "free-overdamped": (9.0, None),
    "forced-undamped": (0.0, (1.3, 2.9, 0.4)),
    "forced-underdamped": (0.6, (1.3, 2.9, 0.4)),
    "forced-overdamped": (9.0, (1.3, 0.8, -1.1)),
}


def _linear_scene(c, forcing):
    effects = []
    if c:
        effects.append(sweep.Damping(c))
    if forcing:
        effects.append(sweep.Forcing(*forcing))
    return sweep.Scene(gravity=4.0, length=1.0, model="linear", effects=tuple(effects))


@pytest.mark.parametrize("case", list(LINEAR_CASES))
def test_linear_model_matches_closed_form(case):
    c, forcing = LINEAR_CASES[case]
    scene = _linear_scene(c, forcing)
    grid = sweep.Grid(theta0=[-0.7, 0.3], omega0=[-1.5, 0.0, 2.0])
    t0, dt, t_end = 0.5, 0.01, 10.5  # t0 != 0 exercises the forcing time t0 + n dt
    coarse, fine = _pair(scene, grid, dt=dt, save_every=25, t_end=t_end, t0=t0)
    A, W, phase = forcing if forcing else (0.0, 0.0, 0.0)
    times = coarse["time"].values
    for i, theta0 in enumerate(grid.axes["theta0"]):
        for j, omega0 in enumerate(grid.axes["omega0"]):
            exact_theta, exact_omega = linear_solution(times, theta0, omega0, w0=2.0, c=c,
                                                       A=A, W=W, phase=phase, t0=t0)
            for name, exact in (("theta", exact_theta), ("omega", exact_omega)):
                # RK4 bound (module docstring) + round-off of 1000 steps of |y| <= 5
                tol = _rk4_bound(coarse, fine, name)[i, j] + _roundoff(1000, 5.0)
                # RK4's phase error on an oscillator is w0 t (w0 dt)^4 / 120 = 2.7e-8
                # rad over 10 s at w0 dt = 0.02, times amplitudes <= 2.5: errors
                # <~ 7e-8, so tolerances ~1e-7; 1e-6 would mean an unresolved motion
                _assert_resolved(tol, 1e-6, f"{case} {name}")
                np.testing.assert_allclose(coarse[name].values[i, j], exact, rtol=0,
                                           atol=tol, err_msg=f"{case} {name}")
            final_theta, final_omega = linear_solution(t_end, theta0, omega0, w0=2.0, c=c,
                                                       A=A, W=W, phase=phase, t0=t0)
            tol = max(_rk4_bound(coarse, fine, n)[i, j] for n in ("theta", "omega")) \
                + _roundoff(1000, 5.0)  # same bound as the samples (the final one is one)
            assert coarse["theta_final"].values[i, j] == pytest.approx(final_theta, abs=tol)
            assert coarse["omega_final"].values[i, j] == pytest.approx(final_omega, abs=tol)


@pytest.mark.parametrize("c,W", [(0.6, 2.9), (0.6, 1.0), (1.5, 2.0)],
                         ids=["above-resonance", "below-resonance", "at-resonance"])
def test_linear_forced_steady_amplitude(c, W):
    """After the transient the forced linear oscillator swings with the textbook
    amplitude R = A / sqrt((w0^2 - W^2)^2 + (c W)^2); theta_max and amplitude over
    t >= t_transient must equal the closed form's extremes at the same step times, and
    those are R up to the decayed transient and the sampling of the peaks."""
    A, phase, w0 = 1.3, 0.4, 2.0
    t_transient, t_end, dt = 60.0, 80.0, 0.01
    scene = _linear_scene(c, (A, W, phase))
    grid = sweep.Grid(theta0=[-0.7, 0.3], omega0=[1.5])
    # every step saved, so that the RK4 bound covers every state the maxima see
    coarse, fine = _pair(scene, grid, dt=dt, save_every=1, t_end=t_end,
                         t_transient=t_transient)
    times = coarse["time"].values
    steady = times >= t_transient - 1e-9  # step 6000 is t = 60 exactly
    radius = A / math.sqrt((w0 ** 2 - W ** 2) ** 2 + (c * W) ** 2)
    for i, theta0 in enumerate(grid.axes["theta0"]):
        exact, _ = linear_solution(times[steady], theta0, 1.5, w0=w0, c=c, A=A, W=W,
                                   phase=phase)
        # a max over the same times of values each within d of the exact ones is
        # within d of the exact max: d = RK4 bound + round-off of 8000 steps
        d = _rk4_bound(coarse, fine, "theta")[i, 0] + _roundoff(8000, 2.0)
        _assert_resolved(d, 1e-6, "theta")  # w0 dt = 0.02: RK4 errors ~1e-9 here
        assert coarse["theta_max"].values[i, 0] == pytest.approx(np.abs(exact).max(), abs=d)
        assert coarse["amplitude"].values[i, 0] == pytest.approx(
            0.5 * (exact.max() - exact.min()), abs=d)
        # physics: the homogeneous part e^{-c t/2} (a cos(w_d t) + b sin(w_d t)) is
        # below e^{-c t/2} (|a| + |b|) (<= 5e-8 at t = 60), and a sampled sine misses
        # its peak by at most R (1 - cos(W dt / 2)) <= R (W dt)^2 / 8 (~1e-5)
        xp0, vp0 = linear_particular(0.0, w0=w0, c=c, A=A, W=W, phase=phase)
        w_d = math.sqrt(w0 ** 2 - c ** 2 / 4)
        a, b = theta0 - xp0, (1.5 - vp0 + c / 2 * (theta0 - xp0)) / w_d
        transient = math.exp(-c * t_transient / 2) * (abs(a) + abs(b))
        sampling = radius * (W * dt) ** 2 / 8
        amplitude = coarse["amplitude"].values[i, 0]
        assert radius - sampling - transient - d <= amplitude <= radius + transient + d


def _rk4_polynomial(z):
    """RK4 applied to y' = lambda y multiplies y by P(h lambda) each step, with P the
    degree-4 Taylor polynomial of exp."""
    return 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24


@pytest.mark.parametrize("c", [0.0, 0.6, 9.0], ids=["undamped", "underdamped", "overdamped"])
def test_linear_free_rk4_equals_its_exact_discrete_solution(c):
    """For a linear system RK4 is exactly y_n = P(h M)^n y_0. M = [[0, 1], [-w0^2, -c]]
    has eigenvalues l1, l2 (roots of l^2 + c l + w0^2) and eigenvectors (1, l), so
    theta_n = a P(h l1)^n + b P(h l2)^n with a + b = theta0, a l1 + b l2 = omega0.
    This closed form of the *discrete* solution needs no error estimate: at a coarse
    step (w0 dt = 0.5) where RK4 is visibly off the true solution, sweep must still
    equal it to round-off."""
    w0, dt, n_steps = 2.0, 0.25, 200
    scene = _linear_scene(c, None)
    grid = sweep.Grid(theta0=[0.9, -0.2], omega0=[1.1, -3.0])
    ds = sweep.run(scene, grid, t_end=n_steps * dt, dt=dt, observe=ALL_OBSERVE,
                   save_every=10)
    l1, l2 = np.roots([1.0, c, w0 * w0]).astype(complex)
    n = np.arange(0, n_steps + 1, 10)
    mu1, mu2 = _rk4_polynomial(dt * l1) ** n, _rk4_polynomial(dt * l2) ** n
    for i, theta0 in enumerate(grid.axes["theta0"]):
        for j, omega0 in enumerate(grid.axes["omega0"]):
            a = (omega0 - l2 * theta0) / (l1 - l2)
            b = theta0 - a
            theta = (a * mu1 + b * mu2).real
            omega = (a * l1 * mu1 + b * l2 * mu2).real
            # round-off only: 200 steps of sweep plus a complex power mu^n (relative
            # error ~ n eps); 1e-12 absolute on states of size <= 3 covers both
            # (_roundoff(200, 3) = 5e-13)
            np.testing.assert_allclose(ds["theta"].values[i, j], theta, rtol=0, atol=1e-12)
            np.testing.assert_allclose(ds["omega"].values[i, j], omega, rtol=0, atol=1e-12)
            if c == 0.0:
                # the undamped RK4 energy shrinks by exactly |P(i w0 dt)|^2 per step
                factor = abs(_rk4_polynomial(1j * w0 * dt)) ** (2 * n_steps)
                e0 = 0.5 * omega0 ** 2 + 0.5 * w0 ** 2 * theta0 ** 2
                assert 0.5 < factor < 0.99  # visibly not conserved: this is RK4's signature
                # relative round-off of the energy after 200 steps (_roundoff, relative)
                assert ds["energy_final"].values[i, j] == pytest.approx(e0 * factor,
                                                                        rel=1e-12)


# ================================================= 2. nonlinear undamped: elliptic
@pytest.mark.parametrize("degrees", [5, 30, 90, 150, 170, 179])
def test_libration_period_is_4K_over_w0(degrees):
    """Integrate exactly one elliptic period T = 4 K(m) / w0 (dt = T / N): the state must
    come back to the start, and pass (0, -w_max), (-theta0, 0), (0, +w_max) at the
    quarter periods.

    Precision this gives on T: if the true period differed by dT, the state at T
    would miss the start by |theta''(0)| dT = w0^2 sin(theta0) dT in omega. The
    tolerances (2e-11 .. 7e-11 up to 170 deg, set by round-off; 1.3e-8 at 179 deg, set
    by RK4's error near the separatrix) therefore pin T to ~1e-11 relative up to
    170 deg and ~1e-8 relative at 179 deg. Landing exactly on T needs no
    interpolation between samples, whose own error (zero crossings of sampled theta or
    omega) would have to be bounded on top of RK4's.
    """
    w0, theta0 = math.sqrt(9.81), math.radians(degrees)
    period = libration_period(theta0, w0)
    n = 4000  # dt = T/4000 in [5e-4, 2e-3] s
    coarse, fine = _pair(sweep.Scene(), sweep.Grid(theta0=[theta0]), dt=period / n,
                         save_every=n // 4, t_end=period)
    w_max = 2 * w0 * math.sin(theta0 / 2)
    expected_theta = [theta0, 0.0, -theta0, 0.0, theta0]
    expected_omega = [0.0, -w_max, 0.0, w_max, 0.0]
    for name, expected in (("theta", expected_theta), ("omega", expected_omega)):
        # RK4 bound + round-off of 4000 steps on states of size <= 2 w0 ~ 6.3
        tol = _rk4_bound(coarse, fine, name)[0] + _roundoff(n, 2 * w0)
        # 1e-7: at 179 deg RK4's error at T/4000 reaches 1.3e-8 (phase error at the
        # fast bottom crossing); below 170 deg tolerances are <~ 1e-10
        _assert_resolved(tol, 1e-7, name)
        np.testing.assert_allclose(coarse[name].values[0], expected, rtol=0, atol=tol,
                                   err_msg=name)
    assert coarse["winding"].values[0] == 0


@pytest.mark.parametrize("degrees", [30, 90, 150, 170, 179])
def test_libration_trajectory_matches_jacobi_elliptic(degrees):
    w0, theta0 = math.sqrt(9.81), math.radians(degrees)
    # 10 s: 1.3 to 5 periods; dt = 2.5e-3 (4000 steps), samples every 0.05 s
    coarse, fine = _pair(sweep.Scene(), sweep.Grid(theta0=[theta0]), dt=2.5e-3,
                         save_every=20, t_end=10.0)
    exact_theta, exact_omega = libration(coarse["time"].values, theta0, w0)
    for name, exact in (("theta", exact_theta), ("omega", exact_omega)):
        # RK4 bound + round-off of 4000 steps + 1e-12 for the elliptic functions
        # (see test_elliptic_oracle_solves_the_pendulum)
        tol = _rk4_bound(coarse, fine, name)[0] + _roundoff(4000, 2 * w0) + 1e-12
        # 1e-6: near the separatrix (179 deg) RK4's error bound at dt = 2.5e-3 is
        # ~2e-7; up to 170 deg it is <= 3e-9
        _assert_resolved(tol, 1e-6, name)
        np.testing.assert_allclose(coarse[name].values[0], exact, rtol=0, atol=tol,
                                   err_msg=name)


@pytest.mark.parametrize("omega0", [7.0, -10.0])
def test_rotation_period_and_unwrapped_angle(omega0):
    """Started at theta = 0 with |omega0| > 2 w0 the pendulum rotates with period
    T_rot = 2 K(1/k^2) / (k w0); after 3.5 turns' time theta = 7 pi sign(omega0)
    (unwrapped), and every half turn the state is (k pi, omega0) or
    (k pi, sign sqrt(omega0^2 - 4 w0^2)) (top: energy omega^2/2 + 2 w0^2)."""
    w0 = math.sqrt(9.81)
    t_rot = rotation_period(omega0, w0)
    n = 2000  # steps per turn: dt = T_rot / 2000 ~ 3.5e-4 .. 6.5e-4 s
    coarse, fine = _pair(sweep.Scene(), sweep.Grid(omega0=[omega0]), dt=t_rot / n,
                         save_every=n // 2, t_end=3.5 * t_rot)
    sign = math.copysign(1.0, omega0)
    top = sign * math.sqrt(omega0 ** 2 - 4 * w0 ** 2)
    expected_theta = sign * math.pi * np.arange(8)
    expected_omega = [omega0 if k % 2 == 0 else top for k in range(8)]
    for name, expected in (("theta", expected_theta), ("omega", expected_omega)):
        # RK4 bound + round-off of 7000 steps on states of size <= 7 pi
        tol = _rk4_bound(coarse, fine, name)[0] + _roundoff(7000, 7 * math.pi)
        # 1e-8: measured bounds are ~1e-11 plus the round-off floor 1.4e-10; theta
        # within 1e-8 at |omega| >= 7 pins the turn time to ~1e-9 s
        _assert_resolved(tol, 1e-8, name)
        np.testing.assert_allclose(coarse[name].values[0], expected, rtol=0, atol=tol,
                                   err_msg=name)
    # 3.5 turns: the tops pi, 3 pi, 5 pi passed and the end on the fourth (to 1e-8),
    # so 3 or 4 passes over the top; test_rotation_winding_counts_the_tops_passed
    # pins the count away from a top
    assert coarse["winding"].values[0] in (sign * 3, sign * 4)


@pytest.mark.parametrize("omega0", [7.0, -10.0])
@pytest.mark.parametrize("turns, tops", [(3.25, 3), (3.75, 4)])
@pytest.mark.parametrize("well", [0, -2, 5])
def test_rotation_winding_counts_the_tops_passed(omega0, turns, tops, well):
    """Started at the bottom of well k (theta0 = 2 pi k) with |omega0| > 2 w0 the
    undamped pendulum is at a top (an odd multiple of pi) at t = (m + 1/2) T_rot
    exactly (u = theta - 2 pi k has u(-t) = -u(t) and u(t + T_rot) = u(t) + 2 pi, so
    u(T_rot / 2) = pi), so by
    t = (3 + 1/4) T_rot it has passed 3 tops and by (3 + 3/4) T_rot 4: winding
    sign(omega0) * 3 and * 4, whatever k. (The net turns there are 3.x: the old
    definition, their integer part, said 3 for both.)"""
    w0 = math.sqrt(9.81)
    t_rot = rotation_period(omega0, w0)
    n = 2000  # steps per turn, as above: theta to ~1e-10, a quarter turn from any top
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[2 * math.pi * well], omega0=[omega0]),
                   t_end=turns * t_rot, dt=t_rot / n, observe=EVERY)  # a shared kernel
    assert ds["winding"].values.item() == math.copysign(tops, omega0)


# ================================================ 3. convergence order of RK4 = 4
def _max_error_elliptic(dt):
    w0, theta0 = math.sqrt(9.81), math.radians(30)
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[theta0]), t_end=10.0, dt=dt,
                   observe=ALL_OBSERVE, save_every=round(0.08 / dt))
    theta, omega = libration(ds["time"].values, theta0, w0)
    return np.max(np.hypot(ds["theta"].values[0] - theta, ds["omega"].values[0] - omega))


def _max_error_linear_forced(dt):
    c, (A, W, phase), t0 = 0.6, (1.3, 2.9, 0.4), 0.5
    scene = _linear_scene(c, (A, W, phase))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.3], omega0=[-1.5]), t0=t0, t_end=t0 + 10.0,
                   dt=dt, observe=ALL_OBSERVE, save_every=round(0.08 / dt))
    theta, omega = linear_solution(ds["time"].values, 0.3, -1.5, w0=2.0, c=c, A=A, W=W,
                                   phase=phase, t0=t0)
    return np.max(np.hypot(ds["theta"].values[0, 0] - theta,
                           ds["omega"].values[0, 0] - omega))


@pytest.mark.parametrize("error_of,dt_max", [(_max_error_elliptic, 0.02),
                                              (_max_error_linear_forced, 0.04)],
                         ids=["nonlinear-30deg-elliptic", "linear-damped-forced-closed-form"])
def test_convergence_order_is_4(error_of, dt_max):
    """Slope of log(max error over 10 s) vs log(dt) for 5 halvings of dt from dt_max.

    The ranges (w0 dt <= 0.08): the dt^5 terms are a few percent of the dt^4 term at
    the coarsest step, and the smallest error (~4e-11 for the linear case at dt =
    0.0025, ~8e-11 for the elliptic one at dt = 0.00125) is still > 100 times the
    round-off of those runs (~sqrt(n) eps |y| ~ 1e-13 for n <= 8000 steps, |y| <= 6),
    so neither end bends the line. 30 deg is used for the nonlinear case because at
    large amplitudes the dt^4 coefficient of the pendulum's error nearly vanishes and
    dt^5, dt^6 terms dominate down to much smaller steps. The forced case makes the
    forcing time enter: evaluating the forcing at other times than t_n, t_n + dt/2,
    t_n + dt drops the order to 1 or 2.
    """
    dts = dt_max / 2.0 ** np.arange(5)
    errors = np.array([error_of(dt) for dt in dts])
    # 1e-11: 100 times the typical round-off (see above): the fit sees truncation only
    assert errors.min() > 1e-11, errors
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    # +-0.1 (the required precision): measured slopes are within 0.03 of 4; 0.1 still
    # separates 4 from 3 and 5 unambiguously
    assert abs(slope - 4.0) <= 0.1, (slope, errors)


# ============================================= 4. nonlinear runs against DOP853
DOP853_CASES = {
    # name: (scene, theta0 values, omega0 values, t_end)
    # the classic chaotic driven pendulum (w0 = 1, q = 2, A = 1.2, W = 2/3): over
    # 20 s (about two forcing periods) RK4's error at dt = 0.01 is still ~1e-8
    "chaotic-driven": (sweep.Scene(gravity=1.0, length=1.0,
                                   effects=(sweep.Damping(0.5),
                                            sweep.Forcing(amplitude=1.2, frequency=2 / 3))),
                       [-2.0, 0.2, 3.0], [0.0, 1.0], 20.0),
    "damped-large-angle": (sweep.Scene(effects=(sweep.Damping(0.3),)),
                           [math.radians(170), 3.1], [0.0], 10.0),
    "damped-rotating": (sweep.Scene(effects=(sweep.Damping(0.3),)),
                        [0.0, -1.0], [10.0, -12.0], 10.0),
    "forced-undamped-rotating": (sweep.Scene(effects=(sweep.Forcing(2.0, 1.7, 0.5),)),
                                 [0.5], [8.0], 10.0),
}


_ORACLE_PARAMETERS = ("damping", "forcing_amplitude", "forcing_frequency", "forcing_phase",
                      "length", "gravity")


def _parameters(scene):
    """The scene's parameters that the DOP853 oracle's equation has (damping, forcing)."""
    p = scene.parameters()
    return dict(model=scene.model, **{name: p[name] for name in _ORACLE_PARAMETERS})


@pytest.mark.parametrize("case", list(DOP853_CASES))
def test_nonlinear_runs_match_dop853(case):
    scene, thetas, omegas, t_end = DOP853_CASES[case]
    grid = sweep.Grid(theta0=thetas, omega0=omegas)
    coarse, fine = _pair(scene, grid, dt=0.01, save_every=50, t_end=t_end)
    times = coarse["time"].values
    for i, theta0 in enumerate(thetas):
        for j, omega0 in enumerate(omegas):
            theta, omega, allowance = _dop853(theta0, omega0, times, **_parameters(scene))
            bounds = {}
            for k, (name, ref) in enumerate((("theta", theta), ("omega", omega))):
                # RK4 bound at dt = 0.01 (5e-9 .. 3e-6 here, measured by the dt/2
                # run) + DOP853's allowance (~1e-11) + round-off of 2000 steps
                tol = (_rk4_bound(coarse, fine, name)[i, j] + allowance[k]
                       + _roundoff(2000, 30.0))
                # 1e-5: RK4 at dt = 0.01 on these motions (|omega| <= 12) errs by
                # <~ 3e-6; more would mean the comparison says little
                _assert_resolved(tol, 1e-5, f"{case} {name}")
                np.testing.assert_allclose(coarse[name].values[i, j], ref, rtol=0, atol=tol,
                                           err_msg=f"{case} {name} start {theta0, omega0}")
                bounds[name] = tol
            # the final-state observables are the last sample
            assert coarse["theta_final"].values[i, j] == pytest.approx(theta[-1],
                                                                       abs=bounds["theta"])
            assert coarse["omega_final"].values[i, j] == pytest.approx(omega[-1],
                                                                       abs=bounds["omega"])


@pytest.mark.parametrize("case", ["chaotic-driven", "damped-large-angle", "damped-rotating"])
def test_steady_observables_match_dop853_with_transient(case):
    """theta_max, amplitude, tension extremes over t >= t_transient and the final energy
    and winding, recomputed from the DOP853 trajectory at the same step times.

    A max (or min) over the same set of times of values that each differ by <= e
    differs by <= e; with state error <= (d_theta, d_omega), |d|theta|| <= d_theta,
    |d tension| <= g d_theta + 2 L |omega| d_omega and
    |d energy| <= (g/L) d_theta + |omega| d_omega (first order; second order is < 1e-12).
    """
    scene, thetas, omegas, t_end = DOP853_CASES[case]
    t_transient, dt = 4.0, 0.01
    grid = sweep.Grid(theta0=thetas, omega0=omegas)
    # save every step, so that the RK4 bound covers every state the maxima see
    coarse, fine = _pair(scene, grid, dt=dt, save_every=1, t_end=t_end,
                         t_transient=t_transient)
    times = coarse["time"].values
    steady = times >= t_transient - 1e-9  # step 400 is t = 4 exactly (0.01 * 400)
    g, length = scene.gravity, scene.length
    for i, theta0 in enumerate(thetas):
        for j, omega0 in enumerate(omegas):
            theta, omega, allowance = _dop853(theta0, omega0, times, **_parameters(scene))
            d_theta = (_rk4_bound(coarse, fine, "theta")[i, j] + allowance[0]
                       + _roundoff(times.size, 30.0))
            d_omega = (_rk4_bound(coarse, fine, "omega")[i, j] + allowance[1]
                       + _roundoff(times.size, 30.0))
            _assert_resolved(np.array([d_theta, d_omega]), 1e-5, case)
            w = np.max(np.abs(omega)) + d_omega
            th_s, om_s = theta[steady], omega[steady]
            tension = length * om_s ** 2 + g * np.cos(th_s)
            d_tension = g * d_theta + 2 * length * w * d_omega
            expected = {
                "theta_max": (np.max(np.abs(th_s)), d_theta),
                "amplitude": (0.5 * (th_s.max() - th_s.min()), d_theta),
                "tension_min": (tension.min(), d_tension),
                "tension_max": (tension.max(), d_tension),
                "energy_initial": (0.5 * omega0 ** 2 + g / length * (1 - math.cos(theta0)),
                                   1e-14 * (1 + w * w)),  # same formula: a few ulp
                "energy_final": (0.5 * omega[-1] ** 2 + g / length * (1 - math.cos(theta[-1])),
                                 g / length * d_theta + w * d_omega),
            }
            for name, (value, tol) in expected.items():
                assert coarse[name].values[i, j] == pytest.approx(value, abs=tol), \
                    f"{case} {name} start {theta0, omega0}"
            # wells crossed: the end's well index minus the start's (round half to
            # even, as the kernel; theta0 is the grid's value, the same float in both)
            end = theta[-1] / (2 * math.pi)
            assert abs(abs(end - round(end)) - 0.5) > 1e-6  # far from a top
            assert coarse["winding"].values[i, j] == round(end) - round(theta0 / (2 * math.pi))


# ==================================================== 5. energy and tension
def _libration_run(model, theta0, dt):
    w0 = math.sqrt(9.81)
    period = libration_period(theta0, w0) if model == "nonlinear" else 2 * math.pi / w0
    t_end = dt * math.ceil(1.25 * period / dt)  # past a bottom and the far turning point
    scene = sweep.Scene(model=model)
    coarse, fine = _pair(scene, sweep.Grid(theta0=[theta0]), dt=dt, save_every=1,
                         t_end=t_end)
    return coarse, fine


@pytest.mark.parametrize("model", ["nonlinear", "linear"])
@pytest.mark.parametrize("degrees", [30, 90, 150, 170])
def test_undamped_libration_energy_tension_and_extremes(model, degrees):
    """Undamped swing from rest at theta0.

    Energy: E0 = (g/L) V(theta0) is conserved; RK4 changes it by at most
    |grad E| * (state error), with grad E = ((g/L) V'(theta), omega).

    Tension: on the exact orbit T = 2 L E0 - 2 g + 3 g cos(theta) (nonlinear) or
    2 L E0 - g theta^2 + g cos(theta) (linear), both decreasing in |theta|: minimum
    g cos(theta0) at the turning points, maximum at the bottom, g (3 - 2 cos theta0)
    (nonlinear) or g (1 + theta0^2) (linear). Off the exact orbit the same identity
    holds with E(y_n) in place of E0, so each state's tension is off by 2 L dE.
    Sampling: the initial state is a turning point, so the minimum is attained
    exactly; the bottom is crossed between two steps, and since |theta'| <= w_max the
    nearest step has |theta| <= w_max dt / 2, where T'' >= -3 g, so the sampled
    maximum is low by at most 3 g (w_max dt / 2)^2 / 2 = 3 g w_max^2 dt^2 / 8.
    theta_max is theta0 (the initial state); the far turning point -theta0 is missed by
    at most |theta''| (dt/2)^2 / 2 = (g/L) V'(theta0) dt^2 / 8, which bounds the
    amplitude's shortfall, and energy drift dE moves a turning point by
    dE / ((g/L) V'(theta0)).
    """
    g, length, dt = 9.81, 1.0, 1e-3
    w0sq = g / length
    theta0 = math.radians(degrees)
    coarse, fine = _libration_run(model, theta0, dt)
    n_steps = coarse.sizes["time"] - 1
    if model == "nonlinear":
        e0 = w0sq * (1 - math.cos(theta0))
        slope = w0sq * math.sin(theta0)            # (g/L) V'(theta0)
        w_max = 2 * math.sqrt(w0sq) * math.sin(theta0 / 2)
        t_max = g * (3 - 2 * math.cos(theta0))
    else:
        e0 = 0.5 * w0sq * theta0 ** 2
        slope = w0sq * theta0
        w_max = math.sqrt(w0sq) * theta0
        t_max = g * (1 + theta0 ** 2)
    t_min = g * math.cos(theta0)

    # energy error of any state: |grad E| <= (g/L) * max(1, |theta|) + w_max, times
    # the RK4 bound; plus the round-off of the energy formula and of n_steps steps
    grad = w0sq * max(1.0, theta0) + w_max
    d_energy = (grad * max(_rk4_bound(coarse, fine, "theta")[0],
                           _rk4_bound(coarse, fine, "omega")[0])
                + _roundoff(n_steps, e0) + _roundoff(n_steps, grad * max(theta0, w_max)))
    # 1e-8: dt = 1e-3 makes RK4's energy error ~1e-12 .. 1e-10 for these swings
    _assert_resolved(d_energy, 1e-8, "energy")

    # energy_initial is the formula at the start: a few ulp of E0
    assert coarse["energy_initial"].values[0] == pytest.approx(e0, rel=1e-14)
    assert coarse["energy_final"].values[0] == pytest.approx(e0, abs=d_energy)

    d_tension = 2 * length * d_energy
    sampling_bottom = 3 * g * w_max ** 2 * dt ** 2 / 8
    tension_min = coarse["tension_min"].values[0]
    tension_max = coarse["tension_max"].values[0]
    # 1e-14 * g: the initial state's tension L*0 + g cos(theta0) is a single cos, so
    # the observed minimum is at most that (to an ulp or two)
    assert t_min - d_tension <= tension_min <= t_min + 1e-14 * g
    assert t_max - sampling_bottom - d_tension <= tension_max <= t_max + d_tension
    # the sampling bound must be small for this to check anything: at dt = 1e-3 it is
    # <= 3.2e-4 m/s^2 (linear model at 170 deg, w_max = 9.3 rad/s) against a maximum
    # tension of 12 to 97 m/s^2, i.e. < 1e-5 of it
    assert sampling_bottom < 1e-5 * t_max

    d_turn = d_energy / slope  # energy error moves a turning point by dE / V'
    sampling_turn = slope * dt ** 2 / 8
    assert theta0 <= coarse["theta_max"].values[0] <= theta0 + d_turn
    assert theta0 - sampling_turn / 2 - d_turn <= coarse["amplitude"].values[0] \
        <= theta0 + d_turn
