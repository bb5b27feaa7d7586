"""The rows of parameter sets a run integrates, described two ways: a `Grid` (named 1-D
axes whose Cartesian product is the set of trajectories) or `Points` (a table of
parameter sets, one per trajectory, e.g. drawn by `sample`).

Both are `ParameterRows`: they map to a flat parameter table (one row per trajectory,
one column per parameter, `sweep.physics.parameter_names`) chunk by chunk, so the table
for a huge run never has to exist in memory at once, and everything below them
(kernels, checkpoints, Dask, CUDA, attractor catalogues) sees only chunks of rows. Flat
per-trajectory outputs are reshaped back to the grid's shape (C order: the last axis
varies fastest), or stay one dimension ``point`` for `Points`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from ._validate import check_axis, check_choice, check_count, check_numbers
from .physics import EFFECTS, Scene, parameter_names, parameters
from .physics.system import System, system_axis

__all__ = ["Grid", "GridRows", "ParameterRows", "Points", "from_degrees", "sample"]


class GridRows:
    """Rows ``start:start + n`` of a grid's parameter table (`Grid.table`), described:
    row ``i`` is ``template`` with, for each axis ``a``, column ``columns[a]`` set to
    ``values[offsets[a] + ((start + i) // strides[a]) % sizes[a]]``.

    What the GPU kernel receives instead of the table: its threads build their own rows,
    so a chunk costs no host-side table and no copy of one (`sweep.kernels.cuda`).

    Attributes
    ----------
    template : ndarray, shape (n_parameters,), float64
        The scene's parameters (theta0 = omega0 = 0 where no axis sets them).
    columns, strides, sizes, offsets : ndarray, shape (n_axes,), int64
        Per axis: its table column, its flat-index stride (C order), its length, and
        where its values start in ``values``.
    values : ndarray, shape (sum of the axes' lengths,), float64
        The axes' values, concatenated in axis order.
    start, n : int
        The first flat trajectory index and the number of rows.
    """

    def __init__(self, *, template, columns, strides, sizes, offsets, values, start, n):
        self.template, self.columns, self.strides = template, columns, strides
        self.sizes, self.offsets, self.values = sizes, offsets, values
        self.start, self.n = start, n

    @classmethod
    def from_table(cls, table: np.ndarray) -> GridRows:
        """A table's rows described: every column an axis of stride 1 over the rows."""
        n, width = table.shape
        return cls(template=np.zeros(width), columns=np.arange(width, dtype=np.int64),
                   strides=np.ones(width, dtype=np.int64),
                   sizes=np.full(width, n, dtype=np.int64),
                   offsets=np.arange(width, dtype=np.int64) * n,
                   values=np.ascontiguousarray(table.T).ravel().astype(np.float64),
                   start=0, n=n)

    def __len__(self) -> int:
        return self.n

    @property
    def shape(self) -> tuple[int, int]:
        """The table's shape, (n, n_parameters)."""
        return (self.n, self.template.size)


def from_degrees(values) -> np.ndarray:
    """Convert angles (deg) or angular velocities (deg/s) to radians.

    The API is in radians throughout; this is the one clear way to pass degrees,
    e.g. ``Grid(theta0=sweep.from_degrees([-10, -120]))``.

    Parameters
    ----------
    values : array_like
        Degrees (or degrees per second).

    Returns
    -------
    ndarray, float64
        Same shape, in radians (or rad/s).
    """
    return np.deg2rad(check_numbers("from_degrees: values", values))


class ParameterRows:
    """What `sweep.run` integrates: rows of parameter sets, one per trajectory, each a
    scene's parameters with some of them (the *axes*) set per row. `Grid` and `Points`
    are the two ways of describing them; below them the engine sees only chunks of rows
    (`table`, `rows`), so checkpoints, Dask, CUDA and catalogues serve both.

    Subclasses set ``_axes`` (``{name: read-only float64 array}``) and define `dims`,
    `shape`, `rows`, `varies`, `coordinates` and `provenance`.
    """

    #: How a message names one of the axes ("grid axis", "points axis").
    _what = "axis"
    _axes: dict[str, np.ndarray]

    @staticmethod
    def _declared() -> dict:
        return {p.axis: p for p in parameters()}

    def _checked(self, axes: dict, column) -> dict[str, np.ndarray]:
        """``axes`` checked, in the order given: at least one, each a declared name,
        each made an array by ``column(name, values)`` (which checks its form) and
        within its parameter's accepted values."""
        declared = self._declared()
        if not axes:
            raise ValueError(f"{type(self).__name__} needs at least one axis; accepted axis "
                             f"names: {', '.join(declared)}")
        checked = {}
        for name, values in axes.items():
            if name not in declared:
                found = system_axis(name)  # a coordinate or parameter of a system
                if found is None:
                    raise ValueError(f"unknown {self._what} {name!r}; accepted axis names: "
                                     f"{', '.join(declared)} (and a system's, e.g. "
                                     "sweep.DoublePendulum's theta1_0, theta2_0, omega1_0, "
                                     "omega2_0, mass1, length2)")
                declared[name] = found
            # a copy: the axes are read-only, and the caller's array stays as it was
            array = checked[name] = np.array(column(name, values), dtype=np.float64)
            bad = declared[name].is_outside(array)
            if bad.any():
                raise ValueError(
                    f"{self._what} {name!r} has value {float(array[bad][0])!r} at index "
                    f"{int(np.flatnonzero(bad)[0])}; accepted: {declared[name].accepted(True)}"
                )
        return checked

    @property
    def axes(self) -> dict[str, np.ndarray]:
        """The axes, ``{name: read-only float64 array}``, in the order given."""
        return dict(self._axes)

    @property
    def size(self) -> int:
        """Number of trajectories (rows)."""
        return math.prod(self.shape)

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}=<{v.size} values>" for k, v in self._axes.items())
        return f"{type(self).__name__}({inner})"

    def check_against(self, scene: Scene) -> None:
        """Refuse axes that the scene cannot honour.

        An axis of an effect the scene lacks switches that effect on when its
        declaration says so (``switched_on_by_grid``: a ``damping`` axis switches damping
        on); otherwise the scene must have the effect (it supplies the effect's other
        parameters: a forcing axis needs a `Forcing`, a torque axis a `Torque`).

        Raises
        ------
        ValueError
        """
        if isinstance(scene, System):
            self._check_against_system(scene)
            return
        pendulum = parameter_names()
        for name in self._axes:
            if name not in pendulum:
                raise ValueError(
                    f"{self._what} {name!r} is a system's, not the single pendulum's; a "
                    f"sweep.Scene accepts the axes {', '.join(pendulum)}; accepted: those, "
                    "or a system (e.g. sweep.DoublePendulum) in place of the scene")
        for name, effect_type in EFFECTS.items():
            declaration = effect_type.declaration
            given = [axis for axis in declaration.axes if axis in self._axes]
            if given and scene.effect(name) is None and not declaration.switched_on_by_grid:
                what = (f"to supply the other {name} parameters" if len(declaration.parameters) > 1
                        else "(the axis alone does not switch it on)")
                raise ValueError(
                    f"{self._what} {given[0]!r} needs a {name} in the scene {what}; accepted: "
                    f"add {effect_type.signature()} to Scene.effects"
                )

    def _check_against_system(self, system: System) -> None:
        """Refuse an axis that names no coordinate or parameter of ``system``."""
        columns = system.accepted_axes()
        for name in self._axes:
            hint = None if name in columns else system.axis_hint(name)
            if hint is not None:  # an effect on a coordinate: say what it needs
                raise ValueError(f"{self._what} {name!r} {hint}")
            if name not in columns:
                raise ValueError(
                    f"{self._what} {name!r} names no coordinate or parameter of "
                    f"{type(system).__name__}; accepted axis names: {', '.join(columns)}")

    def effects(self, scene: Scene) -> frozenset[str]:
        """Names of the effects the run must simulate: the scene's, plus those an axis
        switches on (see `check_against`)."""
        if isinstance(scene, System):
            on = scene.damping is not None or "damping" in self._axes
            return frozenset({"damping"} if on else ())
        names = {e.declaration.name for e in scene.effects}
        for name, effect_type in EFFECTS.items():
            if any(axis in self._axes for axis in effect_type.declaration.axes):
                names.add(name)
        return frozenset(names)

    def table_names(self, scene) -> tuple[str, ...]:
        """The columns of the parameter table for ``scene``: `sweep.physics.
        parameter_names` for a `Scene`; a system's initial state, parameters and (where
        the run simulates it) damping rate for a `sweep.physics.System`."""
        if isinstance(scene, System):
            return scene.columns("damping" in self.effects(scene))
        return parameter_names()

    def _template(self, scene: Scene) -> np.ndarray:
        """The scene's parameter row, the initial state 0 (axes override it)."""
        fixed = {**dict.fromkeys(self.table_names(scene), 0.0), **scene.parameters()}
        return np.array([fixed[name] for name in self.table_names(scene)], dtype=np.float64)

    def _columns(self, scene) -> np.ndarray:
        names = self.table_names(scene)
        return np.array([names.index(name) for name in self._axes], dtype=np.int64)

    def table(self, scene: Scene, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Parameter table for the flat trajectory indices ``start:stop``.

        Parameters
        ----------
        scene : Scene
            Supplies every parameter that is not an axis.
        start, stop : int
            Flat (C-order) trajectory index range; ``stop`` defaults to `size`.

        Returns
        -------
        ndarray, shape (stop - start, n_parameters), float64, C-contiguous
            Columns in the order of `sweep.physics.parameter_names`.
        """
        rows = self.rows(scene, start, stop)
        # the constant row broadcast in one contiguous pass, then only the axes' columns
        table = np.empty(rows.shape, dtype=np.float64)
        table[:] = rows.template
        flat = np.arange(rows.start, rows.start + len(rows), dtype=np.int64)
        for column, stride, size, offset in zip(rows.columns, rows.strides, rows.sizes,
                                                rows.offsets):
            table[:, column] = rows.values[offset + (flat // stride) % size]
        return table

    def rows(self, scene: Scene, start: int = 0, stop: int | None = None) -> GridRows:
        """The rows ``start:stop`` of `table`, described (`GridRows`)."""
        raise NotImplementedError

    def chunks(self, chunk_size: int) -> Iterator[tuple[int, int]]:
        """Yield ``(start, stop)`` flat index ranges of at most ``chunk_size`` rows."""
        for start in range(0, self.size, chunk_size):
            yield start, min(start + chunk_size, self.size)

    def unflatten(self, flat: np.ndarray) -> np.ndarray:
        """Reshape per-trajectory values, shape (size, ...), to (*shape, ...)."""
        return flat.reshape(self.shape + flat.shape[1:])


class Grid(ParameterRows):
    """Named axes of a sweep; the run covers their Cartesian product.

    Parameters
    ----------
    **axes : array_like, each 1-D
        Any parameter name (`sweep.physics.parameter_names`): ``theta0`` [rad],
        ``omega0`` [rad/s], ``length`` [m], ``gravity`` [m/s^2], ``damping`` [1/s],
        ``forcing_amplitude`` [rad/s^2], ``forcing_frequency`` [rad/s],
        ``forcing_phase`` [rad], and those of any registered effect. The keyword order
        is the dimension order of the resulting dataset. An axis overrides the scene's
        value of that parameter; ``theta0`` and ``omega0`` default to 0 when absent.
        A scalar is taken as a one-point axis. Values must be real numbers (booleans,
        strings, None and complex numbers are refused) and distinct; they need not be
        sorted: the dataset keeps the order given, and ``.sel`` works either way.

    Examples
    --------
    >>> import numpy as np, sweep
    >>> grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 5), omega0=[0.0, 1.0])
    >>> grid.shape, grid.size
    ((5, 2), 10)
    """

    _what = "grid axis"

    def __init__(self, **axes) -> None:
        self._axes = self._checked(axes, check_axis)
        for array in self._axes.values():
            array.flags.writeable = False

    @property
    def dims(self) -> tuple[str, ...]:
        """Axis names in grid (dimension) order."""
        return tuple(self._axes)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of points along each axis."""
        return tuple(a.size for a in self._axes.values())

    def rows(self, scene: Scene, start: int = 0, stop: int | None = None) -> GridRows:
        """The rows ``start:stop`` of `table`, described instead of tabulated: the
        constant row and each axis's column, stride and values, from which trajectory
        ``start + i`` builds its own row where it runs (a GPU thread does; see
        `GridRows`). O(number of axis values) memory, whatever the chunk's size."""
        stop = self.size if stop is None else stop
        strides = np.cumprod((self.shape + (1,))[:0:-1])[::-1] if self._axes else ()
        sizes = [values.size for values in self._axes.values()]
        return GridRows(
            template=self._template(scene), columns=self._columns(scene),
            strides=np.array(strides, dtype=np.int64), sizes=np.array(sizes, dtype=np.int64),
            offsets=np.array(np.cumsum([0] + sizes[:-1]), dtype=np.int64),
            values=np.concatenate([np.zeros(0)] + list(self._axes.values())).astype(np.float64),
            start=int(start), n=int(stop - start))

    def varies(self, name: str) -> bool:
        """Whether the axis ``name`` takes more than one value (False if not an axis)."""
        return name in self._axes and self._axes[name].size > 1

    def coordinates(self) -> list[tuple[str, str, np.ndarray]]:
        """``(axis, dimension, values)`` per axis: each axis is its own dimension."""
        return [(name, name, values) for name, values in self._axes.items()]

    def provenance(self) -> dict[str, str]:
        """Dataset attributes that say how to rebuild it (`sweep.io.grid_from`):
        ``grid_axes``, the axis names in dimension order."""
        return {"grid_axes": " ".join(self._axes)}


class Points(ParameterRows):
    """A table of parameter sets, one per trajectory: the run covers exactly these rows.

    Where a `Grid` takes the Cartesian product of its axes, ``Points`` takes its
    columns side by side: point ``i`` has, for each axis, that axis's ``i``-th value. The
    run's dataset has one dimension, ``point``, and every axis is a coordinate along it.
    Each trajectory is bit-identical to the same parameter set inside a `Grid`.

    Parameters
    ----------
    **axes : array_like, each 1-D of length n, or a scalar
        The same names, units and accepted values as `Grid`'s axes: ``theta0`` [rad],
        ``omega0`` [rad/s], ``length`` [m], ``gravity`` [m/s^2], ``damping`` [1/s],
        ``forcing_amplitude`` [rad/s^2], ``forcing_frequency`` [rad/s],
        ``forcing_phase`` [rad], and those of any registered effect. Every 1-D column
        has the same length n (the number of points); a scalar is a constant column of
        that length (n = 1 if every column is a scalar). Values must be real, finite
        numbers within the parameter's accepted range; unlike a grid axis they may
        repeat (two points may share a theta0, or be the same point twice). An axis
        overrides the scene's value of that parameter; ``theta0`` and ``omega0``
        default to 0 when absent.

    Attributes
    ----------
    axes : dict of str to ndarray, shape (n,), float64, read-only
    dims : ("point",)
    shape : (n,)
    size : int
        n, the number of trajectories.

    Raises
    ------
    ValueError
        Naming the axis, the bad value (and its index) and what is accepted: an unknown
        name, a column that is not 1-D numbers, empty, non-finite, out of range, or
        columns of unequal lengths.

    See Also
    --------
    sample : Points drawn in a box (Sobol or uniform random).

    Examples
    --------
    >>> import sweep
    >>> points = sweep.Points(theta0=[0.1, 2.0, 2.0], omega0=[0.0, 0.5, -0.5], damping=0.2)
    >>> points.dims, points.shape, points.size
    (('point',), (3,), 3)
    """

    _what = "points axis"

    def __init__(self, **axes) -> None:
        checked = self._checked(axes, self._column)
        lengths = {name: a.size for name, a in checked.items() if a.ndim == 1}
        if len(set(lengths.values())) > 1:
            raise ValueError(
                "points axes have unequal lengths: "
                + ", ".join(f"{name} has {size}" for name, size in lengths.items())
                + "; accepted: 1-D arrays of one length (one value per point), or scalars "
                "(a constant column)")
        n = next(iter(lengths.values()), 1)
        for name, array in checked.items():
            checked[name] = array = np.ascontiguousarray(np.broadcast_to(array, (n,)),
                                                         dtype=np.float64)
            array.flags.writeable = False
        self._axes = checked
        self._n = n

    def _column(self, name: str, values) -> np.ndarray:
        """One column as float64 (0-D for a scalar), refused unless 1-D or a scalar,
        non-empty and finite."""
        array = check_numbers(f"{self._what} {name!r}", values)
        if array.ndim > 1:
            raise ValueError(
                f"{self._what} {name!r} must be 1-D (one value per point) or a scalar, got "
                f"an array of shape {array.shape}")
        if array.size == 0:
            raise ValueError(f"{self._what} {name!r} is empty; accepted: at least one value")
        bad = ~np.isfinite(np.atleast_1d(array))
        if bad.any():
            raise ValueError(
                f"{self._what} {name!r} has non-finite value "
                f"{float(np.atleast_1d(array)[bad][0])!r} at index "
                f"{int(np.flatnonzero(bad)[0])}; accepted: finite numbers")
        return array

    @property
    def dims(self) -> tuple[str]:
        """``("point",)``: the dataset's one dimension."""
        return ("point",)

    @property
    def shape(self) -> tuple[int]:
        """``(n,)``, the number of points."""
        return (self._n,)

    def __len__(self) -> int:
        return self._n

    def rows(self, scene: Scene, start: int = 0, stop: int | None = None) -> GridRows:
        """The rows ``start:stop`` of `table`, described: each axis a column of stride 1
        over the chunk's own values (as `GridRows.from_table` describes a table), so
        the description is O(chunk) memory and row ``i`` of it is point ``start + i``
        (its ``start`` is 0: the values are the chunk's)."""
        stop = self._n if stop is None else stop
        n, count = int(stop - start), len(self._axes)
        return GridRows(
            template=self._template(scene), columns=self._columns(scene),
            strides=np.ones(count, dtype=np.int64), sizes=np.full(count, n, dtype=np.int64),
            offsets=np.arange(count, dtype=np.int64) * n,
            values=np.concatenate([np.zeros(0)] + [values[start:stop]
                                                   for values in self._axes.values()]),
            start=0, n=n)

    def varies(self, name: str) -> bool:
        """Whether the axis ``name`` has more than one distinct value (False if not an
        axis): a constant column describes one scene, as a one-value grid axis does."""
        if name not in self._axes:
            return False
        values = self._axes[name]
        return bool(np.any(values != values[0]))

    def coordinates(self) -> list[tuple[str, str, np.ndarray]]:
        """``(axis, "point", values)`` per axis: every axis a coordinate along ``point``."""
        return [(name, "point", values) for name, values in self._axes.items()]

    def provenance(self) -> dict[str, str]:
        """Dataset attributes that say how to rebuild it (`sweep.io.grid_from`):
        ``point_axes``, the axis names (coordinates along ``point``)."""
        return {"point_axes": " ".join(self._axes)}



#: The ways `sample` draws points.
SAMPLING_METHODS = ("sobol", "random")


def _sample_range(name: str, value, declared: dict):
    """A `sample` range ``(lo, hi)`` as two floats, or a scalar as a 0-D array."""
    accepted = (f"accepted: (lo, hi) with lo < hi, or one value (a constant column), "
                f"{declared[name].accepted(True)}")
    array = check_numbers(f"sample: {name}", value)
    if array.shape not in ((), (2,)):
        raise ValueError(f"sample: {name} = {value!r} is neither a range nor a value; "
                         f"{accepted}")
    if not np.all(np.isfinite(array)) or np.any(declared[name].is_outside(array)) \
            or (array.shape == (2,) and not array[0] < array[1]):
        raise ValueError(f"sample: {name} = {value!r}; {accepted}")
    return array


def sample(n: int, *, seed: int, method: str = "sobol", **ranges) -> Points:
    """``n`` points drawn in a box of parameters: scrambled Sobol or uniform random.

    For estimating what fraction of a region goes where (basin stability; see
    `sweep.maps.fractions`) at a cost set by the error wanted rather than by a grid's
    resolution.

    Parameters
    ----------
    n : int
        Number of points, >= 1.
    seed : int
        Seed, >= 0 (keyword, required): the same seed gives the same points.
    method : {"sobol", "random"}, default "sobol"
        ``"sobol"``: a scrambled Sobol sequence (``scipy.stats.qmc.Sobol(d,
        scramble=True, seed=seed)``, d the number of ranges), its first ``n`` points
        (drawn as the next power of two and cut, so SciPy's warning about other sizes
        does not arise; the sequence's balance is exact only at powers of two, and
        ``sample(n)`` is a prefix of ``sample(2 n)`` with the same seed). ``"random"``:
        independent uniform points (``numpy.random.default_rng(seed)``), so
        `sweep.maps.fractions`' binomial standard error is exact.
    **ranges : (lo, hi) or float
        Per axis name (those of `Grid`: ``theta0=(-np.pi, np.pi)`` [rad], ``omega0``
        [rad/s], ...): a range ``lo < hi`` (finite, within the parameter's accepted
        values) drawn uniformly in ``[lo, hi)``, or one value, a constant column (``damping=0.2``).
        The keyword order is the column order. At least one range.

    Returns
    -------
    Points
        ``n`` points; column ``name`` is ``lo + (hi - lo) u`` with ``u`` in [0, 1).

    Raises
    ------
    ValueError
        Before any drawing, naming the argument, its value and what is accepted.

    Examples
    --------
    >>> import numpy as np, sweep
    >>> points = sweep.sample(1024, seed=1, theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))
    >>> points.shape
    (1024,)
    """
    n = check_count("sample: n", n, accepted="an int >= 1 (points)")
    seed = check_count("sample: seed", seed, minimum=0, accepted="an int >= 0")
    method = check_choice("sample: method", method, SAMPLING_METHODS)
    declared = ParameterRows._declared()
    if not ranges:
        raise ValueError("sample needs at least one range, e.g. theta0=(-np.pi, np.pi); "
                         f"accepted axis names: {', '.join(declared)}")
    checked = {}
    for name, value in ranges.items():
        if name not in declared:
            found = system_axis(name)  # a coordinate or parameter of a system
            if found is None:
                raise ValueError(f"sample: unknown axis {name!r}; accepted axis names: "
                                 f"{', '.join(declared)} (and a system's, e.g. theta1_0)")
            declared[name] = found
        checked[name] = _sample_range(name, value, declared)
    boxed = [name for name, array in checked.items() if array.shape == (2,)]
    if not boxed:
        raise ValueError("sample needs at least one range (lo, hi), got only constant "
                         f"values ({', '.join(checked)}); accepted: e.g. theta0=(-np.pi, np.pi)")
    if method == "sobol":
        from scipy.stats import qmc  # only here: import sweep stays light

        sobol = qmc.Sobol(len(boxed), scramble=True, seed=seed)
        unit = sobol.random_base2(max(0, math.ceil(math.log2(n))))[:n]
    else:
        unit = np.random.default_rng(seed).random((n, len(boxed)))
    columns = {}
    for name, array in checked.items():
        if array.shape == (2,):
            lo, hi = array
            columns[name] = lo + (hi - lo) * unit[:, boxed.index(name)]
        else:
            columns[name] = float(array)
    return Points(**columns)
