"""Stopping forced trajectories on known cells: `sweep.run(..., known_cells=...)` and
`sweep.maps.refine(..., known_cells=True)` (issue 37).

Oracles: a run without known cells (a map that knows nothing must change no bit), the
full run's labels (the accuracy target), and the same run cut in other ways (threads,
blocks, chunks, Dask: the known map is frozen during a run, so every cut gives the same
bits).
"""

import hashlib

import numba
import numpy as np
import pytest
import xarray as xr
from shared_kernels import WADA_PILOT, WADA_RUN_FILE, WADA_SCENE

import sweep
from sweep import _config, maps
from sweep._known import hits_needed, known_arguments
from sweep.kernels import KernelSpec, source
from sweep.maps.known import background, background_factors, settled
from sweep.observables import KNOWN_HITS, KNOWN_HITS_BY_DEPTH

#: A small Wada map (the issue's scene, c = 0.2, A = 1.66, W = 1): its boundaries are
#: fractal, so a map of known cells there is tested where it is hardest.
SIZE = 48
GRID = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, SIZE), omega0=np.linspace(-4, 4, SIZE))


def _known(values, grid=GRID):
    return xr.DataArray(np.asarray(values, dtype=np.int32), dims=("theta0", "omega0"),
                        coords={"theta0": grid.axes["theta0"], "omega0": grid.axes["omega0"]})


def _run(catalogue, grid=GRID, **kwargs):
    return sweep.run(WADA_SCENE, grid, attractors=catalogue, **WADA_PILOT, **kwargs)


def test_a_map_that_knows_nothing_changes_no_bit(wada_catalogue):
    plain = _run(wada_catalogue)
    nothing = _run(wada_catalogue, known_cells=_known(np.full((SIZE, SIZE), -1)))
    assert nothing.attrs["cells_stopped_known"] == 0
    assert (nothing["stopped_known"] == 0).all()
    for name in ("strobe_theta", "strobe_omega", "attractor", "status"):
        np.testing.assert_array_equal(plain[name].values, nothing[name].values)


@pytest.mark.parametrize("transient, end", [(0.0, 40.5), (3.37, 41.9), (20.0, 40.0)])
def test_a_map_that_knows_nothing_changes_no_bit_whatever_the_transient(
        wada_catalogue, transient, end):
    """With known cells the refill kernel runs the strobe and attractor observables
    only at the steady window's stroboscopic steps (`Observable.phase`): their samples,
    matches and stops are still the plain run's, with no transient, one of no whole
    number of periods, and a run that ends between two stroboscopic steps."""
    period = 2 * np.pi
    run = dict(WADA_PILOT, t_transient=transient * period, t_end=end * period)
    # the rings alone: a catalogue that records its drive phase (the pilot's, 0) is
    # refused at 3.37 periods, where no start could match it; the kernel is the same
    rings = {key: wada_catalogue[key] for key in ("theta", "omega", "period")}
    plain = sweep.run(WADA_SCENE, GRID, attractors=rings, **run)
    nothing = sweep.run(WADA_SCENE, GRID, attractors=rings, **run,
                        known_cells=_known(np.full((SIZE, SIZE), -1)))
    assert np.isfinite(plain["strobe_theta"].values).all(axis=-1).any()  # rings filled
    for name in ("strobe_theta", "strobe_omega", "attractor", "status"):
        np.testing.assert_array_equal(plain[name].values, nothing[name].values)


def test_a_map_of_one_label_stops_every_trajectory_with_it(wada_catalogue):
    """Every cell known as attractor 1: each trajectory's first KNOWN_HITS
    stroboscopic points are hits (the angle wrapped onto the map's rows), so it stops
    there with label 1, long before the catalogue's 20-period transient."""
    ds = _run(wada_catalogue, known_cells=_known(np.ones((SIZE, SIZE))))
    assert ds.attrs["cells_stopped_known"] == SIZE * SIZE
    assert (ds["attractor"] == 1).all() and (ds["stopped_known"] == 1).all()
    # the map shifted by a whole turn is the same map: still every trajectory
    shifted = sweep.Grid(theta0=GRID.axes["theta0"] + 2 * np.pi, omega0=GRID.axes["omega0"])
    again = _run(wada_catalogue, known_cells=_known(np.ones((SIZE, SIZE)), shifted))
    assert again.attrs["cells_stopped_known"] == SIZE * SIZE
    # a map of omega0 beyond anywhere a trajectory goes: no hit, the plain run
    far = sweep.Grid(theta0=GRID.axes["theta0"], omega0=GRID.axes["omega0"] + 100.0)
    none = _run(wada_catalogue, known_cells=_known(np.ones((SIZE, SIZE)), far))
    assert none.attrs["cells_stopped_known"] == 0


def test_a_cell_deep_inside_one_label_stops_a_trajectory_on_fewer_hits():
    """KNOWN_HITS_BY_DEPTH: a cell whose label reaches 2 rows and columns around it
    needs 1 hit, 1 row and column 2 hits, the cell alone 3 (the map's edge counts as
    disagreeing)."""
    labels = np.zeros((7, 8), dtype=np.int64)
    labels[6, 7] = 1
    labels[0, 0] = -1
    want = np.array([[0, 3, 3, 3, 3, 3, 3, 3],   # the edge: 3; unknown: 0 (no hit)
                     [3, 3, 2, 2, 2, 2, 2, 3],   # (1, 1) touches the unknown corner
                     [3, 2, 2, 1, 1, 1, 2, 3],   # (2, 2) reaches it within 2
                     [3, 2, 1, 1, 1, 1, 2, 3],
                     [3, 2, 1, 1, 1, 2, 2, 3],   # (4, 5) reaches label 1 within 2
                     [3, 2, 2, 2, 2, 2, 3, 3],   # (5, 6) touches it
                     [3, 3, 3, 3, 3, 3, 3, 3]])
    np.testing.assert_array_equal(hits_needed(labels), want)
    assert KNOWN_HITS_BY_DEPTH[0] == KNOWN_HITS
    codes, _ = known_arguments(_known(labels, sweep.Grid(theta0=np.arange(7.0),
                                                         omega0=np.arange(8.0))))
    np.testing.assert_array_equal(codes, np.where(labels >= 0, 4 * labels + want, -1))


def test_one_hit_deep_inside_stops_a_trajectory(wada_catalogue):
    """A map of one label, run for 2.5 forcing periods (2 stroboscopic times): 3 hits
    running could never be reached, but away from the map's edges 1 hit is enough (the
    trajectories whose first point falls on the edge rows or columns, or beyond the
    map, run on)."""
    period = 2 * np.pi
    short = dict(WADA_PILOT, t_end=2.5 * period, t_transient=2 * period)
    ds = sweep.run(WADA_SCENE, GRID, attractors=wada_catalogue, **short,
                   known_cells=_known(np.ones((SIZE, SIZE))))
    assert ds.attrs["cells_stopped_known"] > SIZE * SIZE // 2
    assert (ds["attractor"].values[ds["stopped_known"].values == 1] == 1).all()


def test_a_map_of_400_points_per_axis_runs_no_half_resolution_background(wada_catalogue):
    """HALF_BELOW: the 1/2 map costs more than it saves from 400 points per axis on
    (measured); below, and when either axis is shorter, it runs."""
    assert background_factors(400, 1200) == (8, 4)
    assert background_factors(399, 1200) == background_factors(48, 48) == (8, 4, 2)
    axes = [np.linspace(-np.pi, np.pi, 400), np.linspace(-4, 4, 400)]
    _, cells = background(WADA_SCENE, *axes, wada_catalogue, **WADA_PILOT)
    assert cells == 50 * 50 + 100 * 100  # the 1/8 and 1/4 maps only


def test_refine_runs_the_half_resolution_background_whatever_the_size(wada_catalogue,
                                                                       monkeypatch):
    """refine fills blocks from its own levels, so it keeps the 1/2 map (measured: 1228
    starts of the 1200 x 1200 map differ from the full run without it, 696 with it):
    with HALF_BELOW lowered to this map's 48 points, its 24 x 24 background still
    runs (the 1/8 and 1/4 maps are below 16 points per axis, so skipped)."""
    monkeypatch.setattr(sweep.maps.known, "HALF_BELOW", SIZE)
    assert background_factors(SIZE, SIZE) == (8, 4)
    assert _refined(wada_catalogue).attrs["background_cells"] == 24 * 24


def test_refine_runs_its_backgrounds_on_the_grid_s_one_value_axes():
    """A grid's one-value axis (damping = 0.25 over the scene's 0.2) is the map's scene,
    and the catalogue's (the pilot runs the grid): the background maps run it too. They
    ran the scene's 0.2 (silently, then refused as another scene than the catalogue's),
    so the map must equal the same map of a scene with damping 0.25 and no such axis."""
    run = dict(WADA_PILOT, t_end=40 * 2 * np.pi)  # short: the oracle is the other map
    axes = dict(theta0=np.linspace(-np.pi, np.pi, 32), omega0=np.linspace(-4, 4, 32))
    # 32 points per axis: the 1/2 background (16 x 16) is the one run
    grid = sweep.Grid(**axes, damping=np.array([0.25]))
    catalogue = maps.pilot_catalogue(WADA_SCENE, grid, 5, **run)
    got = maps.refine(WADA_SCENE, grid, attractors=catalogue, known_cells=True, **run)
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.25), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    plain = sweep.Grid(**axes)
    want = maps.refine(scene, plain, attractors=maps.pilot_catalogue(scene, plain, 5, **run),
                       known_cells=True, **run)
    assert got.attrs["background_cells"] == want.attrs["background_cells"] == 16 * 16
    np.testing.assert_array_equal(got.values.reshape(32, 32), want.values)


def test_settled_cells_are_those_whose_neighbours_agree():
    labels = np.zeros((5, 6), dtype=np.int64)
    labels[2, 3] = 1
    labels[0, 0] = -1
    got = settled(labels)
    want = np.full((5, 6), -1)
    want[1:4, 1:5] = 0  # the interior, less the neighbours of the odd cell
    want[1:4, 2:5] = -1
    want[2, 1] = 0
    want[1, 1] = -1  # beside the unknown corner
    np.testing.assert_array_equal(got, want)


def _refined(catalogue, **kwargs):
    return maps.refine(WADA_SCENE, GRID, attractors=catalogue, known_cells=True,
                       **WADA_PILOT, **kwargs)


def test_refine_with_known_cells_meets_the_accuracy_target(wada_catalogue):
    """Against the full-length run without early stop (the reference of the issue):
    the target is at most 1e-3 of the starts labelled differently, and the fractions
    within one standard error. On 96 x 96 = 9216 starts, 1e-3 is 9.2 starts: at most
    9 may differ. (The coarser the map, the larger its cells against the basins'
    filaments: at 48 x 48, 9 of 2304 differ; the maps guide has the measurements.)"""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 96), omega0=np.linspace(-4, 4, 96))
    full = maps.basins(sweep.run(WADA_SCENE, grid, t_end=WADA_PILOT["t_end"],
                                 dt=WADA_PILOT["dt"], t_transient=300 * 2 * np.pi,
                                 observe=("strobe",), progress=False))
    known = maps.refine(WADA_SCENE, grid, attractors=wada_catalogue, known_cells=True,
                        **WADA_PILOT)
    assert known.attrs["cells_stopped_known"] > 0
    assert int((known.values != full.values).sum()) <= 9
    n = full.size
    for label in range(len(full.attrs["attractor_size"])):
        p = float((full.values == label).mean())
        # one standard error of a fraction p of n starts
        assert abs(float((known.values == label).mean()) - p) <= np.sqrt(p * (1 - p) / n)


def test_refine_with_known_cells_is_the_same_for_any_threads_blocks_and_chunks(
        wada_catalogue, monkeypatch):
    first = _refined(wada_catalogue)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _refined(wada_catalogue, chunk_size=37)
    finally:
        numba.set_num_threads(before)
    monkeypatch.setattr(_config, "SMALL_BLOCK", 8)  # early stop's block
    blocks = _refined(wada_catalogue, chunk_size=500)
    monkeypatch.setattr(_config, "REFILL", False)  # the fixed-step kernel's own code
    fixed = _refined(wada_catalogue)
    for other in (one, blocks, fixed):
        xr.testing.assert_identical(first, other)


def test_a_run_on_known_cells_is_the_same_on_a_dask_cluster(wada_catalogue):
    """The known map travels with the run's context to each worker: the chunks there
    (two processes, one thread each) give the local run's bits."""
    distributed = pytest.importorskip("distributed")
    from dask_clusters import DASHBOARD, port_8787_taken

    known = _known(settled(_run(wada_catalogue)["attractor"].values.astype(np.int64)))
    local = _run(wada_catalogue, known_cells=known)
    assert local.attrs["cells_stopped_known"] > 0
    with port_8787_taken():
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           dashboard_address=DASHBOARD,
                                           env={"NUMBA_NUM_THREADS": "1"})
    with cluster, distributed.Client(cluster) as client:
        remote = _run(wada_catalogue, known_cells=known, client=client, chunk_size=300)
    local.attrs.pop("history", None)
    remote.attrs.pop("history", None)
    xr.testing.assert_identical(local, remote)


def test_option_off_changes_no_kernel_source():
    """The known-cells code is pasted in only with known_cells=True: without it the
    kernel takes the contract's arguments and reads nothing of it."""
    for refill in (False, True):
        spec = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe", "attractor"),
                          stop_early=True, refill=refill)
        text = source(spec)
        assert "known" not in text and "acc_kn" not in text
        with_known = source(KernelSpec(spec.model, spec.effects, spec.observe,
                                       stop_early=True, refill=refill, known_cells=True))
        assert "saved, catalogue, known, known_axes)" in with_known
        assert hashlib.sha1(text.encode()).digest() != \
            hashlib.sha1(with_known.encode()).digest()


@pytest.mark.parametrize("kwargs, message", [
    (dict(known_cells="yes"), "known_cells must be True or False"),
    (dict(known_cells=True, stop_early=False), "needs stop_early=True"),
    (dict(known_cells=True, pilot=None), "needs an attractor catalogue"),
    (dict(known_cells=True, observe=("final",)), "lacks 'strobe'"),
])
def test_refine_refuses_bad_known_cells_before_any_compute(kwargs, message, no_compute):
    run = dict(WADA_PILOT, **{k: v for k, v in kwargs.items() if k in ("stop_early",
                                                                       "observe")})
    options = {k: v for k, v in kwargs.items() if k not in ("stop_early", "observe")}
    with pytest.raises(ValueError, match=message):
        maps.refine(WADA_SCENE, GRID, **options, **run)


def test_refine_refuses_known_cells_for_an_unforced_map(no_compute):
    scene = sweep.Scene(effects=(sweep.Damping(0.5),))
    with pytest.raises(ValueError, match="without forcing"):
        maps.refine(scene, GRID, known_cells=True, t_end=10.0, dt=0.01,
                    observe=("capture",), stop_early=True)


def test_run_refuses_bad_known_cells_before_any_compute(wada_catalogue, no_compute):
    good = _known(np.zeros((SIZE, SIZE)))
    cases = [
        (dict(known_cells=good, attractors=None), "stop_early=True and attractors"),
        (dict(known_cells=good, attractors=wada_catalogue, stop_early=False),
         "stop_early=True and attractors"),
        (dict(known_cells=good.rename(theta0="x"), attractors=wada_catalogue),
         "DataArray over theta0 and omega0"),
        (dict(known_cells=good + 7, attractors=wada_catalogue),
         "holds 7 at \\(0, 0\\), but the catalogue has 3 attractors"),
        (dict(known_cells=good.astype(float), attractors=wada_catalogue),
         "holds float64 values"),
        (dict(known_cells=good.assign_coords(theta0=np.geomspace(1, 2, SIZE)),
              attractors=wada_catalogue), "axis theta0 is not evenly spaced"),
        (dict(known_cells=good, attractors=wada_catalogue, dtype="float32"),
         "runs on the CPU in float64"),
        (dict(known_cells=good, attractors=wada_catalogue, checkpoint="somewhere"),
         "cannot be used with a checkpoint"),
    ]
    for options, message in cases:
        run = dict(WADA_PILOT, **{k: v for k, v in options.items() if k == "stop_early"})
        options = {k: v for k, v in options.items() if k != "stop_early"}
        with pytest.raises(ValueError, match=message):
            sweep.run(WADA_SCENE, GRID, **run, **options)


def test_run_refuses_known_cells_for_a_system(no_compute):
    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 3), theta2_0=np.linspace(-1, 1, 4))
    with pytest.raises(ValueError, match="known_cells is for the pendulum's forced basins"):
        sweep.run(sweep.DoublePendulum(), grid, t_end=1.0, dt=0.1,
                  known_cells=_known(np.zeros((SIZE, SIZE))))


def test_refine_with_known_cells_on_a_grid_of_omega0_first(wada_catalogue):
    """The map of known cells has theta0 rows whatever the grid's order: a grid of
    omega0 x theta0 gives the transposed labels."""
    flipped = sweep.Grid(omega0=GRID.axes["omega0"], theta0=GRID.axes["theta0"])
    first = _refined(wada_catalogue)
    other = maps.refine(WADA_SCENE, flipped, attractors=wada_catalogue, known_cells=True,
                        **WADA_PILOT)
    assert other.dims == ("omega0", "theta0")
    assert other.attrs["cells_stopped_known"] == first.attrs["cells_stopped_known"]
    np.testing.assert_array_equal(other.values.T, first.values)


# ---------------------------------------------------------------------- run files


def test_a_run_file_stops_on_known_cells_and_labels_as_the_catalogue_route(tmp_path,
                                                                          wada_catalogue):
    """``[run] known_cells = true`` with ``pilot = 21`` on 161 x 161 starts: coarse maps
    of the grid first, then the map stops on their settled cells; every start gets the
    label of the catalogue route (measured: none differs; at 64 x 64, 32 of 4096 did, so
    the route refuses fewer than 96). 161 = 8 x 20 + 1 points per axis: the pilot's every
    eighth start is, to the bit, conftest's 21 x 21 pilot (at 96 it thinned to other
    starts, so another catalogue and two kernels of its own), so the catalogue and the
    kernels are the ``wada_catalogue`` fixture's."""
    from test_cli import call, write

    paths = {}
    for name, extra in (("known", "pilot = 21\nknown_cells = true"), ("plain", "pilot = 21")):
        paths[name] = tmp_path / f"{name}.nc"
        code, _out, err = call("run", write(tmp_path, WADA_RUN_FILE.format(extra=extra, n=161),
                                           f"{name}.toml"), "-o", paths[name],
                              "--no-progress")
        assert (code, err) == (0, ""), err
    known, plain = sweep.load(paths["known"]), sweep.load(paths["plain"])
    for ds in (known, plain):  # the fixture's catalogue, so its kernels
        np.testing.assert_array_equal(sweep.io.run_arguments(ds)["attractors"]["theta"],
                                      wada_catalogue["theta"])
    assert known.attrs["cells_stopped_known"] > 0 and "stopped_known" not in plain
    np.testing.assert_array_equal(maps.basins(known).values, maps.basins(plain).values)


@pytest.mark.parametrize("extra, argv, words", [
    ("known_cells = true", [], "known_cells = true with pilot = N"),
    ("known_cells = 1", [], "known_cells"),
    ("pilot = 21\nknown_cells = true", ["--checkpoint", "ck"], "cannot be used with"),
    ("pilot = 21\nknown_cells = true", ["--small"], "needs 96 points or more per axis"),
])
def test_a_run_files_known_cells_errors_are_one_line_before_any_compute(
        tmp_path, no_compute, extra, argv, words):
    from test_cli import call, write

    n = 64 if "--small" in argv else 96
    argv = [a if a != "ck" else str(tmp_path / "ck") for a in argv if a != "--small"]
    code, out, err = call("run", write(tmp_path, WADA_RUN_FILE.format(extra=extra, n=n)), "-o",
                          tmp_path / "out.nc", *argv)
    assert code != 0 and out == ""
    assert err.startswith("sweep: error:") and words in err and err.count("\n") == 1
    assert not (tmp_path / "out.nc").exists()
