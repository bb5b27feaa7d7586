"""``strobe_samples``: any number of stroboscopic samples, against the naive RK4 loop
(tests/naive.py, an independent plain-Python integrator), with early stop, through
checkpoints and run files, and refused where it cannot apply."""

import numpy as np
import pytest

import sweep
from sweep import maps
from sweep.toml_spec import load_run

import naive

PERIOD_STEPS = 40
FREQUENCY = 1.3  # rad/s
DT = 2 * np.pi / FREQUENCY / PERIOD_STEPS


def _forced(c=0.3, amplitude=1.1):
    return sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(c), sweep.Forcing(amplitude, FREQUENCY, 0.4)))


@pytest.mark.parametrize("samples, taken", [
    (2, 7),    # the smallest count; the ring wrapped three times, rotated by one
    (5, 10),   # odd; a whole number of turns of the ring: no rotation
    (40, 45),  # larger than the default 16; rotated by 5
    (40, 20),  # the ring not yet full: the 20 oldest places stay NaN
])  # (40 samples of 1-3 starts: test_period_map's kernel, compiled once for both files)
def test_any_count_keeps_the_last_samples_at_the_forcing_phase(samples, taken):
    n_transient = 5 * PERIOD_STEPS + 3
    n_steps = n_transient + (taken - 1) * PERIOD_STEPS + 7  # `taken` sampling steps
    ds = sweep.run(_forced(), sweep.Grid(theta0=[0.4, -2.0], omega0=[1.5]),
                   t_end=n_steps * DT, dt=DT, t_transient=n_transient * DT,
                   observe=("strobe",), strobe_samples=samples, progress=False)
    assert ds.sizes["strobe"] == samples and ds.attrs["strobe_samples"] == samples
    np.testing.assert_array_equal(ds.strobe, np.arange(1 - samples, 1))
    kept = min(samples, taken)
    for k, theta0 in enumerate([0.4, -2.0]):
        ref = naive.integrate(theta0, 1.5, t_end=n_steps * DT, dt=DT, model="nonlinear",
                              gravity=1.0, length=1.0, damping=0.3, forcing_amplitude=1.1,
                              forcing_frequency=FREQUENCY, forcing_phase=0.4)
        steps = np.arange(n_transient, n_steps + 1, PERIOD_STEPS)
        assert steps.size == taken
        for name, reference in (("strobe_theta", ref["theta_all"]),
                                ("strobe_omega", ref["omega_all"])):
            values = ds[name].values[k, 0]
            assert np.isnan(values[:samples - kept]).all()
            # the same RK4 arithmetic up to round-off: 1e-11 over ~1700 steps of a damped
            # scene (the budget of test_naive, as in test_strobe)
            np.testing.assert_allclose(values[samples - kept:], reference[steps[-kept:]],
                                       rtol=0, atol=1e-11)


@pytest.mark.parametrize("samples", [5, 40])
def test_stop_early_with_other_counts_finds_the_full_runs_periods(samples):
    """The early-stop test looks for periods up to min(N/2, 8) in a full ring of N:
    with 5 samples (periods 1, 2) and with 40 (periods up to 8, the ring filled only
    after 40 forcing periods) the stopped trajectories have the periods of the full
    run, and some did stop (their samples are from earlier forcing periods)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 15), omega0=np.linspace(-3, 3, 11))
    period = 2 * np.pi
    kwargs = dict(t_end=120 * period, dt=period / 100, t_transient=20 * period,
                  observe=("strobe",), strobe_samples=samples, progress=False)
    full = sweep.run(scene, grid, **kwargs)
    early = sweep.run(scene, grid, stop_early=True, **kwargs)
    np.testing.assert_array_equal(maps.period(early).values, maps.period(full).values)
    assert (maps.period(full) > 0).mean() > 0.9  # the question is not vacuous
    stopped = (early.strobe_theta != full.strobe_theta).any("strobe")
    assert stopped.mean() > 0.5


def test_resuming_with_another_count_is_refused(tmp_path):
    """The count is part of the kernel, so of the checkpoint's fingerprint; the same
    count resumes from the checkpoint without computing anything. (5 samples of 4-127
    starts: the kernel of test_cuda's CPU side.)"""
    grid = sweep.Grid(theta0=np.linspace(-2.0, 2.0, 6), omega0=[0.0])
    kwargs = dict(t_end=30 * PERIOD_STEPS * DT, dt=DT, t_transient=10 * PERIOD_STEPS * DT,
                  observe=("strobe",), chunk_size=4, checkpoint=tmp_path / "ck",
                  keep_checkpoint=True, progress=False)
    first = sweep.run(_forced(), grid, strobe_samples=5, **kwargs)
    with pytest.raises(ValueError, match=r"belongs to a different run: "
                                         r"kernel\.strobe_samples: checkpoint 5, this run 12"):
        sweep.run(_forced(), grid, strobe_samples=12, resume=True, **kwargs)
    again = sweep.run(_forced(), grid, strobe_samples=5, resume=True, **kwargs)
    assert again.strobe_theta.values.tobytes() == first.strobe_theta.values.tobytes()
    assert sweep.io.run_arguments(again)["strobe_samples"] == 5


RUN_FILE = """
[scene]
gravity = 1.0
length = 1.0
[scene.damping]
coefficient = 0.3
[scene.forcing]
amplitude = 1.1
frequency = 1.3
phase = 0.4
[grid]
theta0 = [0.4]
omega0 = [1.5]
[run]
t_end = {t_end!r}
dt = {dt!r}
t_transient = {t_transient!r}
observe = {observe}
strobe_samples = {samples}
"""


def _run_file(tmp_path, samples, observe='["strobe"]'):
    path = tmp_path / "run.toml"
    path.write_text(RUN_FILE.format(t_end=30 * PERIOD_STEPS * DT, dt=DT,
                                    t_transient=5 * PERIOD_STEPS * DT, observe=observe,
                                    samples=samples))
    return path


def test_run_file_strobe_samples(tmp_path):
    scene, grid, kwargs = load_run(_run_file(tmp_path, 24))
    assert kwargs["strobe_samples"] == 24
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    assert ds.sizes["strobe"] == 24 and ds.attrs["strobe_samples"] == 24


@pytest.mark.parametrize("samples, observe, kind, message", [
    ("1", '["strobe"]', ValueError, r"\[run\] strobe_samples must be an int from 2 to 4096"),
    ("8192", '["strobe"]', ValueError, r"\[run\] strobe_samples must be an int from 2 to "
                                       r"4096 \(samples, one per forcing period\), got 8192"),
    ("16.5", '["strobe"]', TypeError, r"\[run\] strobe_samples must be an int"),
    ('"64"', '["strobe"]', TypeError, r"\[run\] strobe_samples must be an int"),
    ("64", '["final"]', ValueError, r"\[run\] strobe_samples = 64 is read only by the "
                                    r"'strobe' observable"),
])
def test_run_file_refuses_a_bad_count_when_read(samples, observe, kind, message, tmp_path):
    with pytest.raises(kind, match=r"run\.toml: " + message):
        load_run(_run_file(tmp_path, samples, observe))


def test_adaptive_methods_refuse_strobe_whatever_the_count(no_compute):
    with pytest.raises(ValueError, match=r"observable 'strobe' is defined on the fixed step "
                                         r"grid .* adaptive method 'dopri5'"):
        sweep.run(_forced(), sweep.Grid(theta0=[0.1]), t_end=100 * DT, dt=DT,
                  method="dopri5", observe=("strobe",), strobe_samples=40)
