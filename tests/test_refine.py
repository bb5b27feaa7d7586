"""Adaptive boundary refinement (`sweep.maps.refine`, issue 27).

The algorithm (`sweep.maps._quadtree.refine_field`) on synthetic label fields with exact
expectations, against a naive recursive implementation of the same rule; then the sweep
wiring against the full run of the same grid.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from sweep.maps._quadtree import refine_field


# ------------------------------------------------------------------ synthetic fields
def field_callback(field: np.ndarray):
    """A callback reading ``field``, that fails if a cell is asked for twice."""
    asked = np.zeros(field.shape, dtype=bool)

    def compute(rows, cols):
        assert rows.dtype == np.int64 and cols.dtype == np.int64
        assert not asked[rows, cols].any(), "a cell was computed twice"
        asked[rows, cols] = True
        return field[rows, cols]

    return compute, asked


def naive(field: np.ndarray, step: int):
    """The rule of sweep.maps._quadtree written plainly: recursion block by block."""
    n0, n1 = field.shape
    out = np.full(field.shape, -999, dtype=np.int64)
    computed = np.zeros(field.shape, dtype=bool)

    def get(r, c):
        out[r, c] = field[r, c]
        computed[r, c] = True

    rows = sorted(set(range(0, n0, step)) | {n0 - 1})
    cols = sorted(set(range(0, n1, step)) | {n1 - 1})
    for r in rows:
        for c in range(n1):
            get(r, c)
    for c in cols:
        for r in range(n0):
            get(r, c)

    def visit(r0, r1, c0, c1):
        if r1 - r0 < 2 or c1 - c0 < 2:
            return
        border = np.concatenate([out[r0, c0:c1 + 1], out[r1, c0:c1 + 1],
                                 out[r0:r1 + 1, c0], out[r0:r1 + 1, c1]])
        if (border == border[0]).all():
            out[r0 + 1:r1, c0 + 1:c1] = border[0]
            return
        rm, cm = (r0 + r1) // 2, (c0 + c1) // 2
        for c in range(c0, c1 + 1):
            get(rm, c)
        for r in range(r0, r1 + 1):
            get(r, cm)
        for a, b in ((r0, rm), (rm, r1)):
            for c, d in ((c0, cm), (cm, c1)):
                visit(a, b, c, d)

    for a, b in zip(rows[:-1], rows[1:]):
        for c, d in zip(cols[:-1], cols[1:]):
            visit(a, b, c, d)
    return out, computed


def disks(shape, centres_radii):
    """Label k + 1 inside the k-th disk (later disks on top), 0 outside."""
    r, c = np.indices(shape)
    field = np.zeros(shape, dtype=np.int64)
    for k, (r0, c0, radius) in enumerate(centres_radii):
        field[(r - r0) ** 2 + (c - c0) ** 2 <= radius**2] = k + 1
    return field


def newton_basins(n: int) -> np.ndarray:
    """Basins of Newton's method for z^3 = 1 on [-1.5, 1.5]^2: a fractal boundary."""
    x = np.linspace(-1.5, 1.5, n)
    z = x[None, :] + 1j * x[:, None]
    with np.errstate(all="ignore"):
        for _ in range(40):
            z = z - (z**3 - 1) / (3 * z**2)
    roots = np.exp(2j * np.pi * np.arange(3) / 3)
    return np.argmin(np.abs(z[..., None] - roots), axis=-1).astype(np.int64)


def stripes(shape, width):
    """Diagonal stripes of ``width`` cells, three labels."""
    r, c = np.indices(shape)
    return ((r + 2 * c) // width) % 3


SYNTHETIC = {
    "stripes": (stripes((129, 129), 7), 16),
    "stripes uneven": (stripes((100, 131), 30), 8),
    "disks": (disks((129, 129), [(40, 50, 30), (90, 90, 25), (64, 64, 9)]), 16),
    "checkerboard": ((np.add.outer(np.arange(129) // 9, np.arange(129) // 9) % 2), 16),
    "newton": (newton_basins(129), 16),
    "newton step 4": (newton_basins(129), 4),
    "one row": (stripes((1, 40), 3), 4),
    "tiny": (stripes((2, 3), 1), 2),
}


@pytest.mark.parametrize("name", list(SYNTHETIC))
def test_same_as_the_naive_rule(name):
    """Cell for cell, the vectorised levels do what the plain recursion does."""
    field, step = SYNTHETIC[name]
    compute, asked = field_callback(field)
    got = refine_field(field.shape, compute, step)
    want, want_computed = naive(field, step)
    np.testing.assert_array_equal(got.labels, want)
    np.testing.assert_array_equal(got.computed, want_computed)
    np.testing.assert_array_equal(got.computed, asked)
    assert got.cells_computed == int(asked.sum())
    # the computed cells hold their own labels
    np.testing.assert_array_equal(got.labels[got.computed], field[got.computed])


@pytest.mark.parametrize("name", ["stripes", "stripes uneven", "disks", "checkerboard"])
def test_exact_on_fields_without_islands(name):
    """Every region of these fields reaches a lattice line (stripes and checker squares
    cross every line; the disks are wider than the step): nothing can be missed."""
    field, step = SYNTHETIC[name]
    got = refine_field(field.shape, field_callback(field)[0], step)
    np.testing.assert_array_equal(got.labels, field)
    assert got.cells_computed < field.size


def test_smooth_boundary_costs_little():
    """One disk of radius 40 in 257 x 257: the lattice (2/16 of the cells) and the blocks
    along the circle, whose cells grow like its length, not the area."""
    field = disks((257, 257), [(128, 128, 40)])
    got = refine_field(field.shape, field_callback(field)[0], 16)
    np.testing.assert_array_equal(got.labels, field)
    assert got.cells_computed < 0.25 * field.size
    assert got.cells_per_level[0] == 257**2 - (257 - 17) ** 2  # 17 lines each way


def test_an_island_inside_one_block_is_missed():
    """The documented limit: a disk of radius 3 inside one 16 x 16 block whose whole
    perimeter is 0 is never seen; the map is the field without it, and nothing but the
    lattice is computed."""
    field = disks((65, 65), [(24, 24, 3)])
    got = refine_field(field.shape, field_callback(field)[0], 16)
    np.testing.assert_array_equal(got.labels, np.zeros_like(field))
    assert got.cells_computed == got.cells_per_level[0] == 65**2 - 60**2  # 5 lines each way


def test_wrong_cells_lie_in_islands(rng):
    """The guarantee, where something is missed: Newton's fractal basins with a dust of
    60 small disks (label 3, radius 1 to 4 cells) on top. Every wrong cell is a filled
    one, and each connected set (through edges and corners) of wrong cells is an island:
    all its neighbours carry the one label its block was filled with."""
    field = newton_basins(257)
    centres = rng.integers(0, 257, size=(60, 2))
    dust = disks(field.shape, [(r, c, rad) for (r, c), rad in
                               zip(centres, rng.integers(1, 5, size=60))]) > 0
    field[dust] = 3
    got = refine_field(field.shape, field_callback(field)[0], 32)
    wrong = got.labels != field
    assert wrong.any()  # some disks sit inside uniform blocks: the test has islands
    assert not (wrong & got.computed).any()
    islands, count = ndimage.label(wrong, structure=np.ones((3, 3)))
    for k in range(1, count + 1):
        cells = islands == k
        ring = ndimage.binary_dilation(cells, structure=np.ones((3, 3))) & ~cells
        assert np.unique(got.labels[ring]).size == 1
        assert (field[ring] == got.labels[ring]).all()


def test_bad_arguments():
    field = stripes((9, 9), 2)
    for step in (1, 0, -4):
        with pytest.raises(ValueError, match="step must be an int >= 2"):
            refine_field(field.shape, field_callback(field)[0], step)
    for step in (2.0, "4", True, None):
        with pytest.raises(ValueError, match="step must be an int >= 2"):
            refine_field(field.shape, field_callback(field)[0], step)
    with pytest.raises(ValueError, match="shape must be two ints"):
        refine_field((9, 9, 9), field_callback(field)[0], 4)
    with pytest.raises(ValueError, match="shape"):
        refine_field((0, 9), field_callback(field)[0], 4)
    with pytest.raises(ValueError, match="dtype float64"):
        refine_field((9, 9), lambda r, c: np.zeros(r.size), 4)
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        refine_field((9, 9), lambda r, c: np.zeros(3, dtype=int), 4)
