"""Shared fixtures. Every test is float64 and seeded.

``device="cuda"`` is tested under numba's CUDA simulator (CI has no GPU): it is
switched on here, before numba is imported, unless ``SWEEP_REAL_CUDA=1`` asks for
the real GPU (``SWEEP_REAL_CUDA=1 pytest tests/test_cuda.py`` on a machine with one).
"""

import os

if os.environ.get("SWEEP_REAL_CUDA") != "1":
    os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")
    # pytest's filterwarnings setting (pyproject) has imported numba already: re-read
    # its environment before numba.cuda is first imported
    from numba.core import config as _numba_config

    _numba_config.reload_config()

import matplotlib
import numpy as np
import pytest
from shared_kernels import WADA_PILOT, WADA_SCENE  # the wada_catalogue fixture's scene

import sweep
import sweep.execution.local

import compile_log

# numba's cache index updates under a lock (as sweep.kernels.build does), also for the
# tests that call sweep.kernels.vecmath's helpers directly: pytest-xdist's workers
# share the cache folders
sweep.kernels.cache._serialise_numba_index()

matplotlib.use("Agg")  # no display on CI
os.environ.setdefault("MPLBACKEND", "Agg")


def pytest_configure(config):
    compile_log.pytest_configure(config)  # SWEEP_COMPILE_LOG=file: log numba's compiles


def pytest_runtest_setup(item):
    compile_log.pytest_runtest_setup(item)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    with compile_log.test_cpu(item):  # SWEEP_COMPILE_LOG: each test's CPU seconds too
        yield


@pytest.fixture(scope="session")
def wada_catalogue():
    """The forced Wada map's attractor catalogue, from its 21 x 21 pilot.

    The tests that need *a* catalogue of this scene, not one from their own pilot, share
    this one: its pilot runs once per process. (A catalogue is the kernel's argument, so
    every catalogue shares the kernels of its run settings.)"""
    from sweep import maps

    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 21),
                      omega0=np.linspace(-4, 4, 21))
    return maps.attractor_catalogue(sweep.run(WADA_SCENE, grid, **WADA_PILOT))


@pytest.fixture
def rng():
    """A seeded generator, so failures reproduce."""
    return np.random.default_rng(20261121)


@pytest.fixture
def no_compute(monkeypatch):
    """Fail loudly if a kernel is built or run: every error comes before compute."""

    def forbidden(*args, **kwargs):
        raise AssertionError("compute started before the input was validated")

    monkeypatch.setattr(sweep.engine, "build", forbidden)  # warm_up
    monkeypatch.setattr(sweep.execution.local, "build", forbidden)  # every run
