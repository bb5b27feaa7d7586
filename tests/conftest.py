"""Shared fixtures. Every test is float64 and seeded."""

import os

import matplotlib
import numpy as np
import pytest

import sweep
import sweep.execution.local

matplotlib.use("Agg")  # no display on CI
os.environ.setdefault("MPLBACKEND", "Agg")


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
