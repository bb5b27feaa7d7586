"""The Wada test of a basin map: `sweep.maps.wada` (the grid method, new trajectories
below the grid's scale) and `sweep.maps.wada_merging` (the merging method, the label
array alone).

Oracles with exact labellings: three sectors around the origin (smooth boundaries, only
the origin touches all three basins: not Wada) and Newton's method for z^3 - 1 (its
three roots' basins share one boundary, the Julia set: Wada). Then the forced pendulum
of the maps issue: A = 1.66 (three basins) is Wada, A = 1.71 (four) only partially
(Wagemakers, Daza, Sanjuán, Discrete Contin. Dyn. Syst. B 26, 717 (2021), Fig. 2a).
"""

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import maps
from sweep.maps.wada import _scene_labels

PERIOD = 2 * np.pi
#: conftest's WADA_PILOT: the wada_catalogue fixture's run settings, so the map runs
#: the kernel other tests compile with that catalogue.
FORCED_RUN = dict(t_end=320 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD,
                  observe=("strobe",), stop_early=True, progress=False)


def sector(starts):
    """Exact: the sector (0, 1, 2) of angle arctan2(y, x) + pi in thirds of a turn."""
    angle = np.arctan2(starts[:, 1], starts[:, 0]) + np.pi
    return np.floor(angle / (2 * np.pi / 3)).astype(np.int64) % 3


def newton(starts, iterations=40):
    """The root of z^3 = 1 that Newton's method reaches from x + iy (0, 1, 2), -1 where
    it has not converged within 1e-6. The boundary of each root's basin is the Julia
    set of the Newton map (the boundary of any attracting cycle's basin is the Julia set
    of a rational map), so every boundary point touches all three basins."""
    z = starts[:, 0] + 1j * starts[:, 1]
    with np.errstate(all="ignore"):
        for _ in range(iterations):
            z = z - (z ** 3 - 1) / (3 * z ** 2)
    distance = np.abs(z[:, None] - np.exp(2j * np.pi * np.arange(3) / 3)[None, :])
    labels = distance.argmin(axis=1)
    labels[~(distance.min(axis=1) < 1e-6)] = -1
    return labels


def label_map(labels_of, x, y):
    starts = np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1).reshape(-1, 2)
    return labels_of(starts).reshape(x.size, y.size)


class Counting:
    """A labelling that records its calls."""

    def __init__(self, labels_of):
        self.labels_of, self.calls = labels_of, []

    def __call__(self, starts):
        self.calls.append(np.array(starts))
        return self.labels_of(starts)


def test_three_sectors_are_not_wada():
    """41 x 41 cells on [-1, 1]^2, the origin a grid point. A cell's new points lie in
    the square of its 3 x 3 neighbourhood; a square not holding the origin meets three
    sectors only if, seen from the origin, it spans two rays 120 degrees apart, which
    needs its centre within 2 h sin(45 deg) / sin(60 deg) = 1.63 h (h the spacing): the
    origin's cell and its 8 neighbours. So at most 9 boundary cells touch 3 basins,
    whatever the refinement."""
    x = y = np.linspace(-1, 1, 41)
    result = maps.wada(label_map(sector, x, y), sector, x, y, max_steps=4)
    assert result.basins == 3 and result.steps == 4
    assert 0 < result.counts[2] <= 9
    assert result.counts.sum() == result.boundary_cells
    assert result.fractions[1] == 1 - result.fractions[2]
    assert result.verdict == "not Wada"
    np.testing.assert_array_equal(result.history[0], result.history[-1])  # smooth
    assert result.trajectories > result.boundary_cells  # it did refine


def test_newtons_basins_are_wada_once_refined():
    """On the grid alone (40 x 40 cells) a third of the boundary cells touch only two
    roots' basins; refinement finds the third in all but at most 1 % (measured: 0 after
    8 steps, the share halving with each step)."""
    x = y = np.linspace(-1.5, 1.5, 40)
    labels = label_map(newton, x, y)
    grid_only = maps.wada(labels, newton, x, y, max_steps=0)
    assert grid_only.verdict == "partially Wada" and grid_only.trajectories == 16
    result = maps.wada(labels, newton, x, y, max_steps=8)
    assert result.verdict == "Wada"
    assert result.fractions[2] >= 1 - result.tolerance
    assert np.all(np.diff(result.history[:, 2]) >= 0)  # a cell never loses a basin
    assert result.history[0, 2] == grid_only.fractions[2]
    assert set(np.unique(result.touching)) <= {0, 2, 3}


def test_merging_method_tells_sectors_from_newton():
    """Sectors: the merged maps' boundaries miss whole rays (a third of the boundary
    each, 29 cells away at the far end). Newton: every merged boundary lies within 2
    cells of the whole boundary (measured distance 2 on 60 x 60 cells)."""
    x = y = np.linspace(-1, 1, 41)
    sectors = maps.wada_merging(label_map(sector, x, y))
    assert sectors.verdict == "not Wada"
    assert (sectors.shares > 0.2).all() and (sectors.distances > 10).all()
    x = y = np.linspace(-1.5, 1.5, 60)
    roots = maps.wada_merging(label_map(newton, x, y))
    assert roots.verdict == "Wada" and (roots.distances <= 2).all()


def test_a_dataarray_brings_its_coordinates_and_uneven_axes_are_followed():
    """The new points of step 1 are the midpoints of the segments between grid points,
    along each axis as it is spaced (x uneven here)."""
    x = np.array([-1.0, -0.7, -0.1, 0.0, 0.2, 0.9, 1.0])
    y = np.linspace(-1, 1, 7)
    labels = xr.DataArray(label_map(sector, x, y), dims=("a", "b"),
                          coords={"a": x, "b": y})
    counting = Counting(sector)
    result = maps.wada(labels, counting, max_steps=1, check=0)
    assert len(counting.calls) == 1 and result.trajectories == len(counting.calls[0])
    midpoints = (x[1:] + x[:-1]) / 2
    assert np.isin(counting.calls[0][:, 0], np.concatenate([x, midpoints])).all()
    assert np.isin(counting.calls[0][:, 1], np.concatenate([y, (y[1:] + y[:-1]) / 2])).all()
    assert np.unique(counting.calls[0], axis=0).shape[0] == result.trajectories  # no twice


def test_a_basin_the_grid_missed_is_counted():
    """A fourth basin, a disc of radius 0.01 at (-0.5, 0.025), on the boundary ray
    y = 0, x < 0 between grid points 0.05 apart: the grid shows three basins, the
    boundary cells' refinement meets the fourth."""

    def labels_of(starts):
        out = sector(starts)
        out[np.hypot(starts[:, 0] + 0.5, starts[:, 1] - 0.025) < 0.01] = 7
        return out

    x = y = np.linspace(-1, 1, 41)
    labels = label_map(labels_of, x, y)
    assert set(np.unique(labels)) == {0, 1, 2}
    result = maps.wada(labels, labels_of, x, y, max_steps=3)
    assert result.basins == 4 and result.labels.tolist() == [0, 1, 2, 7]
    assert result.history.shape == (4, 4) and np.allclose(result.history.sum(axis=1), 1)


@pytest.fixture(scope="module")
def wada_scene_result(wada_catalogue):
    labels_of = _scene_labels(sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2))), wada_catalogue,
        **FORCED_RUN)
    x, y = np.linspace(-np.pi, np.pi, 60), np.linspace(-4, 4, 60)
    labels = label_map(labels_of, x, y)
    return labels, maps.wada(labels, labels_of, x, y, max_steps=6)


def test_the_forced_wada_scene_is_wada(wada_scene_result):
    """c = 0.2, A = 1.66, W = 1, 60 x 60 cells: the share of boundary cells touching
    two basins halves with each step (measured 0.27 on the grid, 0.003 after 6 steps),
    under the default tolerance 0.01. The merging method agrees (measured: at most
    0.09 % of the boundary beyond 2 cells of a merged boundary)."""
    labels, result = wada_scene_result
    assert result.basins == 3 and result.verdict == "Wada"
    assert maps.wada_merging(labels).verdict == "Wada"
    assert result.history[0, 2] < 0.8  # the grid alone does not show it
    assert result.history[-1, 1] < result.history[0, 1] / 8


def test_four_basins_at_a_171_are_only_partially_wada():
    """A = 1.71: four attractors; a smooth piece of boundary between the two period-1
    basins touches only those two, so the share of cells below four basins levels off
    (measured on 60 x 60 cells: 0.031 after 6 steps, 0.018 after 8; 0.035 at
    120 x 120 after 8), three times the tolerance, while most cells touch all four."""
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.71, 1.0, np.pi / 2)))
    pilot = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 21), omega0=np.linspace(-4, 4, 21))
    catalogue = maps.attractor_catalogue(sweep.run(scene, pilot, **FORCED_RUN))
    labels_of = _scene_labels(scene, catalogue, **FORCED_RUN)
    x, y = np.linspace(-np.pi, np.pi, 60), np.linspace(-4, 4, 60)
    labels = label_map(labels_of, x, y)
    result = maps.wada(labels, labels_of, x, y, max_steps=6)
    assert result.basins == 4
    assert result.verdict == "partially Wada"
    assert 0.5 < result.fractions[3] < 1 - 2 * result.tolerance
    # the merged boundaries of the period-1 basins miss 4.3 % and 3.2 % of the boundary
    # (measured), beyond the tolerance 0.01
    assert maps.wada_merging(labels).verdict == "not Wada"


def test_the_map_must_number_basins_as_labels_of_does():
    """A map numbered otherwise (e.g. `maps.basins`' ranking by size against catalogue
    indices) is refused by the check, before any refinement."""
    x = y = np.linspace(-1, 1, 21)
    labels = (label_map(sector, x, y) + 1) % 3
    counting = Counting(sector)
    with pytest.raises(ValueError, match="numbers the basins as the map does"):
        maps.wada(labels, counting, x, y)
    assert len(counting.calls) == 1 and len(counting.calls[0]) == 16


GOOD = np.array([[0, 1, 2], [0, 1, 2], [0, 1, 2]])
AXIS = np.arange(3.0)


@pytest.mark.parametrize(("labels", "kwargs", "match"), [
    (np.arange(5), {}, "2-D array"),
    (GOOD.astype(float), {}, "integer labels"),
    (np.array([[0, 1], [1, 0]]), {"x": AXIS[:2], "y": AXIS[:2]}, "three or more"),
    (np.arange(65 * 2).reshape(65, 2), {"x": np.arange(65.0), "y": AXIS[:2]}, "at most 64"),
    (GOOD, {"x": None}, "x is needed"),
    (GOOD, {"x": AXIS[:2]}, "x must be a 1-D array of 3"),
    (GOOD, {"y": np.array([0.0, 2.0, 1.0])}, "y must be finite and strictly monotonic"),
    (GOOD, {"y": np.array([0.0, np.nan, 1.0])}, "y must be finite"),
    (GOOD, {"labels_of": "sector"}, "labels_of must be a callable"),
    (GOOD, {"max_steps": -1}, "max_steps must be an int from 0 to 20"),
    (GOOD, {"max_steps": 21}, "max_steps"),
    (GOOD, {"max_steps": True}, "max_steps"),
    (GOOD, {"tolerance": 1.0}, r"tolerance must be a number in \[0, 1\)"),
    (GOOD, {"tolerance": float("nan")}, "tolerance"),
    (GOOD, {"check": -1}, "check must be an int >= 0"),
])
def test_bad_input_is_refused_before_any_trajectory(labels, kwargs, match):
    counting = Counting(sector)
    arguments = dict(labels_of=counting, x=AXIS, y=AXIS)
    arguments.update(kwargs)
    with pytest.raises(ValueError, match=match):
        maps.wada(labels, **arguments)
    assert counting.calls == []


@pytest.mark.parametrize(("returns", "match"), [
    (lambda starts: np.zeros(len(starts) + 1, dtype=int), "one label per start"),
    (lambda starts: np.zeros(len(starts)), "integer labels"),
])
def test_a_labelling_that_breaks_its_contract_is_named(returns, match):
    with pytest.raises(ValueError, match=match):
        maps.wada(GOOD, returns, AXIS, AXIS)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"radius": -1}, "radius must be an int >= 0"),
    ({"radius": 1.5}, "radius"),
    ({"tolerance": -0.1}, "tolerance"),
    ({"tolerance": 2}, "tolerance"),
])
def test_merging_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        maps.wada_merging(GOOD, **kwargs)


def test_results_are_frozen():
    x = y = np.linspace(-1, 1, 11)
    result = maps.wada(label_map(sector, x, y), sector, x, y, max_steps=1)
    with pytest.raises(AttributeError):
        result.verdict = "Wada"
    with pytest.raises(ValueError):
        result.fractions[0] = 1.0
    assert result.table().splitlines()[0] == "| m | grid | step 1 |"
