"""Matplotlib figures of sweep datasets: 2-D maps and trajectories.

matplotlib is imported inside the functions, so ``import sweep.plot`` costs nothing
and loads no plotting library until a figure is drawn. Every function works on a
dataset loaded from disk (`sweep.load`): plotting never re-runs the integrator.

Conventions
-----------
- Angle-like coordinates are shown in degrees (deg, deg/s) when ``degrees=True``:
  the axes a run file accepts in degrees (`angle_axis`: ``theta0`` [rad], ``omega0``
  [rad/s], ``forcing_phase``, ``pivot_phase``, and a system's initial angles and
  angular velocities, ``theta1_0``, ``omega1_0``, ...); data values are always shown
  in the units stored with them.
- Axis and colour-bar labels come from the ``long_name`` and ``units`` attributes
  that `sweep.run` writes; UDUNITS strings are shown in the usual notation
  (``"rad s-1"`` as ``rad/s``).
"""

from __future__ import annotations

import math
import os
import re
import secrets
import textwrap
from pathlib import Path

import numpy as np

from ._validate import check_quantity

__all__ = ["angle_axis", "basin_fractions", "basins", "degree_units", "map", "orbit_diagram",
           "period_map", "save_figure", "select", "trajectory"]

#: The single pendulum's coordinates converted to degrees (and deg/s) when
#: ``degrees=True``; `angle_axis` adds every other axis declared as an angle.
ANGLE_COORDS = ("theta0", "omega0", "forcing_phase")

#: Integer-valued maps with at most this many distinct levels get a discrete colormap.
MAX_DISCRETE_LEVELS = 41

#: Most trajectories `trajectory` draws in one figure.
MAX_TRAJECTORIES = 10

_SYMBOLS = {
    "theta0": r"$\theta_0$",
    "omega0": r"$\omega_0$",
    "theta": r"$\theta$",
    "omega": r"$\omega$",
    "time": "$t$",
}

_LABEL_WIDTH = 48  # characters per line of a wrapped colour-bar label


# ----------------------------------------------------------------------------- labels
def units_text(units: str) -> str:
    """Show a UDUNITS string the usual way: ``"rad s-1"`` -> ``"rad/s"``.

    Parameters
    ----------
    units : str
        Space-separated factors with optional integer exponents (``"m s-2"``).
        ``"1"`` and ``""`` mean dimensionless.

    Returns
    -------
    str
        E.g. ``"rad/s"``, ``"m/s²"``, ``"1/s"``; ``""`` for dimensionless.
    """
    units = (units or "").strip()
    if units in ("", "1"):
        return ""
    numerator, denominator = [], []
    for factor in units.split():
        match = re.fullmatch(r"([A-Za-z]+)(-?\d+)?", factor)
        if match is None:
            return units  # not a simple product: show it unchanged
        name, power = match.group(1), int(match.group(2) or 1)
        side = numerator if power > 0 else denominator
        side.append(name + ("" if abs(power) == 1 else _superscript(abs(power))))
    top = " ".join(numerator) or "1"
    return top + ("/" + " ".join(denominator) if denominator else "")


def _superscript(n: int) -> str:
    return str(n).translate(str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹"))


def _label(long_name: str, symbol: str | None, units: str) -> str:
    """``long_name, symbol [units]`` with the parts that exist."""
    text = long_name + (f", {symbol}" if symbol else "")
    shown = units_text(units)
    return f"{text} [{shown}]" if shown else text


def angle_axis(name: str) -> bool:
    """Whether grid axis ``name`` is an angle or an angular velocity, shown in degrees
    (deg/s) with ``degrees=True``: the axes a run file accepts with ``units = "deg"``
    (`sweep.toml_spec`), the single pendulum's (`ANGLE_COORDS`, ``pivot_phase``) and a
    registered system's (``theta1_0`` [rad], ``omega1_0`` [rad/s], ...). An angular
    frequency (``forcing_frequency`` [rad/s]) is not an angle axis.

    Parameters
    ----------
    name : str
        A coordinate's name.

    Returns
    -------
    bool
    """
    if name in ANGLE_COORDS:
        return True
    from .physics.system import angle_parameter

    return angle_parameter(name) is not None


def degree_units(name: str, units: str) -> str | None:
    """The units of axis ``name`` in degrees (``"deg"``, ``"deg s-1"``, ``"deg/s"``) where
    it is an `angle_axis` in radians (``units`` ``"rad"``, ``"rad s-1"`` or ``"rad/s"``),
    else None: what `map`, ``sweep plot`` and the explorer's map convert by 180/pi."""
    if re.match(r"rad(?![A-Za-z])", units) and angle_axis(name):
        return "deg" + units[len("rad"):]
    return None


def _coordinate(da, name: str, degrees: bool) -> tuple[np.ndarray, str]:
    """Values and axis label of coordinate ``name`` (converted to degrees if asked and
    it is an `angle_axis` stored in rad or rad/s)."""
    coord = da[name]
    values = np.asarray(coord.values, dtype=np.float64)
    units = str(coord.attrs.get("units", ""))
    shown = degree_units(name, units) if degrees else None
    if shown is not None:
        values = np.rad2deg(values)
        units = shown
    long_name = str(coord.attrs.get("long_name", name))
    return values, _label(long_name, _SYMBOLS.get(name), units)


def _variable_label(da) -> str:
    """Colour-bar label of a data variable: long name and units, wrapped."""
    long_name = str(da.attrs.get("long_name", da.name if da.name is not None else "value"))
    return textwrap.fill(_label(long_name, None, str(da.attrs.get("units", ""))),
                         _LABEL_WIDTH)


def _scalar_coords_text(obj, names=None) -> str:
    """``"forcing_amplitude = 1.2 rad/s²"`` for the scalar numeric coordinates of
    ``obj`` (those in ``names`` when given), joined by commas."""
    parts = []
    for name, coord in obj.coords.items():
        if names is not None and name not in names:
            continue
        if coord.ndim == 0 and np.issubdtype(coord.dtype, np.number):
            shown = units_text(str(coord.attrs.get("units", "")))
            parts.append(f"{name} = {float(coord):.4g}" + (f" {shown}" if shown else ""))
    return ", ".join(parts)


# ------------------------------------------------------------------------- selection
def select(obj, **sel):
    """Select by nearest coordinate value, refusing names that are not dimensions.

    Parameters
    ----------
    obj : xarray.Dataset or xarray.DataArray
    **sel : float
        ``dim=value`` in the coordinate's stored units (radians for ``theta0``,
        rad/s for ``omega0``, ...); the nearest grid point is taken and the
        dimension dropped (kept as a scalar coordinate).

    Returns
    -------
    Same type as ``obj``.

    Raises
    ------
    ValueError
        On a name that is not a dimension of ``obj``, or a value that is NaN or
        infinite (the nearest point to it is no point in particular).
    TypeError
        On a value that is not a number.
    """
    dims = [d for d in obj.dims if d in obj.coords]
    for name, value in sel.items():
        if name not in dims:
            raise ValueError(f"cannot select {name!r}: not a dimension of the data; "
                             f"accepted: {', '.join(dims) or 'none'}")
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float,
                                                                         np.number)):
            raise TypeError(f"selection {name}={value!r}: accepted: a number "
                             f"({obj[name].attrs.get('units', 'coordinate units')})")
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an int beyond the float range
            finite = False
        if not finite:
            raise ValueError(f"selection {name}={value!r}: accepted: a finite number "
                             f"({obj[name].attrs.get('units', 'coordinate units')})")
        obj = obj.sel({name: float(value)}, method="nearest")
    return obj


# ------------------------------------------------------------------------------ maps
def _integer_levels(values: np.ndarray) -> np.ndarray | None:
    """Distinct levels of an integer-valued array, or None if it is not one."""
    finite = values[np.isfinite(values)]
    if finite.size == 0 or not np.all(finite == np.round(finite)):
        return None
    lo, hi = int(finite.min()), int(finite.max())
    if hi - lo + 1 > MAX_DISCRETE_LEVELS:
        return None
    if lo < 0 < hi:  # symmetric, so that 0 takes the middle colour of a diverging map
        m = max(-lo, hi)
        lo, hi = -m, m
    return np.arange(lo, hi + 1, dtype=np.float64)


def _colormap(name: str):
    """The matplotlib colormap called ``name``; ValueError naming ``cmap`` if none."""
    import matplotlib

    if not isinstance(name, str):
        return name  # already a Colormap
    try:
        return matplotlib.colormaps[name]
    except KeyError:
        raise ValueError(f"cmap {name!r} is not a matplotlib colormap; accepted: a name "
                         "such as viridis, magma, RdBu_r, twilight") from None


def _discrete(levels: np.ndarray, cmap_name: str):
    """Colormap and norm with one colour per level, boundaries half-way between."""
    from matplotlib.colors import BoundaryNorm

    levels = np.asarray(levels, dtype=np.float64)
    mids = 0.5 * (levels[1:] + levels[:-1])
    first = levels[0] - (mids[0] - levels[0] if mids.size else 0.5)
    last = levels[-1] + (levels[-1] - mids[-1] if mids.size else 0.5)
    bounds = np.concatenate(([first], mids, [last]))
    cmap = _colormap(cmap_name).resampled(levels.size)
    return cmap, BoundaryNorm(bounds, cmap.N)


def _flag_levels(da):
    """(levels, tick labels) of a CF flag variable (``flag_values``/``flag_meanings``)."""
    values = da.attrs.get("flag_values")
    meanings = da.attrs.get("flag_meanings")
    if values is None or meanings is None:
        return None
    values = np.atleast_1d(np.asarray(values, dtype=np.float64))
    meanings = str(meanings).split()
    if len(meanings) != values.size:
        return None
    order = np.argsort(values)
    return values[order], [meanings[k] for k in order]


def _as_2d(da):
    """``da`` with size-1 dimensions squeezed; ValueError unless two dimensions remain."""
    da = da.squeeze(drop=False)
    if da.ndim != 2:
        raise ValueError(
            f"map needs a 2-D variable; {da.name or 'the data'} has dimensions "
            f"({', '.join(da.dims)}); accepted: select all but two dimensions first "
            "(sweep.plot.select / --sel DIM=VALUE)"
        )
    return da.sortby(list(da.dims))


def map(da, ax=None, degrees=True, cmap=None, title=None):
    """Draw a 2-D DataArray as a colour map with labelled axes and colour bar.

    The first dimension runs along x and the second along y, so a ``theta0 x
    omega0`` map is a picture of the phase plane. Integer-valued data (winding
    numbers, well indices, labels) spanning at most `MAX_DISCRETE_LEVELS` (41)
    consecutive integers, from their smallest to their largest value, get one
    colour per integer and integer ticks, on a diverging colormap centred on 0 when
    they take both signs. Integer data spanning more (a forced map's winding from
    -27 to 27) are drawn like real-valued data: a continuous colormap, by default
    ``"viridis"`` whatever their signs. CF flag variables (``status``) get their flag
    meanings as tick labels.

    Parameters
    ----------
    da : xarray.DataArray
        Two dimensions after size-1 dimensions are dropped; dimension coordinates
        carry ``units`` and ``long_name`` (as `sweep.run` writes them). NaN cells
        are left blank.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in; a new figure is made when omitted.
    degrees : bool, default True
        Show ``theta0`` and ``forcing_phase`` in deg and ``omega0`` in deg/s
        (coordinates only; data values keep their own units).
    cmap : str or matplotlib.colors.Colormap, optional
        Matplotlib colormap (name). Default: ``"RdBu_r"`` for integer data of both
        signs spanning at most `MAX_DISCRETE_LEVELS` integers, ``"viridis"``
        otherwise.
    title : str, optional
        Axes title. Default: the variable name and any scalar coordinates.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        If ``da`` does not have exactly two dimensions of size > 1.

    Examples
    --------
    >>> fig = sweep.plot.map(ds.winding)                      # doctest: +SKIP
    >>> sweep.plot.save_figure(fig, "winding.png")            # doctest: +SKIP
    """
    import matplotlib.pyplot as plt

    da = _as_2d(da)
    xdim, ydim = da.dims
    x, xlabel = _coordinate(da, xdim, degrees)
    y, ylabel = _coordinate(da, ydim, degrees)
    values = np.ma.masked_invalid(np.asarray(da.transpose(ydim, xdim).values,
                                             dtype=np.float64))
    flags = _flag_levels(da)
    levels = flags[0] if flags else _integer_levels(values.filled(np.nan))
    ticklabels = flags[1] if flags else None
    if levels is not None:
        default = "RdBu_r" if levels[0] < 0 < levels[-1] else "viridis"
        colormap, norm = _discrete(levels, cmap or default)
        colors = {"cmap": colormap, "norm": norm}
    else:
        colors = {"cmap": _colormap(cmap or "viridis")}

    if ax is None:
        fig, ax = plt.subplots(figsize=(7.0, 5.4), layout="constrained")
    else:
        fig = ax.figure
    mesh = ax.pcolormesh(x, y, values, shading="nearest", **colors)
    bar = fig.colorbar(mesh, ax=ax)
    bar.set_label(_variable_label(da))
    if levels is not None:
        step = max(1, int(np.ceil(levels.size / 15)))
        bar.set_ticks(levels[::step])
        if ticklabels is not None:
            bar.set_ticklabels(ticklabels[::step])
        else:
            bar.set_ticklabels([f"{int(v):d}" for v in levels[::step]])
        bar.minorticks_off()

    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title is None:
        scalars = _scalar_coords_text(da)
        title = (str(da.name) if da.name is not None else "") + (
            f" ({scalars})" if scalars else "")
    ax.set_title(title)
    return fig


# ----------------------------------------------------------------------- trajectories
def _trajectories(ds, sel):
    """Select ``sel`` (nearest) and split what remains into single trajectories.

    Returns the selection and the list of one-trajectory datasets, and the names of
    the dimensions along which they differ.
    """
    if "time" not in ds.dims:
        raise ValueError(
            "trajectory needs a dataset with a 'time' dimension (sampled theta and omega); "
            "accepted: the output of a run with save_every set"
        )
    missing = [v for v in ("theta", "omega") if v not in ds.data_vars]
    if missing:
        system = ds.attrs.get("system_name")
        of = f" (this is a run of the system {system})" if system is not None else ""
        raise ValueError(f"trajectory needs the single pendulum's variables theta and "
                         f"omega; missing: {', '.join(missing)}{of}; accepted: the output "
                         "of a single-pendulum run (a [scene] run file, or sweep.Scene) "
                         "with save_every set")
    if "time" in sel:
        raise ValueError("cannot select 'time' for a trajectory; accepted: grid dimensions "
                         + ", ".join(d for d in ds.dims if d != "time"))
    picked = select(ds[["theta", "omega"]], **sel).squeeze(drop=False)
    others = [d for d in picked.theta.dims if d != "time"]
    shape = [picked.sizes[d] for d in others]
    count = int(np.prod(shape)) if others else 1
    if count > MAX_TRAJECTORIES:
        raise ValueError(
            f"{count} trajectories remain after selection; accepted: at most "
            f"{MAX_TRAJECTORIES}; select along {', '.join(others)} (dim=value)"
        )
    lines = [picked.isel(dict(zip(others, index))) for index in np.ndindex(*shape)]
    return picked, lines, others


def trajectory(ds, ax=None, **sel):
    """Draw theta(t) and the phase portrait (theta, omega) side by side.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset with a ``time`` dimension and the sampled ``theta`` [rad] and
        ``omega`` [rad/s] (a run with ``save_every``).
    ax : sequence of two matplotlib.axes.Axes, optional
        Axes for theta(t) and for the phase portrait; a new figure when omitted.
    **sel : float
        ``dim=value`` selections (nearest grid point, in the stored units: rad,
        rad/s, ...). At most `MAX_TRAJECTORIES` trajectories may remain; each is
        drawn as one line and labelled by its grid values.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        If ``ds`` has no ``time`` dimension, ``theta`` or ``omega``; on a bad
        selection; or if too many trajectories remain.

    Examples
    --------
    >>> fig = sweep.plot.trajectory(ds, theta0=-2.0, omega0=0.0)   # doctest: +SKIP
    """
    import matplotlib.pyplot as plt

    picked, lines, others = _trajectories(ds, sel)
    if ax is None:
        fig, ax = plt.subplots(1, 2, figsize=(11.0, 4.4), layout="constrained")
    else:
        if len(ax) != 2:
            raise ValueError(f"ax must be two Axes (theta(t), phase portrait), got {ax!r}")
        fig = ax[0].figure
    time_axis, phase_axis = ax
    t, time_label = _coordinate(ds, "time", degrees=False)
    for one in lines:
        label = _scalar_coords_text(one, others)
        time_axis.plot(t, one.theta.values, lw=1.2, label=label)
        phase_axis.plot(one.theta.values, one.omega.values, lw=1.0, label=label)
        phase_axis.plot(one.theta.values[:1], one.omega.values[:1], "o",
                        color=phase_axis.lines[-1].get_color(), ms=4)
    theta_label = _label(str(ds.theta.attrs.get("long_name", "theta")), _SYMBOLS["theta"],
                         str(ds.theta.attrs.get("units", "")))
    omega_label = _label(str(ds.omega.attrs.get("long_name", "omega")), _SYMBOLS["omega"],
                         str(ds.omega.attrs.get("units", "")))
    time_axis.set(xlabel=time_label, ylabel=theta_label, title="Angle against time")
    phase_axis.set(xlabel=theta_label, ylabel=omega_label,
                   title="Phase portrait (dot: initial state)")
    for axes in (time_axis, phase_axis):
        axes.grid(True, alpha=0.3)
    if others:
        time_axis.legend(fontsize="small")
    common = _scalar_coords_text(picked)
    if common:
        fig.suptitle(common)
    return fig


# ----------------------------------------------------------------------------- files
def basins(labels, ax=None, degrees=True, cmap="tab20", title=None):
    """Draw a basin map (integer attractor labels) with the attractors marked.

    Parameters
    ----------
    labels : xarray.DataArray, int
        From `sweep.maps.basins`: ``-1`` unresolved (drawn blank), ``0..m-1``
        attractor labels; attributes ``attractor_theta`` [rad] and optionally
        ``attractor_omega`` [rad/s] give one point of each attractor.
    ax : matplotlib.axes.Axes, optional
    degrees : bool, default True
        As in `map`.
    cmap : str, default "tab20"
        A qualitative colormap: neighbouring labels get distinct colours.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        The map; when its axes are ``theta0`` and ``omega0``, each attractor point
        that falls inside the window is marked with a white-edged star (angles
        reduced to the window modulo 2 pi).
    """
    masked = labels.where(labels >= 0)
    masked.attrs = dict(labels.attrs)
    masked.attrs.pop("flag_values", None)
    fig = map(masked, ax=ax, degrees=degrees, cmap=cmap, title=title)
    ax = fig.axes[0]
    dims = _as_2d(labels).dims
    if dims == ("theta0", "omega0") and "attractor_theta" in labels.attrs:
        theta = np.atleast_1d(np.asarray(labels.attrs["attractor_theta"], dtype=float))
        omega = np.atleast_1d(np.asarray(labels.attrs.get("attractor_omega",
                                                          np.zeros_like(theta)), dtype=float))
        lo, hi = float(labels.theta0.min()), float(labels.theta0.max())
        theta = lo + np.mod(theta - lo, 2 * np.pi)  # reduce into the window
        inside = (theta <= hi) & (omega >= float(labels.omega0.min())) & \
            (omega <= float(labels.omega0.max()))
        scale = 180 / np.pi if degrees else 1.0
        ax.plot(theta[inside] * scale, omega[inside] * scale, linestyle="none", marker="*",
                markersize=12, markerfacecolor="black", markeredgecolor="white",
                label="attractor")
        if inside.any():
            ax.legend(loc="upper right", fontsize="small")
    return fig


def orbit_diagram(ds, along="forcing_amplitude", variable="theta", ax=None, degrees=False,
                  title=None, markersize=0.6):
    """Draw an orbit (bifurcation) diagram: the stroboscopic samples against a grid axis.

    Every trajectory's stroboscopic samples (one per forcing period after the
    transient; ``sweep.run(..., observe=("strobe",), strobe_samples=N)``) are plotted
    as points above its value of ``along``: one point per value on a period-1 orbit,
    p points on a period-p orbit, a cloud where the motion is chaotic. Trajectories
    that differ in other grid axes (several starts) are all drawn, overplotted.

    Parameters
    ----------
    ds : xarray.Dataset
        A run observing ``strobe`` whose grid has the axis ``along``.
    along : str, default "forcing_amplitude"
        The grid axis on the horizontal axis.
    variable : {"theta", "omega"}
        The angle, wrapped to [-pi, pi) [rad] (or deg with ``degrees``), or the
        angular velocity [rad/s].
    ax : matplotlib.axes.Axes, optional
    degrees : bool, default False
        Angles (and an angle axis ``along``) in degrees.
    title : str, optional
    markersize : float, default 0.6
        Size of each point [pt]; > 0.

    Returns
    -------
    matplotlib.figure.Figure
        With one point per finite stroboscopic sample.

    Raises
    ------
    ValueError
        Without stroboscopic samples, for an ``along`` that is not a grid axis of
        ``ds`` (the message lists them), an unknown ``variable`` or a ``markersize``
        that is not a finite number > 0.
    """
    markersize = check_quantity("markersize", markersize, minimum=0.0, strict=True,
                                accepted="a finite number > 0 (points)")
    import matplotlib.pyplot as plt

    from .maps.labels import strobe_axes

    strobe_axes(ds, "an orbit diagram", along)
    if variable not in ("theta", "omega"):
        raise ValueError(f"variable must be 'theta' or 'omega', got {variable!r}")
    samples = ds[f"strobe_{variable}"]
    values = samples.values
    if variable == "theta":
        values = np.mod(values + np.pi, 2 * np.pi) - np.pi
        if degrees:
            values = np.degrees(values)
    x_values, xlabel = _coordinate(samples, along, degrees)
    x = np.broadcast_to(
        x_values.reshape([-1 if d == along else 1 for d in samples.dims]), values.shape)
    finite = np.isfinite(values)
    if ax is None:
        fig, ax = plt.subplots(figsize=(8.0, 5.0), layout="constrained")
    else:
        fig = ax.figure
    ax.plot(x[finite], values[finite], linestyle="none", marker=".", markersize=markersize,
            color="black", alpha=0.6)
    ax.set_xlabel(xlabel)
    if variable == "theta":
        ax.set_ylabel("theta at the strobe times, wrapped [" + ("deg" if degrees else "rad")
                      + "]")
    else:
        ax.set_ylabel("angular velocity at the strobe times [rad/s]")
    ax.set_title(title if title is not None else "orbit diagram")
    return fig


def period_map(periods, lyapunov=None, ax=None, degrees=True, threshold=0.0, title=None):
    """Draw a periodicity map: one colour per period, grey where none is found, and a
    chaos colour where the largest Lyapunov exponent is positive.

    Parameters
    ----------
    periods : xarray.DataArray, int
        From `sweep.maps.period` (two dimensions after size-1 ones are dropped).
    lyapunov : xarray.DataArray, optional
        ``lyapunov_max`` [1/s] of the same run (``observe=("strobe", "lyapunov")``):
        cells where it exceeds ``threshold`` are drawn as chaotic, whatever their
        period.
    ax : matplotlib.axes.Axes, optional
    degrees : bool, default True
        As in `map`.
    threshold : float, default 0
        Exponent [1/s] above which a cell counts as chaotic; a finite number >= 0
        (checked even without ``lyapunov``).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        The map; the colour bar names each category ("period 1", ..., "none",
        "chaotic").

    Raises
    ------
    ValueError
        For ``periods`` or ``lyapunov`` that are not 2-D maps of the same shape, or a
        ``threshold`` that is not a finite number >= 0.
    """
    threshold = check_quantity("threshold", threshold, minimum=0.0,
                               accepted="a finite number >= 0 (1/s: the Lyapunov exponent "
                                        "above which a cell counts as chaotic)")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap

    periods = _as_2d(periods)
    xdim, ydim = periods.dims
    codes = np.asarray(periods.transpose(ydim, xdim).values, dtype=np.int64)
    chaotic = np.zeros(codes.shape, dtype=bool)
    if lyapunov is not None:
        exponent = _as_2d(lyapunov).transpose(ydim, xdim).values
        if exponent.shape != codes.shape:
            raise ValueError(f"lyapunov has shape {exponent.shape}, the periods "
                             f"{codes.shape}; accepted: lyapunov_max of the same run")
        chaotic = np.asarray(exponent > threshold)
    found = sorted(int(p) for p in np.unique(codes[(codes > 0) & ~chaotic]))
    names = [f"period {p}" for p in found] + ["none"] + (["chaotic"] if chaotic.any() else [])
    index = np.full(codes.shape, len(found), dtype=np.int64)  # "none"
    for k, p in enumerate(found):
        index[(codes == p) & ~chaotic] = k
    index[chaotic] = len(found) + 1
    palette = _colormap("tab10")
    colours = [palette(k % 10) for k in range(len(found))] + ["#d9d9d9", "#000000"]
    cmap = ListedColormap(colours[:len(names)])
    norm = BoundaryNorm(np.arange(len(names) + 1) - 0.5, cmap.N)
    x, xlabel = _coordinate(periods, xdim, degrees)
    y, ylabel = _coordinate(periods, ydim, degrees)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7.0, 5.4), layout="constrained")
    else:
        fig = ax.figure
    mesh = ax.pcolormesh(x, y, index, shading="nearest", cmap=cmap, norm=norm)
    bar = fig.colorbar(mesh, ax=ax)
    bar.set_ticks(np.arange(len(names)))
    bar.set_ticklabels(names)
    bar.minorticks_off()
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title if title is not None else "period of the attractor")
    return fig


def _periods_text(fractions, attractor):
    """"period 1", or "periods 1, 2" for an attractor whose period changes."""
    if "attractor_period" not in fractions:
        return f"period {int(fractions['period'].sel(attractor=attractor))}"
    seen = []
    for p in fractions["attractor_period"].sel(attractor=attractor).values.tolist():
        if p > 0 and p not in seen:
            seen.append(p)
    if len(seen) == 1:
        return f"period {seen[0]}"
    return "periods " + ", ".join(str(p) for p in seen)


def basin_fractions(fractions, ax=None, title=None):
    """Draw the basin fractions of a continuation as stacked areas along its axis.

    Parameters
    ----------
    fractions : xarray.Dataset
        The second result of `sweep.maps.continuation`.
    ax : matplotlib.axes.Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        One area per attractor label (colour by label, ``tab10``, so a label keeps its
        colour in every figure), then the unresolved share in grey on top; the legend
        names each attractor with its period (its periods, in order of appearance,
        where it changes along the axis, e.g. through a period doubling).
    """
    import matplotlib.pyplot as plt

    along = fractions.attrs["along"]
    x, xlabel = _coordinate(fractions, along, False)
    palette = _colormap("tab10")
    layers = [fractions["fraction"].sel(attractor=a).values
              for a in fractions["attractor"].values]
    names = [f"attractor {a} ({_periods_text(fractions, a)})"
             for a in fractions["attractor"].values]
    colours = [palette(int(a) % 10) for a in fractions["attractor"].values]
    layers.append(fractions["unresolved"].values)
    names.append("unresolved")
    colours.append("#bdbdbd")
    if ax is None:
        fig, ax = plt.subplots(figsize=(7.5, 4.5), layout="constrained")
    else:
        fig = ax.figure
    ax.stackplot(x, *layers, labels=names, colors=colours)
    ax.set_xlim(float(x.min()), float(x.max()))
    ax.set_ylim(0.0, 1.0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("basin fraction")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.set_title(title if title is not None else f"attractors continued along {along}")
    return fig


def save_figure(fig, path, dpi=150):
    """Write ``fig`` to ``path`` atomically and close it.

    The image goes to a temporary file in the same folder, then is renamed over
    ``path``: an interrupted save leaves any previous file intact.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        Output file; its suffix picks the format (``.png`` when it has none).
        The folder must exist.
    dpi : float, default 150
        Resolution in dots per inch; a finite number > 0.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        If the folder does not exist or is not writable, the suffix is not a format
        matplotlib writes, or ``dpi`` is not a finite number > 0 (checked before the
        path; the figure is closed in every case).
    """
    import matplotlib.pyplot as plt

    from .io import check_output_path

    try:
        dpi = check_quantity("dpi", dpi, minimum=0.0, strict=True,
                             accepted="a finite number > 0 (dots per inch)")
        path = check_output_path(path)
        fmt = path.suffix.lstrip(".").lower() or "png"
        supported = fig.canvas.get_supported_filetypes()
        if fmt not in supported:
            raise ValueError(f"output path {str(path)!r}: unknown image format {fmt!r}; "
                             f"accepted: {', '.join(sorted(supported))}")
        # a name of our own (not mkstemp) so the file gets the usual permissions
        tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.part")
        try:
            fig.savefig(tmp, format=fmt, dpi=dpi)
            os.replace(tmp, path)
        except BaseException:
            if tmp.exists():
                tmp.unlink()
            raise
    finally:
        plt.close(fig)
    return Path(path)


# ----------------------------------------------------------------------------- accuracy
def work_precision(wp, ax=None, x="wall_time", y="error_max", title=None):
    """Work-precision diagram: error against cost, log-log, one line per method.

    In the convention of the SciML work-precision diagrams: error on the vertical axis,
    cost (wall time by default) on the horizontal one; lower left is better.

    Parameters
    ----------
    wp : xarray.Dataset
        From `sweep.accuracy.work_precision` (dimensions ``integrator`` x ``level``).
    ax : matplotlib Axes, optional
    x : {"wall_time", "time_per_million", "rhs_evaluations"}
        Cost on the horizontal axis.
    y : {"error_max", "error_rms"}
    title : str, optional
        Default: the scene's model and ``t_end``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    for name in (x, y):
        if name not in wp:
            raise ValueError(f"{name!r} is not a variable of the work-precision dataset; "
                             f"accepted: {', '.join(sorted(wp.data_vars))}")
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    else:
        fig = ax.figure
    markers = "osD^v<>phX*"
    for k, method in enumerate(wp.integrator.values):
        row = wp.isel(integrator=k)
        cost, err = row[x].values, row[y].values
        keep = np.isfinite(cost) & np.isfinite(err) & (err > 0)
        order = ""
        if "observed_order" in row and np.isfinite(row.observed_order.values):
            order = f" (order {float(row.observed_order):.2f})"
        ax.loglog(cost[keep], err[keep], marker=markers[k % len(markers)],
                  label=f"{method}{order}")
    ax.set_xlabel(_label(wp[x].attrs.get("long_name", x), None, wp[x].attrs.get("units", "")))
    ax.set_ylabel(_label(wp[y].attrs.get("long_name", y), None, wp[y].attrs.get("units", "")))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title if title is not None else
                 f"{wp.attrs.get('model', '')} pendulum, t_end = {wp.attrs.get('t_end', '')} s, "
                 f"{wp.attrs.get('n_trajectories', '')} trajectories", fontsize="medium")
    return fig


__all__ += ["work_precision"]


def map_accuracy(accuracy, ax=None, x="wall_time", title=None):
    """A map's work-precision diagram: the fraction of labels that differ from the
    most accurate run against cost, log-log, one line per ladder.

    Parameters
    ----------
    accuracy : sweep.map_precision.MapAccuracy or xarray.Dataset
        From `sweep.map_accuracy` (or its ``.dataset``, e.g. loaded from its netCDF).
    ax : matplotlib Axes, optional
    x : {"wall_time", "trajectory_steps"}
        Cost on the horizontal axis.
    title : str, optional
        Default: the labelling and the number of starts.

    Returns
    -------
    matplotlib.figure.Figure
        Each ladder's levels (value beside each point), with their standard errors as
        bars where the starts are sampled; levels whose labels all agree with the
        reference (0 on a log axis) are left out. The reference run is a dotted vertical
        line at its cost.
    """
    import matplotlib.pyplot as plt

    ds = getattr(accuracy, "dataset", accuracy)
    if not hasattr(ds, "data_vars") or "differing" not in ds or "setting" not in ds.coords:
        raise ValueError(f"accuracy must be what sweep.map_accuracy returns (or its "
                         f".dataset), got {type(accuracy).__name__}")
    costs = ("wall_time", "trajectory_steps")
    if x not in costs:
        raise ValueError(f"x must be one of {', '.join(repr(c) for c in costs)}, got {x!r}")
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    else:
        fig = ax.figure
    markers = "osD^v<>phX*"
    settings = [s for s in dict.fromkeys(ds.setting.values.tolist()) if s != "reference"]
    for k, setting in enumerate(settings):
        rows = np.flatnonzero(ds.setting.values == setting)
        cost = ds[x].values[rows].astype(float)
        err = ds.differing.values[rows].astype(float)
        bars = ds.differing_error.values[rows].astype(float)
        keep = np.isfinite(cost) & (cost > 0) & (err > 0)
        if not keep.any():
            continue
        line = ax.errorbar(cost[keep], err[keep],
                           yerr=None if np.isnan(bars[keep]).all() else bars[keep],
                           marker=markers[k % len(markers)], capsize=2, label=setting)
        for c, e, text in zip(cost[keep], err[keep], ds.value.values[rows][keep]):
            ax.annotate(str(text), (c, e), textcoords="offset points", xytext=(4, 4),
                        fontsize="x-small", color=line[0].get_color())
    ax.set_xscale("log")
    ax.set_yscale("log")
    reference = int(np.flatnonzero(ds.setting.values == "reference")[-1])
    ref_cost = float(ds[x].values[reference])
    if np.isfinite(ref_cost) and ref_cost > 0:
        ax.axvline(ref_cost, linestyle=":", color="0.4", label="reference run")
    ax.set_xlabel(_label(ds[x].attrs.get("long_name", x), None, ds[x].attrs.get("units", "")))
    ax.set_ylabel("fraction of labels differing from the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title if title is not None else
                 f"{ds.attrs.get('labelling', 'labels')} of {ds.attrs.get('starts', '')} "
                 "starts against the most accurate run", fontsize="medium")
    return fig


__all__ += ["map_accuracy"]
