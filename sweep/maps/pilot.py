"""A pilot run that finds a forced map's attractors, for ``sweep.run(...,
attractors=...)``: the map's own initial-condition grid, thinned, with early stop."""

from __future__ import annotations

import numpy as np

from .. import engine
from .._validate import check_count
from ..engine import INITIAL_AXES
from ..grid import Grid, Points
from ..physics import Scene
from .labels import attractor_catalogue

__all__ = ["INITIAL_AXES", "pilot_catalogue", "pilot_grid"]

#: Runs' settings the pilot does not take from the map's run (where and how the map
#: itself is run and kept, not what is integrated).
_MAP_ONLY = ("checkpoint", "resume", "keep_checkpoint", "estimate_error", "chunk_size",
             "client", "progress", "stop_early", "attractors", "save_every")


def pilot_grid(grid: Grid | Points, points: int) -> Grid:
    """``grid`` with its initial-condition axes thinned to at most ``points`` evenly
    spaced values each (ends kept); for `Points`, a grid of ``points`` evenly spaced
    values from the smallest to the largest of each initial-condition column (a box
    around them) and their other columns' one value.

    Raises
    ------
    ValueError
        If the grid varies anything but the initial conditions, or ``points`` < 2.
    """
    # named "pilot", as the option of the command line and of a run file that sets it
    points = check_count("pilot", points, minimum=2,
                         accepted="an int >= 2 (points per initial-condition axis)")
    engine.check_one_scene(grid)
    if isinstance(grid, Points):
        return Grid(**{name: np.unique(np.linspace(values.min(), values.max(), points))
                       if name in INITIAL_AXES else values[0]
                       for name, values in grid.axes.items()})
    axes = {}
    for name, values in grid.axes.items():
        values = np.asarray(values)
        if name in INITIAL_AXES and values.size > points:
            values = values[np.linspace(0, values.size - 1, points).round().astype(int)]
        axes[name] = values
    return Grid(**axes)


def pilot_catalogue(scene: Scene, grid: Grid, points: int = 41, **run_kwargs) -> dict:
    """The attractors of ``scene`` found by a pilot over ``grid`` thinned to
    ``points`` x ``points`` starts (`pilot_grid`), run with ``stop_early``.

    Parameters
    ----------
    scene : Scene
        A forced scene.
    grid : Grid
        The map's grid (it may vary only ``theta0`` and ``omega0``).
    points : int, default 41
        Values per initial-condition axis in the pilot.
    **run_kwargs
        The map's `sweep.run` arguments (``observe`` must include ``strobe``); those
        about where and how the map is run (checkpoints, chunks, a Dask client, the
        error estimate) are not used.

    Returns
    -------
    dict
        `attractor_catalogue` of the pilot run: pass it as ``attractors=``.

    Raises
    ------
    ValueError
        As `pilot_grid`, `sweep.run` and `attractor_catalogue` do (before the map runs).
    """
    pilot = pilot_grid(grid, points)
    kwargs = {key: value for key, value in run_kwargs.items() if key not in _MAP_ONLY}
    ds = engine.run(scene, pilot, stop_early=True, progress=False, **kwargs)
    return attractor_catalogue(ds)
