"""sweep.accuracy: elliptic functions and exact solutions against SciPy, the numerical
reference against SciPy's DOP853, convergence and work-precision studies."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk, ellipkinc, ellipkm1

import sweep
from sweep import accuracy

W0 = math.sqrt(9.81)


# =========================================================================== elliptic
@pytest.mark.parametrize("m", [0.0, 0.25, 0.9, 0.998001])
def test_jacobi_functions_match_scipy(m):
    u = np.linspace(-30.0, 30.0, 2001)
    ours = accuracy.jacobi_ellipj(u, m)
    theirs = ellipj(u, m)
    # both are AGM-based to ~1 ulp per stage; over |u| <= 30 the phase am grows to ~30
    # rad, so agreement to 3e-14 is 100 ulps of the phase (measured: <= 2.6e-14)
    for name, a, b in zip(("sn", "cn", "dn", "am"), ours, theirs):
        np.testing.assert_allclose(a, b, rtol=0, atol=3e-14, err_msg=name)
    assert accuracy.ellipk(m) == pytest.approx(ellipk(m), rel=1e-15, abs=0)  # 1 ulp-ish
    phi = np.linspace(-1.5, 1.5, 13)
    # F by Carlson's R_F: a few ulps (measured <= 2.3e-15 near m -> 1)
    np.testing.assert_allclose(accuracy.ellipf(phi, m), ellipkinc(phi, m), rtol=0, atol=5e-15)


def test_jacobi_functions_near_the_separatrix_keep_their_identities():
    """Near m = 1 SciPy's ellipj loses accuracy (it is off by 4e-5 at m = 1 - 1e-12,
    u = 25), so check identities that any correct implementation satisfies."""
    m1 = 1e-12
    m = 1.0 - m1
    big_k = accuracy.ellipk(m, m1)
    assert big_k == pytest.approx(ellipkm1(m1), rel=1e-14)
    u = np.linspace(-25.0, 25.0, 501)
    sn, cn, dn, am = accuracy.jacobi_ellipj(u, m, m1)
    np.testing.assert_allclose(sn ** 2 + cn ** 2, 1.0, rtol=0, atol=4e-16)
    np.testing.assert_allclose(dn ** 2 + m * sn ** 2, 1.0, rtol=0, atol=4e-16)
    # am' = dn, by central differences (h = 1e-5: truncation h^2 am''' ~ 1e-10, and
    # round-off eps * 25 / h ~ 1e-9)
    h = 1e-5
    derivative = (accuracy.jacobi_am(u + h, m, m1) - accuracy.jacobi_am(u - h, m, m1)) / (2 * h)
    np.testing.assert_allclose(derivative, dn, rtol=0, atol=1e-8)
    # quasi-periodicity am(u + 2K) = am(u) + pi (to ~100 ulps of am ~ 30)
    np.testing.assert_allclose(accuracy.jacobi_am(u + 2 * big_k, m, m1), am + np.pi,
                               rtol=0, atol=1e-13)


# =========================================================================== exact
def _dop853(scene, theta0, omega0, times, t0=0.0):
    p = scene.parameters()
    w0sq = p["gravity"] / p["length"]
    restoring = np.sin if scene.model == "nonlinear" else (lambda x: x)

    def f(t, y):
        return (y[1], p["forcing_amplitude"] * math.sin(p["forcing_frequency"] * t
                                                        + p["forcing_phase"])
                - p["damping"] * y[1] - w0sq * restoring(y[0]))

    s = solve_ivp(f, (t0, times[-1]), [theta0, omega0], method="DOP853", rtol=1e-13,
                  atol=1e-13, t_eval=times)
    assert s.success
    return s.y


STARTS = [
    (1.0, 0.0), (0.3, 2.0), (-2.5, -1.0),        # libration, any phase
    (2 * math.asin(0.999), 0.0),                 # near-separatrix libration, k = 0.999
    (7.0, 1.0), (-13.0, -0.5),                   # unwrapped angles beyond 2 pi
    (0.0, 7.0), (1.0, -8.0), (0.2, 6.3),         # rotation both ways, just above separatrix
]


@pytest.mark.parametrize("theta0,omega0", STARTS)
def test_elliptic_solution_matches_dop853(theta0, omega0):
    times = np.linspace(0.0, 10.0, 51)
    theta, omega = accuracy.exact(sweep.Scene(), theta0, omega0, times)
    ref = _dop853(sweep.Scene(), theta0, omega0, times)
    # DOP853 at rtol 1e-13 over ~5 periods: ~1e-12 away from the separatrix; the
    # near-separatrix starts amplify every error (the period depends steeply on the
    # energy) to ~1e-10 (measured 4.6e-10 over 20 s), hence 1e-9
    near = abs(1 - (omega0 / (2 * W0)) ** 2 - math.sin(theta0 / 2) ** 2) < 0.01
    tol = 1e-9 if near else 1e-10
    np.testing.assert_allclose(theta[0], ref[0], rtol=0, atol=tol)
    np.testing.assert_allclose(omega[0], ref[1], rtol=0, atol=tol * W0)


def test_elliptic_solution_from_rest_is_the_textbook_form():
    """From rest at theta0 > 0: theta = 2 arcsin(k sn(K - w0 t | k^2)) (the sign
    convention of tests/test_oracles.py), so the two forms agree."""
    theta0 = 2.0
    k = math.sin(theta0 / 2)
    t = np.linspace(0.0, 5.0, 101)
    sn, cn, _, _ = ellipj(ellipk(k * k) - W0 * t, k * k)
    theta, omega = accuracy.exact(sweep.Scene(), theta0, 0.0, t)
    # arcsin is ill-conditioned near the turning points (derivative 1/sqrt(1 - k^2) =
    # 1.9 here); 1e-13 is ~100 ulps
    np.testing.assert_allclose(theta[0], 2 * np.arcsin(k * sn), rtol=0, atol=1e-13)
    np.testing.assert_allclose(omega[0], -2 * k * W0 * cn, rtol=0, atol=1e-13)


LINEAR = {
    "free": (),
    "underdamped": (sweep.Damping(0.7),),
    "critical": (sweep.Damping(2 * W0),),
    "overdamped": (sweep.Damping(9.0),),
    "forced damped": (sweep.Damping(0.3), sweep.Forcing(1.1, 0.9, 0.4)),
    "resonant undamped": (sweep.Forcing(1.0, W0, 0.2),),
}


@pytest.mark.parametrize("effects", list(LINEAR.values()), ids=list(LINEAR))
def test_linear_closed_forms_match_dop853(effects):
    scene = sweep.Scene(model="linear", effects=effects)
    times = 3.0 + np.linspace(0.0, 20.0, 41)  # t0 = 3: the forcing phase must follow
    theta, omega = accuracy.exact(scene, 0.5, -0.3, times, t0=3.0)
    ref = _dop853(scene, 0.5, -0.3, times, t0=3.0)
    # DOP853 at rtol 1e-13 over 20 s of a state of size <= ~3: measured <= 9e-12
    np.testing.assert_allclose(theta[0], ref[0], rtol=0, atol=3e-11)
    np.testing.assert_allclose(omega[0], ref[1], rtol=0, atol=3e-11 * W0)


def test_exact_refuses_scenes_without_a_closed_form():
    with pytest.raises(ValueError, match=r"no exact solution is known for a nonlinear scene "
                                         r"with damping or forcing; accepted"):
        accuracy.exact(sweep.Scene(effects=(sweep.Damping(0.1),)), 1.0, 0.0, [1.0])
    with pytest.raises(ValueError, match=r"exactly on the separatrix"):
        accuracy.exact(sweep.Scene(), 0.0, 2 * W0, [1.0])


# =========================================================================== reference
def test_numerical_reference_matches_dop853_on_a_damped_forced_scene():
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3, 0.3)))
    sample = sweep.Grid(theta0=[-2.0, 0.5, 3.0], omega0=[0.0, 4.0])
    theta, omega, kind = accuracy.reference(scene, sample, t_end=10.0)
    assert kind == "dopri5"
    table = sample.table(scene)
    for j, (th0, om0) in enumerate(table[:, :2]):
        ref = _dop853(scene, th0, om0, np.array([0.0, 10.0]))
        # both at rtol 1e-13 over 10 s: each ~1e-12, so 1e-10 leaves room for the
        # amplification of this damped forced (non-chaotic over 10 s) motion
        assert abs(theta[j] - ref[0, -1]) < 1e-10 and abs(omega[j] - ref[1, -1]) < 1e-10


def test_reference_uses_the_exact_solution_when_there_is_one():
    sample = sweep.Grid(theta0=[0.5, 1.0])
    theta, _, kind = accuracy.reference(sweep.Scene(), sample, t_end=3.0)
    assert kind == "exact"
    num_theta, _, _ = accuracy.reference(sweep.Scene(), sample, t_end=3.0,
                                                 kind="dopri5")
    # sweep's dopri5 at rtol 1e-13 over 3 s: measured ~1e-13
    np.testing.assert_allclose(num_theta, theta, rtol=0, atol=1e-11)


# =========================================================================== studies
@pytest.mark.parametrize("scene", [
    sweep.Scene(model="linear", effects=(sweep.Damping(0.3), sweep.Forcing(1.1, 0.9, 0.4))),
    sweep.Scene(),
], ids=["linear forced damped (closed form)", "nonlinear (elliptic)"])
def test_convergence_reports_the_order_of_rk4(scene):
    result = accuracy.convergence(scene, [0.5, 1.0], [0.0, 1.0], 2.0, "rk4",
                                  [2.0 / 2 ** k for k in range(5, 9)])
    assert result.method == "rk4" and result.nominal_order == 4
    assert result.reference == "exact"
    # +-0.1 in the asymptotic range (dt = 0.0625 .. 0.0078, errors 1e-5 .. 1e-9)
    assert abs(result.order - 4) <= 0.1, result
    assert len(result.local_orders) == 3 and np.all(np.diff(np.log(result.errors)) < 0)


def test_convergence_refuses_an_adaptive_method():
    with pytest.raises(ValueError, match=r"convergence needs a fixed-step method; 'dopri5'"):
        accuracy.convergence(sweep.Scene(), 1.0, 0.0, 1.0, "dopri5", [0.1, 0.05])


def test_work_precision_dataset():
    sample = sweep.Grid(theta0=[math.pi / 3, 1.0], omega0=[0.0, 0.5])
    wp = accuracy.work_precision(
        sweep.Scene(), sample, ["euler", "rk4", "verlet", "yoshida4", "dopri5"],
        t_end=2.0, dts=[2.0 / 2 ** k for k in range(6, 10)],
        tolerances=[1e-5, 1e-7, 1e-9, 1e-11], repeats=1)
    assert dict(wp.sizes) == {"integrator": 5, "level": 4}
    assert list(wp.integrator.values) == ["euler", "rk4", "verlet", "yoshida4", "dopri5"]
    for name in ("dt", "rtol", "error_max", "error_rms", "wall_time", "time_per_million",
                 "rhs_evaluations", "observed_order", "nominal_order"):
        assert name in wp, name
    assert wp.attrs["reference"] == "exact" and wp.attrs["n_trajectories"] == 4
    assert (wp.error_rms <= wp.error_max).all()
    assert (wp.wall_time > 0).all()
    rk4 = wp.sel(integrator="rk4")
    np.testing.assert_array_equal(rk4.rhs_evaluations, 4 * 2 ** np.arange(6, 10))
    assert np.isnan(rk4.rtol).all() and np.isfinite(wp.sel(integrator="dopri5").dt).all()
    # observed order = -slope against rhs evaluations: the dt order for fixed steps.
    # Euler's ladder here is pre-asymptotic (local slopes 0.9-1.0), the others within
    # 0.15 (four levels, no ladder tuning)
    for method in ("rk4", "verlet", "yoshida4"):
        observed = float(wp.observed_order.sel(integrator=method))
        assert abs(observed - int(wp.nominal_order.sel(integrator=method))) < 0.15, method
    assert 0.8 < float(wp.observed_order.sel(integrator="euler")) < 1.2  # measured 1.09
    # dopri5's error falls with the tolerance
    assert np.all(np.diff(wp.error_max.sel(integrator="dopri5").values) < 0)

    cost = accuracy.cost_at(wp, errors=(1e-6, 1e-12))
    assert dict(cost.sizes) == {"integrator": 5, "error": 2}
    # RK4 reaches 1e-6 (errors 2.4e-6 .. 6e-10 on the ladder) between its first steps
    dt = float(cost.dt.sel(integrator="rk4", error=1e-6))
    assert 2.0 / 2 ** 7 <= dt <= 2.0 / 2 ** 6
    assert np.isnan(float(cost.dt.sel(integrator="euler", error=1e-12)))  # never reached
    assert float(cost.time_per_million.sel(integrator="rk4", error=1e-6)) > 0


def test_work_precision_plot(tmp_path):
    wp = accuracy.work_precision(sweep.Scene(), sweep.Grid(theta0=[1.0]), ["rk4", "dopri5"],
                                 t_end=1.0, dts=[1 / 32, 1 / 64], tolerances=[1e-6, 1e-9],
                                 repeats=1)
    fig = sweep.plot.work_precision(wp, x="rhs_evaluations")
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert [t.get_text().split()[0] for t in ax.get_legend().get_texts()] == ["rk4", "dopri5"]
    assert sweep.plot.save_figure(fig, tmp_path / "wp.png").stat().st_size > 0
    with pytest.raises(ValueError, match=r"'speed' is not a variable of the work-precision"):
        sweep.plot.work_precision(wp, x="speed")


def test_opt_in_error_estimate_brackets_the_true_error():
    """The Richardson estimate attached to a run is close to the error against the exact
    elliptic solution (RK4: the dt^5 term makes the estimate good to ~10-20 % at these
    steps; we accept a factor 2 either way)."""
    import sweep
    from sweep import accuracy

    scene = sweep.Scene(gravity=1.0, length=1.0)
    grid = sweep.Grid(theta0=np.linspace(0.3, 2.5, 6), omega0=[0.0, 0.5])
    ds = sweep.run(scene, grid, t_end=20.0, dt=0.1, observe=("final",), estimate_error=12)
    assert ds.attrs["error_estimate_sample"] == 12
    theta0, omega0 = np.meshgrid(grid.axes["theta0"], grid.axes["omega0"], indexing="ij")
    theta_ref, omega_ref = accuracy.exact(scene, theta0.ravel(), omega0.ravel(), [20.0])
    theta_ref, omega_ref = theta_ref[:, 0], omega_ref[:, 0]
    true = accuracy.state_error(scene, ds.theta_final.values.ravel(),
                                ds.omega_final.values.ravel(), theta_ref, omega_ref)
    assert 0.5 * true.max() < ds.attrs["error_estimate_max"] < 2.0 * true.max()
    with pytest.raises(ValueError, match=r"estimate_error must be None or an int >= 1"):
        sweep.run(scene, grid, t_end=1.0, dt=0.1, estimate_error=0)
