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
    assert report.fractality == metrics.fractality_test(labels, radius=3, n_balls=1000,
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
    # five wells, -2 to 2: each a basin (the wells -2 and -1 were read as unresolved)
    assert "basins (wells)" in out and "5 basins" in out
    assert "fractality test (radius 3 cells): smooth" in out


def test_every_label_but_the_maps_own_unresolved_one_is_a_basin():
    """motion's -1 is a rotation sense, its unresolved value -127: three basins, and
    -127 printed as unresolved (a blanket 'negative is unresolved' read one basin)."""
    labels = np.where(X[:, None] < -0.3, -1, np.where(X[:, None] > 0.3, 1, 0)) \
        + np.zeros((1, Y.size), dtype=np.int64)
    labels[0, 0] = -127
    report = describe_boundary(labels, X, Y, unresolved=-127)
    assert report.basins == 3 and report.unresolved == -127
    text = "\n".join(report.lines())
    assert "3 basins" in text and "unresolved: 0.0006, -1: 0.3409" in text
    assert report.to_dict()["basins"] == 3 and "unresolved" in report.to_dict()["fractions"]
    # a labels_of says its own unresolved value; the default is -1 (sweep.maps.basins)
    def labels_of(starts):
        return np.zeros(len(starts), dtype=np.int64)
    labels_of.unresolved = -127
    assert describe_boundary(labels, X, Y, labels_of).basins == 3
    assert describe_boundary(labels, X, Y).basins == 3  # -1 unresolved, -127 a basin


def test_wada_reads_negative_basins_as_basins():
    """The Wada test counts every basin but the unresolved label: sectors numbered -1,
    -2, -3 (as wells are) give the same verdict and fractions as 0, 1, 2."""
    def negative(starts):
        return -1 - sectors(starts)

    plain = describe_boundary(sector_map(), X, Y, sectors, wada_steps=2)
    shifted = describe_boundary(-1 - sector_map(), X, Y, negative, wada_steps=2,
                                unresolved=-99)
    assert shifted.wada is not None and shifted.wada.verdict == plain.wada.verdict
    np.testing.assert_array_equal(shifted.wada.fractions, plain.wada.fractions)


def stripes(n: int, width: int) -> np.ndarray:
    """Straight bands ``width`` cells wide, labelled 0 to 4 in turn: smooth boundaries,
    basins narrower than a ball of radius n // 10 cells when width < n // 5."""
    i, j = np.indices((n, n))
    return ((i + j // 3) // width % 5).astype(np.int64)


def test_the_fractality_ball_is_small_against_the_map():
    """A smooth map of bands 6 cells wide, 101 x 101 cells: through balls of 10 cells
    (the radius was min(shape) // 10) most boundary balls hold three bands and the
    test read fractal; the ball is now a 40th of the axis (3 cells), and reads smooth.
    Where balls do hold three labels or more, the report says so."""
    x = np.linspace(0.0, 1.0, 101)
    labels = stripes(101, 6)
    report = describe_boundary(labels, x, x)
    assert report.fractality.radius == 3 and not report.fractality.fractal
    assert report.fractality.multi_label_balls == 0
    wide = metrics.fractality_test(labels, radius=10, rng=0)
    assert wide.fractal and wide.multi_label_balls > 500  # most of the 1000 balls
    coarse = describe_boundary(labels[:, :41][:41], x[:41], x[:41])  # radius 3 too
    assert coarse.fractality.radius == 3
    text = "\n".join(describe_boundary(stripes(801, 6), np.arange(801.0),
                                       np.arange(801.0)).lines())
    assert "radius 20 cells): fractal" in text and "hold three labels or more" in text


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


CAPTURE = UNFORCED.replace('observe = ["final", "winding"]',
                           'observe = ["capture"]\nstop_early = true')


def test_an_unforced_map_with_capture_and_stop_early_is_mapped(tmp_path):
    """observe = ["capture"] with stop_early = true (the fast way to the wells): the
    command read the wells from 'final' and 'energy', which stop_early refuses, and
    stopped on 'final', which nobody asked for. Now it reads the observed wells; t_end
    = 2 s leaves starts uncaptured, the unresolved row, apart from the well -1 (the
    two were one label, -1)."""
    run_file = write(tmp_path, CAPTURE.replace("t_end = 20.0", "t_end = 2.0")
                     .format(extra=""))
    code, out, err = call("boundary", run_file)
    assert (code, err) == (0, ""), err
    fractions = next(line for line in out.splitlines() if line.startswith("fractions"))
    assert "unresolved: " in fractions and " -1: " in fractions
    shares = dict(item.split(": ") for item in fractions[len("fractions: "):].split(", "))
    assert f"{len(shares) - 1} basins" in out  # every well, the unresolved row aside


FORCED = """
[scene]
gravity = 1.0
length = 1.0
[scene.damping]
coefficient = 0.5
[scene.forcing]
amplitude = 1.35
frequency = 0.6666666666666666
[grid]
theta0 = {{ start = -3.0, stop = 3.0, num = 40 }}
omega0 = {{ start = -3.0, stop = 3.0, num = 40 }}
[run]
t_end = {{ periods = 20 }}
dt = {{ per_period = 100 }}
observe = {observe}
{extra}
"""


@pytest.mark.parametrize("text, argv, words", [
    (FORCED.format(observe='["final", "winding"]', extra=""), [],
     ['--label basins of a forced scene needs observe = ["strobe"] in [run]',
      "or --label motion, which this run gives"]),
    (FORCED.format(observe='["final", "winding"]', extra=""), ["--label", "well"],
     ["--label well is for unforced scenes", "accepted: --label motion"]),
    (FORCED.format(observe='["strobe"]', extra=""), ["--label", "well"],
     ["--label well is for unforced scenes", "accepted: --label basins or --label period"]),
    (CAPTURE.format(extra=""), ["--label", "motion"],
     ['--label motion needs observe = ["omega_mean" or "winding" or "final"], which needs '
      "the whole run", "stop_early = true", "or --label basins or --label well"]),
    (UNFORCED.format(extra=""), ["--label", "inverted"],
     ['--label inverted needs observe = ["top_distance"]', "or --label basins or "
      "--label well or --label motion, which this run gives"]),
])
def test_a_label_the_run_cannot_give_is_refused_before_any_compute(tmp_path, no_compute,
                                                                     text, argv, words):
    """The label asked for (default basins), what it needs and the labels that would
    work, in one line before anything runs: a forced map without strobe computed for
    seconds, then blamed 'well', which nobody asked for."""
    code, out, err = call("boundary", write(tmp_path, text), *argv)
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith("sweep: error: ") and all(w in err for w in words), err


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


def test_a_map_too_small_for_the_fractality_test_is_not_tested():
    """An 8 x 8 map of two smooth half planes: a ball of 3 cells is more than a third of
    the map, so the test would judge the map's edges, not its boundary (before, such a
    map of smooth wells read "fractal"); it is not run, and the report says why."""
    x = np.linspace(-1.0, 1.0, 8)
    labels = (x[:, None] + 0.3 * x[None, :] > 0).astype(np.int64)
    report = describe_boundary(labels, x, x)
    assert report.fractality is None
    assert report.fractality_note.startswith("the map is too small for it: 8 cells")
    wide = np.linspace(-1.0, 1.0, 30)  # 10 radii of 3 cells: tested
    plane = (wide[:, None] + 0.3 * wide[None, :] > 0).astype(np.int64)
    assert describe_boundary(plane, wide, wide).fractality is not None
