"""Run files: a TOML description of a sweep -> ``(Scene, Grid or Points, run keyword
arguments)``.

A run file has three tables (``[points]`` instead of ``[grid]`` for a table of
parameter sets, `sweep.Points`)::

    [scene]                      # Scene.from_dict: gravity, length, model
    gravity = 9.81               # m/s^2
    [scene.damping]              # optional effect: [scene.<effect name>] with the
    coefficient = 0.5            # 1/s    effect's constructor arguments as keys
    [scene.forcing]              # optional effect
    amplitude = 1.2              # rad/s^2
    frequency = 0.6667           # rad/s
    phase = 0.0                  # rad

    [grid]                       # axes in dimension order; each axis is one of:
    theta0 = {start = -180, stop = 180, num = 361, units = "deg"}   # np.linspace
    omega0 = [0.0, 1.0, 2.0]                                        # a list
    damping = 0.5                                                   # one number
    forcing_phase = {values = [0, 90], units = "deg"}               # a list in degrees

    # or, instead of [grid]: one point per row, columns of one length (a number is a
    # constant column; units = "deg" as in [grid])
    [points]
    theta0 = {values = [10, 120, 170], units = "deg"}
    omega0 = [0.0, 0.5, -0.5]
    damping = 0.2
    # ... or the columns from a file (relative to the run file's folder): a CSV whose
    # header names the axes, or a netCDF whose variables named by axes lie along one
    # dimension; other keys add columns
    # file = "starts.csv"

    # or, instead of [grid]: points drawn in a box (sweep.sample), for basin fractions
    [sample]
    n = 20000                    # points (>= 1)
    seed = 1                     # the same seed gives the same points
    method = "sobol"             # scrambled Sobol ("sobol", default) or "random"
    theta0 = [-3.141592653589793, 3.141592653589793]   # a range [lo, hi] per axis
    omega0 = [-4.0, 4.0]
    damping = 0.2                # a number: a constant column

    [run]                        # keyword arguments of sweep.run
    t_end = 100.0                # s (required)
    dt = 0.01                    # s (required)
    t0 = 0.0                     # s
    t_transient = 80.0           # s
    # or, for a driven run, in drive periods 2 pi / W (sweep.toml_periods):
    # t_end = { periods = 26 }   # 26 periods [s]; likewise t0, t_transient
    # dt = { per_period = 1000 } # the period / 1000 [s] (divides it, for strobe)
    observe = ["final", "winding"]
    strobe_samples = 64          # samples kept by observe "strobe" (2 to 4096; 16)
    save_every = 10              # steps; stores theta(t), omega(t)
    method = "rk4"
    chunk_size = 1000            # trajectories per chunk (progress and checkpoints)
    scheduler = "tcp://HOST:8786"  # run the chunks on this Dask cluster (sweep run only)
    pilot = 41                   # forced maps: find the attractors on 41 x 41 starts
                                 # first, then stop each trajectory on a match
                                 # (sweep run only; sweep.maps.pilot_catalogue)
    refine = true                # sweep run only: write the labels of a 2-D map (a
                                 # [grid] of two varying axes) computing only what its
                                 # boundaries need (sweep.maps.refine)
    known_cells = true           # with pilot: coarse maps of the grid first, then stop
                                 # each trajectory on their settled cells (sweep run
                                 # only; sweep.run's known_cells; with refine too)
    refine_label = "basins"      # with refine: basins, motion, well, period, inverted,
                                 # or a variable of the run ("basins")
    refine_step = 16             # with refine: cells between lattice lines (>= 2; 16)

A system with several coordinates (docs/guide/systems.md) takes ``[system]`` in place
of ``[scene]``: ``kind`` names it, the other keys are its constructor's arguments, and
``[system.damping]`` adds `sweep.Damping`; its axes are the system's::

    [system]
    kind = "DoublePendulum"      # or "CoupledPendula", "SwingNetwork"
    mass1 = 1.0                  # kg (CoupledPendula: n, mass, length, coupling, coupling_kind,
    length2 = 0.5                # m   topology; SwingNetwork: edges or adjacency, power,
                                 #     damping, coupling)
    [grid]
    theta1_0 = {start = -3, stop = 3, num = 201}
    theta2_0 = {start = -3, stop = 3, num = 201}

A driven system's basins by an attractor catalogue take ``pilot = N`` with ``observe =
["attractor"]`` and ``stop_early = true`` (`sweep.toml_pilot`; ``sweep run`` runs
`sweep.maps.pilot_catalogue` of the system first).

``kind = "DeclaredSystem"`` declares a system in the file itself: its coordinates, its
parameters with their values and its Lagrangian as text (`sweep.toml_declared`); its
axes are ``<coordinate>_0``, ``<velocity>_0`` and the parameters' names.

``units = "deg"`` is accepted for the angle-like axes ``theta0`` (deg),
``omega0`` (deg/s), ``forcing_phase`` (deg) and any effect parameter declared as an
angle; values are converted to radians
with `sweep.from_degrees`. Every error is a ValueError (or TypeError for a wrong
type) whose message names the file, the table and the key.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ._validate import check_flag, check_keys, check_positive_int
from .engine import check_strobe_samples, validate_settings
from .grid import Grid, Points, from_degrees
from .kernels.spec import check_device, check_dtype
from .observables import DEFAULT_OBSERVE, resolve
from .physics import Scene, parameter_names, parameters
from .toml_effects import system_effects
from .toml_periods import resolve_periods

__all__ = ["OPTION_KEYS", "REFINE_MAPS", "RUN_KEYS", "SYSTEM_KINDS", "TABLES", "angle_axes",
           "check_scheduler",
           "load_run", "parse_run"]

#: Top-level tables of a run file (one of grid, points and sample; scene or system).
TABLES = ("scene", "grid", "run", "points", "sample", "system")

#: ``[system] kind`` -> the system's class name in `sweep.physics`.
SYSTEM_KINDS = ("DoublePendulum", "CoupledPendula", "SwingNetwork", "DeclaredSystem")

#: The tables that say which trajectories run (one of them).
ROWS_TABLES = ("grid", "points", "sample")

#: Keys of the ``[run]`` table (keyword arguments of `sweep.run`).
RUN_KEYS = ("t_end", "dt", "t0", "t_transient", "observe", "save_every", "method", "rtol",
            "atol", "chunk_size", "stop_early", "check_stability", "estimate_error",
            "scheduler", "device", "strobe_samples", "dtype", "pilot", "refine",
            "refine_label", "refine_step", "known_cells")

#: Keys of ``[run]`` that say where the run executes, not what it computes: returned
#: in ``options`` by `load_run`, never among the keyword arguments of `sweep.run`.
OPTION_KEYS = ("scheduler", "pilot", "refine", "refine_label", "refine_step", "known_cells")

#: ``refine_label`` names of `sweep.maps` functions (any other name: a variable).
REFINE_MAPS = ("basins", "motion", "well", "period", "inverted")

#: Keys of ``[run]`` that must be present.
REQUIRED_RUN_KEYS = ("t_end", "dt")

#: Accepted ``units`` of an angular velocity axis; the value says whether it means
#: degrees (per second).
_RATE_UNITS = {"rad/s": False, "rad": False, "deg/s": True, "deg": True}


def angle_axes() -> tuple[str, ...]:
    """Grid axes that accept ``units = "deg"``: the parameters declared as angles
    (theta0, omega0 in deg/s, forcing_phase, and any registered effect's)."""
    return tuple(p.axis for p in parameters() if p.angle)


def _angle_parameter(name: str):
    """The parameter of axis ``name`` if it is an angle (or an angular velocity): the
    single pendulum's or a system's; None otherwise (`sweep.physics.system.angle_parameter`)."""
    from .physics.system import angle_parameter

    return angle_parameter(name)


def _units(name: str) -> dict[str, bool]:
    """Accepted ``units`` of an angle axis; the value says whether it means degrees."""
    found = _angle_parameter(name)
    rate = name == "omega0" or (found is not None and found.units == "rad s-1")
    return _RATE_UNITS if rate else {"rad": False, "deg": True}

_RANGE_KEYS = ("start", "stop", "num")


def load_run(path, options: dict | None = None) -> tuple[Scene, Grid, dict[str, Any]]:
    """Read a TOML run file into the arguments of `sweep.run`.

    Parameters
    ----------
    path : str or Path
        The run file (UTF-8 TOML with tables ``[scene]``, ``[grid]``, ``[run]``;
        see the module docstring).
    options : dict, optional
        Receives the `OPTION_KEYS` the file gives (``scheduler``: the address of a
        Dask scheduler, which ``sweep run`` connects to). From Python, pass
        ``client=dask.distributed.Client(address)`` to `sweep.run` instead.

    Returns
    -------
    scene : Scene
    grid : Grid
    run_kwargs : dict
        Keyword arguments for `sweep.run` (``t_end`` and ``dt`` always present, the
        other keys of ``[run]`` when given), already validated; times given in drive
        periods (``{ periods = k }``, ``{ per_period = N }``) are in seconds
        (`sweep.toml_periods`).

    Raises
    ------
    ValueError
        If the file cannot be read or is not valid TOML (naming the file and the
        TOML error), on an unknown key (naming the key, its table and the accepted
        keys), a missing required key, or a bad value.
    TypeError
        On a value of the wrong type (a string where a number is expected, ...).

    Examples
    --------
    >>> scene, grid, kwargs = load_run("examples/forced.toml")   # doctest: +SKIP
    >>> ds = sweep.run(scene, grid, **kwargs)                    # doctest: +SKIP
    """
    path = Path(path)
    try:
        with open(path, "rb") as handle:
            spec = tomllib.load(handle)
    except OSError as exc:
        raise ValueError(f"cannot read run file {str(path)!r}: "
                         f"{exc.strerror or exc}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"run file {str(path)!r} is not valid TOML: {exc}") from None
    return parse_run(spec, source=str(path), options=options, folder=path.parent)


def parse_run(spec: dict[str, Any], source: str = "run file", options: dict | None = None,
              folder=None) -> tuple[Scene, Grid | Points, dict[str, Any]]:
    """Turn a parsed run file (nested dicts, as `tomllib` returns) into run arguments.

    Parameters
    ----------
    spec : dict
        ``{"scene": {...}, "grid": {...}, "run": {...}}``; ``scene`` may be omitted
        (the default `Scene`).
    source : str
        Where ``spec`` came from, put at the start of every error message.
    options : dict, optional
        As `load_run`.
    folder : str or Path, optional
        Where ``[points] file`` paths are relative to (the run file's folder; default
        the working directory).

    Returns
    -------
    scene, grid, run_kwargs
        As `load_run`.

    Raises
    ------
    ValueError, TypeError
        As `load_run`.
    """
    _check_keys(source, "top level of the file", spec, TABLES)
    given = [name for name in ROWS_TABLES if name in spec]
    if len(given) > 1:
        raise ValueError(f"{source}: both [{given[0]}] and [{given[1]}]; accepted: one of "
                         "them (a grid's Cartesian product, a table of points, or points "
                         "sampled in a box)")
    for name in ("grid", "run"):
        if name not in spec and not (name == "grid" and given):
            raise ValueError(f"{source}: missing table [{name}]; required tables: grid (or "
                             "points, or sample), run (scene is optional)")
    if "scene" in spec and "system" in spec:
        raise ValueError(f"{source}: both [scene] and [system]; accepted: one of them (the "
                         "single pendulum, or a system of several coordinates)")
    tables = {name: _table(source, name, spec.get(name, {})) for name in TABLES}
    scene = _system(source, tables["system"]) if "system" in spec else \
        _scene(source, tables["scene"])
    names = scene.accepted_axes() if "system" in spec else parameter_names()
    which = given[0] if given else "grid"
    grid = (_points(source, tables["points"], folder, names) if which == "points"
            else _sample(source, tables["sample"], names) if which == "sample"
            else _grid(source, tables["grid"], names))
    with _context(source, which):
        grid.check_against(scene)
    _check_keys(source, "[run]", tables["run"], RUN_KEYS)
    with _context(source, "run"):
        # times in drive periods -> seconds, from the scene's (system's) drive
        run_table = resolve_periods(tables["run"], scene, grid, which)
    kwargs = _run(source, run_table, system="system" in spec)
    found = {key: kwargs.pop(key) for key in OPTION_KEYS if key in kwargs}
    if "system" in spec:
        with _context(source, "run"):
            for key in ("refine", "known_cells"):
                if key in found:
                    raise ValueError(f"{key} is for the single pendulum's forced maps "
                                     "([scene]); accepted: [run] without it for a [system]")
            from .toml_pilot import check_system_pilot

            # the system's observables and options; a pilot's catalogue for 'attractor'
            check_system_pilot(scene, grid, found.get("pilot"), kwargs)
    if options is not None:
        options.update(found)
    return scene, grid, kwargs


def check_scheduler(name: str, address: Any) -> str:
    """Return ``address`` if it can name a Dask scheduler (``tcp://HOST:8786``,
    ``tls://...``, ``HOST:8786``): a non-empty string without spaces.

    Raises
    ------
    TypeError, ValueError
        Naming ``name``, the value and what is accepted.
    """
    accepted = "a Dask scheduler address such as 'tcp://HOST:8786'"
    if not isinstance(address, str):
        raise TypeError(f"{name} must be {accepted}, got {address!r}")
    if not address.strip() or any(c.isspace() for c in address.strip()) or \
            address.strip().endswith("://"):
        raise ValueError(f"{name} must be {accepted}, got {address!r}")
    return address.strip()


# ----------------------------------------------------------------------------- helpers
@contextmanager
def _context(source: str, table: str) -> Iterator[None]:
    """Prefix errors raised inside with the file and the table."""
    try:
        yield
    except (ValueError, TypeError) as exc:
        message = str(exc)
        where = "" if message.startswith(table) else f"[{table}] "
        kind = ValueError if isinstance(exc, ValueError) else TypeError
        raise kind(f"{source}: {where}{message}") from None


def _check_keys(source: str, where: str, table: dict, accepted) -> None:
    try:
        check_keys(table, accepted, f" in {where}")
    except ValueError as exc:
        raise ValueError(f"{source}: {exc}") from None


def _table(source: str, name: str, value: Any) -> dict:
    if not isinstance(value, dict):
        raise TypeError(f"{source}: {name} must be a table ([{name}]), got {value!r}")
    return value


def _scene(source: str, table: dict) -> Scene:
    """``[scene]`` -> Scene (via `Scene.from_dict`)."""
    with _context(source, "scene"):
        return Scene.from_dict(table)


def _system(source: str, table: dict):
    """``[system]`` -> a `sweep.physics.System`: ``kind`` names its class, the other keys
    are its constructor's arguments, ``[system.damping]`` a `sweep.Damping` (without
    ``on``: mass-proportional), and ``[system.<effect>]`` with ``on = "<coordinate>"``
    an effect on one coordinate (`sweep.toml_effects.system_effects`)."""
    import dataclasses

    from . import physics
    from .physics.coordinate_effects import acting_effects

    with _context(source, "system"):
        kind = table.get("kind")
        if kind not in SYSTEM_KINDS:
            raise ValueError(f"kind = {kind!r}; accepted: "
                             f"{', '.join(map(repr, SYSTEM_KINDS))}")
        if kind == "DeclaredSystem":
            from .toml_declared import declared_system

            return declared_system(table)
        cls = getattr(physics, kind)
        # a constructor argument named like the table's `kind` (CoupledPendula's spring
        # or torsion coupling) is written `coupling_kind` (`SYSTEM_KEYS`)
        renamed = {SYSTEM_KEYS.get(f.name, f.name): f.name for f in dataclasses.fields(cls)
                   if f.name != "effects"}
        fields = list(renamed)
        if kind == "SwingNetwork":
            fields = ["edges"] + fields
        effects = {cls.declaration.name: cls for cls in acting_effects()}
        accepted = ["kind"] + fields + (list(effects) if kind != "SwingNetwork" else [])
        check_keys(table, accepted, label=f"accepted for {kind}")
        arguments = {renamed.get(key, key): value for key, value in table.items()
                     if key != "kind"}
        if kind == "SwingNetwork":
            if ("edges" in arguments) == ("adjacency" in arguments):
                raise ValueError("a SwingNetwork needs edges = [[i, j], ...] or adjacency "
                                 "= [[...], ...]; accepted: one of them")
            arguments["adjacency"] = arguments.pop("edges", arguments.get("adjacency"))
        else:
            arguments["effects"] = system_effects(arguments, effects)
        return cls(**arguments)


#: ``[system]`` keys of constructor arguments whose own name the table takes: the
#: table's ``kind`` names the system, so `sweep.CoupledPendula`'s ``kind`` (``"spring"``
#: or ``"torsion"``) is ``coupling_kind``.
SYSTEM_KEYS = {"kind": "coupling_kind"}


def _grid(source: str, table: dict, names=None) -> Grid:
    """``[grid]`` -> Grid, axes in file order (``names``: the accepted axes, the single
    pendulum's by default)."""
    names = parameter_names() if names is None else names
    _check_keys(source, "[grid]", table, names)
    if not table:
        raise ValueError(f"{source}: [grid] has no axes; accepted axis names: "
                         f"{', '.join(names)}")
    axes = {name: _axis(source, name, value) for name, value in table.items()}
    with _context(source, "grid"):
        return Grid(**axes)


def _points(source: str, table: dict, folder, names=None) -> Points:
    """``[points]`` -> Points: columns as ``[grid]`` axes (a number is a constant
    column), and those of ``file`` (a CSV or netCDF of columns)."""
    names = parameter_names() if names is None else tuple(names)
    _check_keys(source, "[points]", table, names + ("file",))
    columns = {}
    if "file" in table:
        columns = _columns_file(source, table["file"], folder)
    for name, value in table.items():
        if name == "file":
            continue
        if name in columns:
            raise ValueError(f"{source}: [points] {name} is both a key and a column of "
                             f"{table['file']!r}; accepted: one of them")
        columns[name] = (float(value) if isinstance(value, (int, float))
                         and not isinstance(value, bool)
                         else _axis(source, name, value, "points"))
    if not columns:
        raise ValueError(f"{source}: [points] has no columns; accepted: axis names "
                         f"({', '.join(names)}) with lists of one length, or file")
    with _context(source, "points"):
        return Points(**columns)


#: Keys of ``[sample]`` besides the axes' ranges.
SAMPLE_KEYS = ("n", "seed", "method")


def _sample(source: str, table: dict, names=None) -> Points:
    """``[sample]`` -> `sweep.sample` (``n``, ``seed``, ``method``; per axis a range
    ``[lo, hi]`` or a number, a constant column)."""
    from .grid import sample

    names = parameter_names() if names is None else tuple(names)
    _check_keys(source, "[sample]", table, SAMPLE_KEYS + names)
    for key in ("n", "seed"):
        if key not in table:
            raise ValueError(f"{source}: [sample] needs {key}; accepted: n = points (an "
                             "int >= 1), seed = an int >= 0, method = \"sobol\" or "
                             "\"random\", and a range [lo, hi] per axis")
    ranges = {}
    for name, value in table.items():
        if name in SAMPLE_KEYS:
            continue
        if isinstance(value, list) and len(value) == 2:
            ranges[name] = tuple(value)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            ranges[name] = float(value)
        else:
            raise ValueError(f"{source}: [sample] {name} = {value!r}; accepted: a range "
                             "[lo, hi] (radians, rad/s and the parameters' own units) or "
                             "one number (a constant column)")
    with _context(source, "sample"):
        return sample(table["n"], seed=table["seed"], method=table.get("method", "sobol"),
                      **ranges)


def _columns_file(source: str, file: Any, folder) -> dict[str, np.ndarray]:
    """The columns of ``[points] file``: a CSV with a header of axis names, or a netCDF
    whose variables named by axes lie along one dimension."""
    if not isinstance(file, str) or not file:
        raise TypeError(f"{source}: [points] file must be a path (a string), got {file!r}")
    path = Path(folder or ".") / file
    where = f"{source}: [points] file {file!r}"
    if not path.is_file():
        raise ValueError(f"{where}: no such file {str(path)!r}; accepted: a CSV or netCDF "
                         "file, relative to the run file's folder")
    if path.suffix.lower() in (".nc", ".nc4", ".netcdf"):
        return _netcdf_columns(where, path)
    import csv

    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = [row for row in csv.reader(handle) if row]
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{where}: cannot read it: {exc}") from None
    if not rows:
        raise ValueError(f"{where} is empty; accepted: a header of axis names, then rows")
    header = [name.strip() for name in rows[0]]
    _check_keys(source, f"the header of {file!r}", dict.fromkeys(header), parameter_names())
    if len(rows) < 2:
        raise ValueError(f"{where} has a header but no rows; accepted: one row per point")
    values = np.empty((len(rows) - 1, len(header)))
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ValueError(f"{where}: line {i} has {len(row)} values, the header "
                             f"{len(header)}; accepted: one value per column")
        for j, cell in enumerate(row):
            try:
                values[i - 2, j] = float(cell)
            except ValueError:
                raise ValueError(f"{where}: line {i}, column {header[j]!r}: {cell!r} is not "
                                 "a number") from None
    return {name: values[:, j] for j, name in enumerate(header)}


def _netcdf_columns(where: str, path: Path) -> dict[str, np.ndarray]:
    import xarray as xr

    try:
        ds = xr.load_dataset(path)
    except (OSError, ValueError, RuntimeError) as exc:
        raise ValueError(f"{where}: cannot read it as netCDF: {exc}") from None
    found = {name: ds[name] for name in parameter_names() if name in ds.variables}
    dims = {variable.dims for variable in found.values()}
    if not found or len(dims) != 1 or len(next(iter(dims))) != 1:
        raise ValueError(f"{where}: variables named by axes ({', '.join(found) or 'none'}) "
                         f"along {sorted(dims) or 'no dimension'}; accepted: variables named "
                         "theta0, omega0, ... along one and the same dimension")
    return {name: variable.values for name, variable in found.items()}


def _axis(source: str, name: str, value: Any, table: str = "grid") -> np.ndarray | list:
    """One ``[grid]`` (or ``[points]``: ``table``) entry -> the values of that axis
    (radians for angles)."""
    if isinstance(value, (bool, str)):
        raise TypeError(f"{source}: [{table}] {name} must be a number, a list of numbers or "
                         f"a table {{start, stop, num}}, got {value!r}")
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, list):
        return _numbers(source, name, value, table)
    if not isinstance(value, dict):
        raise TypeError(f"{source}: [{table}] {name} must be a number, a list of numbers or "
                         f"a table {{start, stop, num}}, got {value!r}")
    return _axis_table(source, name, value, table)


def _numbers(source: str, name: str, values: list, table: str = "grid") -> list:
    for index, item in enumerate(values):
        if isinstance(item, bool) or not isinstance(item, (int, float)):
            raise TypeError(f"{source}: [{table}] {name}[{index}] must be a number, "
                             f"got {item!r}")
    return [float(item) for item in values]


def _axis_table(source: str, name: str, table: dict, kind: str = "grid") -> np.ndarray:
    """``{start, stop, num[, units]}`` or ``{values[, units]}`` -> axis values; errors
    name the table ``[kind.name]`` as the run file wrote it (``grid`` or ``points``)."""
    accepted = _RANGE_KEYS + ("values",) + (("units",) if _angle_parameter(name) else ())
    _check_keys(source, f"[{kind}.{name}]", table, accepted)
    if "values" in table:
        extra = [key for key in _RANGE_KEYS if key in table]
        if extra:
            raise ValueError(f"{source}: [{kind}.{name}] gives both 'values' and {extra[0]!r}; "
                             "accepted: either values or start, stop, num")
        if not isinstance(table["values"], list):
            raise TypeError(f"{source}: [{kind}.{name}] values must be a list of numbers, "
                             f"got {table['values']!r}")
        values = np.asarray(_numbers(source, f"{name}.values", table["values"], kind))
    else:
        missing = [key for key in _RANGE_KEYS if key not in table]
        if missing:
            raise ValueError(f"{source}: [{kind}.{name}] missing key {missing[0]!r}; accepted: "
                             "a table with start, stop, num (np.linspace) or with values")
        start, stop = (_number(source, f"{name}.{key}", table[key], kind)
                       for key in ("start", "stop"))
        num = table["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ValueError(f"{source}: [{kind}.{name}] num must be an integer >= 1, "
                             f"got {num!r}")
        values = np.linspace(start, stop, num)
    if "units" in table:
        return (from_degrees(values) if _is_degrees(source, name, table["units"], kind)
                else values)
    return values


def _number(source: str, key: str, value: Any, table: str = "grid") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{source}: [{table}] {key} must be a number, got {value!r}")
    return float(value)


def _is_degrees(source: str, name: str, units: Any, table: str = "grid") -> bool:
    accepted = _units(name)
    if units not in accepted:
        raise ValueError(f"{source}: [{table}.{name}] units must be one of "
                         f"{', '.join(map(repr, accepted))}, got {units!r}")
    return accepted[units]


def _run(source: str, table: dict, system: bool = False) -> dict[str, Any]:
    """``[run]`` -> validated keyword arguments of `sweep.run` (for a ``system``, its
    observables are checked by `parse_run` with the system)."""
    _check_keys(source, "[run]", table, RUN_KEYS)
    missing = [key for key in REQUIRED_RUN_KEYS if key not in table]
    if missing:
        raise ValueError(f"{source}: [run] missing key {missing[0]!r}; required: "
                         f"{', '.join(REQUIRED_RUN_KEYS)}")
    kwargs = dict(table)
    with _context(source, "run"):
        validate_settings(t_end=kwargs["t_end"], dt=kwargs["dt"],
                          t0=kwargs.get("t0", 0.0),
                          t_transient=kwargs.get("t_transient", 0.0),
                          save_every=kwargs.get("save_every"),
                          method=kwargs.get("method", "rk4"),
                          rtol=kwargs.get("rtol"), atol=kwargs.get("atol"))
        if "observe" in kwargs:
            observe = kwargs["observe"]
            if isinstance(observe, list) and not all(isinstance(o, str) for o in observe):
                raise TypeError(f"observe must be a list of names, got {observe!r}")
            if not isinstance(observe, (str, list)):
                raise TypeError(f"observe must be a name or a list of names, "
                                 f"got {observe!r}")
            if not system:
                resolve(observe)
            kwargs["observe"] = (observe,) if isinstance(observe, str) else tuple(observe)
        if "strobe_samples" in kwargs and not system:
            check_strobe_samples(kwargs["strobe_samples"],
                                 resolve(kwargs.get("observe", DEFAULT_OBSERVE)))
        if "chunk_size" in kwargs:
            chunk_size = kwargs["chunk_size"]
            if isinstance(chunk_size, bool) or not isinstance(chunk_size, int):
                raise TypeError(f"chunk_size must be an integer >= 1 (trajectories), "
                                f"got {chunk_size!r}")
            if chunk_size < 1:
                raise ValueError(f"chunk_size must be an integer >= 1 (trajectories), "
                                 f"got {chunk_size!r}")
        for flag in ("stop_early", "check_stability"):
            if flag in kwargs:
                check_flag(flag, kwargs[flag])
        if "scheduler" in kwargs:
            check_scheduler("scheduler", kwargs["scheduler"])
        if "device" in kwargs:
            check_device(kwargs["device"])
        if "dtype" in kwargs:
            check_dtype(kwargs["dtype"])
        if "estimate_error" in kwargs:
            check_positive_int("estimate_error", kwargs["estimate_error"],
                               "an int >= 1 (trajectories)")
        if "pilot" in kwargs:
            accepted = "an int >= 2 (points per initial-condition axis)"
            if check_positive_int("pilot", kwargs["pilot"], accepted) < 2:
                raise ValueError(f"pilot must be {accepted}, got {kwargs['pilot']!r}")
        if "refine" in kwargs:
            check_flag("refine", kwargs["refine"])
        if "known_cells" in kwargs:
            check_flag("known_cells", kwargs["known_cells"])
            if kwargs["known_cells"] and "pilot" not in kwargs:
                raise ValueError("known_cells = true stops trajectories on the known cells "
                                 "of coarse maps labelled by a pilot's attractor "
                                 "catalogue; accepted: known_cells = true with pilot = N "
                                 "(and stop_early = true, observe = [\"strobe\"]), or "
                                 "neither")
        for key in ("refine_label", "refine_step"):
            if key in kwargs and not kwargs.get("refine"):
                raise ValueError(f"{key} is for refine = true, which this [run] table does "
                                 "not set; accepted: refine = true with it, or neither")
        if "refine_label" in kwargs and (not isinstance(kwargs["refine_label"], str)
                                         or not kwargs["refine_label"]):
            raise TypeError(f"refine_label must be a map name ({', '.join(REFINE_MAPS)}) "
                            f"or a variable name, got {kwargs['refine_label']!r}")
        if "refine_step" in kwargs:
            accepted = "an int >= 2 (cells between lattice lines)"
            if check_positive_int("refine_step", kwargs["refine_step"], accepted) < 2:
                raise ValueError(f"refine_step must be {accepted}, got "
                                 f"{kwargs['refine_step']!r}")
    return kwargs
