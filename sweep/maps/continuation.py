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

from .labels import UNRESOLVED, identify_attractors, strobe_table

__all__ = ["continuation", "set_distance"]

TWO_PI = 2.0 * np.pi


def set_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Hausdorff distance between two sets of stroboscopic points, shape (p, 2) of
    (angle [rad], velocity [rad/s]), the angle taken modulo 2 pi (distances in the
    Euclidean metric of (angle, velocity))."""
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


def continuation(ds: xr.Dataset, along: str, *, max_period: int = 8, tol: float = 1e-3,
                 threshold: float = np.inf):
    """Follow the attractors of a forced basins run along one of its grid axes.

    Parameters
    ----------
    ds : xarray.Dataset
        A run observing ``strobe`` whose grid has the axis ``along`` (e.g. theta0 x
        omega0 x forcing_amplitude).
    along : str
        The grid axis to continue along, in the order of its values.
    max_period, tol
        Passed to `sweep.maps.identify_attractors` at each value.
    threshold : float, default inf
        Largest set distance [rad, rad/s] at which two attractors at consecutive values
        are the same one (Attractors.jl's default is also no threshold).

    Returns
    -------
    labels : xarray.DataArray, int32, grid dims
        The continued attractor label of each start (``-1`` unresolved: no period
        found, or a failed trajectory). Labels count up from 0 in order of first
        appearance along the axis (at the first value, by basin size).
    fractions : xarray.Dataset
        Dims ``(along, "attractor")``: ``fraction`` [1], the share of that value's
        starts in each attractor's basin (0 where it does not exist), and
        ``unresolved`` (dim ``along``), so that they sum to one per value;
        ``attractor_theta`` [rad, in [0, 2 pi)] and ``attractor_omega`` [rad/s], one
        stroboscopic point of each attractor per value (NaN where absent); coordinates
        ``period`` (forcing periods) and ``turns_per_period`` per attractor, and
        ``first``/``last``, the values of ``along`` where it exists.

    Raises
    ------
    ValueError
        Without stroboscopic samples, for an ``along`` that is not a grid axis of
        ``ds`` (the message lists them), or an axis with fewer than two values.
    """
    theta_all = ds.get("strobe_theta")
    if theta_all is None or "strobe_omega" not in ds:
        raise ValueError("continuation needs stroboscopic samples; accepted: a dataset from "
                         "sweep.run(..., observe=('strobe',)) of a forced scene")
    axes = [d for d in theta_all.dims if d != "strobe"]
    if along not in axes:
        raise ValueError(f"along = {along!r} is not a grid axis of this dataset; accepted: "
                         f"{', '.join(repr(a) for a in axes)}")
    n_values = ds.sizes[along]
    if n_values < 2:
        raise ValueError(f"along = {along!r} has {n_values} value; accepted: an axis with "
                         "at least two values to continue along")
    if not (isinstance(threshold, (int, float, np.floating)) and threshold > 0):
        raise ValueError(f"threshold must be a number > 0 (rad, rad/s), got {threshold!r}")
    others = [d for d in axes if d != along]
    out = np.full((n_values,) + tuple(ds.sizes[d] for d in others), UNRESOLVED,
                  dtype=np.int32)
    previous, previous_labels = [], []
    known = []  # per global label: (period, turns, {value index: (theta, omega, fraction)})
    unresolved = np.zeros(n_values)
    for k in range(n_values):
        theta, omega, dims = strobe_table(ds.isel({along: k}))
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
            known[label][2][k] = (points[-1, 0], points[-1, 1], size / local.size)
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
    n_attractors = len(known)
    fraction = np.zeros((n_values, n_attractors))
    point = np.full((2, n_values, n_attractors), np.nan)
    for label, (_, _, where) in enumerate(known):
        for k, (theta_point, omega_point, share) in where.items():
            fraction[k, label] = share
            point[:, k, label] = theta_point, omega_point
    values = ds[along].values
    first = [values[min(w)] for _, _, w in known]
    last = [values[max(w)] for _, _, w in known]
    fractions = xr.Dataset(
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
                                                              "attractor: angular velocity"})},
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
    return labels, fractions
