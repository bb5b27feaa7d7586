"""An attractor catalogue of a scene with two drives records the phase of the second one
at its samples (``other_drive_phases``, `sweep.strobe_phase`): a run that samples another
section of that drive is refused before any compute, one that samples the pilot's
sections (in another order) is accepted and labels as it should, and the field survives
a file and ``sweep.io.run_arguments``.

The single pendulum: the forced map of tests/test_attractor_catalogue.py (same run
settings) with a weak pivot drive ``0.05 cos(nu t)`` beside its forcing ``1.66 sin(t +
pi/2)``. A system: the damped double pendulum on a pivot driven at nu = 4 rad/s with a
Forcing at W = 2 rad/s on theta1.
"""

import numpy as np
import pytest

import sweep
from sweep import maps

PERIOD = 2 * np.pi  # the forcing's, W = 1 rad/s
EARLY = dict(t_end=320 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD,
             observe=("strobe",), progress=False, stop_early=True)
GRID = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9))


def _scene(nu, phi=np.pi / 2):
    """The forced map's scene with a pivot drive of angular frequency ``nu`` [rad/s]
    and the forcing's phase constant ``phi`` [rad]."""
    return sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, phi), sweep.PivotDrive(0.05, nu)))


@pytest.fixture(scope="module")
def catalogues():
    """The pilot catalogues (9 x 9 starts, the pilot's t0 = 0, t_transient = 20
    forcing periods) at nu = 2 rad/s (the pivot's period divides the forcing's) and
    nu = 2.5 rad/s (every second forcing period)."""
    return {nu: maps.pilot_catalogue(_scene(nu), GRID, 9, **EARLY) for nu in (2.0, 2.5)}


def test_the_catalogue_records_the_other_drives_phase(catalogues):
    """Per attractor, the pivot's phase nu t_s + psi at the first sample t_s = 40 pi s:
    80 pi and 100 pi rad, 0 mod 2 pi; at nu = 2.5 the rings' periods are even."""
    for catalogue in catalogues.values():
        phases = catalogue["other_drive_phases"]
        assert phases.dtype.names == ("pivot_frequency",)
        assert phases.shape == catalogue["period"].shape
        # 2000 steps of dt summed in float64 round nu t_s by ~1e-13 rad
        np.testing.assert_allclose(np.cos(phases["pivot_frequency"]), 1.0, atol=1e-9)
    assert catalogues[2.5]["period"].tolist() == [2, 4]  # the pivot repeats every 2


@pytest.mark.parametrize("nu, words", [
    (2.0, r"its other drive \(pivot_frequency = 2\.0 rad/s, pivot_phase = 0\.0 rad, period "
          r"3\.141592654 s\) is at phase nu t \+ psi = 3\.14159 rad, but along the "
          r"catalogue's attractor 0 \(a ring of period 1\) that drive's phase at the samples "
          r"was \S+ rad, so this run's stroboscopic points lie on another section of it"),
    (2.5, r"pivot_frequency = 2\.5 rad/s, .* is at phase nu t \+ psi = 3\.92699 rad, but "
          r"along the catalogue's attractor 0 \(a ring of period 2\) that drive's phase at "
          r"the samples was \S+, 3\.14159 rad"),
])
def test_a_forcing_phase_shifted_onto_the_section_that_moves_the_pivot_is_refused(
        catalogues, no_compute, nu, words):
    """phi = 0 with t0 a quarter forcing period later samples the forcing at the
    pilot's W t + phi (accepted so far), but the pivot at nu T / 4 rad further, a
    section the pilot's rings never were on: no start could match (at nu = 2 each of
    81 starts was labelled -1 by the kernel). Refused, naming the pivot, both phases and
    what is accepted."""
    accepted = (r"accepted: t0 \+ t_transient shifted from the pilot's by a whole number "
                r"of periods of forcing_frequency \(6\.283185307 s\) with the pilot's "
                r"forcing_phase and pivot_phase, or a catalogue of a pilot with this run's "
                r"t0, t_transient, forcing_phase and pivot_phase")
    with pytest.raises(ValueError, match=words + ".*" + accepted):
        sweep.run(_scene(nu, 0.0), GRID,
                  **dict(EARLY, t0=PERIOD / 4, t_end=320.25 * PERIOD),
                  attractors=catalogues[nu])


def test_a_whole_forcing_period_later_is_accepted_and_labels_alike(catalogues):
    """t0 one forcing period later: at nu = 2 the pivot's phase is the pilot's too
    (its period divides the forcing's), the map is the pilot-settings map's, start by
    start; at nu = 2.5 the pivot is half a turn further, where the pilot's rings were
    every second sample, so the run samples the same sections in the other order: every
    start is matched, and with the attractor the run finds without a catalogue (the
    strict early stop of the pilot, whose basins are a partition equal to it)."""
    # the catalogues record the pivot's phase: the acceptance is the check's, not that
    # of a catalogue it cannot check
    assert all("other_drive_phases" in catalogue for catalogue in catalogues.values())
    later = dict(EARLY, t0=PERIOD, t_end=321 * PERIOD)
    same = sweep.run(_scene(2.0), GRID, **EARLY, attractors=catalogues[2.0])
    shifted = sweep.run(_scene(2.0), GRID, **later, attractors=catalogues[2.0])
    assert (shifted.attractor >= 0).all()
    np.testing.assert_array_equal(shifted.attractor.values, same.attractor.values)
    matched = sweep.run(_scene(2.5), GRID, **later, attractors=catalogues[2.5])
    alone = maps.basins(sweep.run(_scene(2.5), GRID, **later)).values
    labels = maps.basins(matched).values
    assert (matched.attractor >= 0).all() and (alone >= 0).all()
    pairs = set(zip(labels.ravel().tolist(), alone.ravel().tolist()))
    assert len(pairs) == len({a for a, _ in pairs}) == len({b for _, b in pairs}) == 2


def test_the_field_survives_a_file_and_run_arguments(catalogues, tmp_path):
    """A map with the catalogue keeps its other drives' phases in the attributes
    (``attractors_other_drive_phases``): after a save and a load, ``run_arguments``
    gives them back, and the catalogue of the loaded map records them (from its
    ``strobe_other_drives``)."""
    catalogue = catalogues[2.0]
    ds = sweep.run(_scene(2.0), GRID, **EARLY, attractors=catalogue)
    sweep.save(ds, tmp_path / "map.nc")
    loaded = sweep.load(tmp_path / "map.nc")
    assert loaded.attrs["strobe_other_drives"] == '{"pivot_frequency": "pivot_phase"}'
    again = sweep.io.run_arguments(loaded)["attractors"]
    np.testing.assert_array_equal(again["other_drive_phases"], catalogue["other_drive_phases"])
    np.testing.assert_array_equal(maps.attractor_catalogue(loaded)["other_drive_phases"],
                                  catalogue["other_drive_phases"])


def test_without_the_field_a_catalogue_is_checked_as_before(catalogues, no_compute):
    """An older or hand-made catalogue without ``other_drive_phases`` is not checked for
    the pivot (the refused run above is accepted, as it was); a field that is not a
    phase per attractor is refused."""
    old = {k: v for k, v in catalogues[2.0].items() if k != "other_drive_phases"}
    sweep.engine.prepare(_scene(2.0, 0.0), GRID,
                         **dict(EARLY, t0=PERIOD / 4, t_end=320.25 * PERIOD), attractors=old)
    with pytest.raises(ValueError, match=r"a catalogue's other_drive_phases .*; accepted: "
                                         r"the other drives' phases nu t \+ psi"):
        sweep.engine.prepare(_scene(2.0), GRID, **EARLY,
                             attractors=dict(old, other_drive_phases={
                                 "pivot_frequency": [np.nan]}))


def _system(phase=0.0):
    """A double pendulum on a pivot driven at nu = 4 rad/s (the strobe drive) with a
    Forcing of W = 2 rad/s and phase constant ``phase`` on theta1; heavily damped, so
    both starts of SYSTEM_GRID settle on one orbit of period 2 pivot periods (the
    forcing's) within 48 periods."""
    return sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=4.0, effects=(
        sweep.Damping(2.0), sweep.Forcing(0.5, 2.0, phase, on="theta1")))


SYSTEM_PERIOD = np.pi / 2  # the pivot's
SYSTEM_GRID = sweep.Grid(theta1_0=[0.0, 0.3], theta2_0=[0.0])
SYSTEM_RUN = dict(t_end=80 * SYSTEM_PERIOD, dt=SYSTEM_PERIOD / 40, progress=False)


def test_a_systems_catalogue_records_and_checks_its_other_drive():
    """The system's catalogue records its forcing's phase W t_s + phi (0 at t_s = 24 pi)
    and the pilot names the forcing as its other drive; a run one pivot period later
    (the forcing half a turn further, which the period-2 ring had every second sample)
    is accepted and matches both starts; a catalogue whose forcing phase is a quarter
    turn off every sample of its ring (a section the run never meets) is refused before
    any compute, naming the forcing. (A system's strobe drive with a second one is a
    pivot or a declared drive, without a phase constant: every run the strobe check
    accepts is whole strobe periods off, so the check guards catalogues edited or made
    by hand.)"""
    pilot = sweep.run(_system(), SYSTEM_GRID, observe=("strobe",),
                      t_transient=48 * SYSTEM_PERIOD, **SYSTEM_RUN)
    assert pilot.attrs["strobe_other_drives"] == \
        '{"forcing_frequency_theta1": "forcing_phase_theta1"}'
    catalogue = maps.attractor_catalogue(pilot)
    assert catalogue["period"].tolist() == [2]
    # 48 pivot periods of 40 steps: W t_s = 48 pi, rounded in float64 to ~1e-13 rad
    np.testing.assert_allclose(
        np.cos(catalogue["other_drive_phases"]["forcing_frequency_theta1"]), 1.0, atol=1e-9)
    kwargs = dict(SYSTEM_RUN, observe=("attractor",), attractors=catalogue, stop_early=True)
    later = sweep.run(_system(), SYSTEM_GRID,
                      **dict(kwargs, t0=SYSTEM_PERIOD, t_end=81 * SYSTEM_PERIOD))
    np.testing.assert_array_equal(later["attractor"].values, [[0], [0]])
    off = dict(catalogue, other_drive_phases=catalogue["other_drive_phases"].copy())
    off["other_drive_phases"]["forcing_frequency_theta1"] += np.pi / 2
    with pytest.raises(ValueError, match=r"its other drive \(forcing_frequency_theta1 = "
                                         r"2\.0 rad/s, forcing_phase_theta1 = 0\.0 rad, "
                                         r"period 3\.141592654 s\) is at phase nu t \+ psi "
                                         r"= 0 rad, .* whole number of periods of "
                                         r"pivot_frequency \(1\.570796327 s\)"):
        sweep.engine.prepare(_system(), SYSTEM_GRID, **dict(kwargs, attractors=off))
