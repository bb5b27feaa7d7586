"""Phase-space maps: pure functions ``Dataset -> DataArray``.

Maps never re-run the integrator: they read the features a run stored (final state,
winding, mean angular velocity, energy, amplitude) and turn them into labels, so they
work as well on a file loaded from disk (`sweep.load`). This is the split of
Attractors.jl: the kernel computes features, the maps compute labels.

For developers
--------------
A map takes the dataset and keyword options, checks that the variables it needs are
there (naming the ``observe=`` entry that provides them when they are not), and
returns a DataArray on the grid's dimensions with ``long_name``, ``units`` or CF
``flag_values``/``flag_meanings``. Trajectories whose ``status`` is not ok are never
given a label other than the documented "unresolved" value.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._timesteps import transient_steps
from .._validate import check_count, check_numbers, check_quantity
from ..catalogue_scene import PENDULUM_DRIVE, PENDULUM_INITIAL, dataset_scene
from ..kernels import Status
from ..strobe_phase import dataset_drive, phase_axis
from ..system_attractors import coordinate_rows
from . import _strobe

__all__ = ["motion", "well", "basins", "attractor_catalogue", "amplitude", "inverted",
           "natural_frequency_squared", "UNRESOLVED"]

#: Label of a trajectory that no map can classify (failed, not settled, ...).
UNRESOLVED = -1

_MOTION_FILL = np.int8(-127)


def _require(ds: xr.Dataset, variables: tuple[str, ...], observe: str, what: str) -> None:
    missing = [v for v in variables if v not in ds]
    if missing:
        raise ValueError(
            f"{what} needs the variable {missing[0]!r}, which this dataset lacks; accepted: "
            f"a dataset from sweep.run(..., observe=(..., {observe!r}))"
        )


def _parameter(ds: xr.Dataset, name: str):
    """A scene parameter as a grid coordinate (when it is an axis) or a float."""
    if name in ds.coords:
        return ds[name]
    if name in ds.attrs:
        return float(ds.attrs[name])
    raise ValueError(f"dataset has neither a {name!r} axis nor a {name!r} attribute; "
                     "accepted: a dataset made by sweep.run")


def natural_frequency_squared(ds: xr.Dataset):
    """``g/L`` [1/s^2] of each trajectory (a float, or a DataArray over grid axes)."""
    return _parameter(ds, "gravity") / _parameter(ds, "length")


def _ok(ds: xr.Dataset) -> xr.DataArray:
    return ds["status"] == int(Status.OK)


def _steady_window(ds: xr.Dataset) -> float:
    """Duration [s] of the steady window ``t >= t0 + t_transient`` (step-aligned)."""
    dt = float(ds.attrs["dt"])
    n_transient = transient_steps(float(ds.attrs["t_transient"]), dt)
    return (int(ds.attrs["n_steps"]) - n_transient) * dt


def check_min_turns(min_turns) -> float:
    """``min_turns`` (net full turns) as a float; ValueError unless a finite number > 0."""
    return check_quantity("min_turns", min_turns, minimum=0.0, strict=True,
                          accepted="a finite number > 0 (net full turns)")


def check_max_period(max_period) -> int:
    """``max_period`` (forcing periods) as an int; ValueError unless an int >= 1."""
    return check_count("max_period", max_period, minimum=1,
                       accepted="an int >= 1 (forcing periods)")


def motion(ds: xr.Dataset, *, min_turns: float = 1.0) -> xr.DataArray:
    """Rotation versus libration, with the sense of rotation.

    With ``omega_mean`` observed the classification is of the steady motion (after
    ``t_transient``): a trajectory rotates if it turns at least ``min_turns`` full
    turns net during the steady window. Otherwise ``winding`` (wells crossed over the
    whole run: the net signed number of passes over the top) is used, which for
    conservative scenes is the same thing; a libration crosses no top, so it counts 0
    wherever in its well it starts and ends.

    Parameters
    ----------
    ds : xarray.Dataset
        From `sweep.run` with ``observe`` containing ``"omega_mean"``, ``"winding"`` or
        ``"final"`` (in that order of preference: ``round(theta_final / 2 pi) -
        round(theta0 / 2 pi)`` is the winding).
    min_turns : float, default 1
        Net turns that count as rotation (the angle turned over 2 pi in the steady
        window, or passes over the top with ``winding``); a finite number > 0.

    Returns
    -------
    xarray.DataArray, int8, grid dims
        ``-1`` rotation in the negative sense, ``0`` libration, ``1`` rotation in the
        positive sense, ``-127`` unresolved (trajectory failed).

    Notes
    -----
    Near the separatrix the time for one turn diverges like ``ln(16/delta)/omega_n``
    (``delta`` the relative energy above the separatrix), so a rotation that has not
    completed ``min_turns`` turns by ``t_end`` is read as libration: the band of
    misclassified starts has relative width about ``16 exp(-omega_n T / (min_turns + 1))``
    for a window of duration ``T``.
    """
    min_turns = check_min_turns(min_turns)
    if "omega_mean" in ds:
        turns = ds["omega_mean"] * _steady_window(ds) / (2 * np.pi)
        source = "omega_mean over the steady window"
    elif "winding" in ds:
        turns = ds["winding"]
        source = "winding over the whole run"
    else:
        if "theta_final" not in ds:
            raise ValueError("motion needs one of the variables 'omega_mean', 'winding' "
                             "or 'theta_final', and this dataset has none; accepted: a "
                             "dataset from sweep.run(..., observe=(..., 'omega_mean')), "
                             "or with 'winding' or 'final' (none works with stop_early)")
        theta0 = ds["theta0"] if "theta0" in ds.coords else 0.0
        # the winding observable's wells crossed (np.round: half to even, as the kernel)
        turns = np.round(ds["theta_final"] / (2 * np.pi)) - np.round(theta0 / (2 * np.pi))
        source = "wells crossed from theta0 to theta_final over the whole run"
    code = xr.where(np.abs(turns) >= min_turns, np.sign(turns), 0)
    code = xr.where(_ok(ds), code, _MOTION_FILL).astype(np.int8)
    code.attrs = {
        "long_name": f"motion: rotation (sense) or libration, from {source}",
        "flag_values": np.array([-1, 0, 1, _MOTION_FILL], dtype=np.int8),
        "flag_meanings": "rotation_negative libration rotation_positive unresolved",
        "min_turns": float(min_turns),
    }
    return code.rename("motion")


def inverted(ds: xr.Dataset, *, tolerance: float = 0.5) -> xr.DataArray:
    """Whether the pendulum stays near the top (``theta = pi`` mod ``2 pi``) after the
    transient: Kapitza's pendulum, stabilised upside down by a fast pivot drive.

    Parameters
    ----------
    ds : xarray.Dataset
        From `sweep.run` with ``observe`` containing ``"top_distance"``.
    tolerance : float, default 0.5
        Largest distance from the upright position [rad] over ``t >= t0 +
        t_transient`` that counts as staying up; finite and in (0, pi).

    Returns
    -------
    xarray.DataArray, bool, grid dims
        True where every steady-window angle is within ``tolerance`` of the top; False
        elsewhere, and for trajectories that failed (``status`` not ok).
    """
    tolerance = check_quantity("tolerance", tolerance, minimum=0.0, strict=True,
                               accepted="a finite number in (0, pi) (rad)")
    if tolerance >= np.pi:
        raise ValueError(f"tolerance must be a finite number in (0, pi) (rad), got "
                         f"{tolerance!r}")
    _require(ds, ("top_distance_max",), "top_distance", "inverted")
    up = (ds["top_distance_max"] < tolerance) & _ok(ds)
    up.attrs = {"long_name": "stays within tolerance of the upright position after "
                             "the transient", "tolerance": tolerance, "units": "1"}
    return up.rename("inverted")


def _captured(ds: xr.Dataset) -> xr.DataArray:
    """True where the final energy is below the separatrix energy ``2 g/L``.

    An unforced damped pendulum below that energy can never leave its well: its
    energy only decreases.
    """
    _require(ds, ("energy_final",), "energy", "capture detection")
    return ds["energy_final"] < 2.0 * natural_frequency_squared(ds)


def _check_unforced(ds: xr.Dataset, what: str) -> None:
    if "forcing" in str(ds.attrs.get("effects", "")).split():
        raise ValueError(f"{what} is for unforced scenes (an unforced damped pendulum "
                         "settles in a well); this dataset's scene has forcing; accepted: "
                         "for a forced scene, sweep.maps.basins of a run observing "
                         "'strobe', or sweep.maps.motion")


def well(ds: xr.Dataset) -> xr.DataArray:
    """The potential well ``k`` (rest position ``2 pi k``) each start ends in.

    Parameters
    ----------
    ds : xarray.Dataset
        An unforced run observing ``capture`` (its ``well`` is used directly), or
        ``final`` and ``energy``.

    Returns
    -------
    xarray.DataArray, float64, grid dims
        ``round(theta_final / 2 pi)`` where the pendulum has been captured (final
        energy below the separatrix, so it can never leave that well); NaN where it
        has not (still rotating at ``t_end``) or the trajectory failed.
    """
    _check_unforced(ds, "well")
    if "well" in ds:  # observed directly ("capture", possibly with stop_early)
        index = ds["well"].where(_ok(ds))
    else:
        missing = [v for v in ("theta_final", "energy_final") if v not in ds]
        if missing:
            raise ValueError(f"well needs the variable 'well' (observe 'capture') or both "
                             f"'theta_final' and 'energy_final' (observe 'final' and "
                             f"'energy'), and this dataset lacks {missing[0]!r}; accepted: "
                             "a dataset from sweep.run(..., observe=(..., 'capture')), "
                             "which stop_early=True also allows")
        index = np.round(ds["theta_final"] / (2 * np.pi))
        index = index.where(_captured(ds) & _ok(ds))
    index.attrs = {"long_name": "final potential well k (rest at theta = 2 pi k)",
                   "units": "1"}
    return index.rename("well")


def basins(ds: xr.Dataset, *, rest_position: bool = False, max_period: int = 8,
           tol: float = 1e-3) -> xr.DataArray:
    """Basins of attraction as integer labels with a catalogue of attractors.

    For unforced damped scenes the attractors are the rest states ``theta = 2 pi k``;
    with ``rest_position=True`` they are identified modulo ``2 pi`` (the physical
    rest position, so every captured start gets the same label).

    For forced scenes (a run observing ``strobe``) the attractors are the periodic
    orbits found in the stroboscopic samples by `identify_attractors`; so for a driven
    system of several coordinates (`sweep.DoublePendulum` with a pivot drive, a
    `sweep.DeclaredSystem` with a ``drive_frequency_axis``), from the samples of every
    coordinate and velocity (``theta1_strobe``, ...), its angles compared modulo 2 pi
    each.

    Parameters
    ----------
    ds : xarray.Dataset
        An unforced run observing ``capture`` (with or without ``stop_early``), or
        ``final`` and ``energy``; or a forced run (of the pendulum or of a system)
        observing ``strobe``.
    rest_position : bool, default False
        Unforced scenes: identify wells modulo 2 pi.
    max_period, tol
        Forced scenes: passed to `identify_attractors` (an int >= 1 and a finite number
        > 0; checked for every scene).

    Returns
    -------
    xarray.DataArray, int32, grid dims
        ``0 .. n-1`` attractor labels, ``-1`` unresolved (not yet captured, chaotic,
        not converged, or failed). Attributes list each attractor by label:
        ``attractor_theta`` [rad] (and, forced, ``attractor_omega`` [rad/s],
        ``attractor_period`` [forcing periods], ``attractor_turns_per_period``,
        ``attractor_size`` [trajectories]). A system's: ``attractor_<coordinate>``
        and ``attractor_<velocity>`` for each (``attractor_theta1``, ...,
        ``attractor_omega2``; angles in [0, 2 pi)), ``attractor_turns_per_period_<angle>``
        for each angle, ``attractor_period``, ``attractor_size``.
    """
    max_period = check_max_period(max_period)  # checked whichever path is taken below
    tol = check_tolerance(tol)
    if "strobe_positions" in ds.attrs:
        return _system_basins(ds, max_period=max_period, tol=tol)
    refuse_system_without_strobe(ds, "basins")
    if "strobe_theta" in ds:
        return _forced_basins(ds, max_period=max_period, tol=tol)
    if "forcing" in str(ds.attrs.get("effects", "")).split():
        raise ValueError("basins of a forced scene need stroboscopic samples; accepted: a "
                         "dataset from sweep.run(..., observe=(..., 'strobe'))")
    index = well(ds)
    if rest_position:
        index = xr.where(index.notnull(), 0.0, np.nan)
    values = index.values
    found = np.unique(values[np.isfinite(values)])
    labels = np.full(values.shape, UNRESOLVED, dtype=np.int32)
    finite = np.isfinite(values)
    labels[finite] = np.searchsorted(found, values[finite])
    out = xr.DataArray(labels, coords=index.coords, dims=index.dims, name="basins")
    out.attrs = {
        "long_name": "basin of attraction (attractor label)",
        "attractor_theta": (2 * np.pi * found).astype(np.float64),
        "attractor_kind": "rest state modulo 2 pi" if rest_position else "rest state",
        "unresolved": UNRESOLVED,
    }
    return out


def refuse_system_without_strobe(ds: xr.Dataset, what: str) -> None:
    """Refuse a system's run (``system_name``) without stroboscopic samples for
    ``sweep.maps.<what>`` (``"basins"``, ...), naming a run that has them, rather than
    the single pendulum's variables."""
    if isinstance(ds, xr.Dataset) and "system_name" in ds.attrs \
            and "strobe_positions" not in ds.attrs:
        if "attractor" in ds.data_vars:  # a run on a catalogue: its labels are there
            raise ValueError(f"sweep.maps.{what} needs a system's stroboscopic samples, "
                             f"and this run of {ds.attrs['system_name']} has none: it was "
                             "run on an attractor catalogue, and its variable 'attractor' "
                             "is each start's attractor (-1: none); accepted: those "
                             "labels, ds['attractor'], or a run observing 'strobe'")
        raise ValueError(f"sweep.maps.{what} needs a system's stroboscopic samples, and "
                         f"this run of {ds.attrs['system_name']} has none; accepted: a "
                         "dataset from sweep.run(driven_system, ..., observe=(..., "
                         "'strobe')), e.g. sweep.DoublePendulum(..., pivot_amplitude=a, "
                         "pivot_frequency=nu)")


def system_strobe_table(ds: xr.Dataset):
    """A system run's stroboscopic samples as two (n, m, P) tables (rows in the order
    of the grid dims), the angular flags of its m coordinates, the grid dims, and the
    names of the coordinates and of the velocities.

    Raises
    ------
    ValueError
        If a sample variable the attributes name is missing.
    """
    positions = str(ds.attrs["strobe_positions"]).split()
    velocities = str(ds.attrs["strobe_velocities"]).split()
    angles = set(str(ds.attrs.get("strobe_angular", "")).split())
    _require(ds, tuple(f"{name}_strobe" for name in positions + velocities), "strobe",
             "basins")
    dims = tuple(d for d in ds[f"{positions[0]}_strobe"].dims if d != "strobe")
    samples = ds.sizes["strobe"]
    tables = [np.stack([ds[f"{name}_strobe"].transpose(*dims, "strobe").values
                        .reshape(-1, samples) for name in names], axis=1)
              for names in (positions, velocities)]
    angular = np.array([name in angles for name in positions])
    return tables[0], tables[1], angular, dims, positions, velocities


def _system_rings(ds: xr.Dataset, width: int) -> tuple[np.ndarray, np.ndarray]:
    """A system run's catalogued rings (``attractors_*`` attributes,
    `sweep.system_attractors.catalogue_attributes`) as (k, m, ``width``) tables, each
    extended backwards along its own orbit or cut to its last ``width`` samples, as
    `_catalogue_rings` does for one angle (a coordinate that is not an angle repeats
    without turns)."""
    attrs = ds.attrs
    samples, m = int(attrs["attractors_samples"]), int(attrs["attractors_coordinates"])
    theta, omega = (np.asarray(attrs[f"attractors_{name}"], dtype=np.float64)
                    .reshape(-1, m, samples) for name in ("theta", "omega"))
    period = np.atleast_1d(np.asarray(attrs["attractors_period"], dtype=np.int64))
    angles = set(str(attrs.get("strobe_angular", "")).split())
    angular = np.array([name in angles for name in str(attrs["strobe_positions"]).split()])
    out_theta = np.empty((theta.shape[0], m, width))
    out_omega = np.empty_like(out_theta)
    for a, p in enumerate(period):
        turn = np.where(angular, theta[a, :, -1] - theta[a, :, -1 - p], 0.0)
        for k in range(1, width + 1):  # k-th sample from the end
            back = max(0, (k - samples + p - 1) // p)  # orbits to step back
            j = samples - k + back * p
            out_theta[a, :, -k] = theta[a, :, j] - back * turn if back else theta[a, :, j]
            out_omega[a, :, -k] = omega[a, :, j]
    return out_theta, out_omega


def _system_basins(ds: xr.Dataset, *, max_period: int, tol: float) -> xr.DataArray:
    """`basins` of a driven system's run (`system_strobe_table`); a trajectory that a
    run with an attractor catalogue matched (``attractor >= 0``: it may have stopped
    before its samples show a period) stands for its catalogued ring, as in the single
    pendulum's `_identify_with_catalogue`."""
    position, velocity, angular, dims, positions, velocities = system_strobe_table(ds)
    index = None
    if "attractor" in ds and "attractors_theta" in ds.attrs:
        index = ds["attractor"].transpose(*dims).values.ravel()
        index = np.where(np.isfinite(index), index, -1).astype(np.int64)
    if index is None or not (index >= 0).any():
        labels, catalogue = identify_attractors(position, velocity, max_period=max_period,
                                                tol=tol, angular=angular)
    else:
        labels, catalogue = _identify_with_catalogue(
            position[index < 0], velocity[index < 0], index, None, max_period=max_period,
            tol=tol, rings=_system_rings(ds, position.shape[2]), angular=angular)
    shape = tuple(ds.sizes[d] for d in dims)
    out = xr.DataArray(labels.reshape(shape), coords=map_coords(ds, dims), dims=dims,
                       name="basins")
    attrs = {"long_name": "basin of attraction (attractor label)"}
    for k, name in enumerate(positions):
        attrs[f"attractor_{name}"] = catalogue["theta"][:, k]
    for k, name in enumerate(velocities):
        attrs[f"attractor_{name}"] = catalogue["omega"][:, k]
    attrs["attractor_period"] = catalogue["period"]
    for k, name in enumerate(positions):
        if angular[k]:
            attrs[f"attractor_turns_per_period_{name}"] = catalogue["turns_per_period"][:, k]
    attrs.update(attractor_size=catalogue["size"],
                 attractor_kind="periodic orbit (stroboscopic point, angles modulo 2 pi)",
                 unresolved=UNRESOLVED)
    out.attrs = attrs
    return out


def strobe_axes(ds: xr.Dataset, what: str, along: str | None = None) -> list[str]:
    """The grid axes of a dataset with stroboscopic samples, in order; with ``along``,
    check that it is one of them.

    Parameters
    ----------
    ds : xarray.Dataset
    what : str
        What needs them, for the message (``"continuation"``).
    along : str, optional

    Raises
    ------
    ValueError
        Without ``strobe_theta`` and ``strobe_omega`` (saying to observe ``strobe``), or
        for an ``along`` that is not a grid axis (saying what it is instead, and listing
        the axes).
    """
    if isinstance(ds, xr.Dataset) and "strobe_positions" in ds.attrs:
        raise ValueError(f"{what} is not available for a system's stroboscopic samples "
                         "yet; accepted: sweep.maps.basins, or a single pendulum's run")
    if not isinstance(ds, xr.Dataset) or "strobe_theta" not in ds or "strobe_omega" not in ds:
        raise ValueError(f"{what} needs stroboscopic samples (strobe_theta and "
                         "strobe_omega); accepted: a dataset from sweep.run(..., "
                         "observe=('strobe',)) of a forced scene")
    axes = [d for d in ds["strobe_theta"].dims if d != "strobe"]
    if along is not None and along not in axes:
        if along == "strobe":
            instead = " (it is the dimension of the stroboscopic samples)"
        elif along in ds.data_vars:
            instead = " (it is a data variable)"
        elif along in ds.coords:
            instead = " (it is a coordinate but not a dimension of the grid)"
        elif along in ds.attrs:
            instead = " (it is held fixed in this run: a dataset attribute)"
        else:
            instead = ""
        raise ValueError(f"along = {along!r} is not a grid axis of this dataset{instead}; "
                         f"accepted: {', '.join(repr(a) for a in axes)}")
    return axes


def check_tolerance(tol) -> float:
    """``tol`` [rad and rad/s] as a float; ValueError unless a finite number > 0 (one
    that is not a number: `ArgumentTypeError`, a ValueError and a TypeError)."""
    return check_quantity("tol", tol, minimum=0.0, strict=True,
                          accepted="a finite number > 0 (rad and rad/s)")


def strobe_table(ds: xr.Dataset, rows=None) -> tuple[np.ndarray, np.ndarray,
                                                     tuple[str, ...]]:
    """The stroboscopic samples of every trajectory as two (n, P) tables, rows in the
    order of the grid dims (returned third); with ``rows`` (indices into that order),
    of those trajectories only (nothing else is copied).

    Raises
    ------
    ValueError
        If the dataset has no stroboscopic samples.
    """
    dims = tuple(strobe_axes(ds, "stroboscopic analysis"))
    theta = ds["strobe_theta"]
    samples = theta.sizes["strobe"]
    table = [ds[name].transpose(*dims, "strobe").values.reshape(-1, samples)
             for name in ("strobe_theta", "strobe_omega")]
    if rows is not None:
        table = [t[rows] for t in table]
    return (np.ascontiguousarray(table[0], dtype=np.float64),
            np.ascontiguousarray(table[1], dtype=np.float64), dims)


def map_coords(ds: xr.Dataset, dims) -> dict[str, xr.DataArray]:
    """The coordinates of ``ds`` that lie along ``dims`` only, for a map over them: a
    grid's axes (each its own dimension), or every axis of `sweep.Points` (all along
    ``point``, which has none of its own)."""
    return {name: coord for name, coord in ds.coords.items()
            if coord.dims and set(coord.dims) <= set(dims)}


def _catalogued(ds: xr.Dataset, dims) -> np.ndarray | None:
    """Per trajectory (rows in ``dims`` order), the index of the catalogued attractor
    the run's ``attractor`` observable matched, -1 where none (or a failed
    trajectory); None for a run without a catalogue."""
    if "attractor" not in ds or "attractors_theta" not in ds.attrs:
        return None
    index = ds["attractor"].transpose(*dims).values.ravel()
    return np.where(np.isfinite(index), index, -1).astype(np.int64)


def _catalogue_rings(attrs, width: int) -> tuple[np.ndarray, np.ndarray]:
    """The run's catalogued rings (``attractors_*`` attributes), each ``width`` samples
    long: a shorter ring is extended backwards along its own orbit (its last ``period``
    points repeat, the angle shifted by the orbit's turns), a longer one keeps its
    last ``width`` samples."""
    samples = int(attrs["attractors_samples"])
    theta, omega = (np.asarray(attrs[f"attractors_{name}"], dtype=np.float64)
                    .reshape(-1, samples) for name in ("theta", "omega"))
    period = np.atleast_1d(np.asarray(attrs["attractors_period"], dtype=np.int64))
    out_theta = np.empty((theta.shape[0], width))
    out_omega = np.empty_like(out_theta)
    for a, p in enumerate(period):
        for k in range(1, width + 1):  # k-th sample from the end
            back = max(0, (k - samples + p - 1) // p)  # orbits to step back
            j = samples - k + back * p
            out_theta[a, -k] = theta[a, j] - back * (theta[a, -1] - theta[a, -1 - p]) \
                if back else theta[a, j]
            out_omega[a, -k] = omega[a, j]
    return out_theta, out_omega


def _identify_with_catalogue(theta, omega, index, attrs, *, max_period: int, tol: float,
                             rings=None, angular=None):
    """`identify_attractors` for a run with an attractor catalogue. A trajectory the
    kernel matched to catalogued attractor ``a`` (``index >= 0``) stopped before its
    own samples could show a period; it stands for that attractor's ring (extended to
    the map's width, `_catalogue_rings`). The unmatched trajectories (``theta`` and
    ``omega``: their samples only, in order) and one row per matched attractor,
    weighted by its matches, are identified together: the labels, sizes and order (ties
    included) are those of identifying every row, at the cost of the unmatched rows
    only. A system's (``theta``, ``omega`` of shape (n, m, P)) gives its ``rings``
    (`_system_rings`) and ``angular`` flags."""
    matched = index >= 0
    counts = np.bincount(index[matched], minlength=0)
    used = np.flatnonzero(counts)  # catalogued attractors this run matched
    if rings is None:
        rings = _catalogue_rings(attrs, theta.shape[1])
    unmatched = np.flatnonzero(~matched)
    table = [np.concatenate([t, r[used]]) for t, r in zip((theta, omega), rings)]
    weights = np.concatenate([np.ones(unmatched.size, dtype=np.int64), counts[used]])
    part, catalogue = identify_attractors(*table, max_period=max_period, tol=tol,
                                          weights=weights, angular=angular)
    labels = np.empty(index.size, dtype=np.int32)
    labels[unmatched] = part[:unmatched.size]
    ring_label = np.full(max(counts.size, 1), UNRESOLVED, dtype=np.int32)
    ring_label[used] = part[unmatched.size:]
    labels[matched] = ring_label[index[matched]]
    return labels, catalogue


def _forced_basins(ds: xr.Dataset, *, max_period: int, tol: float) -> xr.DataArray:
    dims = tuple(strobe_axes(ds, "stroboscopic analysis"))
    index = _catalogued(ds, dims)
    if index is None or not (index >= 0).any():
        flat_theta, flat_omega, _ = strobe_table(ds)
        labels, catalogue = identify_attractors(flat_theta, flat_omega,
                                                max_period=max_period, tol=tol)
    else:  # the samples of the unmatched trajectories only
        flat_theta, flat_omega, _ = strobe_table(ds, np.flatnonzero(index < 0))
        labels, catalogue = _identify_with_catalogue(flat_theta, flat_omega, index,
                                                     ds.attrs, max_period=max_period,
                                                     tol=tol)
    shape = tuple(ds.sizes[d] for d in dims)
    out = xr.DataArray(labels.reshape(shape), coords=map_coords(ds, dims), dims=dims,
                       name="basins")
    out.attrs = {
        "long_name": "basin of attraction (attractor label)",
        "attractor_theta": catalogue["theta"],
        "attractor_omega": catalogue["omega"],
        "attractor_period": catalogue["period"],
        "attractor_turns_per_period": catalogue["turns_per_period"],
        "attractor_size": catalogue["size"],
        "attractor_kind": "periodic orbit (stroboscopic point, angle modulo 2 pi)",
        "unresolved": UNRESOLVED,
    }
    return out


def attractor_catalogue(ds: xr.Dataset, labels: xr.DataArray | None = None, *,
                        max_period: int = 8, tol: float = 1e-3) -> dict:
    """The attractors a forced run found, as a catalogue for ``sweep.run(...,
    attractors=...)``.

    Parameters
    ----------
    ds : xarray.Dataset
        A run of a forced scene observing ``strobe`` (a pilot: e.g. a coarse grid of
        the map to come, with ``stop_early``).
    labels : xarray.DataArray, optional
        `basins` of ``ds`` (computed with ``max_period`` and ``tol`` if not given).
    max_period, tol
        As in `basins` (checked even when ``labels`` is given).

    Returns
    -------
    dict
        ``theta``, ``omega``: ndarray, shape (m, P) [rad, rad/s]: the stroboscopic ring
        (oldest first, angle unwrapped) of one trajectory on each of the m attractors,
        in label order; ``period``: ndarray (m,) of int, forcing periods;
        ``drive_phase`` [rad] and ``drive_frequency`` [rad/s]: ndarray (m,) each, the
        drive's phase ``W (t0 + n_transient dt) + phi mod 2 pi`` at the rings' samples
        (phi its phase constant, ``forcing_phase``) and its angular frequency W
        (`sweep.strobe_phase`; absent where the run has no one frequency and phase): a
        run that uses the catalogue must sample at that drive phase, e.g. its ``t0 +
        t_transient`` a whole number of periods from the pilot's with the same phi, or
        it is refused; ``other_drive_phases``: where the scene has other drives (a
        `sweep.PivotDrive` beside the forcing, a `sweep.Forcing(on=...)` beside a
        system's pivot; those the run names in ``strobe_other_drives``), their phases
        ``nu (t0 + n_transient dt) + psi mod 2 pi`` [rad] (a structured array, a row per
        attractor and a field per drive, named by its frequency axis); a run whose
        first sample meets one at none of the phases the ring met is refused;
        ``scene``: the run's parameters of one value (a structured
        array, a row per attractor; `sweep.catalogue_scene`; absent for a dataset
        without ``strobe_scene``): a run of another value is refused. Of a driven
        system with several coordinates (a run of `sweep.DoublePendulum` with a pivot
        drive, ...): ``theta`` and ``omega`` of shape (m, c, P), the rings of its c
        coordinates and of their velocities (angles unwrapped), and ``coordinates``:
        ndarray (m, c) of str, their names, one row per attractor (every row the
        same); pass it to ``sweep.run(system, grid, observe=("attractor",),
        attractors=...)``. Every value is an array with one entry per attractor first,
        so that selecting attractors, ``{key: value[keep] for key, value in
        catalogue.items()}`` (``keep`` a boolean mask, indices or a slice), gives a
        catalogue of those attractors.

    Raises
    ------
    ValueError
        If the run found no attractor, or for ``max_period`` or ``tol`` out of range.
    """
    max_period = check_max_period(max_period)
    tol = check_tolerance(tol)
    if isinstance(ds, xr.Dataset) and "strobe_positions" in ds.attrs:
        return _system_catalogue(ds, labels, max_period=max_period, tol=tol)
    refuse_system_without_strobe(ds, "attractor_catalogue")
    flat_theta, flat_omega, dims = strobe_table(ds)
    if labels is None:
        labels = basins(ds, max_period=max_period, tol=tol)
    flat = labels.transpose(*dims).values.ravel()
    period = _resolved_periods(labels)
    index, rings = _catalogued(ds, dims), None
    if index is not None and (index >= 0).any():  # matched rows: their catalogued ring
        rings = _catalogue_rings(ds.attrs, flat_theta.shape[1])
    theta, omega = _rings_by_label(period.size, flat, index, rings, flat_theta, flat_omega)
    return {"theta": theta, "omega": omega, "period": period,
            **dataset_drive(ds, "forcing_frequency", period.size),
            **dataset_scene(ds, period.size, PENDULUM_INITIAL, PENDULUM_DRIVE)}


def _rings_by_label(n: int, flat, index, rings, theta_rows, omega_rows):
    """Per label 0 .. n-1, the ring of its first start (rows of ``theta_rows``,
    ``omega_rows``), or, where that start matched a catalogued attractor (``index`` >=
    0), the catalogue's own ring of it (``rings``)."""
    theta = np.empty((n,) + theta_rows.shape[1:])
    omega = np.empty_like(theta)
    for label in range(n):
        row = int(np.flatnonzero(flat == label)[0])
        if index is not None and index[row] >= 0:
            theta[label], omega[label] = rings[0][index[row]], rings[1][index[row]]
        else:
            theta[label], omega[label] = theta_rows[row], omega_rows[row]
    return theta, omega


def _resolved_periods(labels: xr.DataArray) -> np.ndarray:
    """The periods of the attractors ``labels`` found (`basins`' attributes); refuses a
    run that resolved none."""
    period = np.asarray(labels.attrs["attractor_period"], dtype=np.int64)
    if period.size == 0:
        raise ValueError("attractor_catalogue: the run resolved no attractor (every "
                         "trajectory is unresolved); accepted: a run whose trajectories "
                         "settle, e.g. a longer t_end or t_transient")
    return period


def _system_catalogue(ds: xr.Dataset, labels, *, max_period: int, tol: float) -> dict:
    """`attractor_catalogue` of a driven system's run (its rings of every coordinate)."""
    position, velocity, _, dims, positions, velocities = system_strobe_table(ds)
    if labels is None:
        labels = basins(ds, max_period=max_period, tol=tol)
    flat = labels.transpose(*dims).values.ravel()
    period = _resolved_periods(labels)
    index = rings = None
    if "attractor" in ds and "attractors_theta" in ds.attrs:
        index = ds["attractor"].transpose(*dims).values.ravel()
        index = np.where(np.isfinite(index), index, -1).astype(np.int64)
        rings = _system_rings(ds, position.shape[2])
    theta, omega = _rings_by_label(period.size, flat, index, rings, position, velocity)
    drive = str(ds.attrs["strobe_frequency"])
    initial = tuple(f"{name}_0" for name in positions + velocities)  # initial_axes
    return {"theta": theta, "omega": omega, "period": period,
            "coordinates": coordinate_rows(positions, period.size),
            **dataset_drive(ds, drive, period.size),
            **dataset_scene(ds, period.size, initial, (drive, phase_axis(drive)))}


def amplitude(ds: xr.Dataset, *, min_turns: float = 1.0) -> xr.DataArray:
    """Steady amplitude after the transient, NaN where the pendulum rotates.

    Parameters
    ----------
    ds : xarray.Dataset
        A run observing ``amplitude`` and ``omega_mean`` (or ``winding``).
    min_turns : float, default 1
        Passed to `motion`; a finite number > 0.

    Returns
    -------
    xarray.DataArray, float64 [rad], grid dims
        Half peak-to-peak of theta over ``t >= t0 + t_transient``; NaN where `motion`
        says rotation or the trajectory failed.
    """
    min_turns = check_min_turns(min_turns)
    _require(ds, ("amplitude",), "amplitude", "amplitude map")
    code = motion(ds, min_turns=min_turns)
    out = ds["amplitude"].where(code == 0)
    out.attrs = {"long_name": "steady amplitude (half peak-to-peak of theta after the "
                              "transient); NaN where the pendulum rotates",
                 "units": "rad"}
    return out.rename("amplitude")


# ------------------------------------------------------------------ forced attractors
def _orbit(position_row, velocity_row, p, angular=None):
    """The p orbit points of m coordinates (angles wrapped to [0, 2 pi)), then their
    velocities: shape (p, 2 m), from rows of shape (m, P) (or of one angle: (P,), and
    shape (p, 2)); ``angular`` (m,) bool, default all."""
    position_row, velocity_row = np.atleast_2d(position_row), np.atleast_2d(velocity_row)
    if angular is None:
        angular = np.ones(position_row.shape[0], dtype=bool)
    position = position_row[:, -p:]
    position = np.where(angular[:, None], np.mod(position, 2 * np.pi), position)
    return np.concatenate([position, velocity_row[:, -p:]], axis=0).T


def _same_orbit(a: np.ndarray, b: np.ndarray, tol: float,
                angular: np.ndarray | None = None) -> bool:
    """True if orbits a and b (shape (p, 2 m), `_orbit`) coincide up to a cyclic shift,
    the angles (``angular``, default all m coordinates) compared modulo 2 pi."""
    if angular is None:
        angular = np.ones(a.shape[1] // 2, dtype=bool)
    m = angular.size
    for shift in range(len(a)):
        rolled = np.roll(b, shift, axis=0)
        difference = np.abs(a - rolled)
        difference[:, :m] = np.where(angular, np.minimum(difference[:, :m],
                                                         2 * np.pi - difference[:, :m]),
                                     difference[:, :m])
        if (difference < tol).all():
            return True
    return False


def _check_weights(weights, n: int) -> np.ndarray:
    """``weights`` of `identify_attractors` as a float64 array of n whole numbers >= 1."""
    accepted = (f"a 1-D array of n = {n} whole numbers >= 1 (the trajectories each row "
                "stands for)")
    values = check_numbers("weights", weights)
    if values.shape != (n,):
        raise ValueError(f"weights must be {accepted}, got shape {values.shape}")
    bad = ~np.isfinite(values) | (values < 1) | (values != np.round(values))
    if bad.any():
        index = int(np.flatnonzero(bad)[0])
        raise ValueError(f"weights must be {accepted}, got {float(values[index])!r} at index "
                         f"{index}")
    return values


def identify_attractors(theta: np.ndarray, omega: np.ndarray, *, max_period: int = 8,
                        tol: float = 1e-3, weights: np.ndarray | None = None,
                        angular=None):
    """Group trajectories by the periodic attractor their stroboscopic samples sit on.

    Parameters
    ----------
    theta, omega : ndarray, shape (n, P) or (n, m, P)
        Last P stroboscopic samples per trajectory, oldest first: of one angle and its
        velocity (the single pendulum), or of m coordinates and their velocities (a
        system: `sweep.maps.basins` reads them from ``theta1_strobe``, ...).
    max_period : int, default 8
        Longest period (in forcing periods) that is looked for; >= 1.
    tol : float, default 1e-3
        Repetition and identity tolerance, in rad and rad/s (the coordinates' units);
        > 0.
    weights : ndarray of int, shape (n,), optional
        How many trajectories each row stands for (default one each), whole numbers
        >= 1: basin sizes, and the order of the labels, count them so.
    angular : array_like of bool, shape (m,), optional
        With (n, m, P) tables: which coordinates are angles, compared modulo 2 pi and
        allowed whole turns per period (default: all).

    Returns
    -------
    labels : ndarray, shape (n,), int32
        ``0..m-1`` by decreasing basin size; ``-1`` unresolved (no period found:
        chaotic, quasi-periodic or not converged, or a failed trajectory).
    catalogue : dict of ndarray
        ``theta`` [rad, in [0, 2 pi)] and ``omega`` [rad/s]: one point of each
        attractor; ``period`` (forcing periods); ``turns_per_period`` (mean net turns
        per forcing period; 0 for librations); ``size`` (trajectories in its basin).
        With (n, m, P) tables ``theta``, ``omega`` and ``turns_per_period`` have a
        column per coordinate (angles wrapped to [0, 2 pi), others as they are).

    Notes
    -----
    Orbits are first bucketed by (period, turns, quantised orbit point of least
    wrapped angle -- of the first coordinate), then buckets whose orbits coincide up
    to a cyclic shift within ``tol`` are merged, so quantisation edges do not split an
    attractor.

    Raises
    ------
    ValueError
        For ``theta`` and ``omega`` of different shapes, or ``max_period``, ``tol``,
        ``weights`` or ``angular`` out of range.
    """
    max_period = check_max_period(max_period)
    tol = check_tolerance(tol)
    theta, omega, angular, one = _strobe.as_coordinates(theta, omega, angular)
    if weights is not None:
        weights = _check_weights(weights, theta.shape[0])
    period, turns = _strobe.periods(theta, omega, max_period, tol, angular)
    n, m = theta.shape[:2]
    labels = np.full(n, UNRESOLVED, dtype=np.int32)
    resolved = np.flatnonzero(period > 0)
    if resolved.size == 0:
        empty = np.zeros(0 if one else (0, m))
        return labels, {"theta": empty, "omega": empty, "period": np.zeros(0, dtype=int),
                        "turns_per_period": empty, "size": np.zeros(0, dtype=int)}
    bucket_of, buckets, first = _strobe.bucket_keys(theta, omega, period, turns, resolved,
                                                    10 * tol, angular)
    # buckets in lexicographic order of their keys (the merge below and the order of
    # equal-sized basins depend on it)
    order = np.lexsort(buckets.T[::-1])
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    buckets, first, bucket_of = buckets[order], first[order], rank[bucket_of]
    # merge buckets holding the same orbit (few buckets: quadratic is fine); the same
    # period and turns (key columns 0 to m)
    parent = np.arange(len(buckets))
    orbits = [_orbit(theta[r], omega[r], int(buckets[b, 0]), angular)
              for b, r in enumerate(first)]
    for a in range(len(buckets)):
        for b in range(a):
            if parent[b] != b or (buckets[a, :m + 1] != buckets[b, :m + 1]).any():
                continue
            if _same_orbit(orbits[a], orbits[b], 10 * tol, angular):
                parent[a] = b
                break
    attractor_of_bucket = parent[bucket_of]
    roots, inverse, sizes = np.unique(attractor_of_bucket, return_inverse=True,
                                      return_counts=True)
    if weights is not None:
        sizes = np.bincount(inverse.ravel(), weights=weights[resolved],
                            minlength=roots.size).round().astype(np.int64)
    order = np.argsort(-sizes, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    labels[resolved] = rank[inverse.ravel()]
    reps = np.array([first[r] for r in roots[order]])
    last = theta[reps, :, -1]
    turns = turns.reshape(n, m)
    catalogue = {
        "theta": np.where(angular, np.mod(last, 2 * np.pi), last),
        "omega": omega[reps, :, -1],
        "period": period[reps],
        "turns_per_period": turns[reps] / period[reps, None],
        "size": sizes[order],
    }
    if one:
        for key in ("theta", "omega", "turns_per_period"):
            catalogue[key] = catalogue[key][:, 0]
    return labels, catalogue
