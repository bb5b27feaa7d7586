"""A map's work-precision table (`sweep.map_accuracy`, issue 36 item 1): labels that
differ from the most accurate run, against oracles; bad inputs refused before any
compute; the ``sweep map-accuracy`` command's one-line errors; no half-written file."""

from __future__ import annotations

import contextlib
import functools
import io
import math
import os
import types

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import cli, engine, map_precision, maps
from sweep.map_precision import MapAccuracy, _Labeller

#: The unforced, undamped pendulum: g/L = 1 1/s^2, separatrix energy 2 [1/s^2].
FREE = sweep.Scene(gravity=1.0, length=1.0)

#: The forced Wada scene (c = 0.2, A = 1.66, W = 1; cos forcing).
WADA = sweep.Scene(gravity=1.0, length=1.0,
                   effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
PERIOD = 2 * np.pi


def _exact_motion(points):
    """Rotation (+-1, the sense of omega) or libration (0) of each start of the free
    pendulum, from its energy against the separatrix's: what `motion` says of the exact
    motion (a rotation passes the top within t_end = 64 s unless its energy is within
    about 16 exp(-64) of the separatrix, which no start of these samples is)."""
    theta, omega = points.axes["theta0"], points.axes["omega0"]
    energy = omega ** 2 / 2 + (1 - np.cos(theta))
    return np.where(energy > 2.0, np.sign(omega), 0.0), energy


@pytest.fixture(scope="module")
def free_table():
    points = sweep.sample(2000, seed=2, method="random", theta0=(-np.pi, np.pi),
                          omega0=(-3.0, 3.0))
    acc = sweep.map_accuracy(FREE, points, maps.motion, {"dt": [1.0, 0.5, 0.25, 0.125]},
                             t_end=64.0, observe=("winding",))
    return points, acc


def test_the_reference_is_the_exact_labelling_and_differing_falls_with_dt(free_table):
    points, acc = free_table
    ds = acc.dataset
    exact, _ = _exact_motion(points)
    labels = ds.labels.values
    # the reference (dt = 1/8 s, RK4: energy error ~1e-6 at most) labels every start as
    # its exact energy does
    np.testing.assert_array_equal(labels[-1], exact)
    # so each level's differing fraction is its share of wrong labels, counted exactly
    wrong = (labels != exact[None, :]).mean(axis=1)
    np.testing.assert_array_equal(ds.differing.values, wrong)
    assert list(ds.setting.values) == ["dt", "dt", "dt", "reference"]
    assert ds.differing.values[0] > 0 and ds.differing.values[-1] == 0
    assert np.all(np.diff(ds.differing.values) <= 0)
    # binomial standard error of sampled starts: sqrt(p (1 - p) / n), exactly
    p = ds.differing.values
    np.testing.assert_allclose(ds.differing_error.values, np.sqrt(p * (1 - p) / 2000),
                               rtol=1e-12)  # rounding only
    # the reference's fractions are the exact ones
    for label in (-1.0, 0.0, 1.0):
        assert float(ds.fraction.sel(label=label)[-1]) == np.mean(exact == label)
    assert ds.trajectory_steps.values.tolist() == [2000 * 64 / dt for dt in
                                                   (1.0, 0.5, 0.25, 0.125)]


def test_a_label_differs_only_where_the_energy_error_crosses_the_separatrix(free_table):
    points, acc = free_table
    _, energy = _exact_motion(points)
    ds = acc.dataset
    checked = 0
    for k in range(ds.sizes["level"] - 1):
        run = sweep.run(FREE, points, t_end=64.0, dt=float(ds.dt[k]), observe=("energy",),
                        progress=False)
        error = np.abs(run.energy_final.values - run.energy_initial.values)
        differs = ds.labels.values[k] != ds.labels.values[-1]
        # RK4 drains the pendulum's energy steadily, so the final error bounds the error
        # at the crossing: a start that changed side is within it of the separatrix
        assert np.all(np.abs(energy[differs] - 2.0) <= error[differs])
        checked += int(differs.sum())
    assert checked > 0


def test_differing_and_shifts_against_a_labelling_of_known_answer():
    """A labelling that depends on the step alone: ``theta0 > dt``. The share of starts
    whose label changes from dt_k to the reference's dt is the share of theta0 between
    them, exactly, whatever the integrator does."""
    points = sweep.sample(512, seed=3, method="random", theta0=(0.0, 1.0), omega0=0.0)

    def above_dt(ds):
        return (ds["theta0"] > float(ds.attrs["dt"])).astype(np.int64)

    dts = [0.5, 0.25, 0.125]
    acc = sweep.map_accuracy(FREE, points, above_dt, {"dt": dts}, t_end=1.0,
                             observe=("final",))
    ds = acc.dataset
    theta = points.axes["theta0"]
    for k, dt in enumerate(dts):
        level = theta > dt
        reference = theta > dts[-1]
        assert ds.differing.values[k] == np.mean(level != reference)
        shift_of_1 = np.mean(level) - np.mean(reference)
        assert float(ds.fraction_shift.sel(label=1.0)[k]) == pytest.approx(shift_of_1, abs=1e-15)
        # paired difference d_i in {-1, 0}: its variance p (1 - p), p the moved share
        moved = np.mean(level != reference)
        assert float(ds.fraction_shift_error.sel(label=1.0)[k]) == pytest.approx(
            math.sqrt(moved * (1 - moved) / 512), rel=1e-12)  # rounding only
        assert ds.max_shift.values[k] == pytest.approx(abs(shift_of_1), abs=1e-15)


def test_a_grids_fractions_have_no_standard_errors():
    """A grid's cells are not a random sample: like ``differing_error`` and
    `sweep.maps.fractions`, the fractions' and shifts' standard errors are NaN for a
    `sweep.Grid` (they were binomial), and binomial for the same starts as `Points`."""
    theta = np.linspace(0.05, 0.95, 16)

    def above_dt(ds):  # one label per start: the grid's cells and the points alike
        return (ds["theta0"] + 0 * ds["omega0"] > float(ds.attrs["dt"])).astype(np.int64)

    kw = dict(t_end=1.0, observe=("final",))
    grid = sweep.map_accuracy(FREE, sweep.Grid(theta0=theta, omega0=[0.0]), above_dt,
                              {"dt": [0.5, 0.25]}, **kw).dataset
    points = sweep.map_accuracy(FREE, sweep.Points(theta0=theta, omega0=np.zeros(16)),
                                above_dt, {"dt": [0.5, 0.25]}, **kw).dataset
    for name in ("differing_error", "fraction_error", "fraction_shift_error"):
        assert np.isnan(grid[name].values).all(), name
    np.testing.assert_array_equal(grid.fraction.values, points.fraction.values)
    p = points.fraction.values
    np.testing.assert_allclose(points.fraction_error.values, np.sqrt(p * (1 - p) / 16),
                               rtol=1e-15)  # the same formula: rounding only
    assert "NaN" in grid.fraction_error.attrs["long_name"]


def test_rate_is_the_log_log_slope():
    """differing = 3 dt^2 exactly: the fitted rate is 2 (to rounding)."""
    dts = np.array([0.4, 0.2, 0.1, 0.05])
    ds = xr.Dataset({"differing": ("level", np.append(3 * dts[:-1] ** 2, 0.0))},
                    coords={"setting": ("level", ["dt", "dt", "dt", "reference"]),
                            "dt": ("level", dts)})
    assert MapAccuracy(ds).rate("dt") == pytest.approx(2.0, rel=1e-12)  # rounding only
    with pytest.raises(ValueError, match="setting = 'dtype'"):
        MapAccuracy(ds).rate("dtype")


def test_a_grid_has_no_standard_error_and_unforced_basins_number_wells_as_basins():
    """Unforced basins are compared by the well each start settles in, and numbered in
    the end as `basins` numbers them (wells in increasing order)."""
    scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.5),))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 9), omega0=np.linspace(-14, 14, 9))
    acc = sweep.map_accuracy(scene, grid, maps.basins, {"dtype": ["float32", "float64"]},
                             t_end=30.0, dt=0.02, observe=("final", "energy"))
    ds = acc.dataset
    assert np.isnan(ds.differing_error.values).all()
    reference = sweep.run(scene, grid, t_end=30.0, dt=0.02, observe=("final", "energy"),
                          progress=False)
    wells = maps.well(reference).values.ravel()
    # the reference's labels number the wells in increasing order, as basins does
    found = np.unique(wells[np.isfinite(wells)])
    np.testing.assert_array_equal(ds.labels.values[-1], np.searchsorted(found, wells))


def test_forced_attractors_keep_their_number_from_run_to_run():
    """Two forced runs whose `basins` number the same attractors differently (the
    second drops most starts of the first's largest basin, so the sizes reorder): the
    shared numbering gives each start the same label in both."""
    points = sweep.sample(96, seed=5, theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))
    kwargs = dict(t_end=200 * PERIOD, dt=PERIOD / 50, t_transient=20 * PERIOD,
                  observe=("strobe",), stop_early=True, progress=False)
    first = sweep.run(WADA, points, **kwargs)
    raw = maps.basins(first).values
    keep = np.flatnonzero(raw != 0)
    keep = np.concatenate([np.flatnonzero(raw == 0)[:2], keep])
    subset = sweep.Points(theta0=points.axes["theta0"][keep],
                          omega0=points.axes["omega0"][keep])
    second = sweep.run(WADA, subset, **kwargs)
    raw_second = maps.basins(second).values
    assert not np.array_equal(raw_second, raw[keep])  # the numbering did change
    labeller = _Labeller(maps.basins, maps.basins, {}, forced=True, match_tol=1e-3)
    shared_first = labeller(first, ("point",), {})
    shared_second = labeller(second, ("point",), {})
    np.testing.assert_array_equal(shared_second, shared_first[keep])
    np.testing.assert_array_equal(shared_first, raw)  # the first run's numbering kept


def test_forced_basins_stop_on_one_pilot_catalogue_and_keep_basins_numbering():
    """The reference level of a forced map is `basins` of the run `sweep.run` makes
    with the pilot's catalogue: the same labels, in the same numbering."""
    points = sweep.sample(64, seed=7, theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))
    kwargs = dict(t_end=200 * PERIOD, t_transient=20 * PERIOD, observe=("strobe",),
                  stop_early=True)
    acc = sweep.map_accuracy(WADA, points, maps.basins,
                             {"dt": [PERIOD / 25, PERIOD / 50], "tol": [0.05, 1e-3]},
                             pilot=9, **kwargs)
    catalogue = maps.pilot_catalogue(WADA, points, 9, dt=PERIOD / 50, **kwargs)
    run = sweep.run(WADA, points, dt=PERIOD / 50, attractors=catalogue, progress=False,
                    **kwargs)
    ds = acc.dataset
    np.testing.assert_array_equal(ds.labels.values[-1], maps.basins(run).values)
    # the tol level labels the reference's run with basins(tol=0.05)
    assert list(ds.setting.values) == ["dt", "tol", "reference"]
    np.testing.assert_array_equal(ds.tol.values, [1e-3, 0.05, 1e-3])
    np.testing.assert_array_equal(ds.labels.values[1], maps.basins(run, tol=0.05).values)
    np.testing.assert_allclose(ds.fraction.sum("label").values, 1.0,
                               rtol=1e-12)  # rounding only: every start has one label


def test_a_level_at_another_drive_phase_runs_without_the_pilot_catalogue():
    """A ladder of t_transient whose first level is half a drive period off the
    reference's: the reference's pilot catalogue was sampled at another phase, where
    `sweep.run` refuses it (no start could match), so that level runs without it and
    gets the labels of a plain run; the reference keeps its catalogue."""
    points = sweep.sample(64, seed=7, theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0))
    kwargs = dict(t_end=200 * PERIOD, dt=PERIOD / 50, observe=("strobe",),
                  stop_early=True)
    acc = sweep.map_accuracy(WADA, points, maps.basins,
                             {"t_transient": [19.5 * PERIOD, 20 * PERIOD]}, pilot=9,
                             **kwargs)
    plain = sweep.run(WADA, points, t_transient=19.5 * PERIOD, progress=False, **kwargs)
    shared = _Labeller(maps.basins, maps.basins, {}, forced=True, match_tol=1e-3)
    reference = sweep.run(WADA, points, t_transient=20 * PERIOD, progress=False,
                          attractors=maps.pilot_catalogue(WADA, points, 9,
                                                           t_transient=20 * PERIOD,
                                                           **kwargs), **kwargs)
    ds = acc.dataset
    np.testing.assert_array_equal(ds.labels.values[-1], maps.basins(reference).values)
    assert (ds.labels.values[0] >= 0).all()
    first = shared(reference, ("point",), {})
    np.testing.assert_array_equal(first, ds.labels.values[-1])
    np.testing.assert_array_equal(shared(plain, ("point",), {}), ds.labels.values[0])


# ------------------------------------------------------------------------ bad inputs
POINTS = sweep.sample(8, seed=1, theta0=(-1.0, 1.0), omega0=(-1.0, 1.0))
GOOD = dict(t_end=8.0, observe=("winding",))


@pytest.mark.parametrize("args, kwargs, words", [
    ((FREE, POINTS, maps.motion, None), GOOD, "ladder must be a non-empty dict"),
    ((FREE, POINTS, maps.motion, {"step": [0.2, 0.1]}), GOOD, "unknown setting 'step'"),
    ((FREE, POINTS, maps.motion, {"dt": [0.1]}), GOOD, "at least two values"),
    ((FREE, POINTS, maps.motion, {"dt": 0.1}), GOOD, "sequence of at least two"),
    ((FREE, POINTS, maps.motion, {"dt": [0.1, 0.2]}), GOOD, "strictly decreasing"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, -0.1]}), GOOD, "ladder['dt']"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, "0.1"]}), GOOD, "ladder['dt']"),
    ((FREE, POINTS, maps.motion, {"t_end": [16.0, 8.0]}), dict(GOOD, dt=0.1),
     "strictly increasing"),
    ((FREE, POINTS, maps.motion, {"dtype": ["float16", "float64"]}), dict(GOOD, dt=0.1),
     "'float16' is not a dtype"),
    ((FREE, POINTS, maps.motion, {"method": ["rk5", "rk4"]}), dict(GOOD, dt=0.1),
     "method must be one of"),
    ((FREE, POINTS, maps.motion, {"method": ["rk4", "rk4"]}), dict(GOOD, dt=0.1),
     "repeats a value"),
    ((FREE, POINTS, maps.motion, {"tol": [1e-2, 1e-3]}), dict(GOOD, dt=0.1),
     "takes no tol"),
    ((FREE, POINTS, "nothing", {"dt": [0.2, 0.1]}), GOOD, "not a variable of this run"),
    ((FREE, POINTS, functools.partial(maps.motion, turns=2), {"dt": [0.2, 0.1]}), GOOD,
     "turns"),
    ((FREE, [0.1, 0.2], maps.motion, {"dt": [0.2, 0.1]}), GOOD, "starts must be"),
    ((object(), POINTS, maps.motion, {"dt": [0.2, 0.1]}), GOOD, "scene must be"),
    # a system: refused by name, saying what is accepted
    ((sweep.DoublePendulum(), POINTS, maps.motion, {"dt": [0.2, 0.1]}), GOOD,
     "scene must be a sweep.Scene (the single pendulum), got DoublePendulum; accepted: a "
     "sweep.Scene (map_accuracy supports the single pendulum only"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, 0.1]}), {"observe": ("winding",)},
     "needs t_end"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, 0.1]}), dict(GOOD, checkpoint="x"),
     "checkpoint"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, 0.1]}), dict(GOOD, repeats=0), "repeats"),
    ((FREE, POINTS, maps.motion, {"dt": [0.2, 0.1]}), dict(GOOD, pilot=1), "pilot"),
    # a level sweep.run would refuse (0.3 s does not divide t_end = 8 s): refused first
    ((FREE, POINTS, maps.motion, {"dt": [0.3, 0.1]}), GOOD, "dt"),
    ((FREE, POINTS, maps.motion, {"dtype": ["float32", "float64"]}),
     dict(GOOD, dt=0.1, method="dopri5"), "float32"),
])
def test_bad_inputs_are_refused_before_any_run(monkeypatch, args, kwargs, words):
    def no_run(*a, **k):
        raise AssertionError("ran before refusing")

    # map_accuracy's engine: checks as sweep.run's, but neither runs nor compiles
    checks_only = types.SimpleNamespace(prepare=engine.prepare, run=no_run, warm_up=no_run,
                                        INITIAL_AXES=engine.INITIAL_AXES)
    monkeypatch.setattr(map_precision, "engine", checks_only)
    with pytest.raises((ValueError, TypeError)) as info:
        sweep.map_accuracy(*args, **kwargs)
    assert words in str(info.value)


# ------------------------------------------------------------------------------ files
def test_save_leaves_no_half_written_file(tmp_path, monkeypatch, free_table):
    _, acc = free_table
    path = tmp_path / "acc.nc"
    path.write_bytes(b"previous")

    def fail(self, target, *a, **k):
        with open(target, "wb") as handle:
            handle.write(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", fail)
    with pytest.raises(OSError):
        acc.save(path)
    assert path.read_bytes() == b"previous"
    assert sorted(os.listdir(tmp_path)) == ["acc.nc"]


def test_save_round_trips(tmp_path, free_table):
    _, acc = free_table
    back = sweep.load(acc.save(tmp_path / "acc.nc"))
    np.testing.assert_array_equal(back.differing.values, acc.dataset.differing.values)
    assert list(back.setting.values) == list(acc.dataset.setting.values)


def test_the_figure_has_one_line_per_ladder(free_table):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, acc = free_table
    fig = sweep.plot.map_accuracy(acc)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["reference run", "dt"]
    plt.close(fig)
    with pytest.raises(ValueError, match="x must be one of"):
        sweep.plot.map_accuracy(acc, x="rhs")
    with pytest.raises(ValueError, match="accuracy must be"):
        sweep.plot.map_accuracy(xr.Dataset())


# -------------------------------------------------------------------------------- CLI
RUN_FILE = """\
[scene]
gravity = 1.0
length = 1.0

[sample]
n = 64
seed = 1
theta0 = [-3.0, 3.0]
omega0 = [-2.5, 2.5]

[run]
t_end = 32.0
dt = 0.25
observe = ["winding"]
"""


def call(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def test_cli_prints_the_table_and_writes_the_files(tmp_path):
    (tmp_path / "run.toml").write_text(RUN_FILE)
    code, out, err = call("map-accuracy", tmp_path / "run.toml", "--label", "motion",
                          "--ladder", "dt=0.5,0.25,0.125", "--ladder",
                          "dtype=float32,float64", "-o", tmp_path / "acc.nc",
                          "--figure", tmp_path / "acc.png")
    assert code == 0, err
    assert "differing" in out and "rate of differing against dt" in out
    ds = sweep.load(tmp_path / "acc.nc")
    assert list(ds.setting.values) == ["dt", "dt", "dtype", "reference"]
    assert (tmp_path / "acc.png").stat().st_size > 0


def test_cli_prints_no_column_of_nan_errors_for_a_grid(tmp_path):
    """A grid's starts have no standard error (sweep fractions prints no column of its
    NaN errors either); the netCDF file keeps the variable."""
    grid = RUN_FILE.replace("""[sample]
n = 64
seed = 1
theta0 = [-3.0, 3.0]
omega0 = [-2.5, 2.5]""", """[grid]
theta0 = {start = -3.0, stop = 3.0, num = 8}
omega0 = {start = -2.5, stop = 2.5, num = 8}""")
    assert grid != RUN_FILE
    (tmp_path / "run.toml").write_text(grid)
    code, out, err = call("map-accuracy", tmp_path / "run.toml", "--label", "motion",
                          "--ladder", "dt=0.5,0.25", "-o", tmp_path / "acc.nc")
    assert code == 0, err
    assert "a grid: no standard errors" in out and "differing" in out, out
    assert "differing_error" not in out and " NaN" not in out.split("rate of")[0], out
    assert "differing_error" in sweep.load(tmp_path / "acc.nc")
    # one level below the reference: no slope to fit, said in words (it printed nan)
    assert "rate of differing against dt: not computed (it needs two levels of dt whose " \
        "labels differ from the reference)" in out, out
    assert "nan" not in out.lower(), out


@pytest.mark.parametrize("extra, words", [
    (["--ladder", "dt"], "--ladder 'dt'"),
    (["--ladder", "step=0.2,0.1"], "KEY one of"),
    (["--ladder", "dt=0.2,fast"], "dt takes numbers"),
    (["--ladder", "dt=0.5,0.25", "--ladder", "dt=0.2,0.1"], "given twice"),
    (["--ladder", "dt=0.25,0.5"], "strictly decreasing"),
    (["--ladder", "dt=0.5,0.25", "--label", "nothing"], "not a variable"),
    (["--ladder", "dt=0.5,0.25", "--repeats", "0"], "repeats"),
    (["--ladder", "dt=0.5,0.25", "--figure", "{tmp}/acc.xyz"], "unknown image format"),
    (["--ladder", "dt=0.5,0.25", "-o", "{tmp}/missing/acc.nc"], "does not exist"),
])
def test_cli_errors_are_one_line_and_write_nothing(tmp_path, extra, words):
    (tmp_path / "run.toml").write_text(RUN_FILE)
    extra = [e.format(tmp=tmp_path) for e in extra]
    code, out, err = call("map-accuracy", tmp_path / "run.toml", "--label", "motion",
                          "-o", tmp_path / "acc.nc", *extra)
    assert code == cli.EXIT_ERROR and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sweep: error:") and words in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]


@pytest.mark.parametrize("example, kind", [
    ("driven_double_pendulum_basins.toml", "DoublePendulum"),
    ("pendulum_on_cart.toml", "DeclaredSystem"),
])
def test_cli_refuses_a_system_run_file_in_one_line(tmp_path, no_compute, example, kind):
    """A shipped ``[system]`` run file: one line that says map-accuracy takes
    single-pendulum run files only and what is accepted (it said only "scene must be a
    sweep.Scene, got DoublePendulum"), before anything is compiled or run."""
    run_file = os.path.join(os.path.dirname(__file__), "..", "examples", example)
    code, out, err = call("map-accuracy", run_file, "--ladder", "dt=0.01,0.005",
                          "-o", tmp_path / "acc.nc")
    assert code == cli.EXIT_ERROR and out == ""
    assert err == (f"sweep: error: sweep map-accuracy supports single-pendulum run files "
                   f"only; {run_file!r} has a [system] table ({kind}); accepted: a run file "
                   "with a [scene] table, or with neither (the default pendulum)\n")
    assert list(tmp_path.iterdir()) == []


def test_cli_a_failed_write_is_one_line_and_leaves_no_file(tmp_path, monkeypatch):
    (tmp_path / "run.toml").write_text(RUN_FILE)

    def fail(self, target, *a, **k):
        with open(target, "wb") as handle:
            handle.write(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", fail)
    code, _, err = call("map-accuracy", tmp_path / "run.toml", "--label", "motion",
                          "--ladder", "dt=0.5,0.25", "-o", tmp_path / "acc.nc")
    lines = err.strip().splitlines()
    assert code == cli.EXIT_ERROR
    assert len(lines) == 1 and lines[0].startswith("sweep: error:") and "acc.nc" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]
