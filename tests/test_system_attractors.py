"""Basins of a driven system by the attractor catalogue (``sweep.run(system, grid,
observe=("attractor",), attractors=catalogue, stop_early=True)``): the catalogue's
labels must be those `sweep.maps.basins` gives the full stroboscopic run, a trajectory
that is never stopped must keep the very samples of a run without a catalogue, and a
catalogue that does not fit the run is refused before any compute.
"""

import numpy as np
import pytest
from test_system_strobe import _two_forced_pendula

import sweep
from sweep import _config, maps
from sweep.observables import OBSERVABLES, variable_attributes
from sweep.physics import Coordinate, Parameter, SystemDeclaration

#: The damped double pendulum on a fast-driven pivot (the docs' example, as in
#: tests/test_system_basins.py): coexisting attractors of periods 1 and 4.
SYSTEM = sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=60.0,
                              effects=(sweep.Damping(0.5),))
PERIOD = 2 * np.pi / 60.0
#: 800 drive periods (84 s): every start of GRID has converged to within basins' tol =
#: 1e-3 of its attractor by the last 16 samples (at 400 periods 32 of the 144 have not:
#: a slow spiral onto a period-1 orbit, turning by about a third per period, still
#: looks like a period-3 orbit to the last 16 samples; the catalogue route already
#: labels those with the period-1 attractor that the longer run confirms).
RUN = dict(t_end=800 * PERIOD, dt=PERIOD / 40, t_transient=784 * PERIOD, progress=False)
#: 12 x 12 starts at rest, none exactly upright (a start at theta = +-pi stays on the
#: unstable upright equilibrium, which the full run would then catalogue).
GRID = sweep.Grid(theta1_0=np.linspace(-3, 3, 12), theta2_0=np.linspace(-3, 3, 12))


@pytest.fixture(scope="module")
def full():
    """The full stroboscopic run of GRID, its basins and its catalogue."""
    ds = sweep.run(SYSTEM, GRID, observe=("strobe",), **RUN)
    return ds, maps.basins(ds), maps.attractor_catalogue(ds)


def _same_partition(a, b) -> bool:
    """Whether label maps ``a`` and ``b`` are the same up to renaming the labels >= 0
    (-1, unresolved, stays -1)."""
    pairs = set(zip(a.ravel().tolist(), b.ravel().tolist()))
    left, right = [p[0] for p in pairs], [p[1] for p in pairs]
    return len(set(left)) == len(pairs) == len(set(right)) and \
        all((x < 0) == (y < 0) for x, y in pairs)


def test_the_catalogues_labels_are_the_basins_of_the_full_strobe_run(full):
    """The catalogue (the full run's attractors, in basins' label order) run with
    ``stop_early`` from t = 0 (no transient: each start stops after its own
    ATTRACTOR_MATCHES periods on an attractor) labels every one of the 144 starts as
    `sweep.maps.basins` labels the full run: the same integers, as the catalogue's
    attractor k is basins' label k. The variable is the single pendulum's
    ``attractor``, and the catalogue is kept in the attributes."""
    _, labels, catalogue = full
    assert catalogue["theta"].shape == (len(labels.attrs["attractor_period"]), 2, 16)
    assert catalogue["coordinates"].tolist() == [["theta1", "theta2"]] * len(catalogue["period"])
    assert sorted(labels.attrs["attractor_period"].tolist()) == [1, 1, 1, 1, 4]
    route = sweep.run(SYSTEM, GRID, observe=("attractor",), attractors=catalogue,
                      stop_early=True, **dict(RUN, t_transient=0.0))
    np.testing.assert_array_equal(route["attractor"].values, labels.values)
    assert (route["attractor"].values >= 0).all()
    assert route["attractor"].attrs == variable_attributes(*OBSERVABLES["attractor"].variables[0])
    assert route.attrs["stop_early"] == "once settled on a catalogued attractor"
    np.testing.assert_array_equal(sweep.io.run_arguments(route)["attractors"]["theta"],
                                  catalogue["theta"])
    # the pilot's rings were sampled at drive phase 0 of nu = 60 rad/s (784 periods of
    # 40 steps: float64 rounds the phase to ~1e-11 rad, far below 1e-9), as the route's
    # t0 + t_transient = 0, a whole number of periods before: the catalogue records
    # it, and the route's dataset keeps it for a rerun
    np.testing.assert_allclose(np.cos(catalogue["drive_phase"]), 1.0, atol=1e-9)
    np.testing.assert_array_equal(catalogue["drive_frequency"],
                                  np.full(catalogue["period"].shape, 60.0))
    np.testing.assert_array_equal(
        sweep.io.run_arguments(route)["attractors"]["drive_phase"],
        catalogue["drive_phase"])



def test_in_float32_the_catalogue_labels_the_float32_basins(full):
    """float32 (the drive's phase in float64) with the float64 run's catalogue: the
    matching tolerance (ATTRACTOR_TOL = 1e-3) is far above float32's rounding of the
    state (~1e-6 here), so every start is labelled, and the labels are the float32
    full run's basins start for start, up to the labels' names. (They are not the
    float64 basins everywhere: on these intricate basins float32's rounding sends
    about a third of the 144 starts to another attractor, as it does without a
    catalogue.)"""
    _, _, catalogue = full
    single = sweep.run(SYSTEM, GRID, observe=("strobe",), dtype="float32", **RUN)
    route = sweep.run(SYSTEM, GRID, observe=("attractor",), attractors=catalogue,
                      stop_early=True, dtype="float32", **dict(RUN, t_transient=0.0))
    assert (route["attractor"].values >= 0).all()
    assert _same_partition(route["attractor"].values, maps.basins(single).values)

def test_a_trajectory_never_stopped_keeps_the_samples_of_a_run_without_catalogue(
        full, monkeypatch):
    """A catalogue of the largest attractor only: the starts it does not match run to
    t_end and must have the very bits of the full run's samples (with lane refill and
    without); those it matches stop, and `sweep.maps.basins` of the run (their rows
    standing for the catalogued ring) gives the full run's partition. Without
    ``stop_early`` the catalogue changes no sample at all."""
    ds, labels, catalogue = full
    one = {"theta": catalogue["theta"][:1], "omega": catalogue["omega"][:1],
           "period": catalogue["period"][:1]}
    runs = {}
    for refill in (True, False):
        monkeypatch.setattr(_config, "REFILL", refill)
        runs[refill] = sweep.run(SYSTEM, GRID, observe=("strobe", "attractor"),
                                 attractors=one, stop_early=True, **RUN)
    route = runs[True]
    matched = route["attractor"].values == 0
    np.testing.assert_array_equal(matched, labels.values == 0)
    assert 0 < matched.sum() < matched.size
    for name in ("theta1_strobe", "theta2_strobe", "omega1_strobe", "omega2_strobe"):
        assert runs[False][name].values.tobytes() == route[name].values.tobytes()
        assert route[name].values[~matched].tobytes() == ds[name].values[~matched].tobytes()
    assert _same_partition(maps.basins(route).values, labels.values)
    whole = sweep.run(SYSTEM, GRID, observe=("strobe", "attractor"), attractors=one, **RUN)
    for name in ("theta1_strobe", "omega2_strobe"):
        assert whole[name].values.tobytes() == ds[name].values.tobytes()
    np.testing.assert_array_equal(whole["attractor"].values, route["attractor"].values)


def _declared_forced_pair():
    """Two uncoupled forced pendula declared as one system, with a drive frequency axis,
    and the run settings of the tests that use it (60 drive periods, 44 of transient)."""
    period = 2 * np.pi / 0.75
    run = dict(t_end=60 * period, dt=period / 100, t_transient=44 * period, progress=False)
    system = sweep.DeclaredSystem(_two_forced_pendula(Coordinate, Parameter, SystemDeclaration),
                                  drive_frequency_axis="frequency", friction=0.15,
                                  amplitude=0.3, frequency=0.75)
    return system, run


def test_a_declared_system_with_a_drive_frequency_axis():
    """Two uncoupled forced pendula declared as one system (tests/test_system_basins.py,
    60 drive periods): the catalogue of the full run labels the 15 x 15 starts as
    `sweep.maps.basins` does."""
    system, run = _declared_forced_pair()
    starts = np.linspace(-2.5, 2.5, 15)
    grid = sweep.Grid(p1_0=starts, p2_0=starts)
    ds = sweep.run(system, grid, observe=("strobe",), **run)
    labels = maps.basins(ds)
    route = sweep.run(system, grid, observe=("attractor",), stop_early=True,
                      attractors=maps.attractor_catalogue(ds), **run)
    np.testing.assert_array_equal(route["attractor"].values, labels.values)


@pytest.mark.parametrize("keep", ["mask", [0], slice(0, 1)])
def test_selecting_attractors_of_a_systems_catalogue_gives_its_catalogue(keep, tmp_path):
    """The documented selection ``{key: value[keep] for key, value in catalogue.items()}``
    (a boolean mask, indices, a slice) of a system's catalogue (the declared system
    above, 5 x 5 starts) keeps one attractor with its coordinates' names: the map run
    with it labels 0 exactly the starts the full catalogue labels 0 and the others -1,
    and the catalogue survives the netCDF file (`sweep.io.run_arguments`). The names
    were a tuple, which a mask or indices could not index (TypeError) and a slice cut
    to ('p1',), refused as a catalogue of other coordinates."""
    system, run = _declared_forced_pair()
    starts = np.linspace(-2.5, 2.5, 5)
    grid = sweep.Grid(p1_0=starts, p2_0=starts)
    catalogue = maps.attractor_catalogue(sweep.run(system, grid, observe=("strobe",), **run))
    assert len(catalogue["period"]) > 1  # selecting one of them drops some
    if keep == "mask":
        keep = np.arange(len(catalogue["period"])) == 0
    one = {key: value[keep] for key, value in catalogue.items()}
    assert one["coordinates"].tolist() == [["p1", "p2"]]
    assert one["theta"].shape == (1,) + catalogue["theta"].shape[1:]
    every = sweep.run(system, grid, observe=("attractor",), stop_early=True,
                      attractors=catalogue, **run)["attractor"].values
    route = sweep.run(system, grid, observe=("attractor",), stop_early=True,
                      attractors=one, **run)
    assert 0 < (every == 0).sum() < every.size
    np.testing.assert_array_equal(route["attractor"].values, np.where(every == 0, 0, -1))
    sweep.io.save(route, tmp_path / "route.nc")
    again = sweep.io.run_arguments(sweep.io.load(tmp_path / "route.nc"))["attractors"]
    for key in ("theta", "omega", "period", "drive_phase", "drive_frequency", "scene"):
        np.testing.assert_array_equal(again[key], one[key])
    renamed = dict(one, coordinates=np.array([["p1", "q2"]]))
    with pytest.raises(ValueError, match=r"a catalogue of coordinates \('p1', 'q2'\), but "
                                         r"two_forced_pendula has \('p1', 'p2'\)"):
        sweep.run(system, grid, observe=("attractor",), attractors=renamed, **run)


def _catalogue(k=1, m=2, samples=4):
    return {"theta": np.zeros((k, m, samples)), "omega": np.zeros((k, m, samples)),
            "period": np.ones(k, dtype=int)}


@pytest.mark.parametrize("system, grid, kwargs, match", [
    (SYSTEM, GRID, {"attractors": _catalogue(m=3)},
     r"points of 3 coordinates \(rings of shape \(1, 3, 4\)\), but DoublePendulum has 2"),
    (SYSTEM, GRID, {"attractors": {"theta": np.zeros((1, 4)), "omega": np.zeros((1, 4)),
                                   "period": [1]}},
     "points of 1 coordinates"),
    (SYSTEM, GRID, {"attractors": dict(_catalogue(), coordinates=("p1", "p2"))},
     r"a catalogue of coordinates \('p1', 'p2'\), but DoublePendulum has"),
    (SYSTEM, GRID, {"attractors": dict(_catalogue(k=2), coordinates=[["theta1", "theta2"],
                                                                     ["theta1", "p2"]])},
     r"a catalogue of coordinates \('theta1', 'p2'\), but DoublePendulum has"),
    (SYSTEM, GRID, {"attractors": dict(_catalogue(k=2), coordinates=[["theta1", "theta2"]] * 3)},
     r"coordinates of shape \(3, 2\) for 2 attractors; accepted: the names \('theta1', "
     r"'theta2'\), once or once per attractor"),
    (SYSTEM, GRID, {"attractors": dict(_catalogue(), period=[3])}, "periods \\[3\\]"),
    (sweep.DoublePendulum(), sweep.Grid(theta1_0=[0.1]), {"attractors": _catalogue()},
     "this DoublePendulum has no periodic drive; accepted: attractors=None"),
    (SYSTEM, GRID, {"attractors": _catalogue(), "observe": ("strobe",)},
     "attractors= is given but observe has no 'attractor'"),
    (SYSTEM, GRID, {"attractors": None},
     "observable 'attractor' matches the run against an attractor catalogue"),
    (SYSTEM, sweep.Grid(theta1_0=[0.1], pivot_amplitude=[0.1, 0.2]),
     {"attractors": _catalogue()}, "the grid varies pivot_amplitude"),
    (SYSTEM, GRID, {"attractors": _catalogue(), "observe": ("final", "attractor"),
                    "stop_early": True},
     r"or once it settled on a catalogued attractor \(observe=\('attractor',\)"),
])
def test_a_catalogue_that_does_not_fit_is_refused_before_any_compute(system, grid, kwargs,
                                                                     match):
    kwargs = {"observe": ("attractor",), **kwargs}
    with pytest.raises(ValueError, match=match):
        sweep.run(system, grid, t_end=10 * PERIOD, dt=PERIOD / 40, progress=False, **kwargs)


def test_one_kernel_serves_every_catalogue():
    """The catalogue is the kernel's data, not its source: catalogues of 1 and 3
    attractors (periods 1 to 4, another number of samples) give the same kernel spec and
    source, so a new pilot compiles nothing. A sweep.Forcing(on=...) on one coordinate
    is a drive too: its frequency sets the samples' period."""
    from sweep.engine_systems import prepare_system
    from sweep.kernels import build
    from sweep.kernels.system import system_kernel

    small = _catalogue()
    large = {"theta": np.ones((3, 2, 8)), "omega": np.ones((3, 2, 8)),
             "period": np.array([1, 2, 4])}
    specs = [prepare_system(SYSTEM, GRID, observe=("attractor",), attractors=catalogue,
                            stop_early=True, t_end=800 * PERIOD, dt=PERIOD / 40)[1]
             for catalogue in (small, large)]
    assert specs[0] == specs[1] and system_kernel(specs[0]) == system_kernel(specs[1])
    assert build(specs[0]) is build(specs[1])
    forced = sweep.DoublePendulum(effects=(sweep.Damping(0.5),
                                           sweep.Forcing(1.5, 2.0, on="theta2")))
    spec = prepare_system(forced, GRID, observe=("attractor",), attractors=small,
                          t_end=10 * np.pi, dt=np.pi / 100)[1]
    assert spec.strobe_frequency == forced.drive_frequency_parameter.symbol


def test_a_pilot_catalogue_of_a_system(full):
    """`sweep.maps.pilot_catalogue` of a system: the pilot is its strobe run over the
    thinned grid (here not thinned: 12 points per axis), whatever the map observes, so
    its catalogue is the full run's; a grid that varies a parameter is refused."""
    _, _, catalogue = full
    found = maps.pilot_catalogue(SYSTEM, GRID, 12, observe=("attractor",), stop_early=True,
                                 **{k: v for k, v in RUN.items() if k != "progress"})
    for key in ("theta", "omega", "period"):
        np.testing.assert_array_equal(found[key], catalogue[key])
    assert maps.pilot_grid(GRID, 5, SYSTEM).axes["theta1_0"].size == 5
    with pytest.raises(ValueError, match="the grid varies pivot_amplitude; accepted: a grid "
                                         r"that varies only the initial state \(theta1_0"):
        maps.pilot_grid(sweep.Grid(theta1_0=[0.1], pivot_amplitude=[0.1, 0.2]), 5, SYSTEM)


def test_warm_up_compiles_the_kernel_a_run_with_a_catalogue_uses(full):
    """`sweep.engine.warm_up` of a system run with a catalogue passes the kernel its
    catalogue's arrays (it read the system's catalogue as the single pendulum's and
    refused it, and the system's spec as the pendulum's), and a network's run its
    arrays: the runs after it build no kernel."""
    from sweep.kernels import cache

    _, labels, catalogue = full
    kwargs = dict(RUN, t_transient=0.0, observe=("attractor",), attractors=catalogue,
                  stop_early=True)
    spec = sweep.engine.warm_up(SYSTEM, GRID, **kwargs)
    assert spec.observe == ("attractor",)
    built = cache._build.cache_info().misses
    route = sweep.run(SYSTEM, GRID, **kwargs)
    assert cache._build.cache_info().misses == built
    np.testing.assert_array_equal(route["attractor"].values, labels.values)
    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 0)], power=[1.0, -0.5, -0.5])
    grid = sweep.Grid(perturbed_node=[0, 2], delta_theta=np.linspace(-2, 2, 5))
    sweep.engine.warm_up(network, grid, t_end=0.1, dt=0.01)
    built = cache._build.cache_info().misses
    ds = sweep.run(network, grid, t_end=0.1, dt=0.01, progress=False)
    assert cache._build.cache_info().misses == built
    assert (ds["status"].values == 0).all()


def test_without_lane_refill_blocks_of_copies_label_every_start(full, monkeypatch):
    """The block kernel without lane refill (``_config.REFILL = False``) in chunks of 3
    starts, so that each block of SIMD lanes holds many copies of its chunk's last start
    (the padding lanes), which stop together: every start gets the basins' label, as
    with refill. (The step loop stored the last stopped lane's ``done`` into every
    other lane, which then stepped no more and ended unlabelled, -1.)"""
    _, labels, catalogue = full
    monkeypatch.setattr(_config, "REFILL", False)
    kwargs = dict(RUN, t_transient=0.0, observe=("attractor",), attractors=catalogue,
                  stop_early=True)
    spec = sweep.engine.prepare(SYSTEM, GRID, chunk_size=3, **kwargs)[1]
    assert not spec.refill and spec.block > 3  # padding lanes in every chunk
    blocks = sweep.run(SYSTEM, GRID, chunk_size=3, **kwargs)
    np.testing.assert_array_equal(blocks["attractor"].values, labels.values)


@pytest.mark.parametrize("run, words", [
    (dict(t_transient=0.5 * PERIOD),
     r"t0 \+ t_transient = 0\.0 \+ 0\.0523\d* s .* drive phase W t = 3\.14159 rad "
     r"\(pivot_frequency = 60\.0 rad/s, period 0\.1047197551 s\), but the catalogue's "
     r"attractor 0 was sampled at drive phase .* rad, so no start could match it; "
     r"accepted: t0 \+ t_transient = .* \+ k \* 0\.1047197551 s"),
    (dict(t0=0.25 * PERIOD, t_end=800.25 * PERIOD, t_transient=0.0),
     r"t0 \+ t_transient = 0\.0261\d* \+ 0\.0 s .* drive phase W t = 1\.5708 rad"),
])
def test_a_catalogue_of_another_drive_phase_is_refused_before_compute(full, no_compute,
                                                                       run, words):
    """The full run's catalogue (sampled at drive phase 0) on a map whose first
    stroboscopic sample falls half or a quarter of a drive period off: no start could
    match (every label -1), so the run is refused before any kernel is built, naming
    the setting, its phase and what is accepted."""
    _, _, catalogue = full
    with pytest.raises(ValueError, match=words):
        sweep.run(SYSTEM, GRID, observe=("attractor",), attractors=catalogue,
                  stop_early=True, **dict(RUN, **run))
    other = sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=30.0,
                                 effects=(sweep.Damping(0.5),))
    with pytest.raises(ValueError, match=r"drive frequency 60\.0 rad/s, but this run's "
                                         r"pivot_frequency = 30\.0 rad/s"):
        sweep.run(other, GRID, observe=("attractor",), attractors=catalogue,
                  stop_early=True, **RUN)


#: A double pendulum driven by a sweep.Forcing on theta1, of phase constant ``phase``
#: [rad]: heavily damped and weakly forced, so that both starts of FORCED_GRID settle
#: on one period-1 orbit within 24 drive periods (basins' tol = 1e-3).
def _forced(phase):
    return sweep.DoublePendulum(effects=(sweep.Damping(2.0),
                                         sweep.Forcing(0.5, 2.0, phase, on="theta1")))


FORCED_PERIOD = np.pi  # 2 pi / W, W = 2 rad/s
FORCED_GRID = sweep.Grid(theta1_0=[0.0, 0.3], theta2_0=[0.0])
FORCED_RUN = dict(t_end=40 * FORCED_PERIOD, dt=FORCED_PERIOD / 40, progress=False)


def test_a_forcings_phase_constant_is_part_of_the_catalogues_drive_phase():
    """A system's catalogue records the drive phase W t_s + phi of its Forcing on a
    coordinate (phi = forcing_phase_theta1): a run with phi = pi/2 at the pilot's t0
    (every start would be labelled -1) is refused before any compute, and one whose t0
    is a quarter period earlier, W t_s + phi the pilot's section again, is accepted
    and labels both starts with the one attractor. (The check compared the clock's
    phase W t only: it accepted the first and refused the second.)"""
    pilot = sweep.run(_forced(0.0), FORCED_GRID, observe=("strobe",),
                      t_transient=24 * FORCED_PERIOD, **FORCED_RUN)
    catalogue = maps.attractor_catalogue(pilot)
    assert catalogue["period"].tolist() == [1]
    # 24 periods of 40 steps: W t_s = 48 pi, rounded in float64 to ~1e-14 rad
    np.testing.assert_allclose(np.cos(catalogue["drive_phase"]), 1.0, atol=1e-9)
    kwargs = dict(FORCED_RUN, observe=("attractor",), attractors=catalogue, stop_early=True)
    with pytest.raises(ValueError, match=r"drive phase W t \+ phi = 1\.5708 rad "
                                         r"\(forcing_frequency_theta1 = 2\.0 rad/s, "
                                         r"forcing_phase_theta1 = 1\.5707\d* rad"):
        sweep.engine.prepare(_forced(np.pi / 2), FORCED_GRID, **kwargs)
    shifted = sweep.run(_forced(np.pi / 2), FORCED_GRID,
                        **dict(kwargs, t0=-FORCED_PERIOD / 4))
    np.testing.assert_array_equal(shifted["attractor"].values, [[0], [0]])


@pytest.mark.parametrize("system, grid, words", [
    (sweep.DoublePendulum(pivot_amplitude=0.12, pivot_frequency=60.0,
                          effects=(sweep.Damping(0.5),)), GRID,
     r"the catalogue was computed for pivot_amplitude = 0\.1, but this run's "
     r"pivot_amplitude = 0\.12 \(a catalogue holds the attractors of one scene\); "
     r"accepted: pivot_amplitude = 0\.1 \(within 1e-09 relative\)"),
    (SYSTEM, sweep.Grid(theta1_0=np.linspace(-3, 3, 12), theta2_0=np.linspace(-3, 3, 12),
                        damping=[0.6]), r"computed for damping = 0\.5, but this run's "
                                        r"damping = 0\.6"),
    (SYSTEM, sweep.Grid(theta1_0=[0.5], length2=[1.1]),
     r"computed for length2 = 1\.0, but this run's length2 = 1\.1"),
])
def test_a_catalogue_of_another_system_is_refused_before_compute(full, no_compute, system,
                                                                 grid, words):
    """The catalogue records the pilot system's parameters of one value (one row per
    attractor); a map of another pivot amplitude, damping or arm length (the system's
    value or a grid's one-value axis) is refused before any compute, naming the
    parameter, both values and what is accepted. (It was accepted and labelled its
    starts by attractors not its own.)"""
    _, _, catalogue = full
    with pytest.raises(ValueError, match=words):
        sweep.run(system, grid, observe=("attractor",), attractors=catalogue,
                  stop_early=True, **dict(RUN, t_transient=0.0))
    np.testing.assert_array_equal(catalogue["scene"]["pivot_amplitude"],
                                  np.full(catalogue["period"].shape, 0.1))
    assert "pivot_frequency" not in catalogue["scene"].dtype.names  # the drive's: its phase


def test_a_catalogue_of_a_slice_of_a_system_run_over_scenes_is_of_the_slice_s_scene():
    """A strobe run over two pivot amplitudes, then the catalogue of one slice: the
    amplitude the run varied is of the slice's scene (its own amplitude is accepted,
    where it was refused as a scene without pivot_amplitude; the system's 0.1 is
    refused), and the initial state and the drive's frequency are not."""
    axes = dict(theta1_0=np.linspace(-3, 3, 4), theta2_0=np.linspace(-3, 3, 4))
    ds = sweep.run(SYSTEM, sweep.Grid(**axes, pivot_amplitude=[0.1, 0.12]),
                   observe=("strobe",), **RUN)
    catalogue = maps.attractor_catalogue(ds.sel(pivot_amplitude=0.12))
    names = catalogue["scene"].dtype.names
    np.testing.assert_array_equal(catalogue["scene"]["pivot_amplitude"], 0.12)
    assert not {"theta1_0", "omega2_0", "pivot_frequency"} & set(names)
    run = dict(RUN, observe=("strobe", "attractor"), attractors=catalogue, stop_early=True)
    sweep.engine.prepare(SYSTEM, sweep.Grid(**axes, pivot_amplitude=[0.12]), **run)
    with pytest.raises(ValueError, match=r"computed for pivot_amplitude = 0\.12, but this "
                                         r"run's pivot_amplitude = 0\.1\b"):
        sweep.engine.prepare(SYSTEM, sweep.Grid(**axes), **run)
