"""Frequency-response curves by continuation: the linear resonance curve, and the
hysteresis of the softening pendulum whose fold sits on the exact backbone."""

import numpy as np
import pytest

import sweep
from sweep.maps.response import frequency_response

# g = L = 1: omega_n = 1 rad/s. Light damping and forcing make a strongly bent resonance.
C, A = 0.02, 0.02
FREQUENCIES = np.round(np.arange(0.80, 1.1001, 0.01), 10)
SETTINGS = dict(periods_transient=150, periods_measure=10, steps_per_period=200)


def _scene(model):
    return sweep.Scene(gravity=1.0, length=1.0, model=model,
                       effects=(sweep.Damping(C), sweep.Forcing(A, 1.0)))


def test_linear_response_is_the_closed_form_both_ways():
    r = frequency_response(_scene("linear"), FREQUENCIES, **SETTINGS)
    exact = A / np.sqrt((1 - FREQUENCIES**2) ** 2 + (C * FREQUENCIES) ** 2)
    # Peak sampling misses at most (2 pi / 200)^2 / 8 = 1.2e-4 relative; the transient
    # left from the previous point decays by exp(-C/2 * 150 periods) <= exp(-8.6) = 1.9e-4
    # of the jump in amplitude between neighbours (at most ~1x the amplitude here).
    np.testing.assert_allclose(r.amplitude.sel(direction="up"), exact, rtol=5e-4)
    np.testing.assert_allclose(r.amplitude.sel(direction="down"), exact, rtol=5e-4)


def test_nonlinear_response_jumps_with_hysteresis_on_the_backbone():
    special = pytest.importorskip("scipy.special")
    r = frequency_response(_scene("nonlinear"), FREQUENCIES, **SETTINGS)
    up, down = r.amplitude.sel(direction="up").values, r.amplitude.sel(direction="down").values
    assert np.isfinite(up).all() and np.isfinite(down).all()  # librations all along
    gap = down - up
    window = FREQUENCIES[gap > 0.3]
    # softening: the bistable window lies below omega_n = 1
    assert window.size >= 2 and window.max() < 1.0
    # outside the window both sweeps land on the one steady state (same 5e-4 as above)
    outside = (window.min() - 0.015 > FREQUENCIES) | (window.max() + 0.015 < FREQUENCIES)
    np.testing.assert_allclose(up[outside], down[outside], rtol=5e-4)
    # The down sweep rides the large branch to its fold, next to the peak of the
    # resonance, which for light damping lies on the backbone: the free period of an
    # oscillation of amplitude a, omega(a) = pi / (2 K(sin^2(a/2))). Tolerance: one
    # frequency step (0.01) plus the damping shift of the peak, C^2/2 = 2e-4.
    peak = np.nanargmax(down)
    backbone = np.pi / (2 * special.ellipk(np.sin(down[peak] / 2) ** 2))
    assert abs(FREQUENCIES[peak] - backbone) < 0.0102
    # In increasing-frequency order each branch has one big jump: the down sweep's fall
    # from the large branch at the window's low edge, the up sweep's jump onto it at the
    # high edge -- so the up jump comes at a higher frequency than the down one.
    up_jump, down_jump = np.argmax(np.diff(up)), np.argmax(np.diff(down))
    assert np.diff(up)[up_jump] > 0.3 and np.diff(down)[down_jump] > 0.3
    assert FREQUENCIES[up_jump] > FREQUENCIES[down_jump]


def test_frequency_response_refuses_bad_input():
    with pytest.raises(ValueError, match=r"needs a forcing in the scene"):
        frequency_response(sweep.Scene(), [1.0])
    with pytest.raises(ValueError, match=r"frequencies must be > 0 \(rad/s\), got 0\.0"):
        frequency_response(_scene("linear"), [0.0, 1.0])
    with pytest.raises(ValueError, match=r"direction must be one of 'up', 'down', 'both'"):
        frequency_response(_scene("linear"), [1.0], direction="sideways")
    with pytest.raises(ValueError, match=r"steps_per_period must be an int >= 1, got 0"):
        frequency_response(_scene("linear"), [1.0], steps_per_period=0)
