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

__all__ = ["Grid", "from_degrees"]


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
        stop = self.size if stop is None else stop
        n = stop - start
        names = parameter_names()
        table = np.empty((n, len(names)), dtype=np.float64)
        fixed = {"theta0": 0.0, "omega0": 0.0, **scene.parameters()}
        for column, name in enumerate(names):
            table[:, column] = fixed[name]
        if n == 0:
            return table
        index = np.unravel_index(np.arange(start, stop, dtype=np.int64), self.shape)
        for axis_index, (name, values) in zip(index, self._axes.items()):
            table[:, names.index(name)] = values[axis_index]
        return table

    def chunks(self, chunk_size: int) -> Iterator[tuple[int, int]]:
        """Yield ``(start, stop)`` flat index ranges of at most ``chunk_size`` rows."""
        for start in range(0, self.size, chunk_size):
            yield start, min(start + chunk_size, self.size)

    def unflatten(self, flat: np.ndarray) -> np.ndarray:
        """Reshape per-trajectory values, shape (size, ...), to (*shape, ...)."""
        return flat.reshape(self.shape + flat.shape[1:])

