"""`sweep.maps.describe_boundary` and ``sweep boundary``: one call for everything "Is my
map right?" measures on a 2-D map, each number equal to its own function's."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from shared_kernels import WADA_RUN_FILE
from test_cli import call, write
from test_wada import label_map
from test_wada import sector as sectors  # three sectors of 120 degrees: smooth, not Wada

from sweep import maps
from sweep.maps import metrics
from sweep.maps.boundary import SAMPLED_EPS, describe_boundary

X = np.linspace(-1.0, 1.0, 41)  # the origin, where the three sectors meet, a grid point
Y = np.linspace(-1.0, 1.0, 41)


def sector_map() -> np.ndarray:
    return label_map(sectors, X, Y)


def test_each_number_is_its_own_functions_and_a_smooth_map_reads_smooth():
    labels = sector_map()
    report = describe_boundary(labels, X, Y, sectors, sampled=50_000, wada_steps=2, seed=3)
    assert report.shape == (41, 41)
    assert report.fractions == metrics.basin_fractions(labels)
    assert report.entropy == metrics.basin_entropy(labels, box_size=5)
    assert report.fractality == metrics.fractality_test(labels, radius=4, n_balls=1000,
                                                        rng=3)
    assert report.fractality is not None and not report.fractality.fractal
    assert report.uncertainty == metrics.uncertainty_exponent(labels)
    sampled = maps.uncertainty_sampled(sectors, ((-1.0, 1.0), (-1.0, 1.0)), eps=SAMPLED_EPS,
                                       n=50_000, seed=3)
    assert report.sampled == sampled
    # a smooth boundary: alpha = 1, within three of the fit's standard errors
    assert abs(report.sampled.alpha - 1.0) < 3 * report.sampled.alpha_error
    wada = maps.wada(labels, sectors, X, Y, max_steps=2)
    assert report.wada.verdict == wada.verdict == "not Wada"
    np.testing.assert_array_equal(report.wada.fractions, wada.fractions)
    text = "\n".join(report.lines())
    assert "3 basins" in text and "smooth" in text and "not Wada" in text
    assert json.loads(json.dumps(report.to_dict()))["wada"]["verdict"] == "not Wada"


def test_what_is_not_asked_for_is_not_computed():
    calls = []

    def labels_of(starts):
        calls.append(len(starts))
        return sectors(starts)

    report = describe_boundary(sector_map(), X, Y, labels_of)
    assert calls == [] and report.sampled is None and report.wada is None
    one = describe_boundary(np.zeros((40, 40), dtype=np.int64), X[:40], Y[:40])
    assert one.fractality is None and one.fractality_note == "one basin"


@pytest.mark.parametrize("kwargs, words", [
    ({"labels": np.zeros((4, 4, 4), dtype=int)}, "2-D integer"),
    ({"labels": np.zeros((64, 64))}, "2-D integer"),
    ({"x": X[:10]}, "one coordinate per row"),
    ({"sampled": -1}, "sampled"),
    ({"sampled": 50, "labels_of": sectors}, ">= 100"),
    ({"wada_steps": 2}, "need labels_of"),
    ({"seed": -2}, "seed"),
])
def test_bad_input_is_refused_before_anything_is_computed(kwargs, words):
    args = {"labels": sector_map(), "x": X, "y": Y, "labels_of": None, **kwargs}
    with pytest.raises(ValueError, match=words):
        describe_boundary(args.pop("labels"), args.pop("x"), args.pop("y"),
                          args.pop("labels_of"), **args)




def test_the_command_prints_the_forced_wada_maps_numbers_and_writes_them(tmp_path):
    """The conftest's Wada scene at 41 x 41 with a 21 x 21 pilot: 41 = 2 x 20 + 1 points
    per axis, so the pilot's every other start is, to the bit, conftest's 21 x 21 pilot,
    and the catalogue and the kernels are the ``wada_catalogue`` fixture's (at 48 x 48
    the pilot thinned to other starts: another catalogue, a kernel of its own). The map
    is fractal and Wada already at this size (W3 = 0.996 after 6 steps, measured; the
    full-size map's 0.994 after 6, docs/guide/map_accuracy.md)."""
    output = tmp_path / "wada.json"
    run_file = write(tmp_path, WADA_RUN_FILE.format(n=41, extra=""))
    code, out, err = call("boundary", run_file, "--pilot", 21, "--sampled", 300, "--wada", 6,
                          "-o", output)
    assert (code, err) == (0, ""), err
    assert "forced basins (pilot catalogue)" in out and "3 basins" in out
    numbers = json.loads(output.read_text())
    assert numbers["fractality"]["fractal"] and numbers["log2_criterion"]
    # alpha ~ 0.15 for this map (docs' table: 0.147 +- 0.004); well below 1 whatever
    # the sample (300 pairs per level: standard error ~0.02)
    assert numbers["alpha_sampled"]["alpha"] < 0.4
    assert numbers["wada"]["verdict"] == "Wada"
    assert f"wrote {output}" in out
    assert not list(tmp_path.glob("*.tmp"))


UNFORCED = """
[scene]
gravity = 9.81
length = 1.0
[scene.damping]
coefficient = 0.5
[grid]
theta0 = {{ start = -3.141592653589793, stop = 3.141592653589793, num = 48 }}
omega0 = {{ start = -8.0, stop = 8.0, num = 48 }}
{extra}
[run]
t_end = 20.0
dt = 0.02
observe = ["final", "winding"]
"""


def test_an_unforced_maps_basins_are_its_wells_and_its_boundary_is_smooth(tmp_path):
    code, out, err = call("boundary", write(tmp_path, UNFORCED.format(extra="")))
    assert (code, err) == (0, ""), err
    assert "basins (wells)" in out and "fractality test (radius 4 cells): smooth" in out


@pytest.mark.parametrize("extra, argv, words", [
    ("", ["--label", "nonsense"], "--label 'nonsense' is not a map"),
    ("", ["--sampled", "20"], "--sampled must be 0 or >= 100"),
    ("", ["--wada", "-1"], "--wada must be >= 0"),
    ("damping = [0.1]", [], "put damping in [scene]"),
    ("damping = [0.1, 0.2]", [], "a [grid] of theta0 and omega0"),
])
def test_the_commands_errors_are_one_line_before_any_compute(tmp_path, no_compute, extra,
                                                              argv, words):
    code, out, err = call("boundary", write(tmp_path, UNFORCED.format(extra=extra)), *argv)
    assert code == 2 and out == ""
    assert err.startswith("sweep: error:") and words in err and err.count("\n") == 1


def test_a_system_run_file_is_refused_in_one_line(no_compute):
    """A shipped ``[system]`` run file: one line that says ``sweep boundary`` takes
    single-pendulum run files only (it said the grid should vary theta0 and omega0, as
    if renaming the system's axes would do), before anything is compiled or run."""
    run_file = str(Path(__file__).resolve().parents[1] / "examples" /
                   "driven_double_pendulum_basins.toml")
    code, out, err = call("boundary", run_file)
    assert code == 2 and out == ""
    assert err == (f"sweep: error: sweep boundary supports single-pendulum run files only; "
                   f"{run_file!r} has a [system] table (DoublePendulum); accepted: a run "
                   "file with a [scene] table, or with neither (the default pendulum)\n")
