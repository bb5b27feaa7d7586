"""What a map's accuracy costs: the labels of a map's starts under a ladder of settings,
against its most accurate run (issue 36, item 1).

`sweep.accuracy.work_precision` measures a trajectory's error against its cost. A map
is read through labels (a basin, a well, rotation or libration, a period), and a label
changes only where a trajectory's error carries it across a basin boundary: near a
fractal boundary the share of starts within ``delta`` of it scales as ``delta^alpha``,
the uncertainty exponent (Grebogi, McDonald, Ott, Yorke, Phys. Lett. A 99, 415
(1983)), so a map's label error follows its trajectories' error to the power alpha.
`map_accuracy` measures it: every setting of a ladder (``dt`` halvings, ``t_end``
doublings, the labelling's tolerance, float32 against float64, the method) is run on
the same starts, and each run's labels are compared start by start with those of the
most accurate run.

Labels must mean the same thing in every run. A per-trajectory labelling (`motion`,
`well`, `period`, a variable) does; `basins` numbers its labels per run, so its labels
are made comparable as `sweep.maps.refine` makes its levels' labels comparable: the
unforced pendulum's by the well each start settles in, the forced pendulum's by
matching each run's attractors (stroboscopic rings) to those met so far (period, turns
per period and orbit points within 10 ``tol``; the reference run comes first, so its
numbering is kept).
"""

from __future__ import annotations

import functools
import inspect
import json
import math
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from . import engine
from ._validate import check_count, check_real
from .catalogue_drives import pendulum_drives
from .grid import Grid, Points
from .kernels.spec import DTYPES
from .maps.fractions import _table, _unresolved_code
from .maps.labels import UNRESOLVED, basins, well
from .maps.pilot import pilot_catalogue
from .maps.refine import (
    _ForcedAttractors,
    _label_function,
    _variables,
    check_label_options,
    check_levels_arguments,
)
from .physics import Scene
from .physics.scene import check_pendulum_scene
from .settings import validate_method
from .strobe_phase import phase_mismatch

__all__ = ["LADDER_KEYS", "MapAccuracy", "map_accuracy"]

#: The settings a ladder may vary, and which way each grows more accurate:
#: "down" (smaller is more accurate), "up" (larger), or None (the user's order).
LADDER_KEYS = {"dt": "down", "t_end": "up", "t_transient": "up", "tol": "down",
               "rtol": "down", "dtype": None, "method": None}

#: The ``setting`` of the reference level (every ladder at its most accurate value).
REFERENCE = "reference"


# --------------------------------------------------------------------------- checks
def _check_ladder(ladder) -> dict:
    """``ladder`` as ``{key: tuple of values}``, each checked; ValueError/TypeError
    naming the key, the value and what is accepted."""
    accepted_keys = ", ".join(repr(k) for k in LADDER_KEYS)
    if not isinstance(ladder, dict) or not ladder:
        raise ValueError(f"ladder must be a non-empty dict of setting -> values (least to "
                         f"most accurate), got {ladder!r}; accepted keys: {accepted_keys}")
    checked = {}
    for key, values in ladder.items():
        if key not in LADDER_KEYS:
            raise ValueError(f"ladder: unknown setting {key!r}; accepted: {accepted_keys}")
        if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
            raise ValueError(f"ladder[{key!r}] must be a sequence of at least two values, "
                             f"least to most accurate, got {values!r}")
        values = tuple(values)
        if len(values) < 2:
            raise ValueError(f"ladder[{key!r}] must hold at least two values, least to most "
                             f"accurate (the last is the reference), got {values!r}")
        if key == "dtype":
            for v in values:
                if v not in DTYPES:
                    raise ValueError(f"ladder['dtype']: {v!r} is not a dtype; accepted: "
                                     f"{', '.join(map(repr, DTYPES))}")
        elif key == "method":
            values = tuple(validate_method(v) for v in values)
        else:
            minimum, strict, what = {
                "dt": (0.0, True, "a finite number > 0 (s)"),
                "t_end": (None, False, "a finite number (s)"),
                "t_transient": (0.0, False, "a finite number >= 0 (s)"),
                "tol": (0.0, True, "a finite number > 0 (rad and rad/s)"),
                "rtol": (0.0, True, "a finite number > 0"),
            }[key]
            values = tuple(check_real(f"ladder[{key!r}]", v, minimum=minimum, strict=strict,
                                      accepted=what) for v in values)
            grows = LADDER_KEYS[key]
            steps = np.diff(values)
            if not ((steps < 0).all() if grows == "down" else (steps > 0).all()):
                order = "decreasing" if grows == "down" else "increasing"
                raise ValueError(f"ladder[{key!r}] must be strictly {order} (least to most "
                                 f"accurate: the last is the reference), got {values!r}")
        names = [getattr(v, "name", v) for v in values]
        if len(set(names)) != len(names):
            raise ValueError(f"ladder[{key!r}] repeats a value: {names!r}; accepted: "
                             "distinct values, least to most accurate")
        checked[key] = values
    return checked


def _check_label(label, run_kwargs):
    """``(function or None, options)`` of a labelling (`refine`'s rules)."""
    found = _label_function(label)
    if found is None:
        known = _variables(run_kwargs)
        if label not in known:
            raise ValueError(f"label = {label!r} is not a variable of this run; accepted: "
                             f"{', '.join(repr(k) for k in known)} (the variables of "
                             "observe=...), or a map function")
        return None, {}
    func, options = found
    check_label_options(label, func, options)
    return func, options


def _takes_tol(func) -> bool:
    try:
        return "tol" in inspect.signature(func).parameters
    except (TypeError, ValueError):
        return False


def _levels(ladder: dict, run_kwargs: dict, options: dict):
    """``[(setting, value, run kwargs, label options)]``: every ladder's values but its
    last, the others at their most accurate; then the reference (all at the last)."""
    reference = dict(run_kwargs)
    ref_options = dict(options)
    for key, values in ladder.items():
        if key == "tol":
            ref_options["tol"] = values[-1]
        else:
            reference[key] = values[-1]
    levels = []
    for key, values in ladder.items():
        for value in values[:-1]:
            kwargs, opts = dict(reference), dict(ref_options)
            if key == "tol":
                opts["tol"] = value
            else:
                kwargs[key] = value
            levels.append((key, value, kwargs, opts))
    levels.append((REFERENCE, None, reference, ref_options))
    return levels


def _value_text(value) -> str:
    if value is None:
        return ""
    if hasattr(value, "name"):
        return str(value.name)
    return f"{value:.6g}" if isinstance(value, float) else str(value)


# -------------------------------------------------------------------------- labels
class _Labeller:
    """Per run, each start's label in a numbering shared by every run (float64; the
    unresolved value and NaN mean no label)."""

    def __init__(self, label, func, options, forced: bool, match_tol: float):
        self.label, self.func, self.options, self.forced = label, func, options, forced
        self.wells = func is basins and not forced
        if forced:
            self.attractors = _ForcedAttractors(options.get("max_period", 8), match_tol)
        self.unresolved = None

    def __call__(self, ds, dims, options) -> np.ndarray:
        if self.forced:
            keys = self.attractors.keys(ds.transpose(*dims, ...),
                                        tol=options.get("tol", 1e-3))
            self.unresolved = UNRESOLVED
            return keys.astype(np.float64)
        if self.wells:  # the well each start settles in, as basins reads it
            index = well(ds)
            if options.get("rest_position"):
                index = xr.where(index.notnull(), 0.0, np.nan)
            return index.transpose(*dims).values.ravel().astype(np.float64)
        labels = ds[self.label] if self.func is None else self.func(ds, **options)
        if not isinstance(labels, xr.DataArray) or set(labels.dims) != set(dims):
            raise ValueError(f"label = {self.label!r} gives {type(labels).__name__} "
                             f"{getattr(labels, 'dims', '')}; accepted: a map that labels "
                             "each trajectory (one value per start)")
        if labels.dtype.kind not in "biuf":
            raise ValueError(f"label = {self.label!r} gives labels of dtype {labels.dtype}; "
                             "accepted: numbers (int, float or bool labels)")
        code = _unresolved_code(labels, None)
        self.unresolved = None if code is None else float(code)
        return labels.transpose(*dims).values.ravel().astype(np.float64)

    def finish(self, values: np.ndarray) -> tuple[np.ndarray, float | None]:
        """All runs' labels (levels x starts) in their final numbering, and the value
        that means no label (NaN always does)."""
        if not self.wells:
            return values, self.unresolved
        # wells: numbered as basins numbers them, over the wells any run found
        finite = np.isfinite(values)
        wells = np.unique(values[finite])
        out = np.full(values.shape, float(UNRESOLVED))
        out[finite] = np.searchsorted(wells, values[finite])
        return out, float(UNRESOLVED)


def _same(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Element-wise equality with NaN equal to NaN."""
    return (a == b) | (np.isnan(a) & np.isnan(b))


# -------------------------------------------------------------------------- result
@dataclass(frozen=True)
class MapAccuracy:
    """Outcome of `map_accuracy`.

    Attributes
    ----------
    dataset : xarray.Dataset
        Dimensions ``level`` (each ladder's values but its last, then the reference),
        ``label`` (every label any run gave; ``unresolved`` flags the no-label ones) and
        ``start``. Level coordinates: ``setting`` (the ladder key, or ``"reference"``),
        ``value`` (its value, as text) and the level's own ``dt`` [s], ``t_end`` [s],
        ``t_transient`` [s], ``method``, ``dtype``, ``tol`` [rad and rad/s] and ``rtol``
        (NaN where not used). Variables: ``differing`` (fraction of starts whose label
        differs from the reference's) with ``differing_error`` (its binomial standard
        error ``sqrt(p (1 - p) / n)`` for sampled starts, `sweep.Points`; NaN for a
        `sweep.Grid`, whose cells are not a random sample), ``fraction`` and
        ``fraction_error`` (level x label; binomial, NaN for a grid), ``fraction_shift``
        (fraction minus the reference's) with ``fraction_shift_error`` (the standard
        error of a paired difference; NaN for a grid), ``max_shift`` (largest
        ``|fraction_shift|`` of a resolved label), ``unresolved_fraction``,
        ``wall_time`` [s] (best of ``repeats``, compilation excluded) and
        ``trajectory_steps`` (steps of all trajectories; with ``stop_early``, the most
        they could take), and ``labels`` (level x start).
    """

    dataset: xr.Dataset

    def table(self):
        """One row per level: setting, value, ``differing`` +- ``differing_error``,
        ``max_shift``, ``unresolved_fraction``, ``wall_time`` [s] and
        ``trajectory_steps`` (a pandas DataFrame)."""
        import pandas as pd

        ds = self.dataset
        return pd.DataFrame({
            "setting": ds.setting.values, "value": ds.value.values,
            "differing": ds.differing.values, "differing_error": ds.differing_error.values,
            "max_shift": ds.max_shift.values,
            "unresolved": ds.unresolved_fraction.values,
            "wall_time_s": ds.wall_time.values,
            "trajectory_steps": ds.trajectory_steps.values,
        }).set_index(["setting", "value"])

    def rate(self, setting: str = "dt") -> float:
        """Least-squares slope of log(``differing``) against log(value) over the levels
        of a numeric ``setting`` whose labels differ somewhere (NaN with fewer than two
        such levels): the order at which the map's label error falls with it."""
        ds = self.dataset
        known = [s for s in dict.fromkeys(ds.setting.values.tolist()) if s != REFERENCE]
        if setting not in known or setting not in ("dt", "t_end", "t_transient", "tol",
                                                   "rtol"):
            raise ValueError(f"rate: setting = {setting!r} is not a numeric ladder of this "
                             f"table; accepted: "
                             f"{', '.join(repr(s) for s in known if s not in ('dtype', 'method'))}")
        rows = np.flatnonzero(ds.setting.values == setting)
        x = ds[setting].values[rows].astype(float)
        y = ds.differing.values[rows].astype(float)
        keep = np.isfinite(y) & (y > 0) & (x > 0)
        if keep.sum() < 2:
            return math.nan
        return float(np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0])

    def save(self, path):
        """Write `dataset` to netCDF atomically (`sweep.io.save`); return the path."""
        from .io import save

        return save(self.dataset, path)


# ------------------------------------------------------------------------- compute
def map_accuracy(scene: Scene, starts, label=basins, ladder=None, *, repeats: int = 1,
                 pilot: int | None = 41, **run_kwargs) -> MapAccuracy:
    """How many of a map's labels each setting of a ladder changes, and what it costs.

    Every level of ``ladder`` runs the same starts; each start's label is compared with
    its label in the most accurate run (every ladder at its last value).

    Parameters
    ----------
    scene : Scene
    starts : Points or Grid
        The starts: `sweep.sample` points (a table costs seconds at a few thousand
        starts, and the fractions get binomial standard errors), or a grid.
    label : callable or str, default `sweep.maps.basins`
        ``maps.basins``, ``maps.well``, ``maps.motion``, ``maps.period``,
        ``maps.inverted``, ``functools.partial`` of one with its options, any callable
        ``Dataset -> DataArray`` that labels each trajectory on its own, or the name of
        a variable of the run.
    ladder : dict
        Setting -> values, least to most accurate (the last value is that setting's
        reference): ``dt`` [s] (strictly decreasing, e.g. halvings), ``t_end`` [s] and
        ``t_transient`` [s] (strictly increasing, e.g. doublings), ``tol`` (the
        labelling's tolerance [rad and rad/s], `basins`' and `period`'s; decreasing),
        ``rtol`` (adaptive methods; decreasing), ``dtype`` (e.g. ``["float32",
        "float64"]``) and ``method`` (e.g. ``["heun", "rk4"]``). Each level varies one
        setting; the others stay at their reference. A ladder's values replace
        ``run_kwargs``' value of that setting.
    repeats : int, default 1
        Wall time is the best of this many runs of each level, after its kernel is
        compiled (`sweep.engine.warm_up`).
    pilot : int or None, default 41
        Forced `basins` with ``stop_early=True`` and no ``attractors``: the attractors
        are first catalogued by a ``pilot`` x ``pilot`` pilot at the reference settings
        (`sweep.maps.pilot_catalogue`), and every level stops on that one catalogue
        (but a level whose first stroboscopic sample, ``t0 + t_transient`` on a step,
        falls at another drive phase, `sweep.strobe_phase`, runs without it; a
        level whose attractors lie further than `sweep.observables.ATTRACTOR_TOL` from
        it stops by the ``strobe`` test instead: the same labels, later). None: no pilot.
    **run_kwargs
        `sweep.run` arguments common to every level (``t_end``, ``dt``, ``observe``,
        ``stop_early``, ``device``, ...); not ``checkpoint``, ``resume``,
        ``keep_checkpoint`` or ``save_every``. ``progress`` defaults to False.

    Returns
    -------
    MapAccuracy
        ``.dataset`` (the table, the fractions per label and every start's label per
        level), ``.table()`` (a DataFrame), ``.rate(setting)`` and ``.save(path)``.

    Raises
    ------
    ValueError, TypeError
        Before anything runs: a bad scene, starts, label, ladder, ``repeats`` or
        ``pilot``, a refused run argument, or any level's run arguments that
        `sweep.run` would refuse (`sweep.engine.prepare` checks each level in full);
        then what the labelling raises on the reference run, the first one run (a map
        that needs a variable the run does not observe).

    Examples
    --------
    >>> import numpy as np, sweep
    >>> from sweep import maps
    >>> scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.3),))
    >>> starts = sweep.sample(512, seed=1, theta0=(-np.pi, np.pi), omega0=(-10, 10))
    >>> acc = sweep.map_accuracy(scene, starts, maps.well, {"dt": [0.2, 0.1, 0.05]},
    ...                          t_end=40.0, observe=("capture",))
    >>> acc.table()  # doctest: +SKIP
    """
    check_pendulum_scene("map_accuracy", scene)
    if not isinstance(starts, (Grid, Points)):
        raise ValueError(f"starts must be sweep.Points (e.g. sweep.sample(...)) or a "
                         f"sweep.Grid, got {type(starts).__name__}")
    ladder = _check_ladder(ladder)
    repeats = check_count("repeats", repeats, accepted="an int >= 1 (timed runs per level)")
    pilot = check_levels_arguments("map_accuracy", pilot, run_kwargs)
    for name in ("t_end", "dt"):
        if name not in run_kwargs and name not in ladder:
            raise ValueError(f"map_accuracy needs {name}: accepted: {name}=... (a sweep.run "
                             f"argument) or a ladder of it, ladder={{{name!r}: [...]}}")
    run_kwargs.setdefault("progress", False)
    func, options = _check_label(label, run_kwargs)
    if "tol" in ladder and (func is None or not _takes_tol(func)):
        raise ValueError(f"ladder['tol'] varies the labelling's tolerance, but label = "
                         f"{label!r} takes no tol; accepted: a labelling with a tol option "
                         "(maps.basins, maps.period), or no 'tol' ladder")
    if func is not None and _takes_tol(func) and "tol" not in options:
        default = inspect.signature(func).parameters["tol"].default
        if isinstance(default, float):  # recorded per level (the table's tol column)
            options = dict(options, tol=default)
    levels = _levels(ladder, run_kwargs, options)
    plans = [engine.prepare(scene, starts, **kwargs) for _, _, kwargs, _ in levels]

    reference_kwargs = levels[-1][2]
    forced = func is basins and "strobe_theta" in _variables(reference_kwargs)
    if forced and pilot is not None and reference_kwargs.get("stop_early") \
            and reference_kwargs.get("attractors") is None \
            and set(starts.dims) <= {"point", *engine.INITIAL_AXES} \
            and not any(starts.varies(a) for a in starts.axes
                        if a not in engine.INITIAL_AXES):
        catalogue = pilot_catalogue(scene, starts, pilot, **reference_kwargs)
        frequency, phase = engine.forcing_drive(scene, starts)
        for (_, _, kwargs, _), plan in zip(levels, plans):
            # a level of another t_transient or dt may sample another drive phase, where
            # no start could match the catalogue (sweep.run refuses it): no catalogue
            if phase_mismatch(catalogue, len(catalogue["period"]), frequency, plan[0],
                              "forcing_frequency", phase=phase,
                              others=pendulum_drives(scene, starts)) is None:
                kwargs["attractors"] = catalogue
    labeller = _Labeller(label, func, options, forced,
                         levels[-1][3].get("tol", options.get("tol", 1e-3)))

    n = starts.size
    dims = starts.dims
    order = [len(levels) - 1, *range(len(levels) - 1)]  # the reference first
    values = np.empty((len(levels), n))
    wall = np.empty(len(levels))
    steps = np.empty(len(levels))
    for k in order:
        _, _, kwargs, opts = levels[k]
        engine.warm_up(scene, starts, **{a: b for a, b in kwargs.items() if a != "client"})
        best = math.inf
        for _ in range(repeats):
            began = time.perf_counter()
            ds = engine.run(scene, starts, **kwargs)
            best = min(best, time.perf_counter() - began)
        wall[k] = best
        settings = plans[k][0]
        if settings.integrator.adaptive:
            steps[k] = float((ds.steps_accepted + ds.steps_rejected).sum())
        else:
            steps[k] = float(n) * settings.n_steps
        values[k] = labeller(ds, dims, opts)
    values, unresolved = labeller.finish(values)
    return MapAccuracy(_dataset(scene, starts, label, levels, plans, values, unresolved,
                                wall, steps, repeats))


def _label_name(label) -> str:
    if isinstance(label, str):
        return label
    func = label.func if isinstance(label, functools.partial) else label
    return getattr(func, "__name__", repr(func))


def _dataset(scene, starts, label, levels, plans, values, unresolved, wall, steps,
             repeats) -> xr.Dataset:
    n = values.shape[1]
    sampled = isinstance(starts, Points)
    ref = values[-1]
    differs = ~_same(values, ref[None, :])
    differing = differs.mean(axis=1)
    root_n = math.sqrt(n)
    differing_error = np.sqrt(differing * (1 - differing)) / root_n if sampled else \
        np.full(differing.shape, np.nan)
    codes, _ = _table(values)
    member = np.stack([_same(values, c) for c in codes], axis=-1)  # level x start x label
    fraction = member.mean(axis=1)
    fraction_error = np.sqrt(fraction * (1 - fraction)) / root_n if sampled else \
        np.full(fraction.shape, np.nan)  # a grid: as `sweep.maps.fractions`
    into = (member & ~member[-1][None]).mean(axis=1)  # label here, not in the reference
    out_of = (~member & member[-1][None]).mean(axis=1)
    shift = fraction - fraction[-1]
    shift_error = np.sqrt(np.maximum(into + out_of - (into - out_of) ** 2, 0.0)) / root_n \
        if sampled else np.full(shift.shape, np.nan)
    flagged = np.isnan(codes)
    if unresolved is not None:
        flagged |= codes == unresolved
    resolved = ~flagged
    unresolved_fraction = member[..., flagged].any(axis=-1).mean(axis=1)

    dt = np.array([plan[0].dt for plan in plans])
    t_end = np.array([plan[0].t_end for plan in plans])
    t_transient = np.array([plan[0].t_transient for plan in plans])
    rtol = np.array([np.nan if plan[0].rtol is None else plan[0].rtol for plan in plans],
                    dtype=float)
    lv = ("level",)
    coords = {
        "level": np.arange(len(levels)),
        "setting": (lv, np.array([s for s, _, _, _ in levels], dtype=str),
                    {"long_name": "the ladder's setting this level varies"}),
        "value": (lv, np.array([_value_text(v) for _, v, _, _ in levels], dtype=str),
                  {"long_name": "its value (the reference: every ladder's last)"}),
        "dt": (lv, dt, {"units": "s", "long_name": "step (largest step, adaptive)"}),
        "t_end": (lv, t_end, {"units": "s", "long_name": "final time"}),
        "t_transient": (lv, t_transient, {"units": "s", "long_name": "transient"}),
        "method": (lv, np.array([plan[0].method for plan in plans], dtype=str)),
        "dtype": (lv, np.array([kwargs.get("dtype", "float64") for _, _, kwargs, _ in
                                levels], dtype=str)),
        "tol": (lv, np.array([opts.get("tol", np.nan) for *_, opts in levels], dtype=float),
                {"units": "rad and rad/s",
                                       "long_name": "the labelling's tolerance"}),
        "rtol": (lv, rtol, {"long_name": "relative tolerance (adaptive)"}),
        "label": ("label", codes, {"long_name": "label (one numbering for every level)"}),
        "unresolved": ("label", flagged, {"long_name": "the label means no label"}),
    }
    for name, column in starts.axes.items():
        if isinstance(starts, Points):
            coords[name] = ("start", np.asarray(column, dtype=float))
    se_note = ("binomial sqrt(p (1 - p) / n)" if sampled else
               "NaN: the starts are a grid, not a random sample")
    data = {
        "differing": (lv, differing, {"units": "1", "long_name": "fraction of starts "
                                      "whose label differs from the reference's"}),
        "differing_error": (lv, differing_error, {"units": "1", "long_name":
                                                  f"standard error of differing: {se_note}"}),
        "fraction": (("level", "label"), fraction, {"units": "1",
                                                    "long_name": "fraction of the starts"}),
        "fraction_error": (("level", "label"), fraction_error, {
            "units": "1", "long_name": f"standard error of the fraction: {se_note}"}),
        "fraction_shift": (("level", "label"), shift, {"units": "1", "long_name":
                                              "fraction minus the reference's"}),
        "fraction_shift_error": (("level", "label"), shift_error, {
            "units": "1", "long_name": "standard error of the shift (paired starts: "
                                       "sqrt(p_in + p_out - (p_in - p_out)^2) / sqrt(n); "
                                       "NaN for a grid)"}),
        "max_shift": (lv, np.abs(shift[:, resolved]).max(axis=1) if resolved.any() else
                      np.zeros(len(levels)), {"units": "1", "long_name":
                                              "largest |shift| of a resolved label"}),
        "unresolved_fraction": (lv, unresolved_fraction, {
            "units": "1", "long_name": "fraction of starts with no label"}),
        "wall_time": (lv, wall, {"units": "s", "long_name": f"wall time of the run, best "
                                 f"of {repeats}, compilation excluded"}),
        "trajectory_steps": (lv, steps, {"units": "1", "long_name": "steps of all "
                                         "trajectories (stop_early: the most they take)"}),
        "labels": (("level", "start"), values, {"long_name": "each start's label"}),
    }
    return xr.Dataset(data, coords=coords, attrs={
        "scene": json.dumps(scene.to_dict(), sort_keys=True), "labelling": _label_name(label),
        "starts": n, "sampled": int(sampled), "repeats": repeats,
        "start_axes": " ".join(starts.axes),
        "grid_shape": " ".join(str(s) for s in starts.shape),
        "reference_level": len(levels) - 1})
