"""The ``lyapunov`` observable against independent references.

- The linear model: the kernel iterates the RK4 step map ``M = R(dt A)`` (R the RK4
  stability polynomial, A the 2x2 matrix of the damped oscillator), whose exponents are
  exactly ``log|R(dt lambda_k)| / dt`` for the eigenvalues lambda_k of A.
- The sum of the exponents is the mean divergence of the flow, exactly ``-c`` with
  linear damping c (and no other theta'-dependent term); RK4 keeps it to O(dt^4).
- On a periodic attractor with complex Floquet multipliers both exponents are ``-c/2``.
- A Benettin computation with SciPy's DOP853 (variational equations, QR
  renormalisation), written here independently: all five effects on a periodic
  attractor (to many digits), and chaotic parameters (within the measured spread of
  finite-time exponents).
- The declared Jacobian of every effect against central differences of its term.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sweep
from sweep.observables import LYAPUNOV_EVERY
from sweep.physics import EFFECTS

RK4_COEFFS = (1.0, 1.0, 1 / 2, 1 / 6, 1 / 24)


def _rk4_polynomial(z):
    return sum(a * z ** k for k, a in enumerate(RK4_COEFFS))


def _run(scene, grid, **kwargs):
    kwargs.setdefault("observe", ("final", "lyapunov"))
    return sweep.run(scene, grid, progress=False, **kwargs)


# ------------------------------------------------------------------ the linear model
@pytest.mark.parametrize("c, w0sq", [(0.3, 4.0),   # underdamped: complex eigenvalues
                                     (5.0, 4.0)])  # overdamped: -1 and -4
def test_linear_model_gives_the_step_maps_exponents(c, w0sq):
    """Each exponent of the RK4 map ``R(dt A)`` is ``log|R(dt lambda)| / dt``. Over a
    finite time T a tangent vector's growth differs from ``|R|^n`` by at most the
    condition number kappa of A's eigenvector matrix (``|M^n x| / |x|`` lies between
    ``|mu|^n / kappa`` and ``kappa |mu|^n``, with two renormalisations' worth of
    vectors), so each exponent is within ``log(kappa) / T`` of the oracle; the sum is
    ``log|det M| / dt`` exactly, to rounding (1e-12 over 4,000 steps of logarithms of
    numbers near 1)."""
    dt, t_end = 0.05, 200.0
    scene = sweep.Scene(gravity=w0sq, length=1.0, model="linear",
                        effects=(sweep.Damping(c),))
    grid = sweep.Grid(theta0=[0.1, 1.0, -3.0], omega0=[0.0, 2.0])
    ds = _run(scene, grid, t_end=t_end, dt=dt)
    a = np.array([[0.0, 1.0], [-w0sq, -c]])
    eigenvalues, vectors = np.linalg.eig(a)
    rates = np.sort(np.log(np.abs(_rk4_polynomial(dt * eigenvalues))) / dt)
    bound = np.log(np.linalg.cond(vectors)) / t_end
    assert (ds.status == 0).all()
    np.testing.assert_allclose(ds.lyapunov_max, rates[1], rtol=0, atol=bound)
    np.testing.assert_allclose(ds.lyapunov_min, rates[0], rtol=0, atol=bound)
    np.testing.assert_allclose(ds.lyapunov_max + ds.lyapunov_min, rates.sum(), rtol=1e-12)
    # and the map's rates are the flow's to O(dt^4): -c/2 each, or -1 and -4
    np.testing.assert_allclose(rates, np.sort(eigenvalues.real), rtol=1e-4)


# ------------------------------------------------------------------ sum = -c
CHAOTIC = dict(c=0.5, amplitude=1.5, frequency=2 / 3)  # Baker & Gollub's chaotic pendulum


def _chaotic_scene():
    return sweep.Scene(gravity=1.0, length=1.0,
                       effects=(sweep.Damping(CHAOTIC["c"]),
                                sweep.Forcing(CHAOTIC["amplitude"], CHAOTIC["frequency"])))


def test_sum_is_minus_damping_on_every_trajectory_to_order_four():
    """The exponents sum to the mean divergence ``-c`` on every trajectory, chaotic or
    not: per step, ``det`` of the RK4 map is ``exp(-c dt)`` up to O(dt^5), so the sum is
    off by O(dt^4), and halving dt divides that by 16 (measured 6.1e-8 and 3.8e-9 here;
    asserted: below 1e-6 and at least 10x smaller). The run ends on no multiple of the
    renormalisation interval, so an unfinished last segment would show."""
    c = CHAOTIC["c"]
    period = 2 * np.pi / CHAOTIC["frequency"]
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 8), omega0=np.linspace(-1, 1, 4))
    errors = []
    for steps_per_period in (100, 200):
        dt = period / steps_per_period
        n_steps = 40 * steps_per_period + 7
        assert n_steps % LYAPUNOV_EVERY
        # amplitude too: the kernel of the next test (this scene's terms, 16 lanes)
        ds = _run(_chaotic_scene(), grid, t_end=n_steps * dt, dt=dt, t_transient=10 * period,
                  observe=("final", "amplitude", "lyapunov"))
        assert (ds.status == 0).all()
        assert (ds.lyapunov_max > ds.lyapunov_min).all()
        errors.append(float(np.abs(ds.lyapunov_max + ds.lyapunov_min + c).max()))
    assert errors[0] < 1e-6
    assert errors[1] < errors[0] / 10


def test_periodic_attractor_with_complex_multipliers_gives_half_damping():
    """Weak forcing: every start settles on one small period-1 orbit whose Floquet
    multipliers are complex (underdamped), so both exponents are -c/2 = -0.1. Over a
    window T they deviate by O(1/T) (the eigenvector basis is not orthogonal): measured
    5e-4 at T = 400 s, asserted 2e-3, and smaller at T = 800 s; their sum is -c to
    O(dt^4) (measured 4e-8 at dt = 0.05; asserted 1e-7)."""
    c = 0.2
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(c), sweep.Forcing(0.2, 0.8)))
    grid = sweep.Grid(theta0=[0.0, 1.0, -2.0], omega0=[0.0, 1.0])
    deviation = []
    for window in (400.0, 800.0):
        ds = _run(scene, grid, t_end=200.0 + window, dt=0.05, t_transient=200.0,
                  observe=("final", "amplitude", "lyapunov"))  # the previous test's kernel
        np.testing.assert_allclose(ds.amplitude, ds.amplitude[0, 0], rtol=1e-6)  # one orbit
        np.testing.assert_allclose(ds.lyapunov_max + ds.lyapunov_min, -c, rtol=0, atol=1e-7)
        deviation.append(float(np.abs(ds.lyapunov_max + c / 2).max()))
    assert deviation[0] < 2e-3
    assert deviation[1] < deviation[0]


# ------------------------------------------------------------------ DOP853 Benettin
def _benettin(rhs, th0, om0, *, t_transient, t_end, every, tol=1e-12):
    """Both exponents by Benettin's method with SciPy's DOP853: state and two tangent
    vectors integrated together, QR-renormalised every ``every`` seconds, the logs of
    R's diagonal summed over [t_transient, t_end]."""
    y = np.array([th0, om0, 1.0, 0.0, 0.0, 1.0])
    t, sums = 0.0, np.zeros(2)
    while t < t_end - 1e-9:
        t1 = min(t + every, t_end)
        y = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=tol, atol=tol).y[:, -1]
        q, r = np.linalg.qr(y[2:].reshape(2, 2).T)
        if t >= t_transient - 1e-9:
            sums += np.log(np.abs(np.diag(r)))
        y[2:] = q.T.reshape(-1)
        t = t1
    return np.sort(sums / (t_end - t_transient))[::-1]


def test_all_five_effects_against_dop853_benettin():
    """Damping, forcing, torque, drag and a driven pivot, on a start that settles on a
    periodic orbit (not chaotic, so both integrators follow the same trajectory): RK4
    at dt = 0.002 against DOP853 at 1e-12 over the same window. Measured agreement
    about 1e-9; asserted 1e-6 (RK4's O(dt^4) error at this dt, with w0 ~ pi and the
    pivot's nu = 25 rad/s, is ~1e-8 relative, with margin)."""
    g, L, c, A, W, tau, kd, a, nu = 9.81, 1.0, 0.4, 2.0, 2.0, 0.5, 0.05, 0.02, 25.0

    def rhs(t, y):
        th, om, u1, v1, u2, v2 = y
        p = a * nu * nu / L * math.cos(nu * t)
        acc = (-(g / L) * math.sin(th) - c * om + A * math.sin(W * t) + tau
               - kd * om * abs(om) + p * math.sin(th))
        d_theta = (-(g / L) + p) * math.cos(th)
        d_omega = -c - 2 * kd * abs(om)
        return [om, acc, v1, d_theta * u1 + d_omega * v1, v2, d_theta * u2 + d_omega * v2]

    reference = _benettin(rhs, 0.3, 0.0, t_transient=20.0, t_end=60.0, every=1.0)
    scene = sweep.Scene(gravity=g, length=L, effects=(
        sweep.Damping(c), sweep.Forcing(A, W), sweep.Torque(tau), sweep.QuadraticDrag(kd),
        sweep.PivotDrive(a, nu)))
    ds = _run(scene, sweep.Grid(theta0=[0.3], omega0=[0.0]), t_end=60.0, dt=0.002,
              t_transient=20.0)
    got = np.array([ds.lyapunov_max.item(), ds.lyapunov_min.item()])
    np.testing.assert_allclose(got, reference, rtol=0, atol=1e-6)


def test_chaotic_exponent_against_dop853_benettin_within_the_spread():
    """Baker & Gollub's chaotic pendulum (c = 0.5, A = 1.5, W = 2/3): nearby
    trajectories separate, so the two integrators' finite-time exponents agree only
    statistically. Over a window of 150 forcing periods sweep's lambda_max over 128
    starts has mean 0.113 and standard deviation sigma = 0.008 (measured); each of four
    DOP853 starts must lie within 4 sigma of sweep's mean, and the means within 3
    standard errors of their difference. The minimum exponent is -c - lambda_max
    (tested above), so it is not repeated."""
    c, amplitude, frequency = CHAOTIC["c"], CHAOTIC["amplitude"], CHAOTIC["frequency"]
    period = 2 * np.pi / frequency

    def rhs(t, y):
        th, om, u1, v1, u2, v2 = y
        d_theta = -math.cos(th)
        return [om, -math.sin(th) - c * om + amplitude * math.sin(frequency * t),
                v1, d_theta * u1 - c * v1, v2, d_theta * u2 - c * v2]

    starts = [(0.2, 0.0), (1.0, 0.5), (-2.0, 1.0), (2.5, -1.0)]
    reference = np.array([_benettin(rhs, *s, t_transient=20 * period, t_end=170 * period,
                                    every=period, tol=1e-11)[0] for s in starts])
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 16), omega0=np.linspace(-1, 1, 8))
    ds = _run(_chaotic_scene(), grid, t_end=170 * period, dt=period / 200,
              t_transient=20 * period)
    ours = ds.lyapunov_max.values.ravel()
    mean, sigma = ours.mean(), ours.std()
    assert 0.05 < mean < 0.2  # chaotic: clearly positive
    assert np.all(np.abs(reference - mean) < 4 * sigma)
    standard_error = sigma * math.sqrt(1 / len(reference) + 1 / ours.size)
    assert abs(reference.mean() - mean) < 3 * standard_error


def test_exponents_converge_as_dt_shrinks():
    """On a periodic attractor (the damped driven pendulum at weak forcing) the
    finite-time exponents over a fixed window are smooth in dt: the differences
    between dt, dt/2 and dt/4 shrink by ~16 (RK4's order 4; measured 14.9); asserted
    > 8. (On a chaotic trajectory they would not: the trajectory itself changes.)"""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(0.2, 0.8)))
    values = []
    for dt in (0.1, 0.05, 0.025):
        ds = _run(scene, sweep.Grid(theta0=[0.5], omega0=[0.0]), t_end=300.0, dt=dt,
                  t_transient=100.0)
        values.append(ds.lyapunov_max.item())
    first, second = abs(values[0] - values[1]), abs(values[1] - values[2])
    assert second > 0 and first / second > 8


# ------------------------------------------------------------------ declarations
def _evaluate(text, values):
    return eval(text, {"__builtins__": {}, "abs": abs, "math": math}, dict(values))


@pytest.mark.parametrize("model", ["nonlinear", "linear"])
@pytest.mark.parametrize("name", list(EFFECTS))
def test_declared_jacobian_matches_central_differences(name, model, rng):
    """Each effect's jacobian_theta and jacobian_omega against a central difference of
    its term (step 1e-6: truncation ~1e-12, rounding ~1e-10 on terms of order 1;
    asserted 1e-7). |omega| >= 0.2 keeps drag's |omega| away from its kink."""
    declaration = EFFECTS[name].declaration
    f_theta, df_theta = ("math.sin(th)", "math.cos(th)") if model == "nonlinear" \
        else ("th", "1.0")

    def term(th, om, values):
        return _evaluate(declaration.term.replace("FTH", f_theta), {**values, "th": th,
                                                                    "om": om})

    def jacobian(variable, th, om, values):
        text = declaration.jacobian(variable)
        if not text:
            return 0.0
        return _evaluate(text.replace("DFTH", df_theta).replace("FTH", f_theta),
                         {**values, "th": th, "om": om})

    h = 1e-6
    for _ in range(20):
        values = {s: rng.uniform(0.1, 2.0) for s in declaration.symbols}
        values.update(L=1.3, g=9.81)
        if declaration.drive is not None:
            values[declaration.drive.value] = rng.uniform(-2.0, 2.0)
        th = rng.uniform(-4.0, 4.0)
        om = rng.choice([-1, 1]) * rng.uniform(0.2, 3.0)
        d_theta = (term(th + h, om, values) - term(th - h, om, values)) / (2 * h)
        d_omega = (term(th, om + h, values) - term(th, om - h, values)) / (2 * h)
        assert jacobian("th", th, om, values) == pytest.approx(d_theta, abs=1e-7)
        assert jacobian("om", th, om, values) == pytest.approx(d_omega, abs=1e-7)


# ------------------------------------------------------------------ the kernel
def test_tangent_dynamics_leave_the_trajectory_unchanged():
    """The state is computed by the same operations with and without the tangent
    dynamics (sin and cos from one reduction give sin's bits), so the final state is
    bit-identical, for every effect and both models."""
    for model in ("nonlinear", "linear"):
        scene = sweep.Scene(gravity=9.81, length=1.0, model=model, effects=(
            sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3), sweep.Torque(0.3),
            sweep.QuadraticDrag(0.1), sweep.PivotDrive(0.01, 30.0)))
        grid = sweep.Grid(theta0=np.linspace(-3, 3, 9), omega0=[-1.0, 2.0],
                          forcing_frequency=[0.6, 0.7])
        # (final, winding): the nonlinear kernel is test_float32's and test_cuda's
        plain = _run(scene, grid, t_end=20.0, dt=0.01, observe=("final", "winding"))
        with_tangent = _run(scene, grid, t_end=20.0, dt=0.01,
                            observe=("final", "winding", "lyapunov"))
        np.testing.assert_array_equal(plain.theta_final, with_tangent.theta_final)
        np.testing.assert_array_equal(plain.omega_final, with_tangent.omega_final)
        assert np.isfinite(with_tangent.lyapunov_max).all()


def test_a_trajectory_that_blows_up_is_flagged_not_kept():
    """Beyond RK4's stability limit (unchecked) a trajectory overflows: its status is
    non-finite and both exponents NaN, never a number."""
    scene = sweep.Scene(gravity=100.0, length=1.0, model="linear",
                        effects=(sweep.Damping(0.1),))  # w0 dt = 10: |R| ~ 400 per step
    with pytest.warns(RuntimeWarning, match="1 of 1 trajectories became non-finite"):
        ds = _run(scene, sweep.Grid(theta0=[0.5], omega0=[0.0]), t_end=300.0, dt=1.0,
                  check_stability=False)
    assert int(ds.status.item()) == int(sweep.Status.NONFINITE)
    assert np.isnan(ds.lyapunov_max.item()) and np.isnan(ds.lyapunov_min.item())


def test_the_unforced_pendulum_has_a_zero_exponent_pair():
    """Undamped, unforced: the flow conserves area and a libration is neutrally stable
    along the orbit: both exponents tend to 0 like log(t)/t (the period depends on the
    amplitude, so nearby orbits shear apart linearly). Asserted: |lambda| < 0.02 over
    500 s. The sum is RK4's area loss, ``|R(i w dt)|^2 = 1 - (w dt)^6 / 72 + ...`` per
    step: ~(w dt)^6 / (72 dt) = 1.3e-9 /s for w = 3.1 rad/s, dt = 0.01 (measured
    1.1e-9); asserted 3e-9."""
    scene = sweep.Scene(gravity=9.81, length=1.0)
    ds = _run(scene, sweep.Grid(theta0=[0.5, 2.0], omega0=[0.0]), t_end=500.0, dt=0.01)
    assert float(np.abs(ds.lyapunov_max).max()) < 0.02
    assert float(np.abs(ds.lyapunov_max + ds.lyapunov_min).max()) < 3e-9


# ------------------------------------------------------------------ bad input
def test_adaptive_and_symplectic_methods_are_refused(no_compute):
    forced = sweep.Scene(effects=(sweep.Damping(0.1), sweep.Forcing(1.0, 1.0)))
    grid = sweep.Grid(theta0=[0.1], omega0=[0.0])
    with pytest.raises(ValueError, match=r"'lyapunov'.*'dopri5' is adaptive; accepted: "
                                         "'euler', 'heun', 'rk4', 'rk38'"):
        sweep.run(forced, grid, t_end=1.0, dt=0.1, method="dopri5", observe=("lyapunov",))
    with pytest.raises(ValueError, match="'verlet' is symplectic; accepted: 'euler'"):
        sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.1, method="verlet",
                  observe=("lyapunov",))


def test_an_effect_without_a_jacobian_is_refused(no_compute):
    from dataclasses import dataclass
    from typing import ClassVar

    from sweep.physics import Effect, EffectDeclaration, Parameter, register, unregister

    @register
    @dataclass(frozen=True)
    class CubicSpring(Effect):
        stiffness: float
        declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
            name="cubic_spring", term="- kc * th * th * th", equation="- k theta^3",
            parameters=(Parameter("cubic_stiffness", "stiffness", "kc", "s-2", "1/s^2",
                                  "cubic spring stiffness"),),
            conservative=True)

    try:
        assert CubicSpring.declaration.jacobian_missing() == ("theta",)
        scene = sweep.Scene(effects=(CubicSpring(1.0),))
        with pytest.raises(ValueError, match="effect 'cubic_spring' declares no derivative of "
                                             r"'- kc \* th \* th \* th' with respect to theta"):
            sweep.run(scene, sweep.Grid(theta0=[0.1], omega0=[0.0]), t_end=1.0, dt=0.1,
                      observe=("lyapunov",))
    finally:
        unregister("cubic_spring")


# ------------------------------------------------------------------ the TOML route
def test_sweep_run_observes_lyapunov_from_a_run_file(tmp_path):
    """`sweep run` with ``observe = ["lyapunov"]`` writes both exponents to the file,
    with units; their sum is -c (O(dt^4) at w0 dt = 0.05: 1e-6). Eight starts, so the
    run takes a block of 64 lanes: test_float32.py's float64 kernel of this observable
    (a narrow kernel of its own for fewer than 8)."""
    from sweep import cli

    run_file = tmp_path / "chaos.toml"
    run_file.write_text(
        "[scene]\ngravity = 1.0\nlength = 1.0\n"
        "[scene.damping]\ncoefficient = 0.5\n"
        "[scene.forcing]\namplitude = 1.5\nfrequency = 0.6666666666666666\n"
        "[grid]\ntheta0 = {start = 0.1, stop = 1.5, num = 8}\nomega0 = [0.0]\n"
        '[run]\nt_end = 100.0\ndt = 0.05\nobserve = ["lyapunov"]\n')
    output = tmp_path / "chaos.nc"
    assert cli.main(["run", str(run_file), "-o", str(output), "--no-progress"]) == 0
    ds = sweep.load(output)
    assert ds["lyapunov_max"].attrs["units"] == "s-1"
    np.testing.assert_allclose(ds.lyapunov_max + ds.lyapunov_min, -0.5, rtol=0, atol=1e-6)
