"""The drive phase at which an attractor catalogue's stroboscopic rings were sampled,
recorded in the catalogue and checked against a run that uses it.

A ``strobe`` run samples the state at ``t_s + k 2 pi / W`` (k = 0, 1, ...), where
``t_s = t0 + n_transient dt`` is its first step at or after ``t0 + t_transient``
(`sweep.settings.RunSettings`) and W the drive's angular frequency. The Poincare section
the rings lie on is the drive's phase at those samples, ``W t_s + phi mod 2 pi`` [rad],
phi the drive's own phase constant (the single pendulum's ``forcing_phase``: ``A sin(W t
+ phi)``; a system's ``forcing_phase_<coordinate>`` of a `sweep.Forcing` on one
coordinate, `phase_axis`; 0 for a drive without one, the double pendulum's pivot ``a
cos(nu t)`` or a declared system's ``drive_frequency_axis``, whose phase constants, if
any, are scene parameters, `sweep.catalogue_scene`). A run whose section is another one
never meets a catalogued point, so every start would be labelled -1; `check_phase`
refuses it before any compute. A run of another phi whose ``t0 + t_transient`` is
shifted to the same section is accepted: its trajectories are the pilot's shifted in
time. The single pendulum's catalogue (`sweep.engine`) and a system's
(`sweep.system_attractors`) share this module.

A catalogue records, per attractor, ``drive_phase`` [rad] (``W t_s + phi mod 2 pi``) and
``drive_frequency`` [rad/s] (arrays of one value per ring, so that selecting attractors,
``catalogue[key][keep]``, keeps them). A catalogue without both (one built by hand from
rings) is not checked.

Catalogues made before the drive's phase constant was counted (netCDF attribute
``attractors_strobe_phase``) record ``strobe_phase``, the phase of the clock alone, ``W
t_s mod 2 pi``, and not their pilot's phi. Such a catalogue is read with its old
meaning: it is compared with the run's clock phase ``W t_s``, as before, which assumes
the pilot's phi was the run's (a phi it never recorded cannot be checked, and reading
it as phi = 0 would refuse every old catalogue of a ``sin(W t + pi/2)`` forcing used
with its own scene). So nothing an old catalogue was accepted or refused for changes; a
run file or dataset that kept it (``sweep.io.run_arguments``) keeps ``strobe_phase``.
Where a catalogue has both, ``drive_phase`` counts.
"""

from __future__ import annotations

import math

import numpy as np

from ._timesteps import WHOLE_STEPS_RTOL, transient_steps
from .catalogue_scene import one_value

__all__ = ["FIELDS", "LEGACY_FIELD", "PHASE_RTOL", "attributes", "check_phase",
           "dataset_drive", "drive_fields", "from_attributes", "phase_axis",
           "phase_mismatch", "strobe_start"]

#: The catalogue's keys of its drive: per attractor, the drive phase ``W t_s + phi`` of
#: its samples [rad] and the drive's angular frequency [rad/s].
FIELDS = ("drive_phase", "drive_frequency")

#: The key of an older catalogue's phase, the clock's alone (``W t_s``; see above).
LEGACY_FIELD = "strobe_phase"

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
#: radian of drive phase, far inside the matching tolerance ATTRACTOR_TOL = 1e-3. (The
#: drive's phase constant phi is given, not computed: a deg -> rad conversion rounds it
#: by 1e-16 relative.)
PHASE_RTOL = WHOLE_STEPS_RTOL * 1e3


def phase_axis(frequency_axis: str) -> str | None:
    """The grid axis of the phase constant of the drive whose frequency is
    ``frequency_axis``: ``forcing_phase`` for the single pendulum's ``forcing_frequency``,
    ``forcing_phase_<coordinate>`` for a system's ``forcing_frequency_<coordinate>``;
    None for a drive without one (a pivot ``a cos(nu t)``, a declared system's
    ``drive_frequency_axis``)."""
    if frequency_axis == "forcing_frequency" or frequency_axis.startswith("forcing_frequency_"):
        return "forcing_phase" + frequency_axis[len("forcing_frequency"):]
    return None


def strobe_start(t0: float, t_transient: float, dt: float) -> float:
    """The time of a run's first stroboscopic sample [s]: ``t0 + n_transient dt``,
    its first step at or after ``t0 + t_transient``."""
    return float(t0) + transient_steps(float(t_transient), float(dt)) * float(dt)


def _phase(frequency: float, time: float, constant: float = 0.0) -> float:
    return float(np.mod(frequency * time + constant, 2 * np.pi))


def drive_fields(frequency: float, t0: float, t_transient: float, dt: float,
                 count: int, phase: float = 0.0) -> dict:
    """The catalogue's ``drive_phase`` and ``drive_frequency`` (``count`` values each)
    of rings sampled by a run with these settings at drive frequency ``frequency``
    [rad/s] and phase constant ``phase`` [rad]."""
    value = _phase(frequency, strobe_start(t0, t_transient, dt), float(phase))
    return {"drive_phase": np.full(count, value),
            "drive_frequency": np.full(count, float(frequency))}


def _recorded(ds, name: str):
    """The values of ``name`` in ``ds`` (a coordinate's, else an attribute's), or None
    where ``ds`` has no ``name``."""
    if name in ds.coords:
        return ds[name].values
    return ds.attrs.get(name)


def dataset_drive(ds, axis: str, count: int) -> dict:
    """`drive_fields` of the run ``ds`` (its ``t0``, ``t_transient``, ``dt`` attributes,
    its drive frequency ``axis`` and the drive's phase constant `phase_axis`, each a
    coordinate or an attribute; a phase it does not record is 0, the parameter's
    default), or ``{}`` where the run has no one drive frequency or phase (a grid over
    several)."""
    a = ds.attrs
    frequencies = _recorded(ds, axis)
    frequency = None if frequencies is None else one_value(frequencies)
    name = phase_axis(axis)
    phases = None if name is None else _recorded(ds, name)
    phase = 0.0 if phases is None else one_value(phases)
    if frequency is None or phase is None \
            or not all(key in a for key in ("t0", "t_transient", "dt")):
        return {}
    return drive_fields(frequency, a["t0"], a["t_transient"], a["dt"], count, phase)


def _parse(attractors, count: int, accepted: str):
    """The catalogue's (phase, frequency) arrays of ``count`` values and whether the
    phase is the legacy ``strobe_phase`` (the clock's alone), or None without them;
    refuses a phase or a frequency alone, or values that are not finite (a frequency
    <= 0)."""
    if not hasattr(attractors, "get"):
        return None
    key = FIELDS[0] if attractors.get(FIELDS[0]) is not None else LEGACY_FIELD
    names = (key, FIELDS[1])
    given = [attractors.get(name) for name in names]
    if all(value is None for value in given):
        return None
    what = (f"accepted: both {FIELDS[0]!r} (the drive phase W t + phi of the rings' "
            f"samples, rad) and {FIELDS[1]!r} (rad/s), one finite value or {count} per "
            "attractor (sweep.maps.attractor_catalogue records them), or neither "
            "(unchecked)")
    if any(value is None for value in given):
        missing = next(name for name, value in zip(names, given) if value is None)
        raise ValueError(f"attractors: a catalogue without {missing!r}; {what}; {accepted}")
    try:
        phase, frequency = (np.broadcast_to(np.asarray(value, dtype=np.float64), (count,))
                            for value in given)
    except (TypeError, ValueError):
        raise ValueError(f"attractors: {key} {given[0]!r}, {FIELDS[1]} {given[1]!r} "
                         f"for {count} attractors; {what}") from None
    if not (np.all(np.isfinite(phase)) and np.all(np.isfinite(frequency))
            and np.all(frequency > 0)):
        raise ValueError(f"attractors: {key} {phase.tolist()!r}, {FIELDS[1]} "
                         f"{frequency.tolist()!r}; {what}")
    return phase, frequency, key == LEGACY_FIELD


def phase_mismatch(attractors, count: int, frequency: float, settings,
                   axis: str, accepted: str = "", phase: float = 0.0) -> str | None:
    """Why the catalogue ``attractors`` (``count`` rings) cannot match a run with
    ``settings`` (`sweep.settings.RunSettings`) at drive frequency ``frequency`` [rad/s]
    (grid axis ``axis``) and drive phase constant ``phase`` [rad] (its axis
    `phase_axis`), or None where it can (or records no drive)."""
    parsed = _parse(attractors, count, accepted)
    if parsed is None:
        return None
    phases, frequencies, legacy = parsed
    constant = 0.0 if legacy else float(phase)  # an old catalogue: the clock's phase
    name = phase_axis(axis)
    start = float(settings.t0) + int(settings.n_transient) * float(settings.dt)
    period = 2 * np.pi / frequency
    for a, (recorded, built) in enumerate(zip(phases, frequencies)):
        if abs(built - frequency) > PHASE_RTOL * frequency:
            return (f"attractors: the catalogue's attractor {a} was sampled at drive "
                    f"frequency {float(built)!r} rad/s, but this run's {axis} = "
                    f"{float(frequency)!r} rad/s (a catalogue holds the attractors of one "
                    f"scene); accepted: {axis} = {float(built)!r}, or a catalogue of this "
                    "scene (sweep.maps.pilot_catalogue with this run's settings)")
        own = _phase(frequency, start, constant)
        off = abs(math.remainder(own - float(recorded), 2 * np.pi))
        tolerance = PHASE_RTOL * (2 * np.pi + frequency * abs(start))
        if off > tolerance:
            # rounded to 1e-12: a reference of 1e-15 s is shown as 0
            reference = round(float(np.mod(recorded - constant, 2 * np.pi)) / frequency, 12)
            shown = "W t" if legacy or name is None else "W t + phi"
            drive = f"{axis} = {float(frequency)!r} rad/s"
            if name is not None and not legacy:
                drive += f", {name} = {constant!r} rad"
            other = ""
            if name is not None and not legacy:
                wanted = round(float(np.mod(recorded - frequency * start, 2 * np.pi)), 12)
                other = f", {name} = {wanted:.10g} rad (mod 2 pi) with this t0 + t_transient"
            return (f"attractors: t0 + t_transient = {float(settings.t0)!r} + "
                    f"{float(settings.t_transient)!r} s puts this run's first stroboscopic "
                    f"sample at t = {start:.10g} s, drive phase {shown} = {own:.6g} rad "
                    f"({drive}, period {period:.10g} s), but the catalogue's attractor {a} "
                    f"was sampled at drive phase {float(recorded):.6g} rad"
                    f"{' (its strobe_phase, the clock W t alone)' if legacy else ''}, so "
                    f"no start could match it; accepted: t0 + t_transient = "
                    f"{reference:.10g} + k * {period:.10g} s (k a whole number, on a step "
                    f"of dt){other}, or a catalogue of a pilot with this run's t0 and "
                    f"t_transient{f' and {name}' if name is not None else ''} "
                    "(sweep.maps.pilot_catalogue)")
    return None


def check_phase(attractors, count: int, frequency: float, settings, axis: str,
                accepted: str = "", phase: float = 0.0) -> None:
    """Refuse (ValueError, before any compute) a catalogue sampled at another drive
    phase or frequency than the run's (`phase_mismatch`)."""
    problem = phase_mismatch(attractors, count, frequency, settings, axis, accepted, phase)
    if problem is not None:
        raise ValueError(problem)


def attributes(attractors, count: int) -> dict:
    """The catalogue's drive as dataset attributes (``attractors_drive_phase``, or an
    old catalogue's ``attractors_strobe_phase``, and ``attractors_drive_frequency``),
    or ``{}`` where it records none."""
    parsed = _parse(attractors, count, "")
    if parsed is None:
        return {}
    phase, frequency, legacy = parsed
    key = LEGACY_FIELD if legacy else FIELDS[0]
    return {f"attractors_{key}": np.array(phase, dtype=np.float64),
            f"attractors_{FIELDS[1]}": np.array(frequency, dtype=np.float64)}


def from_attributes(attrs) -> dict:
    """The catalogue's drive from dataset attributes (`attributes`: ``drive_phase``, or
    an old catalogue's ``strobe_phase``, and ``drive_frequency``), or ``{}``."""
    key = FIELDS[0] if f"attractors_{FIELDS[0]}" in attrs else LEGACY_FIELD
    names = (key, FIELDS[1])
    if not all(f"attractors_{name}" in attrs for name in names):
        return {}
    return {name: np.atleast_1d(np.asarray(attrs[f"attractors_{name}"], dtype=np.float64))
            for name in names}
