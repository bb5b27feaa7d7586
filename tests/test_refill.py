"""Lane refill (`sweep.kernels.refill`): in an early-stopped run a lane whose trajectory
settles takes the next waiting one. Every trajectory must get the same bits as without
refill, whatever the block, the group and the number of trajectories, including those
that never settle and those that fail."""

import numpy as np
import pytest

import sweep
from sweep import kernels
from sweep.kernels import KernelSpec, Status

DT = 2 * np.pi / (2 / 3) / 150  # 150 steps per forcing period
N_STEPS = 150 * 60


def _table(n, seed=3):
    """Damped forced starts (A = 1.2, W = 2/3, c = 0.5, g/L = 1: several attractors,
    settling at very different times); one with overflowing damping."""
    rng = np.random.default_rng(seed)
    column = {name: k for k, name in enumerate(sweep.physics.parameter_names())}
    params = np.zeros((n, len(column)))
    params[:, column["theta0"]] = rng.uniform(-np.pi, np.pi, n)
    params[:, column["omega0"]] = rng.uniform(-2.0, 2.0, n)
    params[:, column["damping"]] = 0.5
    params[:, column["forcing_amplitude"]] = rng.choice([1.2, 1.07], n)
    params[:, column["forcing_frequency"]] = 2 / 3
    params[:, column["length"]] = 1.0
    params[:, column["gravity"]] = 1.0
    params[n // 2, column["damping"]] = 1e5  # far outside RK4's stability region
    return params


def _call(spec, params, n_transient=150 * 20, extra=()):
    """``extra``: the kernel's arguments after ``saved`` (an attractor catalogue)."""
    out = np.full((params.shape[0], kernels.n_columns(spec)), -7.0)
    status = np.full(params.shape[0], 99, dtype=np.int8)
    kernels.build(spec)(params, 0.0, DT, N_STEPS, n_transient, 1, out, status,
                        np.empty((0, 2, 0)), *extra)
    return out, status


@pytest.mark.parametrize("block, shared", [(8, False), (64, False), (64, True)])
def test_refill_gives_the_same_bits_as_blocks_that_wait(block, shared):
    """Per-lane drive sines, and (shared) a table of the sines over the steps against
    the waiting kernel's sine per block."""
    params = _table(1500)  # not a multiple of the block: some lanes idle at the end
    kwargs = dict(stop_early=True, block=block, shared_forcing=shared)
    waiting = _call(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), **kwargs),
                    params)
    refill = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), refill=True,
                        **kwargs)
    assert refill.refill and "lane_ks" in kernels.source(refill)
    assert ("tab_" in kernels.source(refill)) == shared
    refilled = _call(refill, params)
    np.testing.assert_array_equal(refilled[1], waiting[1])
    assert refilled[0].tobytes() == waiting[0].tobytes()  # NaN where NaN, bits elsewhere
    assert (waiting[1] == Status.NONFINITE).sum() == 1


@pytest.mark.parametrize("samples", [2, 40])
def test_refill_gives_the_same_bits_with_other_strobe_counts(samples):
    """``strobe_samples`` != 16 in both kernels: a ring of 2 (the fewest: only period 1
    can settle) and of 40 (full at the 40th of the 41 samples after the transient, so
    only the last two checks can stop a trajectory). With the shared drive's table of
    sines (one frequency in the table), as `sweep.run` builds them: the refill kernels
    are test_attractor_catalogue.py's 2-sample pilot's and test_strobe_samples.py's
    40-sample run's, so each is compiled once (the drive's two paths are tested
    above)."""
    params = _table(300, seed=5)
    kwargs = dict(stop_early=True, block=64, strobe_samples=samples, shared_forcing=True)
    waiting = _call(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), **kwargs),
                    params)
    refill = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), refill=True,
                        **kwargs)
    assert kernels.n_columns(refill) == 2 * samples
    refilled = _call(refill, params)
    np.testing.assert_array_equal(refilled[1], waiting[1])
    assert refilled[0].tobytes() == waiting[0].tobytes()  # NaN where NaN, bits elsewhere


@pytest.mark.parametrize("groups", [1, 3, 7])
def test_refill_does_not_depend_on_the_number_of_groups(groups):
    """The wrapper makes one group per thread; any number of groups (strided over the
    trajectories) must give the same bits as the waiting kernel, on any machine."""
    params = _table(700, seed=11)
    kwargs = dict(stop_early=True, block=64)
    waiting = _call(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), **kwargs),
                    params)
    spec = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), refill=True, **kwargs)
    grouped = kernels.compiled(kernels.build(spec))  # the compiled kernel itself
    out = np.full((params.shape[0], kernels.n_columns(spec)), -7.0)
    status = np.full(params.shape[0], 99, dtype=np.int8)
    grouped(params, 0.0, DT, N_STEPS, 150 * 20, 1, out, status, np.empty((0, 2, 0)),
            spec.block, groups, 0, groups)  # every group of 64 lanes, in this thread
    np.testing.assert_array_equal(status, waiting[1])
    assert out.tobytes() == waiting[0].tobytes()


def test_refill_refuses_a_run_without_steps_and_runs_without_saving():
    """Every refill lane steps before its first stop test, so zero steps is refused (the
    engine never asks for it); and a spec that saves gets the waiting kernel."""
    spec = KernelSpec("nonlinear", ("damping",), ("capture",), stop_early=True, refill=True)
    with pytest.raises(ValueError, match="n_steps must be >= 1"):
        kernels.build(spec)(_table(10), 0.0, DT, 0, 0, 1, np.empty((10, 2)),
                            np.empty(10, np.int8), np.empty((0, 2, 0)))
    saving = KernelSpec("nonlinear", ("damping",), ("capture",), stop_early=True,
                        refill=True, save=True)
    assert not saving.refill


def test_refill_of_captured_wells_and_a_single_trajectory():
    """Unforced damped wells (capture), and a one-trajectory group (block 1)."""
    params = _table(300, seed=5)
    column = sweep.physics.parameter_names().index("forcing_amplitude")
    params[:, column] = 0.0
    params[:, 1] *= 2  # omega0 up to 4: some start with several turns to make
    for block in (1, 64):
        specs = [KernelSpec("nonlinear", ("damping",), ("capture",), stop_early=True,
                            block=block, refill=refill) for refill in (False, True)]
        for rows in (slice(None), slice(7, 8)):
            a, b = (_call(spec, params[rows], n_transient=0) for spec in specs)
            np.testing.assert_array_equal(a[1], b[1])
            assert a[0].tobytes() == b[0].tobytes()


def test_sweep_run_refills_early_stopped_runs():
    scene = sweep.Scene(effects=(sweep.Damping(0.3),))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 41), omega0=np.linspace(-4, 4, 41))
    spec = sweep.engine.warm_up(scene, grid, t_end=60.0, dt=0.05, observe=("capture",),
                                stop_early=True)
    assert spec.refill
