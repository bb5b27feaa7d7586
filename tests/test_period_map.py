"""Periods, orbit diagrams and ``strobe_samples`` against the period-doubling cascade of
the damped driven pendulum (Taylor, Classical Mechanics, ch. 12) and an independent
SciPy DOP853 reproduction of it.

Taylor's pendulum: phi'' + 2 beta phi' + w0^2 sin phi = gamma w0^2 cos(w t), with
w = 2 pi (period 1 s), w0 = 1.5 w, beta = w0 / 4, from phi(0) = -pi/2, phi'(0) = 0
(the start of his bifurcation diagram; from rest a coexisting period-3 attractor takes
over past gamma ~ 1.079). The book's thresholds: period 1 -> 2 at gamma = 1.0663,
2 -> 4 at 1.0793, 4 -> 8 at 1.0821, chaos past ~1.0829. The gammas below sit inside
each window, away from the thresholds, where convergence is slow.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sweep
from sweep import maps
from sweep.maps import _strobe

W = 2 * np.pi
W0 = 1.5 * W
BETA = W0 / 4
THETA0 = -np.pi / 2
# inside the windows of period 1, 2, 4 and 8
CASCADE = {1.060: 1, 1.072: 2, 1.0805: 4, 1.0824: 8}
TRANSIENT = 400  # forcing periods: enough for the period-8 window (measured: 300 also)
TOL = 1e-4  # rad, rad/s: the orbits are resolved to ~1e-9 after the transient, and the
            # period-8 points are ~1e-2 apart, so 1e-4 separates them without doubt


def _taylor_scene():
    return sweep.Scene(gravity=W0 ** 2, length=1.0, effects=(
        sweep.Damping(2 * BETA), sweep.Forcing(W0 ** 2, W, np.pi / 2)))


def _run(gammas, samples=32, observe=("strobe",), transient=TRANSIENT):
    grid = sweep.Grid(forcing_amplitude=np.asarray(gammas) * W0 ** 2, theta0=[THETA0],
                      omega0=[0.0])
    return sweep.run(_taylor_scene(), grid, t_end=transient + samples, dt=1 / 200,
                     t_transient=transient, observe=observe, strobe_samples=samples,
                     progress=False)


def _dop853_period(gamma, samples=32, max_period=16):
    """The period of Taylor's pendulum at ``gamma`` from SciPy's DOP853 (rtol = atol =
    1e-10), sampled once per drive period after the transient; the period test is
    `sweep.maps._strobe.periods` (tested separately against a NumPy form)."""
    def rhs(t, y):
        return [y[1], -2 * BETA * y[1] - W0 ** 2 * np.sin(y[0])
                + gamma * W0 ** 2 * np.cos(W * t)]

    times = np.arange(TRANSIENT, TRANSIENT + samples) + 1.0
    y = solve_ivp(rhs, (0.0, times[-1]), [THETA0, 0.0], method="DOP853", rtol=1e-10,
                  atol=1e-10, t_eval=times).y
    found, _ = _strobe.periods(np.ascontiguousarray(y[:1]), np.ascontiguousarray(y[1:]),
                               max_period, TOL)
    return int(found[0])


def test_taylor_cascade_periods_match_the_book_and_dop853():
    ds = _run(list(CASCADE))
    periods = maps.period(ds, tol=TOL).values.ravel()
    assert periods.tolist() == list(CASCADE.values())
    assert [_dop853_period(g) for g in CASCADE] == list(CASCADE.values())


def test_past_the_cascade_no_period_and_a_positive_exponent():
    """gamma = 1.084: chaotic (Taylor's fig. 12.17); no period up to 16 is found and
    the largest Lyapunov exponent is clearly positive (measured 0.18-0.24 /s)."""
    ds = _run([1.084], observe=("strobe", "lyapunov"))
    assert int(maps.period(ds, tol=TOL).item()) == maps.NO_PERIOD
    assert float(ds.lyapunov_max.item()) > 0.05


def test_orbit_diagram_draws_every_sample_above_its_gamma():
    ds = _run([1.060, 1.072, 1.0805], samples=24)
    fig = sweep.plot.orbit_diagram(ds, along="forcing_amplitude")
    x, y = fig.axes[0].lines[0].get_data()
    assert x.size == 3 * 24  # one point per sample, overplotted where they repeat
    # above each gamma, as many distinct angles as the period (1, 2, 4)
    for k, count in enumerate([1, 2, 4]):
        column = y[np.isclose(x, ds.forcing_amplitude.values[k])]
        assert np.unique(np.round(column, 6)).size == count
    assert np.all((-np.pi <= y) & (y < np.pi))  # wrapped
    assert "forcing amplitude" in fig.axes[0].get_xlabel()
    assert "[rad]" in fig.axes[0].get_ylabel()


def test_more_samples_keep_the_last_sixteen():
    """``strobe_samples = 40`` keeps 40 samples whose last 16 are the default's, bit for
    bit (the same steps; only the ring is longer)."""
    default = _run([1.072], samples=16, transient=50)
    longer = sweep.run(_taylor_scene(), sweep.Grid(
        forcing_amplitude=[1.072 * W0 ** 2], theta0=[THETA0], omega0=[0.0]),
        t_end=50 + 16, dt=1 / 200, t_transient=50 - 24, observe=("strobe",),
        strobe_samples=40, progress=False)
    assert longer.sizes["strobe"] == 40 and longer.attrs["strobe_samples"] == 40
    np.testing.assert_array_equal(longer.strobe_theta.values[..., -16:],
                                  default.strobe_theta.values)


# ------------------------------------------------------------------ synthetic strobe tables
def _synthetic(theta, omega, **coords):
    """A dataset shaped like a strobe run: (grid dims..., strobe)."""
    import xarray as xr

    dims = tuple(coords) + ("strobe",)
    samples = np.shape(theta)[-1]
    coords = {**coords, "strobe": np.arange(1 - samples, 1)}
    return xr.Dataset({"strobe_theta": (dims, np.asarray(theta, dtype=float)),
                       "strobe_omega": (dims, np.asarray(omega, dtype=float))}, coords)


def test_period_of_synthetic_orbits_keeps_the_grid():
    """Known sequences on a 2 x 3 grid: period 1 at rest and rotating (theta + 2 pi per
    forcing period is the same state), period 2 (not reported as 4), period 3, one
    failed trajectory (NaN) and an aperiodic one (-1)."""
    m = np.arange(12.0)
    rows = [
        [np.full(12, 0.3), 0.3 + 2 * np.pi * m, 0.2 * (-1.0) ** m],
        [np.array([0.1, 0.5, -0.7] * 4), np.full(12, np.nan), np.sin(m * np.sqrt(2))],
    ]
    theta = np.array(rows)
    omega = np.zeros_like(theta)
    omega[0, 1] = 1.0  # rotating: constant omega at the strobe times
    ds = _synthetic(theta, omega, forcing_amplitude=[1.0, 1.1],
                    forcing_frequency=[0.5, 0.6, 0.7])
    periods = maps.period(ds)  # default max_period: 12 // 2 = 6
    assert periods.dims == ("forcing_amplitude", "forcing_frequency")
    np.testing.assert_array_equal(periods.forcing_frequency, [0.5, 0.6, 0.7])
    np.testing.assert_array_equal(periods.values, [[1, 1, 2], [3, -1, -1]])
    assert periods.attrs["max_period"] == 6
    # period 3 is not looked for with max_period = 2
    assert int(maps.period(ds, max_period=2)[1, 0]) == maps.NO_PERIOD


def test_orbit_diagram_of_a_synthetic_run_wraps_and_labels():
    """theta = 3 pi / 2 and -pi wrap to -pi / 2 and -pi ([-pi, pi)); omega is drawn as
    stored; degrees convert the angle; a second grid axis is overplotted."""
    theta = np.array([[[3 * np.pi / 2, -np.pi]], [[0.25, 0.25 + 4 * np.pi]]])  # (A, th0, s)
    omega = np.array([[[1.0, -2.0]], [[0.5, 0.5]]])
    ds = _synthetic(theta, omega, forcing_amplitude=[1.0, 1.2], theta0=[0.0])
    ds["forcing_amplitude"].attrs.update(units="rad s-2", long_name="forcing amplitude")
    fig = sweep.plot.orbit_diagram(ds)
    x, y = fig.axes[0].lines[0].get_data()
    np.testing.assert_array_equal(x, [1.0, 1.0, 1.2, 1.2])
    # wrapping is exact up to the rounding of theta + pi (a few ulp of 2 pi)
    np.testing.assert_allclose(y, [-np.pi / 2, -np.pi, 0.25, 0.25], rtol=0, atol=1e-14)
    omega_fig = sweep.plot.orbit_diagram(ds, variable="omega")
    np.testing.assert_array_equal(omega_fig.axes[0].lines[0].get_data()[1],
                                  [1.0, -2.0, 0.5, 0.5])
    assert omega_fig.axes[0].get_ylabel().endswith("[rad/s]")
    degrees = sweep.plot.orbit_diagram(ds, degrees=True)
    # the same angles in degrees (rounding of the conversion only)
    np.testing.assert_allclose(degrees.axes[0].lines[0].get_data()[1],
                               [-90.0, -180.0, np.degrees(0.25), np.degrees(0.25)],
                               rtol=0, atol=1e-12)
    assert degrees.axes[0].get_ylabel().endswith("[deg]")


def test_period_map_refuses_what_it_cannot_draw():
    import xarray as xr

    periods = xr.DataArray(np.ones((2, 3, 2), dtype=np.int32),
                           dims=("forcing_amplitude", "forcing_frequency", "theta0"),
                           coords={"forcing_amplitude": [1.0, 1.1],
                                   "forcing_frequency": [0.5, 0.6, 0.7],
                                   "theta0": [0.0, 1.0]}, name="period")
    with pytest.raises(ValueError, match=r"needs a 2-D variable; period has dimensions "
                                         r"\(forcing_amplitude, forcing_frequency, theta0\)"):
        sweep.plot.period_map(periods)
    plane = periods.isel(theta0=0)
    short = xr.zeros_like(plane.isel(forcing_frequency=[0, 1]), dtype=float)
    with pytest.raises(ValueError, match=r"lyapunov has shape \(2, 2\), the periods "
                                         r"\(3, 2\); accepted: lyapunov_max of the same run"):
        sweep.plot.period_map(plane, lyapunov=short)


# ------------------------------------------------------------------ periodicity map plot
def test_period_map_names_each_period_none_and_chaos():
    import xarray as xr

    periods = xr.DataArray(np.array([[1, 1, 2], [4, -1, -1]], dtype=np.int32),
                           coords={"forcing_amplitude": [1.0, 1.1],
                                   "forcing_frequency": [0.5, 0.6, 0.7]},
                           dims=("forcing_amplitude", "forcing_frequency"), name="period")
    lyapunov = xr.zeros_like(periods, dtype=float) - 0.1
    lyapunov[1, 2] = 0.2  # one chaotic cell
    fig = sweep.plot.period_map(periods, lyapunov=lyapunov)
    bar = fig.axes[1]
    labels = [t.get_text() for t in bar.get_yticklabels()]
    assert labels == ["period 1", "period 2", "period 4", "none", "chaotic"]
    codes = np.asarray(fig.axes[0].collections[0].get_array()).reshape(3, 2)  # (y, x)
    assert codes[2, 1] == 4 and codes[1, 1] == 3 and codes[0, 0] == 0
    without = sweep.plot.period_map(periods)
    assert [t.get_text() for t in without.axes[1].get_yticklabels()][-1] == "none"


# ------------------------------------------------------------------ bad input
def test_period_needs_strobe_samples_and_sane_options():
    ds = _run([1.06], samples=16, transient=20)
    with pytest.raises(ValueError, match="max_period must be an int from 1 to 8"):
        maps.period(ds, max_period=9)
    with pytest.raises(ValueError, match="tol must be a finite number > 0"):
        maps.period(ds, tol=0.0)
    with pytest.raises(ValueError, match="strobe"):
        maps.period(ds.drop_vars(["strobe_theta", "strobe_omega"]))


def test_orbit_diagram_errors_name_what_is_accepted():
    ds = _run([1.06], samples=16, transient=20)  # the previous test's run (and kernel)
    with pytest.raises(ValueError, match="along = 'damping' is not a grid axis of this "
                                         r"dataset \(it is held fixed in this run: a "
                                         r"dataset attribute\); accepted: "
                                         "'forcing_amplitude', 'theta0', 'omega0'"):
        sweep.plot.orbit_diagram(ds, along="damping")
    with pytest.raises(ValueError, match="variable must be 'theta' or 'omega'"):
        sweep.plot.orbit_diagram(ds, variable="phase")
    with pytest.raises(ValueError, match="needs stroboscopic samples"):
        sweep.plot.orbit_diagram(ds.drop_vars(["strobe_theta"]))


@pytest.mark.parametrize("value, kind, message", [
    (1, ValueError, "strobe_samples must be an int from 2 to 4096"),
    (5000, ValueError, "strobe_samples must be an int from 2 to 4096"),
    (16.0, TypeError, "strobe_samples must be an int"),
    (True, TypeError, "strobe_samples must be an int"),
])
def test_strobe_samples_out_of_range(value, kind, message, no_compute):
    with pytest.raises(kind, match=message):
        sweep.run(_taylor_scene(), sweep.Grid(theta0=[0.0], omega0=[0.0]), t_end=2.0,
                  dt=0.01, observe=("strobe",), strobe_samples=value)


def test_strobe_samples_without_strobe_is_refused(no_compute):
    with pytest.raises(ValueError, match="strobe_samples = 64 is read only by the 'strobe' "
                                         "observable"):
        sweep.run(_taylor_scene(), sweep.Grid(theta0=[0.0], omega0=[0.0]), t_end=2.0,
                  dt=0.01, observe=("final",), strobe_samples=64)


def test_sweep_plot_orbit_diagram_from_the_command_line(tmp_path, capsys):
    """`sweep plot FILE --orbit-diagram AXIS` draws it; an axis that is not in the file
    is one line and status 2."""
    from sweep import cli

    path = tmp_path / "cascade.nc"
    # 24 samples: the kernel of test_orbit_diagram_draws_every_sample_above_its_gamma
    sweep.save(_run([1.06, 1.072], samples=24, transient=40), path)
    assert cli.main(["plot", str(path), "--orbit-diagram", "forcing_amplitude",
                     "-o", str(tmp_path / "od.png")]) == 0
    assert (tmp_path / "od.png").stat().st_size > 0
    assert cli.main(["plot", str(path), "--orbit-diagram", "damping",
                     "-o", str(tmp_path / "bad.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "along = 'damping' is not a grid axis" in err[0]
