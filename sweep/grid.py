"""Named 1-D axes whose Cartesian product is the set of trajectories of a run.

A `Grid` maps to a flat parameter table (one row per trajectory, one column per
parameter, `sweep.physics.parameter_names`) chunk by chunk, so the table for a huge grid
never has to exist in memory at once; flat per-trajectory outputs are reshaped back
to the grid's shape (C order: the last axis varies fastest).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from ._validate import check_axis, check_numbers
from .physics import EFFECTS, Scene, parameter_names, parameters

__all__ = ["Grid", "GridRows", "from_degrees"]


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


class Grid:
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

    def __init__(self, **axes) -> None:
        declared = {p.axis: p for p in parameters()}
        if not axes:
            raise ValueError(
                "Grid needs at least one axis; accepted axis names: " + ", ".join(declared)
            )
        checked = {}
        for name, values in axes.items():
            if name not in declared:
                raise ValueError(
                    f"unknown grid axis {name!r}; accepted axis names: {', '.join(declared)}"
                )
            array = checked[name] = check_axis(name, values)
            bad = declared[name].is_outside(array)
            if bad.any():
                raise ValueError(
                    f"grid axis {name!r} has value {float(array[bad][0])!r} at index "
                    f"{int(np.flatnonzero(bad)[0])}; accepted: {declared[name].accepted(True)}"
                )
            array.flags.writeable = False
        self._axes = checked

    @property
    def axes(self) -> dict[str, np.ndarray]:
        """The axes, ``{name: read-only float64 array, shape (n_name,)}``, in grid order."""
        return dict(self._axes)

    @property
    def dims(self) -> tuple[str, ...]:
        """Axis names in grid (dimension) order."""
        return tuple(self._axes)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of points along each axis."""
        return tuple(a.size for a in self._axes.values())

    @property
    def size(self) -> int:
        """Number of trajectories (product of the axis lengths)."""
        return math.prod(self.shape)

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}=<{v.size} values>" for k, v in self._axes.items())
        return f"Grid({inner})"

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
        for name, effect_type in EFFECTS.items():
            declaration = effect_type.declaration
            given = [axis for axis in declaration.axes if axis in self._axes]
            if given and scene.effect(name) is None and not declaration.switched_on_by_grid:
                what = (f"to supply the other {name} parameters" if len(declaration.parameters) > 1
                        else "(the axis alone does not switch it on)")
                raise ValueError(
                    f"grid axis {given[0]!r} needs a {name} in the scene {what}; accepted: "
                    f"add {effect_type.signature()} to Scene.effects"
                )

    def effects(self, scene: Scene) -> frozenset[str]:
        """Names of the effects the run must simulate: the scene's, plus those a grid
        axis switches on (see `check_against`)."""
        names = {e.declaration.name for e in scene.effects}
        for name, effect_type in EFFECTS.items():
            if any(axis in self._axes for axis in effect_type.declaration.axes):
                names.add(name)
        return frozenset(names)

    def table(self, scene: Scene, start: int = 0, stop: int | None = None) -> np.ndarray:
        """Parameter table for the flat trajectory indices ``start:stop``.

        Parameters
        ----------
        scene : Scene
            Supplies every parameter that is not a grid axis.
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
        """The rows ``start:stop`` of `table`, described instead of tabulated: the
        constant row and each axis's column, stride and values, from which trajectory
        ``start + i`` builds its own row where it runs (a GPU thread does; see
        `GridRows`). O(number of axis values) memory, whatever the chunk's size."""
        stop = self.size if stop is None else stop
        names = parameter_names()
        fixed = {"theta0": 0.0, "omega0": 0.0, **scene.parameters()}
        template = np.array([fixed[name] for name in names], dtype=np.float64)
        strides = np.cumprod((self.shape + (1,))[:0:-1])[::-1] if self._axes else ()
        sizes = [values.size for values in self._axes.values()]
        return GridRows(
            template=template,
            columns=np.array([names.index(name) for name in self._axes], dtype=np.int64),
            strides=np.array(strides, dtype=np.int64), sizes=np.array(sizes, dtype=np.int64),
            offsets=np.array(np.cumsum([0] + sizes[:-1]), dtype=np.int64),
            values=np.concatenate([np.zeros(0)] + list(self._axes.values())).astype(np.float64),
            start=int(start), n=int(stop - start))

    def chunks(self, chunk_size: int) -> Iterator[tuple[int, int]]:
        """Yield ``(start, stop)`` flat index ranges of at most ``chunk_size`` rows."""
        for start in range(0, self.size, chunk_size):
            yield start, min(start + chunk_size, self.size)

    def unflatten(self, flat: np.ndarray) -> np.ndarray:
        """Reshape per-trajectory values, shape (size, ...), to (*shape, ...)."""
        return flat.reshape(self.shape + flat.shape[1:])

