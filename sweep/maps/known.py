"""Known cells of a forced basin map, for `sweep.run(..., known_cells=...)`: which cells
of a map of attractor indices may stop a trajectory (`settled`), the catalogued
attractors' own cells (`seed_attractors`), and the coarse maps of the whole window that
`sweep.maps.refine` runs first (`background`).

What may stop a trajectory was decided by measurement (docs/guide/refine.md): a cell
whose label is shared by its 8 neighbours (`KNOWN_RADIUS`), and the cell of each point
of a catalogued attractor's orbit (`SEED_RADIUS`); a trajectory stops after
`sweep.observables.KNOWN_HITS` periods running in such cells of one label, fewer where
the known cells around the last one share its label (`sweep._known.hits_needed`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import engine
from .._known import agreeing
from ..grid import Grid

__all__ = ["BACKGROUND_FACTORS", "HALF_BELOW", "KNOWN_MIN_POINTS", "KNOWN_RADIUS",
           "SEED_RADIUS", "background", "background_factors", "known_map", "seed_attractors",
           "settled", "upsample"]

#: A cell is settled when every cell within this many rows and columns (its 8
#: neighbours for 1) is known with its label.
KNOWN_RADIUS = 1

#: The cells within this many rows and columns of a catalogued attractor's orbit
#: points are known with that attractor (a stable orbit lies inside its own basin).
SEED_RADIUS = 0

#: The background maps `background` runs before the map: the window at 1/8, 1/4 and
#: 1/2 of the map's resolution, each stopping on the settled cells of the one before
#: (the 1/2 map only below `HALF_BELOW` points per axis: `background_factors`).
BACKGROUND_FACTORS = (8, 4, 2)

#: Maps with at least this many points on each axis run no background at 1/2 of their
#: resolution (its 1/4 map has 100 points per axis or more). Measured on the Wada map
#: (2026-11-28, AMD EPYC Zen 5, CPU times of backgrounds, map and labels): at 1200 x
#: 1200, 6.1 s against 6.9-7.4 s with the 1/2 map, at 400 x 400 0.83 s against
#: 0.88-0.93 s, no start labelled differently from the full run either way; at 200 x
#: 200 without it 4 starts of 40,000 differ (none with it).
HALF_BELOW = 400

#: Fewest points per axis of a map that stops on the known cells of its own coarse maps
#: (`background`: its finest then has 48 or more). Measured on the Wada map (c = 0.2,
#: A = 1.66, W = 1; AMD EPYC Zen 5, 2026-11-27) against the catalogue route: no start
#: labelled differently at 96, 200 and 1200 points per axis, 0.8 % at 64 and 1 % at 48
#: (the coarse maps' settled cells then hide structure finer than their cells).
KNOWN_MIN_POINTS = 96

#: Background maps smaller than this (points per axis) are skipped.
_SMALLEST = 16


def settled(labels: np.ndarray, radius: int = KNOWN_RADIUS) -> np.ndarray:
    """The settled cells of ``labels``: `sweep._known.agreeing` at the known-cells
    radius (`KNOWN_RADIUS` rows and columns by default); -1 elsewhere."""
    return agreeing(labels, radius)


def _cell(theta: np.ndarray, omega: np.ndarray, t: float, w: float) -> tuple[int, int]:
    """The cell (row, column) of the point ``(t, w)`` on evenly spaced axes, the angle
    wrapped by whole turns into the rows as the kernel wraps it
    (`sweep.kernels.snippets.known_source`)."""
    step = (theta[-1] - theta[0]) / (theta.size - 1)
    turn = 2 * np.pi / abs(step)
    x = (t - theta[0]) / step
    x -= turn * np.floor((x + 0.5) / turn)
    y = (w - omega[0]) / ((omega[-1] - omega[0]) / (omega.size - 1))
    return int(np.floor(x + 0.5)), int(np.floor(y + 0.5))


def seed_attractors(known: np.ndarray, theta: np.ndarray, omega: np.ndarray,
                    catalogue: dict, radius: int = SEED_RADIUS) -> np.ndarray:
    """``known`` with the cells within ``radius`` of each point of each catalogued
    attractor's orbit set to its index (``catalogue``: `attractor_catalogue`)."""
    out = np.array(known, dtype=np.int32)
    for a, period in enumerate(np.asarray(catalogue["period"], dtype=np.int64)):
        for q in range(1, int(period) + 1):
            row, col = _cell(theta, omega, catalogue["theta"][a][-q], catalogue["omega"][a][-q])
            if 0 <= row < out.shape[0] and 0 <= col < out.shape[1]:
                out[max(row - radius, 0):row + radius + 1,
                    max(col - radius, 0):col + radius + 1] = a
    return out


def known_map(known: np.ndarray, theta: np.ndarray, omega: np.ndarray) -> xr.DataArray:
    """``known`` (rows theta0, columns omega0) as `sweep.run`'s ``known_cells``."""
    return xr.DataArray(np.asarray(known, dtype=np.int32), dims=("theta0", "omega0"),
                        coords={"theta0": theta, "omega0": omega})


def upsample(known: xr.DataArray, theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The labels of the nearest cell of ``known`` at each point of the axes ``theta``
    x ``omega`` (the same window, finer): shape (theta.size, omega.size)."""
    def nearest(axis, values):
        values = np.asarray(values, dtype=np.float64)
        step = (values[-1] - values[0]) / (values.size - 1)
        return np.clip(np.floor((axis - values[0]) / step + 0.5), 0,
                       values.size - 1).astype(np.int64)

    rows = nearest(theta, known["theta0"].values)
    cols = nearest(omega, known["omega0"].values)
    return np.asarray(known.values)[np.ix_(rows, cols)]


def background_factors(n0: int, n1: int) -> tuple[int, ...]:
    """The factors of `BACKGROUND_FACTORS` a map of ``n0`` x ``n1`` points runs its
    background maps at (`HALF_BELOW`)."""
    if min(n0, n1) >= HALF_BELOW:
        return tuple(f for f in BACKGROUND_FACTORS if f != 2)
    return BACKGROUND_FACTORS


def fixed_axes(grid) -> dict[str, float]:
    """`background`'s ``fixed`` for a map over ``grid``: its axes other than theta0 and
    omega0, each of one value (name -> that value), so that the backgrounds run the
    map's scene."""
    return {name: float(np.asarray(values)[0]) for name, values in grid.axes.items()
            if name not in engine.INITIAL_AXES}


def background(scene, theta: np.ndarray, omega: np.ndarray, catalogue: dict,
               factors: tuple[int, ...] | None = None, fixed: dict | None = None,
               **run_kwargs) -> tuple[xr.DataArray | None, int]:
    """The known cells of the window ``theta`` x ``omega`` from coarse maps of it at
    1 / ``factors`` of its resolution (default: `background_factors`), each run with
    the known cells of the one before (settled cells and seeds). ``fixed``: the map's
    other grid axes, each of one value (name -> value, e.g. ``{"damping": 0.25}``), so
    that the backgrounds run the map's scene, the one its ``catalogue`` was found for
    (without them a grid's ``damping = [0.25]`` over a scene's 0.2 was run at 0.2, and
    `sweep.run` refuses the catalogue of another scene).

    Returns
    -------
    known : xarray.DataArray or None
        The last background's settled cells and seeds (None if every background was
        smaller than 16 x 16).
    cells : int
        Trajectories the backgrounds ran.
    """
    known, cells = None, 0
    if factors is None:
        factors = background_factors(theta.size, omega.size)
    for factor in factors:
        size = [(axis.size - 1) // factor + 1 for axis in (theta, omega)]
        if min(size) < _SMALLEST:
            continue
        axes = [np.linspace(axis[0], axis[-1], n) for axis, n in zip((theta, omega), size)]
        extra = {} if known is None else {"known_cells": known}
        others = {name: np.array([float(value)]) for name, value in (fixed or {}).items()}
        ds = engine.run(scene, Grid(theta0=axes[0], omega0=axes[1], **others),
                        attractors=catalogue, **run_kwargs, **extra)
        cells += int(np.prod(size))
        found = ds["attractor"].values.reshape(size)  # the one-value axes dropped
        index = np.where(np.isfinite(found), found, -1)
        known = known_map(seed_attractors(settled(index.astype(np.int64)), *axes,
                                          catalogue), *axes)
    return known, cells
