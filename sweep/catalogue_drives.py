"""The other periodic drives of a run, besides the one its ``strobe`` samples by, whose
phases an attractor catalogue records (`sweep.strobe_phase`, ``other_drive_phases``).

A scene may have a second drive: the single pendulum's `sweep.PivotDrive` ``a cos(nu t
+ psi)`` beside its `sweep.Forcing` (the strobe drive), a system's `sweep.Forcing(on=...)`
beside the double pendulum's driven pivot or a declared system's
``drive_frequency_axis`` (the strobe drive). Each is named by its frequency's grid axis
(``pivot_frequency``, ``forcing_frequency_theta1``) and has a phase constant's axis
(``pivot_phase``, ``forcing_phase_theta1``). Time terms written into a declared system's
own equations are not known as drives and are not listed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["pendulum_drives", "system_drives"]


def _value(grid, axis: str, values: dict) -> float:
    """The grid's value of ``axis`` (its smallest where it has several: only a dataset's
    attribute naming the drives reads such a grid, and it keeps the names alone), else
    ``values[axis]`` (0 where absent)."""
    column = grid.axes.get(axis, np.array([values.get(axis, 0.0)]))
    return float(np.unique(np.asarray(column, dtype=np.float64))[0])


def pendulum_drives(scene, grid) -> dict:
    """The single pendulum's drives besides its forcing, of a run of ``scene`` (a
    `sweep.Scene`) over ``grid``.

    Returns
    -------
    dict
        Frequency axis -> (frequency [rad/s], phase axis, phase constant [rad]) of each
        simulated effect with a drive but the forcing (`sweep.Grid.effects`: the
        scene's, and those a grid axis switches on); the grid's first value of each,
        else the scene's. ``{}`` without one.
    """
    from .physics.effect import EFFECTS

    values = scene.parameters()
    drives = {}
    for name in sorted(grid.effects(scene)):
        declaration = EFFECTS[name].declaration
        if declaration.drive is None or name == "forcing":
            continue
        axis = {p.symbol: p.axis for p in declaration.parameters}
        frequency, phase = axis[declaration.drive.frequency], axis[declaration.drive.phase]
        drives[frequency] = (_value(grid, frequency, values), phase,
                             _value(grid, phase, values))
    return drives


def system_drives(system, grid, strobe_axis: str) -> dict:
    """A system's drives besides the one of frequency axis ``strobe_axis`` (its
    `sweep.physics.System.drive_frequency_parameter`): each effect with a drive on one
    coordinate (a `sweep.Forcing(on=...)`), as `pendulum_drives` gives them."""
    from .physics.coordinate_effects import parameters_on

    coordinates = {c.name: c for c in system.declaration.coordinates}
    values = system.parameters()
    drives = {}
    for effect in system.effects:
        declaration = type(effect).declaration
        if effect.coordinate is None or declaration.drive is None:
            continue
        found = parameters_on(type(effect), coordinates[effect.coordinate],
                              system.energy_units)
        axis = {p.symbol: q.axis for p, q in zip(declaration.parameters, found)}
        frequency, phase = axis[declaration.drive.frequency], axis[declaration.drive.phase]
        if frequency != strobe_axis:
            drives[frequency] = (_value(grid, frequency, values), phase,
                                 _value(grid, phase, values))
    return dict(sorted(drives.items()))
