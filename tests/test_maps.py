"""Maps against physics that says what the right answer is."""

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import maps

G, L = 9.81, 1.0
W0SQ = G / L


@pytest.fixture(scope="module")
def conservative():
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 81), omega0=np.linspace(-8, 8, 81))
    return sweep.run(sweep.Scene(gravity=G, length=L), grid, t_end=20.0, dt=0.01,
                     t_transient=5.0, observe=("final", "winding", "omega_mean", "energy"))


def _relative_energy_above_separatrix(ds):
    theta0, omega0 = xr.broadcast(ds.theta0, ds.omega0)
    energy = omega0**2 / 2 + W0SQ * (1 - np.cos(theta0))
    return energy / (2 * W0SQ) - 1


# Width of the band around the separatrix that is left out, in relative energy delta.
# A rotation needs a time ln(16/delta)/omega_n per turn, so over the 15 s steady window
# (omega_n = 3.13 rad/s) any delta > 16 exp(-omega_n 15 / 2) ~ 1e-9 completes two turns;
# RK4's energy error at dt = 0.01 over 20 s is below 1e-8 relative. 1e-6 covers both with
# a wide margin, and the test also checks that the band is a tiny part of the grid.
BAND = 1e-6


@pytest.mark.parametrize("use_omega_mean", [True, False])
def test_motion_agrees_with_exact_energy_criterion(conservative, use_omega_mean):
    ds = conservative if use_omega_mean else conservative.drop_vars("omega_mean")
    code = maps.motion(ds)
    delta = _relative_energy_above_separatrix(ds)
    outside = np.abs(delta) > BAND
    assert outside.mean() > 0.97  # the band excludes only the separatrix's neighbourhood
    expected = xr.where(delta > 0, np.sign(ds.omega0), 0)
    # theta0 = +-pi with omega0 = 0 is the upright equilibrium: exactly on the separatrix
    assert (code.where(outside) == expected.where(outside)).where(outside, True).all()
    assert set(np.unique(code.values)) <= {-1, 0, 1}
    assert code.attrs["flag_meanings"].split()[:3] == ["rotation_negative", "libration",
                                                        "rotation_positive"]


def test_motion_of_failed_trajectories_is_unresolved():
    with pytest.warns(RuntimeWarning):
        ds = sweep.run(sweep.Scene(), sweep.Grid(damping=[0.0, 1e5], theta0=[1.0]),
                       t_end=1.0, dt=0.01, observe=("winding",),
                       check_stability=False)  # c = 1e5: unstable on purpose
    np.testing.assert_array_equal(maps.motion(ds).values.ravel(), [0, -127])


@pytest.fixture(scope="module")
def damped():
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 41), omega0=np.linspace(-12, 12, 41))
    return sweep.run(sweep.Scene(gravity=G, length=L, effects=(sweep.Damping(0.4),)), grid,
                     t_end=30.0, dt=0.01, observe=("final", "winding", "energy"))


@pytest.mark.parametrize("source", ["winding", "final"])
def test_motion_of_the_damped_pendulum_is_the_sense_of_its_final_well(damped, source):
    """Every start of the damped grid lies in well 0 (theta0 in [-pi, pi]; the edges
    +-pi too: the well index rounds half to even) and ends captured in some well k, so it
    went over |k| tops in the sense of k: motion (min_turns = 1) is sign(k), from the
    winding or, without it, from theta_final. The former net turns,
    trunc((theta_final - theta0) / 2 pi), made the starts just right of theta0 = 0 that
    go over the top once count 0 turns (libration) while those just left counted 1."""
    ds = damped if source == "winding" else damped.drop_vars("winding")
    wells = maps.well(ds).values
    # captured by t = 30 s (energy down by e^-12), but for the two starts upright at
    # rest (theta0 = +-pi, omega0 = 0), an equilibrium to rounding: never captured
    captured = np.isfinite(wells)
    assert (~captured).sum() == 2
    np.testing.assert_array_equal(maps.motion(ds).values[captured],
                                  np.sign(wells[captured]).astype(np.int8))
    assert (wells == 1).sum() > 20 and (wells == -1).sum() > 20  # one turn: many starts


def test_wells_match_dop853_away_from_basin_boundaries(damped):
    solve_ivp = pytest.importorskip("scipy.integrate").solve_ivp
    wells = maps.well(damped)
    rng = np.random.default_rng(3)
    checked = 0
    for i, j in rng.integers(1, 40, size=(25, 2)):
        block = wells.values[i - 1:i + 2, j - 1:j + 2]
        if not np.isfinite(block).all() or np.ptp(block) != 0:
            continue  # a basin boundary passes through: either answer may be right
        theta0, omega0 = float(damped.theta0[i]), float(damped.omega0[j])
        sol = solve_ivp(lambda t, y: [y[1], -0.4 * y[1] - W0SQ * np.sin(y[0])], (0, 30),
                        [theta0, omega0], method="DOP853", rtol=1e-12, atol=1e-12)
        assert round(sol.y[0, -1] / (2 * np.pi)) == wells.values[i, j]
        checked += 1
    assert checked >= 10


def test_basins_catalogue_and_rest_position(damped):
    labels = maps.basins(damped)
    wells = maps.well(damped)
    assert labels.dtype == np.int32
    catalogue = labels.attrs["attractor_theta"]
    resolved = labels.values >= 0
    # every label points at the rest angle 2 pi k of the well it ended in
    np.testing.assert_allclose(catalogue[labels.values[resolved]],
                               2 * np.pi * wells.values[resolved], rtol=0, atol=1e-12)
    assert (labels.values[~resolved] == maps.UNRESOLVED).all()
    assert len(catalogue) >= 5  # omega0 up to 12 rad/s: several turns before capture
    rest = maps.basins(damped, rest_position=True)
    assert set(np.unique(rest.values)) <= {-1, 0}


def test_well_needs_energy_and_refuses_forced_scenes():
    ds = sweep.run(sweep.Scene(effects=(sweep.Damping(0.4),)), sweep.Grid(theta0=[1.0]),
                   t_end=1.0, dt=0.01, observe=("final",))
    # capture, the documented way (with stop_early too), is what the hint names; it
    # named 'energy' alone
    with pytest.raises(ValueError, match=r"needs the variable 'well' \(observe 'capture'\) "
                       r"or both 'theta_final' and 'energy_final'.*lacks 'energy_final'; "
                       r"accepted: a dataset from sweep.run\(\.\.\., observe=\(\.\.\., "
                       r"'capture'\)\)"):
        maps.well(ds)
    # motion named the one variable theta_final, then asked for omega_mean
    with pytest.raises(ValueError, match=r"motion needs one of the variables 'omega_mean', "
                       r"'winding' or 'theta_final', and this dataset has none"):
        maps.motion(ds.drop_vars("theta_final"))
    forced = sweep.run(sweep.Scene(effects=(sweep.Forcing(1.0, 1.0),)),
                       sweep.Grid(theta0=[1.0]), t_end=1.0, dt=0.01,
                       observe=("final", "energy"))
    with pytest.raises(ValueError, match=r"well is for unforced scenes.*accepted: for a "
                       r"forced scene, sweep.maps.basins of a run observing 'strobe', or "
                       r"sweep.maps.motion"):
        maps.well(forced)


@pytest.mark.parametrize("frequency", [1.0, 2.5, 3.1, 4.0, 6.0])
def test_linear_steady_amplitude_is_the_resonance_curve(frequency):
    c, forcing_amplitude = 0.5, 0.2
    scene = sweep.Scene(gravity=G, length=L, model="linear",
                        effects=(sweep.Forcing(forcing_amplitude, 1.0),
                                 sweep.Damping(c)))
    frequencies = [frequency]
    ds = sweep.run(scene, sweep.Grid(forcing_frequency=frequencies, theta0=[0.1]),
                   t_end=90.0, dt=0.005, t_transient=60.0,
                   observe=("amplitude", "omega_mean"))
    measured = maps.amplitude(ds).values.ravel()
    W = np.asarray(frequencies)
    exact = forcing_amplitude / np.sqrt((W0SQ - W**2) ** 2 + (c * W) ** 2)
    # Two errors, both bounded: the homogeneous part has decayed by exp(-c 60 / 2) = 3e-7
    # relative; the peak is sampled every dt, missing it by at most a (1 - cos(W dt/2))
    # <= a (W dt)^2 / 8 = 1.2e-4 a at W = 6; RK4's own error is ~1e-9. Hence 2e-4.
    np.testing.assert_allclose(measured, exact, rtol=2e-4)


def test_amplitude_is_nan_where_the_pendulum_rotates():
    ds = sweep.run(sweep.Scene(), sweep.Grid(omega0=[0.5, 9.0, -9.0]), t_end=20.0,
                   dt=0.01, t_transient=5.0, observe=("amplitude", "omega_mean"))
    amp = maps.amplitude(ds).values
    assert np.isfinite(amp[0]) and np.isnan(amp[1:]).all()
    # small libration from theta0 = 0: amplitude = omega0 / omega_n to O(omega0^3)
    assert abs(amp[0] - 0.5 / np.sqrt(W0SQ)) < 2e-3


def test_maps_work_on_a_file_loaded_from_disk(damped, tmp_path):
    path = sweep.save(damped, tmp_path / "damped.nc")
    loaded = sweep.load(path)
    xr.testing.assert_identical(maps.basins(loaded), maps.basins(damped))
    xr.testing.assert_identical(maps.motion(loaded), maps.motion(damped))


def _strobe_rows():
    """Synthetic stroboscopic samples (16 per row) with known attractors."""
    m = np.arange(16)
    rng = np.random.default_rng(0)
    rows = [
        # period-1 libration at (0.5, 0.1), seen in well 3 and in well 0: one attractor
        (np.full(16, 0.5 + 6 * np.pi), np.full(16, 0.1)),
        (np.full(16, 0.5 + 1e-5), np.full(16, 0.1)),
        # period-2 libration, and the same orbit sampled half a cycle later
        (np.where(m % 2 == 0, 1.0, -1.0), np.where(m % 2 == 0, 0.3, -0.3)),
        (np.where(m % 2 == 1, 1.0, -1.0), np.where(m % 2 == 1, 0.3, -0.3)),
        # period-1 rotation: one full turn per forcing period
        (2.0 + 2 * np.pi * m, np.full(16, 1.5)),
        # no period up to 8: unresolved
        (rng.uniform(-3, 3, 16), rng.uniform(-3, 3, 16)),
        # one fixed point seen on both sides of the 2 pi wrap
        (np.full(16, 2 * np.pi - 1e-5), np.full(16, -0.2)),
        (np.full(16, 1e-5), np.full(16, -0.2)),
        # a failed trajectory
        (np.full(16, np.nan), np.full(16, np.nan)),
    ]
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def test_identify_attractors_on_known_orbits():
    theta, omega = _strobe_rows()
    labels, catalogue = maps.identify_attractors(theta, omega)
    # same attractor -> same label, across wells, cyclic shifts and the 2 pi wrap
    assert labels[0] == labels[1] and labels[2] == labels[3] and labels[6] == labels[7]
    assert len({labels[0], labels[2], labels[4], labels[6]}) == 4
    assert labels[5] == maps.UNRESOLVED and labels[8] == maps.UNRESOLVED
    by_label = {name: catalogue[name] for name in catalogue}
    assert by_label["period"][labels[2]] == 2 and by_label["period"][labels[0]] == 1
    assert by_label["turns_per_period"][labels[4]] == 1.0
    assert by_label["turns_per_period"][labels[0]] == 0.0
    assert list(by_label["size"]) == sorted(by_label["size"], reverse=True)
    assert by_label["size"].sum() == 7


def test_a_systems_catalogued_run_is_told_its_attractor_none_is_minus_one():
    """maps.basins of a system's run on a catalogue names ds['attractor'] as its labels;
    its 'none' is -1 (the variable's long_name), not NaN, as the message said."""
    from sweep.maps.labels import refuse_system_without_strobe

    ds = xr.Dataset({"attractor": ("point", np.array([0.0, -1.0]))},
                    attrs={"system_name": "DoublePendulum"})
    with pytest.raises(ValueError, match=r"is each start's attractor \(-1: none\)"):
        refuse_system_without_strobe(ds, "basins")
