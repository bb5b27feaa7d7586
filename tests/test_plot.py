"""Figures: labels with units, discrete colour maps for integer data, trajectories,
atomic PNG writes, and no matplotlib at import. Synthetic datasets: no integration."""

import subprocess
import sys

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
from matplotlib.colors import BoundaryNorm

from sweep import plot

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def coordinate(name, values, units, long_name):
    return xr.Variable(name, np.asarray(values, dtype=float),
                       {"units": units, "long_name": long_name})


@pytest.fixture
def maps():
    """A 2-D dataset shaped like a sweep output: theta0 x omega0."""
    theta0 = np.linspace(-np.pi, np.pi, 9)
    omega0 = np.linspace(-4.0, 4.0, 7)
    th, om = np.meshgrid(theta0, omega0, indexing="ij")
    winding = np.trunc(om / 2.0)
    final = th + 2 * np.pi * winding
    final[0, 0] = np.nan  # a failed trajectory is left blank
    dims = ("theta0", "omega0")
    return xr.Dataset(
        {
            "winding": (dims, winding, {"units": "1", "long_name": "net full turns"}),
            "theta_final": (dims, final, {"units": "rad", "long_name": "angle at t_end"}),
            "status": (dims, np.zeros(th.shape, np.int8),
                       {"flag_values": np.array([0, 1], np.int8),
                        "flag_meanings": "ok nonfinite"}),
        },
        coords={
            "theta0": coordinate("theta0", theta0, "rad", "initial angle"),
            "omega0": coordinate("omega0", omega0, "rad s-1", "initial angular velocity"),
        },
    )


@pytest.fixture
def sampled():
    """Sampled trajectories theta(t), omega(t) on a 3 x 2 grid (a ``time`` dimension)."""
    theta0 = np.array([-1.0, 0.0, 1.0])
    omega0 = np.array([0.0, 2.0])
    time = np.linspace(0.0, 10.0, 101)
    th = theta0[:, None, None] * np.cos(time) + omega0[None, :, None] * np.sin(time)
    om = -theta0[:, None, None] * np.sin(time) + omega0[None, :, None] * np.cos(time)
    dims = ("theta0", "omega0", "time")
    return xr.Dataset(
        {"theta": (dims, th, {"units": "rad", "long_name": "angle, unwrapped"}),
         "omega": (dims, om, {"units": "rad s-1", "long_name": "angular velocity"})},
        coords={
            "theta0": coordinate("theta0", theta0, "rad", "initial angle"),
            "omega0": coordinate("omega0", omega0, "rad s-1", "initial angular velocity"),
            "time": coordinate("time", time, "s", "time"),
        },
    )


def colour_bar(fig):
    return fig.axes[1]


def test_importing_sweep_plot_loads_no_matplotlib():
    code = "import sys, sweep.plot; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "False"


@pytest.mark.parametrize("units, shown", [
    ("rad", "rad"), ("rad s-1", "rad/s"), ("m s-2", "m/s²"), ("s-1", "1/s"),
    ("s-2", "1/s²"), ("1", ""), ("", ""), ("deg s-1", "deg/s"),
])
def test_units_are_shown_the_usual_way(units, shown):
    assert plot.units_text(units) == shown


def test_map_axes_are_in_degrees_with_units(maps):
    fig = plot.map(maps.theta_final)
    ax = fig.axes[0]
    assert ax.get_xlabel() == r"initial angle, $\theta_0$ [deg]"
    assert ax.get_ylabel() == r"initial angular velocity, $\omega_0$ [deg/s]"
    assert ax.get_xlim() == pytest.approx((-202.5, 202.5))  # cell edges, 45 deg cells
    assert colour_bar(fig).get_ylabel() == "angle at t_end [rad]"
    assert ax.get_title() == "theta_final"
    assert not isinstance(ax.collections[0].norm, BoundaryNorm)  # continuous data
    assert np.ma.count_masked(ax.collections[0].get_array()) == 1  # the NaN cell


def test_map_in_radians(maps):
    ax = plot.map(maps.theta_final, degrees=False, title="Final angle").axes[0]
    assert ax.get_xlabel().endswith("[rad]") and ax.get_ylabel().endswith("[rad/s]")
    assert ax.get_xlim() == pytest.approx((-1.125 * np.pi, 1.125 * np.pi))
    assert ax.get_title() == "Final angle"


def test_a_systems_angle_axes_follow_the_pendulums_rule():
    """A double pendulum's initial angles and angular velocities are in degrees as the
    pendulum's theta0 and omega0 are (they were left in rad), or all in rad with
    ``degrees=False``; a length stays in metres."""
    theta1_0 = np.linspace(-np.pi / 2, np.pi / 2, 5)
    omega2_0 = np.linspace(-1.0, 1.0, 3)
    length1 = np.array([0.5, 1.0])
    flip = np.zeros((5, 3, 2))
    ds = xr.Dataset(
        {"flip_time": (("theta1_0", "omega2_0", "length1"), flip, {"units": "s"})},
        coords={"theta1_0": coordinate("theta1_0", theta1_0, "rad", "initial theta1"),
                "omega2_0": coordinate("omega2_0", omega2_0, "rad s-1", "initial omega2"),
                "length1": coordinate("length1", length1, "m", "length1")})
    ax = plot.map(ds.flip_time.isel(length1=0)).axes[0]
    assert ax.get_xlabel() == "initial theta1 [deg]"
    assert ax.get_ylabel() == "initial omega2 [deg/s]"
    # cell edges: -90 to 90 deg in 45 deg cells, -1 to 1 rad/s in 1 rad/s cells
    assert ax.get_xlim() == pytest.approx((-112.5, 112.5))
    assert ax.get_ylim() == pytest.approx(np.degrees([-1.5, 1.5]))
    ax = plot.map(ds.flip_time.isel(length1=0), degrees=False).axes[0]
    assert ax.get_xlabel().endswith("[rad]") and ax.get_ylabel().endswith("[rad/s]")
    ax = plot.map(ds.flip_time.isel(omega2_0=0)).axes[0]
    assert ax.get_xlabel().endswith("[deg]") and ax.get_ylabel() == "length1 [m]"
    assert plot.angle_axis("pivot_phase") and plot.angle_axis("omega1_0")
    assert not plot.angle_axis("forcing_frequency")  # rad/s, but a frequency


def test_integer_map_gets_one_colour_per_integer(maps):
    fig = plot.map(maps.winding)
    mesh = fig.axes[0].collections[0]
    assert isinstance(mesh.norm, BoundaryNorm)
    assert mesh.cmap.N == 5  # -2 .. 2, symmetric about 0
    bar = colour_bar(fig)
    assert [t.get_text() for t in bar.get_yticklabels()] == ["-2", "-1", "0", "1", "2"]
    assert bar.get_ylabel() == "net full turns"  # dimensionless: no [units]


def test_flag_map_labels_ticks_with_meanings(maps):
    bar = colour_bar(plot.map(maps.status))
    assert [t.get_text() for t in bar.get_yticklabels()] == ["ok", "nonfinite"]


def test_map_squeezes_size_one_dimensions_and_names_them_in_the_title(maps):
    da = maps.theta_final.expand_dims(forcing_amplitude=[1.5])
    da.forcing_amplitude.attrs["units"] = "rad s-2"
    ax = plot.map(da).axes[0]
    assert ax.get_title() == "theta_final (forcing_amplitude = 1.5 rad/s²)"


def test_map_refuses_other_than_two_dimensions(maps, sampled):
    with pytest.raises(ValueError, match=r"2-D.*theta0, omega0, time"):
        plot.map(sampled.theta)
    with pytest.raises(ValueError, match="2-D"):
        plot.map(maps.winding.isel(theta0=0))


def test_map_refuses_an_unknown_colormap(maps):
    with pytest.raises(ValueError, match="cmap 'nope'"):
        plot.map(maps.theta_final, cmap="nope")
    assert plt.get_fignums() == []  # refused before a figure was made


def test_map_draws_into_given_axes(maps):
    fig, (left, right) = plt.subplots(1, 2)
    assert plot.map(maps.winding, ax=right) is fig
    assert right.collections and not left.collections


def test_select_takes_the_nearest_point_and_refuses_unknown_names(sampled):
    one = plot.select(sampled.theta, theta0=0.1, time=4.96)
    assert one.dims == ("omega0",) and float(one.theta0) == 0.0 and float(one.time) == 5.0
    with pytest.raises(ValueError, match=r"'phi'.*theta0, omega0, time"):
        plot.select(sampled, phi=1.0)
    with pytest.raises(TypeError, match="theta0"):
        plot.select(sampled, theta0="x")


def test_trajectory_draws_angle_and_phase_portrait(sampled):
    fig = plot.trajectory(sampled, theta0=1.0, omega0=0.0)
    time_axis, phase_axis = fig.axes
    t, th = time_axis.lines[0].get_data()
    np.testing.assert_array_equal(t, sampled.time)
    np.testing.assert_allclose(th, np.cos(sampled.time))
    assert time_axis.get_xlabel() == "time, $t$ [s]"
    assert time_axis.get_ylabel() == r"angle, unwrapped, $\theta$ [rad]"
    assert phase_axis.get_ylabel() == r"angular velocity, $\omega$ [rad/s]"
    assert "theta0 = 1 rad" in fig.get_suptitle() and "omega0 = 0 rad/s" in fig.get_suptitle()


def test_trajectory_draws_several_with_a_legend(sampled):
    fig = plot.trajectory(sampled, omega0=2.0)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["theta0 = -1 rad", "theta0 = 0 rad", "theta0 = 1 rad"]


def test_trajectory_errors(sampled, maps):
    with pytest.raises(ValueError, match=r"'time' dimension.*save_every"):
        plot.trajectory(maps)
    with pytest.raises(ValueError, match=r"12 trajectories remain.*length, theta0"):
        plot.trajectory(sampled.expand_dims(length=[1.0, 2.0, 3.0, 4.0]), omega0=0.0)
    with pytest.raises(ValueError, match="cannot select 'time'"):
        plot.trajectory(sampled, time=1.0)
    # a system's saved states (theta1, omega1, ...): what is accepted, and what it is
    system = sampled.rename(theta="theta1", omega="omega1").assign_attrs(
        system_name="double_pendulum")
    with pytest.raises(ValueError, match=r"variables theta and omega; missing: theta, omega "
                       r"\(this is a run of the system double_pendulum\); accepted: the "
                       r"output of a single-pendulum run .* with save_every set$"):
        plot.trajectory(system, theta0=1.0, omega0=0.0)


def test_save_figure_writes_a_png_and_closes_the_figure(maps, tmp_path):
    fig = plot.map(maps.winding)
    path = plot.save_figure(fig, tmp_path / "winding.png")
    assert path.read_bytes()[:8] == PNG_MAGIC
    height, width, channels = matplotlib.image.imread(path).shape
    assert (height, width) == (810, 1050) and channels == 4  # 7 x 5.4 in at 150 dpi
    assert not plt.fignum_exists(fig.number)
    assert [p.name for p in tmp_path.iterdir()] == ["winding.png"]  # no temporary left


def test_save_figure_refusals_leave_nothing(maps, tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        plot.save_figure(plot.map(maps.winding), tmp_path / "missing" / "a.png")
    with pytest.raises(ValueError, match="unknown image format 'xyz'"):
        plot.save_figure(plot.map(maps.winding), tmp_path / "a.xyz")
    assert list(tmp_path.iterdir()) == [] and plt.get_fignums() == []


def test_interrupted_save_keeps_the_previous_file(maps, tmp_path, monkeypatch):
    path = plot.save_figure(plot.map(maps.winding), tmp_path / "map.png")
    before = path.read_bytes()
    fig = plot.map(maps.theta_final)

    def crash(target, **kwargs):
        with open(target, "wb") as handle:
            handle.write(PNG_MAGIC)  # half-written...
        raise KeyboardInterrupt  # ...then Ctrl-C

    monkeypatch.setattr(fig, "savefig", crash)
    with pytest.raises(KeyboardInterrupt):
        plot.save_figure(fig, path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["map.png"]


def test_basins_plot_marks_attractors(tmp_path):
    import sweep
    from sweep import maps

    ds = sweep.run(sweep.Scene(effects=(sweep.Damping(0.5),)),
                   sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 21),
                              omega0=np.linspace(-8, 8, 21)),
                   t_end=20.0, dt=0.02, observe=("final", "energy"))
    fig = sweep.plot.basins(maps.basins(ds))
    ax = fig.axes[0]
    stars = [line for line in ax.get_lines() if line.get_marker() == "*"]
    # every rest state 2 pi k reduces to (0, 0) in the window: one star there
    assert len(stars) == 1 and np.allclose(stars[0].get_xydata(), [[0.0, 0.0]])
    sweep.plot.save_figure(fig, tmp_path / "basins.png")
    assert (tmp_path / "basins.png").read_bytes()[:4] == b"\x89PNG"


def _every_observed_variable():
    """``(name, attributes)`` of every variable the single pendulum's observables, a
    double pendulum's and a swing network's write, as `sweep.io` and
    `sweep.engine_systems` make them (the network's from zeros, no integration; its
    names prefixed ``network.``), and of `sweep.maps.synchronized`'s labels."""
    import sweep
    from sweep.engine_systems import prepare_system, to_network_dataset
    from sweep.kernels.network import network_outputs
    from sweep.observables import OBSERVABLES, variable_attributes
    from sweep.system_observables import SYSTEM_OBSERVABLES, comments, variables

    for observable in OBSERVABLES.values():
        for name, units, long_name in observable.variables:
            yield name, variable_attributes(name, units, long_name)
    system = sweep.DoublePendulum(mass1=1.0, mass2=1.0, length1=1.0, length2=1.0,
                                  gravity=9.81)
    coordinates = system.declaration.coordinates
    for observable in SYSTEM_OBSERVABLES:
        notes = comments(observable, coordinates)
        for name, units, long_name in variables(observable, coordinates,
                                                system.energy_units):
            yield name, variable_attributes(name, units, long_name, notes.get(name, ""))
    network = sweep.SwingNetwork([(0, 1)], power=[-1.0, 1.0])
    grid = sweep.Grid(perturbed_node=[1], delta_theta=[0.0, 0.5])
    settings, spec, _ = prepare_system(network, grid, t_end=1.0, dt=0.1, save_every=5,
                                       observe=("final", "synchrony"))
    ds = to_network_dataset(system=network, grid=grid, settings=settings, spec=spec,
                            out=np.zeros((grid.size, network_outputs(spec))),
                            status=np.zeros(grid.size, dtype=np.int8),
                            saved=np.zeros((grid.size, 4, 3)))
    ds["synchronized"] = sweep.maps.synchronized(ds)
    for name, variable in ds.data_vars.items():
        yield f"network.{name}", dict(variable.attrs)


def test_every_observables_colour_bar_label_is_a_label_and_its_meaning_a_comment():
    """A colour bar names its variable in at most two lines (`plot._variable_label`
    wraps at 48 characters); what the variable means beyond that (a formula, a window,
    when it is NaN) is its CF ``comment``, which the explorer shows under its map.
    ``winding``'s label was four lines of formula beside the map of examples/forced.toml."""
    seen = dict(_every_observed_variable())
    assert {"winding", "lyapunov_max", "strobe_theta", "winding_theta1", "flip_time",
            "attractor", "network.theta", "network.order_parameter",
            "network.synchronized"} <= set(seen)
    for name, attrs in seen.items():
        da = xr.DataArray(np.zeros((2, 2)), name=name, attrs=attrs)
        label = plot._variable_label(da)
        assert label.count("\n") <= 1, (name, label)
    for name in ("winding", "omega_mean", "strobe_theta", "well", "capture_time",
                 "tension_max", "top_distance_max", "lyapunov_max", "attractor",
                 "winding_theta1", "flip_time", "theta1_strobe", "network.theta_final",
                 "network.frequency_spread", "network.order_parameter",
                 "network.synchronized"):
        assert len(seen[name].get("comment", "")) > 20, name  # the meaning is kept
    assert "round(theta_final / 2 pi)" in seen["winding"]["comment"]
