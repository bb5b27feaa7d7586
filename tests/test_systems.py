"""Systems with several coordinates (`sweep.DoublePendulum`) run through `sweep.run`,
checked against oracles: SciPy's DOP853 on the textbook equations of motion (written
out here, not read from sweep), the small-angle normal modes, RK4's measured order, and
DOP853's event location for the first flip.

Tolerances: RK4's global error is C dt^4; the same case at dt and dt/2 differs by
D = (15/16) C dt^4, so ``2 D`` bounds the dt run's error with room for higher-order
terms (as in tests/test_oracles.py). DOP853 at rtol = atol = 1e-13 adds ~1e-12 over
these short runs.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sweep

G = 9.81


def textbook(t, y, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=G, c=0.0):
    """The double pendulum's equations of motion for absolute angles, in the textbook
    closed form (e.g. myphysicslab's "Double Pendulum"), plus mass-proportional damping
    ``- c theta_i'``."""
    th1, th2, w1, w2 = y
    d = th1 - th2
    den = 2 * m1 + m2 - m2 * np.cos(2 * d)
    a1 = (-g * (2 * m1 + m2) * np.sin(th1) - m2 * g * np.sin(th1 - 2 * th2)
          - 2 * np.sin(d) * m2 * (w2 ** 2 * l2 + w1 ** 2 * l1 * np.cos(d))) / (l1 * den)
    a2 = (2 * np.sin(d) * (w1 ** 2 * l1 * (m1 + m2) + g * (m1 + m2) * np.cos(th1)
                           + w2 ** 2 * l2 * m2 * np.cos(d))) / (l2 * den)
    return [w1, w2, a1 - c * w1, a2 - c * w2]


def dop853(y0, t_end, **params):
    return solve_ivp(textbook, (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                     args=tuple(params.get(k, d) for k, d in (
                         ("m1", 1.0), ("m2", 1.0), ("l1", 1.0), ("l2", 1.0), ("g", G),
                         ("c", 0.0)))).y[:, -1]


FINAL = ("theta1_final", "theta2_final", "omega1_final", "omega2_final")

#: The observables of test_bits_do_not_depend_on_blocks_chunks_or_threads, also run by
#: the tests that check one of them on fewer than 4 starts (one lane each), so that they
#: share its kernel (adding observables never changes a trajectory; tests/shared_kernels.py)
OBSERVE = ("final", "winding", "energy", "flip")

# a regular start, a large-amplitude one and one that flips (all non-chaotic over 2 s)
STARTS = [(0.3, -0.2, 0.0, 0.0), (2.0, 1.0, 0.5, -0.5), (1.0, 2.5, 0.0, 1.0)]


def _points(starts):
    return sweep.Points(theta1_0=[s[0] for s in starts], theta2_0=[s[1] for s in starts],
                        omega1_0=[s[2] for s in starts], omega2_0=[s[3] for s in starts])


def _finals(ds):
    return np.stack([ds[name].values for name in FINAL], axis=-1)


@pytest.mark.parametrize("params", [
    {},
    {"m1": 2.0, "m2": 0.5, "l1": 1.5, "l2": 0.7, "g": 3.0},
    {"c": 0.4},
])
def test_final_state_matches_dop853_on_the_textbook_equations(params):
    system = sweep.DoublePendulum(
        mass1=params.get("m1", 1.0), mass2=params.get("m2", 1.0),
        length1=params.get("l1", 1.0), length2=params.get("l2", 1.0),
        gravity=params.get("g", G),
        effects=(sweep.Damping(params["c"]),) if "c" in params else ())
    t_end, dt = 2.0, 0.002
    observe = ("final",) if "c" in params else OBSERVE  # undamped: the shared kernel
    coarse = _finals(sweep.run(system, _points(STARTS), t_end=t_end, dt=dt, observe=observe))
    fine = _finals(sweep.run(system, _points(STARTS), t_end=t_end, dt=dt / 2, observe=observe))
    reference = np.array([dop853(list(s), t_end, **params) for s in STARTS])
    tol = 2 * np.abs(coarse - fine) + 1e-11  # 2 D (module docstring) + DOP853's error
    assert np.all(tol < 1e-6), "dt resolves the motion, so the bound means something"
    np.testing.assert_array_less(np.abs(coarse - reference), tol)


def test_convergence_order_is_4():
    """The error against DOP853 falls 16x per halving of dt: the order, measured."""
    errors = []
    for dt in (0.002, 0.001, 0.0005):
        got = _finals(sweep.run(sweep.DoublePendulum(), _points(STARTS), t_end=2.0, dt=dt,
                                observe=OBSERVE))
        reference = np.array([dop853(list(s), 2.0) for s in STARTS])
        errors.append(np.max(np.abs(got - reference)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # RK4: 4; the next term (dt^5) and round-off move it by < 0.3 at these steps
    np.testing.assert_allclose(orders, 4.0, atol=0.3)


def test_small_angle_normal_modes_of_equal_masses_and_lengths():
    """For m1 = m2 and l1 = l2 = l the small-angle modes are omega^2 = (2 -+ sqrt 2) g/l
    with theta2/theta1 = +-sqrt 2 (linearise the Lagrangian: M = m l^2 [[2, 1], [1, 1]],
    K = m g l [[2, 0], [0, 1]], det(K - w^2 M) = 0). Started in a mode's shape, the
    pendulum oscillates at that frequency alone; measured from the zero crossings of
    theta1 (interpolated) over ~20 periods."""
    length, amplitude = 0.8, 1e-4
    system = sweep.DoublePendulum(length1=length, length2=length)
    for sign in (+1, -1):
        expected = math.sqrt((2 - sign * math.sqrt(2)) * G / length)
        period = 2 * math.pi / expected
        dt = period / 400
        n = 400 * 20
        ds = sweep.run(system, _points([(amplitude, sign * math.sqrt(2) * amplitude, 0, 0)]),
                       t_end=n * dt, dt=dt, save_every=1,
                       observe=("final", "winding"))  # test_saved_trajectory's kernel
        theta = ds["theta1"].values[0]
        time = ds["time"].values
        k = np.flatnonzero(np.sign(theta[:-1]) != np.sign(theta[1:]))
        crossings = time[k] - theta[k] * (time[k + 1] - time[k]) / (theta[k + 1] - theta[k])
        measured = math.pi / np.mean(np.diff(crossings))
        # nonlinearity: relative shift ~ amplitude^2 = 1e-8; linear interpolation of the
        # crossings at 400 steps per period: ~(2 pi / 400)^2 / 8 relative = 3e-5 per
        # crossing, averaged over 40: 1e-5 keeps a margin, while a mode of the other
        # frequency (1.85x) or a wrong g/l fails by far
        assert measured == pytest.approx(expected, rel=1e-5)


def test_energy_error_shrinks_at_rk4_order_without_damping():
    drifts = []
    for dt in (0.01, 0.005):
        ds = sweep.run(sweep.DoublePendulum(), _points(STARTS[:2]), t_end=4.0, dt=dt,
                       observe=OBSERVE)
        drifts.append(np.max(np.abs(ds.energy_final - ds.energy_initial).values))
    # order 4 (16x), or more: the energy error of RK4 can cancel better than the state's;
    # 10x rejects a second-order error (4x) with margin
    assert drifts[0] / drifts[1] > 10
    # and small: energies here are ~20-30 J, so 1e-5 J is < 1e-6 relative (a wrong term
    # in the energy or the accelerations drifts by order 1)
    assert drifts[1] < 1e-5


def test_energy_is_the_textbook_energy():
    m1, m2, l1, l2 = 1.3, 0.7, 0.9, 1.1
    system = sweep.DoublePendulum(mass1=m1, mass2=m2, length1=l1, length2=l2)
    ds = sweep.run(system, _points(STARTS), t_end=0.01, dt=0.01, observe=OBSERVE)
    th1, th2, w1, w2 = np.array(STARTS).T
    # T + V with V = 0 hanging at rest (sweep's convention, as the single pendulum's)
    expected = (0.5 * m1 * l1 ** 2 * w1 ** 2
                + 0.5 * m2 * (l1 ** 2 * w1 ** 2 + l2 ** 2 * w2 ** 2
                              + 2 * l1 * l2 * w1 * w2 * np.cos(th1 - th2))
                + (m1 + m2) * G * l1 * (1 - np.cos(th1)) + m2 * G * l2 * (1 - np.cos(th2)))
    # the same sum in another order: a few ulps of the largest term (~30 J)
    np.testing.assert_allclose(ds.energy_initial.values, expected, rtol=0, atol=1e-12)


def _first_flip(y0, t_end):
    """DOP853 with event location: the first time |theta_i| reaches pi (starts within
    (-pi, pi))."""
    events = [lambda t, y, i=i: abs(y[i]) - math.pi for i in (0, 1)]
    for event in events:
        event.terminal = True
    result = solve_ivp(textbook, (0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-12,
                       events=events)
    times = [e[0] for e in result.t_events if len(e)]
    return min(times) if times else math.nan


def test_flip_time_matches_dop853_events_and_stop_early_keeps_it():
    starts = [(2.0, 1.0, 0.5, -0.5), (1.0, 2.5, 0.0, 1.0), (0.3, -0.2, 0.0, 0.0),
              (-2.5, 2.9, 0.0, 0.0)]
    dt = 0.001
    full = sweep.run(sweep.DoublePendulum(), _points(starts), t_end=5.0, dt=dt,
                     observe=("final", "flip"))
    expected = np.array([_first_flip(list(s), 5.0) for s in starts])
    got = full.flip_time.values
    assert np.isnan(expected[2]) and np.isnan(got[2])  # the small start never flips
    flipped = ~np.isnan(expected)
    # RK4's state error at dt = 1e-3 is ~1e-10 rad; the linear interpolation of the
    # crossing within a step errs by ~dt^2 |theta''| / (8 |theta'|) <~ 1e-6 s here
    np.testing.assert_allclose(got[flipped], expected[flipped], rtol=0, atol=1e-5)
    early = sweep.run(sweep.DoublePendulum(), _points(starts), t_end=5.0, dt=dt,
                      observe=("flip",), stop_early=True)
    # the same arithmetic up to the flip: the same bits
    np.testing.assert_array_equal(early.flip_time.values, got)


def test_bits_do_not_depend_on_blocks_chunks_or_threads():
    import numba

    rng = np.random.default_rng(1)
    starts = rng.uniform(-3, 3, size=(200, 4))
    points = _points(starts)
    kwargs = dict(t_end=1.0, dt=0.01, observe=OBSERVE)
    whole = sweep.run(sweep.DoublePendulum(), points, **kwargs)
    chunked = sweep.run(sweep.DoublePendulum(), points, chunk_size=37, **kwargs)
    alone = sweep.run(sweep.DoublePendulum(), _points(starts[:3]), **kwargs)  # one lane each
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        serial = sweep.run(sweep.DoublePendulum(), points, **kwargs)
    finally:
        numba.set_num_threads(threads)
    for name in FINAL + ("winding_theta1", "energy_final", "flip_time"):
        np.testing.assert_array_equal(chunked[name].values, whole[name].values)
        np.testing.assert_array_equal(serial[name].values, whole[name].values)
        np.testing.assert_array_equal(alone[name].values, whole[name].values[:3])


def test_saved_trajectory_and_winding():
    ds = sweep.run(sweep.DoublePendulum(), _points(STARTS), t_end=2.0, dt=0.01, save_every=10,
                   observe=("final", "winding"))
    assert ds["theta1"].dims == ("point", "time") and ds.sizes["time"] == 21
    for name in ("theta1", "theta2", "omega1", "omega2"):
        np.testing.assert_array_equal(ds[name].values[:, -1], ds[f"{name}_final"].values)
    np.testing.assert_array_equal(ds["theta1"].values[:, 0], [s[0] for s in STARTS])
    wells = np.round(ds["theta2_final"].values / (2 * np.pi)) - \
        np.round(np.array([s[1] for s in STARTS]) / (2 * np.pi))
    np.testing.assert_array_equal(ds["winding_theta2"].values, wells)


def test_dataset_round_trips_through_netcdf(tmp_path):
    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 3), theta2_0=np.linspace(-1, 1, 4),
                      mass2=[0.5, 2.0])
    ds = sweep.run(sweep.DoublePendulum(), grid, t_end=0.5, dt=0.01, observe=("final", "flip"))
    assert ds.theta1_final.dims == ("theta1_0", "theta2_0", "mass2")
    assert ds.theta1_0.attrs["units"] == "rad"
    path = sweep.save(ds, tmp_path / "double.nc")
    back = sweep.load(path)
    np.testing.assert_array_equal(back.theta2_final.values, ds.theta2_final.values)
    assert back.attrs["system_name"] == "double_pendulum"


@pytest.mark.parametrize("make, match", [
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta0=[0.1]), t_end=1, dt=0.1),
     "names no coordinate or parameter of DoublePendulum"),
    (lambda: sweep.run(sweep.Scene(), sweep.Grid(theta1_0=[0.1]), t_end=1, dt=0.1),
     "is a system's, not the single pendulum's"),
    (lambda: sweep.Grid(phi_0=[0.1]), "unknown grid axis 'phi_0'"),
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta3_0=[0.1]), t_end=1, dt=0.1),
     "grid axis 'theta3_0' names no coordinate or parameter of DoublePendulum"),
    (lambda: sweep.Grid(mass1=[-1.0]), "mass1"),
    (lambda: sweep.DoublePendulum(mass1=0.0), "mass1"),
    (lambda: sweep.DoublePendulum(effects=(sweep.Forcing(1.0, 1.0),)), "accepts the effects"),
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[0.1]), t_end=1, dt=0.1,
                       dtype="float32", device="cuda"), "runs on the CPU only"),
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[0.1]), t_end=1, dt=0.1,
                       method="dopri5"), "fixed-step explicit Runge-Kutta"),
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[0.1]), t_end=1, dt=0.1,
                       observe=("final", "flip"), stop_early=True),
     "stop_early stops a system's trajectory at its first flip"),
    (lambda: sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[0.1]), t_end=1, dt=0.1,
                       observe=("amplitude",)), "unknown observable 'amplitude'"),
])
def test_bad_input_is_refused_before_any_compute(make, match):
    with pytest.raises((ValueError, TypeError), match=match):
        make()


def _variational(t, z):
    """The textbook equations and their variational equations d' = J d, with J d by
    complex-step differentiation (exact to rounding: no finite-difference error)."""
    y, d = z[:4], z[4:]
    return np.concatenate([textbook(t, y), np.imag(textbook(t, y + 1e-30j * d)) / 1e-30])


def test_lyapunov_max_is_the_finite_time_exponent_of_dop853_variational_equations():
    """Benettin's method: from d(0) = (1, 1, 1, 1) / 2 (sweep's tangent vector), the
    finite-time exponent over [0, T] is log |d(T)| / T whatever the renormalisations
    (they rescale, the product is the same). DOP853 on the variational equations gives
    it; sweep's RK4 tangent is the derivative of its step map, which converges to the
    flow's at order 4, so the 2 D rule of the module docstring bounds its error. One
    regular start (small angles: the exponent of a quasi-periodic orbit, ~1/T) and two
    chaotic ones."""
    starts = [(0.1, 0.1, 0.0, 0.0), (2.0, 2.5, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0)]
    t_end = 5.0
    reference = []
    for s in starts:
        z = solve_ivp(_variational, (0, t_end), list(s) + [0.5] * 4, method="DOP853",
                      rtol=1e-13, atol=1e-13).y[:, -1]
        reference.append(math.log(np.linalg.norm(z[4:])) / t_end)
    coarse, fine = (sweep.run(sweep.DoublePendulum(), _points(starts), t_end=t_end, dt=dt,
                              observe=("lyapunov",)).lyapunov_max.values
                    for dt in (0.001, 0.0005))
    tol = 2 * np.abs(coarse - fine) + 1e-9  # + DOP853's own error over 5 s
    assert np.all(tol < 1e-3)
    np.testing.assert_array_less(np.abs(coarse - np.array(reference)), tol)
    assert reference[0] < 0.2 < 1.0 < min(reference[1:])  # regular, then chaotic


def test_tangent_dynamics_follow_the_plain_trajectory_bit_for_bit():
    """The lyapunov kernel reads the accelerations' own statements (their sine and
    cosine of theta1 - theta2 paired as in the plain kernel, `vecmath.sincos_quadrant`;
    the Jacobian's extra cosines computed apart), so the state it integrates is the
    plain kernel's to the bit, on chaotic starts where one differing ulp would grow to
    a visible difference over 5 s."""
    starts = [(2.0, 2.5, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0), (0.3, -0.2, 0.4, 0.1)]
    kw = dict(t_end=5.0, dt=0.005, progress=False)
    plain = sweep.run(sweep.DoublePendulum(), _points(starts), observe=("final",), **kw)
    tangent = sweep.run(sweep.DoublePendulum(), _points(starts),
                        observe=("final", "lyapunov"), **kw)
    for name in FINAL:
        assert plain[name].values.tobytes() == tangent[name].values.tobytes(), name


@pytest.mark.parametrize("kind, stiffness, expected", [
    ("spring", 3.0, lambda g, rod, m, k: g / rod + 2 * k / m),
    ("torsion", 3.0, lambda g, rod, m, k: g / rod + 2 * k / (m * rod * rod)),
])
def test_coupled_pendula_normal_modes(kind, stiffness, expected):
    """Two pendula joined by a spring (or a torsion spring): in phase they swing at
    omega^2 = g/l (the spring stays relaxed), in anti-phase at g/l + 2k/m (or
    + 2 kappa/(m l^2)); linearise the Lagrangian of `sweep.physics.systems` by hand.
    Measured from the zero crossings of theta1 as in the double pendulum's modes."""
    g, length, mass = 9.81, 0.6, 1.5
    system = sweep.CoupledPendula(2, mass=mass, length=length, gravity=g,
                                  coupling=stiffness, kind=kind)
    amplitude = 1e-4
    for sign, omega_squared in ((+1, g / length), (-1, expected(g, length, mass, stiffness))):
        omega = math.sqrt(omega_squared)
        dt = 2 * math.pi / omega / 400
        ds = sweep.run(system, sweep.Points(theta1_0=[amplitude], theta2_0=[sign * amplitude]),
                       t_end=400 * 20 * dt, dt=dt, save_every=1, observe=())
        theta, time = ds["theta1"].values[0], ds["time"].values
        k = np.flatnonzero(np.sign(theta[:-1]) != np.sign(theta[1:]))
        crossings = time[k] - theta[k] * (time[k + 1] - time[k]) / (theta[k + 1] - theta[k])
        # as in test_small_angle_normal_modes_of_equal_masses_and_lengths
        assert math.pi / np.mean(np.diff(crossings)) == pytest.approx(omega, rel=1e-5)


def test_coupled_pendula_ring_with_damping_runs_and_loses_energy():
    system = sweep.CoupledPendula(4, coupling=2.0, topology="ring",
                                  effects=(sweep.Damping(0.2),))
    ds = sweep.run(system, sweep.Grid(theta1_0=[0.5, 1.0], theta3_0=[-0.3]), t_end=5.0,
                   dt=0.01, observe=("final", "energy"))
    assert ds.theta4_final.dims == ("theta1_0", "theta3_0")
    # mass-proportional damping: dE/dt = -2 c T <= 0, and T > 0 along the way
    assert (ds.energy_final < 0.5 * ds.energy_initial).all()


def test_cuda_kernel_agrees_with_the_cpu_kernel():
    """device="cuda" (numba's CUDA simulator on CI; SWEEP_REAL_CUDA=1 on a GPU): one
    thread per trajectory from the same per-trajectory code as the CPU lanes. CUDA's
    sine is not sweep's polynomial (both within an ulp or two of the true value), so the
    results agree to rounding: over 300 steps of these regular and flipping (not yet
    chaotic) starts ~1e-13 measured; 1e-10 rad leaves room, while any difference in the
    arithmetic (a term, a stage, a load) is of order 1e-3 or more."""
    starts = STARTS + [(-2.5, 2.9, 0.0, 0.0)]
    kwargs = dict(t_end=3.0, dt=0.01, observe=("final", "winding", "energy", "flip",
                                               "lyapunov"))
    system = sweep.DoublePendulum(effects=(sweep.Damping(0.05),))
    cpu = sweep.run(system, _points(starts), **kwargs)
    gpu = sweep.run(system, _points(starts), device="cuda", **kwargs)
    assert gpu.attrs["device"] == "cuda"
    np.testing.assert_array_equal(gpu.status.values, cpu.status.values)
    for name in FINAL + ("energy_final", "lyapunov_max"):
        np.testing.assert_allclose(gpu[name].values, cpu[name].values, rtol=0, atol=1e-10)
    np.testing.assert_array_equal(gpu.winding_theta2.values, cpu.winding_theta2.values)
    np.testing.assert_allclose(gpu.flip_time.values, cpu.flip_time.values, rtol=0, atol=1e-10)
    early = sweep.run(system, _points(starts), device="cuda", t_end=3.0, dt=0.01,
                      observe=("flip",), stop_early=True, save_every=None)
    np.testing.assert_array_equal(early.flip_time.values, gpu.flip_time.values)
    saved = sweep.run(system, _points(starts[:2]), device="cuda", t_end=1.0, dt=0.01,
                      save_every=25, observe=("final",))
    np.testing.assert_array_equal(saved.theta1.values[:, -1], saved.theta1_final.values)


def _lagrange(t, y, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=G, c1=0.0, c2=0.0, a=0.0, nu=0.0):
    """The double pendulum from Lagrange's equations written out here, solved for the
    accelerations with NumPy: joint torques Q1 = -c1 w1 + c2 (w2 - w1), Q2 = -c2 (w2 -
    w1), and a pivot driven as a cos(nu t), i.e. gravity g + y_p'' = g - a nu^2 cos(nu t)
    in the pivot's frame."""
    th1, th2, w1, w2 = y
    d = th1 - th2
    geff = g - a * nu * nu * np.cos(nu * t)
    mass = np.array([[(m1 + m2) * l1 * l1, m2 * l1 * l2 * np.cos(d)],
                     [m2 * l1 * l2 * np.cos(d), m2 * l2 * l2]])
    q1 = -c1 * w1 + c2 * (w2 - w1)
    q2 = -c2 * (w2 - w1)
    rhs = np.array([q1 - m2 * l1 * l2 * np.sin(d) * w2 * w2 - (m1 + m2) * geff * l1 * np.sin(th1),
                    q2 + m2 * l1 * l2 * np.sin(d) * w1 * w1 - m2 * geff * l2 * np.sin(th2)])
    a1, a2 = np.linalg.solve(mass, rhs)
    return [w1, w2, a1, a2]


def test_joint_damping_and_a_driven_pivot_match_dop853():
    params = {"m1": 1.2, "m2": 0.8, "l1": 0.9, "l2": 0.7, "c1": 0.3, "c2": 0.2, "a": 0.05,
              "nu": 30.0}
    system = sweep.DoublePendulum(mass1=1.2, mass2=0.8, length1=0.9, length2=0.7,
                                  damping1=0.3, damping2=0.2, pivot_amplitude=0.05,
                                  pivot_frequency=30.0)
    assert system.flip_energy is None  # the drive feeds energy in
    t_end, dt = 2.0, 0.0005            # nu dt = 0.015: the drive resolved
    coarse, fine = (_finals(sweep.run(system, _points(STARTS), t_end=t_end, dt=h,
                                      observe=("final",))) for h in (dt, dt / 2))
    reference = np.array([solve_ivp(lambda t, y: _lagrange(t, y, **params), (0, t_end),
                                    list(s), method="DOP853", rtol=1e-13, atol=1e-13
                                    ).y[:, -1] for s in STARTS])
    tol = 2 * np.abs(coarse - fine) + 1e-10  # 2 D (module docstring) + DOP853's error
    assert np.all(tol < 1e-6)
    np.testing.assert_array_less(np.abs(coarse - reference), tol)


def test_a_joint_damping_axis_switches_joint_damping_on():
    ds = sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[1.0], damping2=[0.0, 0.4]),
                   t_end=5.0, dt=0.01, observe=("energy",))
    assert ds.damping2.attrs["units"] == "kg m2 s-1"
    lost = (ds.energy_initial - ds.energy_final).values[0]
    # without damping RK4 keeps the energy to ~1e-7 here; 0.4 N m s takes a good part
    assert abs(lost[0]) < 1e-5 and lost[1] > 0.1


def test_the_docstring_lists_exactly_the_grid_axes_and_outputs_of_a_double_pendulum():
    # The Notes' "Grid axes:" paragraph names every axis in double backticks; the
    # placeholder ``<effect axis>_<angle>`` and the example ``torque_theta2`` (an axis
    # only with a Torque in effects) come after "An effect on one angle given".
    import re

    notes = sweep.DoublePendulum.__doc__.split("Grid axes:")[1]
    axes_text = notes.split("An effect on one angle given")[0]
    documented = re.findall(r"``([a-z0-9_]+)``", axes_text)
    assert sorted(documented) == sorted(sweep.DoublePendulum().accepted_axes())
    outputs = notes.split("Outputs")[1].split("Examples")[0]
    from sweep.system_observables import SYSTEM_OBSERVABLES

    assert set(re.findall(r'``"([a-z]+)"``', outputs)) == set(SYSTEM_OBSERVABLES)
