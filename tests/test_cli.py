"""The ``sweep`` command and its run files: run, demo, plot; one-line errors.

Commands are called in-process through `sweep.cli.main` (fast); one test runs
``python -m sweep`` in a subprocess to see what a user sees on a failure.
"""

import contextlib
import io
import os
import subprocess
import sys
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

import sweep
from sweep import cli
from sweep.toml_spec import load_run, parse_run

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "forced.toml"

# Same kernel as the demo (nonlinear, damping, final + winding + energy): one compile.
RUN_FILE = """\
[scene]
gravity = 9.81
length = 1.0
model = "nonlinear"

[scene.damping]
coefficient = 0.3

[grid]
theta0 = {start = -180, stop = 180, num = 5, units = "deg"}
omega0 = [-1.0, 0.0, 1.0]

[run]
t_end = 2.0
dt = 0.05
observe = ["final", "winding", "energy"]
"""

TRAJECTORY_FILE = RUN_FILE.replace("[run]\n", "[run]\nsave_every = 4\n")


def write(folder: Path, text: str, name: str = "run.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def call(*argv) -> tuple[int, str, str]:
    """Run ``sweep ARGV`` in-process; return (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def assert_png(path: Path, min_pixels: int = 100) -> None:
    assert path.read_bytes()[:8] == PNG_MAGIC
    image = matplotlib.image.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    assert min(image.shape[:2]) >= min_pixels


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """``sweep demo --size 21`` run once: (folder, stdout)."""
    folder = tmp_path_factory.mktemp("demo") / "out"
    code, out, err = call("demo", "-o", folder, "--size", 21, "--no-progress")
    assert code == 0, err
    return folder, out


@pytest.fixture(scope="module")
def trajectory_file(tmp_path_factory):
    """A netCDF file with sampled trajectories (a ``time`` dimension)."""
    folder = tmp_path_factory.mktemp("trajectory")
    path = folder / "trajectory.nc"
    code, _, err = call("run", write(folder, TRAJECTORY_FILE), "-o", path, "--no-progress")
    assert code == 0, err
    return path


# ----------------------------------------------------------------------------- run
def test_run_writes_the_dataset_the_api_makes(tmp_path):
    output = tmp_path / "out.nc"
    code, out, err = call("run", write(tmp_path, RUN_FILE), "-o", output, "--no-progress")
    assert (code, err) == (0, "")
    assert out.count("\n") == 1
    assert str(output) in out and "15 trajectories" in out and "0 non-finite" in out

    ds = sweep.load(output)
    assert dict(ds.sizes) == {"theta0": 5, "omega0": 3}
    assert list(ds.dims) == ["theta0", "omega0"]
    assert set(ds.data_vars) == {"theta_final", "omega_final", "winding", "energy_initial",
                                 "energy_final", "status"}
    np.testing.assert_allclose(ds.theta0, np.deg2rad(np.linspace(-180, 180, 5)))
    assert ds.theta0.attrs["units"] == "rad" and ds.omega0.attrs["units"] == "rad s-1"
    assert ds.attrs["dt"] == 0.05 and ds.attrs["t_end"] == 2.0
    assert ds.attrs["effects"] == "damping" and ds.attrs["model"] == "nonlinear"
    assert sweep.io.scene_from(ds) == sweep.Scene(effects=(sweep.Damping(0.3),))

    scene, grid, kwargs = load_run(tmp_path / "run.toml")
    expected = sweep.run(scene, grid, **kwargs)
    for name in expected.data_vars:
        np.testing.assert_array_equal(ds[name].values, expected[name].values)


# ---------------------------------------------------------------------------- demo
def test_demo_writes_the_dataset_and_two_maps(demo):
    folder, out = demo
    written = {"demo.nc", "well.png", "capture_time.png"}
    assert {p.name for p in folder.iterdir()} == written
    for name in written:
        assert str(folder / name) in out
    assert_png(folder / "well.png")
    assert_png(folder / "capture_time.png")

    ds = sweep.load(folder / "demo.nc")
    assert dict(ds.sizes) == {"theta0": 21, "omega0": 21}
    assert float(ds.theta0.min()) == pytest.approx(-np.pi)
    assert float(ds.theta0.max()) == pytest.approx(np.pi)
    assert float(ds.omega0.max()) == pytest.approx(10.0)
    assert {"theta_final", "winding", "energy_final", "well", "capture_time"} <= set(
        ds.data_vars)
    assert ds.attrs["effects"] == "damping" and "forcing" not in ds.attrs["scene"]
    # every trajectory is captured in a well (except those started exactly at the
    # upright equilibrium theta0 = +-pi, omega0 = 0, on the separatrix: never below
    # it, so no well and no capture time), and some made several turns first
    upright = (abs(abs(ds.theta0) - np.pi) < 1e-12) & (ds.omega0 == 0)
    assert float(ds.energy_final.where(~upright).max()) < 2 * 9.81
    assert bool(ds.well.where(upright).isnull().all())
    assert bool(ds.capture_time.where(upright).isnull().all())
    # once captured (energy below 2 g/L, decreasing under damping) the pendulum stays
    # in that well: the captured well is the final one, exactly
    np.testing.assert_array_equal(ds.well.where(~upright),
                                  np.round(ds.theta_final / (2 * np.pi)).where(~upright))
    assert int(abs(ds.winding).max()) >= 2
    # the two maps differ: more turns before capture take longer (starts with the
    # most turns are captured last), which the well map cannot show
    captured = ds.capture_time.where(~upright)
    assert float(captured.where(abs(ds.winding) >= 2).min()) > float(
        captured.where(ds.winding == 0).min())
    assert float(captured.max()) < 40.0  # all captured within t_end


def test_demo_refuses_a_bad_size_before_creating_anything(tmp_path):
    folder = tmp_path / "never"
    code, out, err = call("demo", "-o", folder, "--size", 1)
    assert code == 2 and out == ""
    assert err.startswith("sweep: error: --size") and err.count("\n") == 1
    assert not folder.exists()


def test_demo_refuses_a_grid_too_large_before_creating_its_folder(tmp_path, monkeypatch,
                                                                 no_compute):
    monkeypatch.setattr(sweep.engine, "_available_memory", lambda: 2**20)  # 1 MiB
    folder = tmp_path / "never" / "demo"
    code, out, err = call("demo", "-o", folder, "--size", 200)
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith("sweep: error: --size 200: a grid of 40000 trajectories needs")
    assert not (tmp_path / "never").exists()


@pytest.mark.parametrize("existing", [False, True], ids=["new folder", "folder exists"])
def test_demo_that_fails_later_removes_only_the_folders_it_made(existing, tmp_path,
                                                                monkeypatch):
    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(cli, "_run_quietly", full)
    folder = tmp_path / "a" / "b"
    if existing:
        folder.mkdir(parents=True)
    code, out, err = call("demo", "-o", folder, "--size", 2)
    assert (code, out) == (2, "") and "No space left on device" in err, err
    assert folder.is_dir() == existing and (tmp_path / "a").is_dir() == existing


def test_demo_help_names_the_maps_it_draws():
    code, out, _ = call("demo", "--help")
    text = " ".join(out.split())
    assert code == 0 and "well.png" in text and "capture_time.png" in text, text
    assert "passes over the top" not in text


# ---------------------------------------------------------------------------- plot
def test_plot_draws_a_map_of_a_variable(demo, tmp_path):
    folder, _ = demo
    for name in ("winding", "capture_time", "status"):
        output = tmp_path / f"{name}.png"
        code, _out, err = call("plot", folder / "demo.nc", "--var", name, "-o", output)
        assert (code, err) == (0, ""), name
        assert_png(output)


def test_plot_selects_down_to_two_dimensions(trajectory_file, tmp_path):
    output = tmp_path / "theta.png"
    code, _, err = call("plot", trajectory_file, "--var", "theta", "--sel", "time=1.0",
                        "-o", output, "--radians")
    assert (code, err) == (0, "")
    assert_png(output)


def test_plot_draws_a_trajectory(trajectory_file, tmp_path):
    output = tmp_path / "trajectory.png"
    code, out, err = call("plot", trajectory_file, "--trajectory", "--sel", "theta0=-90deg",
                          "--sel", "omega0=1", "-o", output)
    assert (code, err) == (0, "")
    assert out.strip() == f"wrote {output}"
    assert_png(output)


def test_version():
    code, out, _ = call("--version")
    assert code == 0 and out.strip() == f"sweep {sweep.__version__}"


def test_usage_errors_are_one_line_not_argparses_usage_block():
    code, out, err = call("run")
    assert (code, out) == (2, "")
    assert err == ("sweep: error: sweep run: the following arguments are required: "
                   "RUN.toml, -o/--output\n")


# -------------------------------------------------------------------------- errors
def _bad_run(text):
    def make(folder):
        return ["run", write(folder, text), "-o", folder / "out.nc"]
    return make


ERROR_CASES = {
    "missing file": (lambda d: ["run", d / "missing.toml", "-o", d / "out.nc"],
                     "missing.toml"),
    "malformed TOML": (_bad_run("[grid\ntheta0 = 1\n"), "not valid TOML"),
    "unknown [run] key": (_bad_run(RUN_FILE.replace("dt =", "dtt =")), "'dtt' in [run]"),
    "unknown [scene] key": (_bad_run(RUN_FILE.replace("gravity", "gravty")), "gravty"),
    "unknown range key": (_bad_run(RUN_FILE.replace("units", "unit")), "'unit'"),
    "negative dt": (_bad_run(RUN_FILE.replace("dt = 0.05", "dt = -1")), "dt must be"),
    "missing output folder": (lambda d: ["run", write(d, RUN_FILE), "-o",
                                         d / "nowhere" / "out.nc"], "nowhere"),
    "unknown variable": (lambda d: ["plot", d / "data.nc", "--var", "nope", "-o",
                                    d / "out.png"], "--var 'nope'"),
    "bad selection": (lambda d: ["plot", d / "data.nc", "--var", "winding", "--sel",
                                 "theta0", "-o", d / "out.png"], "--sel"),
    "selection given twice": (lambda d: ["plot", d / "data.nc", "--var", "winding", "--sel",
                                         "theta0=1", "--sel", "theta0=2", "-o",
                                         d / "out.png"], "--sel theta0 given twice"),
    "trajectory without time": (lambda d: ["plot", d / "data.nc", "--trajectory", "-o",
                                           d / "out.png"], "time"),
    "not a netCDF file": (lambda d: ["plot", write(d, RUN_FILE), "--var", "winding", "-o",
                                     d / "out.png"], "netCDF"),
    # a value that is not on the axis (its nearest value used to be drawn, silently)
    "selection off the axis": (lambda d: ["plot", d / "data.nc", "--var", "winding", "--sel",
                                          "theta0=99", "-o", d / "out.png"],
                               "--sel theta0=99: 99 is not a value of the axis theta0; "
                               "accepted: one of its 21 values from -3.14159 to 3.14159 rad"),
    "selection between two values": (lambda d: ["plot", d / "data.nc", "--var", "winding",
                                                "--sel", "omega0=0.1", "-o", d / "out.png"],
                                     "--sel omega0=0.1: 0.1 is not a value of the axis "
                                     "omega0"),
}


@pytest.mark.parametrize("case", list(ERROR_CASES))
def test_errors_are_one_line_with_status_2_and_write_nothing(case, demo, tmp_path):
    make, expected = ERROR_CASES[case]
    (tmp_path / "data.nc").write_bytes((demo[0] / "demo.nc").read_bytes())
    argv = make(tmp_path)
    code, out, err = call(*argv)
    assert code == 2, err
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("sweep: error: "), err
    assert expected in err
    assert "Traceback" not in err
    output = Path(argv[argv.index("-o") + 1])
    assert not output.exists()
    assert not [p for p in output.parent.glob("*.part")] if output.parent.exists() else True


def test_a_one_value_axis_is_selected_by_the_digits_its_refusal_prints(tmp_path):
    """A grid's axis of one value (damping = 0.123456789 1/s): the refusal of another
    value prints it with 6 digits (0.123457), and those 6 digits select it (they were
    refused in turn: within 1e-9 of the value only)."""
    path = tmp_path / "one.nc"
    text = RUN_FILE.replace("[grid]\n", "[grid]\ndamping = [0.123456789]\n")
    code, _, err = call("run", write(tmp_path, text), "-o", path, "--no-progress")
    assert code == 0, err
    code, _, err = call("plot", path, "--var", "winding", "--sel", "damping=0.2", "-o",
                        tmp_path / "off.png")
    assert code == 2 and "accepted: one of 0.123457 " in err, err
    output = tmp_path / "map.png"
    code, _, err = call("plot", path, "--var", "winding", "--sel", "damping=0.123457",
                        "-o", output)
    assert (code, err) == (0, ""), err
    assert_png(output)


def test_a_selection_within_a_small_fraction_of_the_spacing_is_that_value(trajectory_file,
                                                                         tmp_path):
    # time of the file: samples 0.2 s apart; 1.001 s is 0.5 % of that from the sample
    # 1.0 s, within SELECTION_TOLERANCE (1 %), as a value typed with fewer digits; 1.003 s
    # (1.5 %) is not
    output = tmp_path / "theta.png"
    code, _, err = call("plot", trajectory_file, "--var", "theta", "--sel", "time=1.001",
                        "-o", output)
    assert (code, err) == (0, "")
    assert_png(output)
    code, _, err = call("plot", trajectory_file, "--var", "theta", "--sel", "time=1.003",
                        "-o", tmp_path / "off.png")
    assert code == 2 and "--sel time=1.003: 1.003 is not a value of the axis time" in err
    assert not (tmp_path / "off.png").exists()


def test_a_closed_stdout_ends_quietly_with_141(demo):
    # the reader is gone before sweep writes (``| head`` that has read what it needed):
    # no "Broken pipe" line, and 128 + SIGPIPE, as a shell reports for cat or yes
    read, write_end = os.pipe()
    os.close(read)
    try:
        result = subprocess.run([sys.executable, "-m", "sweep", "fractions",
                                 str(demo[0] / "demo.nc"), "--label", "well"],
                                stdout=write_end, stderr=subprocess.PIPE, text=True,
                                timeout=120, check=False)
    finally:
        os.close(write_end)
    assert (result.returncode, result.stderr) == (141, "")


def test_resume_without_a_checkpoint_says_it_starts_from_the_beginning(tmp_path):
    output = tmp_path / "out.nc"
    code, out, err = call("run", write(tmp_path, RUN_FILE), "-o", output, "--resume",
                          "--no-progress")
    assert code == 0 and out.startswith(f"wrote {output}")
    assert err == (f"sweep: note: --resume: no checkpoint in '{output}.checkpoint'; the run "
                   "starts from the beginning\n")


def test_explore_on_an_address_of_another_machine_says_change_the_host():
    pytest.importorskip("panel")
    # 192.0.2.1: TEST-NET-1 (RFC 5737), never an address of this machine; --port 0 given
    code, out, err = call("explore", "--no-browser", "--port", 0, "--host", "192.0.2.1")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith("sweep: error: cannot listen on address 192.0.2.1, port 0 (a free "
                          "port)"), err
    assert err.rstrip().endswith("accepted: --host an address of this machine (127.0.0.1, "
                                 "the default; 0.0.0.0 for all of its addresses)"), err
    assert "picks a free port" not in err and "(chosen)" not in err


def test_python_dash_m_shows_one_line_and_no_traceback(tmp_path):
    output = tmp_path / "out.nc"
    bad = write(tmp_path, RUN_FILE.replace("dt = 0.05", "dt = -1"))
    result = subprocess.run([sys.executable, "-m", "sweep", "run", str(bad), "-o", str(output)],
                            capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sweep: error: ")
    assert "dt" in lines[0] and "Traceback" not in result.stderr
    assert not output.exists()


# ----------------------------------------------------------------------- run files
def test_the_example_run_file_parses():
    scene, grid, kwargs = load_run(EXAMPLE)
    assert scene.damping == sweep.Damping(0.5)
    assert scene.forcing.amplitude == 1.35
    assert scene.forcing.frequency == pytest.approx(2 / 3)
    assert scene.gravity / scene.length == 1.0
    assert grid.dims == ("theta0", "omega0") and grid.shape == (181, 181)
    np.testing.assert_allclose(grid.axes["theta0"][[0, -1]], [-np.pi, np.pi])
    np.testing.assert_allclose(grid.axes["omega0"][[0, -1]], [-np.pi, np.pi])
    # whole forcing periods, 2 pi / (2/3) = 3 pi s, written as these floats' repr
    period = 3 * np.pi
    assert kwargs == {"t0": 0.0, "t_end": 26 * period, "dt": period / 1000,
                      "t_transient": 10 * period,
                      "observe": ("final", "winding", "amplitude", "theta_max")}


def test_grid_axes_accept_lists_numbers_ranges_and_degrees():
    spec = {
        "scene": {"forcing": {"amplitude": 1.0, "frequency": 1.0}},
        "grid": {
            "omega0": {"values": [0, 90], "units": "deg/s"},
            "theta0": {"start": 0.0, "stop": 1.0, "num": 3},
            "forcing_phase": {"start": 0, "stop": 180, "num": 2, "units": "deg"},
            "damping": 0.5,
            "length": [1, 2],
        },
        "run": {"t_end": 1, "dt": 0.5, "observe": "final", "save_every": 2},
    }
    _scene, grid, kwargs = parse_run(spec)
    assert grid.dims == ("omega0", "theta0", "forcing_phase", "damping", "length")
    axes = grid.axes
    np.testing.assert_allclose(axes["omega0"], [0.0, np.pi / 2])
    np.testing.assert_allclose(axes["theta0"], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(axes["forcing_phase"], [0.0, np.pi])
    np.testing.assert_allclose(axes["damping"], [0.5])
    np.testing.assert_allclose(axes["length"], [1.0, 2.0])
    assert kwargs == {"t_end": 1, "dt": 0.5, "observe": ("final",), "save_every": 2}


def test_scene_table_round_trips_through_to_dict():
    scene = sweep.Scene(gravity=3.7, length=0.5, model="linear",
                        effects=(sweep.Damping(0.1), sweep.Forcing(2.0, 1.5, 0.25)))
    parsed, _, _ = parse_run({"scene": scene.to_dict(), "grid": {"theta0": 0.1},
                              "run": {"t_end": 1.0, "dt": 0.1}})
    assert parsed == scene


GOOD = {"grid": {"theta0": [0.1]}, "run": {"t_end": 1.0, "dt": 0.1}}


def _with(table, key, value):
    spec = {name: dict(content) for name, content in GOOD.items()}
    spec.setdefault(table, {})[key] = value
    return spec


@pytest.mark.parametrize("spec, words", [
    ({**GOOD, "runs": {}}, ["'runs'", "top level", "scene, grid, run"]),
    ({"grid": GOOD["grid"]}, ["[run]"]),
    ({"run": GOOD["run"]}, ["[grid]"]),
    ({"grid": {}, "run": GOOD["run"]}, ["[grid]", "theta0"]),
    ({"grid": GOOD["grid"], "run": {"t_end": 1.0}}, ["'dt'", "[run]"]),
    (_with("run", "tend", 1.0), ["'tend'", "[run]", "t_end, dt"]),
    (_with("grid", "theta", [1.0]), ["'theta'", "[grid]", "theta0, omega0"]),
    (_with("grid", "theta0", {"start": 0, "stop": 1}), ["'num'", "theta0"]),
    (_with("grid", "theta0", {"start": 0, "stop": 1, "num": 0}), ["num", ">= 1"]),
    (_with("grid", "theta0", {"values": [1], "num": 2}), ["values", "num"]),
    (_with("grid", "theta0", {"values": [1], "units": "grad"}), ["units", "'deg'"]),
    (_with("grid", "damping", {"values": [1], "units": "deg"}), ["'units'", "[grid.damping]"]),
    (_with("grid", "theta0", True), ["theta0"]),
    (_with("grid", "theta0", [0.0, "x"]), ["theta0[1]"]),
    (_with("grid", "forcing_amplitude", [1.0]), ["forcing_amplitude", "Forcing"]),
    (_with("run", "observe", ["final", "speed"]), ["'speed'", "observe"]),
    (_with("run", "save_every", 0), ["save_every"]),
    (_with("run", "t_transient", 5.0), ["t_transient"]),
    (_with("scene", "damping", {"coefficient": -1.0}), ["Damping.coefficient"]),
    (_with("scene", "forcing", {"amplitude": 1.0}), ["frequency"]),
])
def test_run_file_errors_name_the_key(spec, words):
    with pytest.raises((ValueError, TypeError)) as info:
        parse_run(spec, source="test.toml")
    message = str(info.value)
    assert message.startswith("test.toml: ")
    for word in words:
        assert word in message


def test_unreadable_and_malformed_files_name_the_file(tmp_path):
    with pytest.raises(ValueError, match=r"missing\.toml"):
        load_run(tmp_path / "missing.toml")
    with pytest.raises(ValueError, match=r"bad\.toml.*not valid TOML.*line 2"):
        load_run(write(tmp_path, "[grid]\ntheta0 = = 1\n", "bad.toml"))
    with pytest.raises(ValueError, match="cannot read run file"):
        load_run(tmp_path)
