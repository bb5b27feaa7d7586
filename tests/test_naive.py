"""The compiled kernel equals the slow pure-Python reference (`naive.py`) to round-off.

Both integrate the same equation with the same RK4 scheme and the same forcing-time
convention (t_n, t_n + dt/2, t_n + dt with t_n = t0 + n dt), so they may differ only by
floating-point rounding (evaluation order, libm vs LLVM math, possible FMA
contraction). Any modelling slip -- a wrong sign, a stage evaluated at the wrong time,
an observable accumulated over the wrong steps, a parameter read from the wrong
column -- shows up as a difference many orders of magnitude above that.

Tolerance (used everywhere below): |kernel - naive| <= 1e-12 * (1 + scale), where
scale is the largest magnitude the quantity reaches (e.g. max |theta| along the
trajectory). Why: each step adds at most a few ulp (2.2e-16 relative) of the largest
magnitudes involved; over the <= 500 steps used here that accumulates to at most
~500 * 4 * 2.2e-16 ~ 4e-13 even if every rounding error added up, and the horizons
(5 s) are short enough that the dynamics amplifies it only mildly (observed: ~1e-15
relative). Comparing against the largest magnitude rather than the value itself avoids
a spurious relative failure when theta or omega happens to pass near zero.
"""

import itertools
import math

import numpy as np
import pytest
from shared_kernels import EVERY

import sweep

import naive

ALL_OBSERVE = EVERY  # every observable; tests/shared_kernels.py shares their kernels
SCALARS = ("theta_final", "omega_final", "theta_max", "amplitude", "omega_mean",
           "tension_min",
           "tension_max", "energy_initial", "energy_final", "top_distance_max")
COMBINATIONS = list(itertools.product(("nonlinear", "linear"), (False, True), (False, True)))
COMBO_IDS = [f"{m}-{'damped' if d else 'free'}-{'forced' if f else 'unforced'}"
             for m, d, f in COMBINATIONS]

#: Relative round-off tolerance; see the module docstring for its size.
RTOL = 1e-12
T0 = 0.7            # nonzero, so that the forcing-time convention t0 + n dt is exercised
DT = 0.01
N_STEPS = 500       # t_end - t0 = 5 s: long enough to swing and rotate, short enough
T_END = T0 + N_STEPS * DT  # that chaos cannot amplify round-off to the tolerance


def _random_case(model, damping, forcing, seed):
    """A scene with random parameters and a 3 x 2 grid of random initial states."""
    rng = np.random.default_rng([20261121, seed])
    effects = []
    if damping:
        effects.append(sweep.Damping(rng.uniform(0.1, 1.0)))
    if forcing:
        effects.append(sweep.Forcing(amplitude=rng.uniform(0.5, 2.0),
                                     frequency=rng.uniform(0.3, 3.0),
                                     phase=rng.uniform(-np.pi, np.pi)))
    scene = sweep.Scene(gravity=rng.uniform(5.0, 15.0), length=rng.uniform(0.5, 2.0),
                        model=model, effects=tuple(effects))
    # theta0 up to +-3 rad and omega0 up to +-6 rad/s: librations and rotations alike
    grid = sweep.Grid(theta0=rng.uniform(-3.0, 3.0, 3), omega0=rng.uniform(-6.0, 6.0, 2))
    return scene, grid


def _naive_point(scene, point, **kwargs):
    """Run the reference for one grid point (a dict of axis values over the scene)."""
    params = {**scene.parameters(), "theta0": 0.0, "omega0": 0.0, **point}
    theta0, omega0 = params.pop("theta0"), params.pop("omega0")
    return naive.integrate(theta0, omega0, model=scene.model, **params, **kwargs)


def _points(grid):
    """Yield (index tuple, {axis: value}) for every point of the grid, C order."""
    axes = grid.axes
    for index in np.ndindex(grid.shape):
        yield index, {name: float(values[k]) for (name, values), k in zip(axes.items(), index)}


def _assert_close(actual, expected, scale, what):
    """|actual - expected| <= RTOL * (1 + scale); see the module docstring."""
    actual, expected = np.asarray(actual), np.asarray(expected)
    assert np.all(np.isfinite(actual)), what
    np.testing.assert_allclose(actual, expected, rtol=0, atol=RTOL * (1.0 + scale),
                               err_msg=what)


def _check_point(ds, index, point, ref, what):
    """Every observable of grid point ``index`` (axis values ``point``) of ``ds``
    against the reference."""
    scales = {
        "theta_final": np.max(np.abs(ref["theta_all"])),
        "omega_final": np.max(np.abs(ref["omega_all"])),
        "theta_max": np.max(np.abs(ref["theta_all"])),
        "amplitude": np.max(np.abs(ref["theta_all"])),
        # a difference of angles divided by the window (>= 3.7 s here): its round-off
        # is at most that of the angles, so max |theta| + max |omega| bounds the scale
        "omega_mean": np.max(np.abs(ref["theta_all"])) + np.max(np.abs(ref["omega_all"])),
        "tension_min": max(ref["tension_max"], abs(ref["tension_min"])),
        "tension_max": max(ref["tension_max"], abs(ref["tension_min"])),
        "energy_initial": abs(ref["energy_initial"]),
        "energy_final": max(abs(ref["energy_initial"]), abs(ref["energy_final"])),
        # |theta mod 2 pi - pi|: the round-off of the angle it is taken of, plus the
        # reduction's (2 pi and pi are at most ~7 in size)
        "top_distance_max": np.max(np.abs(ref["theta_all"])) + 2 * math.pi,
    }
    assert int(ds["status"].values[index]) == int(sweep.Status.OK), what
    for name in SCALARS:
        _assert_close(ds[name].values[index], ref[name], scales[name], f"{what}: {name}")
    # winding is an integer (passes over the top; the reference counts them step by
    # step), so compare it exactly -- unless the start or the end lies within round-off
    # (1e-9 of a turn, far above the 1e-12 the angles agree to) of a top, an odd
    # multiple of pi, where either neighbouring count is right.
    ends = np.array([point.get("theta0", 0.0), ref["theta_final"]]) / (2 * math.pi)
    if np.all(np.abs(np.abs(ends - np.round(ends)) - 0.5) > 1e-9):
        assert ds["winding"].values[index] == ref["winding"], f"{what}: winding"
    else:
        assert abs(ds["winding"].values[index] - ref["winding"]) <= 1, f"{what}: winding"


# ------------------------------------------------------------------ observables
@pytest.mark.parametrize("t_transient", [0.0, 1.0, 1.234],
                         ids=["no-transient", "transient-on-a-step", "transient-between-steps"])
@pytest.mark.parametrize("model,damping,forcing", COMBINATIONS, ids=COMBO_IDS)
def test_every_observable_equals_naive_rk4(model, damping, forcing, t_transient):
    seed = COMBINATIONS.index((model, damping, forcing))
    scene, grid = _random_case(model, damping, forcing, seed)
    ds = sweep.run(scene, grid, t_end=T_END, dt=DT, t0=T0, t_transient=t_transient,
                   observe=ALL_OBSERVE)
    for index, point in _points(grid):
        ref = _naive_point(scene, point, t_end=T_END, dt=DT, t0=T0, t_transient=t_transient)
        _check_point(ds, index, point, ref, f"{point}")


# ------------------------------------------------------------- sampled trajectories
@pytest.mark.parametrize("model,damping,forcing", COMBINATIONS, ids=COMBO_IDS)
def test_sampled_trajectory_equals_naive_rk4(model, damping, forcing):
    seed = 100 + COMBINATIONS.index((model, damping, forcing))
    scene, grid = _random_case(model, damping, forcing, seed)
    save_every = 7  # does not divide N_STEPS = 500: the last sample is step 497
    ds = sweep.run(scene, grid, t_end=T_END, dt=DT, t0=T0, t_transient=1.234,
                   observe=ALL_OBSERVE, save_every=save_every)
    assert ds.sizes["time"] == N_STEPS // save_every + 1
    for index, point in _points(grid):
        ref = _naive_point(scene, point, t_end=T_END, dt=DT, t0=T0, t_transient=1.234,
                           save_every=save_every)
        # the time coordinate is t0 + n dt at the saved steps n = 0, k, 2k, ...;
        # 1e-12 s: both sides compute t0 + n*dt in one or two roundings (~1e-15 s)
        np.testing.assert_allclose(ds["time"].values, ref["time"], rtol=0, atol=1e-12)
        _assert_close(ds["theta"].values[index], ref["theta"],
                      np.max(np.abs(ref["theta_all"])), f"{point}: sampled theta")
        _assert_close(ds["omega"].values[index], ref["omega"],
                      np.max(np.abs(ref["omega_all"])), f"{point}: sampled omega")
        # the first sample is the initial state itself, bit for bit
        assert ds["theta"].values[index][0] == point.get("theta0", 0.0)
        assert ds["omega"].values[index][0] == point.get("omega0", 0.0)
        # a kernel with saving on must compute the same observables as one without
        _check_point(ds, index, point, ref, f"{point} (with save_every)")


# ------------------------------------------------- every parameter as a grid axis
@pytest.mark.parametrize("model", ["nonlinear", "linear"])
def test_every_parameter_axis_reaches_the_kernel(model):
    """Each trajectory reads its own row of parameters: all eight parameters are grid
    axes (two values for five of them, one for the other three -- 32 trajectories keep
    the pure-Python reference quick; the single values still differ from the scene's,
    so they must come from the grid). A parameter read from the wrong column, or a
    damping axis that did not switch damping on, changes the trajectory by far more
    than round-off."""
    rng = np.random.default_rng([20261121, 7, model == "linear"])
    scene = sweep.Scene(gravity=9.81, length=1.0, model=model,
                        effects=(sweep.Forcing(amplitude=0.3, frequency=1.0, phase=0.0),))
    grid = sweep.Grid(
        theta0=rng.uniform(-3.0, 3.0, 2),
        omega0=rng.uniform(-4.0, 4.0, 1),
        damping=rng.uniform(0.1, 1.0, 2),
        forcing_amplitude=rng.uniform(0.5, 2.0, 2),
        forcing_frequency=rng.uniform(0.3, 3.0, 1),
        forcing_phase=rng.uniform(-np.pi, np.pi, 2),
        length=rng.uniform(0.5, 2.0, 2),
        gravity=rng.uniform(5.0, 15.0, 1),
    )
    t_end, dt = T0 + 200 * DT, DT  # 32 trajectories: 2 s each keeps the reference quick
    ds = sweep.run(scene, grid, t_end=t_end, dt=dt, t0=T0, t_transient=0.5,
                   observe=ALL_OBSERVE)
    for index, point in _points(grid):
        ref = _naive_point(scene, point, t_end=t_end, dt=dt, t0=T0, t_transient=0.5)
        _check_point(ds, index, point, ref, f"{point}")
