"""Run files and the command line for systems of several coordinates: ``[system]`` in
place of ``[scene]`` (`sweep.toml_spec`), the same `sweep run` and `sweep plot`."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from test_cli import assert_png, call, write

import sweep
from sweep.toml_spec import load_run, parse_run

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "double_pendulum.toml"
BASINS = EXAMPLE.with_name("driven_double_pendulum_basins.toml")

RUN_FILE = """\
[system]
kind = "DoublePendulum"
mass2 = 0.5
[system.damping]
coefficient = 0.05

[grid]
theta1_0 = {start = -170, stop = 170, num = 5, units = "deg"}
omega2_0 = {values = [0, 90], units = "deg/s"}

[run]
t_end = 2.0
dt = 0.01
observe = ["final", "flip"]
"""


def test_sweep_run_writes_the_dataset_the_api_makes(tmp_path):
    output = tmp_path / "out.nc"
    code, out, err = call("run", write(tmp_path, RUN_FILE), "-o", output, "--no-progress")
    assert (code, err) == (0, ""), err
    assert "10 trajectories" in out
    ds = sweep.load(output)
    assert set(ds.data_vars) == {"theta1_final", "theta2_final", "omega1_final",
                                 "omega2_final", "flip_time", "status"}
    np.testing.assert_allclose(ds.theta1_0, np.deg2rad(np.linspace(-170, 170, 5)))
    np.testing.assert_allclose(ds.omega2_0, [0.0, math.pi / 2])  # deg/s -> rad/s
    system = sweep.DoublePendulum(mass2=0.5, effects=(sweep.Damping(0.05),))
    expected = sweep.run(system, sweep.Grid(theta1_0=ds.theta1_0.values,
                                            omega2_0=ds.omega2_0.values),
                         t_end=2.0, dt=0.01, observe=("final", "flip"))
    for name in expected.data_vars:
        np.testing.assert_array_equal(ds[name].values, expected[name].values)
    image = tmp_path / "flip.png"
    code, _, err = call("plot", output, "--var", "theta2_final", "-o", image)
    assert (code, err) == (0, "")
    assert image.stat().st_size > 1000


def test_the_shipped_example_parses_to_the_flip_map():
    system, grid, kwargs = load_run(EXAMPLE)
    assert system == sweep.DoublePendulum()
    assert grid.dims == ("theta1_0", "theta2_0") and grid.shape == (201, 201)
    assert kwargs["observe"] == ("flip",) and kwargs["stop_early"] is True
    # 100 steps per natural time unit sqrt(l/g) = 0.319 s: dt resolves the motion
    assert kwargs["dt"] * math.sqrt(9.81 / 1.0) < 0.011


def test_a_swing_network_from_a_run_file():
    spec = {"system": {"kind": "SwingNetwork", "edges": [[0, 1], [1, 2], [2, 0]],
                       "power": [1.0, -0.5, -0.5], "coupling": 5.0},
            "grid": {"perturbed_node": [0, 2], "delta_theta": [0.1, 3.0]},
            "run": {"t_end": 1.0, "dt": 0.01}}
    network, grid, kwargs = parse_run(spec)
    assert network == sweep.SwingNetwork([(0, 1), (1, 2), (2, 0)], power=[1, -0.5, -0.5],
                                         coupling=5.0)
    ds = sweep.run(network, grid, **kwargs)
    assert "frequency_spread" in ds and ds.frequency_spread.shape == (2, 2)


@pytest.mark.parametrize("change, match", [
    ({"scene": {}}, r"both \[scene\] and \[system\]"),
    ({"system": {"kind": "TriplePendulum"}}, r"\[system\] kind = 'TriplePendulum'; "
                                             r"accepted: 'DoublePendulum'"),
    ({"system": {"kind": "DoublePendulum", "lenght1": 1.0}},
     r"\[system\] unknown key 'lenght1'; accepted for DoublePendulum"),
    ({"system": {"kind": "DoublePendulum", "damping": 0.1}},
     r"damping must be a table \[system.damping\]"),
    ({"system": {"kind": "DoublePendulum", "mass1": -1.0}}, r"\[system\] mass1"),
    ({"grid": {"theta0": [0.1]}}, r"unknown key 'theta0' in \[grid\]; accepted: theta1_0"),
    ({"run": {"t_end": 1.0, "dt": 0.1, "observe": ["amplitude"]}},
     r"\[run\] unknown observable 'amplitude' for a system"),
    ({"run": {"t_end": 1.0, "dt": 0.1, "pilot": 11}},
     r"\[run\] pilot = 11 catalogues the attractors of a driven system .* this "
     r"DoublePendulum has no periodic drive"),
    ({"run": {"t_end": 1.0, "dt": 0.1, "refine": True}}, r"\[run\] refine is for the single "),
    ({"system": {"kind": "SwingNetwork", "power": [1, -1]}}, r"needs edges"),
])
def test_bad_system_run_files_are_refused_naming_the_table(change, match):
    spec = {"system": {"kind": "DoublePendulum"}, "grid": {"theta1_0": [0.1, 0.2]},
            "run": {"t_end": 1.0, "dt": 0.1}}
    spec.update(change)
    with pytest.raises((ValueError, TypeError), match=match):
        parse_run(spec, source="run.toml")


@pytest.fixture(scope="module")
def basins_file(tmp_path_factory):
    """``sweep run examples/driven_double_pendulum_basins.toml``: (exit status, stdout,
    stderr, the output file)."""
    output = tmp_path_factory.mktemp("basins") / "basins.nc"
    code, out, err = call("run", BASINS, "-o", output, "--no-progress")
    return code, out, err, output


def test_the_driven_example_writes_its_basins_by_a_pilot_catalogue(tmp_path, basins_file):
    """``examples/driven_double_pendulum_basins.toml`` (``[run] pilot = 12``, observe
    ``attractor``, ``stop_early``): `sweep run` writes the dataset that the Python route
    gives (`sweep.maps.pilot_catalogue` of the system, then `sweep.run` with it), bit for
    bit, the catalogue in its attributes, and `sweep plot --var attractor` draws the map.
    Its system, pilot and settings are tests/test_system_attractors.py's (the same
    kernels): the pilot finds that test's five attractors, and every start follows one."""
    code, out, err, output = basins_file
    assert (code, err) == (0, ""), err
    assert "1600 trajectories (theta1_0 40 x theta2_0 40)" in out
    ds = sweep.load(output)
    assert set(ds.data_vars) == {"attractor", "status"}
    options = {}
    system, grid, kwargs = load_run(BASINS, options)
    assert system == sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=60.0,
                                          effects=(sweep.Damping(0.5),))
    assert options == {"pilot": 12} and kwargs["stop_early"] is True
    catalogue = sweep.maps.pilot_catalogue(system, grid, 12, **kwargs)
    expected = sweep.run(system, grid, attractors=catalogue, progress=False, **kwargs)
    assert ds["attractor"].values.tobytes() == expected["attractor"].values.tobytes()
    np.testing.assert_array_equal(ds.attrs["attractors_theta"],
                                  expected.attrs["attractors_theta"])
    assert sorted(ds.attrs["attractors_period"].tolist()) == [1, 1, 1, 1, 4]
    assert (ds["attractor"].values >= 0).all()
    image = tmp_path / "basins.png"
    code, _, err = call("plot", output, "--var", "attractor", "-o", image)
    assert (code, err) == (0, "")
    assert_png(image)


def test_sweep_run_says_the_pilots_size_time_and_attractors(basins_file):
    """With ``[run] pilot = 12`` the summary has the pilot's line before the map's: its
    12 x 12 starts, its wall time and the five attractors it catalogued (the count the
    test above checks in the file)."""
    code, out, err, _ = basins_file
    assert (code, err) == (0, ""), err
    lines = out.splitlines()
    assert re.fullmatch(r"pilot: 144 trajectories \(theta1_0 12 x theta2_0 12\) in "
                        r"\d+\.\d\d s wall time, 5 attractors catalogued", lines[-2]), out
    assert lines[-1].startswith("wrote ") and "1600 trajectories" in lines[-1]


def test_the_attractor_maps_colour_bar_has_a_short_label_and_the_file_the_detail(
        basins_file):
    """The ``attractor`` variable's ``long_name`` is a short label, which the colour bar
    of its map shows (it was a 270-character paragraph, wrapped over many lines); what
    the index means in full is the variable's CF ``comment``."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot

    code, _, err, output = basins_file
    assert (code, err) == (0, ""), err
    ds = sweep.load(output)
    attrs = ds["attractor"].attrs
    assert attrs["long_name"] == "index of the attractor settled on (-1: none)"
    assert "attractors_*" in attrs["comment"] and "ATTRACTOR_MATCHES" in attrs["comment"]
    fig = sweep.plot.map(ds["attractor"])
    try:
        bar = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
        assert len(bar) == 1
        assert bar[0].get_ylabel() == "index of the attractor settled on (-1: none)"
    finally:
        pyplot.close(fig)


DRIVEN = """\
[system]
kind = "DoublePendulum"
pivot_amplitude = 0.1
pivot_frequency = 60.0
[system.damping]
coefficient = 0.5

[grid]
theta1_0 = [0.5, 1.0]
theta2_0 = [0.5, 1.0]

[run]
t_end = 1.0471975511965976
dt = 0.002617993877991494
observe = ["attractor"]
stop_early = true
pilot = 2
"""


@pytest.mark.parametrize("old, new, argv, match", [
    ("pivot_amplitude = 0.1\npivot_frequency = 60.0\n", "", [],
     r"\[run\] pilot = 2 catalogues the attractors of a driven system \(its orbits sampled "
     r"once per drive period\), and this DoublePendulum has no periodic drive; accepted: a "
     r"driven \[system\]"),
    ('observe = ["attractor"]', 'observe = ["final"]', [],
     r"\[run\] pilot = 2 makes an attractor catalogue that labels each start in observe "
     r"'attractor', and observe is \['final'\]; accepted: observe = \[\"attractor\"\]"),
    ("pilot = 2\n", "", [], r"\[run\] observe 'attractor' labels each start by an attractor "
                           r"catalogue, which a run file makes by a pilot; accepted: pilot = N"),
    ("theta2_0 = [0.5, 1.0]", "pivot_amplitude = [0.1, 0.2]", [],
     r"the grid varies pivot_amplitude; accepted: a grid that varies only the initial state"),
    ("pilot = 2\n", "pilot = 1\n", [], r"\[run\] pilot must be an int >= 2"),
    ('observe = ["attractor"]', 'observe = ["final", "attractor"]', [],
     r"stop_early stops a system's trajectory at its first flip"),
    ("", "", ["--pilot", "1"], r"pilot must be an int >= 2"),
    # the drive off (pivot_frequency = 0): the message says what would be accepted
    ("pivot_frequency = 60.0", "pivot_frequency = 0.0", [],
     r"\[run\] observable 'attractor' samples once per drive period 2 pi / pivot_frequency "
     r"and needs pivot_frequency > 0, got 0\.0; accepted: pivot_frequency > 0 rad/s"),
    ('observe = ["attractor"]\nstop_early = true\npilot = 2\n', "", ["--pilot", "5"],
     r"^sweep: error: pilot = 5 makes an attractor catalogue .* and observe is "
     r"\['final', 'winding'\]"),
])
def test_a_pilot_a_driven_system_cannot_use_is_one_line_before_any_compute(
        tmp_path, monkeypatch, old, new, argv, match):
    """A ``[system]`` run file's pilot (or ``--pilot N``) that cannot catalogue the map's
    attractors, and ``observe = ["attractor"]`` without one: one line, exit status 2, no
    output file, and nothing run (the systems' runner is replaced by one that fails)."""
    import re

    import sweep.engine_systems

    def computed(*args, **kwargs):
        raise AssertionError("a system run started")

    monkeypatch.setattr(sweep.engine_systems, "run_system", computed)
    output = tmp_path / "out.nc"
    assert old in DRIVEN
    code, out, err = call("run", write(tmp_path, DRIVEN.replace(old, new, 1)), "-o", output,
                          "--no-progress", *argv)
    assert code == 2 and out == ""
    assert err.startswith("sweep: error: ") and err.count("\n") == 1, err
    assert re.search(match, err), err
    assert not output.exists()


def test_a_sample_of_a_driven_system_takes_a_pilot_and_gives_fractions(tmp_path):
    """The driven example with ``[sample]`` in place of ``[grid]`` (basin stability): the
    pilot is a 12 x 12 grid of the sample's box (`sweep.maps.pilot_grid` of points), the
    sample's starts are labelled as the Python route labels them, and `sweep fractions
    --label attractor` gives each basin's share with its standard error."""
    text = BASINS.read_text()
    start, stop = text.index("[grid]"), text.index("[run]")
    sample = ("[sample]\nn = 300\nseed = 1\ntheta1_0 = [-3.0, 3.0]\n"
              "theta2_0 = [-3.0, 3.0]\n\n")
    run_file = write(tmp_path, text[:start] + sample + text[stop:])
    output = tmp_path / "sample.nc"
    code, out, err = call("run", run_file, "-o", output, "--no-progress")
    assert (code, err) == (0, ""), err
    system, points, kwargs = load_run(run_file)
    expected = sweep.run(system, points, progress=False, **kwargs,
                         attractors=sweep.maps.pilot_catalogue(system, points, 12, **kwargs))
    ds = sweep.load(output)
    assert ds["attractor"].values.tobytes() == expected["attractor"].values.tobytes()
    code, out, err = call("fractions", output, "--label", "attractor")
    assert (code, err) == (0, ""), err
    assert "300 trajectories, attractor" in out and "standard_error" in out
    # the default label (basins) needs stroboscopic samples, which a run on a catalogue
    # does not keep: the error names its labels, 'attractor' (it asked for a pivot
    # drive, which the run has)
    code, out, err = call("fractions", output)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "it was run on an attractor catalogue" in err and "pivot_amplitude" not in err
    assert err.endswith(f"labels that work on {str(output)!r}: --label attractor\n"), err
    # the attractor indices are whole floats: printed as integers, 0 not 0.0
    rows = [line.split()[0] for line in call("fractions", output, "--label",
                                             "attractor")[1].splitlines()[3:]]
    assert rows and all(row.isdigit() or row == "nan" for row in rows), rows
