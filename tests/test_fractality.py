"""`sweep.metrics.fractality_test`: Puy, Daza, Wagemakers and Sanjuán's test for fractal
boundaries from the boundary basin entropy of random balls, which works with two basins.

Verdicts are deterministic (every seed fixed); each map below was measured over six
seeds with margins of several standard errors (given per test), so the verdicts do not
hang on the draw.
"""

import numpy as np
import pytest

import sweep
from sweep import maps
from sweep.maps.metrics import basin_entropy, fractality_test, smooth_boundary_entropy

DAMPED = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.2),))
WELLS_RUN = dict(t_end=40.0, dt=0.02, observe=("capture",), stop_early=True, progress=False)


def phase_grid(n):
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n), omega0=np.linspace(-4.0, 4.0, n))


def mgoy_map(n):
    """The map x -> 3x mod 1, y -> 1.5y + cos(2 pi x) on n x n cells of
    [0, 1] x [-2, 2]: 1 where y -> +inf, 0 where y -> -inf (80 iterations: |y| > 2
    decides the sign for good). Its boundary is a Weierstrass graph of dimension
    2 - ln 1.5 / ln 3 (tests/test_uncertainty_sampled.py derives it)."""
    x = (np.arange(n) + 0.5) / n
    y = -2.0 + 4.0 * (np.arange(n) + 0.5) / n
    x, y = (a.ravel() for a in np.meshgrid(x, y, indexing="ij"))
    for _ in range(80):
        y = 1.5 * y + np.cos(2 * np.pi * x)
        x = (3.0 * x) % 1.0
    return (y > 0).reshape(n, n).astype(np.int8)


def test_smooth_references_are_the_published_values():
    """The smooth-boundary Sbb per dimension: the table of Attractors.jl's
    basins_fractal_test (Puy et al.'s implementation), given there to 7-8 digits."""
    table = [0.499999, 0.4395093, 0.39609176, 0.36319428, 0.33722572]
    for ndim, value in enumerate(table, start=1):
        # the table's last digit (D = 1 is 1/2 exactly, printed as 0.499999)
        assert smooth_boundary_entropy(ndim) == pytest.approx(value, abs=2e-6)


def test_grid_interval_closes_on_the_continuum():
    """A flat cut of a ball of cells: the continuum value plus a discretisation bias
    that depends on the cut's direction; the interval over directions holds the
    continuum value, narrows as the radius grows, and its top stays under
    Attractors.jl's fitted bound S + 0.224 r**-1.006 (from radius 3 on)."""
    radii = (3, 4, 8, 20)
    results = [fractality_test(np.indices((60, 60))[0] > 25, radius=r, n_balls=100, rng=0)
               for r in radii]
    continuum = smooth_boundary_entropy(2)
    widths = [r.smooth_high - r.smooth_low for r in results]
    assert all(np.diff(widths) < 0)
    for r, result in zip(radii, results):
        assert result.smooth_low <= continuum <= result.smooth_high
        assert result.smooth_high - continuum < 0.224 * r**-1.006


@pytest.mark.parametrize("labels", [
    pytest.param((lambda i, j: (i - 200) ** 2 + (j - 200) ** 2 < 150**2), id="disk"),
    pytest.param((lambda i, j: np.sqrt(0.1) * i + j > 250), id="tilted-half-plane"),
])
def test_smooth_shapes_are_smooth(labels):
    """Measured Sbb inside the smooth interval, or within 1.2 standard errors of it,
    at radius 8 over six seeds; the verdict allows 2."""
    i, j = np.indices((400, 400))
    result = fractality_test(labels(i, j), radius=8, rng=1)
    assert not result.fractal
    assert result.n_balls == 1000 and result.n_draws > 1000
    assert 0.003 < result.sbb_error < 0.01  # std of a two-label entropy ~0.2, / sqrt(1000)


def test_two_basin_fractal_is_found():
    """The McDonald-Grebogi-Ott-Yorke map's two basins: Sbb <= log 2, so basin_entropy's
    log-2 criterion cannot see its fractal boundary; the random balls do (Sbb measured
    5.5 to 8.3 standard errors below the smooth interval over six seeds at radius 10)."""
    labels = mgoy_map(400)
    assert not basin_entropy(labels, box_size=10).fractal_boundary
    result = fractality_test(labels, radius=10, rng=2)
    assert result.fractal and result.sbb < result.smooth_sbb


def test_attractors_jl_verdicts():
    """Attractors.jl's tests of its basins_fractal_test (test/basins/uncertainty_tests.jl,
    "Basin entropy and Fractal test"), balls of 5 cells on 300 x 300 grids: the map of
    Grebogi et al. (1983) on [0, 2 pi] x [-0.5, 0.5] is fractal (Sbb measured 0.585 to
    0.593, 25 standard errors above the smooth interval's top 0.471, over four seeds);
    the Henon map's (a = 1.4, b = 0.3) bounded basin on [-2, 2]^2 is smooth (0.448 to
    0.456, inside the interval)."""
    from test_metrics import grebogi_map_basins

    assert fractality_test(grebogi_map_basins(300), radius=5, rng=7).fractal
    x, y = np.meshgrid(np.linspace(-2, 2, 300), np.linspace(-2, 2, 300), indexing="ij")
    for _ in range(60):  # escaped orbits are clipped at 1e6 so that nothing overflows
        x, y = np.clip(1 - 1.4 * x * x + y, -1e6, 1e6), np.clip(0.3 * x, -1e6, 1e6)
    bounded = np.abs(x) < 1e5  # the attractor lies within |x| < 1.3
    assert 0.3 < bounded.mean() < 0.6  # both basins present (measured 0.43)
    assert not fractality_test(bounded, radius=5, rng=8).fractal


def test_pendulum_wells_are_smooth():
    """The damped pendulum's wells on 128 x 128 starts, balls of 3 cells (the map has
    about 40 radii per axis): smooth (Sbb inside the smooth interval for six seeds)."""
    wells = maps.basins(sweep.run(DAMPED, phase_grid(128), **WELLS_RUN))
    result = fractality_test(wells, radius=3, rng=3)
    assert not result.fractal


def test_forced_wada_map_is_fractal(wada_catalogue):
    """The forced Wada scene (c = 0.2, A = 1.66, W = 1) on 128 x 128 starts: Sbb about
    0.89, some 55 standard errors above the smooth interval's top (0.497 at radius 3)."""
    from shared_kernels import WADA_PILOT, WADA_SCENE

    labels = maps.basins(sweep.run(WADA_SCENE, phase_grid(128), attractors=wada_catalogue,
                                   **WADA_PILOT))
    result = fractality_test(labels, radius=3, rng=4)
    assert result.fractal and result.sbb > result.smooth_high


# ------------------------------------------------------------------------- bad input

HALF = np.indices((60, 60))[0] > 30


@pytest.mark.parametrize("labels, match", [
    (np.zeros((60, 60), int), "labels holds a single label"),
    (np.zeros((0, 5)), "labels is empty"),
    (np.full((60, 60), 0.5), "labels must hold integers, got 0.5"),
    (np.array(["a", "b"]), "labels must hold integers, got dtype <U1"),
    (5, "labels must be an array with at least one dimension"),
])
def test_bad_labels(labels, match):
    with pytest.raises(ValueError, match=match):
        fractality_test(labels, radius=3)


@pytest.mark.parametrize("radius", [0, -1, 30, 2.5, True, "3", None])
def test_bad_radius(radius):
    with pytest.raises(ValueError, match=r"radius must be an integer from 1 to .* = 29"):
        fractality_test(HALF, radius=radius)


@pytest.mark.parametrize("n_balls", [99, 0, 150.0, True, "1000", None])
def test_bad_n_balls(n_balls):
    with pytest.raises(ValueError, match=r"n_balls must be an integer >= 100, got"):
        fractality_test(HALF, radius=3, n_balls=n_balls)


@pytest.mark.parametrize("rng", ["x", True, -1, 1.5])
def test_bad_rng(rng):
    with pytest.raises(ValueError, match=r"rng must be None, a seed"):
        fractality_test(HALF, radius=3, rng=rng)


@pytest.mark.parametrize("sigmas", [0, -1.0, np.nan, np.inf, True, "2", None])
def test_bad_sigmas(sigmas):
    with pytest.raises(ValueError, match=r"sigmas must be a finite number > 0"):
        fractality_test(HALF, radius=3, sigmas=sigmas)


def test_too_little_boundary():
    """One odd cell in a corner, outside every ball that fits: no boundary ball."""
    labels = np.zeros((60, 60), int)
    labels[0, 0] = 1
    with pytest.raises(ValueError, match=r"only 0 of 100000 random balls of radius 3"):
        fractality_test(labels, radius=3, n_balls=100, rng=0)


@pytest.mark.parametrize("ndim", [0, -1, 1.5, True, "2"])
def test_bad_ndim(ndim):
    with pytest.raises(ValueError, match=r"ndim must be an integer >= 1"):
        smooth_boundary_entropy(ndim)


def test_other_dimensions():
    """A 1-D map (a step) and a 3-D one (a half space) are smooth too."""
    step = np.arange(400) > 123
    assert not fractality_test(step, radius=20, rng=5).fractal
    half_space = np.indices((40, 40, 40))[0] + 0.5 * np.indices((40, 40, 40))[1] > 30
    result = fractality_test(half_space, radius=4, n_balls=300, rng=6)
    assert not result.fractal
    assert result.smooth_sbb == pytest.approx(0.39609176, abs=1e-7)  # the published value
