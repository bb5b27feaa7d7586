"""The explorer's model for a declared system (`sweep.DeclaredSystem`, from Python and
from a run file's ``kind = "DeclaredSystem"``; `sweep.explore.systems.SystemExplorer`):
any two axes, controls from the declaration, maps equal to sweep.run cell by cell,
clicks, and the run file and Python that reproduce a map."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_explore_systems import RUN, N, plane, reference

import sweep
from sweep.explore.model import InvalidInput
from sweep.explore.systems import SystemExplorer, SystemTrajectory
from sweep.physics import Coordinate, Parameter, SystemDeclaration
from sweep.toml_spec import load_run

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "pendulum_on_cart.toml"


def cart_explorer(**extra):
    """The shipped run file's pendulum on a cart, over (theta_0, x_0)."""
    system, _, _ = load_run(EXAMPLE)
    grid = sweep.Grid(theta_0=np.linspace(-3, 3, N), x_0=np.linspace(-0.5, 0.5, N))
    return SystemExplorer(system, grid, resolution=N, **RUN, **extra)


def test_a_declared_systems_maps_are_its_observables_and_sweep_run():
    e = cart_explorer()
    s = e.state
    assert (s.view.x, s.view.y) == ("theta_0", "x_0")
    assert s.quantity == "log10:flip_time"  # it has an angle: the flip map
    # every variable of the system's observables, named by its coordinates
    assert {"var:theta_final", "var:x_final", "var:v_final", "var:energy_final",
            "var:winding_theta", "var:lyapunov_max"} <= set(e.quantities())
    assert "var:winding_x" not in e.quantities()  # x is not an angle
    e.update(quantity="var:x_final")
    result = e.compute()
    np.testing.assert_array_equal(result.values,
                                  plane(reference(e, observe=("final",)).x_final, "x_0",
                                        "theta_0"))
    assert np.ptp(result.values) > 0
    assert e.axis_units()["x_0"] == "m" and e.axis_units()["k"] == "N m-1"


def test_controls_are_the_declarations_parameters_and_change_the_map():
    e = cart_explorer()
    controls = {c.name: c for c in e.parameter_controls()}
    assert list(controls) == ["M", "m", "l", "g", "k", "b", "damping", "omega_0", "v_0"]
    assert controls["k"].label == "k [N m-1]" and controls["k"].value == 20.0
    assert (controls["k"].minimum, controls["g"].minimum) == (0.0, None)
    assert controls["M"].help.startswith("cart mass")
    e.update(quantity="var:theta_final")
    before = e.compute().values
    e.update(k=5.0, damping=0.3)
    assert e.state.scene.k == 5.0 and e.state.scene.damping == 0.3
    assert e.state.scene.declaration == load_run(EXAMPLE)[0].declaration
    after = e.compute().values
    assert not np.array_equal(before, after)
    np.testing.assert_array_equal(after, plane(reference(e, observe=("final",)).theta_final,
                                               "x_0", "theta_0"))
    with pytest.raises(InvalidInput, match=r"k.*-1"):
        e.update(k=-1.0)


def test_any_two_axes_a_parameter_and_a_velocity():
    e = cart_explorer()
    e.update(x="k", y="v_0", quantity="var:energy_final")
    v = e.state.view
    assert (v.x, v.x_range, v.y) == ("k", (10.0, 30.0), "v_0")  # value x (1/2, 3/2)
    result = e.compute()
    np.testing.assert_array_equal(result.values, plane(
        reference(e, observe=("energy",)).energy_final, "v_0", "k"))
    with pytest.raises(InvalidInput, match="theta1_0"):
        e.update(x="theta1_0")


def test_a_click_and_the_reproducing_run_file_and_python(tmp_path):
    e = cart_explorer()
    e.update(quantity="var:x_final", b=0.5, damping=0.2)
    result = e.compute()
    traj = e.trajectory(1.0, 0.2, result)
    assert isinstance(traj, SystemTrajectory)
    assert list(traj.series) == ["theta", "x", "omega", "v"]
    assert traj.units["x"] == "m" and traj.units["v"] == "m s-1"
    row, col = e.value_at(result, 1.0, 0.2)
    assert traj.series["x"][-1] == result.values[row, col]
    assert "sweep.DeclaredSystem(declaration" in traj.python
    assert 'kind = "DeclaredSystem"' in traj.toml
    path = tmp_path / "map.toml"
    path.write_text(e.toml_text())
    system, grid, kwargs = load_run(path, {})
    assert system == e.state.scene  # the same declaration and values, b, damping too
    assert system.damping == 0.2 and "[system.damping]" in e.toml_text()
    ds = sweep.run(system, grid, progress=False, **kwargs)
    np.testing.assert_array_equal(plane(ds.x_final, "x_0", "theta_0"), result.values)
    scope = {}
    exec(e.python_snippet(), scope)
    np.testing.assert_array_equal(plane(scope["image"], "x_0", "theta_0"), result.values)


def two_wells() -> SystemDeclaration:
    """A declaration made in Python with its own symbols and accelerations: two
    uncoupled Duffing wells q'' = q - q^3 - c q' (no angle, no Lagrangian)."""
    def coordinate(k):
        return Coordinate(f"q{k}", f"p{k}", f"a{k}", f"b{k}", units="m",
                          velocity_units="m s-1", angular=False)
    return SystemDeclaration(
        "test_explore_two_wells", (coordinate(1), coordinate(2)),
        (Parameter("friction", "friction", "cf", "s-1", "1/s", "friction rate",
                   minimum=0.0, default=0.3),),
        accelerations=("a1 - a1**3 - cf*b1", "a2 - a2**3 - cf*b2"),
        potential="a1**4/4 - a1**2/2 + a2**4/4 - a2**2/2")


def test_a_declaration_from_python_with_accelerations_and_its_run_file(tmp_path):
    system = sweep.DeclaredSystem(two_wells(), friction=0.5)
    grid = sweep.Grid(q1_0=np.linspace(-1.5, 1.5, N), p1_0=np.linspace(-1, 1, N))
    e = SystemExplorer(system, grid, resolution=N, t_end=10.0, dt=0.01,
                       quantity="var:q1_final")
    assert "log10:flip_time" not in e.quantities()  # no angle to flip
    assert "var:energy_final" in e.quantities()  # from the potential
    result = e.compute()
    assert set(np.sign(result.values).ravel()) == {-1.0, 1.0}  # both wells reached
    # its run file writes the names as the text declaration's (symbols u_<name>):
    # a new declaration, so read it back in a child process's stead under a new name
    text = e.toml_text().replace('name = "test_explore_two_wells"',
                                 'name = "test_explore_two_wells_file"')
    assert 'acceleration = "q1 - q1 ** 3 - friction * p1"' in text
    path = tmp_path / "wells.toml"
    path.write_text(text)
    again, grid, kwargs = load_run(path, {})
    assert again.friction == 0.5
    ds = sweep.run(again, grid, progress=False, **kwargs)
    # the same equations with other symbols: SymPy may order the terms otherwise, so
    # the basins (the well of every start) must agree, not the last bit
    np.testing.assert_array_equal(np.sign(plane(ds.q1_final, "p1_0", "q1_0")),
                                  np.sign(result.values))


def test_the_command_line_explores_a_run_files_declared_system(monkeypatch):
    pytest.importorskip("panel")
    from sweep.cli import main
    from sweep.explore import app as app_module
    from sweep.explore.system_app import SystemExplorerApp

    opened = []
    monkeypatch.setattr(app_module, "main_serve",
                        lambda app, **kwargs: opened.append(app) or 0)
    assert main(["explore", str(EXAMPLE), "--no-browser"]) == 0
    (app,) = opened
    assert isinstance(app, SystemExplorerApp)
    s = app.template.state
    assert (s.view.x, s.view.y) == ("theta_0", "k")
    assert isinstance(sweep.explore(sweep.DeclaredSystem(two_wells()), sweep.Grid(
        q1_0=np.linspace(-1, 1, N), q2_0=np.linspace(-1, 1, N)), **RUN), SystemExplorerApp)


def test_the_page_labels_its_axes_in_the_coordinates_units():
    pytest.importorskip("panel")
    from sweep.explore.system_app import SystemExplorerApp, _SystemSession

    system, _, _ = load_run(EXAMPLE)
    app = SystemExplorerApp(system, sweep.Grid(theta_0=np.linspace(-3, 3, N),
                                               x_0=np.linspace(-0.5, 0.5, N)),
                            resolution=N, **RUN)
    page = _SystemSession(app)  # no document: the callbacks draw at once
    try:
        assert page.requests.idle(120)
        assert page.trajectory.yaxis.axis_label == "coordinates [rad, m], velocities " \
                                                   "[rad/s, m/s]"
        assert (page.phase.xaxis.axis_label, page.phase.yaxis.axis_label) == \
            ("coordinate [rad, m]", "velocity [rad/s, m/s]")
        assert page.map.yaxis.axis_label == "x_0 [m]"
    finally:
        page.requests.close()
