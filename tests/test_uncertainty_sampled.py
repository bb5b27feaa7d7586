"""`sweep.maps.uncertainty_sampled`: Grebogi et al.'s uncertainty exponent from random
pairs of starts, against maps of known boundary dimension and the pendulum's maps.

Tolerances: ``alpha`` is compared with its exact value within 3 of its standard errors
(a correct estimate lands outside with probability about 0.3 %; every seed is fixed, so
each test is deterministic), and the standard error itself is bounded so that a
test cannot pass by an error bar wide enough to hold anything.
"""

import math

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import maps

#: alpha of the McDonald-Grebogi-Ott-Yorke map (see test_mgoy_map_alpha_is_ln_1_5_over_ln_3)
MGOY_ALPHA = math.log(1.5) / math.log(3.0)
MGOY_BOX = ((0.0, 1.0), (-2.0, 2.0))
DECADES = 10.0 ** -np.arange(3, 10)  # 1e-3 ... 1e-9 of the box

DAMPED = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.2),))
#: captured starts stop at once: a few thousand starts cost a fraction of a second
WELLS_RUN = dict(t_end=40.0, dt=0.02, observe=("capture",), stop_early=True)
PHASE_BOX = ((-np.pi, np.pi), (-4.0, 4.0))


def mgoy_labels(starts, iterations=80):
    """Which attractor, y -> +inf (1) or y -> -inf (0), each start of the map
    x -> 3x mod 1, y -> 1.5y + cos(2 pi x) goes to: once |y| > 2 the sign of y never
    changes (|1.5y + cos| >= 1.5|y| - 1 > |y|); 80 iterations take every start farther
    than 2 * 1.5**-80 (about 2e-14) from the boundary there."""
    x, y = starts[:, 0].copy(), starts[:, 1].copy()
    for _ in range(iterations):
        y = 1.5 * y + np.cos(2 * np.pi * x)
        x = (3.0 * x) % 1.0
    return (y > 0).astype(np.int64)


def test_mgoy_map_alpha_is_ln_1_5_over_ln_3():
    """McDonald, Grebogi, Ott and Yorke's map (Physica D 17, 125 (1985)).

    Derivation: the boundary is the set of starts whose y stays bounded; unrolling
    y_{n+1} = 1.5 y_n + cos(2 pi x_n) gives
    y_n = 1.5**n (y_0 + sum_{k<n} 1.5**-(k+1) cos(2 pi 3**k x_0)), bounded iff
    y_0 = g(x_0) = -sum_{k>=0} 1.5**-(k+1) cos(2 pi 3**k x_0), a Weierstrass function
    W(x) = sum a**k cos(2 pi b**k x) with a = 1/1.5 and b = 3 (a b = 2 > 1). Over an
    interval of width h its graph rises and falls by about h**H with
    H = -ln a / ln b = ln 1.5 / ln 3 (the terms with b**k h < 1 add up to
    h sum (a b)**k ~ h (ab)**(ln(1/h)/ln b) = h**H, the others to a**(ln(1/h)/ln b) =
    h**H), so covering it with boxes of side h takes h**-1 columns of h**(H - 1) boxes
    each: box-counting dimension d = 2 - H (Kaplan, Mallet-Paret, Yorke 1984). A start
    is eps-uncertain when the graph passes within eps of it, a set of area
    eps**(2 - d), so alpha = 2 - d = ln 1.5 / ln 3 = 0.3691."""
    result = maps.uncertainty_sampled(mgoy_labels, MGOY_BOX, eps=DECADES, n=20000, seed=0)
    assert abs(result.alpha - MGOY_ALPHA) < 3 * result.alpha_error
    # binomial counts of 3 to 450 per level give about 0.015 (measured 0.0152); 0.05
    # still tells 0.37 from a smooth boundary's 1 by over 10 errors
    assert result.alpha_error < 0.05
    assert result.dimension == pytest.approx(2.0 - result.alpha, abs=1e-15)  # rounding
    assert all(result.used) and result.pairs == (20000,) * DECADES.size
    # the table: eps increasing, f = uncertain / pairs, f_error binomial
    np.testing.assert_array_equal(result.eps, np.sort(DECADES))
    f = np.asarray(result.uncertain) / 20000
    np.testing.assert_array_equal(result.f, f)
    np.testing.assert_allclose(result.f_error, np.sqrt(f * (1 - f) / 20000), rtol=1e-14)


def test_grebogi_map_alpha_is_the_published_0_2():
    """The map with which Grebogi et al. (1983) introduced the uncertainty exponent
    (tests/test_metrics.py's grebogi_map_basins): alpha ~ 0.2, given to one significant
    figure, so its rounding interval 0.15 .. 0.25 (measured 0.192 to 0.195 +- 0.002 over
    three seeds with 20,000 pairs per level, down to 1e-9 of the box)."""
    def grebogi_labels(starts):
        theta, x = starts[:, 0].copy(), starts[:, 1].copy()
        for _ in range(100):  # every orbit has reached a fixed point (test_metrics)
            theta, x = (np.mod(theta + 1.32 * np.sin(2 * theta) - 0.9 * np.sin(4 * theta)
                               - x * np.sin(theta), 2 * np.pi), -0.3 * np.cos(theta))
        return np.cos(theta) > 0

    result = maps.uncertainty_sampled(grebogi_labels, ((0, 2 * np.pi), (-0.5, 0.5)),
                                      eps=10.0 ** -np.arange(2, 10), n=5000, seed=8)
    assert 0.15 <= result.alpha <= 0.25
    assert result.alpha_error < 0.01  # measured 0.004: the interval is 12 errors wide


def test_half_plane_fraction_is_exact():
    """A straight boundary x = 1 across the box [0, 2] x [0, 1]: a start x (uniform,
    density 1/2 on [0, 2]) moved by eps (2 cos phi, sin phi) crosses it when it lies
    within 2 eps |cos phi| of it on the side the move points to, which has probability
    eps |cos phi|, so f = eps E|cos phi| = 2 eps / pi at every level (the perturbation
    is scaled per axis by the box's sides, in a uniform direction), and alpha = 1."""
    def half_plane(starts):
        return starts[:, 0] > 1.0

    eps = [1e-1, 1e-2, 1e-3, 1e-4]
    result = maps.uncertainty_sampled(half_plane, ((0.0, 2.0), (0.0, 1.0)), eps=eps,
                                      n=100_000, seed=1)
    expected = 2 * np.asarray(result.eps) / np.pi
    # each f is binomial: within 4 standard errors of 2 eps / pi (about 6e-5 chance of a
    # miss per level for a correct implementation)
    assert (np.abs(np.asarray(result.f) - expected)
            < 4 * np.sqrt(expected * (1 - expected) / 100_000)).all()
    assert abs(result.alpha - 1.0) < 3 * result.alpha_error
    assert result.alpha_error < 0.05  # measured 0.009: counts of 7 to 6400 per level


def test_disk_gives_alpha_one():
    """A circle of radius 0.7: smooth, so alpha = 1 (f is eps times the circle's length
    over pi and the box's area, up to curvature corrections of order eps / 0.7)."""
    def disk(starts):
        return (starts[:, 0] ** 2 + starts[:, 1] ** 2 < 0.49).astype(np.int32)

    result = maps.uncertainty_sampled(disk, ((-1.0, 1.0), (-1.0, 1.0)),
                                      eps=[1e-2, 1e-3, 1e-4, 1e-5], n=100_000, seed=2)
    assert abs(result.alpha - 1.0) < 3 * result.alpha_error
    assert result.alpha_error < 0.1  # the 1e-5 level holds a handful of pairs


def test_pendulum_wells_are_smooth():
    """The damped pendulum's wells (c = 0.2): their boundaries are the stable manifolds
    of the upright saddles, smooth curves, so alpha = 1 (measured 0.93 to 1.03 over
    four seeds with 10,000 pairs per level; 20,000 here)."""
    labels_of = maps.scene_labels(DAMPED, maps.well, **WELLS_RUN)
    result = maps.uncertainty_sampled(labels_of, PHASE_BOX, eps=[1e-2, 3e-3, 1e-3, 3e-4],
                                      n=20_000, seed=3)
    assert abs(result.alpha - 1.0) < 3 * result.alpha_error
    assert result.alpha_error < 0.1  # counts of about 20 to 600 per level


def test_forced_wada_scene_is_fractal(wada_catalogue):
    """The forced Wada scene (c = 0.2, A = 1.66, W = 1): three basins sharing a fractal
    boundary, alpha well below 1 (measured 0.147 +- 0.008 with 500 pairs per level).
    Its labels come from one run of every start with conftest's catalogue."""
    from shared_kernels import WADA_PILOT, WADA_SCENE

    labels_of = maps.scene_labels(WADA_SCENE, attractors=wada_catalogue, **WADA_PILOT)
    result = maps.uncertainty_sampled(labels_of, PHASE_BOX, eps=10.0 ** -np.arange(2, 8),
                                      n=300, seed=4)
    # "well below 1": even its upper 3-error bound stays under 0.5
    assert result.alpha + 3 * result.alpha_error < 0.5
    assert result.alpha > 0  # f still falls with eps: the fit is not noise


def test_scene_labels_is_one_run_of_points():
    """scene_labels runs the starts as sweep.Points and labels them: the same labels as
    the run of a grid through the same starts, NaN (an uncaptured start) as NAN_LABEL,
    which ``labels_of.unresolved`` names (not -1: well -1 is a well)."""
    theta = np.linspace(-3.0, 3.0, 9)
    omega = np.array([-3.0, 0.0, 3.0])
    grid = sweep.Grid(theta0=theta, omega0=omega)
    starts = np.column_stack([np.repeat(theta, 3), np.tile(omega, 9)])
    short = dict(WELLS_RUN, t_end=2.0)  # too short for some starts to be captured
    labels_of = maps.scene_labels(DAMPED, maps.well, **short)
    labels = labels_of(starts)
    expected = maps.well(sweep.run(DAMPED, grid, progress=False, **short)).values.ravel()
    assert np.isnan(expected).any() and labels.dtype == np.int64
    np.testing.assert_array_equal(labels, np.where(np.isnan(expected), maps.NAN_LABEL,
                                                   expected))
    assert labels_of.unresolved == maps.NAN_LABEL


def test_levels_without_uncertain_pairs_are_left_out():
    """A level with no uncertain pair (log 0) is reported but not fitted; so is one
    with every pair uncertain (saturated), and fewer than 3 fitted levels give nan."""
    def stripes(starts):  # a boundary every 0.1 of the box
        return np.floor(starts[:, 0] * 10).astype(np.int64)

    result = maps.uncertainty_sampled(stripes, ((0, 1), (0, 1)),
                                      eps=[1e-9, 1e-3, 1e-2, 1e-1], n=1000, seed=5)
    assert result.uncertain[0] == 0 and min(result.uncertain[1:]) > 0
    assert result.used == (False, True, True, True)
    assert abs(result.alpha - 1.0) < 3 * result.alpha_error  # a smooth boundary

    def distinct(starts):  # every start its own label: every pair uncertain
        return np.arange(len(starts))

    result = maps.uncertainty_sampled(distinct, ((0, 1), (0, 1)), eps=[1e-3, 1e-2, 1e-1],
                                      n=100, seed=5)
    assert result.uncertain == (100, 100, 100) and result.used == (False,) * 3
    assert math.isnan(result.alpha) and math.isnan(result.alpha_error)
    assert math.isnan(result.dimension) and math.isnan(result.reduced_chi2)


def test_to_dataset_holds_the_table():
    result = maps.uncertainty_sampled(mgoy_labels, MGOY_BOX, eps=[1e-2, 1e-3, 1e-4], n=500,
                                      seed=6)
    ds = result.to_dataset()
    assert isinstance(ds, xr.Dataset)
    np.testing.assert_array_equal(ds["eps"], result.eps)
    np.testing.assert_array_equal(ds["uncertain"], result.uncertain)
    assert ds.attrs["alpha"] == result.alpha


# ------------------------------------------------------------------------- bad input


def never_called(starts):
    raise AssertionError("labels_of was called before the arguments were checked")


GOOD = dict(eps=[1e-1, 1e-2, 1e-3], n=10, seed=0)


@pytest.mark.parametrize("box", [
    ((0, 1),), ((0, 1), (0, 1), (0, 1)), ((1, 0), (0, 1)), ((0, 0), (0, 1)),
    ((0, np.inf), (0, 1)), ((0, np.nan), (0, 1)), "box", None, ((0, "a"), (0, 1)),
])
def test_bad_box(box):
    with pytest.raises(ValueError, match=r"box must be \(\(lo0, hi0\), \(lo1, hi1\)\)"):
        maps.uncertainty_sampled(never_called, box, **GOOD)


@pytest.mark.parametrize("eps, why", [
    (1e-3, "got 0.001"), ([1e-1, 1e-2], "2 distinct"), ([1e-1, 1e-1, 1e-2], "2 distinct"),
    ([0.0, 1e-2, 1e-3], "bad value 0.0"), ([2.0, 1e-2, 1e-3], "bad value 2.0"),
    ([1e-13, 1e-2, 1e-3], "bad value 1e-13"), ([np.nan, 1e-2, 1e-3], "bad value nan"),
    ([True, 1e-2, 1e-3], "got"), (["a", 1e-2, 1e-3], "got"), ([[1e-1], [1e-2], [1e-3]], "got"),
    (None, "got None"),
])
def test_bad_eps(eps, why):
    with pytest.raises(ValueError, match=rf"eps must be a sequence of at least 3 .*{why}"):
        maps.uncertainty_sampled(never_called, MGOY_BOX, eps=eps, n=10, seed=0)


@pytest.mark.parametrize("n", [1, 0, -5, 2.5, True, "10", None])
def test_bad_n(n):
    with pytest.raises(ValueError, match=r"n must be an int >= 2 .*got"):
        maps.uncertainty_sampled(never_called, MGOY_BOX, eps=GOOD["eps"], n=n, seed=0)


@pytest.mark.parametrize("seed", [-1, 1.5, True, None, "x"])
def test_bad_seed(seed):
    with pytest.raises(ValueError, match=r"seed must be an int >= 0 or a numpy.random"):
        maps.uncertainty_sampled(never_called, MGOY_BOX, eps=GOOD["eps"], n=10, seed=seed)


def test_seed_may_be_a_generator():
    a = maps.uncertainty_sampled(mgoy_labels, MGOY_BOX, n=50, eps=GOOD["eps"],
                                 seed=np.random.default_rng(7))
    b = maps.uncertainty_sampled(mgoy_labels, MGOY_BOX, n=50, eps=GOOD["eps"], seed=7)
    assert a == b


def test_labels_of_must_be_callable():
    with pytest.raises(ValueError, match=r"labels_of must be a callable .* got 3"):
        maps.uncertainty_sampled(3, MGOY_BOX, **GOOD)


@pytest.mark.parametrize("result, why", [
    (lambda s: np.zeros(len(s) - 1, int), r"got shape \(59,\)"),
    (lambda s: np.zeros((len(s), 1), int), r"got shape \(60, 1\)"),
    (lambda s: 0, r"got shape \(\)"),
    (lambda s: np.array(["a"] * len(s)), "got dtype <U1"),
    (lambda s: np.full(len(s), np.nan), "got nan at index 0 .*instead of NaN"),
    (lambda s: np.full(len(s), 0.5), "got 0.5 at index 0"),
])
def test_labels_of_result_is_checked(result, why):
    with pytest.raises(ValueError, match=rf"labels_of must return 60 integer labels.*{why}"):
        maps.uncertainty_sampled(result, MGOY_BOX, **GOOD)


def test_labels_of_may_return_bools_or_whole_floats():
    def as_float(starts):
        return mgoy_labels(starts).astype(np.float64)

    def as_bool(starts):
        return mgoy_labels(starts) == 1

    expected = maps.uncertainty_sampled(mgoy_labels, MGOY_BOX, **dict(GOOD, n=2000))
    assert not math.isnan(expected.alpha)
    for labels_of in (as_float, as_bool):
        assert maps.uncertainty_sampled(labels_of, MGOY_BOX, **dict(GOOD, n=2000)) == expected


@pytest.mark.parametrize("kwargs, match", [
    (dict(label=3), "label must be a callable ds -> DataArray"),
    (dict(axes="theta0"), "axes must be two distinct names"),
    (dict(axes=("theta0",)), "axes must be two distinct names"),
    (dict(axes=("theta0", "theta0")), "axes must be two distinct names"),
    (dict(axes=("theta0", "speed")), r"axes must be two distinct names .*'speed'"),
    (dict(axes=5), "axes must be two distinct names"),
])
def test_scene_labels_bad_input(kwargs, match, no_compute):
    with pytest.raises(ValueError, match=match):
        maps.scene_labels(DAMPED, **kwargs, **WELLS_RUN)


@pytest.mark.parametrize("scene", [None, "pendulum", sweep.Damping(0.2)])
def test_scene_labels_bad_scene(scene, no_compute):
    with pytest.raises(ValueError, match=r"scene must be a sweep.Scene .*got"):
        maps.scene_labels(scene, **WELLS_RUN)


def test_scene_labels_refuses_a_system_saying_what_is_accepted(no_compute):
    with pytest.raises(ValueError, match=r"got DoublePendulum; accepted: a sweep\.Scene "
                       r"\(sweep\.maps\.scene_labels supports the single pendulum only"):
        maps.scene_labels(sweep.DoublePendulum(), **WELLS_RUN)


@pytest.mark.parametrize("run, match", [
    (dict(WELLS_RUN, dt=-1.0), "dt"),
    (dict(WELLS_RUN, observe=("nonsense",)), "nonsense"),
    (dict(WELLS_RUN, t_end=np.nan), "t_end"),
])
def test_scene_labels_run_arguments_are_checked_up_front(run, match, no_compute):
    with pytest.raises(ValueError, match=match):
        maps.scene_labels(DAMPED, maps.well, **run)


def test_scene_labels_holds_other_columns_and_refuses_them_on_its_axes(no_compute):
    """``held``: the columns every start shares (an explorer view's start); one named
    like an axis, or not a column, is refused before anything is computed."""
    with pytest.raises(ValueError, match=r"held must name sweep.Points columns other than"):
        maps.scene_labels(DAMPED, maps.well, held={"theta0": 0.1}, **WELLS_RUN)
    with pytest.raises(ValueError, match=r"held must name sweep.Points columns other than"):
        maps.scene_labels(DAMPED, maps.well, held={"nonsense": 0.1}, **WELLS_RUN)
    labels_of = maps.scene_labels(DAMPED, maps.well, axes=("theta0", "damping"),
                                  held={"omega0": 0.5}, **WELLS_RUN)
    assert callable(labels_of)
