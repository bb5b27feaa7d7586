"""Adaptive boundary refinement of a 2-D map: the labels of a whole grid, computing only
the trajectories its boundaries need (issue 27).

`refine` runs the Mariani-Silver subdivision of `sweep.maps._quadtree` (its module
docstring states the rule and what it guarantees) with one `sweep.run` of `sweep.Points`
per level, and keeps the labels consistent from level to level: a per-trajectory map
(`motion`, `well`, `period`, `inverted`, a variable) labels each trajectory on its own;
`basins` numbers its labels over the whole map, so `refine` labels each level's
trajectories by what they settle on (the well, or the forced attractor matched to the
attractors met so far) and numbers the labels at the end exactly as `basins` numbers
those of the full run.
"""

from __future__ import annotations

import functools
import inspect

import numpy as np
import xarray as xr

from .. import engine
from .._validate import check_count
from ..engine import INITIAL_AXES
from ..grid import Grid, Points
from ..observables import DEFAULT_OBSERVE, OBSERVABLES, resolve
from ..physics import Scene
from ..physics.scene import check_pendulum_scene
from ._quadtree import check_step, refine_field
from .known import (
    BACKGROUND_FACTORS,
    background,
    fixed_axes,
    seed_attractors,
    settled,
    upsample,
)
from .known import known_map as _known_map
from .labels import (
    UNRESOLVED,
    _orbit,
    _same_orbit,
    attractor_catalogue,
    basins,
    check_max_period,
    check_tolerance,
    identify_attractors,
    well,
)
from .pilot import pilot_catalogue

__all__ = ["refine"]

#: `sweep.run` arguments refine refuses: it runs one sweep per level, and a checkpoint
#: belongs to one sweep.
_REFUSED = ("checkpoint", "resume", "keep_checkpoint", "save_every")


class _Codes:
    """Integer codes for label values (NaN its own value), stable across levels."""

    def __init__(self):
        self.codes = {}

    def encode(self, values: np.ndarray) -> np.ndarray:
        values = np.asarray(values).ravel()
        out = np.empty(values.size, dtype=np.int64)
        missing = np.isnan(values) if values.dtype.kind == "f" else np.zeros(values.size, bool)
        if missing.any():
            out[missing] = self.codes.setdefault("nan", len(self.codes))
        present = ~missing
        found, inverse = np.unique(values[present], return_inverse=True)
        lookup = np.array([self.codes.setdefault(v.item(), len(self.codes)) for v in found],
                          dtype=np.int64)
        out[present] = lookup[inverse.ravel()]
        return out

    def decode(self, codes: np.ndarray, dtype) -> np.ndarray:
        lookup = np.zeros(max(len(self.codes), 1), dtype=dtype)
        for value, code in self.codes.items():
            lookup[code] = np.nan if value == "nan" else value
        return lookup[codes]


class _ForcedAttractors:
    """The forced attractors met so far, each a stroboscopic ring: a level's attractors
    are matched to them (period, turns per period and orbit points within 10 ``tol``,
    the identity test of `identify_attractors`) or added."""

    def __init__(self, max_period: int, tol: float):
        self.max_period, self.tol = max_period, tol
        self.theta, self.omega, self.period, self.turns = [], [], [], []

    def index(self, theta, omega, period: int, turns: float) -> int:
        orbit = _orbit(theta, omega, period)
        for k, (t, w, p, n) in enumerate(zip(self.theta, self.omega, self.period,
                                              self.turns)):
            if p == period and abs(n - turns) < 1e-9 \
                    and _same_orbit(_orbit(t, w, p), orbit, 10 * self.tol):
                return k
        self.theta.append(theta)
        self.omega.append(omega)
        self.period.append(period)
        self.turns.append(turns)
        return len(self.theta) - 1

    def keys(self, ds: xr.Dataset, tol: float | None = None) -> np.ndarray:
        """Per trajectory of ``ds`` (one run), the index of its attractor among those
        met so far; -1 unresolved. ``tol``: `basins`' tolerance for this run (default
        the matching's own; `sweep.map_accuracy` varies it from run to run)."""
        tol = self.tol if tol is None else tol
        labels = basins(ds, max_period=self.max_period, tol=tol)
        flat = labels.values.ravel().astype(np.int64)
        periods = np.asarray(labels.attrs["attractor_period"], dtype=np.int64)
        if periods.size == 0:
            return flat  # all unresolved
        rings = attractor_catalogue(ds, labels, max_period=self.max_period, tol=tol)
        turns = labels.attrs["attractor_turns_per_period"]
        found = np.array([self.index(rings["theta"][a], rings["omega"][a], int(periods[a]),
                                     float(turns[a]) * periods[a])
                          for a in range(periods.size)] + [UNRESOLVED], dtype=np.int64)
        return found[flat]  # flat == -1 picks the appended UNRESOLVED

    def labels(self, keys: np.ndarray):
        """`basins`' labels and attributes for a map of attractor indices: the rings,
        weighted by their cells, identified together, as `basins` identifies a run with
        an attractor catalogue (labels by decreasing basin size)."""
        counts = np.bincount(keys[keys >= 0], minlength=len(self.theta))
        used = np.flatnonzero(counts)
        out = np.full(keys.shape, UNRESOLVED, dtype=np.int32)
        if used.size == 0:
            empty = np.zeros(0)
            return out, {"theta": empty, "omega": empty, "period": empty.astype(int),
                         "turns_per_period": empty, "size": empty.astype(int)}
        part, catalogue = identify_attractors(
            np.stack([self.theta[k] for k in used]), np.stack([self.omega[k] for k in used]),
            max_period=self.max_period, tol=self.tol, weights=counts[used])
        label_of = np.full(len(self.theta) + 1, UNRESOLVED, dtype=np.int32)
        label_of[used] = part
        return label_of[keys], catalogue  # keys == -1 picks the last entry


def _label_function(label):
    """``(function, keyword arguments)`` of a map function or a `functools.partial` of
    one; None for a variable name."""
    if isinstance(label, str):
        return None
    if isinstance(label, functools.partial):
        if label.args:
            raise ValueError(f"label = {label!r} fixes positional arguments; accepted: a "
                             "map function, or functools.partial(map, **options)")
        return label.func, dict(label.keywords)
    if callable(label):
        return label, {}
    raise ValueError(
        f"label must be a map function or the name of a data variable, got {label!r} "
        f"({type(label).__name__}); accepted: sweep.maps.basins, motion, well, period, "
        "inverted (or functools.partial of one with its options), any callable Dataset -> "
        "DataArray that labels each trajectory on its own, or a variable name such as "
        "'well'")


def _variables(run_kwargs: dict) -> list[str]:
    """The variables a run with these arguments stores."""
    names = [v[0] for name in resolve(run_kwargs.get("observe", DEFAULT_OBSERVE))
             for v in OBSERVABLES[name].variables]
    names.append("status")
    if run_kwargs.get("attractors") is not None:
        names.append("attractor")
    return names


def _check_known_cells(known_cells, scene, grid, func, pilot, run_kwargs) -> bool:
    """``known_cells`` as a bool; with True, what it needs (forced basins of theta0 x
    omega0 on evenly spaced axes, stop_early and a catalogue)."""
    if not isinstance(known_cells, (bool, np.bool_)):
        raise ValueError(f"known_cells must be True or False, got {known_cells!r}")
    if not known_cells:
        return False
    accepted = ("accepted: known_cells=True with label=sweep.maps.basins of a forced "
                "scene over theta0 x omega0 (evenly spaced), stop_early=True and a "
                "catalogue (pilot=N or attractors=...), or known_cells=False")
    if func is not basins or scene.forcing is None:
        raise ValueError(f"known_cells=True stops trajectories on cells of known forced "
                         f"basins; got label={func.__name__ if func else None!r} and a "
                         f"scene {'without' if scene.forcing is None else 'with'} "
                         f"forcing; {accepted}")
    if set(d for d in grid.dims if grid.varies(d)) != set(INITIAL_AXES):
        raise ValueError(f"known_cells=True needs a map over theta0 and omega0; got "
                         f"{[d for d in grid.dims if grid.varies(d)]}; {accepted}")
    for name in INITIAL_AXES:
        values = np.asarray(grid.axes[name], dtype=np.float64)
        gaps = np.diff(values)
        if np.max(np.abs(gaps - gaps.mean())) > 1e-6 * abs(gaps.mean()):
            raise ValueError(f"known_cells=True needs evenly spaced axes; {name} has gaps "
                             f"from {gaps.min()!r} to {gaps.max()!r}; {accepted}")
    if run_kwargs.get("stop_early") is not True:
        raise ValueError(f"known_cells=True needs stop_early=True, got stop_early="
                         f"{run_kwargs.get('stop_early')!r}; {accepted}")
    if "strobe" not in resolve(run_kwargs.get("observe", DEFAULT_OBSERVE)):
        raise ValueError(f"known_cells=True labels forced basins from stroboscopic "
                         f"samples; observe={run_kwargs.get('observe', DEFAULT_OBSERVE)!r} "
                         f"lacks 'strobe'; {accepted}")
    if run_kwargs.get("attractors") is None and (
            pilot is None or not set(grid.dims) <= set(INITIAL_AXES)):
        raise ValueError(f"known_cells=True needs an attractor catalogue: attractors=..., "
                         f"or pilot=N on a grid of theta0 and omega0 only (got pilot="
                         f"{pilot!r}, axes {list(grid.dims)}); {accepted}")
    if "known_cells" in run_kwargs:
        raise ValueError("known_cells is refine's own option (a bool): refine makes the "
                         "map of known cells itself; accepted: known_cells=True or False")
    return True


def check_levels_arguments(who: str, pilot, run_kwargs: dict):
    """``pilot`` (None or an int >= 2) and the `sweep.run` arguments of a function that
    runs one sweep per level (`refine`, `sweep.map_accuracy`): none of `_REFUSED`.

    Returns
    -------
    int or None
        ``pilot``, checked.

    Raises
    ------
    ValueError
        Naming ``who``, the argument and what is accepted.
    """
    if pilot is not None:
        pilot = check_count("pilot", pilot, minimum=2,
                            accepted="None or an int >= 2 (points per initial-condition "
                                     "axis)")
    for name in _REFUSED:
        if run_kwargs.get(name):
            raise ValueError(f"{who} runs one sweep per level and cannot use {name} = "
                             f"{run_kwargs[name]!r}; accepted: sweep.run arguments "
                             f"without {', '.join(_REFUSED)}")
    return pilot


def check_label_options(label, func, options: dict) -> None:
    """The options of a labelling ``label`` (``func`` with ``options``, e.g. a
    ``functools.partial`` of a map) checked before anything runs: they must be the
    map's own keywords, and `basins`' ``max_period`` and ``tol`` in range.

    Raises
    ------
    ValueError
        Naming the label, the bad option and what is accepted.
    """
    try:  # the options must be the map's own keywords
        inspect.signature(func).bind(None, **options)
    except TypeError as error:
        raise ValueError(f"label = {label!r}: {error}; accepted: the map's own keyword "
                         "options") from None
    except ValueError:  # no signature (a builtin): called as given
        pass
    if func is basins:
        check_max_period(options.get("max_period", 8))
        check_tolerance(options.get("tol", 1e-3))


def _check(scene, grid, label, step, pilot, run_kwargs):
    """Every argument refine can check before computing anything; returns them checked,
    with the grid's two varying axes."""
    check_pendulum_scene("sweep.maps.refine", scene)
    varying = [d for d in grid.dims if grid.varies(d)] if isinstance(grid, Grid) else []
    if len(varying) != 2:
        got = (f"a grid of shape {dict(zip(grid.dims, grid.shape))}"
               if isinstance(grid, Grid) else type(grid).__name__)
        raise ValueError(f"refine needs a sweep.Grid with exactly two axes of more than one "
                         f"value (a 2-D map; other axes may hold one value each), got {got}; "
                         "accepted: e.g. Grid(theta0=..., omega0=...) (for more axes, "
                         "refine each 2-D slice in a loop)")
    step = check_step(step)
    pilot = check_levels_arguments("refine", pilot, run_kwargs)
    function = _label_function(label)
    if function is None:
        known = _variables(run_kwargs)
        if label not in known:
            raise ValueError(f"label = {label!r} is not a variable of this run; accepted: "
                             f"{', '.join(repr(k) for k in known)} (the variables of "
                             "observe=...), or a map function")
        return step, pilot, None, {}, varying
    func, options = function
    check_label_options(label, func, options)
    return step, pilot, func, options, varying


def refine(scene: Scene, grid: Grid, label=basins, *, step: int = 16,
           pilot: int | None = 41, known_cells: bool = False, **run_kwargs) -> xr.DataArray:
    """The labels of a 2-D map, computing only the trajectories its boundaries need.

    The grid's cells on lattice lines every ``step`` cells (and its last row and column)
    are run first; a block of cells whose whole perimeter has one label is filled with
    it, any other is split in four by its middle row and column, whose cells are run
    next (one `sweep.run` of `sweep.Points` per level). A boundary that crosses a
    block's perimeter is always seen; an island of another label lying entirely inside
    a block whose perimeter agrees is not (see `sweep.maps._quadtree`).

    Parameters
    ----------
    scene : Scene
    grid : Grid
        Exactly two axes of more than one value (any two: ``theta0`` and ``omega0``,
        ``torque`` and ``damping``, ...; n0 x n1 cells, in grid order); any other axis
        holds one value.
    label : callable or str, default `sweep.maps.basins`
        ``maps.basins``, ``maps.motion``, ``maps.well``, ``maps.period``,
        ``maps.inverted``; one with options as ``functools.partial(maps.basins,
        rest_position=True)``; any callable ``Dataset -> DataArray`` that labels each
        trajectory on its own (its label must not depend on the other trajectories);
        or the name of a data variable of the run (``"well"`` with ``capture``).
    step : int, default 16
        Cells between lattice lines, >= 2. The lattice costs about ``2 / step`` of the
        cells; an island narrower than about ``step`` inside a block whose perimeter
        agrees can be missed.
    pilot : int or None, default 41
        Forced `basins` run with ``stop_early=True`` and no ``attractors``: the
        attractors are first catalogued by a pilot of ``pilot`` x ``pilot`` starts
        (`sweep.maps.pilot_catalogue`) and every level stops on them (grids of
        ``theta0`` and ``omega0`` only: a catalogue holds one scene's attractors).
        None: no pilot. Ignored otherwise.
    known_cells : bool, default False
        Forced `basins` over theta0 x omega0 (evenly spaced) with ``stop_early`` and a
        catalogue: a trajectory stops once its stroboscopic points fall in known cells
        of one attractor `sweep.observables.KNOWN_HITS` periods running, fewer deep
        inside a region of one label (`sweep.run`'s ``known_cells``). Known are,
        frozen while a level runs: the settled cells (`sweep.maps.known.settled`: 8
        neighbours of one label) of coarse maps of the whole window run first
        (`sweep.maps.known.background`) and of the cells earlier levels decided, and
        the cells of the catalogued attractors. The labels then do not depend on
        threads, blocks, chunks or Dask; they may differ from the full run's near
        fractal boundaries (measured in the refine guide: on the 1200 x 1200 Wada map,
        696 of 1.44 M differ, refine's own filled islands, as without known cells).
    **run_kwargs
        `sweep.run` arguments (``t_end``, ``dt``, ``observe``, ``stop_early``,
        ``attractors``, ``device``, ...), the same for every level; ``progress``
        defaults to False. Not ``checkpoint``, ``resume``, ``keep_checkpoint`` or
        ``save_every``.

    Returns
    -------
    xarray.DataArray, the grid's dims and shape
        What ``label(sweep.run(scene, grid, **run_kwargs))`` returns (name, dtype,
        coordinates with their attributes, attributes; for forced `basins` the
        catalogue's ``attractor_theta``/``attractor_omega`` may be another point of
        the same orbit), where every filled cell has its block's label, with:

        - coordinate ``computed`` (bool, the grid's dims): True where the trajectory
          was run, False where its label was filled in;
        - attributes ``refine_step`` (the step), ``cells_computed`` (trajectories run,
          the pilot's not counted), ``cells_total`` (n0 n1), ``cells_per_level``
          (trajectories run at each level; level 0: the lattice), ``blocks_filled``,
          ``pilot_cells`` (the pilot's trajectories, 0 without one); with
          ``known_cells``: ``cells_stopped_known`` (the map's trajectories that stopped
          on known cells) and ``background_cells`` (the coarse maps' trajectories).

    Raises
    ------
    ValueError
        Before anything is run: a grid without exactly two axes of more than one
        value, a step that is not an int >= 2, a label that is neither callable nor a
        variable of the run, options the label does not take, a refused run argument;
        then whatever `sweep.run` and the label raise on a probe of one trajectory (the
        grid's first cell), before the lattice.

    Examples
    --------
    >>> import numpy as np, sweep
    >>> from sweep import maps
    >>> scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.25),))
    >>> grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 129),
    ...                   omega0=np.linspace(-12, 12, 129))
    >>> wells = maps.refine(scene, grid, maps.well, t_end=40.0, dt=0.02,
    ...                     observe=("capture",), stop_early=True)
    >>> wells.attrs["cells_computed"] < grid.size
    True
    """
    step, pilot, func, options, (first, second) = _check(scene, grid, label, step, pilot,
                                                          run_kwargs)
    known_cells = _check_known_cells(known_cells, scene, grid, func, pilot, run_kwargs)
    kwargs = dict(run_kwargs)
    kwargs.setdefault("progress", False)
    dims = grid.dims
    shape = (grid.axes[first].size, grid.axes[second].size)

    def run(rows, cols, known=None):
        columns = {d: float(values[0]) for d, values in grid.axes.items()}  # one value
        columns[first], columns[second] = grid.axes[first][rows], grid.axes[second][cols]
        return engine.run(scene, Points(**columns), **kwargs,
                          **({} if known is None else {"known_cells": known}))

    def labelled(ds):
        return ds[label] if func is None else func(ds, **options)

    probe = run(np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64))
    template = labelled(probe)
    forced = func is basins and "strobe_theta" in probe
    if not isinstance(template, xr.DataArray) or template.dims != ("point",):
        raise ValueError(f"label = {label!r} gives {type(template).__name__} "
                         f"{getattr(template, 'dims', '')} for a run of points; accepted: "
                         "a map that labels each trajectory (one value per point)")
    pilot_cells = 0
    if forced and pilot is not None and kwargs.get("stop_early") \
            and kwargs.get("attractors") is None and {first, second} <= set(INITIAL_AXES) \
            and set(dims) <= set(INITIAL_AXES):
        kwargs["attractors"] = pilot_catalogue(scene, grid, pilot, **kwargs)
        pilot_cells = min(pilot, shape[0]) * min(pilot, shape[1])

    codes = _Codes()
    if forced:
        attractors = _ForcedAttractors(options.get("max_period", 8), options.get("tol", 1e-3))
        keys = attractors.keys
    elif func is basins:  # unforced: the well, as basins reads it
        def keys(ds):
            index = well(ds)
            if options.get("rest_position"):
                index = xr.where(index.notnull(), 0.0, np.nan)
            return codes.encode(index.values)
    else:
        def keys(ds):
            return codes.encode(labelled(ds).values)

    if known_cells:
        found, known_attrs = _refine_known(scene, grid, run, keys, step, kwargs,
                                           flip=first != "theta0", shape=shape)
    else:
        found, known_attrs = refine_field(shape, lambda rows, cols: keys(run(rows, cols)),
                                          step), {}
    # the coordinates' attributes as the label passes them on (xr.where drops them)
    coords = {d: xr.Variable(d, grid.axes[d], attrs=(template.coords[d] if d in
                                                      template.coords else probe[d]).attrs)
              for d in dims}
    attrs = dict(template.attrs)  # the label's, with a basins catalogue of the whole map
    if forced:
        values, catalogue = attractors.labels(found.labels.reshape(grid.shape))
        attrs.update({f"attractor_{k}": catalogue[k] for k in
                      ("theta", "omega", "period", "turns_per_period", "size")})
    elif func is basins:
        index = codes.decode(found.labels, np.float64).reshape(grid.shape)
        finite = np.isfinite(index)
        wells = np.unique(index[finite])
        values = np.full(index.shape, UNRESOLVED, dtype=np.int32)
        values[finite] = np.searchsorted(wells, index[finite])
        attrs["attractor_theta"] = (2 * np.pi * wells).astype(np.float64)
    else:
        values = codes.decode(found.labels, template.dtype).reshape(grid.shape)
    out = xr.DataArray(values, coords=coords, dims=dims, name=template.name, attrs=attrs)
    out = out.assign_coords(computed=(dims, found.computed.reshape(grid.shape)))
    out["computed"].attrs = {"long_name": "trajectory run (True) or label filled in from "
                                          "its block's perimeter (False)"}
    out.attrs.update({"refine_step": step, "cells_computed": found.cells_computed,
                      "cells_total": int(grid.size),
                      "cells_per_level": np.array(found.cells_per_level, dtype=np.int64),
                      "blocks_filled": found.blocks_filled, "pilot_cells": pilot_cells})
    out.attrs.update(known_attrs)
    return out


def _refine_known(scene, grid: Grid, run, keys, step: int, kwargs: dict, *, flip: bool,
                  shape: tuple[int, int]):
    """`refine_field` whose levels stop on known cells (``known_cells=True``): the
    background's settled cells and seeds, unknown where a cell the levels so far
    decided disagrees with it, overridden by the settled cells among those decided,
    then the catalogued attractors' cells (`sweep.maps.known`). Returns the refinement
    and refine's known-cells attributes."""
    catalogue = kwargs["attractors"]  # flip: the field's rows are omega0, the map's theta0
    theta, omega = (np.asarray(grid.axes[name], dtype=np.float64) for name in INITIAL_AXES)
    others = {k: v for k, v in kwargs.items() if k != "attractors"}
    # every background level, the 1/2 map too (`HALF_BELOW` is measured for the
    # map without refine's filled blocks: at 1200 x 1200 refine then labels 1228
    # starts differently from the full run, against 696 with it)
    back, back_cells = background(scene, theta, omega, catalogue,
                                  factors=BACKGROUND_FACTORS, fixed=fixed_axes(grid),
                                  **others)
    base = upsample(back, theta, omega) if back is not None else \
        np.full((theta.size, omega.size), -1, dtype=np.int32)
    lookup = {}  # the field's key -> catalogue index, from the cells run so far
    stopped = [0]

    def compute(rows, cols, state):
        index = np.full(state.labels.shape, -1, dtype=np.int64)
        if lookup:
            table = np.full(max(lookup) + 2, -1, dtype=np.int64)
            table[list(lookup)] = list(lookup.values())
            index[state.decided] = table[state.labels[state.decided]]  # -1 -> last
        fine = settled(np.where(state.decided, index, -2))
        known = np.array(base.T if flip else base)
        known[state.decided & (index != known)] = -1  # the background is wrong there
        known = np.where(fine >= 0, fine, known)
        known = seed_attractors(known.T if flip else known, theta, omega, catalogue)
        ds = run(rows, cols, _known_map(known, theta, omega))
        stopped[0] += int(ds.attrs["cells_stopped_known"])
        found = keys(ds)
        matched = np.isfinite(ds["attractor"].values) & (ds["attractor"].values >= 0)
        for key, a in zip(found[matched].tolist(),
                          ds["attractor"].values[matched].astype(np.int64).tolist()):
            lookup.setdefault(key, a)
        return found

    found = refine_field(shape, compute, step, with_state=True)
    return found, {"cells_stopped_known": stopped[0], "background_cells": back_cells}
