"""The explorer's model for systems with several coordinates (`sweep.DoublePendulum`,
`sweep.CoupledPendula`, `sweep.DeclaredSystem`): `SystemExplorer`, the single
pendulum's `Explorer` with what depends on the system read from its declaration.

- the quantities are the variables of the system's observables
  (`sweep.system_observables`: ``final``, ``winding``, ``energy``, ``flip``,
  ``lyapunov``; every time in seconds also as its log10), not a list per system; a
  driven system (`sweep.physics.System.drive_frequency_parameter`: a double pendulum's
  pivot drive, a single `sweep.Forcing` on one coordinate, a `sweep.DeclaredSystem`'s
  ``drive_frequency_axis``) also has ``basins`` and ``period``, `sweep.maps.basins` and
  `sweep.maps.period` of its stroboscopic samples (`driven_quantities`);
- the axes are the system's grid axes (every coordinate's initial value and velocity,
  its parameters, ``damping``);
- the controls are its declaration's parameters (units, long names, bounds) and the
  initial values not on the map's axes;
- a click runs the start with ``save_every`` and gives every coordinate and velocity
  over time (`SystemTrajectory`).

Zoom, history, bands, cancellation, caching, exports and validation (`sweep.diskspace.
layout`, the checks `sweep.run` makes) are the `Explorer`'s own.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from .. import maps
from ..grid import Grid
from ..kernels import Status
from ..methods import METHODS
from ..observables import STROBE_SAMPLES
from ..physics.coupled import CoupledPendula
from ..physics.declared import DeclaredSystem
from ..physics.double import DoublePendulum
from ..physics.network import SwingNetwork
from ..physics.system import SYSTEM_DAMPING, System, initial_parameters
from ..settings import validate_settings
from ..system_attractors import initial_axes
from ..system_observables import SYSTEM_OBSERVABLES, variables
from ..toml_periods import run_lines
from ..toml_spec import SYSTEM_KEYS
from .model import (
    PASSTHROUGH,
    RESOLUTION_RANGE,
    TRAJECTORY_SAMPLES,
    Control,
    Explorer,
    InvalidInput,
    MapResult,
    State,
    View,
    check_arguments,
)
from .quantities import Quantity
from .texts import grid_lines, grid_text, number_text, toml_value

__all__ = ["CATALOGUE_OBSERVE", "SYSTEM_PILOT_POINTS", "SYSTEM_RESOLUTION", "SYSTEM_ROUTES",
           "SystemExplorer", "SystemTrajectory", "driven_quantities",
           "system_quantities"]


#: What a continuous map's caption says of its NaN cells (drawn dark grey: the colour
#: bar has no entry for them).
NAN_NOTE = "grey on the map: NaN"


def _always(system) -> bool:
    return True


def _log10_units(units: str) -> str:
    """``" [log10(s)]"``: the bracketed units of the log10 of a value in ``units``
    (UDUNITS), not ``units``; "" for a dimensionless value."""
    from ..plot import units_text

    shown = units_text(units)
    return f" [log10({shown})]" if shown else ""


def _log10_text(name: str, long_name: str, units: str) -> str:
    """``"log10 of the time of the first flip [log10(s)]"``: a log10's label
    (`_log10_units`)."""
    return f"log10 of the {long_name or name}" + _log10_units(units)


def _log10(ds, name: str):
    """The log10 of variable ``name`` (NaN where it is not positive): dimensionless
    (units ``"1"``), its long name saying of what and in what units
    (`_log10_text`)."""
    da = np.log10(ds[name].where(ds[name] > 0))
    da.name = f"log10_{name}"
    da.attrs = {"units": "1", "long_name": _log10_text(
        name, ds[name].attrs.get("long_name", ""), ds[name].attrs.get("units", ""))}
    if "comment" in ds[name].attrs:  # the variable's full meaning (MapResult.caption)
        da.attrs["comment"] = ds[name].attrs["comment"]
    return da


def system_quantities(system: System) -> dict[str, Quantity]:
    """Every map of ``system``: one per variable of each of its observables
    (`sweep.system_observables.variables`, in their order), a time [s] also as its
    log10 (first, as ``log10:<name>``: flip times span decades). A system without an
    angle has no flip map, one declared by accelerations without a potential no
    energy map.

    A driven system (`sweep.physics.System.drive_frequency_parameter`) has
    `driven_quantities` first: ``basins`` and ``period``.

    Returns
    -------
    dict of str to sweep.explore.model.Quantity
        Keys ``var:<variable>`` (``var:theta1_final``), ``log10:<variable>`` and, driven,
        ``basins`` and ``period``.
    """
    declaration = system.declaration
    coordinates = declaration.coordinates
    out: dict[str, Quantity] = driven_quantities() \
        if system.drive_frequency_parameter is not None else {}
    meaningless = {"attractor"}  # it needs an attractor catalogue (sweep.run's attractors=)
    if not any(c.angular for c in coordinates):
        meaningless.add("flip")  # no angle can pass an upright position
    if declaration.lagrangian is None and declaration.potential is None:
        meaningless.add("energy")  # accelerations without a potential: no energy
    for observable in SYSTEM_OBSERVABLES.values():
        if observable.name in meaningless or observable.sampled:  # strobe: a sequence
            continue
        for name, units, long_name in variables(observable.name, coordinates,
                                                system.energy_units):
            if units == "s":
                out[f"log10:{name}"] = Quantity(
                    f"log10:{name}",
                    f"{observable.name}: {_log10_text(name, long_name, units)}",
                    (observable.name,), observable.stops, _always,
                    lambda ds, name=name: _log10(ds, name), False,
                    expression=f'np.log10(ds["{name}"])')
            out[f"var:{name}"] = Quantity(
                f"var:{name}", f"{observable.name}: {name}", (observable.name,),
                observable.stops, _always, lambda ds, name=name: ds[name],
                observable.name == "winding", expression=f'ds["{name}"]')
    return out


def driven_quantities() -> dict[str, Quantity]:
    """The maps of a driven system's stroboscopic samples: ``basins`` (attractor labels,
    `sweep.maps.basins`: every coordinate and velocity, each angle modulo 2 pi; -1
    unresolved) and ``period`` (`sweep.maps.period`, in drive periods; -1 none found).

    Both run with ``observe=("strobe",)`` and the explorer's own ``t_end``, ``dt`` and
    ``t_transient`` (the run controls), and ``strobe_samples`` as given to the explorer
    (default 16, `sweep.run`'s: two repeats of the longest period `sweep.maps.basins`
    looks for, 8): the samples are the last ``strobe_samples`` drive periods before
    ``t_end``, so ``t_end`` sets how long a start has to settle; one that has not (or is
    chaotic) is labelled -1, drawn black and counted on the status line
    (`sweep.explore.model.label_summary`). `SystemExplorer.validate` refuses a ``t_end``
    that reaches fewer samples (every start would be unresolved), and `sweep.run` a
    ``dt`` that does not divide the drive period, with a ``dt`` that does.

    ``basins`` over two initial-state axes takes the catalogue route by default
    (``pilot``: `SystemExplorer.catalogue`, `SystemExplorer.map_kwargs`): the same run
    observing ``("strobe", "attractor")`` with a pilot's attractor catalogue and
    ``stop_early``, then `sweep.maps.basins`; ``period`` is always the full run.
    """
    return {q.name: q for q in (
        Quantity("basins", "attractor basins (driven)", ("strobe",), False, _always,
                 maps.basins, True, pilot=True, expression="maps.basins(ds)"),
        Quantity("period", "period map (driven): drive periods", ("strobe",), False,
                 _always, maps.period, True, expression="maps.period(ds)"),
    )}


def default_system_quantity(quantities: dict[str, Quantity]) -> str:
    """The time to the first flip (log10) where offered, else the first quantity."""
    return "log10:flip_time" if "log10:flip_time" in quantities else next(iter(quantities))


@dataclass
class SystemTrajectory:
    """One start's trajectory of a system.

    Attributes
    ----------
    start : dict of str to float
        Every initial value (``theta1_0`` [rad], ``omega1_0`` [rad/s], ...).
    point : dict
        The clicked pixel's axis values (``{x: value, y: value}``).
    t : ndarray
        Sampled time [s].
    series : dict of str to ndarray
        Every coordinate (unwrapped), then every velocity, over ``t`` (``theta1``,
        ``theta2``, ``omega1``, ``omega2``).
    units : dict of str to str
        UDUNITS units of each series.
    status : str
        ``"ok"`` or the failure and its meaning.
    label : str
        The map's value at the pixel.
    python, toml : str
        Code and run file that reproduce this trajectory.
    """

    start: dict
    point: dict
    t: np.ndarray
    series: dict
    units: dict
    status: str
    label: str
    python: str
    toml: str


def _constructor(system: System) -> dict:
    """``system``'s constructor arguments except ``effects`` (and a declared system's
    declaration) and those left out (None: a term it does not have, such as a double
    pendulum's joint damping)."""
    if isinstance(system, DeclaredSystem):
        return {p.axis: float(getattr(system, p.axis))
                for p in system.declaration.parameters}
    return {f.name: (value.tolist() if isinstance(value, np.ndarray) else value)
            for f in dataclasses.fields(system) if f.name != "effects"
            for value in (getattr(system, f.name),) if value is not None}


def _replaced(system: System, changes: dict) -> System:
    """``system`` with the constructor arguments ``changes`` (validated by it)."""
    if isinstance(system, DeclaredSystem):
        values = {**_constructor(system), **changes}
        effects = values.pop("effects", system.effects)
        return DeclaredSystem(system.declaration, effects=effects, **values)
    return dataclasses.replace(system, **changes)


def _effect_parameters(system: System) -> tuple:
    """The parameters of the system's effects on one coordinate (``damping_theta1``,
    ``torque_theta2``: `sweep.physics.coordinate_effects`), in the effects' order."""
    from ..physics.coordinate_effects import parameters_on

    coordinates = {c.name: c for c in system.declaration.coordinates}
    return tuple(p for e in system.effects if e.coordinate is not None
                 for p in parameters_on(type(e), coordinates[e.coordinate],
                                        system.energy_units))


def _with_effect_value(effects: tuple, axis: str, value: float) -> tuple:
    """``effects`` with the value of the effect parameter named ``axis``
    (``<field axis>_<coordinate>``) replaced (validated by the effect)."""
    import dataclasses

    from ..physics.coordinate_effects import split_axis

    cls, p, coordinate = split_axis(axis)
    return tuple(dataclasses.replace(e, **{p.field: value})
                 if type(e) is cls and e.coordinate == coordinate else e for e in effects)


def _system_python(system: System) -> list[str]:
    """Lines of Python that make ``system`` (as ``system``)."""
    arguments = ", ".join(f"{k}={v!r}" for k, v in _constructor(system).items())
    if system.effects:
        effects = ", ".join(f"sweep.{e!r}" for e in system.effects)
        arguments += f", effects=({effects}{',' if len(system.effects) == 1 else ''})"
    if isinstance(system, DeclaredSystem):
        return ["from sweep.physics import Coordinate, Parameter, SystemDeclaration",
                *_declaration_python(system.declaration),
                f"system = sweep.DeclaredSystem(declaration, {arguments})"]
    return [f"system = sweep.{type(system).__name__}({arguments})"]


def _declaration_python(declaration) -> list[str]:
    """``declaration = SystemDeclaration(...)``, a field per line and a coordinate or
    parameter per line."""
    out = ["declaration = SystemDeclaration("]
    for field in dataclasses.fields(declaration):
        value = getattr(declaration, field.name)
        if field.name in ("coordinates", "parameters"):
            out.append(f"    {field.name}=(")
            out += [f"        {item!r}," for item in value]
            out.append("    ),")
        else:
            out.append(f"    {field.name}={value!r},")
    return [*out, ")"]


def _system_toml(system: System) -> list[str]:
    """The run file's ``[system]`` table (and subtables) of ``system``."""
    if isinstance(system, DeclaredSystem):
        from ..toml_declared import system_lines

        return system_lines(system, toml_value)
    out = ["[system]", f"kind = {toml_value(type(system).__name__)}"]
    out += [f"{SYSTEM_KEYS.get(k, k)} = {toml_value(v)}"
            for k, v in _constructor(system).items()]
    from ..toml_effects import system_effects_lines

    return out + system_effects_lines(system.effects, toml_value)


#: Points per initial-state axis of a driven system's pilot (`sweep.maps.pilot_catalogue`
#: over the home window): 21 x 21 starts found every attractor that the 200 x 200
#: double Kapitza map's starts stop on, in 0.24 s of its 9.9 s
#: (`benchmarks/system_basins.py`, 2-core AMD EPYC Zen 5).
SYSTEM_PILOT_POINTS = 21

#: The routes of a driven system's basins map (`State.catalogue`): stop each start on a
#: pilot's attractor catalogue, or run every start to ``t_end`` (the full strobe run).
SYSTEM_ROUTES = ("catalogue", "exact")

#: What a start of the catalogue route observes: the strobe samples that label the
#: starts the catalogue does not match, and the catalogue's match.
CATALOGUE_OBSERVE = ("strobe", "attractor")

#: Pixels per axis of a system's maps by default: the double pendulum's flip map of
#: examples/double_pendulum.toml takes 3.9 s at 400 x 400 and 1.3 s at 200 x 200
#: (`sweep.run` alone, warm, 2-core AMD EPYC Zen 5, 2026-11-27).
SYSTEM_RESOLUTION = 200


class SystemExplorer(Explorer):
    """`Explorer` of a system with several coordinates (see the module docstring).

    Parameters
    ----------
    system : sweep.DoublePendulum, sweep.CoupledPendula or sweep.DeclaredSystem
    grid : sweep.Grid
        Its first two axes with more than one value are the map's x and y (else the
        first two angles' initial values); every axis must be one of the system's
        (`axes`). One-value axes set the start or a parameter.
    quantity : str, optional
        A key of `system_quantities` (default: ``basins`` for a driven system whose
        ``observe`` asks for ``attractor`` or ``strobe``, as a run file of its basins
        does, else ``log10:flip_time``); a driven system's ``basins`` and ``period`` run
        as `driven_quantities` says.
    resolution : int, default `SYSTEM_RESOLUTION` (200)
        Pixels per axis: a quarter of the pendulum's 400 x 400, since a system's step
        costs several of the pendulum's.
    cache, **run_kwargs
        As `Explorer`.

    Raises
    ------
    InvalidInput
        An axis the system does not have, or a value sweep's validators refuse.
    TypeError
        Not a system this explorer takes, or a keyword `sweep.run` does not take.
    """

    def __init__(self, system: System, grid: Grid, *, quantity: str | None = None,
                 resolution: int = SYSTEM_RESOLUTION, cache: OrderedDict | None = None,
                 **run_kwargs) -> None:
        if not isinstance(system, self.takes):
            takes = self.takes if isinstance(self.takes, tuple) else (self.takes,)
            raise TypeError(f"{type(self).__name__} takes a "
                            f"{' or a '.join(t.__name__ for t in takes)}, got "
                            f"{type(system).__name__}; sweep.explore takes a sweep.Scene, "
                            "a sweep.DoublePendulum, a sweep.CoupledPendula, a "
                            "sweep.DeclaredSystem or a sweep.SwingNetwork")
        check_arguments(grid, run_kwargs)
        self._registry = self._quantities_of(system)
        initial = self._start_names(system)
        offered = self._axes_of(system)
        for name in grid.dims:
            if name not in offered and name not in initial:
                raise InvalidInput("grid", f"grid axis {name!r} is not an axis of "
                                   f"{type(system).__name__}; accepted: "
                                   f"{', '.join(dict.fromkeys((*offered, *initial)))}")
        x, y, ranges, start, fixed = self._home(system, grid, self._preferred_axes(system),
                                                initial)
        try:
            if fixed:
                system = self._with_parameters(system, fixed)
        except (ValueError, TypeError) as exc:
            raise InvalidInput("grid", " ".join(str(exc).split())) from None
        chosen = quantity
        if chosen is None:  # a run of a driven system's basins opens on its basins
            observed = run_kwargs.get("observe") or ()
            observed = (observed,) if isinstance(observed, str) else tuple(observed)
            chosen = "basins" if "basins" in self._registry and \
                {"attractor", "strobe"} & set(observed) else \
                default_system_quantity(self._registry)
        extra = tuple((k, run_kwargs[k]) for k in PASSTHROUGH if k in run_kwargs)
        state = State(scene=system, view=View(x, y, ranges[x], ranges[y]), quantity=chosen,
                      t_end=run_kwargs["t_end"], dt=run_kwargs["dt"],
                      t_transient=run_kwargs.get("t_transient", 0.0),
                      method=run_kwargs.get("method", "rk4"), resolution=resolution,
                      start=start, extra=extra, device=run_kwargs.get("device", "cpu"))
        self.validate(state, "explore")
        self.state = state
        self.home = state.view
        self._history = [state.view]
        self._position = 0
        self._cache = OrderedDict() if cache is None else cache
        self._catalogues = OrderedDict()
        self._costs = OrderedDict()
        from .model import COMPUTE_LOCK

        self._lock = COMPUTE_LOCK

    #: The systems this explorer takes.
    takes = (DoublePendulum, CoupledPendula, DeclaredSystem)

    # -- what the declaration gives ------------------------------------------------
    @staticmethod
    def _quantities_of(system: System) -> dict[str, Quantity]:
        return system_quantities(system)

    @staticmethod
    def _start_names(system: System) -> list[str]:
        """The axes of a start (set by controls where they are not on the map)."""
        return [p.axis for p in initial_parameters(system.declaration)]

    @staticmethod
    def _preferred_axes(system: System) -> list[str]:
        """The map's axes where the grid does not vary two: the first two angles."""
        angles = [f"{c.name}_0" for c in system.declaration.coordinates]
        return angles + [p.axis for p in initial_parameters(system.declaration)]

    @staticmethod
    def _axes_of(system: System) -> tuple[str, ...]:
        return system.columns(True)

    def series_names(self) -> tuple[list[str], list[str]]:
        """Names of the positions and of the velocities a click gives over time."""
        coordinates = self.state.scene.declaration.coordinates
        return [c.name for c in coordinates], [c.velocity for c in coordinates]

    def axis_units(self) -> dict[str, str]:
        """UDUNITS units of every axis."""
        system = self.state.scene
        units = {p.axis: p.units for p in initial_parameters(system.declaration)}
        units.update({p.axis: p.units for p in system.declaration.parameters})
        units["damping"] = SYSTEM_DAMPING.units
        return units

    def axes(self) -> tuple[str, ...]:
        """The system's grid axes: initial values and velocities, its parameters and
        the damping rate (`sweep.physics.system.system_columns`)."""
        return self._axes_of(self.state.scene)

    def quantities(self) -> dict[str, str]:
        """``{name: label}`` of `system_quantities`."""
        return {q.name: q.label for q in self._registry.values()}

    def quantity_info(self, name: str) -> Quantity:
        return self._registry[name]

    def label_at(self, result: MapResult, row: int, col: int) -> str:
        """`Explorer.label_at` for a discrete map; a continuous map's value as
        ``"log10_flip_time = 0.768651 log10(s)"`` (name, value, units: no label), a NaN
        cell's as ``"log10_flip_time = NaN"`` (grey on the map: `NAN_NOTE`)."""
        if result.legend:
            return super().label_at(result, row, col)
        name, _, units = result.title.partition(" [")
        units = units.removesuffix("]")
        value = result.values[row, col]
        return f"{name} = {number_text(value)}" + \
            (f" {units}" if units and np.isfinite(value) else "")

    def _image(self, state: State, ds, preview: bool, catalogue) -> MapResult:
        """`Explorer._image`; a log10 map's colour-bar title gives the log10's units
        (``"log10_flip_time [log10(s)]"``: the DataArray's own units are ``"1"``), and
        a continuous map with NaN cells says in its caption what their grey is
        (`MapResult.comment`: the flip map's "NaN where none flipped before t_end;
        grey on the map: NaN")."""
        result = super()._image(state, ds, preview, catalogue)
        if not result.legend and np.isnan(result.image).any():
            result.comment = "; ".join(filter(None, (result.comment, NAN_NOTE)))
        if state.quantity.startswith("log10:"):
            result.title += _log10_units(str(ds[state.quantity[6:]].attrs.get("units", "")))
        return result

    @staticmethod
    def _default_range(system: System, name: str) -> tuple[float, float]:
        initial = {p.axis: p for p in initial_parameters(system.declaration)}
        if name in initial:
            coordinate = next(c for c in system.declaration.coordinates
                              if name in (f"{c.name}_0", f"{c.velocity}_0"))
            if name == f"{coordinate.name}_0":
                return (-math.pi, math.pi) if coordinate.angular else (-1.0, 1.0)
            gravity = getattr(system, "gravity", None)
            length = getattr(system, "length1", getattr(system, "length", None))
            w = math.sqrt(gravity / length) if gravity and length else 1.0
            return (-2.0 * w, 2.0 * w)
        value = system.parameters().get(name, 1.0)
        return (0.5 * value, 1.5 * value) if value else (0.0, 1.0)

    def parameter_controls(self) -> list[Control]:
        """One control per parameter of the system's declaration and the damping rate
        (units, long name, bound), then the initial values not on the map's axes."""
        system, shown = self.state.scene, (self.state.view.x, self.state.view.y)
        values = system.parameters()
        out = []
        for p in tuple(system.declaration.parameters) + (SYSTEM_DAMPING,) + \
                _effect_parameters(system):
            bound = ""
            if p.minimum is not None:
                bound = f" ({'>' if p.strict else '>='} {p.minimum:g})"
            note = " (on the map's axis)" if p.axis in shown else ""
            out.append(Control(p.axis, f"{p.axis} [{p.unit_text}]", "float",
                               float(values[p.axis]), minimum=p.minimum, strict=p.strict,
                               help=f"{p.long_name}{bound}{note}", group="scene"))
        from ..plot import units_text

        info = {p.axis: p for p in initial_parameters(system.declaration)}
        for name, value in self.state.start:
            if name in shown:
                continue
            p = info[name]
            out.append(Control(name, f"{name} [{units_text(p.units)}]", "float", float(value),
                               help=f"{p.long_name} (the start where it is not an axis)",
                               group="scene"))
        return out

    def run_controls(self) -> list[Control]:
        """t_end, dt, t_transient, method (the fixed-step explicit ones a system takes)
        and resolution."""
        s = self.state
        low, high = RESOLUTION_RANGE
        methods = tuple(n for n, m in METHODS.items() if not m.adaptive and m.kind == "explicit")
        return [
            Control("t_end", "t_end [s]", "float", float(s.t_end), minimum=0.0, strict=True,
                    help="final time; t_end - t0 a whole number of steps dt", group="run"),
            Control("dt", "dt [s]", "float", float(s.dt), minimum=0.0, strict=True,
                    help="time step", group="run"),
            Control("t_transient", "t_transient [s]", "float", float(s.t_transient),
                    minimum=0.0, help="lyapunov_max starts after it; a driven system's "
                    "strobe samples are counted from it", group="run"),
            Control("method", "method", "choice", s.method, choices=methods,
                    help="fixed-step explicit integrator (what a system takes)", group="run"),
            Control("resolution", "resolution [pixels per axis]", "int", int(s.resolution),
                    minimum=low, help=f"an integer from {low} to {high}", group="run"),
        ] + ([Control("route", "driven basins route", "choice",
                      SYSTEM_ROUTES[0] if s.catalogue else SYSTEM_ROUTES[1],
                      choices=SYSTEM_ROUTES,
                      help=f"catalogue: a {self.pilot_points} x {self.pilot_points} pilot "
                      "over the home window catalogues the attractors, then each start "
                      "stops once its strobe points follow a catalogued orbit 3 periods "
                      "running (over two initial-state axes, on the CPU); exact: every "
                      "start runs to t_end and maps.basins labels its last samples",
                      group="run")]
             if "basins" in self._registry else [])

    @staticmethod
    def _with_parameters(system: System, values: dict[str, float]) -> System:
        """``system`` with parameter values replaced (validated by its constructor)."""
        from ..physics.effects import Damping

        changes = {}
        names = [p.axis for p in system.declaration.parameters]
        on_one = {p.axis for p in _effect_parameters(system)}
        effects = tuple(system.effects)
        for name, value in values.items():
            if name == "damping":
                # the mass-proportional damping; effects on one coordinate stay
                effects = tuple(e for e in effects if e.coordinate is not None) + \
                    ((Damping(value),) if value else ())
                changes["effects"] = effects
            elif name in on_one:
                effects = _with_effect_value(effects, name, value)
                changes["effects"] = effects
            elif name in names:
                changes[name] = value
            else:
                accepted = names + ["damping"] + sorted(on_one)
                raise ValueError(f"{name}: not a parameter of {type(system).__name__}; "
                                 f"accepted: {', '.join(accepted)}")
        return _replaced(system, changes)

    # -- validation and updates ------------------------------------------------------
    def _check_quantity(self, state: State) -> None:
        """Refuse a quantity that is not a map of the system (`Explorer.validate`); a
        driven system's map asked of an undriven one says what would drive it."""
        if state.quantity not in self._registry:
            why = ""
            if state.quantity in driven_quantities() and \
                    not isinstance(state.scene, SwingNetwork):
                why = (f" (a {state.quantity} map reads the samples once per period of "
                       "a periodic drive, and it has none: drive it, e.g. "
                       "sweep.DoublePendulum(..., pivot_amplitude=a, pivot_frequency=nu), "
                       "effects=(sweep.Forcing(A, W, on='theta1'),), or "
                       "sweep.DeclaredSystem(..., drive_frequency_axis=...))")
            raise ValueError(f"quantity {state.quantity!r} is not a map of "
                             f"{type(state.scene).__name__}{why}; accepted: "
                             f"{', '.join(self._registry)}")

    def validate(self, state: State, control: str) -> State:
        """`Explorer.validate` (the checks `sweep.run` makes, a ``dt`` that does not
        divide the drive period included), and for a map of the stroboscopic samples
        (`driven_quantities`) a ``t_end`` that reaches all ``strobe_samples`` of them
        after ``t_transient``, at the longest drive period of the map."""
        state = super().validate(state, control)
        if "strobe" in self._registry[state.quantity].observe:
            try:
                self._check_samples(state)
            except ValueError as exc:
                raise InvalidInput(control, str(exc)) from None
        return state

    def _check_samples(self, state: State) -> None:
        """Refuse a run whose samples (every ``P`` steps from step ``n_transient`` up to
        ``n_steps``, ``P`` steps a drive period) are fewer than ``strobe_samples``."""
        kwargs = self.run_kwargs(state)
        samples = int(kwargs.get("strobe_samples", STROBE_SAMPLES))
        settings = validate_settings(t_end=state.t_end, dt=state.dt,
                                     t0=kwargs.get("t0", 0.0), t_transient=state.t_transient,
                                     save_every=None, method=state.method)
        drive = state.scene.drive_frequency_parameter.axis
        grid = self.grid(state)
        nu = float(np.min(grid.axes[drive])) if drive in grid.axes else \
            float(state.scene.parameters()[drive])
        steps = round(2 * math.pi / (nu * state.dt))  # whole: sweep.run checked it
        reached = (settings.n_steps - settings.n_transient) // steps + 1
        if reached < samples:
            needed = settings.t0 + (settings.n_transient + (samples - 1) * steps) * state.dt
            raise ValueError(
                f"t_end = {state.t_end!r} s reaches {reached} of the strobe_samples = "
                f"{samples} samples of the {state.quantity} map (one per drive period "
                f"2 pi / {drive} = {steps * state.dt:.6g} s, from t_transient = "
                f"{state.t_transient!r} s; {drive} = {nu!r} rad/s); accepted: t_end >= "
                f"{needed:.6g} s, and more to let the starts settle")

    def update(self, **changes) -> State:
        """`Explorer.update` (``model`` is the single pendulum's and is refused); a
        driven system's ``route`` is one of `SYSTEM_ROUTES` (`State.catalogue`)."""
        if "model" in changes:
            raise InvalidInput("model", f"model: {type(self.state.scene).__name__} has no "
                               "model choice; accepted: its parameters, "
                               f"{', '.join(c.name for c in self.parameter_controls())}")
        route = changes.pop("route", None)
        if route is not None:
            if "basins" not in self._registry:
                raise InvalidInput("route", f"route: {type(self.state.scene).__name__} has "
                                   "no basins map to route (it has no periodic drive); "
                                   "accepted: no route")
            if route not in SYSTEM_ROUTES:
                raise InvalidInput("route", f"route must be one of "
                                   f"{', '.join(SYSTEM_ROUTES)}, got {route!r}")
        state = super().update(**changes) if changes else self.state
        if route is not None:
            self.state = dataclasses.replace(state, catalogue=route == SYSTEM_ROUTES[0])
        return self.state

    # -- the catalogue route of a driven system's basins ------------------------------
    #: Points per initial-state axis of the pilot (`SYSTEM_PILOT_POINTS`).
    pilot_points = SYSTEM_PILOT_POINTS

    def uses_pilot(self, state: State | None = None) -> bool:
        """Whether ``state``'s map takes the catalogue route: a driven system's basins
        (`driven_quantities`) over two of its initial-state axes (a catalogue holds one
        system's attractors: `sweep.system_attractors.initial_axes`), on the CPU (the
        systems' CUDA kernel takes no catalogue), with ``state.catalogue`` on."""
        state = state or self.state
        q = self._registry.get(state.quantity)
        return bool(q is not None and q.pilot and state.catalogue and state.device == "cpu"
                    and {state.view.x, state.view.y} <= set(initial_axes(state.scene)))

    def pilot_state(self, state: State | None = None) -> State:
        """The state whose grid is the pilot: ``state`` with the home window (with the
        map's axes if they are not the home's: their `reset` window) at
        `pilot_points` pixels per axis, so that every zoom, pan and resolution of a
        window reuses one catalogue (`Explorer.catalogue` keys it on this state's
        system, run settings and start)."""
        state = state or self.state
        v = state.view
        if (v.x, v.y) == (self.home.x, self.home.y):
            view = self.home
        else:
            view = View(v.x, v.y, self._axis_range(state, v.x), self._axis_range(state, v.y))
        return dataclasses.replace(state, view=view, resolution=self.pilot_points)

    def uses_known(self, state: State | None = None) -> bool:
        """Never: known cells are the single pendulum's (`sweep.maps.known`)."""
        return False

    def map_kwargs(self, state: State, catalogue: dict | None) -> dict:
        """`sweep.run` keyword arguments of the map run: `run_kwargs`, and on the
        catalogue route (``catalogue`` given) ``observe=CATALOGUE_OBSERVE``,
        ``attractors=catalogue`` and ``stop_early=True``: a start stops once its
        strobe points follow a catalogued orbit `sweep.observables.ATTRACTOR_MATCHES`
        periods running, and `sweep.maps.basins` lets it stand for that orbit's ring;
        a start never matched runs to ``t_end`` with the very samples of the exact
        route, so it is labelled as there (an attractor the pilot missed included)."""
        kwargs = self.run_kwargs(state)
        if catalogue is not None:
            kwargs.update(observe=CATALOGUE_OBSERVE, attractors=catalogue, stop_early=True)
        return kwargs

    def _route(self, state: State, ds, catalogue, known) -> str:
        """Which route made a driven system's basins map, in words, with how many
        starts the catalogue stopped (the page's status line); "" for other maps."""
        if state.quantity != "basins" or "basins" not in self._registry:
            return ""
        v = state.view
        n = int(np.prod([ds.sizes[d] for d in ds.dims if d in (v.x, v.y)]))
        if catalogue is not None:
            stopped = int(np.sum(np.asarray(ds["attractor"].values) >= 0))
            p = self.pilot_points
            return (f"catalogue route ({p} x {p} pilot, {len(catalogue['period'])} "
                    f"attractors): {stopped} of {n} starts stopped on the catalogue")
        why = ""
        if state.catalogue:
            varied = [a for a in (v.x, v.y) if a not in initial_axes(state.scene)]
            why = (f" (the map varies {', '.join(varied)}: a catalogue holds one "
                   "system's attractors)") if varied else \
                " (the GPU's kernel takes no catalogue)" if state.device != "cpu" else ""
        return f"exact route{why}: {n} starts run to t_end"

    def toml_text(self, state: State | None = None) -> str:
        """`Explorer.toml_text`; on the catalogue route the exact route's run file with a
        note that says so (the Python snippet is the catalogue route): a run file's
        ``pilot = N`` thins the map's own grid, not the explorer's home window, so its
        catalogue, and the labels it gives starts not settled by ``t_end``, would not
        be the page's."""
        state = state or self.state
        if not self.uses_pilot(state):
            return super().toml_text(state)
        first, rest = super().toml_text(dataclasses.replace(state, catalogue=False)) \
            .split("\n", 1)
        p = self.pilot_points
        note = (f"# the explorer drew this map by the catalogue route (a {p} x {p} pilot "
                "over the home window, then each start stopped on a\n# catalogued "
                "attractor: the Python snippet); a run file's pilot = N thins this map's "
                "own grid,\n# not the home window, so its catalogue would differ, and with "
                "it the labels of starts not settled by t_end;\n# this file runs the exact "
                "route: the same labels but where the catalogue labelled a start that had "
                "not settled by t_end")
        return f"{first}\n{note}\n{rest}"

    # -- one trajectory -----------------------------------------------------------------
    def trajectory(self, x: float, y: float, result: MapResult | None = None,
                   state: State | None = None) -> SystemTrajectory:
        """The trajectory of the map's start nearest ``(x, y)`` (snapped to the pixel
        centre of ``result`` when given): every coordinate and velocity over time, from
        one `sweep.run` of the system with ``save_every`` (at most `TRAJECTORY_SAMPLES`
        samples)."""
        state, x, y, label = self.clicked(x, y, result, state)
        v = state.view
        axes = {name: np.array([value]) for name, value in state.start}
        axes[v.x] = np.array([x])
        axes[v.y] = np.array([y])
        kwargs = dict(t_end=state.t_end, dt=state.dt, t_transient=state.t_transient,
                      method=state.method, **dict(state.extra))
        steps = int(round((state.t_end - kwargs.get("t0", 0.0)) / state.dt))  # noqa: RUF046 - NumPy 1.x
        kwargs["save_every"] = max(1, math.ceil(steps / TRAJECTORY_SAMPLES))
        kwargs["observe"] = self.trajectory_observe
        if state.device != "cpu":
            kwargs["device"] = state.device
        with self._lock, warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            ds = self._run(state, Grid(**axes), kwargs)
        one = {d: 0 for d in ds.status.dims}
        status = Status(int(ds.status.isel(one)))
        status_text = "ok" if status == Status.OK else f"{status.name.lower()}: {status.message}"
        series, units = self._series(ds, one)
        grid = Grid(**axes)
        return SystemTrajectory(
            start={n: float(axes[n][0]) for n, _ in state.start}, point={v.x: x, v.y: y},
            t=np.asarray(ds.time.values), series=series, units=units,
            status=status_text, label=label or self._end_label(ds, one),
            python=self._python(state, grid, kwargs, None, trajectory=True),
            toml=self._toml(state, axes, kwargs, pilot=False,
                            comment=f"one trajectory of the explorer's map, from "
                                    f"{v.x} = {x!r}, {v.y} = {y!r}"))

    #: What a click's run observes besides ``save_every`` (`_end_label` reads it).
    trajectory_observe = ("final", "winding")

    def _series(self, ds, one: dict) -> tuple[dict, dict]:
        """``(series, units)`` of a click's run: every coordinate, then every velocity."""
        positions, velocities = self.series_names()
        names = positions + velocities
        return ({n: np.asarray(ds[n].isel(one).values) for n in names},
                {n: str(ds[n].attrs.get("units", "")) for n in names})

    def _end_label(self, ds, one: dict) -> str:
        """What a click's run ended in, where no map was clicked: the windings."""
        return ", ".join(f"winding_{c.name} = {int(ds[f'winding_{c.name}'].isel(one))}"
                         for c in self.state.scene.declaration.coordinates if c.angular)

    # -- reproduction -------------------------------------------------------------------
    @staticmethod
    def _python(state: State, grid: Grid, kwargs: dict, quantity: Quantity | None, *,
                pilot: Grid | None = None, trajectory: bool = False) -> str:
        """The snippet; with ``pilot`` (the catalogue route) the pilot's catalogue over
        that grid first, then the map's run by it (`SystemExplorer.map_kwargs`)."""
        lines = ["import numpy as np", "import sweep"]
        if quantity is not None and "maps." in quantity.expression:
            lines.append("from sweep import maps")
        lines += ["", *_system_python(state.scene),
                 f"grid = {grid_text(grid)}",
                 f"kwargs = dict({', '.join(f'{k}={v!r}' for k, v in kwargs.items())})"]
        if pilot is not None:
            p = SYSTEM_PILOT_POINTS
            lines += [f"home = {grid_text(pilot)}  # the pilot: {p} x {p} starts over the "
                      "home window",
                      f"catalogue = maps.pilot_catalogue(system, home, {p}, **kwargs)",
                      f"kwargs.update(observe={CATALOGUE_OBSERVE!r}, attractors=catalogue, "
                      "stop_early=True)"]
        lines.append("ds = sweep.run(system, grid, **kwargs)")
        if trajectory:
            lines.append("# every coordinate and velocity over ds.time (save_every)")
        elif quantity is not None:
            lines.append(f"image = {quantity.expression}")
        return "\n".join(lines) + "\n"

    @staticmethod
    def _toml(state: State, axes: dict, kwargs: dict, *, pilot: bool, comment: str) -> str:
        out = [f"# {comment}", "# written by sweep explore; run: sweep run THIS.toml -o OUT.nc",
               "", *_system_toml(state.scene)]
        written, grid = grid_lines(axes)
        out += ["", "[grid]", *written, "", "[run]",
                *run_lines(kwargs, state.scene, grid, toml_value)]
        return "\n".join(out) + "\n"
