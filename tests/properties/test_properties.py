"""Properties that hold for every input, checked on inputs Hypothesis draws.

Grids are tiny (at most 27 trajectories, 500 steps) and every run uses one of two
kernels (nonlinear with a damping axis, observing final, winding and energy; the same
saving samples), so the folder runs in about 10 s.
"""

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import sweep
from sweep import maps, metrics
from sweep.kernels import Status

PROFILE = settings.get_profile("sweep-properties")
SCENE = sweep.Scene(gravity=1.0, length=1.0)  # w = 1 rad/s
OBSERVE = ("final", "winding", "energy")
RUN = {"t_end": 5.0, "dt": 0.01, "observe": OBSERVE}  # 500 steps
N_STEPS = 500

angles = st.floats(-10.0, 10.0, allow_nan=False)
speeds = st.floats(-6.0, 6.0, allow_nan=False)
dampings = st.floats(0.0, 2.0, allow_nan=False)
small = {"min_size": 1, "max_size": 3, "unique": True}


def _run(theta0, omega0, damping, **kwargs):
    grid = sweep.Grid(theta0=list(theta0), omega0=list(omega0), damping=list(damping))
    return sweep.run(SCENE, grid, **{**RUN, **kwargs})


@settings(PROFILE)
@given(st.lists(angles, **small), st.lists(speeds, **small), st.lists(dampings, **small))
def test_unforced_motion_is_mirror_symmetric(theta0, omega0, damping):
    """theta'' = -c theta' - (g/L) sin theta is odd: (theta0, omega0) -> (-theta0,
    -omega0) gives (-theta, -omega). Every operation of the RK4 step is odd-exact in
    IEEE arithmetic (negation, products, sums, sin(-x) = -sin(x)), so the mirror image is
    bit-exact, and so are the winding (a difference of roundings half to even, which
    are odd) and the energy (even)."""
    a = _run(theta0, omega0, damping)
    b = _run([-x for x in theta0], [-x for x in omega0], damping)
    np.testing.assert_array_equal(b.theta_final.values, -a.theta_final.values)
    np.testing.assert_array_equal(b.omega_final.values, -a.omega_final.values)
    np.testing.assert_array_equal(b.winding.values, -a.winding.values)
    np.testing.assert_array_equal(b.energy_final.values, a.energy_final.values)


@settings(PROFILE)
@given(angles, speeds, dampings, st.integers(-3, 3).filter(bool))
def test_a_2pi_shift_changes_only_theta_by_2pi(theta0, omega0, damping, turns):
    """theta0 -> theta0 + 2 pi k: the same motion, theta shifted by 2 pi k; the winding
    round(theta_final / 2 pi) - round(theta0 / 2 pi) and the energy are unchanged. Not
    bit-exact: theta0 + 2 pi k rounds by ulp(|theta0| + 6 pi) <= 3.6e-15, and every step
    rounds the shifted angle again; the flow's Jacobian has norm <= max(1, g/L) = 1, so
    differences grow at most like e^t: n ulp e^T = 500 * 3.6e-15 * e^5 = 2.7e-10; bound
    1e-9."""
    shift = 2 * math.pi * turns
    a = _run([theta0], [omega0], [damping])
    b = _run([theta0 + shift], [omega0], [damping])
    assert abs(float(b.theta_final.values.ravel()[0]) - float(a.theta_final.values.ravel()[0])
               - shift) < 1e-9
    assert abs(float(b.omega_final.values.ravel()[0]) - float(a.omega_final.values.ravel()[0])) \
        < 1e-9
    assert abs(float(b.energy_final.values.ravel()[0]) - float(a.energy_final.values.ravel()[0])) \
        < 1e-9
    # the winding is a difference of well indices: equal unless the start or the end
    # sits within the difference bound of a top, an odd multiple of pi (then either
    # side is right)
    ends = np.array([theta0, float(a.theta_final.values.ravel()[0])]) / (2 * math.pi)
    assume(np.all(np.abs(np.abs(ends - np.round(ends)) - 0.5) > 1e-8))
    assert int(b.winding.values.ravel()[0]) == int(a.winding.values.ravel()[0])


@settings(PROFILE)
@given(st.lists(angles, **small), st.lists(speeds, **small), st.lists(dampings, **small))
def test_damped_unforced_energy_never_increases(theta0, omega0, damping):
    """dE/dt = -c omega^2 <= 0. RK4 adds an error of O((w dt)^4) per unit time and
    energy, of either sign (measured +4.8e-14 on a 3-turn rotation just above the
    separatrix, undamped): tolerance 1e-9 (1 + E0) covers 500 steps with a margin."""
    ds = _run(theta0, omega0, damping)
    assert (ds.status == Status.OK).all()
    e0, e1 = ds.energy_initial.values, ds.energy_final.values
    assert np.all(e1 <= e0 + 1e-9 * (1 + e0))
    assert np.all(e1 >= 0)


@settings(PROFILE)
@given(st.lists(angles, **small), st.lists(speeds, **small), st.lists(dampings, **small))
def test_labels_stay_in_their_documented_sets(theta0, omega0, damping):
    ds = _run(theta0, omega0, damping)
    motion = maps.motion(ds)
    assert set(np.unique(motion.values)) <= {-1, 0, 1}  # all ok: never -127
    basins = maps.basins(ds)
    assert basins.values.dtype.kind == "i" and basins.values.min() >= -1
    assert basins.values.max() < max(len(basins.attrs["attractor_theta"]), 1)
    wells = maps.well(ds).values
    assert np.all(np.isnan(wells) | (wells == np.round(wells)))
    fractions = metrics.basin_fractions(basins)
    assert math.isclose(sum(fractions.values()), 1.0, rel_tol=0, abs_tol=1e-12)
    assert all(0 < f <= 1 for f in fractions.values())


@settings(PROFILE)
@given(hnp.arrays(np.int64, hnp.array_shapes(min_dims=1, max_dims=3, max_side=6),
                  elements=st.integers(-1, 5)))
def test_basin_fractions_sum_to_one(labels):
    fractions = metrics.basin_fractions(labels)
    # each fraction is count / size: the sum's rounding is at most one ulp per label
    assert math.isclose(sum(fractions.values()), 1.0, rel_tol=0, abs_tol=1e-12)
    assert set(fractions) == set(np.unique(labels).tolist())
    if np.any(labels != -1):
        resolved = metrics.basin_fractions(labels, ignore=-1)
        assert math.isclose(sum(resolved.values()), 1.0, rel_tol=0, abs_tol=1e-12)
        assert -1 not in resolved


@settings(PROFILE)
@given(st.lists(angles, **small), st.lists(speeds, **small), st.lists(dampings, **small),
       st.sampled_from([None, 100]))
def test_save_load_identity(theta0, omega0, damping, save_every):
    ds = _run(theta0, omega0, damping, save_every=save_every)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "run.nc"
        sweep.save(ds, path)
        again = sweep.load(path)
    assert again.identical(ds)
