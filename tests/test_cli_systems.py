"""Run files and the command line for systems of several coordinates: ``[system]`` in
place of ``[scene]`` (`sweep.toml_spec`), the same `sweep run` and `sweep plot`."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from test_cli import call, write

import sweep
from sweep.toml_spec import load_run, parse_run

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "double_pendulum.toml"

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
    ({"run": {"t_end": 1.0, "dt": 0.1, "pilot": 11}}, r"\[run\] pilot is for the single "),
    ({"system": {"kind": "SwingNetwork", "power": [1, -1]}}, r"needs edges"),
])
def test_bad_system_run_files_are_refused_naming_the_table(change, match):
    spec = {"system": {"kind": "DoublePendulum"}, "grid": {"theta1_0": [0.1, 0.2]},
            "run": {"t_end": 1.0, "dt": 0.1}}
    spec.update(change)
    with pytest.raises((ValueError, TypeError), match=match):
        parse_run(spec, source="run.toml")
