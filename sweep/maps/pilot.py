"""A pilot run that finds a forced map's attractors, for ``sweep.run(...,
attractors=...)``: the map's own initial-condition grid, thinned, with early stop (for
a driven system with several coordinates: its strobe run, to ``t_end``)."""

from __future__ import annotations

import numpy as np

from .. import engine
from .._validate import check_count
from ..engine import INITIAL_AXES
from ..grid import Grid, Points
from ..physics import Scene
from ..physics.system import System
from .labels import attractor_catalogue

__all__ = ["INITIAL_AXES", "pilot_catalogue", "pilot_grid"]

#: Runs' settings the pilot does not take from the map's run (where and how the map
#: itself is run and kept, not what is integrated).
_MAP_ONLY = ("checkpoint", "resume", "keep_checkpoint", "estimate_error", "chunk_size",
             "client", "progress", "stop_early", "attractors", "save_every")


def pilot_grid(grid: Grid | Points, points: int, system: System | None = None) -> Grid:
    """``grid`` with its initial-condition axes thinned to at most ``points`` evenly
    spaced values each (ends kept); for `Points`, a grid of ``points`` evenly spaced
    values from the smallest to the largest of each initial-condition column (a box
    around them) and their other columns' one value. The initial-condition axes are the
    pendulum's ``theta0`` and ``omega0``, or with ``system`` (several coordinates)
    its initial state's (``theta1_0``, ..., ``omega2_0``:
    `sweep.system_attractors.initial_axes`).

    Raises
    ------
    ValueError
        If the grid varies anything but the initial conditions, or ``points`` < 2.
    """
    # named "pilot", as the option of the command line and of a run file that sets it
    points = check_count("pilot", points, minimum=2,
                         accepted="an int >= 2 (points per initial-condition axis)")
    initial = INITIAL_AXES
    if system is None:
        engine.check_one_scene(grid)
    else:
        from ..system_attractors import initial_axes

        initial = initial_axes(system)
        varied = [name for name in grid.axes if name not in initial and grid.varies(name)]
        if varied:
            raise ValueError(f"an attractor catalogue holds the attractors of one system, "
                             f"but the grid varies {', '.join(varied)}; accepted: a grid "
                             f"that varies only the initial state ({', '.join(initial)})")
    if isinstance(grid, Points):
        return Grid(**{name: np.unique(np.linspace(values.min(), values.max(), points))
                       if name in initial else values[0]
                       for name, values in grid.axes.items()})
    axes = {}
    for name, values in grid.axes.items():
        values = np.asarray(values)
        if name in initial and values.size > points:
            values = values[np.linspace(0, values.size - 1, points).round().astype(int)]
        axes[name] = values
    return Grid(**axes)


def pilot_catalogue(scene: Scene, grid: Grid, points: int = 41, **run_kwargs) -> dict:
    """The attractors of ``scene`` found by a pilot over ``grid`` thinned to
    ``points`` x ``points`` starts (`pilot_grid`), run with ``stop_early``.

    Parameters
    ----------
    scene : Scene or System
        A forced scene, or a driven system with several coordinates (its pilot observes
        ``strobe`` over the whole run: a system's trajectory does not stop on its
        samples' periodicity).
    grid : Grid
        The map's grid (it may vary only ``theta0`` and ``omega0``, a system's only its
        initial state).
    points : int, default 41
        Values per initial-condition axis in the pilot.
    **run_kwargs
        The map's `sweep.run` arguments (a scene's ``observe`` must include ``strobe``;
        a system's is replaced by ``("strobe",)``); those about where and how the map is
        run (checkpoints, chunks, a Dask client, the error estimate) are not used.

    Returns
    -------
    dict
        `attractor_catalogue` of the pilot run: pass it as ``attractors=``.

    Raises
    ------
    ValueError
        As `pilot_grid`, `sweep.run` and `attractor_catalogue` do (before the map runs).
    """
    kwargs = {key: value for key, value in run_kwargs.items() if key not in _MAP_ONLY}
    if isinstance(scene, System):
        kwargs["observe"] = ("strobe",)
        ds = engine.run(scene, pilot_grid(grid, points, scene), progress=False, **kwargs)
        return attractor_catalogue(ds)
    pilot = pilot_grid(grid, points)
    ds = engine.run(scene, pilot, stop_early=True, progress=False, **kwargs)
    return attractor_catalogue(ds)
