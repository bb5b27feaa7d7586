"""Simulate only what the question needs: stop a trajectory once its fate is decided,
and get the same answer as the full run."""

import numpy as np
import pytest

import sweep
from sweep import maps


@pytest.fixture(scope="module")
def damped_grid():
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 41), omega0=np.linspace(-12, 12, 41))


def test_capture_well_matches_the_full_run_map(damped_grid):
    scene = sweep.Scene(effects=(sweep.Damping(0.4),))
    full = sweep.run(scene, damped_grid, t_end=30.0, dt=0.01,
                     observe=("final", "capture", "energy"))
    # once below the separatrix energy the well cannot change: the well seen at capture
    # is the well the run ends in
    np.testing.assert_array_equal(full.well, maps.well(full))
    captured = np.isfinite(full.capture_time)
    assert captured.mean() > 0.99
    assert (full.capture_time.values[captured] <= 30.0).all()
    # a start inside the separatrix is captured at t0
    inside = full.sel(theta0=0.0, omega0=0.0, method="nearest")
    assert float(inside.capture_time) == 0.0


def test_stop_early_gives_the_same_wells_faster(damped_grid):
    scene = sweep.Scene(effects=(sweep.Damping(0.4),))
    kwargs = dict(t_end=30.0, dt=0.01, observe=("capture",))
    full = sweep.run(scene, damped_grid, **kwargs)
    early = sweep.run(scene, damped_grid, stop_early=True, **kwargs)
    # bit-identical: the states up to the capture step are the same
    assert early.drop_attrs().identical(full.drop_attrs())


def test_stop_early_on_forced_basins_gives_the_same_labels():
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 41), omega0=np.linspace(-4, 4, 41))
    period = 2 * np.pi
    kwargs = dict(t_end=100 * period, dt=period / 100, t_transient=20 * period,
                  observe=("strobe",))
    full = maps.basins(sweep.run(scene, grid, **kwargs))
    early = maps.basins(sweep.run(scene, grid, stop_early=True, **kwargs))
    # labels are ranked by basin size, so compare the partitions through the catalogue:
    # the attractors' (period, turns per period) must agree label by label
    for key in ("attractor_period", "attractor_turns_per_period", "attractor_size"):
        np.testing.assert_array_equal(full.attrs[key], early.attrs[key])
    np.testing.assert_array_equal(full.values, early.values)


def test_stop_early_refuses_what_needs_the_whole_run():
    scene = sweep.Scene(effects=(sweep.Damping(0.4),))
    grid = sweep.Grid(theta0=[1.0])
    with pytest.raises(ValueError, match=r"stop_early=True: observable 'final' needs the "
                                         r"whole run; accepted with stop_early: strobe, attractor, "
                                         r"capture"):
        sweep.run(scene, grid, t_end=1.0, dt=0.1, observe=("final", "capture"),
                  stop_early=True)
    with pytest.raises(ValueError, match=r"cannot save trajectories"):
        sweep.run(scene, grid, t_end=1.0, dt=0.1, observe=("capture",), stop_early=True,
                  save_every=1)
    with pytest.raises(ValueError, match=r"observable 'capture' is for unforced scenes"):
        sweep.run(sweep.Scene(effects=(sweep.Forcing(1.0, 1.0),)), grid, t_end=1.0, dt=0.1,
                  observe=("capture",))
    with pytest.raises(TypeError, match=r"stop_early must be True or False, got 'yes'"):
        sweep.run(scene, grid, t_end=1.0, dt=0.1, observe=("capture",), stop_early="yes")


def test_basins_from_a_capture_only_run(damped_grid):
    scene = sweep.Scene(effects=(sweep.Damping(0.4),))
    full = sweep.run(scene, damped_grid, t_end=30.0, dt=0.01, observe=("final", "energy"))
    early = sweep.run(scene, damped_grid, t_end=30.0, dt=0.01, observe=("capture",),
                      stop_early=True)
    np.testing.assert_array_equal(maps.basins(early), maps.basins(full))
