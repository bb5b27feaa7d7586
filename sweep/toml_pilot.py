"""A run file's ``[run] pilot`` for a driven system with several coordinates: the checks
``sweep run`` makes before any compute (`check_system_pilot`).

For a ``[system]`` the pilot is `sweep.maps.pilot_catalogue` of the system: its strobe
run over the grid thinned to ``pilot`` values per initial-state axis; the map then runs
``observe = ["attractor"]`` (or ``["strobe", "attractor"]``) with the pilot's catalogue
as ``attractors=`` (`sweep.system_attractors`), ``stop_early = true`` stopping each
start once it follows a catalogued attractor.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_system_pilot"]


def _stand_in(system) -> dict:
    """A catalogue of one period-1 attractor of ``system``'s coordinates: what the pilot
    will pass as ``attractors=``, for validating the map's run before the pilot ran."""
    m = len(system.declaration.coordinates)
    return {"theta": np.zeros((1, m, 2)), "omega": np.zeros((1, m, 2)),
            "period": np.ones(1, dtype=np.int64)}


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
