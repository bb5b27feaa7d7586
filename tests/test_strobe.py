"""Stroboscopic samples and forced-scene basins, against the naive loop and closed forms."""

import math

import numpy as np
import pytest
from shared_kernels import EVERY

import sweep
from sweep import maps
from sweep.observables import STROBE_SAMPLES

import naive

PERIOD_STEPS = 40


def _forced(model="nonlinear", c=0.3, amplitude=1.1, frequency=1.3, phase=0.4):
    return sweep.Scene(gravity=1.0, length=1.0, model=model,
                       effects=(sweep.Damping(c), sweep.Forcing(amplitude, frequency, phase)))


def test_strobe_samples_are_the_states_at_the_forcing_phase():
    frequency = 1.3
    dt = 2 * np.pi / frequency / PERIOD_STEPS
    n_steps, n_transient = 30 * PERIOD_STEPS + 7, 5 * PERIOD_STEPS + 3
    ds = sweep.run(_forced(), sweep.Grid(theta0=[0.4, -2.0], omega0=[1.5]), t_end=n_steps * dt,
                   dt=dt, t_transient=n_transient * dt, observe=("strobe",))
    assert ds.strobe_theta.dims == ("theta0", "omega0", "strobe")
    np.testing.assert_array_equal(ds.strobe, np.arange(1 - STROBE_SAMPLES, 1))
    for k, theta0 in enumerate([0.4, -2.0]):
        ref = naive.integrate(theta0, 1.5, t_end=n_steps * dt, dt=dt, model="nonlinear",
                              gravity=1.0, length=1.0, damping=0.3, forcing_amplitude=1.1,
                              forcing_frequency=frequency, forcing_phase=0.4)
        # samples at steps n_transient + m * PERIOD_STEPS; keep the last 16
        steps = np.arange(n_transient, n_steps + 1, PERIOD_STEPS)[-STROBE_SAMPLES:]
        # same arithmetic up to round-off: 1e-12 over ~1200 steps of a damped scene (see
        # test_naive for the budget)
        np.testing.assert_allclose(ds.strobe_theta.values[k, 0], ref["theta_all"][steps],
                                   rtol=0, atol=1e-11)
        np.testing.assert_allclose(ds.strobe_omega.values[k, 0], ref["omega_all"][steps],
                                   rtol=0, atol=1e-11)


def test_cosine_forcing_is_phase_half_pi():
    """Literature writes A cos(W t); phase = pi/2 must give exactly that motion."""
    frequency, dt = 1.0, 2 * np.pi / 200
    ds = sweep.run(_forced(c=0.2, amplitude=1.66, frequency=frequency, phase=np.pi / 2),
                   sweep.Grid(theta0=[0.3]), t_end=10 * 2 * np.pi, dt=dt,
                   observe=("final",))
    theta, omega = 0.3, 0.0
    for n in range(2000):  # textbook RK4 with an explicit cosine
        t = n * dt

        def f(t, th, om):
            return om, 1.66 * math.cos(frequency * t) - 0.2 * om - math.sin(th)

        k1 = f(t, theta, omega)
        k2 = f(t + dt / 2, theta + dt / 2 * k1[0], omega + dt / 2 * k1[1])
        k3 = f(t + dt / 2, theta + dt / 2 * k2[0], omega + dt / 2 * k2[1])
        k4 = f(t + dt, theta + dt * k3[0], omega + dt * k3[1])
        theta += dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        omega += dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    # sin(x + pi/2) and cos(x) differ by at most 1 ulp per evaluation (x < 63 rad), and
    # the 10 periods here amplify round-off only mildly: 1e-10 rad
    assert abs(float(ds.theta_final.item()) - theta) < 1e-10
    assert abs(float(ds.omega_final.item()) - omega) < 1e-10


def test_linear_forced_scene_has_one_period_one_attractor_at_the_closed_form():
    c, amplitude, frequency = 0.5, 0.8, 1.7
    dt = 2 * np.pi / frequency / PERIOD_STEPS
    periods, transient = 80, 60
    ds = sweep.run(_forced("linear", c, amplitude, frequency, 0.0),
                   sweep.Grid(theta0=np.linspace(-1, 1, 5), omega0=np.linspace(-1, 1, 4)),
                   t_end=periods * PERIOD_STEPS * dt, dt=dt,
                   t_transient=transient * PERIOD_STEPS * dt, observe=("strobe",))
    labels = maps.basins(ds)
    assert (labels.values == 0).all()
    assert list(labels.attrs["attractor_period"]) == [1]
    assert list(labels.attrs["attractor_turns_per_period"]) == [0.0]
    # particular solution theta_p = R sin(W t - delta) sampled at t = k T
    w0sq = 1.0
    R = amplitude / math.hypot(w0sq - frequency**2, c * frequency)
    delta = math.atan2(c * frequency, w0sq - frequency**2)
    exact = (R * math.sin(-delta), R * frequency * math.cos(-delta))
    # transient: exp(-c/2 * 60 T) = 1e-10 relative; RK4 at 40 steps per period has a
    # global error ~ (W dt)^4 / 120 * R ~ 5e-6 rad: 2e-5 bounds both
    np.testing.assert_allclose(labels.attrs["attractor_theta"][0],
                               exact[0] % (2 * np.pi), atol=2e-5)
    np.testing.assert_allclose(labels.attrs["attractor_omega"][0], exact[1], atol=2e-5)


def test_forced_pendulum_basins_have_coexisting_rotations_and_a_fractal_boundary():
    """g = L = 1, c = 0.2, A = 1.66, W = 1, cos forcing: the classic case whose basins
    have fractal boundaries (Daza et al. 2016 use this forced pendulum)."""
    scene = _forced(c=0.2, amplitude=1.66, frequency=1.0, phase=np.pi / 2)
    n = 61
    period = 2 * np.pi
    ds = sweep.run(scene, sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n),
                                     omega0=np.linspace(-4, 4, n)),
                   t_end=80 * period, dt=period / 100, t_transient=60 * period,
                   observe=("strobe",))
    labels = maps.basins(ds)
    turns = set(labels.attrs["attractor_turns_per_period"])
    assert {-1.0, 1.0} <= turns  # rotations in both senses coexist
    assert (labels.values == maps.UNRESOLVED).mean() < 0.02
    entropy = sweep.metrics.basin_entropy(labels.values, box_size=5)
    assert entropy.fractal_boundary  # Sbb > log 2: sufficient for a fractal boundary


def test_strobe_refuses_what_it_cannot_sample():
    with pytest.raises(ValueError, match=r"observable 'strobe' samples once per forcing "
                                         r"period and needs a forcing"):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1]), t_end=1.0, dt=0.1,
                  observe=("strobe",))
    with pytest.raises(ValueError, match=r"forcing period 2 pi / 1\.3 is not a whole number "
                                         r"of steps dt = 0\.1 .*accepted: dt = period / N"):
        sweep.run(_forced(), sweep.Grid(theta0=[0.1]), t_end=10.0, dt=0.1,
                  observe=("strobe",))
    with pytest.raises(ValueError, match=r"basins of a forced scene need stroboscopic"):
        maps.basins(sweep.run(_forced(), sweep.Grid(theta0=[0.1]), t_end=1.0, dt=0.1,
                              observe=EVERY))  # every observable but strobe: a shared kernel
