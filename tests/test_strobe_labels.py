"""The compiled attractor search (`sweep.maps._strobe`) against the NumPy form it
replaced, kept here as the reference: the same periods, turns, labels and catalogue on
random orbits around the tolerance (periods up to 8, turns, the 2 pi wrap, NaN and inf
rows, equal-sized basins) and on noise-free binary-exact rows that hit the edge cases
exactly (points on half cells, argmin ties, angles at 0 and 2 pi, negative zero)."""

import numpy as np
import pytest

from sweep import maps
from sweep.maps import _strobe


def _reference_periods(theta, omega, max_period, tol):
    """The NumPy form (sweep 0.2's ``_periods``)."""
    n, samples = theta.shape
    period = np.zeros(n, dtype=np.int64)
    turns = np.zeros(n, dtype=np.int64)
    finite = np.isfinite(theta).all(axis=1) & np.isfinite(omega).all(axis=1)
    for p in range(1, max_period + 1):
        if samples < 2 * p:
            break
        d_theta = theta[:, p:] - theta[:, :-p]
        q = np.round(d_theta[:, -1] / (2 * np.pi))
        ok = (np.abs(d_theta - 2 * np.pi * q[:, None]) < tol).all(axis=1)
        ok &= (np.abs(omega[:, p:] - omega[:, :-p]) < tol).all(axis=1)
        new = ok & finite & (period == 0)
        period[new] = p
        turns[new] = q[new].astype(np.int64)
    return period, turns


def _reference_keys(theta, omega, period, turns, resolved, tol):
    """The NumPy form's bucket keys (one row per resolved trajectory)."""
    keys = np.empty((resolved.size, 4), dtype=np.int64)
    for p in np.unique(period[resolved]):
        rows = resolved[period[resolved] == p]
        wrapped = np.mod(theta[rows, -p:], 2 * np.pi)
        pick = np.argmin(wrapped, axis=1)
        where = np.searchsorted(resolved, rows)
        keys[where, 0] = p
        keys[where, 1] = turns[rows]
        keys[where, 2] = np.round(wrapped[np.arange(rows.size), pick] / (10 * tol))
        keys[where, 3] = np.round(omega[rows, -p:][np.arange(rows.size), pick] / (10 * tol))
    return keys


def _table(n=20000, samples=16, seed=0):
    """Stroboscopic samples on periodic orbits of period 1..8 with turns, noise from
    1e-12 to 1e-2 (around tol = 1e-3), angles across the 2 pi wrap, points near
    quantisation-cell edges and near-equal samples (within the noise: the exact cases
    are in `_exact_rows`), and non-finite rows."""
    rng = np.random.default_rng(seed)
    period = rng.integers(1, 9, n)
    turns = rng.integers(-2, 3, n)
    k = np.arange(samples)
    base = rng.uniform(-0.02, 2 * np.pi + 0.02, (n, 8))  # straddles the wrap
    base[: n // 10] = np.round(base[: n // 10] / 0.01) * 0.01 + 0.005  # near cell edges
    omega_base = rng.normal(0, 2, (n, 8))
    omega_base[n // 10: n // 5] = 0.005 * rng.integers(-100, 100, (n // 10, 8))
    theta = np.take_along_axis(base, k[None, :] % period[:, None], axis=1) + \
        2 * np.pi * turns[:, None] * (k[None, :] // period[:, None])
    omega = np.take_along_axis(omega_base, k[None, :] % period[:, None], axis=1)
    theta[n // 5: n // 4] = theta[n // 5: n // 4, :1]  # equal up to the noise
    noise = 10.0 ** rng.uniform(-12, -2, (n, 1))
    theta += noise * rng.normal(size=(n, samples))
    omega += noise * rng.normal(size=(n, samples))
    theta[-50:-40, 3] = np.nan
    omega[-40:-30, 7] = np.inf
    return theta, omega


@pytest.mark.parametrize("max_period, tol", [(8, 1e-3), (3, 1e-3), (8, 1e-6), (5, 0.05)])
def test_periods_match_the_numpy_form(max_period, tol):
    theta, omega = _table()
    got = _strobe.periods(theta, omega, max_period, tol)
    want = _reference_periods(theta, omega, max_period, tol)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[1], want[1])
    assert 0 < (got[0] > 0).mean() < 1  # both resolved and unresolved rows were tested


def _exact_rows():
    """Noise-free rows with binary-exact values (tol = 0.025, so the cell 10 tol is
    0.25): orbit points exactly on half cells (rint rounds half to even), equal wrapped
    angles with different velocities (argmin's first-least tie), angles exactly at 0
    and 2 pi, whole turns, negative zero."""
    samples = 16
    k = np.arange(samples)
    rows_theta, rows_omega = [], []
    for th, om in [([0.125], [0.375]), ([0.375], [-0.125]), ([0.625, 0.625], [0.5, -0.5]),
                   ([0.0, 1.0], [0.25, 0.75]), ([-0.0, 0.5], [-0.0, 0.125]),
                   ([2 * np.pi, 1.0], [0.0, 0.0]), ([1.0, 1.0, 3.0], [1.0, -1.0, 1.0])]:
        p = len(th)
        for turns in (-1, 0, 2):
            rows_theta.append(np.array(th)[k % p] + 2 * np.pi * turns * (k // p))
            rows_omega.append(np.array(om)[k % p])
    return np.array(rows_theta), np.array(rows_omega)


@pytest.mark.parametrize("seed", [1, None])
def test_bucket_keys_match_the_numpy_form(seed):
    theta, omega = _table(seed=seed) if seed is not None else _exact_rows()
    tol = 1e-3 if seed is not None else 0.025
    period, turns = _reference_periods(theta, omega, 8, tol)
    np.testing.assert_array_equal(_strobe.periods(theta, omega, 8, tol)[0], period)
    resolved = np.flatnonzero(period > 0)
    bucket_of, keys, first = _strobe.bucket_keys(theta, omega, period, turns, resolved,
                                                 10 * tol)
    want = _reference_keys(theta, omega, period, turns, resolved, tol)
    np.testing.assert_array_equal(keys[bucket_of], want)
    assert np.unique(want, axis=0).shape[0] == keys.shape[0]  # one bucket per key
    for b, row in enumerate(first):  # each bucket's first member, in resolved order
        assert row == resolved[np.flatnonzero(bucket_of == b)[0]]


def test_identify_attractors_on_a_large_table():
    """Labels and catalogue on three attractors (one rotating, one period 2) with 1e-9
    noise, orbits shifted by whole turns, two basins of equal size."""
    rng = np.random.default_rng(2)
    n, samples = 30000, 16
    which = np.repeat([0, 1, 2], [12000, 9000, 9000])
    k = np.arange(samples)
    theta = np.empty((n, samples))
    omega = np.empty((n, samples))
    orbits = [([1.0], [0.5], 1, 0), ([2.0, 3.0], [-0.3, 0.7], 2, 0), ([0.2], [2.0], 1, 1)]
    for label, (th, om, p, t) in enumerate(orbits):
        rows = which == label
        theta[rows] = np.array(th)[k % p] + 2 * np.pi * t * (k // p) + \
            2 * np.pi * rng.integers(-3, 3, rows.sum())[:, None]
        omega[rows] = np.array(om)[k % p]
    theta += rng.normal(0, 1e-9, theta.shape)
    labels, catalogue = maps.identify_attractors(theta, omega)
    assert list(catalogue["size"]) == [12000, 9000, 9000]
    # equal basins keep the order of their keys: period 1 (turning) before period 2
    assert list(catalogue["period"]) == [1, 1, 2]
    np.testing.assert_allclose(catalogue["turns_per_period"], [0, 1, 0])
    np.testing.assert_array_equal(labels, np.array([0, 2, 1])[which])


def test_identify_attractors_refuses_mismatched_tables():
    with pytest.raises(ValueError, match=r"same shape \(n, P\), got \(4, 16\) and \(3, 16\)"):
        maps.identify_attractors(np.zeros((4, 16)), np.zeros((3, 16)))
