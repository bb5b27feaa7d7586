"""`sweep.Points`: a table of parameter sets run by `sweep.run` exactly as a `Grid` is.

The oracle is the grid itself: points drawn from a grid's cells, with the cells' exact
parameter values, must give every variable (status included) bit-identical to those
cells, since both reach the kernel as rows of the same parameter table (one path below
`ParameterRows`). Runs are small and share kernel specs (a grid of 91 cells and 30 points
both run in `sweep._config.SMALL_BLOCK` lanes), since each new spec compiles for seconds.
"""

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import maps

DAMPED = sweep.Scene(effects=(sweep.Damping(0.2),))
GRID = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 13), omega0=np.linspace(-2.0, 2.0, 7))
BASE = dict(t_end=5.0, dt=0.01, observe=("final", "winding", "theta_max"), progress=False)

FORCED = sweep.Scene(gravity=1.0, length=1.0,
                     effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
PERIOD = 2 * np.pi
FORCED_GRID = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9),
                         omega0=np.linspace(-4.0, 4.0, 9))
FORCED_RUN = dict(t_end=60 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD,
                  observe=("strobe",), stop_early=True, progress=False)


def subset(grid: sweep.Grid, n: int, seed: int = 3):
    """``n`` distinct random cells of a 2-D ``grid``: (Points with the cells' exact
    values, and the cells' indices along each axis)."""
    picks = np.random.default_rng(seed).choice(grid.size, n, replace=False)
    index = np.unravel_index(picks, grid.shape)
    columns = {name: values[i] for (name, values), i in zip(grid.axes.items(), index)}
    return sweep.Points(**columns), index


def assert_same_as_cells(points_ds, grid_ds, index):
    """Every data variable of the points run equals the grid run's at the cells."""
    assert set(points_ds.data_vars) == set(grid_ds.data_vars)
    for name in grid_ds.data_vars:
        cells = grid_ds[name].transpose(*grid_ds.attrs["grid_axes"].split(), ...).values[index]
        assert np.array_equal(points_ds[name].values, cells, equal_nan=True), name


# ------------------------------------------------------------------ construction
def test_points_has_grid_like_attributes():
    points = sweep.Points(theta0=[0.1, 2.0, 2.0], omega0=[0, 0.5, -0.5], damping=0.2)
    assert points.dims == ("point",) and points.shape == (3,) and points.size == 3
    assert list(points.axes) == ["theta0", "omega0", "damping"]
    np.testing.assert_array_equal(points.axes["damping"], [0.2, 0.2, 0.2])  # scalar: constant
    for values in points.axes.values():
        assert values.dtype == np.float64 and not values.flags.writeable
    assert repr(points) == "Points(theta0=<3 values>, omega0=<3 values>, damping=<3 values>)"
    assert points.varies("theta0") and not points.varies("damping")
    assert not points.varies("length")  # not an axis
    assert sweep.Points(theta0=0.5).shape == (1,)  # all scalars: one point
    # a chunk's rows are the points' own, with the scene's other parameters
    table = points.table(DAMPED, 1, 3)
    names = sweep.physics.parameter_names()
    np.testing.assert_array_equal(table[:, names.index("theta0")], [2.0, 2.0])
    np.testing.assert_array_equal(table[:, names.index("omega0")], [0.5, -0.5])
    assert np.all(table[:, names.index("length")] == 1.0)


@pytest.mark.parametrize("axes, message", [
    ({}, "Points needs at least one axis; accepted axis names: theta0"),
    ({"theta": [1.0]}, "unknown points axis 'theta'; accepted axis names: theta0"),
    ({"theta0": [0.0, 1.0], "omega0": [1.0, 2.0, 3.0]},
     "points axes have unequal lengths: theta0 has 2, omega0 has 3; accepted: 1-D arrays "
     "of one length"),
    ({"theta0": [[0.0, 1.0]]}, r"points axis 'theta0' must be 1-D .* shape \(1, 2\)"),
    ({"theta0": []}, "points axis 'theta0' is empty; accepted: at least one value"),
    ({"theta0": [0.0, np.nan]}, "points axis 'theta0' has non-finite value nan at index 1; "
                                "accepted: finite numbers"),
    ({"theta0": "0.5"}, "points axis 'theta0' must be a 1-D array of numbers"),
    ({"theta0": [True, False]}, "points axis 'theta0'"),
    ({"length": [1.0, -1.0]}, "points axis 'length' has value -1.0 at index 1; accepted: "
                              "finite numbers > 0"),
])
def test_bad_points_are_refused_naming_axis_value_and_accepted(axes, message):
    with pytest.raises(ValueError, match=message):
        sweep.Points(**axes)


def test_points_needing_an_effect_the_scene_lacks_are_refused(no_compute):
    with pytest.raises(ValueError, match="points axis 'forcing_phase' needs a forcing"):
        sweep.run(DAMPED, sweep.Points(forcing_phase=[0.0, 1.0]), **BASE)
    with pytest.raises(TypeError, match="grid must be a sweep.Grid or sweep.Points"):
        sweep.run(DAMPED, {"theta0": [1.0]}, **BASE)


# ------------------------------------------------------------------ bit-identity
@pytest.fixture(scope="module")
def damped_pair():
    points, index = subset(GRID, 30)
    return sweep.run(DAMPED, points, **BASE), sweep.run(DAMPED, GRID, **BASE), index


def test_points_run_is_bit_identical_to_the_grid_cells(damped_pair):
    ds, grid_ds, index = damped_pair
    assert ds.sizes == {"point": 30} and "point" not in ds.coords
    for name in ("theta0", "omega0"):
        assert ds[name].dims == ("point",)
        assert ds[name].attrs == grid_ds[name].attrs  # units and long_name
    assert_same_as_cells(ds, grid_ds, index)
    assert ds.attrs["point_axes"] == "theta0 omega0" and "grid_axes" not in ds.attrs
    same = {"effects", "damping", "length", "gravity", "method", "dt", "observe", "scene"}
    assert {k: ds.attrs[k] for k in same} == {k: grid_ds.attrs[k] for k in same}


def test_repeated_points_give_repeated_results():
    points = sweep.Points(theta0=[1.0, 2.5, 1.0], omega0=[0.5, 0.0, 0.5])
    ds = sweep.run(DAMPED, points, **BASE)
    for name in ds.data_vars:
        assert np.array_equal(ds[name].values[0], ds[name].values[2]), name


def test_a_saved_points_file_says_how_to_rerun_it(damped_pair, tmp_path):
    ds, _, _ = damped_pair
    back = sweep.load(sweep.save(ds, tmp_path / "points.nc"))
    points = sweep.io.grid_from(back)
    assert isinstance(points, sweep.Points)
    again = sweep.run(sweep.io.scene_from(back), points, **sweep.io.run_arguments(back),
                      progress=False)
    assert again.drop_attrs().identical(ds.drop_attrs())
    assert isinstance(sweep.io.grid_from(sweep.run(DAMPED, GRID, **BASE)), sweep.Grid)
    with pytest.raises(ValueError, match="neither a 'grid_axes' nor a 'point_axes'"):
        sweep.io.grid_from(xr.Dataset())


@pytest.mark.parametrize("case", ["stop_early", "float32", "dopri5"])
def test_points_are_bit_identical_for_other_run_settings(case):
    kwargs = {"stop_early": dict(t_end=20.0, dt=0.01, observe=("capture",), stop_early=True),
              "float32": dict(BASE, dtype="float32"),
              "dopri5": dict(BASE, method="dopri5", rtol=1e-6, atol=1e-9)}[case]
    kwargs = dict(kwargs, progress=False)
    points, index = subset(GRID, 30)
    assert_same_as_cells(sweep.run(DAMPED, points, **kwargs),
                         sweep.run(DAMPED, GRID, **kwargs), index)


@pytest.fixture(scope="module")
def forced_pair():
    """A forced run with strobe and its pilot catalogue, as grid and as points."""
    catalogue = maps.pilot_catalogue(FORCED, FORCED_GRID, 9, **FORCED_RUN)
    points, index = subset(FORCED_GRID, 40)
    run = dict(FORCED_RUN, attractors=catalogue)
    return (sweep.run(FORCED, points, **run), sweep.run(FORCED, FORCED_GRID, **run), index,
            catalogue)


def test_forced_points_with_a_catalogue_are_bit_identical(forced_pair):
    ds, grid_ds, index, _ = forced_pair
    assert "attractor" in ds and ds["strobe_theta"].dims == ("point", "strobe")
    assert_same_as_cells(ds, grid_ds, index)
