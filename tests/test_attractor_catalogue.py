"""Early stop on a catalogued attractor: ``sweep.run(..., attractors=catalogue)``.

The oracle is the full run: every start that the full-length run (300 transient + 20
observed periods, no early stop) resolves must get the same attractor when the run
stops each trajectory as soon as its stroboscopic point follows a catalogued orbit.
Beside it: the trajectories really stop (a longer t_end changes nothing), lane refill
stays bit-identical, an attractor missing from the catalogue is still found by the
strobe test, the catalogue survives a netCDF file, the CUDA kernel (simulated) matches
the CPU's, and bad catalogues are refused before compute.
"""

import numpy as np
import pytest

import sweep
from sweep import kernels, maps
from sweep.kernels import KernelSpec

PERIOD = 2 * np.pi
#: The forced map of the maps issue (c = 0.2, A = 1.66, W = 1, cos forcing, g/L = 1):
#: three attractors (two period-2 rotations, one period-1 oscillation), fractal basins.
SCENE = sweep.Scene(gravity=1.0, length=1.0, effects=(
    sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
FULL = dict(t_end=320 * PERIOD, dt=PERIOD / 100, t_transient=300 * PERIOD,
            observe=("strobe",), progress=False)
EARLY = dict(FULL, t_transient=20 * PERIOD, stop_early=True)


def _grid(n):
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n), omega0=np.linspace(-4, 4, n))


@pytest.fixture(scope="module")
def catalogue(wada_catalogue):
    """From a coarse pilot with the strict early stop, as a user would make it: SCENE
    on _grid(21) with EARLY (conftest's session fixture, shared with other files;
    test_pilot_catalogue_thins_the_map_and_finds_its_attractors checks that this file's
    SCENE and EARLY give the same bits)."""
    return wada_catalogue


@pytest.fixture(scope="module")
def full_run():
    return sweep.run(SCENE, _grid(41), **FULL)


@pytest.fixture(scope="module")
def full_labels(full_run):
    return maps.basins(full_run)


def test_the_pilot_finds_the_three_attractors(catalogue):
    assert sorted(catalogue["period"].tolist()) == [1, 2, 2]
    assert catalogue["theta"].shape == catalogue["omega"].shape == (3, 16)


def test_labels_are_the_full_runs_on_every_start(catalogue, full_labels):
    """41 x 41 starts: every one the full run resolves gets its attractor (the labels,
    ranked by basin size, and the catalogue's periods and sizes are the same), and
    nearly all are matched in the kernel rather than by the slow periodicity test."""
    ds = sweep.run(SCENE, _grid(41), **EARLY, attractors=catalogue)
    labels = maps.basins(ds)
    assert (full_labels >= 0).all()
    np.testing.assert_array_equal(labels.values, full_labels.values)
    for key in ("attractor_period", "attractor_turns_per_period", "attractor_size"):
        np.testing.assert_array_equal(labels.attrs[key], full_labels.attrs[key])
    assert (ds.attractor >= 0).mean() > 0.99
    assert "attractor" in ds.attrs["observe"].split()
    # a short label (what plots show) and the full meaning in the CF comment
    assert ds.attractor.attrs["long_name"] == "index of the attractor settled on (-1: none)"
    assert "ATTRACTOR_MATCHES" in ds.attractor.attrs["comment"]


def test_the_period_map_of_a_catalogue_run_is_the_full_runs(catalogue, full_run):
    """A trajectory stopped on a catalogued attractor keeps too few stroboscopic
    samples to show its period (it read -1 everywhere): it gets the catalogued orbit's,
    which is what the full run's own samples give, start by start; and -1 is the
    unresolved row of the fractions."""
    early = sweep.run(SCENE, _grid(41), **EARLY, attractors=catalogue)
    full = maps.period(full_run)
    assert (full > 0).all()
    periods = maps.period(early)
    np.testing.assert_array_equal(periods.values, full.values)
    periods[0, 0] = -1  # as a start that settles on nothing would read
    table = maps.fractions(periods)
    assert table.unresolved.sel(label=-1).item()
    assert not table.unresolved.sel(label=[1, 2]).any()
    assert table["count"].sel(label=-1).item() == 1


def test_trajectories_stop_once_matched(catalogue):
    """A stopped trajectory never sees the end of the run: twice the t_end gives the
    same bits, where a trajectory that ran on would have moved on its orbit."""
    grid = _grid(9)
    short = sweep.run(SCENE, grid, **EARLY, attractors=catalogue)
    long = sweep.run(SCENE, grid, **dict(EARLY, t_end=640 * PERIOD), attractors=catalogue)
    assert (short.attractor >= 0).all()
    for name in ("strobe_theta", "strobe_omega", "attractor"):
        assert short[name].values.tobytes() == long[name].values.tobytes(), name


def test_an_attractor_missing_from_the_catalogue_is_still_found(catalogue, full_labels):
    """Drop the period-1 attractor from the catalogue: its starts are not matched, run
    on until the strobe test settles, and get the full run's label all the same."""
    keep = catalogue["period"] == 2
    partial = {key: value[keep] for key, value in catalogue.items()}
    ds = sweep.run(SCENE, _grid(41), **EARLY, attractors=partial)
    labels = maps.basins(ds)
    np.testing.assert_array_equal(labels.values, full_labels.values)
    period_one = labels.attrs["attractor_period"] == 1
    unmatched = ds.attractor.values < 0
    assert unmatched.sum() == labels.attrs["attractor_size"][period_one].sum()


def test_refill_gives_the_same_bits_as_waiting_lanes(catalogue):
    """With the table of the shared drive's sines, as `sweep.run` builds them: the
    refill kernel is the one the runs above use (test_refill.py tests the per-lane
    sines against the table)."""
    from test_refill import _call, _table

    params = _table(300)
    extra = (kernels.catalogue_argument(sweep.engine.attractor_orbits(catalogue)),)
    common = dict(stop_early=True, block=64, shared_forcing=True)
    waiting = _call(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe", "attractor"),
                               **common), params, extra=extra)
    refill = _call(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe", "attractor"),
                              refill=True, **common), params, extra=extra)
    np.testing.assert_array_equal(refill[1], waiting[1])
    assert refill[0].tobytes() == waiting[0].tobytes()


def test_the_catalogue_survives_a_file_and_run_arguments(catalogue, tmp_path):
    ds = sweep.run(SCENE, _grid(9), **EARLY, attractors=catalogue)
    sweep.save(ds, tmp_path / "map.nc")
    loaded = sweep.load(tmp_path / "map.nc")
    np.testing.assert_array_equal(maps.basins(loaded).values, maps.basins(ds).values)
    again = maps.attractor_catalogue(loaded)  # from a run that matched: its stored rings
    assert sorted(again["period"].tolist()) == sorted(catalogue["period"].tolist())
    arguments = sweep.io.run_arguments(loaded)
    np.testing.assert_array_equal(arguments["attractors"]["theta"], catalogue["theta"])
    np.testing.assert_array_equal(arguments["attractors"]["period"], catalogue["period"])


def test_float32_with_a_catalogue(catalogue, full_labels):
    """The catalogue's tolerance (1e-3) is far above float32's rounding: the labels of
    a float32 run with it are the float32 full run's (both compared on the starts
    where float32 and float64 agree, see docs/guide/integrators.md, float32)."""
    ds = sweep.run(SCENE, _grid(21), **EARLY, attractors=catalogue, dtype="float32")
    full32 = maps.basins(sweep.run(SCENE, _grid(21), **FULL, dtype="float32"))
    np.testing.assert_array_equal(maps.basins(ds).values, full32.values)


#: SHA-256 (first 32 hex digits) of a 21 x 21 run's labels, statuses and stroboscopic
#: rings (rounded to 1e-6, so that the digest pins where each trajectory stopped -- a
#: period more or less moves a ring point by far more, up to the 1e-3 of the match --
#: and not the last bits of a machine's arithmetic), computed with the kernels that
#: still pasted the catalogue into their text as constants (commit a70ebbf): the
#: catalogue as the kernel's argument gives the same results.
DIGESTS = {"float64": "f7653767bc11d8f989685d4ce66cef5e",
           "float32": "dfb6bc080059535cc2f5b75aace35f1f"}


@pytest.mark.parametrize("dtype", sorted(DIGESTS))
def test_labels_and_stops_are_those_of_the_pasted_catalogue(catalogue, dtype):
    import hashlib

    ds = sweep.run(SCENE, _grid(21), **EARLY, attractors=catalogue, dtype=dtype)
    digest = hashlib.sha256()
    digest.update(ds.attractor.values.astype(np.int8).tobytes())
    digest.update(ds.status.values.astype(np.int8).tobytes())
    for name in ("strobe_theta", "strobe_omega"):
        digest.update(np.round(ds[name].values, 6).astype("<f8").tobytes())
    assert digest.hexdigest()[:32] == DIGESTS[dtype]


def test_cuda_matches_the_cpu(catalogue):
    pytest.importorskip("numba.cuda")
    grid = _grid(5)
    kwargs = dict(EARLY, t_end=120 * PERIOD, attractors=catalogue)
    gpu = sweep.run(SCENE, grid, device="cuda", **kwargs)
    cpu = sweep.run(SCENE, grid, **kwargs)
    np.testing.assert_array_equal(gpu.attractor, cpu.attractor)
    # the CUDA sine is not vecmath's: samples agree to rounding amplified over the run
    np.testing.assert_allclose(gpu.strobe_theta, cpu.strobe_theta, rtol=0, atol=1e-9)


# ------------------------------------------------------------------ refusals
@pytest.mark.parametrize("bad, words", [
    ({"theta": [[0.0, 1.0]], "omega": [[0.0, 1.0]]}, "attractors must be an attractor"),
    ({"theta": [[0.0, 1.0]], "omega": [[0.0, 1.0]], "period": [3]}, r"periods \[3\]"),
    ({"theta": [[np.nan, 1.0]], "omega": [[0.0, 1.0]], "period": [1]}, "rings of shape"),
    ({"theta": [0.0, 1.0], "omega": [0.0, 1.0], "period": [1]}, "rings of shape"),
    ("catalogue", "attractors must be an attractor catalogue, got 'catalogue'"),
])
def test_a_bad_catalogue_is_refused_before_compute(bad, words, no_compute):
    with pytest.raises(ValueError, match=words):
        sweep.run(SCENE, _grid(3), **EARLY, attractors=bad)


def test_the_observable_without_a_catalogue_is_refused(no_compute):
    with pytest.raises(ValueError, match="observable 'attractor' matches the run against an "
                                         "attractor catalogue; accepted: attractors="):
        sweep.run(SCENE, _grid(3), **dict(EARLY, observe=("strobe", "attractor")))


def test_a_catalogue_needs_forcing(catalogue, no_compute):
    with pytest.raises(ValueError, match="observable 'attractor' samples once per forcing "
                                         "period and needs a forcing"):
        sweep.run(sweep.Scene(effects=(sweep.Damping(0.2),)), _grid(3), t_end=10.0,
                  dt=0.1, observe=("final",), attractors=catalogue)


def test_a_run_that_resolved_nothing_has_no_catalogue():
    ds = sweep.run(SCENE, _grid(3), **dict(FULL, t_end=4 * PERIOD, t_transient=0.0))
    with pytest.raises(ValueError, match="resolved no attractor"):
        maps.attractor_catalogue(ds)


def test_the_kernel_reads_the_catalogue_as_an_argument():
    """The catalogue is the kernel's argument, not part of its text: one kernel (one
    compile) serves every catalogue, and the stop test is the strobe's or the match."""
    spec = KernelSpec("nonlinear", ("forcing",), ("strobe", "attractor"), stop_early=True)
    text = kernels.source(spec)
    assert "(settled_0) or settled_1" in text
    assert "saved, catalogue)" in text and "saved, catalogue, b_first" not in text
    table = kernels.catalogue_argument((((1.0, 0.0), (2.0, 0.5)), ((3.0, -1.0),)))
    # per point: theta, omega, the row of the orbit's next point, the attractor
    np.testing.assert_array_equal(table, [[1.0, 0.0, 1, 0], [2.0, 0.5, 0, 0],
                                          [3.0, -1.0, 2, 1]])
    assert table.flags.c_contiguous and table.dtype == np.float64
    single = kernels.catalogue_argument(((( 0.1, 0.2),),), "float32")
    assert single.dtype == np.float32 and single[0, 0] == np.float32(0.1)


def test_two_catalogues_run_one_kernel(catalogue):
    """A catalogue that differs (one attractor fewer) builds no second kernel, and each
    run's labels are its own catalogue's."""
    partial = {name: values[1:] for name, values in catalogue.items()}
    grid = _grid(9)
    first = sweep.run(SCENE, grid, **EARLY, attractors=catalogue)
    built = kernels.build.cache_info().misses
    second = sweep.run(SCENE, grid, **EARLY, attractors=partial)
    assert kernels.build.cache_info().misses == built
    assert int(first.attractor.max()) == 2 and int(second.attractor.max()) == 1


@pytest.mark.parametrize("orbits", [(), ((),), (((1.0, np.nan),),)])
def test_a_bad_catalogue_argument_is_refused(orbits):
    with pytest.raises(ValueError, match="catalogue must hold at least one orbit, each "
                                         "with at least one point, every point finite"):
        kernels.catalogue_argument(orbits)


# ------------------------------------------------------------------ the pilot
def test_pilot_catalogue_thins_the_map_and_finds_its_attractors(catalogue):
    grid = _grid(101)
    pilot = maps.pilot_grid(grid, 21)
    assert pilot.axes["theta0"].size == pilot.axes["omega0"].size == 21
    np.testing.assert_array_equal(pilot.axes["theta0"][[0, -1]], grid.axes["theta0"][[0, -1]])
    found = maps.pilot_catalogue(SCENE, grid, 21, **dict(EARLY, chunk_size=7))
    np.testing.assert_array_equal(found["period"], catalogue["period"])
    np.testing.assert_array_equal(found["theta"], catalogue["theta"])  # the same runs


@pytest.mark.parametrize("grid, points, words", [
    (sweep.Grid(theta0=[0.0, 1.0], forcing_amplitude=[1.0, 1.2]), 5,
     "grid varies forcing_amplitude; accepted: a grid that varies only theta0 and"),
    (sweep.Grid(theta0=[0.0, 1.0]), 1, "pilot must be an int >= 2"),
    (sweep.Grid(theta0=[0.0, 1.0]), 2.5, "pilot must be an int >= 2"),
])
def test_a_bad_pilot_is_refused_before_compute(grid, points, words, no_compute):
    with pytest.raises(ValueError, match=words):
        maps.pilot_catalogue(SCENE, grid, points, **EARLY)


def test_command_line_and_run_file_pilot(catalogue, tmp_path):
    """``[run] pilot`` and ``--pilot`` run the pilot first: the file records the
    catalogue and its labels are the Python API's; a bad value is one line."""
    from sweep import cli

    run_file = tmp_path / "forced.toml"
    run_file.write_text(
        "[scene]\ngravity = 1.0\nlength = 1.0\n"
        "[scene.damping]\ncoefficient = 0.2\n"
        "[scene.forcing]\namplitude = 1.66\nfrequency = 1.0\nphase = 1.5707963267948966\n"
        # the fixture's pilot: _grid(21) and EARLY (so its catalogue, and the kernel
        # with it, is the fixture's); --pilot 7 below makes another
        f"[grid]\ntheta0 = {{start = {-np.pi!r}, stop = {np.pi!r}, num = 21}}\n"
        "omega0 = {start = -4.0, stop = 4.0, num = 21}\n"
        f"[run]\nt_end = {320 * PERIOD!r}\ndt = {PERIOD / 100!r}\n"
        f"t_transient = {20 * PERIOD!r}\nobserve = [\"strobe\"]\nstop_early = true\n"
        "pilot = 21\n")
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "a.nc"),
                     "--no-progress"]) == 0
    ds = sweep.load(tmp_path / "a.nc")
    assert "attractors_theta" in ds.attrs and (ds.attractor >= 0).all()
    np.testing.assert_array_equal(sweep.io.run_arguments(ds)["attractors"]["theta"],
                                  catalogue["theta"])  # the Python API's pilot
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "b.nc"), "--pilot", "7",
                     "--no-progress"]) == 0
    np.testing.assert_array_equal(maps.basins(sweep.load(tmp_path / "b.nc")),
                                  maps.basins(ds))
    run_file.write_text(run_file.read_text().replace("pilot = 21", "pilot = 1"))
    with pytest.raises(ValueError, match="pilot must be an int >= 2"):
        sweep.toml_spec.load_run(run_file)


def test_a_catalogue_of_shorter_rings_leaves_the_maps_own_rings_whole(full_labels):
    """A pilot that kept 2 stroboscopic samples only (it finds only the period-1
    attractor): the map's 16-sample rings stay whole, so its period-2 attractors are
    still found, and every label is the full run's (the catalogued ring is extended
    along its orbit to the map's width, not the map's rings cut to the ring's)."""
    small = maps.attractor_catalogue(sweep.run(SCENE, _grid(11), **EARLY, strobe_samples=2))
    assert small["theta"].shape == (1, 2) and small["period"].tolist() == [1]
    ds = sweep.run(SCENE, _grid(41), **EARLY, attractors=small)
    np.testing.assert_array_equal(maps.basins(ds).values, full_labels.values)
    assert 0 < int((ds.attractor >= 0).sum()) < ds.attractor.size


def test_equal_basins_keep_the_full_runs_order():
    """Two attractors with equal basins: labels tie-break as identify_attractors does
    on the full run, whichever of them the kernel matched more often (a matched
    attractor's ring is identified once, weighted by its matches)."""
    samples = 16
    rings = {"theta": np.array([np.full(samples, 1.0), np.full(samples, 3.0)]),
             "omega": np.array([np.full(samples, 0.5), np.full(samples, -1.0)]),
             "period": np.array([1, 1])}
    theta = np.repeat(rings["theta"], 10, axis=0)
    omega = np.repeat(rings["omega"], 10, axis=0)
    full, _ = maps.identify_attractors(theta, omega)
    index = np.array([0] * 7 + [-1] * 3 + [1] * 3 + [-1] * 7)
    stopped = theta.copy()
    stopped[index >= 0] += np.linspace(0.0, 0.5, samples)  # not yet periodic
    attrs = {"attractors_theta": rings["theta"].ravel(),
             "attractors_omega": rings["omega"].ravel(),
             "attractors_period": rings["period"], "attractors_samples": samples}
    labels, found = sweep.maps.labels._identify_with_catalogue(
        stopped[index < 0], omega[index < 0], index, attrs, max_period=8, tol=1e-3)
    np.testing.assert_array_equal(labels, full)
    np.testing.assert_array_equal(found["size"], [10, 10])


def test_a_catalogue_across_scenes_is_refused(catalogue, no_compute):
    grid = sweep.Grid(theta0=[0.0, 1.0], forcing_amplitude=[1.5, 1.66])
    with pytest.raises(ValueError, match="an attractor catalogue holds the attractors of "
                                         "one scene, but the grid varies forcing_amplitude"):
        sweep.run(SCENE, grid, **EARLY, attractors=catalogue)


def test_the_pilot_ignores_what_only_the_map_does(catalogue):
    """A map that saves trajectories or checkpoints: its pilot runs with early stop and
    none of that."""
    found = maps.pilot_catalogue(SCENE, _grid(21), 21,
                                 **dict(EARLY, save_every=100, chunk_size=5,
                                        estimate_error=3))
    np.testing.assert_array_equal(found["period"], catalogue["period"])


def test_the_resume_hint_repeats_the_pilot(tmp_path):
    import argparse

    from sweep import cli

    (tmp_path / "ck").mkdir()
    args = argparse.Namespace(run_file="map.toml", checkpoint=str(tmp_path / "ck"),
                              scheduler=None, pilot=7)
    hint = cli._resume_hint(args, tmp_path / "ck", tmp_path / "map.nc")
    assert "--pilot 7 --resume" in hint


def test_weights_count_as_repeated_rows():
    """identify_attractors(weights=): one row of weight 5 is five identical rows."""
    a = (np.full(16, 1.0), np.full(16, 0.5))
    b = (np.full(16, 3.0), np.full(16, -1.0))
    repeated = maps.identify_attractors(np.array([a[0]] * 5 + [b[0]] * 3),
                                        np.array([a[1]] * 5 + [b[1]] * 3))
    weighted = maps.identify_attractors(np.array([a[0], b[0], b[0], b[0]]),
                                        np.array([a[1], b[1], b[1], b[1]]),
                                        weights=np.array([5, 1, 1, 1]))
    assert weighted[0].tolist() == [0, 1, 1, 1] and repeated[0][0] == 0
    np.testing.assert_array_equal(weighted[1]["size"], repeated[1]["size"])  # [5, 3]


def test_the_strobe_table_of_some_rows_is_those_rows_of_the_whole_table():
    """`maps.basins` of a run with a catalogue copies the samples of its unmatched
    trajectories only (`strobe_table(ds, rows)`); they are the whole table's rows."""
    ds = sweep.run(SCENE, _grid(7), **EARLY)
    theta, omega, dims = sweep.maps.labels.strobe_table(ds)
    rows = np.array([0, 5, 48])
    some_theta, some_omega, some_dims = sweep.maps.labels.strobe_table(ds, rows)
    assert some_dims == dims and some_theta.flags.c_contiguous
    np.testing.assert_array_equal(some_theta, theta[rows])
    np.testing.assert_array_equal(some_omega, omega[rows])


def test_the_catalogue_records_its_drive_phase_and_a_whole_period_later_labels_alike(
        catalogue):
    """The pilot (t0 = 0, t_transient = 20 periods, phase constant pi/2) sampled its
    rings at drive phase W t + phi = pi/2 of W = 1 rad/s, and the catalogue says so, one
    value per attractor (so that selecting attractors keeps them). A map whose transient
    is one period longer samples the same Poincare section: every start matches, the
    same attractor as with the pilot's own settings (a settled trajectory is on its
    attractor at every period), and the dataset keeps the drive for a rerun
    (`sweep.io.run_arguments`)."""
    # 1e-9 rad: 2000 steps of dt = 2 pi / 100 summed in float64 round to ~1e-13 rad
    np.testing.assert_allclose(catalogue["drive_phase"], np.pi / 2, atol=1e-9)
    assert catalogue["drive_phase"].shape == catalogue["period"].shape
    np.testing.assert_array_equal(catalogue["drive_frequency"], [1.0, 1.0, 1.0])
    grid = _grid(9)
    same = sweep.run(SCENE, grid, **EARLY, attractors=catalogue)
    later = sweep.run(SCENE, grid, **dict(EARLY, t_transient=21 * PERIOD),
                      attractors=catalogue)
    assert (later.attractor >= 0).all()
    np.testing.assert_array_equal(later.attractor.values, same.attractor.values)
    np.testing.assert_array_equal(maps.basins(later).values, maps.basins(same).values)
    again = sweep.io.run_arguments(later)["attractors"]
    for key in ("drive_phase", "drive_frequency"):
        np.testing.assert_array_equal(again[key], catalogue[key], err_msg=key)


@pytest.mark.parametrize("scene, run, words", [
    (SCENE, dict(t_transient=20.5 * PERIOD),
     r"t0 \+ t_transient = 0\.0 \+ 128\.80\d* s puts this run's first stroboscopic "
     r"sample at t = 128\.80\d* s, drive phase W t \+ phi = 4\.71239 rad "
     r"\(forcing_frequency = 1\.0 rad/s, forcing_phase = 1\.5707\d* rad, period "
     r"6\.283185307 s\), but the catalogue's attractor 0 was sampled at drive phase "
     r"1\.5708 rad, so no start could match it; accepted: t0 \+ t_transient = "
     r"0 \+ k \* 6\.283185307 s \(k a whole number, on a step of dt\), forcing_phase = "
     r"4\.71238898\d* rad \(mod 2 pi\) with this t0 \+ t_transient, or a catalogue"),
    (SCENE, dict(t0=PERIOD / 4, t_end=320.25 * PERIOD),
     r"t0 \+ t_transient = 1\.5707\d* \+ 125\.66\d* s .* drive phase W t \+ phi = "
     r"3\.14159 rad"),
    (sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 2.0, np.pi / 2))), {},
     r"attractor 0 was sampled at drive frequency 1\.0 rad/s, but this run's "
     r"forcing_frequency = 2\.0 rad/s .*; accepted: forcing_frequency = 1\.0"),
])
def test_a_catalogue_of_another_drive_phase_is_refused_before_compute(
        catalogue, no_compute, scene, run, words):
    """A map whose first stroboscopic sample falls at another phase of the drive (a
    transient half a period longer, a start a quarter period later) or of another
    drive frequency could match no start (every label -1): refused, naming the
    setting, its phase and what would be accepted."""
    with pytest.raises(ValueError, match=words):
        sweep.run(scene, _grid(9), **dict(EARLY, **run), attractors=catalogue)


def test_a_catalogue_without_its_drive_is_not_checked_and_half_of_one_is_refused(
        catalogue, no_compute):
    """Rings built by hand (no drive recorded) are taken as given; a catalogue with
    one of the two drive fields only is refused."""
    rings = {key: catalogue[key] for key in ("theta", "omega", "period")}
    sweep.engine.prepare(SCENE, _grid(9), **dict(EARLY, t_transient=20.5 * PERIOD),
                         attractors=rings)
    with pytest.raises(ValueError, match="a catalogue without 'drive_frequency'; accepted: "
                                         "both 'drive_phase'"):
        sweep.run(SCENE, _grid(9), **EARLY,
                  attractors=dict(rings, drive_phase=catalogue["drive_phase"]))


def test_a_catalogue_of_another_forcing_phase_is_refused_before_compute(catalogue,
                                                                         no_compute):
    """The drive's phase constant phi is part of the Poincare section W t + phi: the
    catalogue of SCENE (phi = pi/2) on the same scene with phi = 0 and the pilot's t0
    and t_transient (every start would be labelled -1) is refused, as a Forcing of
    phase 0 and as a grid's one-value forcing_phase axis. (It was accepted: the
    check compared the clock's phase W t only.)"""
    other = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, 0.0)))
    # the run's own phase W t_s = 40 pi shows as ~0 or ~2 pi (its float64 rounding)
    words = (r"drive phase W t \+ phi = \S+ rad \(forcing_frequency = 1\.0 rad/s, "
             r"forcing_phase = 0\.0 rad, period 6\.283185307 s\), but the catalogue's "
             r"attractor 0 was sampled at drive phase 1\.5708 rad, so no start could "
             r"match it; accepted: t0 \+ t_transient = 1\.570796327 \+ k \* 6\.283185307 "
             r"s \(k a whole number, on a step of dt\), forcing_phase = 1\.570796327 rad")
    with pytest.raises(ValueError, match=words):
        sweep.run(other, _grid(9), **EARLY, attractors=catalogue)
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9),
                      forcing_phase=[0.0])
    with pytest.raises(ValueError, match=words):
        sweep.run(SCENE, grid, **EARLY, attractors=catalogue)


def test_a_run_of_another_phase_shifted_onto_the_same_section_labels_alike(catalogue):
    """phi = 0 with t0 a quarter period (25 steps) later samples W t + phi = pi/2 + 2 pi
    k, the pilot's section: its trajectories are SCENE's shifted in time, so the
    catalogue is accepted and labels every start as on SCENE itself. (It was refused:
    the clock's phase pi/2 is not the pilot's clock phase 0.)"""
    other = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, 0.0)))
    grid = _grid(9)
    same = sweep.run(SCENE, grid, **EARLY, attractors=catalogue)
    shifted = sweep.run(other, grid, **dict(EARLY, t0=PERIOD / 4, t_end=320.25 * PERIOD),
                        attractors=catalogue)
    assert (shifted.attractor >= 0).all()
    np.testing.assert_array_equal(shifted.attractor.values, same.attractor.values)


def test_an_old_catalogue_with_the_clocks_phase_keeps_its_meaning(catalogue, no_compute):
    """A catalogue made before phi was counted records ``strobe_phase``, the clock's
    phase W t_s alone (0 for this pilot): it is read with that meaning, so it is still
    accepted with its own scene (phi = pi/2: read as phi = 0 it would be refused), and
    still refused half a period off, naming its strobe_phase; a dataset keeps it under
    its old name."""
    old = {key: catalogue[key] for key in ("theta", "omega", "period", "drive_frequency")}
    old["strobe_phase"] = np.zeros(catalogue["period"].size)
    sweep.engine.prepare(SCENE, _grid(9), **EARLY, attractors=old)
    with pytest.raises(ValueError, match=r"drive phase W t = 3\.14159 rad .* sampled at "
                                         r"drive phase 0 rad \(its strobe_phase, the "
                                         r"clock W t alone\)"):
        sweep.run(SCENE, _grid(9), **dict(EARLY, t_transient=20.5 * PERIOD),
                  attractors=old)
    attrs = sweep.strobe_phase.attributes(old, old["period"].size)
    assert sorted(attrs) == ["attractors_drive_frequency", "attractors_strobe_phase"]
    again = sweep.strobe_phase.from_attributes(attrs)
    np.testing.assert_array_equal(again["strobe_phase"], old["strobe_phase"])


@pytest.mark.parametrize("scene, axes, words", [
    (sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.5, 1.0, np.pi / 2))), {},
     r"the catalogue was computed for forcing_amplitude = 1\.66, but this run's "
     r"forcing_amplitude = 1\.5 \(a catalogue holds the attractors of one scene\); "
     r"accepted: forcing_amplitude = 1\.66 \(within 1e-09 relative\), or a catalogue of "
     r"this scene \(sweep\.maps\.pilot_catalogue"),
    (SCENE, {"damping": [0.25]}, r"computed for damping = 0\.2, but this run's damping = "
                                 r"0\.25"),
    (SCENE, {"length": [2.0]}, r"computed for length = 1\.0, but this run's length = 2\.0"),
    (sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2), sweep.Torque(0.1))), {},
     r"computed for torque = 0\.0, but this run's torque = 0\.1"),
])
def test_a_catalogue_of_another_scene_is_refused_before_compute(catalogue, no_compute,
                                                                scene, axes, words):
    """The catalogue records the pilot's scene (its parameters of one value); a map of
    another forcing amplitude, damping, length or with a torque (a Scene's value or a
    grid's one-value axis) would label its starts by attractors that are not its own
    (-1 everywhere): refused, naming the parameter, both values and what is accepted.
    (It was accepted.)"""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9),
                      **axes)
    with pytest.raises(ValueError, match=words):
        sweep.run(scene, grid, **EARLY, attractors=catalogue)


def test_the_catalogues_scene_is_kept_and_its_own_scene_is_accepted(catalogue, no_compute):
    """The pilot's parameters of one value, besides the drive's frequency and phase
    constant (checked through the drive phase), one row per attractor; the same scene
    given as a grid's one-value axis, or off by a rounding (1e-12 relative, below
    SCENE_RTOL = 1e-9), is accepted; a dataset keeps the scene for a rerun."""
    scene = catalogue["scene"]
    assert scene.shape == catalogue["period"].shape
    assert set(scene.dtype.names) >= {"damping", "forcing_amplitude", "gravity", "length",
                                      "torque"}
    assert not {"forcing_frequency", "forcing_phase"} & set(scene.dtype.names)
    np.testing.assert_array_equal(scene["forcing_amplitude"], 1.66)
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9),
                      forcing_amplitude=[1.66 * (1 + 1e-12)], damping=[0.2])
    sweep.engine.prepare(SCENE, grid, **EARLY, attractors=catalogue)
    selected = {key: value[:2] for key, value in catalogue.items()}  # the docs' idiom
    sweep.engine.prepare(SCENE, grid, **EARLY, attractors=selected)
    attrs = sweep.engine._catalogue_attrs(selected)
    again = sweep.catalogue_scene.from_attributes(attrs)["scene"]
    np.testing.assert_array_equal(again["damping"], [0.2, 0.2])
    with pytest.raises(ValueError, match=r"computed for damping = 0\.2, but this run's "
                                         r"damping = 0\.3"):
        sweep.engine.prepare(SCENE, sweep.Grid(theta0=[0.0], omega0=[0.0], damping=[0.3]),
                             **EARLY, attractors=dict(selected, scene=again))


def test_a_catalogue_of_a_slice_of_a_run_over_scenes_is_of_the_slice_s_scene():
    """A strobe run over two forcing amplitudes, then the catalogue of one slice
    (``ds.sel(forcing_amplitude=1.3)``, or an ``isel`` keeping the dim): the run's
    ``strobe_scene`` lacks the amplitude it varied, the slice has one value of it, and
    that value is the slice's scene. Its own amplitude is accepted (it was refused as
    a scene without forcing_amplitude, and worked before the scene was recorded);
    another amplitude is refused."""
    run = dict(EARLY, t_end=40 * PERIOD)  # short: only the catalogue's scene is read
    axes = dict(theta0=np.linspace(-np.pi, np.pi, 5), omega0=np.linspace(-4, 4, 5))
    ds = sweep.run(SCENE, sweep.Grid(**axes, forcing_amplitude=[1.2, 1.3]), **run)
    for part in (ds.sel(forcing_amplitude=1.3), ds.isel(forcing_amplitude=[1])):
        catalogue = maps.attractor_catalogue(part)
        np.testing.assert_array_equal(catalogue["scene"]["forcing_amplitude"], 1.3)
        assert "theta0" not in catalogue["scene"].dtype.names
        sweep.engine.prepare(SCENE, sweep.Grid(**axes, forcing_amplitude=[1.3]), **run,
                             attractors=catalogue)
        with pytest.raises(ValueError, match=r"computed for forcing_amplitude = 1\.3, "
                                             r"but this run's forcing_amplitude = 1\.2"):
            sweep.engine.prepare(SCENE, sweep.Grid(**axes, forcing_amplitude=[1.2]), **run,
                                 attractors=catalogue)


def test_a_parameter_only_one_side_knows_is_accepted_at_zero(catalogue, no_compute):
    """A catalogue made where another effect was registered (its parameters recorded at
    0, the value of an absent effect) or where one was not (the run's scene then has a
    parameter at 0 that the catalogue lacks) holds the same scene: accepted (both were
    refused, as a scene with or without that parameter). At another value it is
    another scene: refused."""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9))
    recorded = {name: catalogue["scene"][name][0] for name in catalogue["scene"].dtype.names}
    count = catalogue["period"].size
    with_plugin = dict(catalogue, scene=sweep.catalogue_scene.as_record(
        dict(recorded, plugin_stiffness=0.0), count))
    sweep.engine.prepare(SCENE, grid, **EARLY, attractors=with_plugin)
    without_torque = dict(catalogue, scene=sweep.catalogue_scene.as_record(
        {k: v for k, v in recorded.items() if k != "torque"}, count))
    sweep.engine.prepare(SCENE, grid, **EARLY, attractors=without_torque)
    stiff = dict(catalogue, scene=sweep.catalogue_scene.as_record(
        dict(recorded, plugin_stiffness=0.5), count))
    with pytest.raises(ValueError, match=r"computed for plugin_stiffness = 0\.5, and this "
                                         r"run has no one value of plugin_stiffness"):
        sweep.engine.prepare(SCENE, grid, **EARLY, attractors=stiff)
    torqued = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2), sweep.Torque(0.1)))
    with pytest.raises(ValueError, match=r"this run's torque = 0\.1, but the catalogue "
                                         r"was computed for a scene without torque"):
        sweep.engine.prepare(torqued, grid, **EARLY, attractors=without_torque)


def test_the_one_value_of_an_axis():
    """`catalogue_scene.one_value`: an axis's, coordinate's or attribute's one distinct
    value, None for several or none; `grid_value`: a grid axis's one value, else the
    default, refused (naming the axis) where the grid varies it."""
    from sweep.catalogue_scene import grid_value, one_value

    assert one_value([1.5, 1.5]) == 1.5 and one_value(2) == 2.0
    assert one_value([1.0, 2.0]) is None and one_value([]) is None
    grid = sweep.Grid(theta0=[0.0, 1.0], forcing_frequency=[1.5])
    assert grid_value(grid, "forcing_frequency", 9.0) == 1.5
    assert grid_value(grid, "forcing_phase", 0.25) == 0.25
    with pytest.raises(ValueError, match="axis theta0 has several values; accepted: one"):
        grid_value(grid, "theta0", 0.0)
