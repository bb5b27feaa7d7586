"""A run file's ``[run] pilot`` (or ``sweep run --pilot N``): the checks ``sweep run``
makes before any compute, for a forced pendulum (`check_scene_pilot`) and for a driven
system with several coordinates (`check_system_pilot`).

For a forced ``[scene]`` the pilot is `sweep.maps.pilot_catalogue`: a run of the grid
thinned to ``pilot`` x ``pilot`` starts with ``stop_early`` (each start stops once its
stroboscopic points repeat), observing what the map observes, ``strobe`` among it.

For a ``[system]`` the pilot is `sweep.maps.pilot_catalogue` of the system: its strobe
run over the grid thinned to ``pilot`` values per initial-state axis; the map then runs
``observe = ["attractor"]`` (or ``["strobe", "attractor"]``) with the pilot's catalogue
as ``attractors=`` (`sweep.system_attractors`), ``stop_early = true`` stopping each
start once it follows a catalogued attractor.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_scene_pilot", "check_system_pilot"]


def _stand_in(system) -> dict:
    """A catalogue of one period-1 attractor of ``system``'s coordinates: what the pilot
    will pass as ``attractors=``, for validating the map's run before the pilot ran."""
    m = len(system.declaration.coordinates)
    return {"theta": np.zeros((1, m, 2)), "omega": np.zeros((1, m, 2)),
            "period": np.ones(1, dtype=np.int64)}


def check_scene_pilot(scene, grid, pilot, run_kwargs: dict) -> None:
    """Refuse, before any compute, a forced pendulum's ``pilot`` (``[run] pilot`` or
    ``sweep run --pilot N``) whose run `sweep.maps.pilot_catalogue` could not make:
    a map that does not observe ``strobe`` (the pilot finds the attractors from the
    stroboscopic points), or any other error of the pilot's run, named as the pilot's.

    Parameters
    ----------
    scene : sweep.Scene
    grid : Grid or Points
        The map's trajectories.
    pilot : int
        Values per initial-condition axis of the pilot (``pilot`` x ``pilot`` starts).
    run_kwargs : dict
        The map's `sweep.run` arguments from ``[run]`` (without ``attractors``).

    Raises
    ------
    ValueError, TypeError
        Naming ``pilot``, its value and what is accepted.
    """
    from .engine import prepare
    from .maps.pilot import _MAP_ONLY, pilot_grid
    from .observables import DEFAULT_OBSERVE

    thinned = pilot_grid(grid, pilot)  # an int >= 2; a grid of initial conditions only
    names = tuple(run_kwargs.get("observe", DEFAULT_OBSERVE))
    if "strobe" not in names:
        raise ValueError(f"pilot = {pilot!r} finds the attractors of a forced map from the "
                         f"stroboscopic points of its starts (observe 'strobe'), and "
                         f"observe is {list(names)!r}; accepted: observe = [\"strobe\"] "
                         "with stop_early = true, or [run] without pilot (and no --pilot)")
    kwargs = {key: value for key, value in run_kwargs.items() if key not in _MAP_ONLY}
    try:
        prepare(scene, thinned, stop_early=True, **kwargs)  # what pilot_catalogue runs
    except (ValueError, TypeError) as exc:
        raise type(exc)(f"pilot = {pilot!r}: the pilot runs {pilot} x {pilot} starts with "
                        f"stop_early = true, and that run is refused: {exc}") from None


def check_system_pilot(system, grid, pilot, run_kwargs: dict) -> None:
    """Refuse, before any compute, a ``[system]`` run file's ``pilot`` (or ``sweep run
    --pilot N``) that cannot give the map its catalogue, and ``observe = ["attractor"]``
    without a pilot.

    Parameters
    ----------
    system : sweep.physics.System
    grid : Grid or Points
        The map's trajectories.
    pilot : int or None
        Values per initial-state axis of the pilot (``pilot`` x ``pilot`` starts of a
        2-D map), or None for a run file without one.
    run_kwargs : dict
        The map's `sweep.run` arguments from ``[run]`` (without ``attractors``).

    Raises
    ------
    ValueError, TypeError
        Naming ``pilot`` (or ``observe``), the value and what is accepted: a system
        without a periodic drive, a map that does not observe ``attractor``, a grid that
        varies anything but the initial state, a bad ``pilot``; any other error of the
        map's `sweep.run` arguments with the pilot's catalogue.
    """
    from .engine import prepare
    from .maps.pilot import pilot_grid
    from .observables import DEFAULT_OBSERVE

    names = tuple(run_kwargs.get("observe", DEFAULT_OBSERVE))
    if pilot is None:
        if "attractor" in names:
            raise ValueError("observe 'attractor' labels each start by an attractor "
                             "catalogue, which a run file makes by a pilot; accepted: "
                             "pilot = N in [run] (N x N starts of the grid, run first "
                             "observing 'strobe', find the attractors), or observe without "
                             "'attractor'")
        prepare(system, grid, **run_kwargs)  # the system's observables and options
        return
    if system.drive_frequency_parameter is None:
        raise ValueError(f"pilot = {pilot!r} catalogues the attractors of a driven system "
                         f"(its orbits sampled once per drive period), and this "
                         f"{system.title} has no periodic drive; accepted: a driven "
                         "[system] (a DoublePendulum with pivot_amplitude and "
                         "pivot_frequency, or a [system.forcing] table with on = "
                         "\"<coordinate>\"), or [run] without pilot")
    if "attractor" not in names:
        raise ValueError(f"pilot = {pilot!r} makes an attractor catalogue that labels each "
                         f"start in observe 'attractor', and observe is {list(names)!r}; "
                         "accepted: observe = [\"attractor\"] (or [\"strobe\", "
                         "\"attractor\"]) with stop_early = true, or [run] without pilot")
    pilot_grid(grid, pilot, system)  # an int >= 2; a grid of initial states only
    prepare(system, grid, attractors=_stand_in(system), **run_kwargs)
