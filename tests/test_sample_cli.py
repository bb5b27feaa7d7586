"""Sampled points and basin fractions from run files and the command line: ``[sample]``
is `sweep.sample` (the same points), and ``sweep fractions`` prints (and writes) what
`sweep.maps.fractions` gives for the file's labels."""

import numpy as np
import pandas as pd
import pytest
from test_cli import call, write

import sweep
from sweep import maps
from sweep.toml_spec import parse_run

SCENE = """
[scene]
gravity = 9.81
length = 1.0
[scene.damping]
coefficient = 0.5
"""
SAMPLE = """
[sample]
n = 500
seed = 7
method = "random"
theta0 = [-3.0, 3.0]
omega0 = [-9.0, 9.0]
damping = 0.5
"""
RUN = """
[run]
t_end = 20.0
dt = 0.02
observe = ["capture"]
stop_early = true
"""


def test_a_sample_table_is_sweep_sample():
    spec = {"sample": {"n": 100, "seed": 3, "theta0": [-1.0, 1.0], "omega0": [0.0, 2.0],
                       "damping": 0.2}, "run": {"t_end": 1.0, "dt": 0.1}}
    _, points, _ = parse_run(spec)
    expected = sweep.sample(100, seed=3, theta0=(-1.0, 1.0), omega0=(0.0, 2.0),
                            damping=0.2)
    assert isinstance(points, sweep.Points) and points.dims == ("point",)
    for name, values in expected.axes.items():
        np.testing.assert_array_equal(points.axes[name], values)


@pytest.mark.parametrize("change, message", [
    ({"grid": {"theta0": [0.0]}}, r"both \[grid\] and \[sample\]; accepted: one of them"),
    ({"sample": {"n": 10, "theta0": [0.0, 1.0]}}, r"\[sample\] needs seed"),
    ({"sample": {"n": 10, "seed": 1, "theta0": [0.0, 1.0, 2.0]}},
     r"\[sample\] theta0 = \[0\.0, 1\.0, 2\.0\]; accepted: a range \[lo, hi\]"),
    ({"sample": {"n": 0, "seed": 1, "theta0": [0.0, 1.0]}}, r"n must be an int >= 1"),
    ({"sample": {"n": 10, "seed": 1, "theta0": [1.0, 0.0]}}, r"theta0"),
    ({"sample": {"n": 10, "seed": 1, "gamma": [0.0, 1.0]}}, r"unknown key 'gamma' in \[sample\]"),
])
def test_bad_sample_tables_are_refused_by_name(change, message):
    spec = {"sample": {"n": 10, "seed": 1, "theta0": [0.0, 1.0]},
            "run": {"t_end": 1.0, "dt": 0.1}} | change
    with pytest.raises((ValueError, TypeError), match=message):
        parse_run(spec, source="run.toml")


def test_sweep_fractions_prints_and_writes_what_the_api_gives(tmp_path):
    """A sampled damped-well run through `sweep run`, then `sweep fractions --label
    well`: the same fractions, errors and counts as the API, printed and as CSV."""
    run_file = write(tmp_path, SCENE + SAMPLE + RUN)
    code, out, err = call("run", str(run_file), "-o", str(tmp_path / "s.nc"))
    assert code == 0, err
    ds = sweep.load(tmp_path / "s.nc")
    expected = maps.fractions(maps.well(ds)).to_dataframe()
    code, out, err = call("fractions", str(tmp_path / "s.nc"), "--label", "well",
                          "-o", str(tmp_path / "f.csv"))
    assert code == 0, err
    assert "500 trajectories, well (binomial" in out
    written = pd.read_csv(tmp_path / "f.csv", index_col="label")
    np.testing.assert_array_equal(written["count"], expected["count"])
    np.testing.assert_allclose(written["fraction"], expected["fraction"], rtol=1e-15)
    np.testing.assert_allclose(written["standard_error"], expected["standard_error"],
                               rtol=1e-15)
    assert written["count"].sum() == 500
    rows = [line.split() for line in out.splitlines()[3:-1]]  # after the title, header
    assert [int(row[3]) for row in rows] == expected["count"].tolist()
    np.testing.assert_allclose([float(row[1]) for row in rows], expected["fraction"],
                               rtol=1e-5)  # printed with pandas' 6 significant digits
    code, out, err = call("fractions", str(tmp_path / "s.nc"), "--label", "winding")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("sweep: error: --label 'winding' is "
                                                   "neither a map nor a variable")


GRID = """
[grid]
theta0 = { start = -3.0, stop = 3.0, num = 12 }
omega0 = { start = -9.0, stop = 9.0, num = 10 }
damping = 0.5
"""


def test_sweep_fractions_of_a_grid(tmp_path):
    """A grid of the same run: no standard errors (its cells are not a random sample:
    no column of them printed),
    whole-number labels printed as integers (the well variable is float: 0, not 0.0),
    and a variable of other floats refused in one line that names the labels that
    work (it printed a row of count 1 per value)."""
    code, out, err = call("run", str(write(tmp_path, SCENE + GRID + RUN)), "-o",
                          str(tmp_path / "g.nc"))
    assert code == 0, err
    code, out, err = call("fractions", str(tmp_path / "g.nc"), "--label", "well")
    assert (code, err) == (0, ""), err
    assert "120 trajectories, well (a grid: no standard errors" in out
    rows = [line.split() for line in out.splitlines()[3:]]
    assert [row[0] for row in rows] == ["-2", "-1", "0", "1", "2"], out  # all captured
    assert out.splitlines()[1].split() == ["fraction", "count", "unresolved"]  # no NaN column
    assert all(len(row) == 4 for row in rows)
    code, out, err = call("fractions", str(tmp_path / "g.nc"), "--label", "capture_time")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("sweep: error: --label capture_time: variable 'capture_time' "
                          "holds ") and "which is not a label" in err
    assert err.endswith("labels that work on " + repr(str(tmp_path / "g.nc"))
                        + ": --label basins, --label well\n")
    # the first 16, 32, ... cells of a grid are rows of its first axis, not a sample
    code, out, err = call("fractions", str(tmp_path / "g.nc"), "--label", "well",
                          "--convergence")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith("sweep: error: --convergence: the labels are a grid's cells"), err
    assert "accepted: a file of a [sample] or [points] run" in err, err

