"""The scene an attractor catalogue was computed for, recorded in the catalogue and
checked against a run that uses it.

A catalogue holds the attractors of one scene: with another forcing amplitude, damping,
gravity or length its orbits are not the run's, so no start would match one (every
label -1, and no trajectory stopped early) or, worse, a start would stop on an orbit
that is no longer an attractor. A strobe run records its parameters of one value (those
with one value over its grid, besides the initial state and the drive's frequency and
phase constant, which `sweep.strobe_phase` checks through the drive phase) in the
attribute ``strobe_scene`` (JSON); `sweep.maps.attractor_catalogue` copies them into the
catalogue as ``scene``, a structured array of one row per attractor and a float64 field
per parameter [its units] (so that selecting attractors, ``catalogue[key][keep]``, keeps
it; a mapping of parameter names to values is accepted too), and `check_scene` refuses,
before any compute, a run whose value of one of them differs beyond `SCENE_RTOL`, or
that has a parameter the catalogue's scene has not (or lacks one it has), unless that
parameter is 0 (an effect registered in one session only, absent: 0). A dataset of
a run with a catalogue keeps it (``attractors_scene``, JSON) for
`sweep.io.run_arguments`.

Every route that builds its catalogue from its own scene passes: `sweep.maps.
pilot_catalogue` (``[run] pilot`` and ``--pilot`` of a run file, the explorer's pilot,
which its zooms reuse, `sweep.maps.refine`, `sweep.map_accuracy`, the boundary and known
cells), as it runs the pilot on the map's scene and grid (thinned in the initial state
only).

A catalogue without ``scene`` (built by hand, by an older sweep, or from a dataset
without ``strobe_scene``) is not checked: its scene is unknown, so the run is trusted,
as before. The single pendulum (`sweep.engine`) and a system (`sweep.engine_systems`)
share this module.
"""

from __future__ import annotations

import json

import numpy as np

__all__ = ["ATTRIBUTE", "FIELD", "PENDULUM_DRIVE", "PENDULUM_INITIAL", "SCENE_RTOL",
           "as_record", "attributes", "check_scene", "dataset_scene", "from_attributes",
           "grid_value", "one_value", "pendulum_values", "record_columns", "record_from_json",
           "record_json", "scene_values"]

#: The catalogue's key of its scene: a dict of parameter name to value.
FIELD = "scene"

#: The dataset attribute in which a strobe run records its parameters of one value.
ATTRIBUTE = "strobe_scene"

#: Relative tolerance of the comparison of a parameter's value. A parameter of the same
#: scene reaches the catalogue and the run as the same float64 (JSON and netCDF keep it
#: exactly), or through a unit conversion (deg -> rad in a run file: 1e-16 relative per
#: operation); 1e-9 admits any such rounding by seven orders of magnitude. Any other
#: value is another scene, and whether its attractors still lie within the matching
#: tolerance of the catalogue's cannot be told from the catalogue (near a bifurcation a
#: change of 1e-6 changes them), so it is refused.
SCENE_RTOL = 1e-9


def one_value(values) -> float | None:
    """The one distinct value of ``values`` (a grid axis's column, a dataset
    coordinate's values or attribute: a number or an array), or None where it holds
    several (or none)."""
    distinct = np.unique(np.asarray(values, dtype=np.float64))
    return float(distinct[0]) if distinct.size == 1 else None


def grid_value(grid, name: str, default: float) -> float:
    """The one value of ``grid``'s axis ``name`` (`one_value`), or ``default`` where
    ``grid`` has no such axis (the scene's or system's value of the parameter).

    Raises
    ------
    ValueError
        Where the axis has several values (a run with a catalogue never has: its grid
        varies the initial state only).
    """
    value = one_value(grid.axes.get(name, default))
    if value is None:
        raise ValueError(f"the grid's axis {name} has several values; accepted: one value "
                         "(a run with an attractor catalogue varies only its initial state)")
    return value


def scene_values(parameters: dict, grid, initial: tuple, drive: tuple = ()) -> dict:
    """The run's parameters of one value [their units]: ``parameters`` (the scene's or
    system's ``parameters()``) overridden by the grid's axes, each of the grid's axes
    that is not in ``initial`` (the initial state) and has one distinct value; neither
    the axes in ``drive`` (the drive's frequency and phase constant) nor those the grid
    varies."""
    values = {name: float(value) for name, value in parameters.items()}
    for name, column in grid.axes.items():
        value = one_value(column)
        if value is not None:
            values[name] = value
        else:
            values.pop(name, None)
    return {name: value for name, value in sorted(values.items())
            if name not in initial and name not in drive}


#: The single pendulum's initial state and its drive's frequency and phase constant:
#: the axes that are never of its scene (`pendulum_values`).
PENDULUM_INITIAL, PENDULUM_DRIVE = ("theta0", "omega0"), ("forcing_frequency", "forcing_phase")


def pendulum_values(scene, grid) -> dict:
    """`scene_values` of a single pendulum's run: ``scene`` (a `sweep.Scene`) over
    ``grid``, without ``theta0`` and ``omega0`` and the forcing's frequency and phase
    constant."""
    return scene_values(scene.parameters(), grid, PENDULUM_INITIAL, PENDULUM_DRIVE)


def as_record(values: dict, count: int) -> np.ndarray:
    """``values`` (parameter name to value) as the catalogue's ``scene``: a structured
    array of ``count`` equal rows, one float64 field per parameter, so that selecting
    attractors (``catalogue[key][keep]``) keeps it."""
    dtype = [(str(name), np.float64) for name in values]
    return np.array([tuple(float(v) for v in values.values())] * count, dtype=dtype)


def record_columns(given) -> dict | None:
    """A catalogue's record of named values (a structured array of a field per name, or
    a mapping of names to values) as a dict of name to its float64 values (1-D), or
    None where it is neither or holds a value that is not finite (the caller refuses
    it, naming its field)."""
    try:
        if isinstance(given, np.ndarray) and given.dtype.names is not None:
            columns = {name: np.asarray(given[name], dtype=np.float64).ravel()
                       for name in given.dtype.names}
        else:
            columns = {str(name): np.atleast_1d(np.asarray(value, dtype=np.float64)).ravel()
                       for name, value in dict(given).items()}
    except (TypeError, ValueError):
        return None
    return columns if all(np.all(np.isfinite(v)) for v in columns.values()) else None


def _recorded(attractors) -> dict | None:
    """The catalogue's scene as a dict of parameter name to its float64 values (one per
    attractor, or one), or None without one; refuses anything else (not finite)."""
    given = attractors.get(FIELD) if hasattr(attractors, "get") else None
    if given is None:
        return None
    scene = record_columns(given)
    if scene is None:
        raise ValueError(f"attractors: a catalogue's {FIELD} {given!r}; accepted: the "
                         "parameters' values as sweep.maps.attractor_catalogue records "
                         "them (a structured array, a field per parameter), a mapping of "
                         "parameter names to finite values, or none (unchecked)")
    return scene


def check_scene(attractors, values: dict) -> None:
    """Refuse (ValueError, before any compute) a catalogue computed for another scene
    than the run's parameters of one value ``values`` (`scene_values`); nothing for a
    catalogue that records no scene."""
    scene = _recorded(attractors)
    if scene is None:
        return
    fix = ("or a catalogue of this scene (sweep.maps.pilot_catalogue with this run's "
           "scene and settings)")
    for name in sorted(set(scene) | set(values)):
        recorded, own = scene.get(name), values.get(name)
        # a parameter only one side knows, at 0 there: an effect registered in one
        # session only (sweep.physics.register), absent from the scene, whose parameters
        # are 0 and never read (Scene.parameters); nothing to compare
        if (recorded is None and own == 0.0) or (own is None and np.all(recorded == 0.0)):
            continue
        if recorded is None:
            raise ValueError(f"attractors: this run's {name} = {own!r}, but the catalogue "
                             f"was computed for a scene without {name} (a catalogue holds "
                             f"the attractors of one scene); accepted: a run without "
                             f"{name}, {fix}")
        built = float(recorded[np.argmax(np.abs(recorded - (own or 0.0)))])  # the worst
        if own is None:
            raise ValueError(f"attractors: the catalogue was computed for {name} = "
                             f"{built!r}, and this run has no one value of {name} (a "
                             f"catalogue holds the attractors of one scene); accepted: "
                             f"{name} = {built!r}, {fix}")
        if abs(own - built) > SCENE_RTOL * max(abs(own), abs(built)):
            raise ValueError(f"attractors: the catalogue was computed for {name} = "
                             f"{built!r}, but this run's {name} = {own!r} (a catalogue "
                             f"holds the attractors of one scene); accepted: {name} = "
                             f"{built!r} (within {SCENE_RTOL:g} relative), {fix}")


def attributes(attractors) -> dict:
    """The catalogue's scene as a dataset attribute (``attractors_scene``: JSON of each
    parameter's values), or ``{}`` where it records none."""
    scene = _recorded(attractors)
    if scene is None:
        return {}
    return {f"attractors_{FIELD}": record_json(scene)}


def from_attributes(attrs) -> dict:
    """The catalogue's scene from dataset attributes (`attributes`), ``{"scene": ...}``
    (a structured array, as `as_record` makes), or ``{}`` without it."""
    key = f"attractors_{FIELD}"
    record = record_from_json(attrs[key]) if key in attrs else None
    return {} if record is None else {FIELD: record}


def record_json(columns: dict) -> str:
    """A catalogue's record of named values (`record_columns`: name -> float64 values)
    as a dataset attribute: JSON of each name's values."""
    return json.dumps({name: np.asarray(values).tolist() for name, values in columns.items()})


def record_from_json(text: str) -> np.ndarray | None:
    """The record `record_json` wrote, as the structured array `as_record` makes (a row
    per attractor, a float64 field per name), or None where it names nothing."""
    columns = {name: np.atleast_1d(np.asarray(values, dtype=np.float64))
               for name, values in json.loads(text).items()}
    if not columns:
        return None
    record = np.zeros(max(v.size for v in columns.values()),
                      dtype=[(name, np.float64) for name in columns])
    for name, values in columns.items():
        record[name] = values
    return record


def dataset_scene(ds, count: int, initial: tuple = (), drive: tuple = ()) -> dict:
    """``{"scene": ...}`` (`as_record`, ``count`` rows) of a strobe run's dataset ``ds``
    (its attribute ``strobe_scene``), for its catalogue, or ``{}`` without it.

    A grid axis the run varied, so not in ``strobe_scene``, that has one value in ``ds``
    (a slice of the run: ``ds.sel(forcing_amplitude=1.3)``) is of the slice's scene
    too, and is added; ``initial`` and ``drive`` name the axes that never are (the
    initial state, the drive's frequency and phase constant: `scene_values`). Without
    it a catalogue of such a slice had no ``forcing_amplitude``, and a run of
    ``forcing_amplitude = 1.3`` was refused as of another scene."""
    attrs = ds.attrs
    if ATTRIBUTE not in attrs:
        return {}
    values = dict(json.loads(attrs[ATTRIBUTE]))
    axes = str(attrs.get("grid_axes", attrs.get("point_axes", ""))).split()
    for name in axes:  # `sweep.Grid.provenance`, `sweep.Points.provenance`
        if name in values or name in initial or name in drive or name not in ds.coords:
            continue
        value = one_value(ds[name].values)
        if value is not None:
            values[name] = value
    values = dict(sorted(values.items()))
    return {FIELD: as_record(values, count)} if values else {}
