"""`sweep.Points`: a table of parameter sets run by `sweep.run` exactly as a `Grid` is.

The oracle is the grid itself: points drawn from a grid's cells, with the cells' exact
parameter values, must give every variable (status included) bit-identical to those
cells, since both reach the kernel as rows of the same parameter table (one path below
`ParameterRows`). Runs are small and share kernel specs (a grid of 91 cells and 30 points
both run in `sweep._config.SMALL_BLOCK` lanes), since each new spec compiles for seconds.
"""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from dask_clusters import DASHBOARD, port_8787_taken
from shared_kernels import EVERY, EVERY_ADAPTIVE

import sweep
from sweep import maps

DAMPED = sweep.Scene(effects=(sweep.Damping(0.2),))
GRID = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 13), omega0=np.linspace(-2.0, 2.0, 7))
#: every observable: the damped scene's kernels of test_naive, test_engine and
#: test_distributed for the same grid sizes (tests/shared_kernels.py)
BASE = dict(t_end=5.0, dt=0.01, observe=EVERY, progress=False)

FORCED = sweep.Scene(gravity=1.0, length=1.0,
                     effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
PERIOD = 2 * np.pi
FORCED_GRID = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9),
                         omega0=np.linspace(-4.0, 4.0, 9))
FORCED_RUN = dict(t_end=60 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD,
                  observe=("strobe",), stop_early=True, progress=False)


def subset(grid: sweep.Grid, n: int, seed: int = 3):
    """``n`` distinct random cells of a 2-D ``grid``: (Points with the cells' exact
    values, and the cells' indices along each axis)."""
    picks = np.random.default_rng(seed).choice(grid.size, n, replace=False)
    index = np.unravel_index(picks, grid.shape)
    columns = {name: values[i] for (name, values), i in zip(grid.axes.items(), index)}
    return sweep.Points(**columns), index


def assert_same_as_cells(points_ds, grid_ds, index):
    """Every data variable of the points run equals the grid run's at the cells."""
    assert set(points_ds.data_vars) == set(grid_ds.data_vars)
    for name in grid_ds.data_vars:
        cells = grid_ds[name].transpose(*grid_ds.attrs["grid_axes"].split(), ...).values[index]
        assert np.array_equal(points_ds[name].values, cells, equal_nan=True), name


# ------------------------------------------------------------------ construction
def test_points_has_grid_like_attributes():
    points = sweep.Points(theta0=[0.1, 2.0, 2.0], omega0=[0, 0.5, -0.5], damping=0.2)
    assert points.dims == ("point",) and points.shape == (3,) and points.size == 3
    assert list(points.axes) == ["theta0", "omega0", "damping"]
    np.testing.assert_array_equal(points.axes["damping"], [0.2, 0.2, 0.2])  # scalar: constant
    for values in points.axes.values():
        assert values.dtype == np.float64 and not values.flags.writeable
    assert repr(points) == "Points(theta0=<3 values>, omega0=<3 values>, damping=<3 values>)"
    assert points.varies("theta0") and not points.varies("damping")
    assert not points.varies("length")  # not an axis
    assert sweep.Points(theta0=0.5).shape == (1,)  # all scalars: one point
    # a chunk's rows are the points' own, with the scene's other parameters
    table = points.table(DAMPED, 1, 3)
    names = sweep.physics.parameter_names()
    np.testing.assert_array_equal(table[:, names.index("theta0")], [2.0, 2.0])
    np.testing.assert_array_equal(table[:, names.index("omega0")], [0.5, -0.5])
    assert np.all(table[:, names.index("length")] == 1.0)


@pytest.mark.parametrize("axes, message", [
    ({}, "Points needs at least one axis; accepted axis names: theta0"),
    ({"theta": [1.0]}, "unknown points axis 'theta'; accepted axis names: theta0"),
    ({"theta0": [0.0, 1.0], "omega0": [1.0, 2.0, 3.0]},
     "points axes have unequal lengths: theta0 has 2, omega0 has 3; accepted: 1-D arrays "
     "of one length"),
    ({"theta0": [[0.0, 1.0]]}, r"points axis 'theta0' must be 1-D .* shape \(1, 2\)"),
    ({"theta0": []}, "points axis 'theta0' is empty; accepted: at least one value"),
    ({"theta0": [0.0, np.nan]}, "points axis 'theta0' has non-finite value nan at index 1; "
                                "accepted: finite numbers"),
    ({"theta0": "0.5"}, "points axis 'theta0' must be a 1-D array of numbers"),
    ({"theta0": [True, False]}, "points axis 'theta0'"),
    ({"length": [1.0, -1.0]}, "points axis 'length' has value -1.0 at index 1; accepted: "
                              "finite numbers > 0"),
])
def test_bad_points_are_refused_naming_axis_value_and_accepted(axes, message):
    with pytest.raises(ValueError, match=message):
        sweep.Points(**axes)


def test_points_needing_an_effect_the_scene_lacks_are_refused(no_compute):
    with pytest.raises(ValueError, match="points axis 'forcing_phase' needs a forcing"):
        sweep.run(DAMPED, sweep.Points(forcing_phase=[0.0, 1.0]), **BASE)
    with pytest.raises(TypeError, match=r"grid must be a sweep\.Grid or sweep\.Points"):
        sweep.run(DAMPED, {"theta0": [1.0]}, **BASE)


# ------------------------------------------------------------------ bit-identity
@pytest.fixture(scope="module")
def damped_pair():
    points, index = subset(GRID, 30)
    return sweep.run(DAMPED, points, **BASE), sweep.run(DAMPED, GRID, **BASE), index


def test_points_run_is_bit_identical_to_the_grid_cells(damped_pair):
    ds, grid_ds, index = damped_pair
    assert ds.sizes == {"point": 30} and "point" not in ds.coords
    for name in ("theta0", "omega0"):
        assert ds[name].dims == ("point",)
        assert ds[name].attrs == grid_ds[name].attrs  # units and long_name
    assert_same_as_cells(ds, grid_ds, index)
    assert ds.attrs["point_axes"] == "theta0 omega0" and "grid_axes" not in ds.attrs
    same = {"effects", "damping", "length", "gravity", "method", "dt", "observe", "scene"}
    assert {k: ds.attrs[k] for k in same} == {k: grid_ds.attrs[k] for k in same}


def test_repeated_points_give_repeated_results():
    points = sweep.Points(theta0=[1.0, 2.5, 1.0], omega0=[0.5, 0.0, 0.5])
    ds = sweep.run(DAMPED, points, **BASE)
    for name in ds.data_vars:
        assert np.array_equal(ds[name].values[0], ds[name].values[2]), name


def test_a_saved_points_file_says_how_to_rerun_it(damped_pair, tmp_path):
    ds, _, _ = damped_pair
    back = sweep.load(sweep.save(ds, tmp_path / "points.nc"))
    points = sweep.io.grid_from(back)
    assert isinstance(points, sweep.Points)
    again = sweep.run(sweep.io.scene_from(back), points, **sweep.io.run_arguments(back),
                      progress=False)
    assert again.drop_attrs().identical(ds.drop_attrs())
    assert isinstance(sweep.io.grid_from(sweep.run(DAMPED, GRID, **BASE)), sweep.Grid)
    with pytest.raises(ValueError, match="neither a 'grid_axes' nor a 'point_axes'"):
        sweep.io.grid_from(xr.Dataset())


@pytest.mark.parametrize("case", ["stop_early", "float32", "dopri5"])
def test_points_are_bit_identical_for_other_run_settings(case):
    kwargs = {"stop_early": dict(t_end=20.0, dt=0.01, observe=("capture",), stop_early=True),
              "float32": dict(BASE, dtype="float32"),
              "dopri5": dict(BASE, method="dopri5", rtol=1e-6, atol=1e-9,
                             observe=EVERY_ADAPTIVE)}[case]
    kwargs = dict(kwargs, progress=False)
    points, index = subset(GRID, 30)
    assert_same_as_cells(sweep.run(DAMPED, points, **kwargs),
                         sweep.run(DAMPED, GRID, **kwargs), index)


@pytest.fixture(scope="module")
def forced_pair(wada_catalogue):
    """A forced run with strobe and a catalogue of its scene, as grid and as points (the
    catalogue is conftest's, from a finer pilot: any catalogue of the scene will do, and
    this one's kernel is shared with other files instead of compiled for this file's)."""
    catalogue = wada_catalogue
    points, index = subset(FORCED_GRID, 40)
    run = dict(FORCED_RUN, attractors=catalogue)
    return (sweep.run(FORCED, points, **run), sweep.run(FORCED, FORCED_GRID, **run), index,
            catalogue)


def test_forced_points_with_a_catalogue_are_bit_identical(forced_pair):
    ds, grid_ds, index, _ = forced_pair
    assert "attractor" in ds and ds["strobe_theta"].dims == ("point", "strobe")
    assert_same_as_cells(ds, grid_ds, index)


# ------------------------------------------------------------------ the engine's paths
def _same(a, b):
    """Identical datasets but for the creation time."""
    a, b = a.copy(), b.copy()
    for ds in (a, b):
        ds.attrs.pop("history", None)
    xr.testing.assert_identical(a, b)


def test_points_checkpoint_resumes_bit_identically(damped_pair, tmp_path):
    ds, _, _ = damped_pair
    points = sweep.io.grid_from(ds)
    folder = tmp_path / "ck"
    sweep.run(DAMPED, points, checkpoint=folder, keep_checkpoint=True, chunk_size=8, **BASE)
    chunks = sorted(folder.glob("chunk-*.npz"))
    assert len(chunks) == 4  # 30 points in chunks of 8
    chunks[1].unlink()  # as if interrupted: one chunk is recomputed on resume
    _same(sweep.run(DAMPED, points, checkpoint=folder, resume=True, chunk_size=8, **BASE), ds)
    # a checkpoint of other points is refused, naming the difference
    sweep.run(DAMPED, points, checkpoint=tmp_path / "other", keep_checkpoint=True,
              chunk_size=8, **BASE)
    moved = sweep.Points(theta0=points.axes["theta0"] + 0.5, omega0=points.axes["omega0"])
    with pytest.raises(ValueError, match="grid"):
        sweep.run(DAMPED, moved, checkpoint=tmp_path / "other", resume=True, chunk_size=8,
                  **BASE)


def test_points_stream_to_netcdf_by_row_ranges(damped_pair, tmp_path):
    from sweep.distributed import run_to_netcdf

    ds, _, _ = damped_pair
    path = run_to_netcdf(tmp_path / "points.nc", DAMPED, sweep.io.grid_from(ds),
                         rows_per_task=7, **BASE)  # 5 blocks of rows, the last short
    _same(sweep.load(path), ds)


def test_points_on_a_dask_cluster_are_identical(damped_pair, tmp_path):
    distributed = pytest.importorskip("distributed")
    from sweep.distributed import run_to_netcdf

    ds, _, _ = damped_pair
    points = sweep.io.grid_from(ds)
    with port_8787_taken():  # tests/dask_clusters.py: the Scheduler on a free port
        cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1,
                                           processes=False, dashboard_address=DASHBOARD)
    with cluster, distributed.Client(cluster) as client:
        _same(sweep.run(DAMPED, points, client=client, chunk_size=8, **BASE), ds)
        path = run_to_netcdf(tmp_path / "p.nc", DAMPED, points, client=client,
                             rows_per_task=16, **BASE)
    _same(sweep.load(path), ds)


def test_points_on_cuda_are_bit_identical_to_the_grid_on_cuda():
    """Under numba's CUDA simulator (tests/conftest.py) or a GPU: the same device code,
    so the cells agree exactly (CPU and GPU differ by an ulp in sine: not compared)."""
    pytest.importorskip("numba.cuda")
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 5), omega0=[-1.0, 0.0, 2.0])
    points, index = subset(grid, 6)
    kwargs = dict(BASE, t_end=1.0, device="cuda")
    ds = sweep.run(DAMPED, points, chunk_size=4, **kwargs)  # two chunks: rows per chunk
    assert ds.attrs["device"] == "cuda"
    assert_same_as_cells(ds, sweep.run(DAMPED, grid, **kwargs), index)


def test_a_catalogue_takes_points_of_one_scene_only(forced_pair, no_compute):
    _, _, _, catalogue = forced_pair
    run = dict(FORCED_RUN, attractors=catalogue)
    varied = sweep.Points(theta0=[0.0, 1.0], damping=[0.2, 0.3])
    with pytest.raises(ValueError, match="grid varies damping; accepted: a grid that varies "
                                         "only theta0 and omega0"):
        sweep.run(FORCED, varied, **run)
    # a constant column is one scene: validated, then refused only because no compute
    # is allowed here
    with pytest.raises(AssertionError, match="compute started"):
        sweep.run(FORCED, sweep.Points(theta0=[0.0, 1.0], damping=[0.2, 0.2]), **run)


# ------------------------------------------------------------------ maps on points
def _same_partition(a: np.ndarray, b: np.ndarray) -> None:
    """Labels ``a`` and ``b`` name the same classes (up to renaming the labels)."""
    pairs = set(zip(a.tolist(), b.tolist()))
    assert len(pairs) == len(set(a.tolist())) == len(set(b.tolist())), pairs


def test_forced_maps_label_points_as_their_grid_cells(forced_pair):
    ds, grid_ds, index, _ = forced_pair
    for label in (maps.basins, maps.period):
        points, cells = label(ds), label(grid_ds).values[index]
        assert points.dims == ("point",)
        assert set(points.coords) == {"theta0", "omega0"}
        _same_partition(points.values, cells)
    np.testing.assert_array_equal(maps.period(ds).values, maps.period(grid_ds).values[index])
    assert maps.basins(ds).attrs["attractor_period"].size >= 2


def test_unforced_maps_label_points_as_their_grid_cells(damped_pair):
    ds, grid_ds, index = damped_pair
    np.testing.assert_array_equal(maps.motion(ds).values, maps.motion(grid_ds).values[index])
    kwargs = dict(t_end=20.0, dt=0.01, observe=EVERY, progress=False)  # BASE's kernels
    points = sweep.io.grid_from(ds)
    point_run, grid_run = sweep.run(DAMPED, points, **kwargs), sweep.run(DAMPED, GRID, **kwargs)
    np.testing.assert_array_equal(maps.well(point_run).values,
                                  maps.well(grid_run).values[index])
    np.testing.assert_array_equal(maps.inverted(point_run).values,
                                  maps.inverted(grid_run).values[index])
    _same_partition(maps.basins(point_run).values, maps.basins(grid_run).values[index])
    assert maps.basins(point_run).dims == ("point",)


# ------------------------------------------------------------------ run files, CLI
RUN_FILE = """
[scene.damping]
coefficient = 0.2
[points]
{points}
[run]
t_end = 5.0
dt = 0.01
observe = OBSERVE
""".replace("OBSERVE", str(list(EVERY)).replace("'", '"'))  # BASE's


def _sweep(*argv):
    """``sweep ARGV`` in-process: (exit status, stdout, stderr)."""
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = sweep.cli.main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def test_run_file_points_inline_from_csv_and_from_netcdf(tmp_path, damped_pair):
    from sweep.toml_spec import load_run

    ds, _, _ = damped_pair
    theta0, omega0 = ds.theta0.values, ds.omega0.values
    inline = tmp_path / "inline.toml"
    inline.write_text(RUN_FILE.format(points=f"theta0 = {theta0.tolist()}\n"
                                             f"omega0 = {omega0.tolist()}"))
    folder = tmp_path / "sub"
    folder.mkdir()
    rows = "\n".join(f"{float(t)!r},{float(w)!r}" for t, w in zip(theta0, omega0))
    (folder / "starts.csv").write_text("theta0, omega0\n" + rows + "\n")
    xr.Dataset({"theta0": ("row", theta0), "omega0": ("row", omega0)}).to_netcdf(
        folder / "starts.nc")
    for name, points in (("csv", 'file = "starts.csv"'), ("nc", 'file = "starts.nc"')):
        (folder / f"{name}.toml").write_text(RUN_FILE.format(points=points))
    for path in (inline, folder / "csv.toml", folder / "nc.toml"):  # relative to the file
        _scene, points, _kwargs = load_run(path)
        assert isinstance(points, sweep.Points)
        for axis in ("theta0", "omega0"):  # repr round trip: the exact values
            np.testing.assert_array_equal(points.axes[axis], ds[axis].values)
    status, out, err = _sweep("run", folder / "csv.toml", "-o", tmp_path / "out.nc")
    assert status == 0 and err == ""
    assert "30 trajectories (30 points of theta0, omega0)" in out
    _same(sweep.load(tmp_path / "out.nc").drop_attrs(), ds.drop_attrs())


@pytest.mark.parametrize("points, words", [
    ("theta0 = [0.0, 1.0]\nomega0 = [1.0]",
     "run.toml: points axes have unequal lengths: theta0 has 2, omega0 has 1"),
    ('file = "nowhere.csv"', "[points] file 'nowhere.csv': no such file"),
    ('file = "bad.csv"', "line 3, column 'omega0': 'x' is not a number"),
    ('file = "short.csv"', "line 2 has 1 values, the header 2"),
    ('file = "unknown.csv"', "unknown key 'theta' in the header of 'unknown.csv'"),
    ('file = "bad.nc"', "accepted: variables named theta0, omega0, ... along one"),
    ("", "[points] has no columns"),
    ("theta0 = [0.0]\n[grid]\nomega0 = [0.0]", "both [grid] and [points]"),
])
def test_bad_points_in_a_run_file_are_one_line_errors(tmp_path, points, words, no_compute):
    (tmp_path / "bad.csv").write_text("theta0,omega0\n0.0,1.0\n0.5,x\n")
    (tmp_path / "short.csv").write_text("theta0,omega0\n0.0\n")
    (tmp_path / "unknown.csv").write_text("theta,omega0\n0.0,1.0\n")
    xr.Dataset({"theta0": ("a", [0.0]), "omega0": ("b", [1.0])}).to_netcdf(tmp_path / "bad.nc")
    (tmp_path / "run.toml").write_text(RUN_FILE.format(points=points))
    status, out, err = _sweep("run", tmp_path / "run.toml", "-o", tmp_path / "out.nc")
    assert status == 2 and out == ""
    assert err.startswith("sweep: error: ") and err.count("\n") == 1, err
    assert words in err, err
    assert not (tmp_path / "out.nc").exists()


def test_the_example_points_run_file_runs_with_its_pilot(tmp_path):
    example = Path(__file__).resolve().parents[1] / "examples" / "points.toml"
    status, out, _ = _sweep("run", example, "-o", tmp_path / "points.nc")
    assert status == 0 and "8 trajectories (8 points of theta0, omega0)" in out
    ds = sweep.load(tmp_path / "points.nc")
    labels = maps.basins(ds)
    assert labels.dims == ("point",) and "attractor" in ds and (labels >= 0).all()
    assert len(np.unique(labels)) == 3  # the three attractors of the Wada map


@pytest.mark.parametrize("make", [lambda a: sweep.Grid(theta0=a),
                                  lambda a: sweep.Points(theta0=a, omega0=0.0)],
                         ids=["grid", "points"])
def test_axes_are_copies_of_the_callers_arrays(make):
    """The axes are read-only and the caller's array is not theirs: it stays writeable
    (a Grid used to lock it) and changing it changes no axis (Points kept a view)."""
    values = np.linspace(-1.0, 1.0, 5)
    rows = make(values)
    assert values.flags.writeable
    values[0] = 9.0
    assert rows.axes["theta0"][0] == -1.0
    assert not rows.axes["theta0"].flags.writeable
