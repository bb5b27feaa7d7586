"""Run-file times in drive periods (`sweep.toml_periods`): ``[run] t_end = { periods = k
}`` and ``dt = { per_period = N }`` resolve to the seconds ``k * (2 pi / W)`` and ``(2
pi / W) / N`` of the run's one drive frequency W, bit for bit; stroboscopic sampling
accepts them; a run without one drive frequency, or a bad table, is refused in one line
before any compute. The run files sweep writes (`sweep.toml_periods.run_lines`) give
those tables back where they resolve to the very same floats, and seconds elsewhere."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from test_cli import call, write

import sweep
from sweep._timesteps import check_sampling_period, transient_steps, whole_steps
from sweep.explore.texts import toml_value as _toml_value
from sweep.toml_periods import in_periods, run_lines
from sweep.toml_spec import load_run, parse_run

W = 0.6666666666666666  # examples/forced.toml's forcing frequency [rad/s]

# examples/wada_map.toml's scene (damping and a cos forcing of W = 1 rad/s): its strobe
# kernel is the one test_map_examples compiles
WADA = {"scene": {"gravity": 1.0, "length": 1.0, "damping": {"coefficient": 0.2},
                  "forcing": {"amplitude": 1.66, "frequency": 1.0,
                              "phase": 1.5707963267948966}},
        "grid": {"theta0": [0.5], "omega0": [0.5]},
        "run": {"t_end": {"periods": 40}, "dt": {"per_period": 100},
                "t_transient": {"periods": 20}, "observe": ["strobe"]}}

FORCED = {"scene": {"damping": {"coefficient": 0.5},
                    "forcing": {"amplitude": 1.35, "frequency": W}},
          "grid": {"theta0": [0.1], "omega0": [0.0]},
          "run": {"t0": {"periods": 2}, "t_end": {"periods": 26},
                  "dt": {"per_period": 1000}, "t_transient": {"periods": 10}}}


def spec_with(base, section, **values):
    spec = copy.deepcopy(base)
    spec[section].update(values)
    return spec


# ------------------------------------------------------------------ the seconds
def test_periods_resolve_to_the_seconds_computed_in_float64():
    _, _, kwargs = parse_run(FORCED)
    period = 2 * math.pi / W
    # exact: the same float64 operations as writing them by hand
    assert kwargs["t0"] == 2 * period
    assert kwargs["t_end"] == 26 * period
    assert kwargs["dt"] == period / 1000
    assert kwargs["t_transient"] == 10 * period
    # examples/forced.toml's decimals, which it wrote until it could say periods
    assert (kwargs["t_end"], kwargs["dt"], kwargs["t_transient"]) == (
        245.04422698000386, 0.00942477796076938, 94.24777960769379)
    assert all(type(kwargs[key]) is float for key in ("t0", "t_end", "dt", "t_transient"))


def test_seconds_and_periods_mix_and_a_float_count_of_periods_is_accepted():
    spec = spec_with(FORCED, "run", t0=0.0, t_end={"periods": 2.5}, dt={"per_period": 10},
                     t_transient={"periods": 0}, save_every=5)
    _, _, kwargs = parse_run(spec)
    assert kwargs["t0"] == 0.0 and kwargs["save_every"] == 5
    assert kwargs["t_end"] == 2.5 * (2 * math.pi / W) and kwargs["t_transient"] == 0.0
    spec = spec_with(FORCED, "run", t0=0.0, t_end=10.0, dt=0.01, t_transient={"periods": 1})
    _, _, kwargs = parse_run(spec)
    assert (kwargs["t_end"], kwargs["dt"]) == (10.0, 0.01)
    assert kwargs["t_transient"] == 2 * math.pi / W
    spec = spec_with(FORCED, "run", t0={"periods": -3})
    assert parse_run(spec)[2]["t0"] == -3 * (2 * math.pi / W)


@pytest.mark.parametrize("scene, rows", [
    # the pivot alone drives
    ({"pivot": {"amplitude": 0.1, "frequency": 5.0}}, {"grid": {"theta0": [0.1]}}),
    # a forcing and a pivot of one frequency: one period
    ({"forcing": {"amplitude": 1.0, "frequency": 5.0},
      "pivot": {"amplitude": 0.1, "frequency": 5.0}}, {"grid": {"theta0": [0.1]}}),
    # the frequency from a grid axis of one value, a points column of one value, a
    # sample's constant column (they override the scene's 1 rad/s)
    ({"forcing": {"amplitude": 1.0, "frequency": 1.0}},
     {"grid": {"theta0": [0.1, 0.2], "forcing_frequency": 5.0}}),
    ({"forcing": {"amplitude": 1.0, "frequency": 1.0}},
     {"points": {"theta0": [0.1, 0.2], "forcing_frequency": [5.0, 5.0]}}),
    ({"forcing": {"amplitude": 1.0, "frequency": 1.0}},
     {"sample": {"n": 4, "seed": 1, "theta0": [-1.0, 1.0], "forcing_frequency": 5.0}}),
])
def test_the_drive_frequency_is_the_runs_one_frequency(scene, rows):
    spec = {"scene": scene, **rows, "run": {"t_end": {"periods": 3},
                                            "dt": {"per_period": 7}}}
    _, _, kwargs = parse_run(spec)
    assert kwargs["t_end"] == 3 * (2 * math.pi / 5.0)
    assert kwargs["dt"] == (2 * math.pi / 5.0) / 7


@pytest.mark.parametrize("frequency", [W, 1.0, 60.0, 0.1, math.pi, 1e-3, 1234.5])
def test_the_steps_fit_whole_periods_for_counts_up_to_a_million(frequency):
    """`sweep._timesteps` accepts every resolved run: t_end - t0 a whole number of steps
    and the period a whole number of steps for stroboscopic sampling; the steady window
    starts on the transient's last period boundary."""
    period = 2 * math.pi / frequency
    for per_period in (1, 3, 7, 40, 100, 1000, 12345, 10**6):
        dt = period / per_period
        check_sampling_period("strobe", [frequency], dt)
        for periods in (1, 10, 26, 320, 999, 10**4, 10**6):
            for start in (0, 3, -7):
                span = periods * period - start * period
                assert whole_steps("t_end - t0", span, dt) == (periods - start) * per_period
            assert transient_steps(periods * period, dt) == periods * per_period


def test_the_slack_of_whole_steps_stays_below_a_step_for_long_runs():
    """The relative slack (1e-9, for the rounding of span / dt) is capped at a quarter
    step: from 1e9 steps on it reached a whole step, so the steady window began a step
    early (`transient_steps(1e6, 1e-3)` gave 999999999) and a span a step off whole was
    accepted. An exact binary case (dt = 2^-10) and a decimal one."""
    assert transient_steps(1e6, 1e-3) == 10**9
    assert transient_steps(3e9 * 2.0**-10, 2.0**-10) == 3 * 10**9
    assert transient_steps((3e9 + 0.5) * 2.0**-10, 2.0**-10) == 3 * 10**9 + 1
    assert whole_steps("t_end - t0", 3e9 * 2.0**-10, 2.0**-10) == 3 * 10**9
    with pytest.raises(ValueError, match="not a whole number of steps"):
        whole_steps("t_end - t0", (3e9 + 0.6) * 2.0**-10, 2.0**-10)
    # the rounding slack still holds where it is needed: 300 / 0.01 = 30000.000000000004
    assert whole_steps("t_end - t0", 300.0, 0.01) == 30000
    assert transient_steps(300.0, 0.01) == 30000


def test_a_strobe_run_with_periods_samples_at_one_phase():
    """A run file in periods through `sweep.run`: accepted by the strobe check, every
    sample filled, and the samples those of the same run in hand-written seconds."""
    scene, grid, kwargs = parse_run(WADA)
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    assert ds.attrs["t_end"] == 40 * 2 * math.pi and ds.attrs["dt"] == 2 * math.pi / 100
    assert np.isfinite(ds.strobe_theta).all() and ds.strobe_theta.sizes["strobe"] == 16
    by_hand = spec_with(WADA, "run", t_end=40 * (2 * math.pi), dt=2 * math.pi / 100,
                        t_transient=20 * (2 * math.pi))
    scene, grid, kwargs = parse_run(by_hand)
    same = sweep.run(scene, grid, progress=False, **kwargs)
    np.testing.assert_array_equal(ds.strobe_theta, same.strobe_theta)  # the same floats


# ---------------------------------------------------------------------- refused
@pytest.mark.parametrize("spec, words", [
    # no drive
    ({"scene": {"damping": {"coefficient": 0.5}}, "grid": {"theta0": [0.1]},
      "run": {"t_end": {"periods": 26}, "dt": 0.1}},
     ["[run] t_end = {periods = 26}", "no periodic drive", "[scene.forcing]", "seconds"]),
    ({"grid": {"theta0": [0.1]}, "run": {"t_end": 1.0, "dt": {"per_period": 10}}},
     ["[run] dt = {per_period = 10}", "no periodic drive"]),
    # two drives of different frequencies
    ({"scene": {"forcing": {"amplitude": 1.0, "frequency": 1.0},
                "pivot": {"amplitude": 0.1, "frequency": 2.0}},
      "grid": {"theta0": [0.1]}, "run": {"t_end": {"periods": 2}, "dt": 0.1}},
     ["t_end = {periods = 2}", "different frequencies", "forcing_frequency = 1.0",
      "pivot_frequency = 2.0", "accepted:"]),
    # the drive frequency swept
    (spec_with(FORCED, "grid", forcing_frequency=[0.5, 1.0]),
     ["[grid] forcing_frequency has 2 values (0.5, 1.0)", "one drive frequency"]),
    ({**{k: v for k, v in FORCED.items() if k != "grid"},
      "points": {"theta0": [0.1, 0.2], "forcing_frequency": [0.5, 1.0]}},
     ["[points] forcing_frequency has 2 values"]),
    ({**{k: v for k, v in FORCED.items() if k != "grid"},
      "sample": {"n": 8, "seed": 1, "theta0": [-1.0, 1.0], "forcing_frequency": [0.5, 1.0]}},
     ["[sample] forcing_frequency has 8 values (0.5", "...)"]),
    # W = 0
    (spec_with(FORCED, "scene", forcing={"amplitude": 1.0, "frequency": 0.0}),
     ["forcing_frequency = 0.0 rad/s has no period"]),
    # bad counts
    (spec_with(FORCED, "run", dt={"per_period": 0}),
     ["[run] dt = {per_period = 0}", "per_period must be an integer >= 1, got 0"]),
    (spec_with(FORCED, "run", dt={"per_period": 2.5}), ["integer >= 1, got 2.5"]),
    (spec_with(FORCED, "run", dt={"per_period": True}), ["integer >= 1, got True"]),
    (spec_with(FORCED, "run", dt={"per_period": "1000"}), ["integer >= 1, got '1000'"]),
    (spec_with(FORCED, "run", t_end={"periods": 0}),
     ["[run] t_end = {periods = 0}", "a finite number > 0, got 0"]),
    (spec_with(FORCED, "run", t_end={"periods": -3}), ["finite number > 0, got -3"]),
    (spec_with(FORCED, "run", t_end={"periods": math.inf}), ["got inf"]),
    (spec_with(FORCED, "run", t0={"periods": math.nan}),
     ["[run] t0 = {periods = nan}", "a finite number, got nan"]),
    (spec_with(FORCED, "run", t_transient={"periods": -1}),
     ["t_transient", "finite number >= 0, got -1"]),
    (spec_with(FORCED, "run", t_end={"periods": "26"}), ["got '26'"]),
    # unknown or missing key in the table
    (spec_with(FORCED, "run", t_end={"periods": 26, "unit": "s"}),
     ["t_end = {periods = 26, unit = 's'} has unknown key 'unit'",
      "accepted: t_end = seconds, or t_end = { periods = k }"]),
    (spec_with(FORCED, "run", t_end={"per_period": 26}), ["unknown key 'per_period'"]),
    (spec_with(FORCED, "run", dt={"periods": 1000}),
     ["unknown key 'periods'", "dt = { per_period = N }"]),
    (spec_with(FORCED, "run", t_end={}), ["t_end = {} has no 'periods'"]),
    # a table for another key
    (spec_with(FORCED, "run", save_every={"periods": 1}),
     ["[run] save_every = {periods = 1}", "only for t0, t_end, t_transient",
      "save_every as a plain value"]),
])
def test_bad_periods_are_refused_naming_the_key_and_the_value(spec, words):
    _refused_in_one_line(spec, words, (ValueError, TypeError))


def test_an_unknown_run_key_given_as_a_table_is_an_unknown_key():
    with pytest.raises(ValueError, match=r"unknown key 'tend' in \[run\]"):
        parse_run(spec_with(FORCED, "run", tend={"periods": 2}), source="test.toml")


def test_the_cli_refuses_a_bad_count_in_one_line_and_writes_nothing(tmp_path):
    text = """\
[scene.forcing]
amplitude = 1.0
frequency = 1.0
[grid]
theta0 = [0.1]
[run]
t_end = { periods = 10 }
dt = { per_period = 0 }
"""
    output = tmp_path / "out.nc"
    code, out, err = call("run", write(tmp_path, text), "-o", output, "--no-progress")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("sweep: error: "), err
    assert "[run] dt = {per_period = 0}: per_period must be an integer >= 1" in err
    assert not output.exists()


# ---------------------------------------------------------------------- systems
PIVOTED = {"system": {"kind": "DoublePendulum", "pivot_amplitude": 0.1,
                      "pivot_frequency": 60.0},
           "grid": {"theta1_0": [0.1]},
           "run": {"t_end": {"periods": 800}, "dt": {"per_period": 40},
                   "t_transient": {"periods": 16}}}

CART = {"system": {"kind": "DeclaredSystem", "name": "driven",
                   "lagrangian": "v**2/2 - k*x**2/2 + a*x*cos(nu*t)",
                   "drive_frequency_axis": "nu",
                   "coordinates": [{"name": "x", "velocity": "v", "units": "m",
                                    "angular": False}],
                   "parameters": {"k": 1.0, "a": 0.5, "nu": 3.0}},
        "grid": {"x_0": [0.0, 1.0]},
        "run": {"t_end": {"periods": 5}, "dt": {"per_period": 50}}}


def test_a_systems_drive_sets_the_period():
    _, _, kwargs = parse_run(PIVOTED)
    period = 2 * math.pi / 60.0
    assert (kwargs["t_end"], kwargs["dt"], kwargs["t_transient"]) == (
        800 * period, period / 40, 16 * period)
    # examples/driven_double_pendulum_basins.toml's decimals before it said periods
    assert (kwargs["t_end"], kwargs["dt"]) == (83.7758040957278, 0.002617993877991494)
    _, _, kwargs = parse_run(CART)  # a declared system's drive_frequency_axis
    assert kwargs["t_end"] == 5 * (2 * math.pi / 3.0)
    assert kwargs["dt"] == (2 * math.pi / 3.0) / 50
    forced = {**PIVOTED, "system": {"kind": "DoublePendulum", "forcing": {
        "on": "theta2", "amplitude": 1.0, "frequency": 2.0}}}
    _, _, kwargs = parse_run(forced)  # a forcing on one coordinate
    assert kwargs["t_end"] == 800 * (2 * math.pi / 2.0)


@pytest.mark.parametrize("spec, words", [
    ({"system": {"kind": "DoublePendulum"}, "grid": {"theta1_0": [0.1]},
      "run": {"t_end": {"periods": 3}, "dt": 0.01}},
     ["[run] t_end = {periods = 3}", "no periodic drive", "pivot_frequency"]),
    (spec_with(PIVOTED, "system",
               forcing={"on": "theta1", "amplitude": 1.0, "frequency": 2.0}),
     ["different frequencies", "pivot_frequency = 60.0", "forcing_frequency_theta1 = 2.0"]),
    (spec_with(PIVOTED, "grid", pivot_frequency=[50.0, 60.0]),
     ["[grid] pivot_frequency has 2 values (50.0, 60.0)"]),
    (spec_with(CART, "grid", nu=[1.0, 2.0]), ["[grid] nu has 2 values"]),
])
def test_a_system_without_one_drive_frequency_is_refused(spec, words):
    _refused_in_one_line(spec, words)


def _refused_in_one_line(spec, words, errors=ValueError):
    """`parse_run` refuses ``spec`` in one line naming the file and every one of
    ``words``."""
    with pytest.raises(errors) as info:
        parse_run(spec, source="test.toml")
    message = str(info.value)
    assert message.startswith("test.toml: ") and "\n" not in message
    for word in words:
        assert word in message, message


def test_a_pivot_the_grid_switches_on_sets_the_period():
    # a DoublePendulum without pivot_amplitude, its pivot switched on by the [grid]'s
    # pivot_amplitude axis (as the run does it): the pivot's frequency is the drive's
    spec = {"system": {"kind": "DoublePendulum"},
            "grid": {"theta1_0": [0.1], "pivot_amplitude": [0.01, 0.02],
                     "pivot_frequency": [60.0]},
            "run": {"t_end": {"periods": 3}, "dt": {"per_period": 40},
                    "observe": ["strobe"]}}
    _, _, kwargs = parse_run(spec)
    period = 2 * math.pi / 60.0
    assert (kwargs["t_end"], kwargs["dt"]) == (3 * period, period / 40)


# ------------------------------------------------------------- writing periods back
#: The shipped driven examples, each with its times in periods.
DRIVEN_EXAMPLES = ["forced.toml", "wada_map.toml", "points.toml", "wada_sample.toml",
                   "driven_double_pendulum_basins.toml"]

TIMES = ("t0", "t_end", "dt", "t_transient")


def written_again(spec: dict, kwargs: dict, scene, grid,
                  options: dict | None = None) -> tuple[str, dict]:
    """The ``[run]`` text `run_lines` writes of ``kwargs``, and the `sweep.run` keyword
    arguments `parse_run` reads back from ``spec`` with that ``[run]`` (and the file's
    ``options``, `load_run`'s: a pilot)."""
    text = "\n".join(run_lines(kwargs, scene, grid, _toml_value)) + "\n"
    _, _, again = parse_run({**spec, "run": {**(options or {}), **tomllib.loads(text)}})
    return text, again


def same_floats(again: dict, kwargs: dict) -> None:
    """Every time of ``kwargs`` read back as the very same float64 (its bits)."""
    for key in TIMES:
        if key in kwargs:
            assert float(again[key]).hex() == float(kwargs[key]).hex(), key


@pytest.mark.parametrize("name", DRIVEN_EXAMPLES)
def test_a_written_driven_run_gives_its_times_in_periods_and_reads_back_bit_for_bit(name):
    path = f"examples/{name}"
    with open(path, "rb") as file:
        spec = tomllib.load(file)
    options = {}
    scene, grid, kwargs = load_run(path, options)
    text, again = written_again(spec, kwargs, scene, grid, options)
    same_floats(again, kwargs)
    for key in TIMES:  # the file's own tables come back, the seconds in a comment
        value = spec["run"].get(key)
        if isinstance(value, dict):
            assert f"{key} = {_toml_value(value)}  # {kwargs[key]!r} s\n" in text, text
    assert "t_end = {periods = " in text and "dt = {per_period = " in text


def test_times_that_are_not_whole_periods_stay_seconds():
    period = 2 * math.pi / W
    # t_end one float above 26 periods, t_transient 2.5 periods: seconds; dt a period's
    # 1000th: per_period; t0 = 0: seconds
    spec = spec_with(FORCED, "run", t0=0.0, t_end=math.nextafter(26 * period, math.inf),
                     dt={"per_period": 1000}, t_transient=2.5 * period)
    scene, grid, kwargs = parse_run(spec)
    text, again = written_again(spec, kwargs, scene, grid)
    assert text.splitlines()[:4] == [
        "t0 = 0.0", f"t_end = {kwargs['t_end']!r}",
        f"dt = {{per_period = 1000}}  # {kwargs['dt']!r} s",
        f"t_transient = {kwargs['t_transient']!r}"], text
    same_floats(again, kwargs)
    # seconds 0.01 (not a period's divisor), a step one float off one; t0 a negative
    # count of periods
    for dt in (0.01, math.nextafter(period / 1000, 0.0)):
        kwargs = dict(kwargs, dt=dt, t0=-3 * period)
        assert in_periods(kwargs, scene, grid) == {"t0": {"periods": -3}}


@pytest.mark.parametrize("spec", [
    # no drive: an unforced run's file is as before
    {"scene": {"damping": {"coefficient": 0.5}}, "grid": {"theta0": [0.1]},
     "run": {"t_end": 2 * math.pi, "dt": 2 * math.pi / 100}},
    # the drive frequency swept: no one period
    {**spec_with(FORCED, "grid", forcing_frequency=[W, 1.0]),
     "run": {"t_end": 26 * (2 * math.pi / W), "dt": 2 * math.pi / W / 1000}},
    # a system without a drive
    {"system": {"kind": "DoublePendulum"}, "grid": {"theta1_0": [0.1]},
     "run": {"t_end": 2 * math.pi, "dt": 2 * math.pi / 100}},
])
def test_a_run_without_one_drive_frequency_is_written_in_seconds(spec):
    scene, grid, kwargs = parse_run(spec)
    lines = run_lines(kwargs, scene, grid, _toml_value)
    assert lines == [f"{key} = {_toml_value(value)}" for key, value in kwargs.items()]
    assert in_periods(kwargs, scene, grid) == {}
