"""The drive phase at which an attractor catalogue's stroboscopic rings were sampled,
recorded in the catalogue and checked against a run that uses it.

A ``strobe`` run samples the state at ``t_s + k 2 pi / W`` (k = 0, 1, ...), where
``t_s = t0 + n_transient dt`` is its first step at or after ``t0 + t_transient``
(`sweep.settings.RunSettings`) and W the drive's angular frequency. The drive's phase
at those samples, ``W t_s mod 2 pi`` [rad] (the phase of its clock: a drive's own phase
constant is part of the scene, as its amplitude is), is the Poincare section the rings
lie on. A run whose section is another one never meets a catalogued point, so every
start would be labelled -1; `check_phase` refuses it before any compute. The single
pendulum's catalogue (`sweep.engine`) and a system's (`sweep.system_attractors`) share
this module.

A catalogue records, per attractor, ``strobe_phase`` [rad] and ``drive_frequency``
[rad/s] (arrays of one value per ring, so that selecting attractors, ``catalogue[key]
[keep]``, keeps them). A catalogue without both (one built by hand from rings) is not
checked.
"""

from __future__ import annotations

import math

import numpy as np

from ._timesteps import WHOLE_STEPS_RTOL, transient_steps

__all__ = ["FIELDS", "PHASE_RTOL", "attributes", "check_phase", "dataset_drive",
           "drive_fields", "from_attributes", "phase_mismatch", "strobe_start"]

#: The catalogue's keys of its drive: per attractor, the drive phase of its samples
#: [rad] and the drive's angular frequency [rad/s].
FIELDS = ("strobe_phase", "drive_frequency")

#: Relative tolerance of the phase and frequency comparisons. t0 + t_transient is
#: rounded to float64 (1e-16 relative) and ``W t`` with it, far below this; but the
#: kernel counts a drive period as round(2 pi / (W dt)) steps, which
#: `sweep._timesteps.check_sampling_period` accepts up to 1e-6 relative off the true
#: period (``WHOLE_STEPS_RTOL * 1e3``): two runs k whole periods apart on the kernel's
#: clock then differ in true phase by up to 2 pi k 1e-6 rad. The tolerance is that bound
#: for k up to this run's ``W |t_s| / 2 pi`` periods, and at least 2 pi 1e-6 rad (a
#: catalogue records its phase, not its start, so the pilot's periods are not counted:
#: a pilot far later than the run with a period 1e-6 off whole steps is refused, and a
#: pilot with this run's t0 and t_transient always fits). A phase off by the tolerance
#: moves a stroboscopic point by about that many times the state's rate of change per
#: radian of drive phase, far inside the matching tolerance ATTRACTOR_TOL = 1e-3.
PHASE_RTOL = WHOLE_STEPS_RTOL * 1e3


def strobe_start(t0: float, t_transient: float, dt: float) -> float:
    """The time of a run's first stroboscopic sample [s]: ``t0 + n_transient dt``,
    its first step at or after ``t0 + t_transient``."""
    return float(t0) + transient_steps(float(t_transient), float(dt)) * float(dt)


def _phase(frequency: float, time: float) -> float:
    return float(np.mod(frequency * time, 2 * np.pi))


def drive_fields(frequency: float, t0: float, t_transient: float, dt: float,
                 count: int) -> dict:
    """The catalogue's ``strobe_phase`` and ``drive_frequency`` (``count`` values each)
    of rings sampled by a run with these settings at drive frequency ``frequency``
    [rad/s]."""
    phase = _phase(frequency, strobe_start(t0, t_transient, dt))
    return {"strobe_phase": np.full(count, phase),
            "drive_frequency": np.full(count, float(frequency))}


def dataset_drive(ds, axis: str, count: int) -> dict:
    """`drive_fields` of the run ``ds`` (its ``t0``, ``t_transient``, ``dt`` attributes
    and its drive frequency ``axis``, a coordinate or an attribute), or ``{}`` where the
    run has no one drive frequency (a grid over several)."""
    a = ds.attrs
    if axis in ds.coords:
        values = np.unique(np.asarray(ds[axis].values, dtype=np.float64))
    elif axis in a:
        values = np.atleast_1d(np.asarray(a[axis], dtype=np.float64))
    else:
        return {}
    if values.size != 1 or not all(name in a for name in ("t0", "t_transient", "dt")):
        return {}
    return drive_fields(float(values[0]), a["t0"], a["t_transient"], a["dt"], count)


def _parse(attractors, count: int, accepted: str):
    """The catalogue's (phase, frequency) arrays of ``count`` values, or None without
    them; refuses one of the two alone, or values that are not finite (a frequency
    <= 0)."""
    if not hasattr(attractors, "get"):
        return None
    given = [attractors.get(name) for name in FIELDS]
    if all(value is None for value in given):
        return None
    what = (f"accepted: both {FIELDS[0]!r} (the drive phase of the rings' samples, rad) "
            f"and {FIELDS[1]!r} (rad/s), one finite value or {count} per attractor "
            "(sweep.maps.attractor_catalogue records them), or neither (unchecked)")
    if any(value is None for value in given):
        missing = next(name for name, value in zip(FIELDS, given) if value is None)
        raise ValueError(f"attractors: a catalogue without {missing!r}; {what}; {accepted}")
    try:
        phase, frequency = (np.broadcast_to(np.asarray(value, dtype=np.float64), (count,))
                            for value in given)
    except (TypeError, ValueError):
        raise ValueError(f"attractors: {FIELDS[0]} {given[0]!r}, {FIELDS[1]} {given[1]!r} "
                         f"for {count} attractors; {what}") from None
    if not (np.all(np.isfinite(phase)) and np.all(np.isfinite(frequency))
            and np.all(frequency > 0)):
        raise ValueError(f"attractors: {FIELDS[0]} {phase.tolist()!r}, {FIELDS[1]} "
                         f"{frequency.tolist()!r}; {what}")
    return phase, frequency


def phase_mismatch(attractors, count: int, frequency: float, settings,
                   axis: str, accepted: str = "") -> str | None:
    """Why the catalogue ``attractors`` (``count`` rings) cannot match a run with
    ``settings`` (`sweep.settings.RunSettings`) at drive frequency ``frequency`` [rad/s]
    (grid axis ``axis``), or None where it can (or records no drive)."""
    parsed = _parse(attractors, count, accepted)
    if parsed is None:
        return None
    phases, frequencies = parsed
    start = float(settings.t0) + int(settings.n_transient) * float(settings.dt)
    period = 2 * np.pi / frequency
    for a, (phase, built) in enumerate(zip(phases, frequencies)):
        if abs(built - frequency) > PHASE_RTOL * frequency:
            return (f"attractors: the catalogue's attractor {a} was sampled at drive "
                    f"frequency {float(built)!r} rad/s, but this run's {axis} = "
                    f"{float(frequency)!r} rad/s (a catalogue holds the attractors of one "
                    f"scene); accepted: {axis} = {float(built)!r}, or a catalogue of this "
                    "scene (sweep.maps.pilot_catalogue with this run's settings)")
        own = _phase(frequency, start)
        off = abs(math.remainder(own - float(phase), 2 * np.pi))
        tolerance = PHASE_RTOL * (2 * np.pi + frequency * abs(start))
        if off > tolerance:
            reference = float(np.mod(phase, 2 * np.pi)) / frequency
            return (f"attractors: t0 + t_transient = {float(settings.t0)!r} + "
                    f"{float(settings.t_transient)!r} s puts this run's first stroboscopic "
                    f"sample at t = {start:.10g} s, drive phase {own:.6g} rad ({axis} = "
                    f"{float(frequency)!r} rad/s, period {period:.10g} s), but the "
                    f"catalogue's attractor {a} was sampled at drive phase "
                    f"{float(phase):.6g} rad, so no start could match it; accepted: "
                    f"t0 + t_transient = {reference:.10g} + k * {period:.10g} s (k a whole "
                    "number, on a step of dt), or a catalogue of a pilot with this run's "
                    "t0 and t_transient (sweep.maps.pilot_catalogue)")
    return None


def check_phase(attractors, count: int, frequency: float, settings, axis: str,
                accepted: str = "") -> None:
    """Refuse (ValueError, before any compute) a catalogue sampled at another drive
    phase or frequency than the run's (`phase_mismatch`)."""
    problem = phase_mismatch(attractors, count, frequency, settings, axis, accepted)
    if problem is not None:
        raise ValueError(problem)


def attributes(attractors, count: int) -> dict:
    """The catalogue's drive as dataset attributes (``attractors_strobe_phase``,
    ``attractors_drive_frequency``), or ``{}`` where it records none."""
    parsed = _parse(attractors, count, "")
    if parsed is None:
        return {}
    return {f"attractors_{name}": np.array(values, dtype=np.float64)
            for name, values in zip(FIELDS, parsed)}


def from_attributes(attrs) -> dict:
    """The catalogue's drive from dataset attributes (`attributes`), or ``{}``."""
    if not all(f"attractors_{name}" in attrs for name in FIELDS):
        return {}
    return {name: np.atleast_1d(np.asarray(attrs[f"attractors_{name}"], dtype=np.float64))
            for name in FIELDS}
