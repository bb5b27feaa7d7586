"""Numeric parameters of the maps, metrics and plots (tolerances, thresholds, counts,
sizes, periods, seeds) are checked at the top of each public function, on every path,
before any work, with a message naming the parameter, the bad value and what is
accepted; and the 0.1 module paths (``sweep.metrics``, ...) import again, with a
DeprecationWarning.

Every case below was accepted, or refused only after some work, or refused with a
ValueError alone for a value of the wrong type, before these checks. Cases that were
already refused in the same way are in test_continuation, test_period_map,
test_response, test_attractor_catalogue and test_metrics.

The datasets are built by hand (no run): the internals that do the work are replaced by
functions that fail the test if called.
"""

import importlib
import subprocess
import sys

import matplotlib.figure
import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr

import sweep
import sweep.engine
import sweep.io
import sweep.plot
from sweep import maps
from sweep._validate import ArgumentTypeError, check_count, check_quantity
from sweep.maps import _strobe, labels, metrics, response

# sweep.maps.period and sweep.maps.continuation are also functions of sweep.maps
period = importlib.import_module("sweep.maps.period")
continuation = importlib.import_module("sweep.maps.continuation")

NAN, INF = float("nan"), float("inf")
SAMPLES = 16


def _forced():
    """Stroboscopic samples of a forced run over forcing_amplitude x theta0."""
    shape = (2, 2, SAMPLES)
    return xr.Dataset(
        {"strobe_theta": (("forcing_amplitude", "theta0", "strobe"), np.full(shape, 0.1)),
         "strobe_omega": (("forcing_amplitude", "theta0", "strobe"), np.zeros(shape)),
         "status": (("forcing_amplitude", "theta0"), np.zeros((2, 2), dtype=np.int8))},
        coords={"forcing_amplitude": [1.0, 1.1], "theta0": [0.0, 1.0]},
        attrs={"effects": "damping forcing", "gravity": 1.0, "length": 1.0})


def _unforced():
    """Final states, energies, mean velocities and amplitudes of an unforced run."""
    dims, zeros = ("theta0", "omega0"), np.zeros((2, 2))
    return xr.Dataset(
        {name: (dims, zeros) for name in ("theta_final", "energy_final", "omega_mean",
                                          "amplitude", "top_distance_max")}
        | {"status": (dims, np.zeros((2, 2), dtype=np.int8))},
        coords={"theta0": [0.0, 1.0], "omega0": [0.0, 1.0]},
        attrs={"effects": "damping", "gravity": 9.81, "length": 1.0, "dt": 0.01,
               "t_transient": 0.0, "n_steps": 100})


def _periods():
    return xr.DataArray(np.array([[1, 2], [-1, 1]], dtype=np.int32),
                        coords={"theta0": [0.0, 1.0], "omega0": [0.0, 1.0]},
                        dims=("theta0", "omega0"), name="period")


FORCED, UNFORCED, PERIODS = _forced(), _unforced(), _periods()
SCENE = sweep.Scene(gravity=1.0, length=1.0,
                    effects=(sweep.Damping(0.2), sweep.Forcing(1.2, 1.0)))
GRID = sweep.Grid(theta0=[0.0, 1.0, 2.0], omega0=[0.0, 1.0, 2.0])
LABELS = np.zeros((64, 64), dtype=np.int64)
STROBE = np.zeros((2, SAMPLES))


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a map, metric, plot, run or file write gets past its checks."""

    def forbidden(*args, **kwargs):
        raise AssertionError("work started before the parameters were checked")

    for module, name in [(_strobe, "periods"), (_strobe, "bucket_keys"),
                         (labels, "strobe_table"), (labels, "well"),
                         (labels, "_steady_window"), (labels, "_require"),
                         (period, "strobe_table"), (continuation, "strobe_axes"),
                         (continuation, "strobe_table"), (metrics, "_boxes"),
                         (metrics, "_fit_slope"), (sweep.engine, "run"),
                         (sweep.engine, "check_one_scene"), (sweep.io, "check_output_path"),
                         (plt, "subplots")]:
        monkeypatch.setattr(module, name, forbidden)
    monkeypatch.setattr(sweep.maps.labels, "strobe_axes", forbidden)  # orbit_diagram's


# (id, call, bad value's type is wrong, pattern naming the parameter and the value)
CASES = [
    # basins: checked whatever the scene, not only on the forced path
    ("basins unforced tol -1", lambda: maps.basins(UNFORCED, tol=-1.0), False,
     r"tol must be a finite number > 0 \(rad and rad/s\), got -1\.0"),
    ("basins unforced max_period 0", lambda: maps.basins(UNFORCED, max_period=0), False,
     r"max_period must be an int >= 1 \(forcing periods\), got 0"),
    ("basins unforced max_period str", lambda: maps.basins(UNFORCED, max_period="8"), True,
     r"max_period must be an int >= 1 .*got '8' \(str\)"),
    ("basins forced tol -1", lambda: maps.basins(FORCED, tol=-1.0), False,
     r"tol must be a finite number > 0 .*got -1\.0"),
    ("basins forced tol 0", lambda: maps.basins(FORCED, tol=0), False,
     r"tol must be a finite number > 0 .*got 0\b"),
    ("basins forced tol nan", lambda: maps.basins(FORCED, tol=NAN), False,
     r"tol must be a finite number > 0 .*got nan"),
    ("basins forced tol inf", lambda: maps.basins(FORCED, tol=INF), False,
     r"tol must be a finite number > 0 .*got inf"),
    ("basins forced tol None", lambda: maps.basins(FORCED, tol=None), True,
     r"tol must be a finite number > 0 .*got None \(NoneType\)"),
    ("basins forced tol bool", lambda: maps.basins(FORCED, tol=True), True,
     r"tol must be a finite number > 0 .*got True \(bool\)"),
    ("basins forced max_period 0", lambda: maps.basins(FORCED, max_period=0), False,
     r"max_period must be an int >= 1 .*got 0"),
    ("basins forced max_period -3", lambda: maps.basins(FORCED, max_period=-3), False,
     r"max_period must be an int >= 1 .*got -3"),
    ("basins forced max_period float", lambda: maps.basins(FORCED, max_period=2.5), True,
     r"max_period must be an int >= 1 .*got 2\.5 \(float\)"),
    ("basins forced max_period bool", lambda: maps.basins(FORCED, max_period=True), True,
     r"max_period must be an int >= 1 .*got True \(bool\)"),
    ("basins forced max_period nan", lambda: maps.basins(FORCED, max_period=NAN), True,
     r"max_period must be an int >= 1 .*got nan \(float\)"),
    # attractor_catalogue: checked even when the labels are given (they are unused then)
    ("attractor_catalogue tol", lambda: maps.attractor_catalogue(FORCED, tol=-1), False,
     r"tol must be a finite number > 0 .*got -1\b"),
    ("attractor_catalogue max_period with labels",
     lambda: maps.attractor_catalogue(FORCED, PERIODS, max_period=0), False,
     r"max_period must be an int >= 1 .*got 0"),
    ("attractor_catalogue max_period str",
     lambda: maps.attractor_catalogue(FORCED, max_period="x"), True,
     r"max_period must be an int >= 1 .*got 'x' \(str\)"),
    # identify_attractors
    ("identify_attractors tol 0", lambda: maps.identify_attractors(STROBE, STROBE, tol=0.0),
     False, r"tol must be a finite number > 0 .*got 0\.0"),
    ("identify_attractors tol str",
     lambda: maps.identify_attractors(STROBE, STROBE, tol="1e-3"), True,
     r"tol must be a finite number > 0 .*got '1e-3' \(str\)"),
    ("identify_attractors max_period 0",
     lambda: maps.identify_attractors(STROBE, STROBE, max_period=0), False,
     r"max_period must be an int >= 1 .*got 0"),
    ("identify_attractors max_period float",
     lambda: maps.identify_attractors(STROBE, STROBE, max_period=8.0), True,
     r"max_period must be an int >= 1 .*got 8\.0 \(float\)"),
    ("identify_attractors weights negative",
     lambda: maps.identify_attractors(STROBE, STROBE, weights=[1, -2]), False,
     r"weights must be a 1-D array of n = 2 whole numbers >= 1 .*got -2\.0 at index 1"),
    ("identify_attractors weights fraction",
     lambda: maps.identify_attractors(STROBE, STROBE, weights=[1.5, 1]), False,
     r"weights must be .*whole numbers >= 1 .*got 1\.5 at index 0"),
    ("identify_attractors weights nan",
     lambda: maps.identify_attractors(STROBE, STROBE, weights=[1, NAN]), False,
     r"weights must be .*got nan at index 1"),
    ("identify_attractors weights shape",
     lambda: maps.identify_attractors(STROBE, STROBE, weights=[1, 1, 1]), False,
     r"weights must be a 1-D array of n = 2 .*got shape \(3,\)"),
    ("identify_attractors weights bools",
     lambda: maps.identify_attractors(STROBE, STROBE, weights=[True, True]), False,
     r"weights holds booleans"),
    # period: tol before the samples are read; a wrong type is a TypeError
    ("period tol -1", lambda: maps.period(FORCED, tol=-1.0), False,
     r"tol must be a finite number > 0 .*got -1\.0"),
    ("period max_period bool", lambda: maps.period(FORCED, max_period=True), True,
     r"max_period must be an int from 1 to 8 \(half the 16 stroboscopic samples; "
     r"more samples: .*\), got True \(bool\)"),
    ("period max_period float", lambda: maps.period(FORCED, max_period=4.0), True,
     r"max_period must be an int from 1 to 8 .*got 4\.0 \(float\)"),
    # continuation: a wrong type is a TypeError too
    ("continuation max_period str",
     lambda: maps.continuation(FORCED, "forcing_amplitude", max_period="8"), True,
     r"max_period must be an int >= 1 \(forcing periods\), got '8' \(str\)"),
    ("continuation tol bool",
     lambda: maps.continuation(FORCED, "forcing_amplitude", tol=True), True,
     r"tol must be a finite number > 0 .*got True \(bool\)"),
    ("continuation threshold str",
     lambda: maps.continuation(FORCED, "forcing_amplitude", threshold="far"), True,
     r"threshold must be a number > 0 \(rad, rad/s; inf for no threshold\), got 'far' "
     r"\(str\)"),
    # motion and amplitude: min_turns was not checked at all
    ("motion min_turns -1", lambda: maps.motion(UNFORCED, min_turns=-1), False,
     r"min_turns must be a finite number > 0 \(net full turns\), got -1"),
    ("motion min_turns 0", lambda: maps.motion(UNFORCED, min_turns=0.0), False,
     r"min_turns must be a finite number > 0 .*got 0\.0"),
    ("motion min_turns nan", lambda: maps.motion(UNFORCED, min_turns=NAN), False,
     r"min_turns must be a finite number > 0 .*got nan"),
    ("motion min_turns inf", lambda: maps.motion(UNFORCED, min_turns=INF), False,
     r"min_turns must be a finite number > 0 .*got inf"),
    ("motion min_turns bool", lambda: maps.motion(UNFORCED, min_turns=True), True,
     r"min_turns must be a finite number > 0 .*got True \(bool\)"),
    ("motion min_turns None", lambda: maps.motion(UNFORCED, min_turns=None), True,
     r"min_turns must be a finite number > 0 .*got None \(NoneType\)"),
    ("amplitude min_turns -1", lambda: maps.amplitude(UNFORCED, min_turns=-1.0), False,
     r"min_turns must be a finite number > 0 .*got -1\.0"),
    ("amplitude min_turns str", lambda: maps.amplitude(UNFORCED, min_turns="1"), True,
     r"min_turns must be a finite number > 0 .*got '1' \(str\)"),
    # inverted: a wrong type is a ValueError too (it was a TypeError only)
    ("inverted tolerance str", lambda: maps.inverted(UNFORCED, tolerance="0.5"), True,
     r"tolerance must be a finite number in \(0, pi\) \(rad\), got '0\.5' \(str\)"),
    # pilot and frequency_response counts: a wrong type is a TypeError too
    ("pilot_grid points float", lambda: maps.pilot_grid(GRID, 2.5), True,
     r"pilot must be an int >= 2 \(points per initial-condition axis\), got 2\.5 "
     r"\(float\)"),
    ("pilot_catalogue points bool", lambda: maps.pilot_catalogue(SCENE, GRID, True), True,
     r"pilot must be an int >= 2 .*got True \(bool\)"),
    ("frequency_response periods_transient float",
     lambda: response.frequency_response(SCENE, [1.0], periods_transient=100.0), True,
     r"periods_transient must be an int >= 1, got 100\.0 \(float\)"),
    ("frequency_response periods_measure bool",
     lambda: response.frequency_response(SCENE, [1.0], periods_measure=True), True,
     r"periods_measure must be an int >= 1, got True \(bool\)"),
    ("frequency_response steps_per_period str",
     lambda: response.frequency_response(SCENE, [1.0], steps_per_period="200"), True,
     r"steps_per_period must be an int >= 1, got '200' \(str\)"),
    ("frequency_response theta0 str",
     lambda: response.frequency_response(SCENE, [1.0], theta0="0"), True,
     r"theta0 must be a finite number, got '0' \(str\)"),
    # metrics: rng is checked whether or not n_samples asks for a draw
    ("uncertainty_exponent rng str", lambda: metrics.uncertainty_exponent(LABELS, rng="x"),
     False, r"rng must be None, a seed \(an int >= 0 .*\), .*Generator.*, got 'x'"),
    ("uncertainty_exponent rng bool",
     lambda: metrics.uncertainty_exponent(LABELS, n_samples=10, rng=True), False,
     r"rng must be None, a seed .*got True"),
    ("uncertainty_exponent rng negative",
     lambda: metrics.uncertainty_exponent(LABELS, rng=-1), False,
     r"rng must be None, a seed .*got -1"),
    ("uncertainty_exponent rng float",
     lambda: metrics.uncertainty_exponent(LABELS, n_samples=10, rng=0.5), False,
     r"rng must be None, a seed .*got 0\.5"),
    # plots
    ("period_map threshold nan", lambda: sweep.plot.period_map(PERIODS, threshold=NAN),
     False, r"threshold must be a finite number >= 0 \(1/s: .*\), got nan"),
    ("period_map threshold -1", lambda: sweep.plot.period_map(PERIODS, threshold=-1.0),
     False, r"threshold must be a finite number >= 0 .*got -1\.0"),
    ("period_map threshold inf", lambda: sweep.plot.period_map(PERIODS, threshold=INF),
     False, r"threshold must be a finite number >= 0 .*got inf"),
    ("period_map threshold str", lambda: sweep.plot.period_map(PERIODS, threshold="0"),
     True, r"threshold must be a finite number >= 0 .*got '0' \(str\)"),
    ("orbit_diagram markersize 0", lambda: sweep.plot.orbit_diagram(FORCED, markersize=0),
     False, r"markersize must be a finite number > 0 \(points\), got 0"),
    ("orbit_diagram markersize nan",
     lambda: sweep.plot.orbit_diagram(FORCED, markersize=NAN), False,
     r"markersize must be a finite number > 0 .*got nan"),
    ("orbit_diagram markersize None",
     lambda: sweep.plot.orbit_diagram(FORCED, markersize=None), True,
     r"markersize must be a finite number > 0 .*got None \(NoneType\)"),
    ("save_figure dpi 0",
     lambda: sweep.plot.save_figure(matplotlib.figure.Figure(), "never.png", dpi=0), False,
     r"dpi must be a finite number > 0 \(dots per inch\), got 0"),
    ("save_figure dpi -150",
     lambda: sweep.plot.save_figure(matplotlib.figure.Figure(), "never.png", dpi=-150.0),
     False, r"dpi must be a finite number > 0 .*got -150\.0"),
    ("save_figure dpi inf",
     lambda: sweep.plot.save_figure(matplotlib.figure.Figure(), "never.png", dpi=INF),
     False, r"dpi must be a finite number > 0 .*got inf"),
    ("save_figure dpi str",
     lambda: sweep.plot.save_figure(matplotlib.figure.Figure(), "never.png", dpi="150"),
     True, r"dpi must be a finite number > 0 .*got '150' \(str\)"),
    ("select nan", lambda: sweep.plot.select(UNFORCED, theta0=NAN), False,
     r"selection theta0=nan: accepted: a finite number"),
    ("select inf", lambda: sweep.plot.select(UNFORCED, omega0=-INF), False,
     r"selection omega0=-inf: accepted: a finite number"),
]


@pytest.mark.parametrize("call, wrong_type, pattern", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_a_bad_parameter_is_refused_before_any_work(call, wrong_type, pattern, no_work):
    # a value of the wrong type is a TypeError, and a ValueError as such checks raised
    # before (code catching ValueError keeps working); the metrics raise ValueError
    # for every bad value, as documented there
    kind = TypeError if wrong_type else ValueError
    with pytest.raises(kind, match=pattern) as caught:
        call()
    assert isinstance(caught.value, ValueError)


def test_the_checks_accept_what_they_say(no_work):
    """The edges of what is accepted pass (and nothing here reaches the work)."""
    assert check_count("n", np.int64(3)) == 3 and check_count("n", 2, minimum=2) == 2
    assert check_count("n", 8, maximum=8) == 8
    assert check_quantity("x", np.float32(0.5), minimum=0.0, strict=True) == 0.5
    assert check_quantity("x", 0, minimum=0.0) == 0.0
    assert check_quantity("x", INF, minimum=0.0, strict=True, allow_inf=True) == INF
    for bad in (-INF, NAN):
        with pytest.raises(ValueError, match="x must be"):
            check_quantity("x", bad, minimum=0.0, allow_inf=True)
    with pytest.raises(ValueError, match=r"beyond the float range"):
        check_quantity("x", 10**400)
    for bad in (np.bool_(True), 1 + 0j, np.array([1.0]), b"1"):
        with pytest.raises(ArgumentTypeError, match="x must be"):
            check_quantity("x", bad)
    with pytest.raises(ValueError, match=r"n must be an int from 1 to 8, got 9"):
        check_count("n", 9, maximum=8)
    # continuation's threshold still takes inf ("no threshold")
    assert continuation._check_options("theta0", 8, 1e-3, INF) == (8, 1e-3, INF)


# ------------------------------------------------------------------- 0.1 module paths
SHIMS = {"metrics": "sweep.maps.metrics", "response": "sweep.maps.response",
         "scene": "sweep.physics.scene", "checkpoint": "sweep.execution.checkpoint"}


def _python(*args, **kwargs):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True,
                          timeout=120, **kwargs)


@pytest.mark.parametrize("old", sorted(SHIMS))
def test_an_old_module_path_warns_naming_the_new_one(old):
    strict = _python("-W", "error::DeprecationWarning", "-c", f"import sweep.{old}")
    assert strict.returncode != 0
    assert (f"DeprecationWarning: the module path sweep.{old} is deprecated and will be "
            f"removed in 0.3; import {SHIMS[old]} instead") in strict.stderr
    # default filters show a DeprecationWarning only when it points at __main__: it
    # does, since it points at the importing line
    default = _python("-c", f"import sweep.{old}")
    assert default.returncode == 0, default.stderr
    assert f"import {SHIMS[old]} instead" in default.stderr


OLD_PATHS = """\
import importlib
import sys
import warnings

import sweep  # run with -W error: the package warns nothing

assert not {"sweep.metrics", "sweep.response", "sweep.scene", "sweep.checkpoint"} & set(
    sys.modules)  # and imports no shim
alias = sweep.metrics  # the package's aliases stay, and warn nothing
from sweep import metrics, response
assert alias is metrics is importlib.import_module("sweep.maps.metrics")
assert response is importlib.import_module("sweep.maps.response")
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import sweep.metrics
    from sweep.response import frequency_response
    from sweep.scene import MODELS, Scene
    from sweep.checkpoint import open_checkpoint
import sweep.execution.checkpoint
import sweep.maps.metrics
import sweep.physics.scene
assert sweep.metrics is sweep.maps.metrics is alias
assert sweep.metrics.basin_entropy is sweep.maps.metrics.basin_entropy
assert frequency_response is sweep.maps.response.frequency_response
assert Scene is sweep.Scene is sweep.physics.scene.Scene
assert MODELS is sweep.physics.scene.MODELS
assert open_checkpoint is sweep.execution.checkpoint.open_checkpoint
for warning in caught:
    print(warning.category.__name__, warning.filename, warning.lineno)
import sweep.metrics  # imported already: no second warning
"""


def test_old_module_paths_give_the_new_modules_and_the_package_warns_nothing(tmp_path):
    script = tmp_path / "old_paths.py"
    script.write_text(OLD_PATHS)
    done = _python("-W", "error", str(script), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    # one warning per old path, each pointing at its own import line in the script
    lines = [number for number, text in enumerate(OLD_PATHS.splitlines(), start=1)
             if text.startswith("    ") and "import" in text and "sweep." in text]
    assert len(lines) == 4
    assert done.stdout.splitlines() == [f"DeprecationWarning {script} {line}"
                                        for line in lines]
