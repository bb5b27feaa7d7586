"""The explorer's model: what the browser shows, as plain Python (no Panel, no Bokeh).

A `State` says everything a map depends on: the scene (model and parameter values), the
two axes shown and their window, the quantity, the run settings and the resolution.
`Explorer` turns user input into states through sweep's own validators (a refused value
raises `InvalidInput`, naming the control, and nothing is computed), keeps the history of
views, and computes a state's map (`Explorer.compute`: state -> grid -> `sweep.run` ->
`sweep.maps` -> image) in bands of rows, checking a `CancelToken` between bands, so that
a newer request (`Requests`) stops an older one within one band. It also writes the
Python snippet and the TOML run file that reproduce a map or one trajectory, and the
exports (netCDF with `sweep.save`'s attributes, PNG, run file) as bytes.

Nothing typed is executed: every value is a number or a choice from a fixed list, and
goes through `sweep.Scene`, `sweep.Grid` and `sweep.io.layout` (the checks `sweep.run`
makes) before any compute.

Beside it, each with one job: `sweep.explore.quantities` (the maps a scene offers),
`sweep.explore.requests` (the newest request wins), `sweep.explore.legend` (a discrete
map's words) and `sweep.explore.texts` (numbers and grids as exact Python and TOML text).
"""

from __future__ import annotations

import dataclasses
import io as _stdio
import math
import os
import re
import tempfile
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import io as sweep_io
from .. import maps
from .._validate import check_count
from ..diskspace import layout as run_layout
from ..engine import run as sweep_run
from ..grid import Grid
from ..kernels import Status
from ..maps.known import KNOWN_MIN_POINTS
from ..methods import METHODS
from ..observables import STROBE_SAMPLES_RANGE
from ..physics import BASE_PARAMETERS, EFFECTS, MODELS, Scene, parameters
from ..toml_periods import run_lines
from .legend import MOTION_TEXT, label_summary, legend_of
from .quantities import QUANTITIES, Quantity, default_quantity, effect_names, forced
from .requests import Cancelled, CancelToken, Requests
from .texts import grid_lines, grid_text, number_text, toml_value

__all__ = ["AXES_INITIAL", "CancelToken", "Cancelled", "Control", "Explorer", "InvalidInput",
           "MapResult", "QUANTITIES", "Quantity", "Requests", "State", "Trajectory", "View",
           "label_summary"]

#: The initial-state axes (always offered as map axes).
AXES_INITIAL = ("theta0", "omega0")

#: Points per axis of the pilot run that catalogues a forced map's attractors
#: (`sweep.maps.pilot_catalogue`, as ``sweep run --pilot 41``).
PILOT_POINTS = 41

#: The preview's resolution is the map's divided by this (per axis): 1/16 of the work.
PREVIEW_FACTOR = 4

#: Smallest number of trajectories per band of the final map: each band is one
#: `sweep.run` call (~5 ms of overhead each, measured on 400 x 400 damped wells), and a
#: cancel lands between bands.
BAND_MIN = 16_384

#: Bands a final map is cut into at most (a cancel waits for at most 1/BANDS of a map).
BANDS = 8

#: Seconds of computation one band aims at when the preview measured the map's cost
#: (`Explorer.stages`): a cheap map is one run (each band costs a `sweep.run` call:
#: 8 bands of a 400 x 400 damped-well map took 32 ms against 13 ms in one run, Zen 5),
#: an expensive one up to `BANDS` bands, so that a newer zoom waits at most about this.
#: Each band is a run with its own start-up and its own slowest trajectory: the forced
#: 400 x 400 Wada window (known cells) reached the page in 1.02 s (1.50) with 0.25 s
#: bands and 0.85 s (1.36) with 0.5 s bands, its first step at 0.22 against 0.29 s
#: (`benchmarks/explore.py`, AMD EPYC Zen 5, quiet, 2026-11-27).
BAND_SECONDS = 0.5

#: Seconds of final map (estimated from the preview's cost per start, its run's fixed
#: cost included: a 400 x 400 damped-well map is estimated at 0.08-0.15 s and takes
#: 0.01-0.05 s) below which the preview is not shown: the final picture follows within
#: about this, and each picture costs the browser a redraw (30-60 ms in headless
#: chromium on 2 shared cores) that would delay the final one.
PREVIEW_AFTER = 0.2

#: Seconds between two progressive steps shown while a final map computes: a step
#: (the rows computed so far, each missing row drawn as its nearest computed one) is
#: shown after 1, 2, 4, ... bands only when at least this long passed since the last
#: picture, so a map that is ready sooner is shown once, final.
STEP_SECONDS = 0.15

#: Resolution limits (pixels per axis): a 2000 x 2000 map is 4 M trajectories.
RESOLUTION_RANGE = (8, 2000)

#: Final maps kept for back/forward (each holds its dataset: a 400 x 400 forced map
#: with 16 stroboscopic samples is ~45 MB).
CACHE_SIZE = 3

#: Samples of theta(t) kept for the trajectory panel (save_every is chosen to stay under).
TRAJECTORY_SAMPLES = 4000

#: One computation at a time in this process, whichever session asks: the computations
#: would share the cores anyway, and `sweep.maps`' period finder is a numba parallel
#: loop, which numba's workqueue layer refuses to run from two threads at once.
COMPUTE_LOCK = threading.RLock()

#: `sweep.run` keywords the explorer takes from ``run_kwargs`` and passes on unchanged.
PASSTHROUGH = ("t0", "rtol", "atol", "dtype", "check_stability", "strobe_samples")

#: Smallest resolution [pixels per axis] at which the explorer stops on known cells
#: (`sweep.maps.known.KNOWN_MIN_POINTS`, measured: below it the background's settled
#: cells are too coarse).
KNOWN_MIN_RESOLUTION = KNOWN_MIN_POINTS

#: The forced basins' routes (`State.known_cells`): stop on known cells, or the
#: catalogue alone.
ROUTES = ("known cells", "exact")

#: `sweep.run` keywords the explorer sets itself (per quantity, per view) and ignores.
SET_BY_EXPLORER = ("observe", "stop_early", "attractors", "known_cells", "progress",
                   "chunk_size",
                   "save_every", "checkpoint", "resume", "keep_checkpoint", "client",
                   "estimate_error", "specialize")


class InvalidInput(ValueError):
    """A value sweep's validators refuse; ``control`` names the control it came from.

    Attributes
    ----------
    control : str
        The control (``"damping"``, ``"dt"``, ``"view"``, ...) the message belongs to.
    """

    def __init__(self, control: str, message: str) -> None:
        super().__init__(message)
        self.control = control


# ------------------------------------------------------------------------ state
@dataclass(frozen=True)
class View:
    """The window shown: axes and their ranges (in the axes' units: rad, rad/s, ...)."""

    x: str
    y: str
    x_range: tuple[float, float]
    y_range: tuple[float, float]


@dataclass(frozen=True)
class State:
    """Everything a map depends on (hashable: results are cached by state).

    Attributes
    ----------
    scene : Scene
        Model and parameter values (an axis's value here is unused).
    view : View
    quantity : str
        A key of `QUANTITIES`.
    t_end, dt, t_transient : float
        As `sweep.run` [s].
    method : str
    resolution : int
        Pixels (trajectories) per axis of the final map.
    start : tuple of (str, float)
        ``theta0`` [rad] and ``omega0`` [rad/s] of the start where they are not axes.
    extra : tuple of (str, value)
        `PASSTHROUGH` keywords of `sweep.run`.
    device : str
    known_cells : bool, default True
        Forced basins over the initial state: stop a trajectory on the known cells of a
        background map of the home window (`Explorer.known`; `sweep.run`'s
        ``known_cells``) where the run allows it (`Explorer.uses_known`); False: the
        exact route (the catalogue alone).
    catalogue : bool, default True
        A driven system's basins over its initial state (`sweep.explore.systems.
        SystemExplorer`): stop each start on a pilot's attractor catalogue (the
        catalogue route); False: the exact route (every start's strobe run to
        ``t_end``, then `sweep.maps.basins`). The single pendulum's explorer ignores it.
    """

    scene: Scene
    view: View
    quantity: str
    t_end: float
    dt: float
    t_transient: float = 0.0
    method: str = "rk4"
    resolution: int = 400
    start: tuple = (("theta0", 0.0), ("omega0", 0.0))
    extra: tuple = ()
    device: str = "cpu"
    known_cells: bool = True
    catalogue: bool = True


def centres(lo: float, hi: float, n: int) -> np.ndarray:
    """Pixel centres of ``n`` pixels covering ``[lo, hi]``: ``np.linspace`` of the first
    and last centre (so a run file's ``{start, stop, num}`` gives the same floats)."""
    step = (hi - lo) / n
    return np.linspace(lo + 0.5 * step, hi - 0.5 * step, n)


# ------------------------------------------------------------------------ controls
@dataclass(frozen=True)
class Control:
    """One input of the control panel, written from the declarations.

    Attributes
    ----------
    name : str
        Key for `Explorer.update` / `Explorer.set_parameter` (a grid axis name for a
        parameter).
    label : str
        ``"damping c [1/s]"``.
    kind : {"float", "int", "choice"}
    value : float, int or str
    choices : tuple of str
    minimum : float, optional
    strict : bool
    help : str
        Long name and what is accepted.
    group : str
        ``"scene"``, ``"run"`` or ``"map"``.
    """

    name: str
    label: str
    kind: str
    value: Any
    choices: tuple = ()
    minimum: float | None = None
    strict: bool = False
    help: str = ""
    group: str = "scene"


# ------------------------------------------------------------------------ results
@dataclass
class MapResult:
    """A computed map.

    Attributes
    ----------
    state : State
    preview : bool
        The coarse preview (resolution / `PREVIEW_FACTOR`), not the final map.
    x, y : ndarray
        Pixel centres along the view's axes.
    values : ndarray, shape (ny, nx)
        The map's values (labels for a discrete map; NaN where there is none).
    image : ndarray, shape (ny, nx), float64
        What is drawn: for a discrete map the index into `legend`, else `values`.
    legend : list of (value, str)
        Discrete maps: each value shown, with its meaning (image index i is
        ``legend[i]``).
    title : str
        Colour bar title: name and units (``"lyapunov_max [1/s]"``).
    description : str
        The map's long name (short: a label).
    comment : str
        The map's CF ``comment``: its full meaning where the long name is a short label
        (the ``attractor`` variable's, `sweep.observables.COMMENTS`); "" without one.
        The page shows both below the map (`caption`).
    da : xarray.DataArray
        The map (2-D, dims (y, x)).
    ds : xarray.Dataset or None
        The run (final maps only).
    seconds : float
        Wall time of this stage (pilot included).
    catalogue : dict or None
        The pilot's attractor catalogue (forced basins).
    stage : {"preview", "step", "final"}
        The coarse preview, a progressive step of the final map (full resolution, only
        the rows of the bands computed so far; the others repeat their nearest computed
        row) or the final map. `preview` is True for the first two.
    done : float
        Share of the final map's starts computed for this picture (1.0 for the final
        map, the preview's own share for the preview).
    run_seconds : float
        Wall time of the `sweep.run` calls alone [s] (no pilot, no labelling).
    numbers : ViewNumbers or None
        The view's numbers (`Explorer.numbers`), once computed.
    preview_seconds : float
        A final map's: wall time of the preview `Explorer.stages` computed before it
        (shown or not) [s]; 0 when none was (a cached map).
    summary : str
        Basins and period maps: what the labels found, in words (`label_summary`: the
        attractors or periods and the unresolved starts), for the page's status line;
        "" for other maps.
    """

    state: State
    preview: bool
    x: np.ndarray
    y: np.ndarray
    values: np.ndarray
    image: np.ndarray
    legend: list
    title: str
    description: str
    da: Any
    ds: Any
    seconds: float
    catalogue: dict | None = None
    route: str = ""
    stage: str = "final"
    done: float = 1.0
    run_seconds: float = 0.0
    numbers: Any = None
    preview_seconds: float = 0.0
    summary: str = ""
    comment: str = ""

    @property
    def caption(self) -> str:
        """The text below the map (Markdown): the long name in italics and, where the
        map has a CF ``comment``, that comment on a line of its own."""
        text = f"*{_markdown(self.description)}*"
        return text + (f"\n\n{_markdown(self.comment)}" if self.comment else "")


def _markdown(text: str) -> str:
    """``text`` with Markdown's emphasis, code and link characters escaped, so that it
    shows as written (``attractors_*`` is not the start of an emphasis)."""
    return re.sub(r"([\\`*_\[\]<>])", r"\\\1", str(text))


@dataclass
class Trajectory:
    """One start's trajectory.

    Attributes
    ----------
    theta0, omega0 : float
        The start [rad, rad/s] (for parameter axes: the state's start).
    point : dict
        The clicked pixel's axis values (``{x: value, y: value}``).
    t, theta, omega : ndarray
        Sampled time [s], angle [rad] and angular velocity [rad/s].
    strobe_theta, strobe_omega : ndarray
        Stroboscopic samples (forced scenes; empty otherwise) [rad, rad/s].
    status : str
        ``"ok"`` or the failure and its meaning.
    label : str
        The map's value at the pixel and its meaning.
    python, toml : str
        Code and run file that reproduce this trajectory.
    """

    theta0: float
    omega0: float
    point: dict
    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    strobe_theta: np.ndarray
    strobe_omega: np.ndarray
    status: str
    label: str
    python: str
    toml: str


# ------------------------------------------------------------------------ explorer
def check_arguments(grid, run_kwargs: dict) -> None:
    """Refuse an explorer's grid that is not a `sweep.Grid`, and run keywords it does not
    take or lacks (``t_end`` and ``dt`` are required).

    Raises
    ------
    TypeError
        Naming the argument and what is accepted.
    """
    if not isinstance(grid, Grid):
        raise TypeError(f"grid must be a sweep.Grid, got {grid!r}")
    known = ("t_end", "dt", "t_transient", "method", "device") + PASSTHROUGH
    unknown = sorted(set(run_kwargs) - set(known) - set(SET_BY_EXPLORER))
    if unknown:
        raise TypeError(f"explore: unknown keyword(s) {', '.join(unknown)}; accepted: "
                        f"{', '.join(known)} (and sweep.run's {', '.join(SET_BY_EXPLORER)},"
                        " which the explorer sets per map)")
    for key in ("t_end", "dt"):
        if key not in run_kwargs:
            raise TypeError(f"explore: missing run keyword {key!r} (s); accepted: the "
                            "keywords of sweep.run, t_end and dt required")


class Explorer:
    """State, validation, history and computation of the browser explorer.

    Parameters
    ----------
    scene : Scene
    grid : Grid
        Its first two axes with more than one value are the map's x and y (others: the
        first value); its ranges are the home view. ``theta0``/``omega0`` not among the
        axes start at their grid value when the grid gives one, else 0.
    quantity : str, optional
        A key of `QUANTITIES` (default: `default_quantity`).
    resolution : int, default 400
        Pixels per axis of the final map.
    cache : OrderedDict, optional
        Final maps by state, shared with other explorers (an app's sessions).
    **run_kwargs
        `sweep.run` arguments: ``t_end`` and ``dt`` (required), ``t_transient``,
        ``method``, ``device`` and the `PASSTHROUGH` ones; those the explorer sets per map
        (`SET_BY_EXPLORER`: observe, stop_early, attractors, ...) are ignored.

    Raises
    ------
    InvalidInput
        On a value sweep's validators refuse (naming the control).
    TypeError
        On a keyword `sweep.run` does not take or the explorer cannot use.
    """

    #: Points per initial-state axis of the pilot that catalogues the attractors.
    pilot_points = PILOT_POINTS

    def __init__(self, scene: Scene, grid: Grid, *, quantity: str | None = None,
                 resolution: int = 400, cache: OrderedDict | None = None,
                 **run_kwargs) -> None:
        if not isinstance(scene, Scene):
            raise TypeError(f"scene must be a sweep.Scene, got {scene!r}")
        check_arguments(grid, run_kwargs)
        x, y, ranges, start, fixed = self._home(scene, grid, AXES_INITIAL, AXES_INITIAL)
        if fixed:  # other axes: their first value goes into the scene
            scene = self._with_parameters(scene, fixed)
        # the scene's natural map first; a run whose settings cannot give it (a forced
        # scene whose dt does not divide the forcing period: no stroboscopic samples)
        # opens on the motion map, with a warning that says why
        chosen = quantity if quantity is not None else default_quantity(scene)
        extra = tuple((k, run_kwargs[k]) for k in PASSTHROUGH if k in run_kwargs)
        state = State(scene=scene, view=View(x, y, ranges[x], ranges[y]), quantity=chosen,
                      t_end=run_kwargs["t_end"], dt=run_kwargs["dt"],
                      t_transient=run_kwargs.get("t_transient", 0.0),
                      method=run_kwargs.get("method", "rk4"), resolution=resolution,
                      start=start, extra=extra, device=run_kwargs.get("device", "cpu"))
        try:
            self.validate(state, "explore")
        except InvalidInput as exc:
            if quantity is not None or chosen == "motion":
                raise
            state = dataclasses.replace(state, quantity="motion")
            self.validate(state, "explore")
            warnings.warn(f"explore: the {QUANTITIES[chosen].label} map cannot be made with "
                          f"these run settings ({exc}); showing the motion map",
                          stacklevel=2)
        self.state = state
        self.home = state.view
        self._history = [state.view]
        self._position = 0
        # final maps by state; an app's sessions share one (the start-up warm-up's map)
        self._cache: OrderedDict[State, MapResult] = OrderedDict() if cache is None else cache
        self._catalogues: OrderedDict[tuple, dict] = OrderedDict()
        self._known: OrderedDict[tuple, tuple] = OrderedDict()  # `known`: per catalogue
        # seconds per start of the last final map of each setting (all but the window)
        self._costs: OrderedDict[State, float] = OrderedDict()
        self._lock = COMPUTE_LOCK

    # -- controls --------------------------------------------------------------
    def _home(self, model, grid: Grid, preferred, initial) -> tuple:
        """The home window of ``grid`` for ``model`` (a scene or a system): its axes (the
        varying ones, then ``preferred``), their ranges (the grid's points as pixel
        centres; `_default_range` for an axis of one value), the start (``initial``
        names: a one-value axis's value, else 0) and the other one-value axes' values.

        Returns
        -------
        x, y : str
        ranges : dict of str to (float, float)
        start : tuple of (str, float)
        fixed : dict of str to float
        """
        varying = [name for name in grid.dims if grid.axes[name].size > 1]
        names = list(varying) + [n for n in preferred if n not in varying]
        x, y = names[0], names[1]
        ranges = {}
        for name in (x, y):
            values = np.asarray(grid.axes[name], dtype=float) if name in grid.axes else None
            if values is None or values.size < 2:
                ranges[name] = self._default_range(model, name)
            else:
                lo, hi = float(values.min()), float(values.max())
                half = 0.5 * (hi - lo) / (values.size - 1)  # the grid's points as centres
                ranges[name] = (lo - half, hi + half)
        start = tuple((n, float(grid.axes[n][0]) if n in grid.axes and
                       grid.axes[n].size == 1 else 0.0) for n in initial)
        fixed = {n: float(v[0]) for n, v in grid.axes.items()
                 if n not in (x, y) and n not in initial}
        return x, y, ranges, start, fixed

    @staticmethod
    def _default_range(scene: Scene, name: str) -> tuple[float, float]:
        if name == "theta0":
            return (-math.pi, math.pi)
        if name == "omega0":
            return (-2.0 * scene.natural_frequency, 2.0 * scene.natural_frequency)
        value = scene.parameters().get(name, 1.0)
        return (0.5 * value, 1.5 * value) if value else (0.0, 1.0)

    def axes(self) -> tuple[str, ...]:
        """Axes the map can show: the initial state, the pendulum's length and gravity,
        and the parameters of the scene's effects (from their declarations)."""
        names = list(AXES_INITIAL) + ["length", "gravity"]
        for effect in self.state.scene.effects:
            names += [p.axis for p in effect.declaration.parameters]
        return tuple(names)

    def quantities(self) -> dict[str, str]:
        """``{name: label}`` of the quantities that apply to the current scene."""
        return {q.name: q.label for q in QUANTITIES.values() if q.applies(self.state.scene)}

    def quantity_info(self, name: str) -> Quantity:
        """The `Quantity` named ``name`` (a key of `QUANTITIES`)."""
        return QUANTITIES[name]

    def parameter_controls(self) -> list[Control]:
        """One control per parameter of the scene (pendulum and each effect), with the
        units, long name and bound of its declaration (`sweep.physics.parameters`)."""
        scene, shown = self.state.scene, (self.state.view.x, self.state.view.y)
        values = scene.parameters()
        out = []
        declared = list(BASE_PARAMETERS[2:])
        for effect in scene.effects:
            declared += list(effect.declaration.parameters)
        for p in declared:
            bound = ""
            if p.minimum is not None:
                bound = f" ({'>' if p.strict else '>='} {p.minimum:g})"
            note = " (on the map's axis)" if p.axis in shown else ""
            out.append(Control(p.axis, f"{p.axis} {p.symbol} [{p.unit_text}]", "float",
                               float(values[p.axis]), minimum=p.minimum, strict=p.strict,
                               help=f"{p.long_name}{bound}{note}", group="scene"))
        for name, value in self.state.start:
            if name in shown:
                continue
            p = next(q for q in BASE_PARAMETERS if q.axis == name)
            out.append(Control(name, f"{name} [{p.unit_text}]", "float", float(value),
                               help=f"{p.long_name} (the start where it is not an axis)",
                               group="scene"))
        return out

    def run_controls(self) -> list[Control]:
        """Model, t_end, dt, t_transient, method and resolution."""
        s = self.state
        low, high = RESOLUTION_RANGE
        return [
            Control("model", "model", "choice", s.scene.model, choices=MODELS,
                    help="nonlinear: sin(theta); linear: theta", group="run"),
            Control("t_end", "t_end [s]", "float", float(s.t_end), minimum=0.0, strict=True,
                    help="final time; t_end - t0 a whole number of steps dt", group="run"),
            Control("dt", "dt [s]", "float", float(s.dt), minimum=0.0, strict=True,
                    help="time step", group="run"),
            Control("t_transient", "t_transient [s]", "float", float(s.t_transient),
                    minimum=0.0, help="steady observables start after it", group="run"),
            Control("method", "method", "choice", s.method, choices=tuple(METHODS),
                    help="integrator (sweep.methods.METHODS)", group="run"),
            Control("resolution", "resolution [pixels per axis]", "int", int(s.resolution),
                    minimum=low, help=f"an integer from {low} to {high}", group="run"),
        ] + ([Control("route", "forced basins route", "choice",
                      ROUTES[0] if s.known_cells else ROUTES[1], choices=ROUTES,
                      help="known cells: a trajectory stops once its stroboscopic points "
                      "land 3 periods running in cells of a background map whose label "
                      "is settled (measured: no start labelled differently on the Wada "
                      "map); exact: the attractor catalogue alone", group="run")]
             if self.uses_pilot(s) else [])

    # -- validation and updates ------------------------------------------------
    @staticmethod
    def _with_parameters(scene: Scene, values: dict[str, float]) -> Scene:
        """``scene`` with parameter values replaced (validated by the effects)."""
        spec = scene.to_dict()
        for name, value in values.items():
            if name in ("length", "gravity"):
                spec[name] = value
                continue
            for effect in scene.effects:
                for p in effect.declaration.parameters:
                    if p.axis == name:
                        spec[effect.declaration.name][p.field] = value
                        break
                else:
                    continue
                break
            else:
                accepted = [p.axis for p in parameters() if p.axis not in AXES_INITIAL]
                raise ValueError(f"{name}: not a parameter of this scene; accepted: "
                                 f"{', '.join(accepted)} of the scene's effects")
        return Scene.from_dict(spec)

    def grid(self, state: State | None = None, resolution: int | None = None,
             rows: slice | None = None) -> Grid:
        """The grid of ``state``'s map: y then x (so the map is (ny, nx)), and the start's
        ``theta0``/``omega0`` as one-value axes where they are not shown."""
        state = state or self.state
        n = resolution or state.resolution
        v = state.view
        ys = centres(*v.y_range, n)
        axes = {v.y: ys if rows is None else ys[rows], v.x: centres(*v.x_range, n)}
        for name, value in state.start:
            if name not in axes:
                axes[name] = np.array([value])
        return Grid(**axes)

    def run_kwargs(self, state: State | None = None) -> dict:
        """`sweep.run` keyword arguments of ``state``'s map (without the catalogue)."""
        state = state or self.state
        q = self.quantity_info(state.quantity)
        extra = dict(state.extra)
        if "strobe" not in q.observe:  # sweep.run refuses samples nothing reads
            extra.pop("strobe_samples", None)
        kwargs = dict(t_end=state.t_end, dt=state.dt, t_transient=state.t_transient,
                      method=state.method, observe=q.observe, **extra)
        if q.stop_early:
            kwargs["stop_early"] = True
        if state.device != "cpu":
            kwargs["device"] = state.device
        return kwargs

    def map_kwargs(self, state: State, catalogue: dict | None) -> dict:
        """`sweep.run` keyword arguments of ``state``'s map run: `run_kwargs` with the
        attractor catalogue (`catalogue`) where there is one."""
        kwargs = self.run_kwargs(state)
        if catalogue is not None:
            kwargs["attractors"] = catalogue
        return kwargs

    def uses_pilot(self, state: State | None = None) -> bool:
        """Forced basins over the initial state: the attractors are catalogued first."""
        state = state or self.state
        return self.quantity_info(state.quantity).pilot and \
            {state.view.x, state.view.y} <= set(AXES_INITIAL)

    def _check_quantity(self, state: State) -> None:
        """Refuse a quantity that is unknown or does not apply to the state's scene
        (a ValueError; `validate` names the control)."""
        if state.quantity not in QUANTITIES:
            raise ValueError(f"quantity {state.quantity!r} is unknown; accepted: "
                             f"{', '.join(QUANTITIES)}")
        if not QUANTITIES[state.quantity].applies(state.scene):
            names = [q.name for q in QUANTITIES.values() if q.applies(state.scene)]
            raise ValueError(f"quantity {state.quantity!r} does not apply to this scene "
                             f"(effects: {', '.join(sorted(effect_names(state.scene))) or 'none'}"
                             f"); accepted: {', '.join(names)}")

    def validate(self, state: State, control: str) -> State:
        """Check ``state`` as `sweep.run` would (`sweep.diskspace.layout`: scene, grid, settings,
        stability, strobe period, ...) without computing; raise `InvalidInput` naming
        ``control`` with the validator's message."""
        try:
            self._check_quantity(state)
            v = state.view
            if v.x == v.y:
                raise ValueError(f"x and y are both {v.x!r}; accepted: two different axes")
            for name, (lo, hi) in ((v.x, v.x_range), (v.y, v.y_range)):
                if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                    raise ValueError(f"range of {name} must be finite with start < end, got "
                                     f"({lo!r}, {hi!r})")
            low, high = RESOLUTION_RANGE
            check_count("resolution", state.resolution, minimum=low, maximum=high,
                        accepted=f"an integer from {low} to {high} (pixels per axis)")
            run_layout(state.scene, self.grid(state), **self.run_kwargs(state))
        except InvalidInput:
            raise
        except (ValueError, TypeError) as exc:
            raise InvalidInput(control, " ".join(str(exc).split())) from None
        return state

    def update(self, **changes) -> State:
        """Change settings; validated before anything is computed.

        Parameters
        ----------
        **changes
            ``quantity``, ``x``, ``y`` (axis names; a new axis gets its default range),
            ``model``, ``t_end``, ``dt``, ``t_transient``, ``method``, ``resolution``,
            ``device``, and any parameter of the scene or ``theta0``/``omega0`` by its
            axis name (``damping=0.25``).

        Returns
        -------
        State
            The new current state.

        Raises
        ------
        InvalidInput
            Naming the first control changed and the validator's message; the state is
            unchanged.
        """
        if not changes:
            return self.state
        control = next(iter(changes))
        state = self.state
        try:
            values = {}
            for name, value in changes.items():
                if isinstance(value, (bool, np.bool_)) or (
                        name not in ("quantity", "x", "y", "model", "method", "device",
                                     "route")
                        and not isinstance(value, (int, float, np.integer, np.floating))):
                    raise TypeError(f"{name} must be a number, got {value!r}")
                if name in ("t_end", "dt", "t_transient"):
                    state = dataclasses.replace(state, **{name: float(value)})
                elif name == "resolution":
                    state = dataclasses.replace(state, resolution=value)
                elif name in ("quantity", "method", "device"):
                    state = dataclasses.replace(state, **{name: value})
                elif name == "route":
                    if value not in ROUTES:
                        raise ValueError(f"route must be one of {', '.join(ROUTES)}, got "
                                         f"{value!r}")
                    state = dataclasses.replace(state, known_cells=value == ROUTES[0])
                elif name == "model":
                    spec = state.scene.to_dict()
                    spec["model"] = value
                    state = dataclasses.replace(state, scene=Scene.from_dict(spec))
                elif name in ("x", "y"):
                    if value not in self.axes():
                        raise ValueError(f"{name} axis {value!r} is not offered; accepted: "
                                         f"{', '.join(self.axes())}")
                    v = state.view
                    other = v.y if name == "x" else v.x
                    if value == other:  # swap
                        view = View(v.y, v.x, v.y_range, v.x_range)
                    elif name == "x":
                        view = View(value, v.y, self._axis_range(state, value), v.y_range)
                    else:
                        view = View(v.x, value, v.x_range, self._axis_range(state, value))
                    state = dataclasses.replace(state, view=view)
                elif name in dict(state.start):
                    start = tuple((n, float(value) if n == name else v)
                                  for n, v in state.start)
                    if not math.isfinite(float(value)):
                        raise ValueError(f"{name} must be a finite number, got {value!r}")
                    state = dataclasses.replace(state, start=start)
                else:
                    values[name] = float(value)
            if values:
                state = dataclasses.replace(
                    state, scene=self._with_parameters(state.scene, values))
        except (ValueError, TypeError) as exc:
            raise InvalidInput(control, " ".join(str(exc).split())) from None
        self.validate(state, control)
        view_changed = state.view != self.state.view
        self.state = state
        if view_changed:
            self._push(state.view)
        return state

    def set_parameter(self, name: str, value: float) -> State:
        """`update` of one parameter by its axis name."""
        return self.update(**{name: value})

    def _axis_range(self, state: State, name: str) -> tuple[float, float]:
        if name == self.home.x:
            return self.home.x_range
        if name == self.home.y:
            return self.home.y_range
        return self._default_range(state.scene, name)

    # -- history -----------------------------------------------------------------
    def zoom(self, x_range, y_range) -> State:
        """Show the window ``x_range`` x ``y_range`` (box-zoom, wheel, pan); adds it to
        the history. Raises `InvalidInput` (control ``"view"``) on a refused window."""
        try:
            x_range = tuple(float(v) for v in x_range)
            y_range = tuple(float(v) for v in y_range)
            if len(x_range) != 2 or len(y_range) != 2:
                raise ValueError("a range is two numbers (start, end)")
        except (TypeError, ValueError) as exc:
            raise InvalidInput("view", f"zoom: {exc}") from None
        v = self.state.view
        state = dataclasses.replace(self.state, view=View(v.x, v.y, x_range, y_range))
        self.validate(state, "view")
        self.state = state
        self._push(state.view)
        return state

    def _push(self, view: View) -> None:
        if self._history[self._position] == view:
            return
        del self._history[self._position + 1:]
        self._history.append(view)
        self._position += 1

    def _go(self, position: int) -> State:
        view = self._history[position]
        state = dataclasses.replace(self.state, view=view)
        self.validate(state, "view")
        self._position = position
        self.state = state
        return state

    @property
    def history(self) -> list[View]:
        """The views visited, oldest first."""
        return list(self._history)

    @property
    def position(self) -> int:
        """Index of the current view in `history`."""
        return self._position

    def can_go_back(self) -> bool:
        return self._position > 0

    def can_go_forward(self) -> bool:
        return self._position < len(self._history) - 1

    def back(self) -> State:
        """The previous view (unchanged at the first)."""
        return self._go(max(0, self._position - 1))

    def forward(self) -> State:
        """The next view (unchanged at the last)."""
        return self._go(min(len(self._history) - 1, self._position + 1))

    def reset(self) -> State:
        """The home view (the start-up window, with the current axes if they are the
        home's), added to the history."""
        v = self.state.view
        if (v.x, v.y) == (self.home.x, self.home.y):
            view = self.home
        else:
            view = View(v.x, v.y, self._axis_range(self.state, v.x),
                        self._axis_range(self.state, v.y))
        state = dataclasses.replace(self.state, view=view)
        self.validate(state, "view")
        self.state = state
        self._push(view)
        return state

    # -- computation -------------------------------------------------------------
    def pilot_state(self, state: State | None = None) -> State:
        """The state whose grid the pilot thins: ``state`` with the home window (when
        its axes are the home's), so that every zoom reuses one catalogue."""
        state = state or self.state
        v = state.view
        if (v.x, v.y) == (self.home.x, self.home.y):
            return dataclasses.replace(state, view=self.home)
        return state

    def catalogue(self, state: State | None = None) -> dict | None:
        """The attractor catalogue of ``state`` (forced basins over the initial state):
        `sweep.maps.pilot_catalogue` over the home window's grid (`pilot_state`), thinned
        to `pilot_points` per axis; cached per scene, settings and start.

        One catalogue for every zoom: a new one costs its pilot run (the catalogue is
        the kernel's data, so no compilation), while the labels do not depend on it (a
        catalogue only decides when a trajectory may stop; attractors it lacks are still
        found by the strobe test; `sweep.maps.basins` orders them as a full run does).
        """
        state = state or self.state
        if not self.uses_pilot(state):
            return None
        pilot = self.pilot_state(state)
        key = self.pilot_key(pilot)
        if key not in self._catalogues:
            self._catalogues[key] = maps.pilot_catalogue(
                pilot.scene, self.grid(pilot), self.pilot_points, **self.run_kwargs(pilot))
            while len(self._catalogues) > 8:
                self._catalogues.popitem(last=False)
        return self._catalogues[key]

    @staticmethod
    def pilot_key(pilot: State) -> tuple:
        """The cache key of the catalogue of ``pilot`` (a `pilot_state`) and of the
        background computed with it (`known`): every field of ``pilot`` that the pilot
        run and the background read (`grid`, `run_kwargs`; ``extra`` holds ``t0``,
        ``rtol``, ``atol``, ``dtype``, ...).

        Left out, as they cannot change either: ``quantity`` (`uses_pilot` holds for
        the quantities with ``pilot`` only, one per explorer: ``basins``),
        ``known_cells`` (`known` runs only with it on), ``catalogue`` (the systems'
        route, on wherever `SystemExplorer.uses_pilot` holds) and `pilot_points` (the
        explorer's constant). ``start`` and ``device`` are in it although, today,
        neither reaches a pilot's grid or a background (`uses_pilot`: both initial axes
        are shown; `uses_known`: the CPU only), so that a background is keyed as the
        catalogue it is computed with.
        """
        return (pilot.scene, pilot.view, pilot.resolution, pilot.t_end, pilot.dt,
                pilot.t_transient, pilot.method, pilot.extra, pilot.device, pilot.start)

    def uses_known(self, state: State | None = None) -> bool:
        """Forced basins over the initial state, run where `sweep.run` takes
        ``known_cells`` (the CPU, float64, a fixed-step method), at a resolution of
        `KNOWN_MIN_RESOLUTION` or more, with ``state.known_cells`` on."""
        state = state or self.state
        return bool(state.known_cells) and self.uses_pilot(state) \
            and state.resolution >= KNOWN_MIN_RESOLUTION \
            and state.device == "cpu" and dict(state.extra).get("dtype", "float64") == \
            "float64" and not METHODS[state.method].adaptive

    def known(self, state: State | None = None):
        """The known cells of ``state``'s map (`uses_known`), or None: the settled cells
        of a background of the home window (`sweep.maps.known.background`: maps at 1/8,
        1/4 and 1/2 of the home resolution, each stopping on the one before), computed
        once per catalogue and shared by every zoom, so that a zoomed window's
        trajectories also stop where they enter a region whose fate is known; frozen
        while a map runs (the labels do not depend on threads, bands or blocks)."""
        state = state or self.state
        if not self.uses_known(state):
            return None
        from ..maps.known import background, fixed_axes

        pilot = self.pilot_state(state)
        key = self.pilot_key(pilot)  # the catalogue's: one background per catalogue
        if key not in self._known:
            grid = self.grid(pilot)
            self._known[key] = background(pilot.scene, grid.axes["theta0"],
                                          grid.axes["omega0"], self.catalogue(state),
                                          fixed=fixed_axes(grid), **self.run_kwargs(pilot))
            while len(self._known) > 8:
                self._known.popitem(last=False)
        return self._known[key][0]

    def compute(self, state: State | None = None, *, preview: bool = False,
                cancel: CancelToken | None = None, per_start: float | None = None,
                on_step: Callable[[MapResult], None] | None = None) -> MapResult:
        """Compute ``state``'s map (default: the current state).

        Parameters
        ----------
        state : State, optional
        preview : bool, default False
            The coarse preview: resolution / `PREVIEW_FACTOR` per axis, in one run.
        cancel : CancelToken, optional
            Checked between bands (and before the run); `Cancelled` is raised once set.
        per_start : float, optional
            Seconds one start costs (measured by the preview): the final map is cut into
            bands of about `BAND_SECONDS` (at most `BANDS`, each at least `BAND_MIN`
            starts); without it, into `BANDS` bands of at least `BAND_MIN` starts.
        on_step : callable, optional
            ``on_step(result)`` with a progressive step of the final map (``stage ==
            "step"``) after 1, 2, 4, ... of its bands, when `STEP_SECONDS` passed since
            the computation began or the last step.

        Returns
        -------
        MapResult
        """
        state = state or self.state
        if not preview and state in self._cache:
            self._cache.move_to_end(state)
            return self._cache[state]
        cancel = cancel or CancelToken()
        with self._lock:
            cancel.check()
            begin = time.perf_counter()
            catalogue = self.catalogue(state)
            kwargs = self.map_kwargs(state, catalogue)
            known = self.known(state)
            if known is not None:
                kwargs["known_cells"] = known
            cancel.check()
            run_begin = time.perf_counter()
            if preview:
                n = max(RESOLUTION_RANGE[0], state.resolution // PREVIEW_FACTOR)
                ds = self._run(state, self.grid(state, n), kwargs)
                run_seconds = time.perf_counter() - run_begin
            else:
                ds, run_seconds = self._run_bands(state, kwargs, cancel, per_start, on_step,
                                                  begin, catalogue)
            cancel.check()
            result = self._image(state, ds, preview, catalogue)
            result.route = self._route(state, ds, catalogue, known)
            result.seconds = time.perf_counter() - begin
            result.run_seconds = run_seconds
            if preview:
                result.stage = "preview"
                result.done = min(1.0, (n / state.resolution) ** 2)
        if not preview:
            self._cache[state] = result
            while len(self._cache) > CACHE_SIZE:
                self._cache.popitem(last=False)
        return result

    def stages(self, state: State, cancel: CancelToken, emit: Callable[[MapResult], None]
               ) -> MapResult:
        """The preview, progressive steps of the final map (`compute`'s ``on_step``) and
        the final map; each is passed to ``emit`` as it is ready.

        The preview is shown only when the final map is expected to take `PREVIEW_AFTER`
        or more. It is not computed when the final map is cached, nor when the last final
        map of the same settings (another window) cost under half of that per start: its
        cost per start then sizes the bands. Raises `Cancelled` once ``cancel`` is
        set."""
        per_start, preview_seconds = None, 0.0
        starts = state.resolution ** 2
        v = state.view  # the setting: all but the window (the axes kept)
        setting = dataclasses.replace(state, view=View(v.x, v.y, (0.0, 1.0), (0.0, 1.0)))
        if state not in self._cache:
            known = self._costs.get(setting)
            if known is not None and known * starts < 0.5 * PREVIEW_AFTER:
                per_start = known
            else:
                preview = self.compute(state, preview=True, cancel=cancel)
                preview_seconds = preview.seconds
                per_start = preview.run_seconds / preview.values.size
                if per_start * starts >= PREVIEW_AFTER:
                    emit(preview)
        final = self.compute(state, cancel=cancel, per_start=per_start, on_step=emit)
        final.preview_seconds = preview_seconds
        if per_start is not None:  # computed now: its cost is the newest measure
            self._costs[setting] = final.run_seconds / starts
            self._costs.move_to_end(setting)
            while len(self._costs) > 16:
                self._costs.popitem(last=False)
        cancel.check()
        emit(final)
        return final

    @staticmethod
    def _route(state: State, ds, catalogue, known) -> str:
        """Which route made the map, in words, with how many starts stopped early on
        known cells (the page's status line)."""
        n = int(np.prod([ds.sizes[d] for d in ds.dims if d in (state.view.x,
                                                                  state.view.y)]))
        if known is not None and "stopped_known" in ds:
            stopped = int(np.nansum(ds["stopped_known"].values))
            return (f"catalogue + known cells: {n} starts computed, {stopped} stopped on "
                    "known cells")
        if catalogue is not None:
            why = " (exact route)" if not state.known_cells else (
                f" (known cells from {KNOWN_MIN_RESOLUTION} pixels per axis)"
                if state.resolution < KNOWN_MIN_RESOLUTION else "")
            return f"catalogue{why}: {n} starts computed"
        return ""

    def numbers(self, result: MapResult):
        """The numbers of ``result``'s view (`sweep.explore.numbers.view_numbers`:
        fractions with their standard errors, Sb and Sbb with the fractality verdict);
        computed once per result. None for a map of continuous values."""
        from .numbers import view_numbers

        if result.numbers is None:
            result.numbers = view_numbers(result)
        return result.numbers

    @staticmethod
    def _run(state: State, grid: Grid, kwargs: dict):
        with warnings.catch_warnings():  # failures are in the status, shown per start
            warnings.simplefilter("ignore", RuntimeWarning)
            return sweep_run(state.scene, grid, progress=False, **kwargs)

    @staticmethod
    def band_count(n: int, per_start: float | None = None) -> int:
        """Bands of an ``n`` x ``n`` final map: `BANDS` at most, each of at least
        `BAND_MIN` starts, and with ``per_start`` (seconds per start) no more than
        needed for about `BAND_SECONDS` each."""
        by_size = math.ceil(n / max(1, min(n, max(math.ceil(n / BANDS),
                                                  math.ceil(BAND_MIN / n)))))
        if per_start is None or not math.isfinite(per_start):
            return by_size
        by_time = max(1, math.ceil(per_start * n * n / BAND_SECONDS))
        return int(min(by_size, by_time))

    @staticmethod
    def band_order(bands: int) -> list[int]:
        """The order the interleaved bands are computed in: band ``j`` holds the rows
        ``j, j + bands, ...``, taken in van der Corput order (0, 4, 2, 6, 1, 5, 3, 7 for
        8 bands), so the rows computed after 1, 2, 4, ... bands are evenly spread."""
        def radical_inverse(j: int) -> float:
            out, scale = 0.0, 0.5
            while j:
                out += scale * (j & 1)
                j >>= 1
                scale *= 0.5
            return out

        return sorted(range(bands), key=radical_inverse)

    def _run_bands(self, state: State, kwargs: dict, cancel: CancelToken,
                   per_start: float | None = None, on_step=None, begin: float = 0.0,
                   catalogue=None):
        """The final map as `band_count` runs of interleaved rows (band ``j``: rows ``j,
        j + bands, ...``, in `band_order`), put back in row order: the same values as
        one run (results do not depend on how the work is cut), with a cancel check
        between bands. Returns ``(ds, seconds of the runs)``."""
        n = state.resolution
        bands = min(n, self.band_count(n, per_start))
        parts, rows, run_seconds = [], [], 0.0
        last = begin or time.perf_counter()
        for done, first in enumerate(self.band_order(bands), start=1):
            cancel.check()
            band = slice(first, None, bands)
            started = time.perf_counter()
            parts.append(self._run(state, self.grid(state, rows=band), kwargs))
            run_seconds += time.perf_counter() - started
            rows.append(np.arange(n)[band])
            power_of_two = done & (done - 1) == 0
            if (on_step is not None and done < bands and power_of_two
                    and time.perf_counter() - last >= STEP_SECONDS):
                cancel.check()
                on_step(self._step(state, parts, rows, catalogue))
                last = time.perf_counter()
        return self._in_row_order(state, parts, rows), run_seconds

    @staticmethod
    def _in_row_order(state: State, parts: list, rows: list):
        """Bands of interleaved rows concatenated along y, in row order."""
        import xarray as xr

        if len(parts) == 1:
            return parts[0]
        ds = xr.concat(parts, dim=state.view.y, data_vars="minimal", coords="minimal",
                       compat="override", combine_attrs="override")
        return ds.isel({state.view.y: np.argsort(np.concatenate(rows), kind="stable")})

    def _step(self, state: State, parts: list, rows: list, catalogue) -> MapResult:
        """A progressive step: the map of the rows computed so far, each missing row
        drawn as its nearest computed row."""
        n = state.resolution
        ds = self._in_row_order(state, parts, rows)
        partial = self._image(state, ds, True, catalogue)
        done = np.sort(np.concatenate(rows))
        every = np.arange(n)
        above = np.clip(np.searchsorted(done, every), 0, done.size - 1)
        below = np.clip(above - 1, 0, done.size - 1)
        nearest = np.where(np.abs(done[below] - every) <= np.abs(done[above] - every),
                           below, above)
        partial.values = partial.values[nearest]
        partial.image = partial.image[nearest]
        partial.y = centres(*state.view.y_range, n)
        partial.stage = "step"
        partial.done = done.size / n
        return partial

    def _image(self, state: State, ds, preview: bool, catalogue) -> MapResult:
        q = self.quantity_info(state.quantity)
        v = state.view
        da = q.compute(ds)
        extra = [d for d in da.dims if d not in (v.x, v.y)]
        da = da.squeeze(extra).transpose(v.y, v.x)
        values = np.asarray(da.values)
        from ..plot import units_text

        units = str(da.attrs.get("units", ""))
        name = str(da.name) if da.name is not None else state.quantity
        if q.discrete:
            legend, image = legend_of(state.quantity, da, values)
        else:
            legend = []
            image = values.astype(np.float64)
        title = f"{name} [{units_text(units)}]" if units and units != "1" else name
        return MapResult(state=state, preview=preview, x=np.asarray(da[v.x].values),
                         y=np.asarray(da[v.y].values), values=values, image=image,
                         legend=legend, title=title,
                         description=str(da.attrs.get("long_name", name)),
                         comment=str(da.attrs.get("comment", "")), da=da,
                         ds=None if preview else ds,
                         seconds=0.0, catalogue=catalogue,
                         summary=label_summary(state.quantity, values))

    def value_at(self, result: MapResult, x: float, y: float) -> tuple[int, int]:
        """Indices ``(row, column)`` of the pixel of ``result`` nearest ``(x, y)``."""
        return (int(np.argmin(np.abs(result.y - y))), int(np.argmin(np.abs(result.x - x))))

    def label_at(self, result: MapResult, row: int, col: int) -> str:
        """The map's value at a pixel, with its meaning."""
        value = result.values[row, col]
        if result.legend:
            index = result.image[row, col]
            if np.isfinite(index):
                return f"{result.legend[int(index)][1]} ({number_text(value)})"
            return "none"
        return f"{number_text(value)} ({result.title})"

    # -- one trajectory ---------------------------------------------------------
    def clicked(self, x, y, result: MapResult | None, state: State | None):
        """A click at ``(x, y)``: the state it belongs to, the start (snapped to the pixel
        centre of ``result`` when given, so it is one of the map's starts) and the map's
        label there ("" without ``result``).

        Raises
        ------
        InvalidInput
            When ``x`` or ``y`` is not a number.
        """
        state = state or (result.state if result is not None else self.state)
        label = ""
        try:
            x, y = float(x), float(y)
        except (TypeError, ValueError):
            raise InvalidInput("view", f"a start is two numbers, got ({x!r}, {y!r})") from None
        if result is not None:
            row, col = self.value_at(result, x, y)
            x, y = float(result.x[col]), float(result.y[row])
            label = self.label_at(result, row, col)
        return state, x, y, label

    def trajectory(self, x: float, y: float, result: MapResult | None = None,
                   state: State | None = None) -> Trajectory:
        """The trajectory of the map's start nearest ``(x, y)`` (snapped to the pixel
        centre of ``result`` when given, so it is one of the map's starts).

        Returns
        -------
        Trajectory
            Sampled theta(t) and omega(t) (save_every chosen to keep at most
            `TRAJECTORY_SAMPLES`), stroboscopic points (forced scenes), status, the map's
            label at that pixel, and the code and run file that reproduce it.
        """
        state, x, y, label = self.clicked(x, y, result, state)
        v = state.view
        axes, kwargs = self._trajectory_inputs(state, x, y)
        with self._lock:
            ds = self._run(state, Grid(**axes), kwargs)
        one = {d: 0 for d in ds.status.dims}
        code = int(ds.status.isel(one))
        status = Status(code)
        status_text = "ok" if status == Status.OK else f"{status.name.lower()}: {status.message}"
        if "strobe_theta" in ds:
            st = np.asarray(ds.strobe_theta.isel(one).values)
            so = np.asarray(ds.strobe_omega.isel(one).values)
            keep = np.isfinite(st)
            st, so = st[keep], so[keep]
        else:
            st = so = np.empty(0)
        if not label:
            label = MOTION_TEXT.get(int(maps.motion(ds).isel(one)), "")
        start = dict(state.start)
        return Trajectory(
            theta0=float(axes["theta0"][0]), omega0=float(axes["omega0"][0]),
            point={v.x: x, v.y: y}, t=np.asarray(ds.time.values),
            theta=np.asarray(ds.theta.isel(one).values),
            omega=np.asarray(ds.omega.isel(one).values), strobe_theta=st, strobe_omega=so,
            status=status_text, label=label,
            python=self._python(state, Grid(**axes), kwargs, None, trajectory=True),
            toml=self._toml(state, axes, kwargs, pilot=False,
                            comment=f"one trajectory of the explorer's map, from "
                                    f"{v.x} = {x!r}, {v.y} = {y!r}"
                                    + ("" if v.x in start and v.y in start else
                                       f" (theta0 = {start['theta0']!r}, omega0 = "
                                       f"{start['omega0']!r})")))

    def _trajectory_inputs(self, state: State, x: float, y: float):
        v = state.view
        axes = {name: np.array([value]) for name, value in state.start}
        axes[v.x] = np.array([x])
        axes[v.y] = np.array([y])
        kwargs = dict(t_end=state.t_end, dt=state.dt, t_transient=state.t_transient,
                      method=state.method, **dict(state.extra))
        observe = ["final", "winding"]
        steps = int(round((state.t_end - kwargs.get("t0", 0.0)) / state.dt))  # noqa: RUF046 - NumPy 1.x
        kwargs["save_every"] = max(1, math.ceil(steps / TRAJECTORY_SAMPLES))
        if forced(state.scene) and "forcing_frequency" not in (v.x, v.y):
            frequency = state.scene.forcing.frequency
            if frequency > 0:
                period = 2 * math.pi / frequency
                observed = state.t_end - kwargs.get("t0", 0.0) - state.t_transient
                low, high = STROBE_SAMPLES_RANGE
                samples = int(min(high, max(low, math.floor(observed / period + 1e-9))))
                steps_per_period = period / state.dt
                if abs(steps_per_period - round(steps_per_period)) < 1e-6 * steps_per_period:
                    observe.append("strobe")
                    kwargs["strobe_samples"] = samples
        kwargs["observe"] = tuple(observe)
        if state.device != "cpu":
            kwargs["device"] = state.device
        return axes, kwargs

    # -- reproduction -----------------------------------------------------------
    def python_snippet(self, state: State | None = None) -> str:
        """Python that recomputes ``state``'s map exactly (same grid floats, settings and
        pilot), ending with ``image = <the map>``."""
        state = state or self.state
        pilot = self.grid(self.pilot_state(state)) if self.uses_pilot(state) else None
        return self._python(state, self.grid(state), self.run_kwargs(state),
                            self.quantity_info(state.quantity), pilot=pilot)

    def toml_text(self, state: State | None = None) -> str:
        """A run file (`sweep.toml_spec.load_run`) that recomputes ``state``'s map:
        ``sweep run THIS.toml -o map.nc``, then the map named in its first line."""
        state = state or self.state
        q = self.quantity_info(state.quantity)
        v = state.view
        n = state.resolution
        axes = {}
        for name, rng in ((v.y, v.y_range), (v.x, v.x_range)):
            c = centres(*rng, n)
            axes[name] = {"start": float(c[0]), "stop": float(c[-1]), "num": n}
        for name, value in state.start:
            if name not in axes:
                axes[name] = float(value)
        imports = ", from sweep import maps" if "maps." in q.expression else ""
        comment = (f"the explorer's map: {q.label}; after sweep run, image = {q.expression} "
                   f"(ds = sweep.load(OUT.nc){imports})")
        if self.uses_pilot(state):
            comment += ("\n# pilot = 41 catalogues the attractors on this window (the "
                        "explorer's pilot used its home window): the labels are the same, "
                        "a catalogue only decides when a start may stop")
        return self._toml(state, axes, self.run_kwargs(state), pilot=self.uses_pilot(state),
                          comment=comment)

    @staticmethod
    def _python(state: State, grid: Grid, kwargs: dict, quantity: Quantity | None, *,
                pilot: Grid | None = None, trajectory: bool = False) -> str:
        lines = ["import numpy as np", "import sweep", "from sweep import maps", "",
                 f"scene = sweep.Scene.from_dict({state.scene.to_dict()!r})"]
        lines.append(f"grid = {grid_text(grid)}")
        items = ", ".join(f"{k}={v!r}" for k, v in kwargs.items())
        lines.append(f"kwargs = dict({items})")
        if pilot is not None:
            lines.append(f"home = {grid_text(pilot)}  # the pilot's window: the home view")
            lines.append(f"kwargs['attractors'] = maps.pilot_catalogue(scene, home, "
                         f"{PILOT_POINTS}, **kwargs)")
        lines.append("ds = sweep.run(scene, grid, **kwargs)")
        if trajectory:
            lines.append("sweep.plot.trajectory(ds)  # theta(t) and the phase portrait")
        elif quantity is not None:
            lines.append(f"image = {quantity.expression}")
        return "\n".join(lines) + "\n"

    @staticmethod
    def _toml(state: State, axes: dict, kwargs: dict, *, pilot: bool, comment: str) -> str:
        spec = state.scene.to_dict()
        out = [f"# {comment}", "# written by sweep explore; run: sweep run THIS.toml -o OUT.nc",
               "", "[scene]"]
        for key in ("gravity", "length", "model"):
            out.append(f"{key} = {toml_value(spec[key])}")
        for name in EFFECTS:
            if name in spec:
                out += ["", f"[scene.{name}]"]
                out += [f"{k} = {toml_value(v)}" for k, v in spec[name].items()]
        written, grid = grid_lines(axes)
        out += ["", "[grid]", *written, "", "[run]",
                *run_lines(kwargs, state.scene, grid, toml_value)]
        if pilot:
            out.append(f"pilot = {PILOT_POINTS}")
        return "\n".join(out) + "\n"

    # -- exports ------------------------------------------------------------------
    def netcdf_bytes(self, result: MapResult) -> bytes:
        """The final map's run as netCDF (written by `sweep.save`: its provenance
        attributes), with the map added as a variable and ``explore_quantity`` /
        ``explore_map`` attributes naming it."""
        if result.ds is None:
            result = self.compute(result.state)
        ds = result.ds.copy()
        name = str(result.da.name or "map")
        if name in ds:
            name = f"{name}_map"
        da = result.da.copy()
        da.attrs = {k: v for k, v in da.attrs.items() if not isinstance(v, bool)}
        if da.dtype == bool:
            da = da.astype(np.int8)
        ds[name] = da.transpose(*[d for d in ds.status.dims if d in da.dims])
        ds.attrs["explore_quantity"] = result.state.quantity
        ds.attrs["explore_map"] = name
        with tempfile.TemporaryDirectory(prefix="sweep-explore-") as folder:
            path = Path(folder) / "map.nc"
            sweep_io.save(ds, path)
            return path.read_bytes()

    def png_bytes(self, result: MapResult, dpi: int = 120) -> bytes:
        """The map drawn by `sweep.plot` (`png_figure`), as PNG."""
        buffer = _stdio.BytesIO()
        self.png_figure(result).savefig(buffer, format="png", dpi=dpi)
        return buffer.getvalue()

    def png_figure(self, result: MapResult):
        """The map drawn by `sweep.plot` (basins: `plot.basins`; others: `plot.map`) on
        matplotlib's Agg canvas (no pyplot, so no GUI backend is touched), its angle
        axes in degrees as the page shows them (`sweep.plot.angle_axis`)."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        from .. import plot

        v = result.state.view
        fig = Figure(figsize=(7.0, 5.4), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot()
        da = result.da.transpose(v.x, v.y)
        title = f"{self.quantity_info(result.state.quantity).label}"
        degrees = True  # as the page and `sweep plot` draw them
        if result.state.quantity == "basins":
            plot.basins(da, ax=ax, degrees=degrees, title=title)
        else:
            if da.dtype == bool:
                da = da.astype(np.int8)
            plot.map(da, ax=ax, degrees=degrees, title=title)
        return fig


def rss_bytes() -> int:
    """This process's resident memory [bytes] (Linux ``/proc/self/statm``; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as handle:
            return int(handle.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0
