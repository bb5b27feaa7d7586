"""The explorer's model for systems with several coordinates (sweep.explore.systems; no
browser): quantities from the system's observables, maps equal to sweep.run cell by
cell, controls from the declaration, clicked trajectories of every coordinate, refused
input, and the snippets that reproduce a map."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sweep
from sweep import maps
from sweep.explore.model import InvalidInput, centres
from sweep.explore.networks import NetworkExplorer, explorer_for
from sweep.explore.systems import SystemExplorer, SystemTrajectory
from sweep.physics.system import SYSTEM_DAMPING
from sweep.system_observables import SYSTEM_OBSERVABLES, variables
from sweep.toml_spec import load_run

N = 12  # pixels per axis: small maps, the code paths are those of 400 x 400
RUN = dict(t_end=3.0, dt=0.01)  # 300 steps: flips and chaos already differ between starts


def double(system=None, **extra):
    system = system or sweep.DoublePendulum()
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, N), theta2_0=np.linspace(-3, 3, N))
    return SystemExplorer(system, grid, resolution=N, **RUN, **extra)


def reference(e, state=None, **kwargs):
    """`sweep.run` of ``state``'s window, written out by hand (not with the explorer's
    `grid`): rows y, columns x, the start's other values as one-value axes."""
    s = state or e.state
    v = s.view
    axes = {v.y: centres(*v.y_range, s.resolution), v.x: centres(*v.x_range, s.resolution)}
    axes.update({n: [value] for n, value in s.start if n not in axes})
    return sweep.run(s.scene, sweep.Grid(**axes), t_end=s.t_end, dt=s.dt, progress=False,
                     **kwargs)


def plane(da, y="theta2_0", x="theta1_0"):
    """``da`` as the map's (y, x) array (one-value axes dropped)."""
    return da.squeeze([d for d in da.dims if d not in (x, y)]).transpose(y, x).values


def test_quantities_are_the_variables_of_the_system_observables():
    e = double()
    # every variable of one value per start (not strobe's sequence: it is no map; not
    # attractor, which needs an attractor catalogue)
    expected = {f"var:{name}" for o, observable in SYSTEM_OBSERVABLES.items()
                if not observable.sampled and o != "attractor"
                for name, _, _ in variables(o, sweep.DoublePendulum().declaration.coordinates,
                                            "J")}
    assert set(e.quantities()) == expected | {"log10:flip_time"}
    assert "var:theta1_strobe" not in e.quantities()
    assert "var:attractor" not in e.quantities()
    assert {"var:theta1_final", "var:omega2_final", "var:energy_final", "var:lyapunov_max",
            "var:winding_theta2", "var:flip_time"} <= set(e.quantities())
    assert e.state.quantity == "log10:flip_time"  # the double pendulum's best known map
    # three pendula: the third coordinate's variables, from the same observables
    three = SystemExplorer(sweep.CoupledPendula(3), sweep.Grid(
        theta1_0=np.linspace(-1, 1, N), theta3_0=np.linspace(-1, 1, N)), resolution=N, **RUN)
    assert {"var:theta3_final", "var:omega3_final", "var:winding_theta3"} <= \
        set(three.quantities())
    assert (three.state.view.x, three.state.view.y) == ("theta1_0", "theta3_0")


@pytest.mark.parametrize("quantity, observe, stop_early", [
    ("log10:flip_time", ("flip",), True),
    ("var:theta2_final", ("final",), False),
    ("var:energy_final", ("energy",), False),
])
def test_a_zoomed_map_is_sweep_run_of_the_window_cell_by_cell(quantity, observe, stop_early):
    e = double()
    e.update(quantity=quantity)
    e.zoom((-1.0, 2.5), (0.5, 2.9))
    result = e.compute()
    ds = reference(e, observe=observe, stop_early=stop_early)
    name = quantity.split(":")[1]
    expected = plane(ds[name])
    if quantity.startswith("log10:"):
        expected = np.log10(expected)
    assert result.values.shape == (N, N)
    np.testing.assert_array_equal(result.x, centres(-1.0, 2.5, N))
    # the same kernel on the same floats: equal to the bit (NaN where no arm flipped)
    np.testing.assert_array_equal(result.values, expected)
    assert np.isfinite(result.values).any()


def test_a_log10_map_is_labelled_in_log10_units_not_seconds():
    """The flip map is the log10 of a time: its title, colour bar and long name give
    log10(s), never "[s]" (a log10 has no unit of seconds)."""
    e = double()
    result = e.compute()
    label = e.quantities()["log10:flip_time"]
    assert label == "flip: log10 of the time of the first flip [log10(s)]"
    assert result.title == "log10_flip_time [log10(s)]"
    assert result.da.attrs["units"] == "1"  # the DataArray's: dimensionless (CF)
    assert result.description == "log10 of the time of the first flip [log10(s)]"
    assert "[s]" not in label + result.title + result.description


def test_a_click_on_a_continuous_map_gives_its_value_name_and_units():
    """The clicked start's log10 flip time is a value with its name and units, not a
    label; a map's NaN (no flip before t_end) reads NaN."""
    e = double()
    result = e.compute()
    row, col = np.argwhere(np.isfinite(result.values))[0]
    value = result.values[row, col]
    assert e.label_at(result, row, col) == f"log10_flip_time = {value:.6g} log10(s)"
    rows, cols = np.nonzero(np.isnan(result.values))
    assert e.label_at(result, rows[0], cols[0]) == "log10_flip_time = NaN"  # no units
    e.update(quantity="var:theta2_final")
    result = e.compute()
    assert e.label_at(result, 0, 0) == f"theta2_final = {result.values[0, 0]:.6g} rad"


def test_the_caption_says_what_the_grey_cells_are():
    """Cells that never flipped are NaN, drawn dark grey with no colour-bar entry: the
    caption says so after the meaning of NaN; a map without NaN says nothing of it."""
    e = double()
    result = e.compute()
    assert np.isnan(result.values).any()
    assert result.caption.endswith("NaN where none flipped before t\\_end; "
                                   "grey on the map: NaN")
    e.update(quantity="var:theta2_final")
    result = e.compute()
    assert not np.isnan(result.values).any() and "grey" not in result.caption


def test_the_map_over_a_parameter_axis():
    e = double()
    e.update(x="mass2", quantity="var:theta1_final")
    v = e.state.view
    assert (v.x, v.x_range) == ("mass2", (0.5, 1.5))  # the default: value x (1/2, 3/2)
    result = e.compute()
    ds = reference(e, observe=("final",))
    np.testing.assert_array_equal(result.values,
                                  plane(ds.theta1_final, v.y, "mass2"))


def test_controls_are_the_declaration_parameters_with_units_and_bounds():
    e = double()
    controls = {c.name: c for c in e.parameter_controls()}
    declared = sweep.DoublePendulum().declaration.parameters
    assert [c for c in controls if c not in ("omega1_0", "omega2_0")] == \
        [p.axis for p in declared] + ["damping"]
    for p in (*declared, SYSTEM_DAMPING):
        c = controls[p.axis]
        assert (c.minimum, c.strict) == (p.minimum, p.strict)
        assert c.label == f"{p.axis} [{p.unit_text}]"
    assert controls["mass2"].label == "mass2 [kg]" and controls["mass2"].value == 1.0
    # the starts not on the map's axes, in their units
    assert controls["omega1_0"].label == "omega1_0 [rad/s]"
    assert "theta1_0" not in controls  # on the map's axis
    assert "model" not in {c.name for c in e.run_controls()}


def test_a_parameter_change_recomputes_the_map_of_the_new_system():
    e = double()
    e.update(quantity="var:theta1_final")
    before = e.compute()
    e.update(mass2=2.5)
    assert e.state.scene == sweep.DoublePendulum(mass2=2.5)
    after = e.compute()
    assert not np.array_equal(after.values, before.values, equal_nan=True)
    ds = reference(e, observe=("final",))
    np.testing.assert_array_equal(after.values,
                                  plane(ds.theta1_final))
    # damping from its control: the energy falls
    e.update(quantity="var:energy_final", damping=0.5)
    assert e.state.scene.damping == 0.5
    damped = e.compute().values
    e.update(damping=0.0)
    assert e.state.scene.effects == ()
    free = e.compute().values
    assert (damped < free).all()
    # a start value from its control
    e.update(omega1_0=1.5)
    assert dict(e.state.start)["omega1_0"] == 1.5


def test_a_click_gives_every_coordinate_of_that_start_over_time():
    e = double()
    e.update(quantity="var:theta2_final")
    result = e.compute()
    traj = e.trajectory(0.9, -1.2, result)
    assert isinstance(traj, SystemTrajectory)
    row, col = e.value_at(result, 0.9, -1.2)
    x, y = result.x[col], result.y[row]
    assert traj.point == {"theta1_0": x, "theta2_0": y}
    assert traj.start == {"theta1_0": x, "theta2_0": y, "omega1_0": 0.0, "omega2_0": 0.0}
    assert list(traj.series) == ["theta1", "theta2", "omega1", "omega2"]
    assert traj.units == {"theta1": "rad", "theta2": "rad", "omega1": "rad s-1",
                          "omega2": "rad s-1"}
    ds = sweep.run(sweep.DoublePendulum(), sweep.Grid(theta1_0=[x], theta2_0=[y]),
                   save_every=1, observe=("final",), progress=False, **RUN)
    np.testing.assert_array_equal(traj.t, ds.time.values)
    for name in traj.series:
        np.testing.assert_array_equal(traj.series[name], ds[name].values.ravel())
    # the clicked pixel's map value is that trajectory's end
    assert traj.series["theta2"][-1] == result.values[row, col]
    assert traj.status == "ok" and "theta2_final" in traj.label
    assert "sweep.DoublePendulum(" in traj.python and "[system]" in traj.toml



def test_the_trajectory_title_gives_the_start_in_rad_and_degrees():
    """The page's trajectory title (a session without a browser): the clicked start in
    rad and in degrees as the map's axes, not a bare number; the controls' heading."""
    pytest.importorskip("panel")
    from sweep.explore.system_app import SystemExplorerApp, _SystemSession

    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, N), theta2_0=np.linspace(-3, 3, N))
    page = _SystemSession(SystemExplorerApp(sweep.DoublePendulum(), grid, resolution=N,
                                            **RUN))
    try:
        result = page.explorer.compute()
        page.result = result
        traj = page.explorer.trajectory(0.9, -1.2, result)
        page.show_trajectory(traj)
        x, y = traj.point["theta1_0"], traj.point["theta2_0"]
        assert page.trajectory.title.text == (
            f"trajectory from theta1_0 = {x:.6g} rad ({np.degrees(x):.4g} deg),\n"
            f"theta2_0 = {y:.6g} rad ({np.degrees(y):.4g} deg)")
        assert page.info.object.startswith(f"**start** theta1_0 = {x:.6g} rad (")
        # the system's controls are headed "System" (a double pendulum is no Scene)
        import panel as pn

        headings = [m.object for m in page.layout.select(pn.pane.Markdown)
                    if str(m.object).startswith("### ")]
        assert "### System" in headings and "### Scene" not in headings
    finally:
        page.requests.close()


def test_effects_on_one_coordinate_are_controls_and_change_the_map(tmp_path):
    """A system's effects on one coordinate (``damping_theta1``, ``torque_theta2``) are
    controls with their generalized force's units; a change recomputes the map of the
    system with the new value (cell by cell sweep.run's), the other effects kept, and
    the run file the page offers reproduces it."""
    system = sweep.DoublePendulum(effects=(sweep.Damping(0.1, on="theta1"),
                                           sweep.Torque(0.3, on="theta2")))
    e = double(system)
    controls = {c.name: c for c in e.parameter_controls()}
    assert controls["damping_theta1"].label == "damping_theta1 [N m s]"
    assert controls["torque_theta2"].label == "torque_theta2 [N m]"
    assert controls["torque_theta2"].value == 0.3
    e.update(quantity="var:theta1_final")
    before = e.compute()
    e.update(torque_theta2=2.0)
    assert e.state.scene == sweep.DoublePendulum(effects=(
        sweep.Damping(0.1, on="theta1"), sweep.Torque(2.0, on="theta2")))
    after = e.compute()
    assert not np.array_equal(after.values, before.values, equal_nan=True)
    np.testing.assert_array_equal(after.values, plane(reference(e, observe=("final",))
                                                      .theta1_final))
    path = tmp_path / "map.toml"
    path.write_text(e.toml_text())
    assert load_run(path, {})[0] == e.state.scene
    with pytest.raises(InvalidInput, match="finite"):
        e.update(damping_theta1=float("nan"))

def test_the_run_file_of_a_driven_system_counts_drive_periods(tmp_path):
    """A driven system's download gives examples/driven_double_pendulum_basins.toml's
    times back in drive periods (`sweep.toml_periods.run_lines`), the seconds in a
    comment, and reads back as the very same floats. Nothing is computed."""
    options = {}
    system, grid, kwargs = load_run("examples/driven_double_pendulum_basins.toml", options)
    e = SystemExplorer(system, grid, resolution=N, **kwargs)
    text = e.toml_text()
    assert "\nt_end = {periods = 800}  # 83.7758040957278 s\n" in text, text
    assert "\ndt = {per_period = 40}  # 0.002617993877991494 s\n" in text, text
    path = tmp_path / "map.toml"
    path.write_text(text)
    _, _, again = load_run(path, {})
    for key in ("t_end", "dt"):
        assert again[key].hex() == kwargs[key].hex(), key  # the same bits


def test_the_run_file_and_python_reproduce_the_map(tmp_path):
    e = double(sweep.DoublePendulum(mass1=2.0, effects=(sweep.Damping(0.1),)))
    e.zoom((0.0, 2.0), (-2.0, 0.0))
    result = e.compute()
    path = tmp_path / "map.toml"
    path.write_text(e.toml_text())
    system, grid, kwargs = load_run(path, {})
    assert system == e.state.scene
    ds = sweep.run(system, grid, progress=False, **kwargs)
    np.testing.assert_array_equal(np.log10(plane(ds.flip_time)),
                                  result.values)
    scope = {}
    exec(e.python_snippet(), scope)  # the snippet the page shows
    np.testing.assert_array_equal(plane(scope["image"]),
                                  result.values)


def test_explore_and_the_command_line_take_a_system(monkeypatch, capsys):
    pytest.importorskip("panel")
    from sweep.cli import main
    from sweep.explore import app as app_module
    from sweep.explore.system_app import NetworkExplorerApp, SystemExplorerApp

    opened = []
    monkeypatch.setattr(app_module, "main_serve",
                        lambda app, **kwargs: opened.append(app) or 0)
    assert main(["explore", "examples/double_pendulum.toml", "--no-browser"]) == 0
    (app,) = opened
    assert isinstance(app, SystemExplorerApp)
    s = app.template.state
    assert (s.view.x, s.view.y, s.quantity) == ("theta1_0", "theta2_0", "log10:flip_time")
    assert isinstance(sweep.explore(sweep.CoupledPendula(2), sweep.Grid(
        theta1_0=np.linspace(-1, 1, N), theta2_0=np.linspace(-1, 1, N)), **RUN),
        SystemExplorerApp)
    network = sweep.SwingNetwork([(0, 1)], power=[1.0, -1.0], damping=0.1, coupling=4.0)
    assert isinstance(sweep.explore(network, sweep.Grid(delta_theta=[0.0, 1.0],
                                                        delta_omega=[0.0, 1.0]), **RUN),
                      NetworkExplorerApp)


@pytest.mark.parametrize("make, words", [
    (lambda: double().update(x="theta0"), ["theta0", "theta1_0"]),
    (lambda: double().update(mass1=-1.0), ["mass1", "-1.0"]),
    (lambda: double().update(quantity="well"), ["well", "var:theta1_final"]),
    (lambda: double().update(model="linear"), ["model", "mass1"]),
    (lambda: double().update(method="rk45"), ["rk45", "rk4"]),
    (lambda: SystemExplorer(sweep.DoublePendulum(), sweep.Grid(
        theta0=np.linspace(-1, 1, N), theta2_0=np.linspace(-1, 1, N)), **RUN),
     ["theta0", "DoublePendulum", "theta1_0"]),
    (lambda: SystemExplorer(sweep.DoublePendulum(), sweep.Grid(
        theta1_0=np.linspace(-1, 1, N), theta3_0=np.linspace(-1, 1, N)), **RUN),
     ["theta3_0", "theta2_0"]),
    (lambda: SystemExplorer(sweep.DoublePendulum(), sweep.Grid(
        theta1_0=np.linspace(-1, 1, N), theta2_0=np.linspace(-1, 1, N), theta0=[0.5]),
        **RUN), ["theta0", "omega1_0", "mass1"]),  # a one-value axis: every axis accepted
])
def test_bad_input_is_refused_naming_the_value_and_what_is_accepted(make, words):
    with pytest.raises(InvalidInput) as info:
        make()
    for word in words:
        assert word in str(info.value)


# ------------------------------------------------------------------ driven systems
#: The docs' double Kapitza pendulum (pivot a cos(nu t), a = 0.1 m, nu = 60 rad/s),
#: damped harder (c = 2/s against the docs' 0.5) so that 100 drive periods (10.5 s,
#: 4000 steps) settle most starts: the 8 x 8 window below has 7 attractors and 32
#: unresolved starts, so it checks labels, their order and the unresolved ones.
DRIVEN = sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=60.0,
                              effects=(sweep.Damping(2.0),))
PERIOD = 2 * np.pi / 60.0  # s
DRIVEN_RUN = dict(t_end=100 * PERIOD, dt=PERIOD / 40)
#: Pixels per axis of the driven maps: 64 starts, one 16-lane kernel that the explorer's
#: exact route, the reference run and both snippets share (one compilation); the
#: catalogue route's pilot (21 x 21) and its stopping run take the 64-lane kernels that
#: tests/test_system_attractors.py compiles (the same declaration, another damping).
M = 8


def driven(system=DRIVEN, **extra):
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, M), theta2_0=np.linspace(-3, 3, M))
    return SystemExplorer(system, grid, resolution=M, **{**DRIVEN_RUN, **extra})


def test_a_driven_systems_basins_map_is_maps_basins_of_the_same_run(tmp_path):
    """The basins map of a driven double pendulum by the exact route (and its period
    map) equals `sweep.maps.basins` (`sweep.maps.period`) of `sweep.run` of the window's
    starts, cell by cell: the same kernel on the same floats gives the same samples to
    the bit, so the same labels (exact, unresolved ones included); the run file and the
    Python the page shows give them again."""
    e = driven(quantity="basins")
    assert list(e.quantities())[:2] == ["basins", "period"]
    assert e.state.quantity == "basins"
    e.update(route="exact")
    result = e.compute()
    assert result.route == f"exact route: {M * M} starts run to t_end"
    assert result.catalogue is None
    ds = reference(e, observe=("strobe",))
    expected = maps.basins(ds)
    np.testing.assert_array_equal(result.values, plane(expected))
    attractors = len(expected.attrs["attractor_period"])
    unresolved = int((result.values == -1).sum())
    assert attractors >= 2 and unresolved > 0  # the window has both
    # the legend: "unresolved" (drawn black) first, then each attractor with its period
    # and each angle's turns per drive period
    assert result.legend[0] == (-1.0, "unresolved")
    period = int(expected.attrs["attractor_period"][0])
    assert result.legend[1] == (0.0, f"attractor 0: period {period}, turns/period "
                                     "theta1 +0, theta2 +0")
    assert result.summary.startswith(f"{attractors} attractors; {unresolved} of {M * M} "
                                     "starts unresolved")
    # the period map of the same samples
    e.update(quantity="period")
    periods = e.compute()
    np.testing.assert_array_equal(periods.values, plane(maps.period(ds)))
    assert periods.summary.startswith("periods 1")
    # the snippets reproduce the basins map
    e.update(quantity="basins")
    scope = {}
    exec(e.python_snippet(), scope)  # the snippet the page shows
    np.testing.assert_array_equal(plane(scope["image"]), result.values)
    path = tmp_path / "basins.toml"
    path.write_text(e.toml_text())
    system, grid, kwargs = load_run(path, {})
    assert system == DRIVEN and tuple(kwargs["observe"]) == ("strobe",)
    again = maps.basins(sweep.run(system, grid, progress=False, **kwargs))
    np.testing.assert_array_equal(plane(again), result.values)
    pytest.importorskip("panel")
    from sweep.explore.app import _palette

    colours = _palette(result)  # categorical, the unresolved black as the pendulum's
    assert colours[0] == "#000000" and "#000000" not in colours[1:]
    assert len(set(colours[1:])) == len(colours) - 1


def test_every_kind_of_drive_offers_basins():
    """A forcing on one coordinate and a declared system's drive_frequency_axis are
    drives as the pivot is (no compute: the quantities and the run's checks)."""
    from test_system_strobe import _two_forced_pendula

    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    forced = sweep.DoublePendulum(effects=(sweep.Forcing(1.0, 2.0, on="theta1"),))
    e = driven(forced, quantity="basins", t_end=20 * np.pi, dt=np.pi / 200)  # W = 2/s
    assert {"basins", "period"} <= set(e.quantities())
    assert e.state.scene.drive_frequency_parameter.axis == "forcing_frequency_theta1"
    declared = sweep.DeclaredSystem(_two_forced_pendula(Coordinate, Parameter,
                                                        SystemDeclaration),
                                    drive_frequency_axis="frequency", frequency=0.75)
    e = SystemExplorer(declared, sweep.Grid(p1_0=np.linspace(-2.5, 2.5, M),
                                            p2_0=np.linspace(-2.5, 2.5, M)),
                       resolution=M, quantity="basins", t_end=60 * 2 * np.pi / 0.75,
                       dt=2 * np.pi / 75)
    assert e.run_kwargs()["observe"] == ("strobe",)



def test_a_run_file_of_a_driven_systems_basins_opens_on_its_basins():
    """`sweep explore examples/driven_double_pendulum_basins.toml` (observe attractor,
    a pilot) opens on the basins map, not on the flip time; an undriven system, or a
    driven one whose run observes neither attractor nor strobe, opens on the flip time
    (no compute: the explorer's first state)."""
    from pathlib import Path

    from sweep.explore.networks import explorer_for
    from sweep.toml_spec import load_run

    example = Path(__file__).resolve().parents[1] / "examples" / \
        "driven_double_pendulum_basins.toml"
    system, grid, kwargs = load_run(str(example), {})
    assert kwargs["observe"] == ("attractor",)
    assert explorer_for(system, grid, **kwargs).state.quantity == "basins"
    plain = {k: v for k, v in kwargs.items() if k not in ("observe", "stop_early")}
    assert explorer_for(system, grid, **plain).state.quantity == "log10:flip_time"
    assert double(observe=("strobe",)).state.quantity == "log10:flip_time"

@pytest.mark.parametrize("make, control, words", [
    # no drive: the map is refused, naming it, what would drive the system, what is offered
    (lambda: double().update(quantity="basins"), "quantity",
     ["'basins'", "pivot_frequency", "Forcing", "drive_frequency_axis", "var:theta1_final"]),
    (lambda: double(quantity="period"), "explore", ["'period'", "periodic drive"]),
    # a step that does not divide the drive period: sweep.run's message, with a dt that does
    (lambda: driven(quantity="basins", dt=100 * PERIOD / 1001), "explore",
     ["drive period", "not a whole number of steps", "e.g. dt = 0.0104719"]),
    (lambda: driven().update(dt=100 * PERIOD / 1001, quantity="basins"), "dt",
     ["drive period", "e.g. dt = "]),
    # fewer drive periods than strobe samples: every start would be unresolved
    (lambda: driven(quantity="basins", t_end=10 * PERIOD), "explore",
     ["t_end = 1.047", "reaches 11 of the strobe_samples = 16", "t_end >= 1.5708"]),
    (lambda: driven(quantity="period").update(t_transient=95 * PERIOD), "t_transient",
     ["reaches 6 of the strobe_samples = 16", "t_end >= 11.5192"]),
])
def test_driven_maps_refuse_what_cannot_give_them(make, control, words):
    with pytest.raises(InvalidInput) as info:
        make()
    assert info.value.control == control
    for word in words:
        assert word in str(info.value)


def test_explore_refuses_basins_of_an_undriven_system():
    pytest.importorskip("panel")
    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, N), theta2_0=np.linspace(-1, 1, N))
    with pytest.raises(InvalidInput, match="'basins' is not a map of DoublePendulum "
                                           r"\(a basins map reads the samples once per "
                                           "period of a periodic drive"):
        sweep.explore(sweep.DoublePendulum(), grid, quantity="basins", **RUN)


def test_strobe_samples_reach_only_the_maps_that_read_them():
    """strobe_samples given to the explorer goes to the driven maps' runs, not to the
    others (sweep.run refuses samples nothing reads)."""
    e = driven(strobe_samples=32)
    assert "strobe_samples" not in e.run_kwargs()  # the flip map
    e.update(quantity="basins")
    assert e.run_kwargs()["strobe_samples"] == 32


# ------------------------------------------------------------------ swing networks
def network_explorer(**extra):
    """The five-node ring with a dead end of docs/guide/systems.md, node 4 perturbed."""
    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 3), (3, 0), (0, 4)],
                                 power=[1, -1, 1, -1, 0], damping=0.1, coupling=8.0)
    grid = sweep.Grid(perturbed_node=[4], delta_theta=np.linspace(-np.pi, np.pi, N),
                      delta_omega=np.linspace(-15, 15, N))
    return explorer_for(network, grid, resolution=N, t_end=20.0, dt=0.01, **extra)


def test_a_network_map_is_sweep_run_of_one_node_perturbed(tmp_path):
    e = network_explorer()
    assert isinstance(e, NetworkExplorer)
    # the per-run variables of the network's observables, and the synchronized map
    assert set(e.quantities()) == {"var:frequency_spread", "var:order_parameter",
                                   "synchronized"}
    s = e.state
    assert (s.view.x, s.view.y, s.quantity) == ("delta_theta", "delta_omega", "synchronized")
    assert dict(s.start)["perturbed_node"] == 4
    result = e.compute()
    ds = reference(e, observe=("synchrony",))
    expected = plane(sweep.maps.synchronized(ds), "delta_omega", "delta_theta")
    np.testing.assert_array_equal(result.values, expected)
    assert set(np.unique(result.values)) == {0, 1}  # this window has both
    # the run file reproduces it
    path = tmp_path / "network.toml"
    path.write_text(e.toml_text())
    network, grid, kwargs = load_run(path, {})
    again = sweep.maps.synchronized(sweep.run(network, grid, progress=False, **kwargs))
    np.testing.assert_array_equal(plane(again, "delta_omega", "delta_theta"), result.values)


def test_network_controls_change_the_map_and_a_click_gives_every_node():
    e = network_explorer()
    controls = {c.name: c for c in e.parameter_controls()}
    assert list(controls) == ["damping", "coupling", "perturbed_node"]
    assert controls["coupling"].label == "coupling [1/s^2]" and controls["coupling"].strict
    e.update(quantity="var:frequency_spread")
    before = e.compute().values
    e.update(perturbed_node=1)
    assert e.state.scene.coupling == 8.0 and dict(e.state.start)["perturbed_node"] == 1
    other_node = e.compute().values
    assert not np.array_equal(other_node, before)
    e.update(coupling=6.0)
    assert e.state.scene.coupling == 6.0
    weaker = e.compute()
    assert not np.array_equal(weaker.values, other_node)
    np.testing.assert_array_equal(weaker.values, plane(reference(
        e, observe=("synchrony",)).frequency_spread, "delta_omega", "delta_theta"))
    traj = e.trajectory(1.0, 5.0, weaker)
    row, col = e.value_at(weaker, 1.0, 5.0)
    assert list(traj.series) == [f"theta_{k}" for k in range(5)] + \
        [f"omega_{k}" for k in range(5)]
    ds = sweep.run(e.state.scene, sweep.Grid(perturbed_node=[1], delta_theta=[weaker.x[col]],
                                             delta_omega=[weaker.y[row]]),
                   t_end=20.0, dt=0.01, save_every=1,  # the explorer keeps all 2001 samples
                   observe=("synchrony",), progress=False)
    for k in range(5):
        np.testing.assert_array_equal(traj.series[f"theta_{k}"],
                                      ds.theta.isel(node=k).values.ravel())
    # the map's value at the pixel is the frequency spread at that run's end
    assert np.abs([traj.series[f"omega_{k}"][-1] for k in range(5)]).max() == \
        weaker.values[row, col]


@pytest.mark.parametrize("change, words", [
    (dict(perturbed_node=7), ["perturbed_node", "7", "0 to 4"]),
    (dict(coupling=-1.0), ["coupling", "-1.0", "> 0"]),
    (dict(x="theta1_0"), ["theta1_0", "delta_theta"]),
])
def test_bad_network_input_is_refused(change, words):
    e = network_explorer()
    with pytest.raises(InvalidInput) as info:
        e.update(**change)
    for word in words:
        assert word in str(info.value)


# ------------------------------------------------ driven basins: the catalogue route
def _point(labels, label: int) -> np.ndarray:
    """basins' attractor ``label`` as one point (theta1, theta2, omega1, omega2)."""
    return np.array([labels.attrs[f"attractor_{n}"][label]
                     for n in ("theta1", "theta2", "omega1", "omega2")])


def _same_place(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two attractor points are within 0.1 (rad, rad/s) of each other, angles
    modulo 2 pi: one attractor seen at two stages of a start's slow convergence (the
    points below differ by at most 0.03), while this window's distinct attractors (arms
    down or upright) are pi apart in an angle."""
    d = np.abs(a - b)
    d[:2] = np.minimum(np.mod(d[:2], 2 * np.pi), 2 * np.pi - np.mod(d[:2], 2 * np.pi))
    return bool((d < 0.1).all())


#: A zoom of the driven window with starts the two routes label differently.
ZOOM = ((-3.0, 0.5), (-1.0, 3.4))


def test_the_catalogue_route_labels_the_starts_as_the_exact_route(monkeypatch):
    """A driven system's basins map takes the catalogue route by default: a 21 x 21
    pilot over the home window (one strobe run, `sweep.maps.pilot_catalogue`), then the
    window's run observing strobe and attractor with the catalogue and stop_early, and
    `sweep.maps.basins`. Its labels are the exact route's (the full strobe run: the
    same integers, unresolved ones included) but where the catalogue legitimately
    labels a start the exact route has not resolved yet: the catalogue stopped it (its
    strobe points within 1e-3 of a catalogued orbit 3 periods running), and the exact
    route's last 16 samples call it unresolved (a spiral onto the orbit still wider than
    basins' tol) or an "attractor" at the same place (a period-8 ring around the
    catalogue's period-1 point; the 4 corners of the home window, still creeping onto
    both arms upright at |omega| ~ 5e-3 rad/s, each called a period-1 point where it is
    at t_end). 4 of the 64 starts at home, 4 in the zoom. Two of the home corners were
    not stopped: their samples are the exact route's, but the stopped corners' split
    of the creeping points renumbers theirs (labels are ordered by basin size)."""
    calls = []
    pilot = maps.pilot_catalogue
    monkeypatch.setattr(maps, "pilot_catalogue",
                        lambda *a, **k: calls.append(a) or pilot(*a, **k))
    e = driven(quantity="basins")
    assert e.state.catalogue and e.uses_pilot()
    route = next(c for c in e.run_controls() if c.name == "route")
    assert route.value == "catalogue" and route.choices == ("catalogue", "exact")
    for window, expected in ((None, 4), (ZOOM, 4)):
        if window is not None:
            e.zoom(*window)
        result = e.compute()
        stopped = plane(result.ds["attractor"]) >= 0
        assert 0 < stopped.sum() < M * M
        assert result.route == (f"catalogue route (21 x 21 pilot, "
                                f"{len(result.catalogue['period'])} attractors): "
                                f"{stopped.sum()} of {M * M} starts stopped on the catalogue")
        exact = e.compute(dataclasses.replace(e.state, catalogue=False))
        assert exact.catalogue is None and exact.route.startswith("exact route")
        differ = result.values != exact.values
        assert differ.sum() == expected
        assert stopped[differ].sum() >= expected - 2 and (result.values[differ] >= 0).all()
        for ours, theirs in zip(result.values[differ], exact.values[differ]):
            assert theirs == -1 or _same_place(_point(result.da, ours),
                                               _point(exact.da, theirs))
    assert len(calls) == 1  # one pilot for the home window and the zoom


def test_the_catalogue_is_reused_on_zoom_and_rebuilt_when_the_system_changes(
        monkeypatch, tmp_path):
    """One pilot per system, run settings and start: zooms, pans, a new resolution and
    the exact route's maps reuse it (no new pilot run), a changed parameter or t_end
    runs a new one over the new system; the page's Python reproduces the catalogue
    route's map to the bit, and its run file (a run file's pilot thins the map's own
    grid, not the home window: another catalogue) says so and gives the exact route's
    map."""
    calls = []
    pilot = maps.pilot_catalogue
    monkeypatch.setattr(maps, "pilot_catalogue",
                        lambda *a, **k: calls.append((a, k)) or pilot(*a, **k))
    e = driven(quantity="basins")
    first = e.compute()
    e.zoom((-2.0, 1.0), (-2.5, 0.5))
    e.compute()
    e.zoom((-1.5, 1.5), (-2.5, 0.5))  # a pan
    e.update(resolution=M + 2)
    panned = e.compute()
    assert len(calls) == 1 and panned.catalogue is first.catalogue
    home = calls[0][0][1]
    np.testing.assert_array_equal(home.axes["theta1_0"], centres(-3.0 - 3 / 7, 3 + 3 / 7, 21))
    scope = {}
    exec(e.python_snippet(), scope)  # the catalogue route, its own pilot included
    np.testing.assert_array_equal(plane(scope["image"]), panned.values)
    assert len(calls) == 2 and calls[1][1] == calls[0][1]  # its pilot is the explorer's
    for name in home.dims:
        np.testing.assert_array_equal(calls[1][0][1].axes[name], home.axes[name])
    assert "stopped on the catalogue" in panned.route
    text = e.toml_text()
    assert "by the catalogue route" in text and "runs the exact" in text
    assert "pilot = N thins this map's" in text and "takes no pilot" not in text
    path = tmp_path / "basins.toml"
    path.write_text(text)
    system, grid, kwargs = load_run(path, {})
    assert tuple(kwargs["observe"]) == ("strobe",) and "attractors" not in kwargs
    e.update(route="exact")
    exact = e.compute()
    np.testing.assert_array_equal(
        plane(maps.basins(sweep.run(system, grid, progress=False, **kwargs))), exact.values)
    assert len(calls) == 2
    e.update(route="catalogue", pivot_amplitude=0.12)
    again = e.compute()
    assert len(calls) == 3 and calls[2][0][0].pivot_amplitude == 0.12
    assert again.catalogue is not first.catalogue
    e.update(t_end=110 * PERIOD)
    e.compute()
    assert len(calls) == 4 and calls[3][1]["t_end"] == 110 * PERIOD
    with pytest.raises(InvalidInput, match="route must be one of catalogue, exact, got "
                                           "'known cells'"):
        e.update(route="known cells")
    with pytest.raises(InvalidInput, match="route: DoublePendulum has no basins map"):
        double().update(route="exact")


def test_a_torsion_coupled_run_file_reads_back_the_same_system(tmp_path):
    """`sweep.CoupledPendula`'s own ``kind`` (spring or torsion) shares its name with the
    ``[system]`` table's ``kind`` (the system's class): the explorer wrote both as
    ``kind``, a TOML file with a duplicate key that no reader accepts, and a hand-written
    file could not give a torsion coupling at all. It is ``coupling_kind`` in run files;
    a wrong one names the argument as the class takes it."""
    from sweep.toml_spec import load_run

    system = sweep.CoupledPendula(3, kind="torsion", coupling=0.5)
    e = SystemExplorer(system, sweep.Grid(theta1_0=np.linspace(-1, 1, N),
                                          theta3_0=np.linspace(-1, 1, N)),
                       resolution=N, **RUN)
    text = e.toml_text()
    assert 'coupling_kind = "torsion"' in text and text.count("\nkind = ") == 1
    path = tmp_path / "torsion.toml"
    path.write_text(text)
    assert load_run(path, {})[0] == system
    with pytest.raises(ValueError, match=r"^CoupledPendula: kind='rubber' is not accepted"):
        sweep.CoupledPendula(3, kind="rubber")
