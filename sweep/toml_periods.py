"""A run file's times in drive periods: ``[run] t_end = { periods = 26 }``, ``dt = {
per_period = 1000 }`` -> seconds.

A driven scene's natural unit of time is its drive period ``P = 2 pi / W`` [s], W [rad/s]
the run's one drive frequency. In ``[run]``, ``t0``, ``t_end`` and ``t_transient`` may be
given as ``{ periods = k }`` (k periods: ``k * P`` s) and ``dt`` as ``{ per_period = N }``
(``P / N`` s, N a positive integer), in place of seconds. The values are computed in
float64 exactly as ``k * (2 * math.pi / W)`` and ``(2 * math.pi / W) / N``, so a step of
``per_period = N`` divides the period as stroboscopic sampling requires
(`sweep._timesteps.check_sampling_period`), and the seconds are those a user who wrote
``26 * (2 * math.pi / W)`` by hand gets; `sweep.run` and the dataset see seconds only.

W is, for the single pendulum (``[scene]``), the frequency of its one harmonic drive (an
effect with a `sweep.physics.effect.Drive`: the forcing's ``frequency``, the pivot's
``frequency``), or of several whose frequencies are one value; a ``[grid]``,
``[points]`` or ``[sample]`` axis of that frequency counts when it has one distinct
value. For a ``[system]``, it is the system's drive frequency
(`sweep.physics.System.drive_frequency_parameter`, the one ``strobe`` samples by) and the
frequency of every `sweep.Forcing` on a coordinate, again one value.

The inverse, for the run files sweep writes (the explorer's downloads): `in_periods` gives
back ``{ periods = k }`` (k a whole number) and ``{ per_period = N }`` for the seconds that
those tables resolve to bit for bit, and `run_lines` writes a ``[run]`` table with them,
so that reading the file back gives the very same float64 values; other seconds, and the
times of a run without one drive frequency, stay seconds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["PERIOD_KEYS", "STEP_KEY", "drive_frequency", "in_periods", "resolve_periods",
           "run_lines"]

#: ``[run]`` keys that accept ``{ periods = k }``.
PERIOD_KEYS = ("t0", "t_end", "t_transient")

#: The ``[run]`` key that accepts ``{ per_period = N }``.
STEP_KEY = "dt"

#: The largest count `in_periods` writes: 2^53, below which every integer is a float64
#: (``k * P`` computes with k exactly) and a TOML integer.
_LARGEST_COUNT = 2**53

_ACCEPTED = {
    "t0": "t0 = seconds, or t0 = { periods = k } with k a finite number",
    "t_end": "t_end = seconds, or t_end = { periods = k } with k a finite number > 0",
    "t_transient": "t_transient = seconds, or t_transient = { periods = k } with k a finite "
                   "number >= 0",
    "dt": "dt = seconds, or dt = { per_period = N } with N an integer >= 1 (steps per "
          "drive period)",
}


def resolve_periods(table: dict[str, Any], scene, grid, rows: str = "grid") -> dict[str, Any]:
    """``[run]`` with its times in drive periods replaced by seconds.

    Parameters
    ----------
    table : dict
        The ``[run]`` table as `tomllib` reads it.
    scene : sweep.Scene or sweep.physics.System
        The run's scene or system (its drive).
    grid : sweep.Grid or sweep.Points
        The run's rows (an axis of the drive frequency counts).
    rows : str
        The run file's table of the rows (``grid``, ``points`` or ``sample``), for the
        messages.

    Returns
    -------
    dict
        A copy of ``table`` in which ``{ periods = k }`` is ``k * (2 pi / W)`` [s] and
        ``{ per_period = N }`` is ``(2 pi / W) / N`` [s]; ``table`` itself when it gives
        no time in periods.

    Raises
    ------
    ValueError, TypeError
        One line naming the key, the bad value and what is accepted: a table for another
        key, an unknown key in the table, a count out of range, or no one drive frequency
        (an undriven scene, two drives of different frequencies, an axis sweeping it).
    """
    counts = {key: _count(key, value) for key, value in table.items()
              if isinstance(value, dict)}
    if not counts:
        return table
    key = next(iter(counts))
    frequency = drive_frequency(scene, grid, f"{key} = {_text(table[key])}", rows)
    period = 2 * math.pi / frequency
    out = dict(table)
    for key, count in counts.items():
        out[key] = period / count if key == STEP_KEY else count * period
    return out


def drive_frequency(scene, grid, what: str, rows: str = "grid") -> float:
    """The run's one drive frequency W [rad/s] (see the module docstring).

    Parameters
    ----------
    scene : sweep.Scene or sweep.physics.System
    grid : sweep.Grid or sweep.Points
    what : str
        The setting that needs it, for the messages (``"t_end = {periods = 26}"``).
    rows : str
        The run file's table of the rows, for the messages.

    Raises
    ------
    ValueError
        Without a drive, with drives or an axis of several frequencies, or W = 0.
    """
    from .physics.system import System

    system = isinstance(scene, System)
    drives = _system_drives(scene, grid) if system else _scene_drives(scene)
    accepted = ("times in seconds, or a run with one drive frequency W > 0 (the drive "
                "period 2 pi / W)")
    if not drives:
        kind = ("a system with a periodic drive (a pivot_frequency, a drive_frequency_axis "
                "or a Forcing(on=...))" if system else "a [scene.forcing] or [scene.pivot]")
        raise ValueError(f"{what} counts drive periods, but this run has no periodic "
                         f"drive; accepted: {kind}, or {accepted}")
    axes = grid.axes
    values = {}
    for axis, value in drives.items():
        found = np.unique(np.asarray(axes.get(axis, [value]), dtype=np.float64))
        if found.size > 1:
            raise ValueError(f"{what} counts drive periods, but [{rows}] {axis} has "
                             f"{found.size} values ({_values(found)}); accepted: {accepted}")
        values[axis] = float(found[0])
    if len(set(values.values())) > 1:
        listed = ", ".join(f"{axis} = {value!r}" for axis, value in values.items())
        raise ValueError(f"{what} counts drive periods, but the run has drives of "
                         f"different frequencies ({listed} rad/s); accepted: {accepted}")
    axis, frequency = next(iter(values.items()))
    if not math.isfinite(frequency) or frequency <= 0:
        raise ValueError(f"{what} counts drive periods, but {axis} = {frequency!r} rad/s "
                         f"has no period; accepted: {accepted}")
    return frequency


def in_periods(table: dict[str, Any], scene, grid) -> dict[str, dict[str, int]]:
    """The times of a ``[run]`` table [s] that are whole drive periods, as the tables
    `resolve_periods` turns back into the very same float64 values.

    ``t0``, ``t_end`` and ``t_transient`` equal to ``k * (2 pi / W)`` bit for bit (k a
    nonzero whole number; > 0 for ``t_end`` and ``t_transient``) give ``{"periods": k}``;
    ``dt`` equal to ``(2 pi / W) / N`` bit for bit (N >= 1) gives ``{"per_period": N}``.
    A zero time, any other value, and every time of a run without one drive frequency
    (`drive_frequency` refuses it: an undriven scene, drives of different frequencies,
    an axis of several) are left out: they stay seconds.

    Parameters
    ----------
    table : dict
        The ``[run]`` keys and values, times in seconds (`sweep.run`'s keyword arguments).
    scene : sweep.Scene or sweep.physics.System
        The scene or system the file writes.
    grid : sweep.Grid or sweep.Points
        The rows the file writes (an axis of the drive frequency counts).

    Returns
    -------
    dict
        ``{key: {"periods": k}}`` or ``{"dt": {"per_period": N}}`` for each time that
        resolves exactly; empty when none does.
    """
    times = {key: float(value) for key, value in table.items()
             if key in (*PERIOD_KEYS, STEP_KEY) and _real(value) and value != 0}
    if not times:
        return {}
    try:
        frequency = drive_frequency(scene, grid, "a time in periods")
    except ValueError:  # no one drive frequency: the times stay seconds
        return {}
    period = 2 * math.pi / frequency
    out = {}
    for key, seconds in times.items():
        ratio = period / seconds if key == STEP_KEY else seconds / period
        if not abs(ratio) < _LARGEST_COUNT:  # also inf: no count to write
            continue
        count = round(ratio)
        if key == STEP_KEY:
            if count >= 1 and period / count == seconds:
                out[key] = {"per_period": count}
        elif count != 0 and (key == "t0" or count > 0) and count * period == seconds:
            out[key] = {"periods": count}
    return out


def run_lines(table: dict[str, Any], scene, grid, text) -> list[str]:
    """The lines ``key = value`` of a written run file's ``[run]`` table: its times in
    drive periods where they resolve exactly (`in_periods`), each with a comment of its
    seconds (``t_end = {periods = 26}  # 245.04422698000386 s``), every other value as
    ``text`` writes it.

    Parameters
    ----------
    table : dict
        The ``[run]`` keys and values, times in seconds.
    scene : sweep.Scene or sweep.physics.System
        The scene or system the file writes.
    grid : sweep.Grid or sweep.Points
        The rows the file writes.
    text : callable
        A value as TOML text (the writer's own, e.g. `sweep.explore.texts.toml_value`);
        it must write a dict as an inline table.

    Returns
    -------
    list of str
        One line per key of ``table``, in its order.
    """
    counts = in_periods(table, scene, grid)
    return [f"{key} = {text(counts[key])}  # {float(value)!r} s" if key in counts
            else f"{key} = {text(value)}" for key, value in table.items()]


# ----------------------------------------------------------------------------- helpers
def _real(value: Any) -> bool:
    """A finite real number (not a bool)."""
    return isinstance(value, (int, float, np.integer, np.floating)) \
        and not isinstance(value, (bool, np.bool_)) and math.isfinite(value)


def _count(key: str, value: dict) -> float | int:
    """The number in ``key = { periods = k }`` (or ``{ per_period = N }``), checked."""
    if key not in _ACCEPTED:
        raise TypeError(f"{key} = {_text(value)}: a table counts drive periods only for "
                        f"{', '.join(PERIOD_KEYS)} ({{periods = k}}) and {STEP_KEY} "
                        f"({{per_period = N}}); accepted: {key} as a plain value")
    name = "per_period" if key == STEP_KEY else "periods"
    if set(value) != {name}:
        unknown = sorted(set(value) - {name})
        got = f"unknown key {unknown[0]!r}" if unknown else f"no {name!r}"
        raise ValueError(f"{key} = {_text(value)} has {got}; accepted: {_ACCEPTED[key]}")
    count = value[name]
    if key == STEP_KEY:
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise ValueError(f"{key} = {_text(value)}: per_period must be an integer >= 1, "
                             f"got {count!r}; accepted: {_ACCEPTED[key]}")
        return count
    if isinstance(count, bool) or not isinstance(count, (int, float)) \
            or not math.isfinite(count) or (key == "t_end" and count <= 0) \
            or (key == "t_transient" and count < 0):
        low = {"t_end": " > 0", "t_transient": " >= 0"}.get(key, "")
        raise ValueError(f"{key} = {_text(value)}: periods must be a finite number{low}, "
                         f"got {count!r}; accepted: {_ACCEPTED[key]}")
    return count


def _scene_drives(scene) -> dict[str, float]:
    """The single pendulum's drive frequencies: {axis: value} of every effect with a
    harmonic drive."""
    drives = {}
    for effect in scene.effects:
        declaration = type(effect).declaration
        if declaration.drive is None:
            continue
        parameter = next(p for p in declaration.parameters
                         if p.symbol == declaration.drive.frequency)
        drives[parameter.axis] = float(getattr(effect, parameter.field))
    return drives


def _system_drives(system, grid) -> dict[str, float]:
    """A system's drive frequencies: its drive parameter's and every forcing's on a
    coordinate, {axis: value}, with the terms the grid's axes switch on (a
    ``pivot_amplitude`` axis drives a `sweep.DoublePendulum`'s pivot, as in the run)."""
    system = system.switched_on(tuple(grid.axes))
    values = system.parameters()
    drive = system.drive_frequency_parameter
    axes = [drive.axis] if drive is not None else []
    axes += [axis for axis in values if axis.startswith("forcing_frequency_")
             and axis not in axes]
    return {axis: float(values[axis]) for axis in axes}


def _values(values: np.ndarray) -> str:
    shown = ", ".join(repr(float(v)) for v in values[:3])
    return shown + (", ..." if values.size > 3 else "")


def _text(value: Any) -> str:
    """A ``[run]`` value as TOML writes it (an inline table: ``{periods = 26}``)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)
