"""Compiled passes of the forced-attractor search (`sweep.maps.labels.identify_attractors`)
over the stroboscopic samples of every trajectory.

The NumPy form of the same tests made temporaries of the whole (n, P) sample table for
every period tried and sorted an (n, 4) key table row-wise: 6 s for a 1200 x 1200
map. Here each trajectory is one pass that stops at its first period (one thread per
part of the table), and the bucket keys go into a hash table (plain arrays), so the
same map takes a fraction of a second. The arithmetic is the NumPy form's, operation
for operation and without fast-math, so the labels are the same (a test compares both
on hard cases).

The samples are those of one angle (the single pendulum: tables of shape (n, P)) or of
m coordinates (a system: (n, m, P), angular or not); the compiled passes take the
second form, the first as m = 1 angle.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..kernels.cache import _serialise_numba_index

_serialise_numba_index()  # this module's cache=True functions save under the lock too

__all__ = ["as_coordinates", "bucket_keys", "periods"]

TWO_PI = 2.0 * math.pi
#: The hash of a bucket key starts from FNV-1a's offset basis and mixes each value with
#: its prime (64-bit, wrapping); equal hashes are told apart by comparing the keys.
_BASIS, _PRIME = -3750763034362895579, 1099511628211


def as_coordinates(position, velocity, angular=None):
    """The samples as ``(n, m, P)`` float64 tables and the ``(m,)`` angular flags, and
    whether they came as one angle's ``(n, P)`` tables.

    Raises
    ------
    ValueError
        For tables that are not 2-D or 3-D of one shape, or flags not of length m.
    """
    position = np.asarray(position, dtype=np.float64)
    velocity = np.asarray(velocity, dtype=np.float64)
    if position.ndim not in (2, 3) or position.shape != velocity.shape:
        raise ValueError(f"theta and omega must be arrays of the same shape (n, P), got "
                         f"{position.shape} and {velocity.shape}; accepted: (n, P) for one "
                         "angle and its velocity, (n, m, P) for m coordinates")
    one = position.ndim == 2
    if one:
        position, velocity = position[:, None, :], velocity[:, None, :]
    m = position.shape[1]
    flags = np.ones(m, dtype=np.bool_) if angular is None else \
        np.asarray(angular, dtype=np.bool_).reshape(-1)
    if flags.shape != (m,):
        raise ValueError(f"angular must say of each of the m = {m} coordinates whether it "
                         f"is an angle (m booleans), got {np.shape(angular)}")
    return (np.ascontiguousarray(position), np.ascontiguousarray(velocity), flags, one)


def periods(theta, omega, max_period, tol, angular=None):
    """Smallest stroboscopic period and turns per period of each trajectory.

    Parameters
    ----------
    theta, omega : ndarray, shape (n, P) or (n, m, P), float64
        The last P stroboscopic samples of one angle [rad, unwrapped] and its velocity
        [rad/s], or of m coordinates and their velocities.
    max_period : int
        Largest period p tried (only those with ``P >= 2 p``).
    tol : float
        Closeness in the coordinates' units for a sample to count as repeating.
    angular : array_like of bool, shape (m,), optional
        Which coordinates are angles (default: all); the others repeat without turns.

    Returns
    -------
    period : ndarray, shape (n,), int64
        Smallest p with ``|theta[j + p] - theta[j] - 2 pi q| < tol`` and
        ``|omega[j + p] - omega[j]| < tol`` for every j and coordinate, where ``q`` is
        the coordinate's number of turns over the last p samples (0 for one that is not
        an angle); 0 where none (or a sample is not finite).
    turns : ndarray, shape (n,) or (n, m), int64
        ``q`` for that period, per coordinate for (n, m, P) tables (0 where unresolved).
    """
    position, velocity, flags, one = as_coordinates(theta, omega, angular)
    period, turns = _periods(position, velocity, flags, max_period, tol)
    return period, (turns[:, 0] if one else turns)


@njit(cache=True, parallel=True)
def _periods(position, velocity, angular, max_period, tol):
    """`periods` on (n, m, P) tables: for one angle (m = 1) the very loop of the
    single pendulum's search, each coordinate's in turn for more."""
    n, m, samples = position.shape
    period = np.zeros(n, dtype=np.int64)
    turns = np.zeros((n, m), dtype=np.int64)
    for i in prange(n):
        finite = True
        for c in range(m):
            for j in range(samples):
                if not (math.isfinite(position[i, c, j]) and math.isfinite(velocity[i, c, j])):
                    finite = False
                    break
            if not finite:
                break
        if not finite:
            continue
        for p in range(1, max_period + 1):
            if samples < 2 * p:
                break
            ok = True
            for c in range(m):
                shift = 0.0
                if angular[c]:
                    shift = TWO_PI * np.rint((position[i, c, samples - 1]
                                              - position[i, c, samples - 1 - p]) / TWO_PI)
                for j in range(samples - p):
                    if not (abs((position[i, c, j + p] - position[i, c, j]) - shift) < tol
                            and abs(velocity[i, c, j + p] - velocity[i, c, j]) < tol):
                        ok = False
                        break
                if not ok:
                    break
            if ok:
                period[i] = p
                for c in range(m):
                    if angular[c]:
                        turns[i, c] = np.int64(np.rint((position[i, c, samples - 1]
                                                        - position[i, c, samples - 1 - p])
                                                       / TWO_PI))
                break
    return period, turns


def bucket_keys(theta, omega, period, turns, resolved, cell, angular=None):
    """Bucket of each resolved trajectory, by (period, turns, the orbit point of least
    wrapped first coordinate quantised to ``cell``).

    Parameters
    ----------
    theta, omega : ndarray, shape (n, P) or (n, m, P)
    period : ndarray, shape (n,), int64
    turns : ndarray, shape (n,) or (n, m), int64
        From `periods`.
    resolved : ndarray, shape (r,), int64
        Rows with a period, ascending.
    cell : float
        Quantisation step of the orbit point [the coordinates' units].
    angular : array_like of bool, shape (m,), optional
        Which coordinates are angles (wrapped to [0, 2 pi) first); default all.

    Returns
    -------
    bucket_of : ndarray, shape (r,), int64
        Bucket index of each resolved row, buckets numbered in order of first
        appearance.
    keys : ndarray, shape (buckets, 1 + 3 m), int64
        (period, turns of each coordinate, quantised (wrapped) position of each, quantised
        velocity of each) of each bucket: (period, turns, angle cell, velocity cell) for
        one angle.
    first : ndarray, shape (buckets,), int64
        The first row (in ``resolved`` order) of each bucket.
    """
    position, velocity, flags, _ = as_coordinates(theta, omega, angular)
    turns = np.ascontiguousarray(np.asarray(turns, dtype=np.int64).reshape(period.size, -1))
    return _bucket_keys(position, velocity, flags, period, turns,
                        np.asarray(resolved, dtype=np.int64), cell)


@njit(cache=True)
def _wrapped(x, angular):
    return np.mod(x, TWO_PI) if angular else x


@njit(cache=True)
def _bucket_keys(position, velocity, angular, period, turns, resolved, cell):
    """`bucket_keys` on (n, m, P) tables: an open-addressing hash table of the keys in
    plain arrays (at most half full; a slot holds a bucket's index, equal hashes and
    taken slots are passed by comparing the keys and probing the next slot). Plain
    arrays, not numba's typed Dict: the same buckets, compiled in a fraction of the
    time, and no Dict key quirks (it lost some negative int64 keys in numba 0.68)."""
    m, samples = position.shape[1], position.shape[2]
    width = 1 + 3 * m
    size = 1
    while size < 2 * resolved.size:
        size *= 2
    slots = np.full(size, -1, dtype=np.int64)
    bucket_of = np.empty(resolved.size, dtype=np.int64)
    keys = np.empty((resolved.size, width), dtype=np.int64)
    first = np.empty(resolved.size, dtype=np.int64)
    key = np.empty(width, dtype=np.int64)
    count = 0
    for k in range(resolved.size):
        row = resolved[k]
        p = period[row]
        best, pick = np.inf, 0
        for j in range(samples - p, samples):
            wrapped = _wrapped(position[row, 0, j], angular[0])
            if wrapped < best:  # the first least, as np.argmin
                best, pick = wrapped, j
        key[0] = p
        for c in range(m):
            key[1 + c] = turns[row, c]
            key[1 + m + c] = np.int64(np.rint(_wrapped(position[row, c, pick], angular[c])
                                              / cell))
            key[1 + 2 * m + c] = np.int64(np.rint(velocity[row, c, pick] / cell))
        digest = _BASIS
        for c in range(width):
            digest = (digest ^ key[c]) * _PRIME
        # FNV-1a's low bits depend only on the keys' low bits: fold the high ones in
        slot = (digest ^ (digest >> 29) ^ (digest >> 47)) & (size - 1)
        while True:
            found = slots[slot]
            if found < 0:  # a free slot: a new bucket, numbered in order of appearance
                found = count
                slots[slot] = found
                for c in range(width):  # not keys[found] = key: 1.7 s more to compile
                    keys[found, c] = key[c]
                first[found] = row
                count += 1
                break
            same = True
            for c in range(width):
                if keys[found, c] != key[c]:
                    same = False
                    break
            if same:
                break
            slot = (slot + 1) & (size - 1)
        bucket_of[k] = found
    return bucket_of, keys[:count].copy(), first[:count].copy()
