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
time (where no other drive's phase moves with it: below). The single pendulum's
catalogue (`sweep.engine`) and a system's (`sweep.system_attractors`) share this module.

A catalogue records, per attractor, ``drive_phase`` [rad] (``W t_s + phi mod 2 pi``) and
``drive_frequency`` [rad/s] (arrays of one value per ring, so that selecting attractors,
``catalogue[key][keep]``, keeps them). A catalogue without both (one built by hand from
rings) is not checked.

A scene may have other drives besides the strobe drive (`sweep.catalogue_drives`: the
single pendulum's `sweep.PivotDrive` ``a cos(nu t + psi)`` beside its forcing, a
system's `sweep.Forcing(on=...)` beside its driven pivot). The rings then lie on the
section of every drive's phase, and a catalogue records, per attractor, also
``other_drive_phases`` [rad]: a structured array of one row per attractor and a float64
field per other drive, named by its frequency axis (``pivot_frequency``), holding ``nu
t_s + psi mod 2 pi`` (nu its frequency, psi its phase constant; their values are of the
catalogue's scene, `sweep.catalogue_scene`). A strobe run with other drives names them
in the dataset attribute ``strobe_other_drives`` (JSON: frequency axis -> phase axis),
which `dataset_drive` reads. Along a ring of period P the other drive's phase at the
samples takes the values ``nu t_s + psi + m nu T`` (m = 0 .. P - 1, T the strobe
period), which the pilot saw: a run whose other drive's phase at its first sample is
one of them samples the same sections in another order and is accepted (a shift of t0 +
t_transient by whole strobe periods always is: with nu / W = p / q the drives repeat
every q samples, and so does a ring on which both act, q dividing its period); any
other phase is refused by `check_phase`: the single pendulum's run of another forcing
phase phi shifted onto the strobe drive's section (t0 by a fraction of a period) moved
its pivot's phase, and its stroboscopic points lay on another section of the pivot (no
start matched; nothing said so). A catalogue without ``other_drive_phases`` (an older
one, one built by hand, one of a scene with one drive) is not checked for them; a drive
only the catalogue or only the run has is not compared (its parameters are of the
scene, which `sweep.catalogue_scene` compares).

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

import json
import math

import numpy as np

from ._timesteps import WHOLE_STEPS_RTOL, transient_steps
from .catalogue_scene import (
    as_record,
    one_value,
    record_columns,
    record_from_json,
    record_json,
)

__all__ = ["FIELDS", "LEGACY_FIELD", "OTHER_ATTRIBUTE", "OTHER_FIELD", "PHASE_RTOL",
           "attributes", "check_phase", "dataset_drive", "drive_fields", "from_attributes",
           "other_drives_attribute", "phase_axis", "phase_mismatch", "strobe_start"]

#: The catalogue's keys of its drive: per attractor, the drive phase ``W t_s + phi`` of
#: its samples [rad] and the drive's angular frequency [rad/s].
FIELDS = ("drive_phase", "drive_frequency")

#: The catalogue's key of its other drives' phases ``nu t_s + psi mod 2 pi`` [rad]: a
#: structured array, a row per attractor and a float64 field per drive, named by its
#: frequency axis.
OTHER_FIELD = "other_drive_phases"

#: The dataset attribute in which a strobe run names its other drives: JSON of each
#: one's frequency axis -> its phase constant's axis (`sweep.catalogue_drives`).
OTHER_ATTRIBUTE = "strobe_other_drives"

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
                 count: int, phase: float = 0.0, others: dict | None = None) -> dict:
    """The catalogue's ``drive_phase`` and ``drive_frequency`` (``count`` values each)
    of rings sampled by a run with these settings at drive frequency ``frequency``
    [rad/s] and phase constant ``phase`` [rad], and ``other_drive_phases`` of its
    ``others`` (frequency axis -> (frequency [rad/s], phase constant [rad])), where
    given."""
    start = strobe_start(t0, t_transient, dt)
    fields = {"drive_phase": np.full(count, _phase(frequency, start, float(phase))),
              "drive_frequency": np.full(count, float(frequency))}
    if others:
        fields[OTHER_FIELD] = as_record(
            {name: _phase(float(nu), start, float(psi))
             for name, (nu, psi) in sorted(others.items())}, count)
    return fields


def other_drives_attribute(others: dict) -> dict:
    """The attribute in which a strobe run names its other drives (`OTHER_ATTRIBUTE`:
    JSON of each one's frequency axis -> its phase constant's axis), of ``others`` as
    `sweep.catalogue_drives` gives them; ``{}`` without one."""
    if not others:
        return {}
    return {OTHER_ATTRIBUTE: json.dumps({name: phase for name, (_, phase, _) in
                                         others.items()})}


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
    return drive_fields(frequency, a["t0"], a["t_transient"], a["dt"], count, phase,
                        _dataset_others(ds))


def _dataset_others(ds) -> dict:
    """The other drives the run ``ds`` names (``strobe_other_drives``) of one frequency
    and phase constant each: frequency axis -> (frequency, phase constant); a drive of
    several values in ``ds`` (a grid over them) is left out."""
    others = {}
    for name, phase_name in json.loads(ds.attrs.get(OTHER_ATTRIBUTE, "{}")).items():
        recorded = _recorded(ds, name)
        frequency = None if recorded is None else one_value(recorded)
        recorded = None if phase_name is None else _recorded(ds, phase_name)
        phase = 0.0 if recorded is None else one_value(recorded)
        if frequency is not None and phase is not None:
            others[name] = (frequency, phase)
    return others


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


def _parse_others(attractors, count: int) -> dict | None:
    """The catalogue's ``other_drive_phases`` as frequency axis -> its ``count`` phases
    [rad], or None without them; refuses anything else (values not finite)."""
    given = attractors.get(OTHER_FIELD) if hasattr(attractors, "get") else None
    if given is None:
        return None
    columns = record_columns(given)
    try:
        phases = None if columns is None else {
            name: np.broadcast_to(value, (count,)) for name, value in columns.items()}
    except ValueError:  # neither one value nor one per attractor
        phases = None
    if phases is None:
        raise ValueError(f"attractors: a catalogue's {OTHER_FIELD} {given!r} for {count} "
                         "attractors; accepted: the other drives' phases nu t + psi (rad) "
                         "as sweep.maps.attractor_catalogue records them (a structured "
                         "array, a row per attractor and a field per drive, named by its "
                         "frequency axis), a mapping of those names to one finite value or "
                         f"{count}, or none (unchecked)")
    return phases


def _other_mismatch(attractors, count: int, frequency: float, settings, axis: str,
                    others: dict) -> str | None:
    """Why the catalogue's ``other_drive_phases`` cannot match the run's ``others``
    (frequency axis -> (frequency [rad/s], phase axis or None, phase constant [rad])),
    the strobe drive (``axis``, ``frequency``) matching; None where they can."""
    recorded = _parse_others(attractors, count)
    if not recorded or not others:
        return None
    periods = np.ones(count, dtype=np.int64)
    if attractors.get("period") is not None:
        periods = np.broadcast_to(np.asarray(attractors["period"], dtype=np.int64), (count,))
    dt = float(settings.dt)
    start = float(settings.t0) + int(settings.n_transient) * dt
    strobe = round(2 * np.pi / (frequency * dt)) * dt  # the kernel's period [s]
    for a in range(count):
        for name in sorted(set(recorded) & set(others)):
            nu, phase_name, psi = others[name]
            nu, psi = float(nu), float(psi)
            own = _phase(nu, start, psi)
            ring = [float(np.mod(recorded[name][a] + nu * m * strobe, 2 * np.pi))
                    for m in range(max(int(periods[a]), 1))]
            # as the strobe drive's tolerance (PHASE_RTOL), over the m periods, and with
            # the strobe drive's own tolerance in time (its phase's / W) moving this one
            if any(abs(math.remainder(own - value, 2 * np.pi))
                   <= PHASE_RTOL * (2 * np.pi * (1 + nu / frequency)
                                    + nu * (abs(start) + m * strobe))
                   for m, value in enumerate(ring)):
                continue
            shown = ", ".join(f"{value:.6g}" for value in ring[:4]) \
                + (", ..." if len(ring) > 4 else "")
            drive = f"{name} = {nu!r} rad/s"
            if phase_name is not None:
                drive += f", {phase_name} = {psi!r} rad"
            names = [n for n in (phase_axis(axis), phase_name) if n]
            constants = " and ".join(names)
            return (f"attractors: t0 + t_transient = {float(settings.t0)!r} + "
                    f"{float(settings.t_transient)!r} s puts this run's first stroboscopic "
                    f"sample at t = {start:.10g} s, where its other drive ({drive}, period "
                    f"{2 * np.pi / nu if nu > 0 else math.inf:.10g} s) is at phase "
                    f"{'nu t + psi' if phase_name is not None else 'nu t'} = {own:.6g} rad, "
                    f"but along the catalogue's attractor {a} (a ring of period "
                    f"{len(ring)}) that drive's phase at the samples was {shown} rad, so "
                    f"this run's stroboscopic points lie on another section of it and no "
                    f"start could match it; accepted: t0 + t_transient shifted from the "
                    f"pilot's by a whole number of periods of {axis} ("
                    f"{2 * np.pi / frequency:.10g} s) with the pilot's "
                    f"{constants or 'phase constants'}, or a catalogue of a pilot with this "
                    f"run's {', '.join(['t0', 't_transient', *names][:-1])} and "
                    f"{(['t_transient', *names])[-1]} "
                    "(sweep.maps.pilot_catalogue)")
    return None


def phase_mismatch(attractors, count: int, frequency: float, settings,
                   axis: str, accepted: str = "", phase: float = 0.0,
                   others: dict | None = None) -> str | None:
    """Why the catalogue ``attractors`` (``count`` rings) cannot match a run with
    ``settings`` (`sweep.settings.RunSettings`) at drive frequency ``frequency`` [rad/s]
    (grid axis ``axis``) and drive phase constant ``phase`` [rad] (its axis
    `phase_axis`), with other drives ``others`` (frequency axis -> (frequency [rad/s],
    phase axis or None, phase constant [rad]), `sweep.catalogue_drives`), or None where
    it can (or records no drive)."""
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
    return _other_mismatch(attractors, count, frequency, settings, axis, others or {})


def check_phase(attractors, count: int, frequency: float, settings, axis: str,
                accepted: str = "", phase: float = 0.0, others: dict | None = None) -> None:
    """Refuse (ValueError, before any compute) a catalogue sampled at another drive
    phase or frequency than the run's, or at another phase of one of its other drives
    ``others`` (`phase_mismatch`)."""
    problem = phase_mismatch(attractors, count, frequency, settings, axis, accepted, phase,
                             others)
    if problem is not None:
        raise ValueError(problem)


def attributes(attractors, count: int) -> dict:
    """The catalogue's drive as dataset attributes (``attractors_drive_phase``, or an
    old catalogue's ``attractors_strobe_phase``, and ``attractors_drive_frequency``;
    ``attractors_other_drive_phases``, JSON of each other drive's phases, where it has
    them), or ``{}`` where it records none."""
    parsed = _parse(attractors, count, "")
    out = {}
    if parsed is not None:
        phase, frequency, legacy = parsed
        key = LEGACY_FIELD if legacy else FIELDS[0]
        out = {f"attractors_{key}": np.array(phase, dtype=np.float64),
               f"attractors_{FIELDS[1]}": np.array(frequency, dtype=np.float64)}
    others = _parse_others(attractors, count)
    if others:
        out[f"attractors_{OTHER_FIELD}"] = record_json(others)
    return out


def from_attributes(attrs) -> dict:
    """The catalogue's drive from dataset attributes (`attributes`: ``drive_phase``, or
    an old catalogue's ``strobe_phase``, and ``drive_frequency``; ``other_drive_phases``
    as a structured array where kept), or ``{}``."""
    key = FIELDS[0] if f"attractors_{FIELDS[0]}" in attrs else LEGACY_FIELD
    names = (key, FIELDS[1])
    out = {}
    if all(f"attractors_{name}" in attrs for name in names):
        out = {name: np.atleast_1d(np.asarray(attrs[f"attractors_{name}"], dtype=np.float64))
               for name in names}
    if f"attractors_{OTHER_FIELD}" in attrs:
        record = record_from_json(attrs[f"attractors_{OTHER_FIELD}"])
        if record is not None:
            out[OTHER_FIELD] = record
    return out
