"""The guards before compute and the flags after it (issue 25): huge starts never end in a
traceback from a guard, a step that cannot resolve a drive is refused (with the threshold
derived from the method on a sinusoid and checked against a real run's closed form),
and angles beyond the range of the kernel's sine are refused at the start and flagged
when a trajectory reaches them."""

import math
import re

import numpy as np
import pytest
from shared_kernels import EVERY, EVERY_ADAPTIVE

import sweep
from sweep.kernels import KernelSpec, Status
from sweep.kernels.vecmath import SIN32_RANGE, SIN_RANGE
from sweep.methods import resolve
from sweep.stability import DRIVE_TOLERANCE, drive_error, drive_step_limit, eigenvalues

RUN = dict(t_end=1.0, dt=0.01)


# ------------------------------------------------------------------ huge starts
def test_a_huge_start_fails_per_trajectory_not_in_the_guard():
    """The regression: omega0 = 1e300 made the energy bound's ``omega0 ** 2`` raise
    OverflowError. Now that trajectory is flagged and the other one is untouched."""
    scene = sweep.Scene(effects=(sweep.Damping(0.5),))
    # every observable (tests/shared_kernels.py): test_points' kernel of this scene
    with pytest.warns(RuntimeWarning, match="1 of 2 trajectories"):
        ds = sweep.run(scene, sweep.Grid(theta0=[0.3], omega0=[1.0, 1e300]), **RUN,
                       observe=EVERY)
    alone = sweep.run(scene, sweep.Grid(theta0=[0.3], omega0=[1.0]), **RUN, observe=EVERY)
    assert ds.status.values.tolist() == [[Status.OK, Status.NONFINITE]]
    assert np.isnan(ds.theta_final.values[0, 1])
    assert ds.theta_final.values[0, 0] == alone.theta_final.values[0, 0]


def test_a_huge_start_with_drag_is_refused_by_the_stability_guard(no_compute):
    """Drag's damping ``2 k omega_max`` at 1e300 rad/s is 2e299 1/s: a clear refusal
    (eigenvalues computed without ``c^2``, which overflowed into a LinAlgError)."""
    scene = sweep.Scene(effects=(sweep.QuadraticDrag(0.1),))
    with pytest.raises(ValueError, match=r"dt = 0\.01 exceeds RK4's stability limit .*"
                                         r"check_stability=False"):
        sweep.run(scene, sweep.Grid(theta0=[0.3], omega0=[1.0, 1e300]), **RUN)


def test_an_overflowing_stiffness_is_refused_by_name(no_compute):
    scene = sweep.Scene(gravity=1e300, length=1e-300)
    with pytest.raises(ValueError, match=r"stiffness of inf .* accepted: finite g/L"):
        sweep.run(scene, sweep.Grid(theta0=[0.3]), **RUN)


@pytest.mark.parametrize("c, w2", [(0.5, 9.81), (100.0, 9.81), (2 * math.sqrt(9.81), 9.81),
                                   (1e-3, 1e4), (2e299, 9.81)])
def test_eigenvalues_solve_the_characteristic_equation(c, w2):
    """Oracle: ``lambda^2 + c lambda + w^2 = 0``, written as the sum ``-c`` and product
    ``w^2`` of the two roots (Vieta), to a few ulps of the larger term."""
    one, two = eigenvalues(c, w2)
    assert abs((one + two) + c) <= 1e-12 * max(c, math.sqrt(w2))
    assert abs(one * two - w2) <= 1e-12 * w2


# ------------------------------------------------------------- drive resolution
@pytest.mark.parametrize("effect, axis", [
    (sweep.Forcing(1.0, frequency=1000.0), "forcing_frequency"),
    (sweep.PivotDrive(0.01, frequency=1000.0), "pivot_frequency"),
])
def test_an_unresolved_drive_is_refused(effect, axis, no_compute):
    """The issue's cases: W dt = 10 rad per step."""
    scene = sweep.Scene(effects=(sweep.Damping(0.5), effect))
    with pytest.raises(ValueError, match=rf"{axis} = 1000\.0 rad/s is not resolved by "
                                         r"dt = 0\.01 s: 10 rad per step \(0\.628 steps per "
                                         r"period\).*accepted: dt <= 0\.00169 s"):
        sweep.run(scene, sweep.Grid(theta0=[0.3]), **RUN)


def test_every_drive_frequency_on_the_grid_is_checked(no_compute):
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Forcing(1.0, frequency=1.0)))
    with pytest.raises(ValueError, match=r"forcing_frequency = 500\.0 rad/s"):
        sweep.run(scene, sweep.Grid(theta0=[0.3], forcing_frequency=[1.0, 500.0]), **RUN)
    pivot = sweep.Scene(effects=(sweep.PivotDrive(0.001, frequency=10.0),))
    with pytest.raises(ValueError, match=r"pivot_frequency = 400\.0 rad/s .* DOPRI5"):
        sweep.run(pivot, sweep.Grid(theta0=[0.3], pivot_frequency=[10.0, 400.0]), **RUN,
                  method="dopri5")  # its largest step dt: 4 rad per step > 3.24


def test_check_stability_false_integrates_an_unresolved_drive():
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Forcing(1.0, frequency=1000.0)))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.3]), **RUN, check_stability=False)
    assert ds.status.values.tolist() == [Status.OK]


def test_a_resolved_drive_at_the_limit_is_accepted():
    limit = drive_step_limit(resolve("rk4"))
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Forcing(1.0, frequency=1.0)))
    grid = sweep.Grid(theta0=[0.3], forcing_frequency=[0.99 * limit / 0.01])
    assert sweep.run(scene, grid, **RUN).status.values.tolist() == [[Status.OK]]


@pytest.mark.parametrize("method, order", [("euler", 1), ("heun", 2), ("rk4", 4),
                                           ("rk38", 4), ("dopri5", 5)])
def test_drive_error_converges_at_the_method_order(method, order):
    """Oracle: the measured order of `drive_error` as ``W dt -> 0`` is the method's
    order (a slope from a factor-2 ladder; 0.05 allows the next term's share at
    x = 0.02-0.04; DOPRI5 at 0.1-0.2, where its error is still far above rounding)."""
    tableau = resolve(method)
    x = np.array([0.04, 0.02]) if order < 5 else np.array([0.2, 0.1])
    errors = [drive_error(tableau, v) for v in x]
    assert math.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.05)


def _steady_response_error(method: str, x: float) -> float:
    """The complex amplitude of theta fitted to a real run's steady window, against the
    closed form of the driven damped linear oscillator ``theta'' + c theta' + theta =
    sin(W t)``: ``Z = -i / (1 - W^2 + i c W)``. W = 16 rad/s and w0 = 1 rad/s, so the
    run is near the forced double integrator that `drive_error` describes."""
    frequency, damping = 16.0, 2.0
    dt = x / frequency
    scene = sweep.Scene(gravity=1.0, length=1.0, model="linear",
                        effects=(sweep.Damping(damping), sweep.Forcing(1.0, frequency)))
    ds = sweep.run(scene, sweep.Grid(theta0=[0.0], omega0=[0.0]), t_end=dt * round(30 / dt),
                   dt=dt, method=method, observe=(), save_every=1, check_stability=False)
    t, theta = ds.time.values, ds.theta.values.reshape(-1)
    steady = t > 15.0  # e^(-c t / 2) = e^-15: the start is forgotten
    basis = np.column_stack([np.cos(frequency * t[steady]), np.sin(frequency * t[steady])])
    a, b = np.linalg.lstsq(basis, theta[steady], rcond=None)[0]
    exact = -1j / (1.0 - frequency ** 2 + 1j * damping * frequency)
    return abs((a - 1j * b) / exact - 1.0)


@pytest.mark.parametrize("method", ["heun", "rk4"])
def test_the_drive_threshold_separates_resolved_from_unresolved_runs(method):
    """A real run against a closed form: the measured error of the steady response is
    `drive_error`'s prediction within 15 % (the oscillator's own w0 dt and damping,
    which the double integrator leaves out, shift it by up to ~8 %, measured), so at
    half the limit it is well within the 1 % tolerance and at 1.3x the limit beyond."""
    tableau = resolve(method)
    limit = drive_step_limit(tableau)
    for factor in (0.5, 1.3):
        measured = _steady_response_error(method, factor * limit)
        assert measured == pytest.approx(drive_error(tableau, factor * limit), rel=0.15)
    assert _steady_response_error(method, 0.5 * limit) < DRIVE_TOLERANCE
    assert _steady_response_error(method, 1.3 * limit) > DRIVE_TOLERANCE


# ----------------------------------------------------------------- angle range
@pytest.mark.parametrize("dtype, limit", [("float64", SIN_RANGE), ("float32", SIN32_RANGE)])
def test_starts_beyond_the_sine_range_are_refused(dtype, limit, no_compute):
    scene = sweep.Scene(effects=(sweep.Damping(0.5),))
    with pytest.raises(ValueError, match=re.escape(f"theta0 = {10 * limit!r} rad (index 1) "
                                                   "is beyond") + rf".*\({dtype}\); accepted: "
                                         + re.escape(f"|theta0| <= {limit:g} rad")):
        sweep.run(scene, sweep.Grid(theta0=[0.3, 10 * limit]), **RUN, dtype=dtype)


def test_the_linear_model_takes_no_sine_of_the_angle():
    assert KernelSpec(model="linear", effects=(), observe=("final",)).angle_limit is None
    assert KernelSpec(model="linear", effects=(), observe=("tension",)).angle_limit \
        == SIN_RANGE
    ds = sweep.run(sweep.Scene(model="linear"), sweep.Grid(theta0=[1e16]), **RUN)
    assert ds.status.values.tolist() == [Status.OK]


@pytest.mark.parametrize("method", ["rk4", "dopri5"])
def test_a_trajectory_leaving_the_range_is_flagged(method):
    """omega0 = 1e14 rad/s carries theta past 1e12 rad within 0.01 s: its outputs are NaN
    and its status says why; the start within the range is unaffected."""
    with pytest.warns(RuntimeWarning, match=r"1 angle_out_of_range"):
        # dopri5 with every observable it takes: test_methods' kernel of this scene
        ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.3], omega0=[1.0, 1e14]),
                       **{**RUN, "method": method,
                          **({"observe": EVERY_ADAPTIVE} if method == "dopri5" else {})})
    assert ds.status.values.tolist() == [[Status.OK, Status.ANGLE_OUT_OF_RANGE]]
    assert np.isnan(ds.theta_final.values[0, 1]) and np.isnan(ds.omega_final.values[0, 1])
    assert "angle_out_of_range" in ds.status.attrs["flag_meanings"].split()


def test_samples_beyond_the_range_are_nan_and_those_before_kept():
    with pytest.warns(RuntimeWarning, match="angle_out_of_range"):
        ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.3], omega0=[1e14]), **RUN,
                       save_every=25, observe=EVERY)  # test_oracles' kernel
    theta, omega = ds.theta.values.reshape(-1), ds.omega.values.reshape(-1)
    assert theta[0] == 0.3 and omega[0] == 1e14  # the start, with its sine accurate
    assert np.isnan(theta[1:]).all() and np.isnan(omega[1:]).all()
