"""Run files that declare their own system (``[system] kind = "DeclaredSystem"``,
`sweep.toml_declared`): the shipped example through ``sweep run`` and ``sweep plot`` in
a child process, against the same system built in Python and against SciPy's DOP853;
bad declarations refused in one line before any compute."""

from __future__ import annotations

import copy
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import sweep
from sweep.physics import Coordinate, Parameter, SystemDeclaration
from sweep.toml_spec import load_run, parse_run

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "pendulum_on_cart.toml"


def cart_in_python() -> SystemDeclaration:
    """The example's declaration written by hand with the documented kernel symbols
    (``u_<name>``, `sweep.toml_declared.kernel_symbol`)."""
    def parameter(name, units, long_name, minimum=0.0):  # values: the system's, no default
        return Parameter(name, name, f"u_{name}", units, units, long_name, minimum=minimum)
    return SystemDeclaration(
        name="pendulum_on_cart",
        coordinates=(Coordinate("theta", "omega", "u_theta", "u_omega",
                                long_name="pendulum angle"),
                     Coordinate("x", "v", "u_x", "u_v", units="m", velocity_units="m s-1",
                                long_name="cart position", angular=False)),
        parameters=(parameter("M", "kg", "cart mass"),
                    parameter("m", "kg", "bob mass"),
                    parameter("l", "m", "rod length"),
                    parameter("g", "m s-2", "gravity", minimum=None),
                    parameter("k", "N m-1", "spring constant"),
                    parameter("b", "N m s", "joint damping")),
        lagrangian="(u_M + u_m) * u_v ** 2 / 2 + u_m * u_l * u_v * u_omega * cos(u_theta) + "
                   "u_m * u_l ** 2 * u_omega ** 2 / 2 - u_k * u_x ** 2 / 2 + "
                   "u_m * u_g * u_l * cos(u_theta)",
        forces=("-u_b * u_omega", "0"))


def sweep_cli(*argv) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sweep", *map(str, argv)],
                          capture_output=True, text=True, timeout=600, check=False)


def test_the_shipped_example_runs_and_plots_through_the_cli_as_python_does(tmp_path):
    output, image = tmp_path / "cart.nc", tmp_path / "cart.png"
    result = sweep_cli("run", EXAMPLE, "-o", output, "--no-progress")
    assert result.returncode == 0, result.stderr
    result = sweep_cli("plot", output, "--var", "x_final", "-o", image)
    assert result.returncode == 0, result.stderr
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ds = sweep.load(output)
    assert ds.sizes == {"theta_0": 81, "k": 60}
    np.testing.assert_allclose(ds.theta_0, np.deg2rad(np.linspace(-170, 170, 81)))
    # the oracle: the same declaration built in Python, run on the same axes
    system = sweep.DeclaredSystem(cart_in_python(), M=2.0, m=1.0, l=1.0, g=9.81, k=20.0,
                                  b=0.1)
    assert system.declaration == load_run(EXAMPLE)[0].declaration
    expected = sweep.run(system, sweep.Grid(theta_0=ds.theta_0.values, k=ds.k.values),
                         t_end=20.0, dt=0.005, observe=("final", "energy"), progress=False)
    assert set(expected.data_vars) == set(ds.data_vars)
    for name in expected.data_vars:
        np.testing.assert_array_equal(ds[name].values, expected[name].values)
    assert ds.x_final.attrs["units"] == "m"


def cart_rhs(M, m, l, g, k, b):  # noqa: E741 - the rod length, as in the run file
    """The example's equations by hand: (M+m) v' + m l cos(q) w' = m l w^2 sin(q) - k x,
    m l cos(q) v' + m l^2 w' = -m g l sin(q) - b w, solved for (w', v')."""
    def rhs(_t, y):
        q, x, w, v = y
        c, s = np.cos(q), np.sin(q)
        a11, a12, a22 = m * l * l, m * l * c, M + m
        r1, r2 = -m * g * l * s - b * w, m * l * w * w * s - k * x
        det = a11 * a22 - a12 * a12
        return [w, v, (a22 * r1 - a12 * r2) / det, (a11 * r2 - a12 * r1) / det]
    return rhs


def test_the_run_file_system_follows_scipy_dop853():
    from scipy.integrate import solve_ivp

    system, _, _ = load_run(EXAMPLE)
    starts = [(2.5, 0.1, 5.0), (-0.7, -0.2, 40.0)]  # theta_0 [rad], x_0 [m], k [N/m]
    ds = sweep.run(system, sweep.Points(theta_0=[s[0] for s in starts],
                                        x_0=[s[1] for s in starts],
                                        k=[s[2] for s in starts]),
                   t_end=4.0, dt=1e-3, observe=("final",), progress=False)
    for i, (theta0, x0, k) in enumerate(starts):
        ref = solve_ivp(cart_rhs(2.0, 1.0, 1.0, 9.81, k, 0.1), (0.0, 4.0),
                        [theta0, x0, 0.0, 0.0], method="DOP853", rtol=1e-12,
                        atol=1e-12).y[:, -1]
        got = [float(ds[name].values[i]) for name in ("theta_final", "x_final",
                                                       "omega_final", "v_final")]
        # RK4 at dt = 1e-3 over 4 s: global error ~ t dt^4 |y^(5)| ~ 1e-9 for these
        # frequencies (<= 6 rad/s); 1e-7 leaves margin and is far below any wrong term
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-7)



def test_effects_on_its_coordinates_are_read_and_written_back():
    """A declared system takes the effects on one coordinate as every system does
    (``[system.<effect>]`` with ``on``; ``[[system.<effect>]]`` for several), and the
    explorer's run file of it (`sweep.toml_spec.system_effects_lines`) reads back the
    same system; a torque on the cart in N is the same system as in Python."""
    from sweep.explore.systems import _system_toml
    from sweep.explore.texts import toml_value as _toml_value
    from sweep.toml_effects import system_effects_lines

    spec = copy.deepcopy(spec_of_example())
    spec["system"]["torque"] = {"value": 0.5, "on": "x"}
    spec["system"]["damping"] = [{"coefficient": 0.2, "on": "x"},
                                 {"coefficient": 0.05, "on": "theta"}]
    system = parse_run(spec, "run.toml")[0]
    assert sorted(map(repr, system.effects)) == sorted(map(repr, (
        sweep.Damping(0.2, on="x"), sweep.Damping(0.05, on="theta"), sweep.Torque(0.5, on="x"))))
    assert system.parameters()["torque_x"] == 0.5
    lines = system_effects_lines(system.effects, _toml_value)
    assert lines.count("[[system.damping]]") == 2 and "[system.torque]" in lines
    text = "\n".join(_system_toml(system))
    back = parse_run(tomllib.loads(text + "\n\n[grid]\ntheta_0 = [0.1]\n\n[run]\n"
                                   "t_end = 1.0\ndt = 0.01\n"), "back.toml")[0]
    assert back == system

def spec_of_example() -> dict:
    with open(EXAMPLE, "rb") as handle:
        return tomllib.load(handle)


def _set(path: str, value):
    def change(spec):
        *keys, last = path.split("/")
        node = spec
        for key in keys:
            node = node[int(key)] if isinstance(node, list) else node[key]
        if value is _DELETE:
            del node[last]
        else:
            node[last] = value
    return change


_DELETE = object()


@pytest.mark.parametrize("change, match", [
    (_set("system/lagrangian", "m*l**2*omega**2/2 + v**2/2 + mystery*cos(theta)"),
     r"\[system\] the lagrangian, .*names 'mystery', which is no coordinate, velocity or "
     r"parameter; accepted: theta, omega, x, v, M, m, l, g, k, b, t, pi"),
    (_set("system/lagrangian", "m*l**2*omega**2/2 - k*x**2/2"),
     r"^run.toml: system 'test_bad_cart': the lagrangian has no kinetic term in v "),
    (_set("system/lagrangian", "(omega + v)**2/2 - k*x**2/2 + g*cos(theta)"),
     r"^run.toml: system 'test_bad_cart': the mass matrix .* is singular"),
    (_set("system/coordinates/1/name", "theta"),
     r"\[system\] the name 'theta' is given twice \(by coordinate 'theta' and coordinate "
     r"'theta'\)"),
    (_set("system/parameters/omega", 1.0), r"the name 'omega' is given twice"),
    (_set("system/coordinates/0/force", "-b*omega*__import__('os')"),
     r"force on 'theta', \"-b\*omega\*__import__\('os'\)\", calls '__import__'"),
    (_set("system/lagrangian", "v**2/2 + omega**2/2 + exp(theta)"),
     r"the lagrangian, .* calls 'exp'; accepted: the functions sin, cos, sqrt"),
    (_set("system/coordinates/1/units", _DELETE), r"'x'\) is not angular and gives no units"),
    (_set("system/coordinates/0/name", "t"), r"coordinates\[0\] name = 't'; accepted: an "
                                             r"identifier"),
    (_set("system/parameters/k", {"value": -1.0, "minimum": 0.0}), r"k.*-1"),
    (_set("system/parameters/k", {"units": "N m-1"}), r"parameters.k needs value"),
    (_set("system/coordinates/1/acceleration", "-k*x"),
     r"either lagrangian .* or an acceleration .* in every \[\[system.coordinates\]\] "
     r"table; got both \(accelerations on 1 of 2 coordinates\)"),
    (_set("system/lagrangian", _DELETE),
     r"either lagrangian .*; got neither \(accelerations on 0 of 2 coordinates\)"),
    (_set("system/mass", 1.0), r"unknown key 'mass'; accepted for DeclaredSystem: kind, "
                               r"name, lagrangian"),
    (_set("grid", {"y_0": [0.0]}), r"unknown key 'y_0' in \[grid\]; accepted: theta_0"),
])
def test_bad_declarations_are_refused_naming_the_table(change, match):
    spec = copy.deepcopy(spec_of_example())
    spec["system"]["name"] = "test_bad_cart"  # not the example's: another declaration
    change(spec)
    with pytest.raises((ValueError, TypeError), match=match):
        parse_run(spec, source="run.toml")


def test_a_bad_declaration_is_one_line_from_the_cli_before_any_compute(tmp_path):
    text = EXAMPLE.read_text().replace("- k*x**2/2", "- kk*x**2/2")
    bad, output = tmp_path / "bad.toml", tmp_path / "out.nc"
    bad.write_text(text)
    result = sweep_cli("run", bad, "-o", output)
    assert result.returncode == 2 and result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sweep: error: "), result.stderr
    assert "names 'kk'" in lines[0] and "Traceback" not in result.stderr
    assert not output.exists()


#: Two uncoupled forced pendula declared in a run file by their accelerations (as
#: tests/test_system_strobe.py's in Python), driven at W = 0.75 rad/s.
DRIVEN = """\
[system]
kind = "DeclaredSystem"
name = "test_two_forced_pendula_run_file"
drive_frequency_axis = "W"
[[system.coordinates]]
name = "p1"
velocity = "v1"
acceleration = "-sin(p1) - c*v1 + A*cos(W*t)"
[[system.coordinates]]
name = "p2"
velocity = "v2"
acceleration = "-sin(p2) - c*v2 + A*cos(W*t)"
[system.parameters]
c = {value = 0.15, units = "s-1"}
A = {value = 0.3, units = "s-2"}
W = {value = 0.75, units = "rad s-1"}

[grid]
p1_0 = [-1.0, 1.0]
p2_0 = [-1.0, 1.0]
damping_p1 = 0.1

[run]
t_end = 502.6548245743669
dt = 0.08377580409572781
observe = ["attractor"]
stop_early = true
pilot = 2
"""


def test_a_declared_system_names_its_drive_for_a_pilot_catalogue():
    """``drive_frequency_axis = "W"`` in ``[system]``: the declared system is driven at
    its parameter W (the strobe's and the catalogue's period 2 pi / W), so ``[run]
    pilot`` is accepted, also with an effect the grid switches on (``damping_p1``);
    the explorer's run file of it (`sweep.toml_declared.system_lines`) reads back the
    same system. Without it the pilot is refused as for an undriven system; a name that
    is no parameter, or not a string, is refused naming the key. Nothing is compiled."""
    from sweep.explore.systems import _system_toml

    options = {}
    system, grid, kwargs = parse_run(tomllib.loads(DRIVEN), "run.toml", options)
    assert system.drive_frequency_parameter.axis == "W"
    assert options == {"pilot": 2} and kwargs["observe"] == ("attractor",)
    assert grid.axes["damping_p1"].tolist() == [0.1]  # an effect the grid switches on
    text = "\n".join(_system_toml(system))
    assert 'drive_frequency_axis = "W"' in text
    back = parse_run(tomllib.loads(text + "\n\n[grid]\np1_0 = [0.1]\n\n[run]\nt_end = 1.0"
                                   "\ndt = 0.01\n"), "back.toml")[0]
    assert back == system
    for old, new, match in [
            ('drive_frequency_axis = "W"\n', "", r"^run.toml: \[run\] pilot = 2 catalogues "
             r"the attractors of a driven system .* this test_two_forced_pendula_run_file has "
             r"no periodic drive"),
            ('drive_frequency_axis = "W"', 'drive_frequency_axis = "Q"',
             r"\[system\] .*drive_frequency_axis = 'Q' names no parameter; accepted: None or "
             r"one of 'c', 'A', 'W'"),
            ('drive_frequency_axis = "W"', "drive_frequency_axis = 1",
             r"\[system\] drive_frequency_axis = 1; accepted: the name of the parameter")]:
        with pytest.raises((ValueError, TypeError), match=match):
            parse_run(tomllib.loads(DRIVEN.replace(old, new)), "run.toml")
