"""Shared fixtures. Every test is float64 and seeded."""

import os

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")  # no display on CI
os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture
def rng():
    """A seeded generator, so failures reproduce."""
    return np.random.default_rng(20261121)
