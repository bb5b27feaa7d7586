"""Progress: a tqdm bar where someone can see it (a terminal, a notebook), never under CI
unless asked for; chunks sized so that a long run's bar moves about every second."""

import numpy as np
import pytest

import sweep
from sweep import _config
from sweep.engine import default_chunk_size, validate_settings
from sweep.execution import progress

SCENE = sweep.Scene(effects=(sweep.Damping(0.3),))
GRID = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 40))


def test_progress_true_shows_a_bar_with_rate_and_time_left(capsys, monkeypatch):
    monkeypatch.setenv("CI", "true")  # an explicit True wins over CI
    sweep.run(SCENE, GRID, t_end=1.0, dt=0.01, progress=True)
    err = capsys.readouterr().err
    assert "sweep: 100%" in err and " 40/40 [" in err and "traj/s]" in err
    assert "00:00<00:00" in err  # elapsed < remaining


@pytest.mark.parametrize("ci", ["true", "1", "yes"])
def test_by_default_there_is_no_bar_under_ci(capsys, monkeypatch, ci):
    monkeypatch.setenv("CI", ci)
    monkeypatch.setattr("sys.stderr.isatty", lambda: True, raising=False)
    assert not progress.wanted(None)
    sweep.run(SCENE, GRID, t_end=1.0, dt=0.01)
    assert capsys.readouterr().err == ""


def test_by_default_a_terminal_gets_a_bar_and_a_pipe_does_not(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.setattr("sys.stderr.isatty", lambda: True, raising=False)
    assert progress.wanted(None) and not progress.wanted(False)
    monkeypatch.setattr("sys.stderr.isatty", lambda: False, raising=False)
    assert not progress.wanted(None)  # no terminal and no notebook
    monkeypatch.setenv("CI", "false")
    assert not progress.wanted(None) and progress.wanted(True)


def test_progress_false_prints_nothing(capsys):
    sweep.run(SCENE, GRID, t_end=1.0, dt=0.01, progress=False)
    assert capsys.readouterr().err == ""


def _settings(t_end, dt):
    return validate_settings(t_end=t_end, dt=dt, t0=0.0, t_transient=0.0, save_every=None,
                             method="rk4")


def test_default_chunks_hold_about_a_second_of_work():
    # 2,000 steps: the CHUNK_SIZE cap (65,536 trajectories, 1.3e8 trajectory-steps)
    assert default_chunk_size(_settings(20.0, 0.01)) == _config.CHUNK_SIZE
    # 30,000 steps: 3e8 / 3e4 = 10,000 trajectories, rounded down to whole CHUNK_MIN
    long = default_chunk_size(_settings(300.0, 0.01))
    assert long % _config.CHUNK_MIN == 0 and long * 30_000 <= _config.CHUNK_WORK
    assert (long + _config.CHUNK_MIN) * 30_000 > _config.CHUNK_WORK
    # 10^7 steps: never fewer than CHUNK_MIN trajectories
    assert default_chunk_size(_settings(1e5, 0.01)) == _config.CHUNK_MIN
    # early stop: the cap whatever t_end (most trajectories end long before it, and a
    # chunk's slowest trajectory keeps the other threads waiting at its end)
    assert default_chunk_size(_settings(300.0, 0.01), stop_early=True) == _config.CHUNK_SIZE
    assert default_chunk_size(_settings(1e5, 0.01), stop_early=True) == _config.CHUNK_SIZE


def test_the_default_chunks_give_the_same_result_as_one_chunk(monkeypatch):
    """Results do not depend on the chunking; here the default cuts 4,000 trajectories x
    3,000 steps into 2 chunks (CHUNK_WORK made small for the test)."""
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 4000))
    kwargs = dict(t_end=30.0, dt=0.01, observe=("final", "theta_max"), progress=False)
    whole = sweep.run(SCENE, grid, chunk_size=4000, **kwargs)
    monkeypatch.setattr(_config, "CHUNK_WORK", _config.CHUNK_MIN * 3000)
    assert default_chunk_size(_settings(30.0, 0.01)) == _config.CHUNK_MIN  # 2 chunks
    chunked = sweep.run(SCENE, grid, **kwargs)
    for name in whole.data_vars:
        assert whole[name].values.tobytes() == chunked[name].values.tobytes()
