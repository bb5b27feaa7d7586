"""Hypothesis settings for the property tests: few examples (each one integrates a
small grid), no deadline (the first example of a kernel may compile it), derandomised
and without an example database so a run is reproducible and writes nothing."""

import pytest

hypothesis = pytest.importorskip("hypothesis")

hypothesis.settings.register_profile(
    "sweep-properties", max_examples=20, deadline=None, derandomize=True, database=None,
    suppress_health_check=[hypothesis.HealthCheck.too_slow],
)
