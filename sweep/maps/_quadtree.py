"""Adaptive boundary refinement of a 2-D label field (Mariani-Silver subdivision), as a
pure algorithm: it asks a callback for the labels of the cells it needs and knows
nothing of pendulums. `sweep.maps.refine` runs it on a grid of trajectories.

The rule
--------
A *block* is a rectangle of cells ``[r0, r1] x [c0, c1]`` (ends included); its
*perimeter* is its first and last row and column, its *interior* the rest.

1. The lattice: every cell of the rows ``0, s, 2s, ...`` and the columns ``0, s, 2s,
   ...`` (``s`` the step), and of the last row and column, is computed. The lattice
   lines cut the field into blocks of at most ``(s + 1) x (s + 1)`` cells whose
   perimeters are all computed.
2. A block without interior is done. A block whose perimeter cells (every one of them,
   at full resolution, not only its corners) all hold one label is *filled*: its
   interior gets that label without being computed.
3. Any other block is split in four by its middle row and middle column: the cells of
   that cross not yet computed are computed, and each of the four sub-blocks (whose
   perimeters are now all computed) goes back to step 2.

All the blocks of one level are decided together, so the callback is called once per
level with every new cell of that level (in a pendulum map: one `sweep.run` per level).

The guarantee
-------------
Every perimeter cell of a filled block was computed and holds the fill label. A region
of another label (a set of cells connected through edges or corners) that reaches a
block's perimeter therefore shows up there, and the block is split, never filled: a
boundary that crosses a block's border is always seen, however thin, since a connected
path from outside a block into its interior passes through a perimeter cell. What can
be missed is exactly what never touches the perimeter: a filled cell is labelled wrongly
only if it lies in an *island*, a connected set of cells of other labels entirely inside
the interior of the block. Islands narrower than the step, in blocks whose whole
border agrees, are what refinement can miss (measured on the fractal forced map by
``benchmarks/refine.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_count

__all__ = ["Refinement", "refine_field", "check_step"]


@dataclass
class Refinement:
    """The result of `refine_field`.

    Attributes
    ----------
    labels : ndarray, shape (n0, n1), int64
        The label of every cell: computed, or filled from its block's perimeter.
    computed : ndarray, shape (n0, n1), bool
        True where the callback computed the cell.
    cells_per_level : list of int
        Cells computed at each level (level 0: the lattice lines).
    blocks_filled : int
        Blocks whose interior was filled without being computed.
    decided : ndarray, shape (n0, n1), bool
        True where the label is final: computed, or filled (a block is filled as soon
        as its perimeter is seen to agree, so during the refinement this is what the
        levels so far decided).
    """

    labels: np.ndarray
    computed: np.ndarray
    cells_per_level: list = field(default_factory=list)
    blocks_filled: int = 0
    decided: np.ndarray = None

    @property
    def cells_computed(self) -> int:
        """Number of cells the callback computed (each once)."""
        return int(sum(self.cells_per_level))


def check_step(step) -> int:
    """The lattice step as an int; ValueError unless an int >= 2."""
    return check_count("step", step, minimum=2,
                       accepted="an int >= 2 (cells between lattice lines)")


def _lines(n: int, step: int) -> np.ndarray:
    """Lattice line indices ``0, step, 2 step, ...`` and ``n - 1``."""
    return np.unique(np.append(np.arange(0, n, step), n - 1)).astype(np.int64)


def _ragged(start: np.ndarray, stop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For segments ``start[k] .. stop[k]`` (ends included): the segment of each element
    and the element's value, concatenated over the segments."""
    length = stop - start + 1
    which = np.repeat(np.arange(start.size), length)
    offset = np.arange(length.sum()) - np.repeat(np.cumsum(length) - length, length)
    return which, start[which] + offset


def refine_field(shape: tuple[int, int], compute: Callable[..., np.ndarray],
                 step: int = 16, *, with_state: bool = False) -> Refinement:
    """Labels of a 2-D field, computing only the cells its boundaries need.

    Parameters
    ----------
    shape : (int, int)
        ``(n0, n1)``, cells along each axis, each >= 1.
    compute : callable ``(rows, cols) -> labels``
        ``rows``, ``cols``: int64 arrays of shape (m,), the cells to compute (each cell
        is asked for once over the whole refinement); returns their labels, shape (m,),
        integers (equal labels mean the same class).
        With ``with_state``, called as ``compute(rows, cols, refinement)``: the
        `Refinement` so far (read only; its ``labels`` hold what ``decided`` marks).
    step : int, default 16
        Spacing of the lattice lines, cells; >= 2. Larger steps compute fewer lattice
        cells but can miss larger islands (see the module docstring).

    Returns
    -------
    Refinement
        The labels, the mask of computed cells and counts.

    Raises
    ------
    ValueError
        For a shape that is not two ints >= 1, a step that is not an int >= 2, or a
        callback answer of the wrong shape or not integers.
    """
    step = check_step(step)
    if len(shape) != 2:
        raise ValueError(f"shape must be two ints >= 1, got {shape!r}")
    n0, n1 = (check_count("shape", n, minimum=1, accepted="two ints >= 1") for n in shape)
    labels = np.zeros((n0, n1), dtype=np.int64)
    computed = np.zeros((n0, n1), dtype=bool)
    out = Refinement(labels, computed, decided=np.zeros((n0, n1), dtype=bool))

    def ask(rows: np.ndarray, cols: np.ndarray) -> None:
        got = np.asarray(compute(rows, cols, out) if with_state else compute(rows, cols))
        if got.shape != rows.shape:
            raise ValueError(f"compute returned labels of shape {got.shape} for "
                             f"{rows.size} cells; accepted: shape ({rows.size},)")
        if got.dtype.kind not in "biu":
            raise ValueError(f"compute returned labels of dtype {got.dtype}; accepted: "
                             "integers")
        labels[rows, cols] = got
        computed[rows, cols] = True
        out.decided[rows, cols] = True
        out.cells_per_level.append(int(rows.size))

    rows_l, cols_l = _lines(n0, step), _lines(n1, step)
    lattice = np.zeros((n0, n1), dtype=bool)
    lattice[rows_l, :] = True
    lattice[:, cols_l] = True
    ask(*(index.astype(np.int64) for index in np.nonzero(lattice)))
    del lattice
    r0, c0 = (a.ravel() for a in np.meshgrid(rows_l[:-1], cols_l[:-1], indexing="ij"))
    r1, c1 = (a.ravel() for a in np.meshgrid(rows_l[1:], cols_l[1:], indexing="ij"))
    while True:
        inner = (r1 - r0 >= 2) & (c1 - c0 >= 2)
        r0, r1, c0, c1 = r0[inner], r1[inner], c0[inner], c1[inner]
        if r0.size == 0:
            break
        # label changes along each perimeter side, from running counts of the changes
        # between neighbouring cells (only computed cells lie on a perimeter)
        top_bottom = np.unique(np.concatenate([r0, r1]))
        left_right = np.unique(np.concatenate([c0, c1]))
        sub = labels[top_bottom]
        along = np.zeros(sub.shape, dtype=np.int64)
        np.cumsum(sub[:, 1:] != sub[:, :-1], axis=1, out=along[:, 1:])
        sub = labels[:, left_right]
        down = np.zeros(sub.shape, dtype=np.int64)
        np.cumsum(sub[1:] != sub[:-1], axis=0, out=down[1:])
        t, b = np.searchsorted(top_bottom, r0), np.searchsorted(top_bottom, r1)
        left, right = np.searchsorted(left_right, c0), np.searchsorted(left_right, c1)
        uniform = ((along[t, c1] == along[t, c0]) & (along[b, c1] == along[b, c0])
                   & (down[r1, left] == down[r0, left]) & (down[r1, right] == down[r0, right]))
        # filled now (a filled interior lies on no other block's perimeter, so the
        # decisions below do not see it)
        for i, j, k, m in zip(r0[uniform].tolist(), r1[uniform].tolist(),
                              c0[uniform].tolist(), c1[uniform].tolist()):
            labels[i + 1:j, k + 1:m] = labels[i, k]
            out.decided[i + 1:j, k + 1:m] = True
        out.blocks_filled += int(uniform.sum())
        split = ~uniform
        r0, r1, c0, c1 = r0[split], r1[split], c0[split], c1[split]
        if r0.size == 0:
            break
        rm, cm = (r0 + r1) // 2, (c0 + c1) // 2
        which, cols = _ragged(c0, c1)  # the middle row of each block
        need = np.zeros((n0, n1), dtype=bool)
        need[rm[which], cols] = True
        which, rows = _ragged(r0, r1)  # the middle column
        need[rows, cm[which]] = True
        need &= ~computed
        ask(*(index.astype(np.int64) for index in np.nonzero(need)))
        del need
        r0, r1 = np.concatenate([r0, r0, rm, rm]), np.concatenate([rm, rm, r1, r1])
        c0, c1 = np.concatenate([c0, cm, c0, cm]), np.concatenate([cm, c1, cm, c1])
    return out
