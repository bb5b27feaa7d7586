"""Attractor continuation along a parameter: attractors found at each value of a grid
axis are matched to those at the previous value, so an attractor keeps its label along
the axis, and the basin fractions per value and attractor follow.

The matching is that of Attractors.jl's ``global_continuation`` with
``MatchBySSSetDistance``: the distance between two attractors is a distance between
their state-space sets, here their stroboscopic points (a period-p orbit is a set of p
points, so a cyclic shift of its samples changes nothing); pairs are matched one to one
in order of increasing distance, up to a threshold; an attractor with no partner is new
and gets a label never used before, and the label of one that vanished is never reused.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import check_quantity
from .labels import (
    UNRESOLVED,
    check_max_period,
    check_tolerance,
    identify_attractors,
    strobe_axes,
    strobe_table,
)
from .period import NO_PERIOD

__all__ = ["continuation", "set_distance"]

TWO_PI = 2.0 * np.pi


def set_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Hausdorff distance between two sets of stroboscopic points.

    Parameters
    ----------
    a, b : ndarray, shapes (p, 2) and (q, 2)
        Points (angle [rad], angular velocity [rad/s]), in any order: a period-p orbit
        is the set of its p points, so a cyclic shift of its samples changes nothing.

    Returns
    -------
    float
        The largest distance from a point of one set to the nearest point of the other
        [rad, rad/s], in the Euclidean metric of (angle, velocity) with the angle
        difference taken modulo 2 pi (so 0.01 and 2 pi - 0.01 are 0.02 apart, and a
        rotating orbit's unwrapped angle may be given as it is).
    """
    d_theta = np.abs(a[:, None, 0] - b[None, :, 0]) % TWO_PI
    d_theta = np.minimum(d_theta, TWO_PI - d_theta)
    d = np.hypot(d_theta, a[:, None, 1] - b[None, :, 1])
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def _attractors(theta, omega, max_period, tol):
    """Local labels of one slice and, per attractor, (points (p, 2), period, turns per
    period, size)."""
    labels, catalogue = identify_attractors(theta, omega, max_period=max_period, tol=tol)
    found = []
    for a in range(catalogue["size"].size):
        row = int(np.flatnonzero(labels == a)[0])
        p = int(catalogue["period"][a])
        points = np.stack([np.mod(theta[row, -p:], TWO_PI), omega[row, -p:]], axis=1)
        found.append((points, p, float(catalogue["turns_per_period"][a]),
                      int(catalogue["size"][a])))
    return labels, found


def _match(previous, current, threshold):
    """{current index: previous index}: pairs in order of increasing set distance, one
    to one, only attractors with the same turns per period and within ``threshold``."""
    pairs = []
    for i, (points, _, turns, _) in enumerate(current):
        for j, (old_points, _, old_turns, _) in enumerate(previous):
            if abs(turns - old_turns) > 1e-9:
                continue
            distance = set_distance(points, old_points)
            if distance <= threshold:
                pairs.append((distance, i, j))
    matched, used = {}, set()
    for _, i, j in sorted(pairs):
        if i not in matched and j not in used:
            matched[i] = j
            used.add(j)
    return matched


def _check_options(along, max_period, tol, threshold) -> tuple[int, float, float]:
    """Refuse bad options before any work, naming what is accepted; return
    ``max_period``, ``tol`` and ``threshold`` as an int and floats."""
    if not isinstance(along, str):
        raise ValueError(f"along must be the name of a grid axis (a str), got {along!r}")
    return (check_max_period(max_period), check_tolerance(tol),
            check_quantity("threshold", threshold, minimum=0.0, strict=True, allow_inf=True,
                           accepted="a number > 0 (rad, rad/s; inf for no threshold)"))


def continuation(ds: xr.Dataset, along: str, *, max_period: int = 8, tol: float = 1e-3,
                 threshold: float = np.inf) -> tuple[xr.DataArray, xr.Dataset]:
    """Follow the attractors of a forced basins run along one of its grid axes.

    At each value of ``along`` the attractors of that slice of the grid are found by
    `sweep.maps.identify_attractors`, then matched to those of the previous value
    (see Notes): a matched attractor keeps its label, an unmatched one gets
    the next unused label, and the label of one that is not found again is retired.

    Parameters
    ----------
    ds : xarray.Dataset
        A run observing ``strobe`` (variables ``strobe_theta`` and ``strobe_omega``
        over the grid dims and ``strobe``) whose grid has the axis ``along``, e.g.
        theta0 x omega0 x forcing_amplitude.
    along : str
        The grid axis to continue along, taken in the stored order of its values (a
        descending axis is continued downwards).
    max_period : int, default 8
        Longest period looked for [forcing periods], >= 1; periods longer than half
        the stroboscopic samples are never found.
    tol : float, default 1e-3
        Repetition and identity tolerance of `identify_attractors` [rad and rad/s].
    threshold : float, default inf
        Largest set distance [rad, rad/s] at which two attractors at consecutive values
        can be the same one; farther ones are never matched. Attractors.jl's
        ``MatchBySSSetDistance`` has no threshold by default either; unlike its
        ``use_vanished`` (on there when a threshold is given), a vanished attractor is
        never matched again.

    Returns
    -------
    labels : xarray.DataArray, int32, the grid dims of ``ds`` (order kept)
        The continued attractor label of each start; ``-1`` unresolved (no period
        found: chaotic or not converged, or a failed trajectory: non-finite samples,
        or a nonzero ``status`` where the dataset has one). Labels count up from
        0 in order of first appearance along the axis (at the first value, by
        decreasing basin size).
    fractions : xarray.Dataset
        Dims ``(along, "attractor")``, ``attractor`` = 0 .. number of labels - 1:

        - ``fraction`` [1]: the share of that value's starts in each attractor's
          basin, 0 where the attractor does not exist;
        - ``unresolved`` [1] (dim ``along``): the share of starts with label -1, so
          that ``fraction.sum("attractor") + unresolved`` is one at every value;
        - ``attractor_theta`` [rad, in [0, 2 pi)] and ``attractor_omega`` [rad/s]: one
          stroboscopic point of the attractor at each value (NaN where absent);
        - ``attractor_period`` [forcing periods]: its period at each value, ``-1``
          where absent (a label continued through a period doubling changes period);
        - coordinates per attractor: ``period`` (where it is first found),
          ``turns_per_period`` (net turns per forcing period, 0 for an oscillation;
          the same along the label), ``first`` and ``last``, the values of ``along``
          where it is first and last found (it exists at every value in between).

        Attributes: ``along``, ``matching``, ``threshold``, ``tol``, ``max_period``.

    Raises
    ------
    ValueError
        Before any work: without stroboscopic samples (the message says to observe
        ``'strobe'``); for an ``along`` that is not a grid axis of ``ds`` (the message
        lists them) or one with fewer than two values; for ``max_period``, ``tol`` or
        ``threshold`` out of range.

    Notes
    -----
    Two attractors at consecutive values are compared only if they turn the same
    number of times per forcing period; their distance is the Hausdorff distance of
    their stroboscopic sets (`set_distance`). Pairs are matched one to one in order of
    increasing distance (greedy, as Attractors.jl does), so an attractor that vanishes
    while another appears far away hands its label on unless ``threshold`` forbids it.
    """
    max_period, tol, threshold = _check_options(along, max_period, tol, threshold)
    axes = strobe_axes(ds, "continuation", along)
    n_values = ds.sizes[along]
    if n_values < 2:
        raise ValueError(f"along = {along!r} has {n_values} value; accepted: an axis with "
                         "at least two values to continue along")
    others = [d for d in axes if d != along]
    out = np.full((n_values,) + tuple(ds.sizes[d] for d in others), UNRESOLVED,
                  dtype=np.int32)
    previous, previous_labels = [], []
    # per label: (period, turns, {value index: (theta, omega, fraction, period)})
    known = []
    unresolved = np.zeros(n_values)
    for k in range(n_values):
        here = ds.isel({along: k})
        theta, omega, dims = strobe_table(here)
        if "status" in here:  # a failed trajectory's last samples may look periodic
            failed = (here["status"].transpose(*dims).values != 0).reshape(-1, 1)
            theta, omega = np.where(failed, np.nan, theta), np.where(failed, np.nan, omega)
        local, found = _attractors(theta, omega, max_period, tol)
        matched = _match(previous, found, threshold)
        labels_here = []
        for i, (points, period, turns, size) in enumerate(found):
            if i in matched:
                label = previous_labels[matched[i]]
            else:
                label = len(known)
                known.append((period, turns, {}))
            labels_here.append(label)
            known[label][2][k] = (points[-1, 0], points[-1, 1], size / local.size, period)
        mapping = np.array(labels_here + [UNRESOLVED], dtype=np.int32)
        out[k] = mapping[np.where(local >= 0, local, len(labels_here))].reshape(
            tuple(ds.sizes[d] for d in dims))
        unresolved[k] = float(np.mean(local < 0))
        previous, previous_labels = found, labels_here
    coords = {d: ds[d] for d in [along] + others}
    labels = xr.DataArray(out, coords=coords, dims=[along] + others, name="continued_basins")
    labels = labels.transpose(*axes)
    labels.attrs = {"long_name": f"attractor label, continued along {along}",
                    "unresolved": UNRESOLVED, "along": along}
    return labels, _fractions(ds, along, known, unresolved, max_period, tol, threshold)


def _fractions(ds, along, known, unresolved, max_period, tol, threshold) -> xr.Dataset:
    """The ``fractions`` Dataset of `continuation` from its per-label records."""
    n_values, n_attractors = unresolved.size, len(known)
    fraction = np.zeros((n_values, n_attractors))
    point = np.full((2, n_values, n_attractors), np.nan)
    period_here = np.full((n_values, n_attractors), NO_PERIOD, dtype=np.int32)
    for label, (_, _, where) in enumerate(known):
        for k, (theta_point, omega_point, share, period) in where.items():
            fraction[k, label] = share
            point[:, k, label] = theta_point, omega_point
            period_here[k, label] = period
    values = ds[along].values
    first = [values[min(w)] for _, _, w in known]
    last = [values[max(w)] for _, _, w in known]
    return xr.Dataset(
        {"fraction": ((along, "attractor"), fraction,
                      {"units": "1", "long_name": "basin fraction of the starts at this "
                                                  f"{along}"}),
         "unresolved": ((along,), unresolved,
                        {"units": "1", "long_name": "fraction of starts with no attractor "
                                                    "found (chaotic, not converged, failed)"}),
         "attractor_theta": ((along, "attractor"), point[0],
                             {"units": "rad", "long_name": "a stroboscopic point of the "
                                                          "attractor: angle modulo 2 pi"}),
         "attractor_omega": ((along, "attractor"), point[1],
                             {"units": "rad s-1", "long_name": "a stroboscopic point of the "
                                                              "attractor: angular velocity"}),
         "attractor_period": ((along, "attractor"), period_here,
                              {"units": "1", "long_name": "period of the attractor at this "
                                                          f"{along} (forcing periods); -1 "
                                                          "where absent"})},
        coords={along: ds[along],
                "attractor": np.arange(n_attractors),
                "period": ("attractor", np.array([p for p, _, _ in known], dtype=np.int64)),
                "turns_per_period": ("attractor", np.array([t for _, t, _ in known])),
                "first": ("attractor", np.array(first, dtype=float)),
                "last": ("attractor", np.array(last, dtype=float))},
        attrs={"along": along, "matching": "one to one by increasing Hausdorff distance "
               "of the stroboscopic sets (angle modulo 2 pi), same turns per period",
               "threshold": float(threshold), "tol": float(tol),
               "max_period": int(max_period)})
