"""The map of known cells of `sweep.run(..., known_cells=...)`: its checks, before any
compute, and the two kernel arguments it becomes (`sweep.kernels.KernelSpec.known_cells`,
`sweep.kernels.snippets.known_source`): each known cell with the hits it needs, fewer
deep inside a region of one label (`hits_needed`)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .observables import KNOWN_HITS_BY_DEPTH

__all__ = ["KNOWN_DIMS", "agreeing", "check_known_cells", "hits_needed", "known_arguments",
           "no_known_arguments"]

#: The known map's dimensions, in the kernel's order (rows, columns).
KNOWN_DIMS = ("theta0", "omega0")

#: Largest departure from even spacing [cells] of a known map's axis: a point is
#: snapped to a cell by the axis' first value and mean spacing, so an axis off by a
#: tenth of a cell would snap some points to a neighbour.
_SPACING_RTOL = 1e-6

_ACCEPTED = ("an xarray.DataArray over theta0 and omega0 (each evenly spaced, >= 2 "
             "values) of integers: the index in the run's attractor catalogue of the "
             "attractor each cell's start settles on, -1 where unknown")


def _axis(name: str, values) -> tuple[float, float]:
    """First value and spacing of an evenly spaced axis."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 1 or values.size < 2 or not np.isfinite(values).all():
        raise ValueError(f"known_cells: axis {name} must hold >= 2 finite values, got "
                         f"{values.size}; accepted: {_ACCEPTED}")
    step = (values[-1] - values[0]) / (values.size - 1)
    gaps = np.diff(values)
    if step == 0 or np.max(np.abs(gaps - step)) > _SPACING_RTOL * abs(step):
        raise ValueError(f"known_cells: axis {name} is not evenly spaced (gaps from "
                         f"{gaps.min()!r} to {gaps.max()!r}); accepted: {_ACCEPTED}")
    return float(values[0]), float(step)


def check_known_cells(known_cells, *, attractors: int, stop_early, method,
                      checkpoint) -> xr.DataArray:
    """``known_cells`` checked against the run: a DataArray over `KNOWN_DIMS` (in that
    order) of int32 labels in ``-1 .. attractors - 1``.

    Parameters
    ----------
    known_cells : xarray.DataArray
    attractors : int
        Attractors in the run's catalogue (0: none).
    stop_early : bool
    method : method object
        The run's integrator (fixed-step only).
    checkpoint : object
        The run's checkpoint (None only: the known map is not kept in one).

    Raises
    ------
    ValueError
        Naming what is wrong and what is accepted.
    """
    if not attractors or not stop_early:
        raise ValueError("known_cells stops trajectories on cells labelled with a "
                         "catalogued attractor; accepted: known_cells with "
                         "stop_early=True and attractors=sweep.maps.attractor_catalogue(...)")
    if method.adaptive:
        raise ValueError(f"known_cells stops trajectories at stroboscopic times on the "
                         f"fixed step grid; method {method.name!r} is adaptive; accepted: "
                         "a fixed-step method, or known_cells=None")
    if checkpoint is not None:
        raise ValueError("known_cells cannot be used with a checkpoint (the known map "
                         "is not stored in it); accepted: checkpoint=None")
    if not isinstance(known_cells, xr.DataArray) or set(known_cells.dims) != set(KNOWN_DIMS):
        got = (f"a DataArray over {known_cells.dims}" if isinstance(known_cells, xr.DataArray)
               else type(known_cells).__name__)
        raise ValueError(f"known_cells must be {_ACCEPTED}; got {got}")
    known = known_cells.transpose(*KNOWN_DIMS)
    for name in KNOWN_DIMS:
        if name not in known.coords:
            raise ValueError(f"known_cells has no {name} coordinate; accepted: {_ACCEPTED}")
        _axis(name, known[name].values)
    values = np.asarray(known.values)
    if values.dtype.kind not in "iu":
        raise ValueError(f"known_cells holds {values.dtype} values; accepted: {_ACCEPTED}")
    bad = (values < -1) | (values >= attractors)
    if bad.any():
        index = tuple(int(k) for k in np.argwhere(bad)[0])
        raise ValueError(f"known_cells holds {int(values[index])} at {index}, but the "
                         f"catalogue has {attractors} attractors; accepted: -1 (unknown) "
                         f"or 0 .. {attractors - 1}")
    return xr.DataArray(values.astype(np.int32), dims=KNOWN_DIMS,
                        coords={name: known[name].values for name in KNOWN_DIMS})


def agreeing(labels: np.ndarray, radius: int) -> np.ndarray:
    """The labels (>= 0) of the cells whose neighbours within ``radius`` rows and
    columns all hold the same label; -1 elsewhere (cells within ``radius`` of the map's
    edge too).

    Parameters
    ----------
    labels : ndarray, shape (n0, n1), int
        Attractor indices, negative where unknown.
    radius : int
        >= 0.
    """
    labels = np.asarray(labels)
    out = np.where(labels >= 0, labels, -1).astype(np.int32)
    n0, n1 = labels.shape
    for dr in range(-radius, radius + 1):
        for dc in range(-radius, radius + 1):
            if dr == 0 and dc == 0:
                continue
            shifted = np.full(labels.shape, -2, dtype=labels.dtype)
            shifted[max(-dr, 0):n0 - max(dr, 0), max(-dc, 0):n1 - max(dc, 0)] = \
                labels[max(dr, 0):n0 - max(-dr, 0), max(dc, 0):n1 - max(-dc, 0)]
            out[shifted != labels] = -1
    return out


def hits_needed(labels: np.ndarray) -> np.ndarray:
    """Per cell of a map of known labels (-1 unknown), the stroboscopic hits running
    that stop a trajectory there: ``KNOWN_HITS_BY_DEPTH[r]`` where every cell within
    ``r`` rows and columns holds the cell's label (r = 0: the cell alone; the last entry
    for every larger r); 0 where unknown."""
    labels = np.asarray(labels)
    need = np.where(labels >= 0, KNOWN_HITS_BY_DEPTH[0], 0)
    for radius, hits in enumerate(KNOWN_HITS_BY_DEPTH[1:], start=1):
        need = np.where(agreeing(labels, radius) >= 0, hits, need)
    return need


def known_arguments(known: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's ``known`` and ``known_axes`` of a checked map (`check_known_cells`):
    per cell ``4 * label + hits`` (`hits_needed`; -1 where unknown), and ``[theta of
    row 0, rows per rad, omega of column 0, columns per rad/s, rows per 2 pi]``."""
    known = known.transpose(*KNOWN_DIMS)
    theta0, d_theta = _axis("theta0", known["theta0"].values)
    omega0, d_omega = _axis("omega0", known["omega0"].values)
    axes = np.array([theta0, 1.0 / d_theta, omega0, 1.0 / d_omega,
                     2.0 * np.pi / abs(d_theta)], dtype=np.float64)
    labels = np.asarray(known.values, dtype=np.int32)
    codes = np.where(labels >= 0, 4 * labels + hits_needed(labels), -1)
    return np.ascontiguousarray(codes, dtype=np.int32), axes


def no_known_arguments() -> tuple[np.ndarray, np.ndarray]:
    """The two arguments of a known-cells kernel with nothing known (one unknown cell),
    for a call that integrates nothing (compiling it)."""
    return np.full((1, 1), -1, dtype=np.int32), np.array([0.0, 1.0, 0.0, 1.0, 1.0])
