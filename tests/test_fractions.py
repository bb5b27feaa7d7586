"""`sweep.sample` (points in a box) and `sweep.maps.fractions` (basin stability with
standard errors), against oracles: Monte Carlo of a known fraction for the binomial
error, the net property of a scrambled Sobol sequence, and the forced Wada map's
fractions from its full 1200 x 1200 grid."""

import functools
import importlib.util
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import maps

EXAMPLE = Path(__file__).parent.parent / "examples" / "basin_stability.py"


def _example():
    """examples/basin_stability.py as a module (its Wada scene and sampling)."""
    spec = importlib.util.spec_from_file_location("basin_stability", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ------------------------------------------------------------------ sample
def test_sample_is_reproducible_from_its_seed_and_stays_in_its_box():
    box = dict(theta0=(-np.pi, np.pi), omega0=(-4.0, 4.0), damping=0.2)
    for method in ("sobol", "random"):
        a = sweep.sample(100, seed=7, method=method, **box)
        b = sweep.sample(100, seed=7, method=method, **box)
        c = sweep.sample(100, seed=8, method=method, **box)
        assert isinstance(a, sweep.Points) and a.shape == (100,)
        assert list(a.axes) == ["theta0", "omega0", "damping"]
        for name in ("theta0", "omega0"):
            np.testing.assert_array_equal(a.axes[name], b.axes[name])
            assert not np.array_equal(a.axes[name], c.axes[name])
            lo, hi = box[name]
            assert np.all((a.axes[name] >= lo) & (a.axes[name] < hi))
        assert np.all(a.axes["damping"] == 0.2)
    # a Sobol sample of n is the first n points of a larger one with the same seed
    big = sweep.sample(256, seed=7, **box)
    np.testing.assert_array_equal(big.axes["omega0"][:100],
                                  sweep.sample(100, seed=7, **box).axes["omega0"])


def test_sobol_sample_is_a_net_at_powers_of_two():
    """The oracle: the first 2^m points of a scrambled Sobol sequence put exactly one
    point in each of the 2^m equal intervals of every coordinate (a (0, m, 1)-net)."""
    points = sweep.sample(256, seed=3, theta0=(0.0, 1.0), omega0=(-1.0, 1.0))
    for name, (lo, hi) in (("theta0", (0.0, 1.0)), ("omega0", (-1.0, 1.0))):
        cells = np.floor((points.axes[name] - lo) / (hi - lo) * 256).astype(int)
        np.testing.assert_array_equal(np.sort(cells), np.arange(256))


def test_random_sample_is_uniform():
    """Mean and variance of each coordinate against the uniform distribution's; 4
    standard errors (of the mean: sqrt(1/12 / n); of the variance: sqrt(1/180 / n))
    keep the seeded check from failing by chance."""
    n = 20000
    u = sweep.sample(n, seed=5, method="random", theta0=(0.0, 1.0)).axes["theta0"]
    assert abs(u.mean() - 0.5) < 4 * np.sqrt(1 / 12 / n)
    assert abs(u.var() - 1 / 12) < 4 * np.sqrt(1 / 180 / n)


@pytest.mark.parametrize("args, kwargs, message", [
    ((0,), dict(seed=1, theta0=(0, 1)), r"sample: n must be an int >= 1 \(points\), got 0"),
    ((2.0,), dict(seed=1, theta0=(0, 1)), "sample: n must be an int >= 1"),
    ((8,), dict(seed=-1, theta0=(0, 1)), "sample: seed must be an int >= 0, got -1"),
    ((8,), dict(seed=None, theta0=(0, 1)), "sample: seed must be an int >= 0"),
    ((8,), dict(seed=1, method="halton", theta0=(0, 1)),
     "sample: method must be one of 'sobol', 'random', got 'halton'"),
    ((8,), dict(seed=1), "sample needs at least one range"),
    ((8,), dict(seed=1, damping=0.2), "sample needs at least one range"),
    ((8,), dict(seed=1, theta=(0, 1)), "sample: unknown axis 'theta'; accepted axis names"),
    ((8,), dict(seed=1, theta0=(1, 0)), r"sample: theta0 = \(1, 0\); accepted: \(lo, hi\) "
                                        "with lo < hi"),
    ((8,), dict(seed=1, theta0=(0, np.inf)), "sample: theta0 = "),
    ((8,), dict(seed=1, length=(0.0, 2.0)), r"sample: length = \(0.0, 2.0\); .*> 0"),
    ((8,), dict(seed=1, theta0=(0, 1, 2)), "sample: theta0 = .* is neither a range nor a "
                                           "value"),
])
def test_bad_sample_arguments_are_refused(args, kwargs, message):
    with pytest.raises((ValueError, TypeError), match=message):
        sweep.sample(*args, **kwargs)


# ------------------------------------------------------------------ fractions
def test_binomial_standard_error_matches_a_monte_carlo_of_known_p():
    """Draw 4000 independent samples of n = 400 labels with P(label 1) = 0.3: the spread
    of the estimated fraction is the binomial sqrt(p (1 - p) / n) = 0.0229. With 4000
    repetitions the spread's own relative error is 1 / sqrt(2 * 4000) = 1.1 %: 5 % is
    over 4 of those. The reported errors' mean is within 1 % (each is sqrt(p^(1 - p^)
    / n), p^ within a few % of p)."""
    rng = np.random.default_rng(11)
    p, n, repeats = 0.3, 400, 4000
    estimates, errors = [], []
    for _ in range(repeats):
        table = maps.fractions((rng.random(n) < p).astype(np.int32))
        estimates.append(float(table.fraction.sel(label=1)))
        errors.append(float(table.standard_error.sel(label=1)))
    exact = np.sqrt(p * (1 - p) / n)
    assert abs(np.std(estimates) / exact - 1) < 0.05
    assert abs(np.mean(errors) / exact - 1) < 0.01
    assert abs(np.mean(estimates) - p) < 4 * exact / np.sqrt(repeats)  # unbiased


def test_replicates_give_the_spread_of_their_fractions():
    """R = 8 replicates of n = 100 random labels: the mean fraction, and the standard
    error of the mean from their spread; its square averages to p (1 - p) / (n R) (the
    sample variance is unbiased). One squared spread of R = 8 has a relative standard
    deviation of sqrt(2 / (R - 1)) = 53 %, so the mean of 2000 seeded repetitions is
    within 1.2 %: 5 % is over 4 of those."""
    rng = np.random.default_rng(12)
    p, n, r = 0.4, 100, 8
    squares = []
    for _ in range(2000):
        labels = xr.DataArray((rng.random((r, n)) < p).astype(np.int32),
                              dims=("replicate", "point"))
        table = maps.fractions(labels)
        assert table.attrs["replicates"] == r and table.attrs["samples"] == n
        squares.append(float(table.standard_error.sel(label=1)) ** 2)
    assert abs(np.mean(squares) / (p * (1 - p) / (n * r)) - 1) < 0.05
    explicit = maps.fractions(labels)
    np.testing.assert_allclose(explicit.fraction.sel(label=1),
                               (labels == 1).mean("point").mean("replicate"), rtol=1e-15)


def test_unresolved_labels_keep_a_row_of_their_own():
    basins = xr.DataArray(np.array([0, 0, 1, -1], dtype=np.int32), dims="point",
                          attrs={"unresolved": -1}, name="basins")
    table = maps.fractions(basins)
    assert table.label.values.tolist() == [-1, 0, 1]
    assert table.unresolved.values.tolist() == [True, False, False]
    assert table.fraction.values.tolist() == [0.25, 0.5, 0.25]
    assert table.attrs["labels"] == "basins"
    # motion's unresolved flag is -127; -1 is a label there (rotation, negative sense)
    motion = xr.DataArray(np.array([-1, 0, 1, -127], dtype=np.int8), dims="point",
                          attrs={"flag_values": np.array([-1, 0, 1, -127], dtype=np.int8),
                                 "flag_meanings": "rotation_negative libration "
                                                  "rotation_positive unresolved"})
    assert maps.fractions(motion).unresolved.values.tolist() == [True, False, False, False]
    well = maps.fractions(np.array([0.0, 1.0, np.nan, 1.0]))  # NaN: always no label
    assert well.unresolved.values.tolist() == [False, False, True]
    assert well.fraction.values.tolist() == [0.25, 0.5, 0.25]
    assert float(well.fraction.sum()) == 1.0
    # a catalogued run's variable attractor: -1 is no attractor (its long_name says so),
    # which sweep fractions' hints name as a label (the row read unresolved False)
    attractor = xr.DataArray(np.array([0.0, 1.0, -1.0, 1.0]), dims="point",
                             name="attractor", attrs={
                                 "units": "1",
                                 "long_name": "index of the attractor settled on (-1: none)"})
    assert maps.fractions(attractor).unresolved.values.tolist() == [True, False, False]
    from sweep.maps.fractions import ATTRACTOR_NONE
    from sweep.observables import OBSERVABLES

    assert OBSERVABLES["attractor"].variables[0][2].endswith(ATTRACTOR_NONE)  # as written


def test_a_grid_gets_no_binomial_error():
    """A grid's cells are not a random sample: no standard error (NaN), as
    map_accuracy.md says of a grid; a run of points (along ``point``) and a plain array
    keep the binomial error, and sampled= says it either way."""
    values = np.array([[0, 0, 1], [1, 1, 0]], dtype=np.int32)
    grid = xr.DataArray(values, dims=("theta0", "omega0"), name="basins")
    table = maps.fractions(grid)
    assert np.isnan(table.standard_error.values).all()
    assert table.attrs["standard_error_method"].startswith("none: the labels are a grid")
    assert table.fraction.values.tolist() == [0.5, 0.5]
    points = maps.fractions(grid.stack(point=("theta0", "omega0")).drop_vars(
        ["point", "theta0", "omega0"]))
    binomial = np.sqrt(0.5 * 0.5 / 6)  # rtol 1e-15 below: the same formula, rounding only
    np.testing.assert_allclose(points.standard_error, binomial, rtol=1e-15)
    np.testing.assert_allclose(maps.fractions(values).standard_error, binomial, rtol=1e-15)
    np.testing.assert_allclose(maps.fractions(grid, sampled=True).standard_error, binomial,
                               rtol=1e-15)
    assert np.isnan(maps.fractions(values, sampled=False).standard_error).all()


def test_labels_must_be_whole_numbers_and_whole_floats_are_integers():
    """A float such as an amplitude is no label (it gave a row of count 1 per value);
    whole floats (the catalogued 'attractor') are labelled as integers, NaN aside."""
    amplitude = xr.DataArray(np.array([0.25, 1.0, 0.5]), dims="point", name="amplitude")
    with pytest.raises(ValueError, match=r"variable 'amplitude' holds 0\.25, which is "
                                         r"not a label; accepted: whole numbers"):
        maps.fractions(amplitude)
    with pytest.raises(ValueError, match="labels holds inf"):
        maps.fractions(np.array([1.0, np.inf]))
    attractor = maps.fractions(np.array([1.0, 0.0, 1.0]))
    assert attractor.label.dtype == np.int64 and attractor.label.values.tolist() == [0, 1]
    assert maps.fractions(np.array([1.0, np.nan])).label.dtype == np.float64


def test_convergence_table_over_prefixes():
    labels = np.random.default_rng(4).integers(0, 3, 1000)
    table = maps.fractions(labels, convergence=True)
    assert table.n.values.tolist() == [16, 32, 64, 128, 256, 512, 1000]
    assert table.fraction.dims == ("n", "label")
    last = maps.fractions(labels)
    np.testing.assert_array_equal(table.fraction.isel(n=-1), last.fraction)
    for m in (16, 256):
        np.testing.assert_array_equal(table.fraction.sel(n=m), maps.fractions(labels[:m]).fraction
                                      .reindex(label=table.label, fill_value=0.0))


def test_convergence_of_a_grid_is_refused():
    """The first n cells of a grid (C order) are rows of its first axis, not a sample of
    the box: their fractions converge to nothing (here the first 16 are all label 0)."""
    grid = xr.DataArray(np.repeat([0, 1], 16).reshape(4, 8), dims=("theta0", "omega0"))
    with pytest.raises(ValueError, match=r"^convergence=True: the labels are a grid's "
                       r"cells, .*; accepted: the labels of sampled points"):
        maps.fractions(grid, convergence=True)
    table = maps.fractions(grid, convergence=True, sampled=True)  # the caller says so
    assert table.n.values.tolist() == [16, 32]
    assert table.fraction.sel(n=16).values.tolist() == [1.0, 0.0]


@pytest.mark.parametrize("labels, kwargs, error, message", [
    (np.array([]), {}, ValueError, "labels are empty"),
    (np.array(["a", "b"]), {}, ValueError, "labels must be numbers"),
    (xr.DataArray(np.zeros((1, 4)), dims=("replicate", "point")), {}, ValueError,
     "labels have 1 replicate; accepted: R >= 2"),
    (np.zeros(4), {"convergence": "yes"}, TypeError, "convergence must be True or False"),
])
def test_bad_labels_are_refused(labels, kwargs, error, message):
    with pytest.raises(error, match=message):
        maps.fractions(labels, **kwargs)


# ------------------------------------------------------------------ the forced Wada map
#: Fractions of the three basins of the full 1200 x 1200 forced map
#: (benchmarks/forced_basins.py; labels in the pilot catalogue's order).
WADA = np.array([0.396, 0.384, 0.220])  # examples/basin_stability.py FULL_MAP


def test_wada_fractions_from_20000_sobol_samples_match_the_full_map():
    """20,000 scrambled Sobol starts in the map's box, labelled with the pilot
    catalogue, give each basin's fraction within two standard errors (binomial, ~0.0035)
    of the full map's: the issue's validation (about 10 s here, most of it compiling).
    The example's catalogue() runs a 21 x 21 pilot instead of its 41 x 41: conftest's
    Wada pilot, whose catalogue's kernel the suite compiles once (wada_catalogue)."""
    example = _example()
    example.catalogue = functools.partial(example.catalogue, 21)
    table, _ = example.wada_fractions(20000, seed=1)
    resolved = table.where(~table.unresolved, drop=True)
    assert resolved.sizes["label"] == 3
    assert np.all(np.abs(resolved.fraction.values - WADA)
                  <= 2 * resolved.standard_error.values)


def test_file_labels_leave_out_quantities_with_units():
    """A variable of whole numbers in seconds or radians (capture_time, all 10.0 s when
    every start is captured as t_transient ends) is a time, not a label: the hints of
    sweep fractions named it as one."""
    from sweep.maps.requirements import file_labels

    dims = ("theta0", "omega0")
    ds = xr.Dataset({"well": (dims, np.zeros((2, 3)), {"units": "1"}),
                     "capture_time": (dims, np.full((2, 3), 10.0), {"units": "s"}),
                     "theta_final": (dims, np.zeros((2, 3)), {"units": "rad"}),
                     "count": (dims, np.ones((2, 3), dtype=np.int64)),
                     "status": (dims, np.zeros((2, 3), dtype=np.int8))})
    assert file_labels(ds) == ["basins", "motion", "well", "count"]  # maps, then variables
