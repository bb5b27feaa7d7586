"""Stroboscopic samples of a system with several coordinates (``observe=("strobe",)``
on a driven `sweep.DoublePendulum` or `sweep.DeclaredSystem`), checked against two
oracles: the run's own saved trajectory (``save_every=1``: the samples are the state at
the sampled steps, so the same bits) and SciPy's DOP853 on Lagrange's equations written
out in tests/test_systems.py.
"""

import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_systems import _lagrange

import sweep

NU = 2 * np.pi  # the pivot's angular frequency [rad/s]: a period of 1 s
DT = 1 / 200    # 200 steps per drive period
PARAMS = {"m1": 1.2, "m2": 0.8, "l1": 0.9, "l2": 0.7, "c1": 0.3, "c2": 0.2, "a": 0.05,
          "nu": NU}
SYSTEM = sweep.DoublePendulum(mass1=1.2, mass2=0.8, length1=0.9, length2=0.7, damping1=0.3,
                              damping2=0.2, pivot_amplitude=0.05, pivot_frequency=NU)
STATE = ("theta1", "theta2", "omega1", "omega2")


def _starts(n):
    return sweep.Points(theta1_0=np.linspace(-2.0, 2.0, n), theta2_0=np.linspace(1.0, -1.5, n),
                        omega1_0=np.linspace(0.5, -0.5, n), omega2_0=np.zeros(n))


@pytest.mark.parametrize("n, t_transient, samples", [
    (2, 2.5, 6),    # one lane per block; the first sample at step 500, mid-period
    (20, 0.0, 4),   # 16 lanes, a padded block; the initial state is sample 0
    (3, 8.0, 5),    # only 3 samples in the run: the first 2 columns stay NaN
])
def test_samples_are_the_saved_states_at_the_sampled_steps(n, t_transient, samples):
    """The pendulum's rule: samples at steps n_transient + m 200 (m = 0, 1, ...) up to
    n_steps = 2000, the last ``samples`` of them oldest first, NaN before the first."""
    ds = sweep.run(SYSTEM, _starts(n), t_end=10.0, dt=DT, t_transient=t_transient,
                   observe=("final", "strobe"), strobe_samples=samples, save_every=1,
                   progress=False)
    steps = np.arange(round(t_transient / DT), 2001, 200)[-samples:]
    missing = samples - steps.size
    assert ds["theta1_strobe"].dims == ("point", "strobe")
    np.testing.assert_array_equal(ds["strobe"].values, np.arange(1 - samples, 1))
    assert ds.attrs["strobe_samples"] == samples
    assert ds.attrs["strobe_frequency"] == "pivot_frequency"
    for name in STATE:
        strobe = ds[f"{name}_strobe"].values
        assert np.isnan(strobe[:, :missing]).all()
        np.testing.assert_array_equal(strobe[:, missing:], ds[name].values[:, steps])


def test_samples_match_dop853_at_the_drive_period():
    """Lagrange's equations (joint damping, pivot a cos(nu t)) by DOP853 at the strobe
    times t = 3 + m (t_transient 3 s, period 1 s). Tolerance: RK4's global error is C
    dt^4 and the runs at dt and dt/2 differ by D = (15/16) C dt^4, so 2 D bounds the dt
    run's error (as in tests/test_systems.py), plus DOP853's own ~1e-12 at rtol = atol
    = 1e-13 over 10 s."""
    starts = [(0.3, -0.2, 0.0, 0.0), (2.0, 1.0, 0.5, -0.5), (1.0, 2.5, 0.0, 1.0)]
    points = sweep.Points(**{f"{name}_0": [s[k] for s in starts]
                             for k, name in enumerate(STATE)})
    coarse, fine = (np.stack([sweep.run(SYSTEM, points, t_end=10.0, dt=h, t_transient=3.0,
                                        observe=("strobe",), strobe_samples=8,
                                        progress=False)[f"{name}_strobe"].values
                              for name in STATE], axis=1) for h in (DT, DT / 2))
    times = 3.0 + np.arange(8)
    reference = np.stack([solve_ivp(lambda t, y: _lagrange(t, y, **PARAMS), (0, 10.0),
                                    list(s), method="DOP853", rtol=1e-13, atol=1e-13,
                                    t_eval=times).y for s in starts])
    tol = 2 * np.abs(coarse - fine) + 1e-10
    assert np.all(tol < 1e-5)
    np.testing.assert_array_less(np.abs(coarse - reference), tol)


def test_a_frequency_axis_samples_each_trajectory_at_its_own_period():
    """pivot_frequency as a grid axis: each trajectory's samples are its own saved states
    every 2 pi / (nu dt) steps (100 and 200 here)."""
    grid = sweep.Grid(theta1_0=[0.5, 1.5], pivot_frequency=[NU, 2 * NU])
    ds = sweep.run(sweep.DoublePendulum(pivot_amplitude=0.05), grid, t_end=4.0, dt=DT,
                   observe=("strobe",), strobe_samples=3, save_every=1, progress=False)
    for k, every in enumerate((200, 100)):
        np.testing.assert_array_equal(ds["theta2_strobe"].values[:, k],
                                      ds["theta2"].values[:, k, [800 - 2 * every,
                                                                 800 - every, 800]])


def test_a_declared_system_samples_at_its_declared_drive():
    """Two uncoupled damped pendula, each forced: a DeclaredSystem naming its drive's
    frequency parameter samples every 2 pi / (W dt) steps."""
    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    system = sweep.DeclaredSystem(_two_forced_pendula(Coordinate, Parameter, SystemDeclaration),
                                  drive_frequency_axis="frequency", frequency=2.0)
    ds = sweep.run(system, sweep.Points(p1_0=[0.5], p2_0=[-0.5]), t_end=10 * np.pi,
                   dt=np.pi / 100, observe=("strobe",), strobe_samples=4, save_every=1,
                   progress=False)
    assert ds.attrs["strobe_frequency"] == "frequency"
    np.testing.assert_array_equal(ds["v2_strobe"].values[0], ds["v2"].values[0, -301::100])
    again = pickle.loads(pickle.dumps(system))  # as a Dask worker gets it
    assert again == system and again.drive_frequency_parameter.axis == "frequency"


def _two_forced_pendula(Coordinate, Parameter, SystemDeclaration):
    """theta_i'' = -sin theta_i - c theta_i' + A cos(W t), i = 1, 2: the single
    pendulum's equation with g/L = 1, damping c and a forcing A cos(W t), twice."""
    coords = tuple(Coordinate(f"p{k}", f"v{k}", f"q{k}", f"w{k}") for k in (1, 2))
    parameters = (
        Parameter("friction", "friction", "cf", "s-1", "1/s", "damping rate", minimum=0.0,
                  default=0.2),
        Parameter("amplitude", "amplitude", "af", "s-2", "1/s^2", "forcing amplitude",
                  minimum=0.0, default=1.0),
        Parameter("frequency", "frequency", "wf", "rad s-1", "rad/s", "forcing frequency",
                  minimum=0.0, default=1.0))
    return SystemDeclaration(
        name="two_forced_pendula", coordinates=coords, parameters=parameters,
        accelerations=tuple(f"-sin(q{k}) - cf*w{k} + af*cos(wf*t)" for k in (1, 2)),
        potential="2 - cos(q1) - cos(q2)")


@pytest.mark.parametrize("system, kwargs, match", [
    (sweep.DoublePendulum(), {}, "has no periodic drive; accepted: a driven system"),
    (sweep.DoublePendulum(pivot_amplitude=0.1), {},
     r"needs pivot_frequency > 0, got 0\.0; accepted: pivot_frequency > 0 rad/s \(every "
     r"value, a drive period that is a whole number of steps dt = .*\), or observe "
     r"without 'strobe'"),
    (SYSTEM, {"dt": 0.003}, "the drive period 2 pi / 6.28318"),
    (SYSTEM, {"observe": ("final",), "strobe_samples": 8}, "read only by the 'strobe'"),
    (SYSTEM, {"strobe_samples": 1}, "strobe_samples must be an int from 2 to 4096"),
    (SYSTEM, {"stop_early": True}, "stop_early stops a system's trajectory at its first flip"),
])
def test_bad_strobe_runs_are_refused_before_any_compute(system, kwargs, match):
    args = {"t_end": 3.0, "dt": DT, "observe": ("strobe",), "progress": False, **kwargs}
    with pytest.raises(ValueError, match=match):
        sweep.run(system, sweep.Points(theta1_0=[0.1]), **args)


def test_a_declared_system_refuses_a_drive_axis_it_lacks():
    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    declaration = _two_forced_pendula(Coordinate, Parameter, SystemDeclaration)
    with pytest.raises(ValueError, match="drive_frequency_axis = 'omega' names no parameter"):
        sweep.DeclaredSystem(declaration, drive_frequency_axis="omega")


def test_a_declared_systems_drive_survives_an_effect_the_grid_switches_on():
    """A grid axis of an effect on one coordinate (``damping_p1``) adds that effect to
    the system it runs (`System.switched_on`); a DeclaredSystem keeps its
    ``drive_frequency_axis`` then (it lost it, and its strobe run was refused as
    undriven). Validation only: nothing is compiled."""
    from sweep.engine import prepare
    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    declared = sweep.DeclaredSystem(_two_forced_pendula(Coordinate, Parameter,
                                                        SystemDeclaration),
                                    drive_frequency_axis="frequency", frequency=0.75)
    switched = declared.switched_on(("damping_p1",))
    assert switched.effects == (sweep.Damping(0.0, on="p1"),)
    assert switched.drive_frequency_parameter.axis == "frequency"
    period = 2 * np.pi / 0.75
    spec = prepare(declared, sweep.Grid(p1_0=[0.1, 0.2], damping_p1=[0.0, 0.1]),
                   t_end=20 * period, dt=period / 100, observe=("strobe",))[1]
    assert spec.strobe_frequency == declared.drive_frequency_parameter.symbol


def test_cuda_kernel_samples_as_the_cpu_kernel():
    """device="cuda" (numba's CUDA simulator on CI): the same sampling lines; CUDA's
    sine is not sweep's polynomial, so the samples agree to rounding (1e-10 rad, as in
    tests/test_systems.py's CUDA test, over these 400 regular steps)."""
    kwargs = dict(t_end=2.0, dt=DT, t_transient=0.5, observe=("strobe",), strobe_samples=3,
                  progress=False)
    cpu = sweep.run(SYSTEM, _starts(2), **kwargs)
    gpu = sweep.run(SYSTEM, _starts(2), device="cuda", **kwargs)
    for name in STATE:
        np.testing.assert_allclose(gpu[f"{name}_strobe"].values, cpu[f"{name}_strobe"].values,
                                   rtol=0, atol=1e-10)


def test_a_forcing_on_one_coordinate_is_the_drive_that_strobe_samples():
    """With no drive of its own, a system forced on one coordinate (`sweep.Forcing(A, W,
    on="theta1")`, a generalized force A sin(W t)) is sampled once per 2 pi / W, the
    forcing's frequency axis ``forcing_frequency_theta1``: the samples are the saved
    states at those steps, bit for bit, and a grid over that axis samples each start at
    its own period."""
    w = 2.0
    period = 2 * np.pi / w
    system = sweep.DoublePendulum(effects=(sweep.Damping(0.5),
                                           sweep.Forcing(3.0, w, on="theta1")))
    assert system.drive_frequency_parameter.axis == "forcing_frequency_theta1"
    starts = sweep.Points(theta1_0=[0.1, 2.0, -1.0], theta2_0=[0.0, 1.0, 2.5])
    kw = dict(t_end=12 * period, dt=period / 100, progress=False)
    sampled = sweep.run(system, starts, observe=("strobe",), strobe_samples=4, **kw)
    saved = sweep.run(system, starts, observe=("final",), save_every=100, **kw)
    for name in ("theta1", "theta2", "omega1", "omega2"):
        assert sampled[f"{name}_strobe"].values.tobytes() == \
            np.ascontiguousarray(saved[name].values[:, -4:]).tobytes(), name
    two = sweep.run(system, sweep.Grid(theta1_0=[0.5], forcing_frequency_theta1=[w, w / 2]),
                    t_end=12 * period, dt=period / 100, observe=("strobe",),
                    strobe_samples=2, progress=False)
    alone = sweep.run(sweep.DoublePendulum(effects=(sweep.Damping(0.5),
                                                    sweep.Forcing(3.0, w / 2, on="theta1"))),
                      sweep.Points(theta1_0=[0.5], theta2_0=[0.0]), observe=("strobe",),
                      strobe_samples=2, **kw)
    assert two.theta1_strobe.values[0, 1].tobytes() == alone.theta1_strobe.values[0].tobytes()
