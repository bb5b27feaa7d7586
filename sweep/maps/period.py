"""Periodicity maps: the period of the attractor each trajectory settles on, over any
grid (the "isoperiodic" diagrams of the driven-pendulum literature)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import check_count
from . import _strobe
from .labels import (
    check_tolerance,
    map_coords,
    refuse_system_without_strobe,
    strobe_axes,
    strobe_table,
    system_strobe_table,
)

__all__ = ["NO_PERIOD", "period"]

#: The period given where none is found (chaotic, quasi-periodic, not converged, or a
#: failed trajectory).
NO_PERIOD = -1


def period(ds: xr.Dataset, *, max_period: int | None = None, tol: float = 1e-3
           ) -> xr.DataArray:
    """The period, in forcing periods, of the attractor each trajectory settles on.

    A trajectory has period p when its last stroboscopic samples repeat after p
    forcing periods (angles up to whole turns) within ``tol``: the smallest such p is
    given (a period-2 orbit is not also called period 4).

    Parameters
    ----------
    ds : xarray.Dataset
        A run observing ``strobe`` (forced scene, or a driven system: then every
        coordinate and velocity repeats, each angle up to whole turns), over any grid.
    max_period : int, optional
        Longest period looked for; at most half the stroboscopic samples (the
        default: ``strobe_samples // 2``, 8 with the default 16 samples).
    tol : float, default 1e-3
        Repetition tolerance [rad and rad/s]; > 0.

    Returns
    -------
    xarray.DataArray, int32, grid dims
        ``1 .. max_period``, or ``NO_PERIOD`` (-1) where none is found: chaotic or
        quasi-periodic motion, a transient too short to settle, a period longer than
        ``max_period``, or a failed trajectory. A trajectory of a run with an attractor
        catalogue (``attractors=``) that matched one gets the catalogued orbit's period.
        Attributes: ``max_period``, ``tol``, ``no_period``.

    Raises
    ------
    ValueError
        Without stroboscopic samples, or for ``max_period``/``tol`` out of range.
    """
    tol = check_tolerance(tol)
    refuse_system_without_strobe(ds, "period")
    system = isinstance(ds, xr.Dataset) and "strobe_positions" in ds.attrs
    if not system:
        strobe_axes(ds, "stroboscopic analysis")  # before reading the number of samples
    samples = ds.sizes["strobe"]
    largest = samples // 2
    if max_period is None:
        max_period = largest
    max_period = check_count("max_period", max_period, minimum=1, maximum=largest,
                             accepted=f"an int from 1 to {largest} (half the {samples} "
                                      "stroboscopic samples; more samples: sweep.run(..., "
                                      "strobe_samples=N))")
    if system:  # every coordinate's samples, each angle up to whole turns
        theta, omega, angular, dims, *_ = system_strobe_table(ds)
    else:
        theta, omega, dims = strobe_table(ds)
        angular = None
    found, _ = _strobe.periods(theta, omega, max_period, tol, angular)
    found = np.where(found > 0, found, NO_PERIOD).astype(np.int32)
    if "attractor" in ds.data_vars and "attractors_period" in ds.attrs:
        # a trajectory stopped on a catalogued attractor kept too few samples to show
        # its period: it is the catalogued orbit's
        index = np.asarray(ds["attractor"].transpose(*dims).values, float).reshape(-1)
        matched = np.isfinite(index) & (index >= 0)  # NaN: a failed trajectory
        known = np.asarray(ds.attrs["attractors_period"]).reshape(-1)[
            index[matched].astype(np.int64)]
        found[matched] = np.where(known <= max_period, known, NO_PERIOD)
    shape = tuple(ds.sizes[d] for d in dims)
    out = xr.DataArray(found.reshape(shape), coords=map_coords(ds, dims), dims=dims,
                       name="period")
    out.attrs = {"long_name": "period of the attractor (forcing periods); -1: none found",
                 "units": "1", "max_period": int(max_period), "tol": float(tol),
                 "no_period": NO_PERIOD}
    return out
