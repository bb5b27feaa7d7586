"""Compiled passes of the forced-attractor search (`sweep.maps.labels.identify_attractors`)
over the stroboscopic samples of every trajectory.

The NumPy form of the same tests made temporaries of the whole (n, P) sample table for
every period tried and sorted an (n, 4) key table row-wise: 6 s for a 1200 x 1200
map. Here each trajectory is one pass that stops at its first period (one thread per
part of the table), and the bucket keys go into a hash table, so the same map takes a
fraction of a second. The arithmetic is the NumPy form's, operation for operation and
without fast-math, so the labels are the same (a test compares both on hard cases).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange, types
from numba.typed import Dict

from ..kernels.cache import _serialise_numba_index

_serialise_numba_index()  # this module's cache=True functions save under the lock too

__all__ = ["bucket_keys", "periods"]

TWO_PI = 2.0 * math.pi
_KEY = types.UniTuple(types.int64, 4)  # (period, turns, angle cell, velocity cell)


@njit(cache=True, parallel=True)
def periods(theta, omega, max_period, tol):
    """Smallest stroboscopic period and turns per period of each trajectory.

    Parameters
    ----------
    theta, omega : ndarray, shape (n, P), float64
        The last P stroboscopic samples (unwrapped angle [rad], velocity [rad/s]).
    max_period : int
        Largest period p tried (only those with ``P >= 2 p``).
    tol : float
        Closeness in rad and rad/s for a sample to count as repeating.

    Returns
    -------
    period : ndarray, shape (n,), int64
        Smallest p with ``|theta[j + p] - theta[j] - 2 pi q| < tol`` and
        ``|omega[j + p] - omega[j]| < tol`` for every j, where ``q`` is the number of
        turns over the last p samples; 0 where none (or a sample is not finite).
    turns : ndarray, shape (n,), int64
        ``q`` for that period (0 where unresolved).
    """
    n, samples = theta.shape
    period = np.zeros(n, dtype=np.int64)
    turns = np.zeros(n, dtype=np.int64)
    for i in prange(n):
        finite = True
        for j in range(samples):
            if not (math.isfinite(theta[i, j]) and math.isfinite(omega[i, j])):
                finite = False
                break
        if not finite:
            continue
        for p in range(1, max_period + 1):
            if samples < 2 * p:
                break
            q = np.rint((theta[i, samples - 1] - theta[i, samples - 1 - p]) / TWO_PI)
            shift = TWO_PI * q
            ok = True
            for j in range(samples - p):
                if not (abs((theta[i, j + p] - theta[i, j]) - shift) < tol
                        and abs(omega[i, j + p] - omega[i, j]) < tol):
                    ok = False
                    break
            if ok:
                period[i] = p
                turns[i] = np.int64(q)
                break
    return period, turns


@njit(cache=True)
def bucket_keys(theta, omega, period, turns, resolved, cell):
    """Bucket of each resolved trajectory, by (period, turns, the orbit point of least
    wrapped angle quantised to ``cell``).

    Parameters
    ----------
    theta, omega : ndarray, shape (n, P)
    period, turns : ndarray, shape (n,), int64
        From `periods`.
    resolved : ndarray, shape (m,), int64
        Rows with a period, ascending.
    cell : float
        Quantisation step of the orbit point [rad, rad/s].

    Returns
    -------
    bucket_of : ndarray, shape (m,), int64
        Bucket index of each resolved row, buckets numbered in order of first
        appearance.
    keys : ndarray, shape (buckets, 4), int64
        (period, turns, quantised angle, quantised velocity) of each bucket.
    first : ndarray, shape (buckets,), int64
        The first row (in ``resolved`` order) of each bucket.
    """
    samples = theta.shape[1]
    index = Dict.empty(key_type=_KEY, value_type=types.int64)
    bucket_of = np.empty(resolved.size, dtype=np.int64)
    keys = np.empty((resolved.size, 4), dtype=np.int64)
    first = np.empty(resolved.size, dtype=np.int64)
    count = 0
    for k in range(resolved.size):
        row = resolved[k]
        p = period[row]
        best, pick = np.inf, 0
        for j in range(samples - p, samples):
            wrapped = np.mod(theta[row, j], TWO_PI)
            if wrapped < best:  # the first least, as np.argmin
                best, pick = wrapped, j
        key = (p, turns[row], np.int64(np.rint(best / cell)),
               np.int64(np.rint(omega[row, pick] / cell)))
        found = index.get(key, -1)
        if found < 0:
            found = count
            index[key] = found
            keys[found, 0], keys[found, 1], keys[found, 2], keys[found, 3] = key
            first[found] = row
            count += 1
        bucket_of[k] = found
    return bucket_of, keys[:count].copy(), first[:count].copy()
