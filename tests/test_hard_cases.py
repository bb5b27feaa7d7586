"""Hard cases, each checked against the physics that says what the right answer is.

Oracles: `sweep.accuracy.exact` (Jacobi elliptic functions for the undamped pendulum,
closed forms for the linear model), the separatrix's closed form
``theta = 4 arctan(exp(w t)) - pi``, SciPy's elliptic K and DOP853 at ``rtol = 1e-12``,
and RK4's stability polynomial ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``. Every
tolerance says why it is that size; "measured" numbers are from this machine.
"""

import math
import warnings

import numpy as np
import pytest
from shared_kernels import EVERY

import sweep
from sweep import accuracy, maps, stability
from sweep.kernels import Status

special = pytest.importorskip("scipy.special")
integrate = pytest.importorskip("scipy.integrate")

EPS = np.finfo(np.float64).eps
UNIT = sweep.Scene(gravity=1.0, length=1.0)  # w = sqrt(g/L) = 1 rad/s


def R(z):
    """RK4's stability polynomial (amplification of y' = lambda y per step, z = dt lambda)."""
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def _one(ds, name):
    return float(ds[name].values.ravel()[0])


def _dop853(rhs, y0, t_end, t_eval=None):
    sol = integrate.solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-12,
                              atol=1e-12, t_eval=t_eval)
    assert sol.success
    return sol.y


# ----------------------------------------------------------------- the separatrix
@pytest.mark.parametrize("k,tolerance", [
    # sensitivity of theta(T) to the RK4 local error grows like the period's dT/dE,
    # ~ 1/(1 - k^2): measured 1.3e-13 (k = 0.999) and 6.1e-11 (k = 1 - 1e-9) with
    # 40,000 steps per period; the tolerances allow 10x that
    (0.999, 2e-12),
    (1 - 1e-9, 6e-10),
])
def test_near_separatrix_libration_has_the_elliptic_period(k, tolerance):
    theta0 = 2 * math.asin(k)  # at rest at the turning point theta_max = 2 arcsin k
    m = math.sin(theta0 / 2) ** 2  # k^2 of the rounded start
    period = 4 * special.ellipk(m)  # SciPy's K, independent of sweep.accuracy
    ds = sweep.run(UNIT, sweep.Grid(theta0=[theta0]), t_end=period, dt=period / 40_000,
                   observe=EVERY, save_every=4_000)  # (test_oracles' kernel)
    # after exactly one period it is back at the turning point, at rest
    assert abs(_one(ds, "theta_final") - theta0) < tolerance
    assert abs(_one(ds, "omega_final")) < tolerance
    # In between it follows the Jacobi-elliptic motion, but there the timing matters:
    # near the separatrix the period T = 4 K(m)/w is ill-conditioned, dT/dE = 1/(w (1 - m))
    # (E in units of g/L), so an energy error dE (RK4's and round-off's) shifts the phase
    # by t/T * dT, i.e. theta and omega by up to 2 w dE t / (w (1 - m) T) (speed <= 2 w).
    # With the measured dE of the samples that bound is ~5e-6 for k = 1 - 1e-9 (measured
    # error 7e-8); at the turning points the error is second order, hence the period check
    # above can be that much tighter. (DOP853 at rtol 1e-13 is off by 1e-5 here: same cause.)
    t = ds.time.values
    th, om = accuracy.exact(UNIT, theta0, 0.0, t)
    theta, omega = ds.theta.values[0], ds.omega.values[0]
    energy = omega**2 / 2 + 2 * np.sin(theta / 2) ** 2
    d_energy = max(np.max(np.abs(energy - 2 * m)), EPS)
    bound = tolerance + 2 * 2 * d_energy / (1 - m) * t / period  # 2x margin
    assert np.all(np.abs(theta - th[0]) <= bound)
    assert np.all(np.abs(omega - om[0]) <= bound)
    # libration: no turn, labelled 0; energy 2 k^2 (g/L) kept to RK4's O(dt^5) drift per
    # period (measured 1.2e-14 and 5e-15; 1e-12 is far below the 2e-9 gap to the
    # separatrix energy 2 for k = 1 - 1e-9)
    assert int(ds.winding.values.ravel()[0]) == 0
    assert int(maps.motion(ds).values.ravel()[0]) == 0
    assert abs(_one(ds, "energy_final") - _one(ds, "energy_initial")) < 1e-12
    assert _one(ds, "energy_final") < 2.0


def test_separatrix_start_follows_the_closed_form_then_stays_bounded():
    """theta0 = 0, omega0 = 2 w: the exact motion creeps up to the upright position,
    theta(t) = 4 arctan(exp(w t)) - pi -> pi, and never arrives.

    The upright is a saddle with eigenvalues +-w, so any error is amplified like
    exp(w t): RK4 (dt = 0.01) errs by ~1e-11 exp(w t) (measured 1.6e-9 at t = 5, 2.4e-7
    at t = 10, 3.5e-5 at t = 15: a factor e^5 = 148 per 5 s). The bound
    3e-11 exp(w t) holds it to that law with a margin of 3.
    """
    ds = sweep.run(UNIT, sweep.Grid(theta0=[0.0], omega0=[2.0]), t_end=60.0, dt=0.01,
                   observe=EVERY, save_every=100)  # (test_oracles' kernel)
    t = ds.time.values
    theta, omega = ds.theta.values[0, 0], ds.omega.values[0, 0]
    exact = 4 * np.arctan(np.exp(t)) - np.pi
    early = t <= 15.0
    # before the saddle dominates (t < 3 s) the error is RK4's ordinary accumulated
    # local error, ~1e-10 at dt = 0.01 (measured 1.2e-10 at t = 1): hence the 2e-10
    assert np.all(np.abs(theta - exact)[early] <= 2e-10 + 3e-11 * np.exp(t[early]))
    assert theta[early][-1] > np.pi - 1e-4  # it did climb to within 1e-4 of the top
    # RK4's |R(i y)| = 1 - y^6/144 + ... < 1 takes energy out: the numerical energy
    # sits just below the separatrix energy 2 (measured 2 - 9.9e-11 at t = 60), so the
    # computed motion is a libration: it falls back and never turns over. Its energy
    # error is of RK4's size (y = w dt = 0.01: the drift is ~1e-10, far from 1e-8).
    energy = omega**2 / 2 + (1 - np.cos(theta))
    assert np.all(np.abs(energy - 2.0) < 1e-8)
    assert _one(ds, "energy_final") < 2.0
    assert np.all(np.abs(theta) < np.pi)  # never over the top
    assert int(ds.winding.values.ravel()[0]) == 0
    assert int(maps.motion(ds).values.ravel()[0]) == 0


@pytest.mark.parametrize("excess", [1e-3, 1e-6])
def test_rotation_just_above_the_separatrix_turn_time_and_sense(excess):
    """omega0 = 2 w (1 + excess) from the bottom: one turn takes 2 K(1/k^2) / (k w) with
    k = omega0 / (2 w) > 1 (and half a turn reaches the top)."""
    omega0 = 2.0 * (1 + excess)
    k = omega0 / 2.0
    turn = 2 * special.ellipk(1 / k**2) / k  # 8.98 s and 15.9 s
    n = 20_000  # steps per turn
    for sense in (1, -1):
        ds = sweep.run(UNIT, sweep.Grid(theta0=[0.0], omega0=[sense * omega0]),
                       t_end=3.5 * turn, dt=turn / n, observe=("final", "winding", "energy"))
        # after 3.5 turns it is upright: theta = 7 pi. The error is RK4's, amplified by
        # the slow passage past the top (measured 1.9e-11 and 5.2e-8 after 3 turns);
        # 1e-6 is still far below a turn's worth of mistiming.
        assert abs(_one(ds, "theta_final") - sense * 7 * np.pi) < 1e-6
        # the winding counts passes over the top: pi, 3 pi and 5 pi passed, and the end
        # is on the fourth top, 7 pi, to within 1e-6, so 3 or 4 (whichever side of it
        # the computed angle is) in the sense of rotation
        assert int(ds.winding.values.ravel()[0]) in (sense * 3, sense * 4)
        assert int(maps.motion(ds).values.ravel()[0]) == sense
        # energy k^2 * 2 above the separatrix, kept to 1e-12 (measured 7e-14), far less
        # than the 4e-6 (excess 1e-6) that separates it from the separatrix energy
        assert abs(_one(ds, "energy_final") - _one(ds, "energy_initial")) < 1e-12
        assert _one(ds, "energy_final") > 2.0


# ------------------------------------------------------- stability: fast and stiff
def test_rk4_stability_limits_from_its_tableau():
    # b^T (I - zA)^-1 1 from the tableau: the truncated exponential sum z^k/k!, k <= s,
    # for every explicit method whose stage count equals its order
    for name in ("euler", "heun", "rk4", "rk38"):
        method = sweep.methods.METHODS[name]
        expected = [1 / math.factorial(k) for k in range(method.order + 1)]
        np.testing.assert_allclose(stability.stability_polynomial(method), expected,
                                   rtol=1e-15)
    # the classical values: 2.7853 on the negative real axis, 2 sqrt 2 on the imaginary
    assert stability.ray_limit(sweep.methods.RK4, -1.0) == pytest.approx(2.785293563, 1e-9)
    assert stability.ray_limit(sweep.methods.RK4, 1j) == pytest.approx(2 * math.sqrt(2), 1e-12)
    assert stability.ray_limit(sweep.methods.EULER, -1.0) == pytest.approx(2.0, 1e-12)
    assert stability.ray_limit(sweep.methods.EULER, 1j) is None  # |1 + iy| > 1 always
    assert stability.ray_limit(sweep.methods.HEUN, -1.0) == pytest.approx(2.0, 1e-12)
    assert stability.splitting_limit(sweep.methods.VERLET) == pytest.approx(2.0, 1e-12)
    assert stability.splitting_limit(sweep.methods.YOSHIDA4) == pytest.approx(1.5734, 1e-4)
    # at the limit |R| = 1 exactly (the polynomial's root), just inside it is < 1
    assert abs(R(-2.785293563405277)) == pytest.approx(1.0, abs=1e-12)
    assert abs(R(2.8j)) < 1 < abs(R(2.83j))


@pytest.mark.parametrize("y", [2.0, 2.8, 2.82])
def test_linear_oscillation_near_the_imaginary_limit_decays_at_rk4s_rate(y):
    """Linear model, w dt = y just inside RK4's limit 2.828: the energy is a quadratic
    form in which RK4's step is normal, so after n steps it is exactly |R(i y)|^(2n)
    times the start (relative round-off ~ n eps; measured <= 1.7e-12 for n = 1000)."""
    dt, n = 0.01, 1000
    scene = sweep.Scene(model="linear", length=9.81 / (y / dt) ** 2)
    ds = sweep.run(scene, sweep.Grid(theta0=[0.1]), t_end=n * dt, dt=dt, observe=("energy",))
    ratio = _one(ds, "energy_final") / _one(ds, "energy_initial")
    assert ratio == pytest.approx(abs(R(1j * y)) ** (2 * n), rel=1e-10)
    assert ratio <= 1.0


def test_linear_oscillation_beyond_the_limit_is_refused_and_grows_if_forced_through():
    dt, n, y = 0.01, 1000, 2.84
    scene = sweep.Scene(model="linear", length=9.81 / (y / dt) ** 2)
    with pytest.raises(ValueError, match=r"dt = 0\.01 exceeds RK4's stability limit "
                                         r"0\.00996 s .*eigenvalue \+-284i"):
        sweep.run(scene, sweep.Grid(theta0=[0.1]), t_end=n * dt, dt=dt, observe=("energy",))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.1]), t_end=n * dt, dt=dt, observe=("energy",),
                   check_stability=False)
    ratio = _one(ds, "energy_final") / _one(ds, "energy_initial")
    # |R(2.84 i)|^2000 = 1.6e25: the growth the guard exists to prevent, exactly as predicted
    assert ratio == pytest.approx(abs(R(1j * y)) ** (2 * n), rel=1e-10)
    assert ratio > 1e25


@pytest.mark.parametrize("omega_dt,bound", [
    # gravity is a perturbation of relative size (w/omega)^2 of the rotation's kinetic
    # energy; resolved at omega dt below RK4's imaginary-axis limit 2.83, its energy
    # error is a fraction of that (measured 0.02, 0.11 and 0.23 of it at omega dt =
    # 1.0, 2.5, 2.8); bound 0.5
    (1.0, 0.5), (2.5, 0.5), (2.8, 0.5)])
def test_fast_rotation_near_the_limit_stays_close_to_dop853(omega_dt, bound):
    """Fast rotation (omega0 = 100 .. 280 rad/s, dt = 0.01, g = 9.81, L = 1).

    The guard does not refuse it: the variational equation about a fast rotation,
    delta'' = -w^2 cos(omega t) delta, has no eigenvalue near i omega, so omega dt
    is no stability limit, only the resolution of the gravity perturbation (beyond
    omega dt ~ 3 the error exceeds the perturbation itself: measured 18x at omega dt = 10).
    """
    omega0, t_end, w2 = omega_dt / 0.01, 10.0, 9.81
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.0], omega0=[omega0]), t_end=t_end,
                   dt=0.01, observe=("final", "winding", "energy"))  # (the kernel above)
    ref = _dop853(lambda t, s: [s[1], -w2 * math.sin(s[0])], [0.0, omega0], t_end)
    relative = abs(_one(ds, "energy_final") / _one(ds, "energy_initial") - 1)
    assert relative < bound * w2 / omega0**2
    # the angle after ~omega0 t_end rad of travel: off by at most the same relative
    # amount of the distance travelled (the speed error is half the energy error)
    assert abs(_one(ds, "theta_final") - ref[0, -1]) < bound * w2 / omega0**2 * omega0 * t_end
    assert (ds.status == Status.OK).all()


def test_stiff_damping_at_the_limit_is_bounded_and_beyond_it_refused():
    """c = 100 1/s: lambda = -99.90 and -0.098; RK4 needs dt <= 2.7853/99.90 = 0.02788."""
    scene = sweep.Scene(model="linear", effects=(sweep.Damping(100.0),))
    limit = stability.max_stable_step(sweep.methods.RK4, [100.0], [9.81])
    lam = -50 - math.sqrt(2500 - 9.81)
    assert limit.dt == pytest.approx(2.785293563405277 / -lam, rel=1e-12)
    assert limit.eigenvalue.real == pytest.approx(lam, rel=1e-12)
    with pytest.raises(ValueError, match=r"dt = 0\.03 exceeds RK4's stability limit 0\.0279 s"
                                         r" for this scene \(damping c = 100 1/s, g/L = "
                                         r"9\.81 1/s\^2: eigenvalue -99\.9\); accepted: "
                                         r"dt <= 0\.0278"):
        sweep.run(scene, sweep.Grid(theta0=[1.0]), t_end=30.0, dt=0.03, observe=("final",))
    # at the limit the fast mode is amplified by R(dt lambda) = 0.988 per step instead of
    # e^(dt lambda) = 0.06: stable, but slow to decay. From rest at theta0 = 1 the fast
    # mode's share is a2 = lambda_slow theta0 / (lambda_slow - lambda_fast) = -9.8e-4 rad
    # (omega share a2 lambda_fast = 0.098 rad/s); after n = 36 steps RK4 keeps R^n = 0.65
    # of it, where the exact solution keeps nothing, so the error is a2 (R^n - e^(lambda t))
    # in theta and a2 lambda (R^n - e^(lambda t)) in omega (measured 6.4e-4 and 0.064: the
    # slow mode, dt |lambda_slow| = 0.0027, adds only ~1e-12; tolerance 1 % of the error).
    dt, n = 0.0278, 36
    slow = -50 + math.sqrt(2500 - 9.81)
    a2 = slow * 1.0 / (slow - lam)
    kept = R(dt * lam) ** n - math.exp(lam * n * dt)
    ds = sweep.run(scene, sweep.Grid(theta0=[1.0]), t_end=n * dt, dt=dt, observe=("final",))
    th, om = accuracy.exact(scene, 1.0, 0.0, [n * dt])
    assert _one(ds, "theta_final") - th[0, 0] == pytest.approx(a2 * kept, rel=0.01)
    assert _one(ds, "omega_final") - om[0, 0] == pytest.approx(a2 * lam * kept, rel=0.01)
    # beyond it with the guard off: |R(-3.0)| = 1.37 per step; after 1000 steps the fast
    # mode has grown by 1e136 and yet nothing overflows: silent garbage, status "ok".
    # This is what the guard refuses.
    ds = sweep.run(scene, sweep.Grid(theta0=[1.0]), t_end=30.0, dt=0.03, observe=("final",),
                   check_stability=False)
    assert (ds.status == Status.OK).all() and abs(_one(ds, "theta_final")) > 1e100


def test_guard_takes_the_extremes_of_the_grid_and_skips_adaptive_methods():
    scene = sweep.Scene(model="linear")
    grid = sweep.Grid(theta0=[0.1], damping=[0.0, 0.5, 100.0])
    with pytest.raises(ValueError, match=r"damping c = 100 1/s"):
        sweep.run(scene, grid, t_end=0.3, dt=0.03, observe=("final",))
    # dopri5 controls its own step (dt is only its largest step): no limit
    ds = sweep.run(scene, grid, t_end=0.3, dt=0.03, observe=("final",), method="dopri5")
    assert (ds.status == Status.OK).all()
    # a length axis: the shortest pendulum sets the limit (g/L = 9810 -> 2.83/99.05 s)
    with pytest.raises(ValueError, match=r"exceeds RK4's stability limit 0\.0286 s .*"
                                         r"g/L = 9810"):
        sweep.run(scene, sweep.Grid(theta0=[0.1], length=[1.0, 1e-3]), t_end=0.3, dt=0.03)


# ------------------------------------------------------------------ very long runs
def test_linear_energy_decays_at_rk4s_predicted_rate_over_1e7_steps():
    """Undamped linear oscillator, w dt = 0.1, 1e7 steps: E_n / E_0 = |R(0.1 i)|^(2n)
    = (1 - y^6/72 + y^8/576)^n = 0.870476 exactly in exact arithmetic. Round-off: one
    relative eps per step at most, so n eps = 2.2e-9 (measured 1.2e-9); bound 1e-8,
    against a predicted drift of 0.13."""
    n, dt = 10**7, 0.1
    ds = sweep.run(sweep.Scene(gravity=1.0, length=1.0, model="linear"),
                   sweep.Grid(theta0=[0.5]), t_end=n * dt, dt=dt, observe=("energy",))
    ratio = _one(ds, "energy_final") / _one(ds, "energy_initial")
    predicted = abs(R(0.1j)) ** (2 * n)
    assert predicted == pytest.approx(0.8704758372, abs=1e-10)
    assert abs(ratio - predicted) < 1e-8


@pytest.mark.parametrize("amplitude", [0.01, 0.1])
def test_nonlinear_energy_drift_is_steady_and_tends_to_the_linear_rate(amplitude):
    """Nonlinear pendulum, 1e7 steps of w dt = 0.05: the energy decays at a constant
    rate (log E linear in time) equal to the linear one at the softened frequency
    w (1 - a^2/16): the rate scales like (w_eff dt)^6, so the ratio to the linear rate
    is 1 - 3 a^2/8 + O(a^4) (measured 1 - 3.5e-5 at a = 0.01, 1 - 3.5e-3 at a = 0.1
    with dt = 0.1)."""
    n, dt = 10**7, 0.05
    ds = sweep.run(UNIT, sweep.Grid(theta0=[amplitude]), t_end=n * dt, dt=dt,
                   observe=("energy",), save_every=10**6)
    theta, omega = ds.theta.values[0], ds.omega.values[0]
    log_energy = np.log((omega**2 / 2 + 2 * np.sin(theta / 2) ** 2)
                        / (amplitude and 2 * math.sin(amplitude / 2) ** 2))
    t = ds.time.values
    slope, intercept = np.polyfit(t, log_energy, 1)
    # steady: the samples lie on the line to 1e-3 of the total drift (oscillation of
    # the energy error within a period and round-off; the drift is 2.2e-3 in all)
    assert np.max(np.abs(slope * t + intercept - log_energy)) < 1e-3 * abs(log_energy[-1])
    linear_rate = 2 * math.log(abs(R(1j * dt))) / dt
    expected = 1 - 3 * amplitude**2 / 8
    # the O(a^4) term is (a^2)^2 ~ 1e-4 at a = 0.1: tolerance 3e-4 relative plus the
    # fit's share of the within-period oscillation (1e-3 of the drift)
    assert slope / linear_rate == pytest.approx(expected, abs=3e-4 + 1e-3)


def test_forcing_phase_stays_exact_over_1e7_steps():
    """Linear, undamped, non-resonant (w = 1, W = 0.7) started on the particular
    solution A/(w^2 - W^2) sin(W t + phase): the solution is that sine forever.

    With time t0 + n dt the error after 1e7 steps is RK4's O(dt^4) response error
    (measured 7.6e-12 in theta at t0 = 0 and 1.2e-11 at t0 = 1e4). Time accumulated by
    t += dt would be off by 1.4e-5 s after 1e7 additions of 0.01 (np.cumsum), a theta
    error of A W / (w^2 - W^2) * 1.4e-5 = 1.9e-6: the 1e-9 bound tells the two apart.
    """
    amp, freq, phase = 0.1, 0.7, 0.3
    scene = sweep.Scene(gravity=1.0, length=1.0, model="linear",
                        effects=(sweep.Forcing(amp, freq, phase),))
    n, dt = 10**7, 0.01
    for t0 in (0.0, 1.0e4):
        x0 = amp / (1 - freq**2) * math.sin(freq * t0 + phase)
        v0 = amp * freq / (1 - freq**2) * math.cos(freq * t0 + phase)
        ds = sweep.run(scene, sweep.Grid(theta0=[x0], omega0=[v0]), t0=t0, t_end=t0 + n * dt,
                       dt=dt, observe=("final",))
        th, om = accuracy.exact(scene, x0, v0, [t0 + n * dt], t0=t0)
        assert abs(_one(ds, "theta_final") - th[0, 0]) < 1e-9
        assert abs(_one(ds, "omega_final") - om[0, 0]) < 1e-9


# ------------------------------------------------------------------- huge angles
def test_huge_angles_move_like_the_reduced_angle_and_keep_the_winding():
    """|theta0| = 1e4 rad: the same motion as remainder(theta0, 2 pi), shifted by the
    exact multiple of 2 pi. Near 1e4 a double has ulp = 1.8e-12, so every step rounds
    theta (and the argument of sin) by up to ulp/2; over n steps that is n ulp, and the
    energy error it makes shifts a libration's frequency, so the phase error grows up
    to w t times that: bound n ulp (1 + w T) = 5.9e-8 (measured <= 3.5e-9)."""
    theta0 = np.array([1e4, -1e4, 1e4 + 0.5])
    reduced = np.array([math.remainder(x, 2 * math.pi) for x in theta0])
    shift = theta0 - reduced  # an exact multiple of 2 pi up to the rounding of 1e4
    np.testing.assert_allclose(shift / (2 * np.pi), np.round(shift / (2 * np.pi)),
                               rtol=0, atol=np.spacing(1e4))
    n, dt = 1000, 0.01
    w = math.sqrt(9.81)
    tolerance = n * np.spacing(1e4) * (1 + w * n * dt)
    for omega0 in (0.5, 7.0):  # a libration and a rotation (7 > 2 w = 6.26)
        kwargs = {"t_end": n * dt, "dt": dt, "observe": ("final", "winding", "energy")}
        huge = sweep.run(sweep.Scene(), sweep.Grid(theta0=theta0, omega0=[omega0]), **kwargs)
        small = sweep.run(sweep.Scene(), sweep.Grid(theta0=reduced, omega0=[omega0]), **kwargs)
        a, b = huge.theta_final.values[:, 0], small.theta_final.values[:, 0]
        assert np.all(np.abs(a - b - shift) < tolerance)
        assert np.all(np.abs(huge.omega_final.values - small.omega_final.values) < tolerance)
        np.testing.assert_array_equal(huge.winding.values, small.winding.values)
        # energy depends on cos theta only: the same to the same budget (times w^2)
        assert np.all(np.abs(huge.energy_final.values - small.energy_final.values)
                      < w**2 * tolerance)
    # the rotation turns 12.4 to 12.9 times in 10 s; the start at remainder(-1e4, 2 pi)
    # = +2.83 rad, 0.31 rad below the top at +pi and going up, passes it at once: 13
    # passes over the top, the other two starts 12
    np.testing.assert_array_equal(huge.winding.values[:, 0], [12, 13, 12])


def test_inverted_start_stays_put_until_round_off_tips_it():
    """theta0 = pi (the double): sin(pi) = 1.2246e-16, not 0, so gravity pulls with
    (g/L) 1.2e-16. While the angle increment dt omega is below ulp(pi)/2 = 2.2e-16 the
    angle cannot move (it rounds back to pi) and omega grows linearly,
    omega = -(g/L) sin(pi) t; that lasts until t* = ulp(pi) / (2 dt (g/L) sin(pi)) =
    18.5 s at dt = 0.01. After that it falls (to the side sin(pi) > 0 says: theta < pi)
    like exp(w (t - t*)) from ~1e-14: |theta - pi| < 1e-11 at t = 20 (measured 6e-13)."""
    g_over_l, dt = 9.81, 0.01
    pinned = sweep.run(sweep.Scene(), sweep.Grid(theta0=[np.pi]), t_end=10.0, dt=dt,
                       observe=("final",))
    assert _one(pinned, "theta_final") == np.pi
    # RK4 integrates a constant force exactly; round-off of 1000 sums: 1000 eps relative
    assert _one(pinned, "omega_final") == pytest.approx(-g_over_l * math.sin(np.pi) * 10.0,
                                                        rel=1000 * EPS)
    t_star = np.spacing(np.pi) / (2 * dt * g_over_l * math.sin(np.pi))
    assert 18 < t_star < 19
    tipped = sweep.run(sweep.Scene(), sweep.Grid(theta0=[np.pi]), t_end=20.0, dt=dt,
                       observe=("final",))
    assert -1e-11 < _one(tipped, "theta_final") - np.pi < 0


# -------------------------------------------------------------------- resonance
def test_undamped_linear_resonance_grows_as_the_closed_form():
    """W = w = 1, A = 0.01, from rest: theta = A/(2 w^2) (sin w t - w t cos w t), an
    envelope A t / (2 w) = 5 rad at t = 1000 s. RK4's numerical frequency is
    w (1 - (w dt)^4/120), detuned from W by delta = 8.3e-11 rad/s, so the computed
    response drifts in phase by delta t against the drive: error <= envelope * delta t =
    4.2e-7 at t = 1000 (measured 2.0e-7)."""
    amp, t_end, dt = 0.01, 1000.0, 0.01
    scene = sweep.Scene(gravity=1.0, length=1.0, model="linear",
                        effects=(sweep.Forcing(amp, 1.0, 0.0),))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.0]), t_end=t_end, dt=dt,
                   observe=("final", "theta_max"), save_every=100)
    t = ds.time.values
    closed = amp / 2 * (np.sin(t) - t * np.cos(t))
    th, _ = accuracy.exact(scene, 0.0, 0.0, t)
    np.testing.assert_allclose(th[0], closed, rtol=0, atol=1e-9)  # oracle vs closed form
    delta = dt**4 / 120
    bound = amp * t / 2 * delta * t + 1e-12
    assert np.all(np.abs(ds.theta.values[0] - closed) <= bound)
    # the last peak lies within half a period of t_end
    assert amp * (t_end - np.pi) / 2 <= _one(ds, "theta_max") <= amp * t_end / 2 + 1e-6


@pytest.mark.parametrize("amp", [0.001, 0.01])
def test_undamped_nonlinear_resonance_stays_bounded(amp):
    """The same drive on the pendulum: it softens, w(a) = w (1 - a^2/16), so as the
    amplitude grows it detunes from the drive and the growth stops. First-order
    averaging gives a conserved slow Hamiltonian whose level through rest bounds the
    amplitude at a_max = (32 A / w^2)^(1/3) (0.317 and 0.684 rad), far below pi for
    A << pi^3/32: it never goes over the top. Averaging neglects O(a^2) terms: within
    5 % (measured 0.3 % and 1 %). DOP853 agrees on the trajectory (measured 2e-9 at
    t = 2000 s; bound 1e-7 for RK4's O(dt^4) over 2000 s of libration)."""
    t_end = 2000.0
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Forcing(amp, 1.0, 0.0),))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.0]), t_end=t_end, dt=0.01,
                   observe=("final", "theta_max", "winding"))
    a_max = (32 * amp) ** (1 / 3)
    assert _one(ds, "theta_max") == pytest.approx(a_max, rel=0.05)
    assert _one(ds, "theta_max") < np.pi and int(ds.winding.values.ravel()[0]) == 0
    ref = _dop853(lambda t, s: [s[1], amp * math.sin(t) - math.sin(s[0])], [0.0, 0.0], t_end)
    assert abs(_one(ds, "theta_final") - ref[0, -1]) < 1e-7


# --------------------------------------------------------------------- overflow
@pytest.mark.parametrize("model", ["linear", "nonlinear"])
def test_overflow_in_a_forced_grid_is_flagged_and_neighbours_bit_identical(model):
    """c = 1e4 with dt = 0.01 is far beyond RK4's limit (|R(-100)| = 3.8e6 per step):
    those points overflow within ~50 steps; the guard is switched off on purpose."""
    scene = sweep.Scene(model=model, effects=(sweep.Damping(0.1), sweep.Forcing(0.5, 0.9)))
    theta0 = np.linspace(-1.0, 1.0, 3)
    kwargs = {"t_end": 2.0, "dt": 0.01, "check_stability": False,
              "observe": EVERY}  # test_naive's kernels (tests/shared_kernels.py)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        clean = sweep.run(scene, sweep.Grid(theta0=theta0, damping=[0.1, 0.3],
                                            forcing_amplitude=[0.5, 2.0]), **kwargs)
    with pytest.warns(RuntimeWarning, match=r"^6 of 18 trajectories became non-finite"):
        mixed = sweep.run(scene, sweep.Grid(theta0=theta0, damping=[0.1, 1e4, 0.3],
                                            forcing_amplitude=[0.5, 2.0]), **kwargs)
    bad = mixed.sel(damping=1e4)
    assert (bad.status == Status.NONFINITE).all()
    for name in ("theta_final", "omega_final", "winding", "energy_final", "amplitude"):
        assert np.isnan(bad[name]).all(), name
    good = mixed.sel(damping=[0.1, 0.3])
    assert (good.status == Status.OK).all()
    assert good.drop_attrs().identical(clean.drop_attrs())
    # with the guard on, the same grid is refused before any compute
    with pytest.raises(ValueError, match=r"exceeds RK4's stability limit 0\.000279 s"):
        sweep.run(scene, sweep.Grid(theta0=theta0, damping=[0.1, 1e4, 0.3]),
                  **{**kwargs, "check_stability": True})
