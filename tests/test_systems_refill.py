"""Lane refill for a system's early stop (`sweep.kernels.system_refill`): a lane whose
trajectory has flipped, reached t_end or started below the lowest flipping energy takes
the next waiting one. Every trajectory must get the same bits as in the block kernel
without refill, whatever the threads and chunks, including starts that never flip,
starts skipped by their energy, a driven pivot (whose time is the lane's own step
count) and trajectories that fail."""

import math

import numba
import numpy as np
import pytest

import sweep
from sweep import _config
from sweep.engine_systems import prepare_system
from sweep.kernels import Status

T = math.sqrt(1.0 / 9.81)  # sqrt(l / g) of the default double pendulum [s]


def _runs(system, grid, monkeypatch, **kw):
    """{label: dataset} without refill, then with it on 1 and 2 threads and in chunks."""
    kw = dict(t_end=30 * T, dt=T / 50, observe=("flip",), stop_early=True, progress=False,
              **kw)
    runs = {}
    monkeypatch.setattr(_config, "REFILL", False)
    assert not prepare_system(system, grid, **kw_of(kw))[1].refill
    runs["blocks"] = sweep.run(system, grid, **kw)
    monkeypatch.setattr(_config, "REFILL", True)
    assert prepare_system(system, grid, **kw_of(kw))[1].refill
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        runs["refill, 1 thread"] = sweep.run(system, grid, **kw)
    finally:
        numba.set_num_threads(threads)
    runs["refill"] = sweep.run(system, grid, **kw)
    runs["refill, chunks of 97"] = sweep.run(system, grid, chunk_size=97, **kw)
    return runs


def kw_of(kw):
    return {k: v for k, v in kw.items() if k != "progress"}


def _same_bits(runs):
    first = runs["blocks"]
    for label, ds in runs.items():
        for name in first.data_vars:
            assert ds[name].values.tobytes() == first[name].values.tobytes(), (label, name)


def test_refill_gives_the_block_kernels_bits(monkeypatch):
    """Starts at rest over [-3, 3]^2 (a third below the lowest flipping energy, the
    rest flipping at times spread over the run or never), and a second sheet with an
    initial velocity so large that every step overflows (flagged NONFINITE)."""
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, 16), theta2_0=np.linspace(-3, 3, 16),
                      omega1_0=[0.0, 1e300])
    runs = _runs(sweep.DoublePendulum(), grid, monkeypatch)
    _same_bits(runs)
    ds = runs["refill"]
    flipped = np.isfinite(ds.flip_time.values[..., 0])
    assert 0.2 < flipped.mean() < 0.8  # the lanes finish at many different steps
    assert np.all(ds.status.values[..., 1] == int(Status.NONFINITE))


def test_refill_keeps_a_driven_pivots_time(monkeypatch):
    """A damped double pendulum on a vertically driven pivot: its accelerations read the
    time, which each lane counts on its own (``t0 + ks dt``), and nothing is skipped by
    energy (the drive feeds energy in)."""
    system = sweep.DoublePendulum(damping1=0.1, damping2=0.1, pivot_amplitude=0.05,
                                  pivot_frequency=40.0)
    grid = sweep.Grid(theta1_0=np.linspace(-2.5, 2.5, 16), theta2_0=np.linspace(-2.5, 2.5, 16))
    runs = _runs(system, grid, monkeypatch, t0=T)  # not 0: the lane clock t0 + ks dt
    _same_bits(runs)
    assert 0.05 < np.isfinite(runs["refill"].flip_time.values).mean() < 0.95


@pytest.mark.parametrize("n", [20, 63, 65])
def test_refill_with_fewer_or_just_more_trajectories_than_lanes(monkeypatch, n):
    """One group whose lanes are mostly idle copies, and a group with one trajectory
    waiting: the idle copies never write."""
    points = sweep.Points(theta1_0=np.linspace(-3, 3, n), theta2_0=np.full(n, 2.5))
    runs = _runs(sweep.DoublePendulum(), points, monkeypatch)
    _same_bits(runs)
