"""The Wada test of a 2-D basin map: does every boundary point of three or more basins
touch all of them?

Two published tests:

- `wada`, the grid method of Daza, Wagemakers, Sanjuán and Yorke, "Testing for basins
  of Wada", Sci. Rep. 5, 16579 (2015). It computes new trajectories, so it needs the
  labelling (``labels_of``) besides the map, and it is the one that settles each
  boundary cell below the grid's scale: the share ``W_m`` of boundary cells touching
  ``m`` basins, refined until it no longer moves.
- `wada_merging`, the merging method of Daza, Wagemakers and Sanjuán, "Ascertaining
  when a basin is Wada: the merging method", Sci. Rep. 8, 9954 (2018). It reads the
  label array alone (no new trajectory): merging all basins but one leaves a Wada
  boundary unchanged, so each merged map's boundary must lie within a few cells of the
  whole boundary.

Both ignore negative labels (`sweep.maps.UNRESOLVED`, -1): an unresolved cell is no
basin, and a new trajectory that is unresolved adds no basin to its cell. Neither treats
an axis as periodic (``theta0`` from -pi to pi is a flat strip here).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_count, check_quantity

__all__ = ["Wada", "WadaMerging", "wada", "wada_merging"]

#: At most this many basins (labels >= 0): a cell's basins are the bits of an uint64.
MAX_BASINS = 64

#: The verdict "partially Wada" needs at least this share of the boundary cells touching
#: three or more basins: a map whose only such cells are around isolated points where
#: three smooth boundaries meet (a handful of cells, whatever the resolution) is "not
#: Wada" (three sectors: 9 of 200 cells at 41 x 41).
PARTIAL_SHARE = 0.1

#: The eight neighbours of a cell, (row, column) offsets.
_NEIGHBOURS = np.array([(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0),
                        (1, 1)], dtype=np.int64)


@dataclass(frozen=True)
class Wada:
    """The grid method's answer (`wada`); arrays are read-only.

    Attributes
    ----------
    m : ndarray of int, shape (N,)
        ``1 .. N``, the numbers of basins a cell can touch (N = `basins`).
    fractions : ndarray of float, shape (N,)
        ``W_m``: the share of boundary cells touching ``m`` basins after the last
        refinement step (``fractions[m - 1]``; ``W_1`` is 0, a boundary cell touches
        two or more by definition). They sum to 1.
    counts : ndarray of int, shape (N,)
        The boundary cells touching ``m`` basins.
    history : ndarray of float, shape (steps + 1, N)
        ``W_m`` on the grid alone (row 0) and after each refinement step: the
        convergence the verdict rests on.
    touching : ndarray of int8, the map's shape
        Per cell, the basins it touches when it is a boundary cell; 0 elsewhere
        (interior and unresolved cells).
    basins : int
        N: the basins met (labels >= 0 of the map, and any new label refinement met).
    labels : ndarray of int
        The labels of the N basins, in bit order.
    boundary_cells : int
        Cells (labelled >= 0) whose 3 x 3 neighbourhood holds two or more basins.
    trajectories : int
        New trajectories computed (the check's and the refinement's; a point shared by
        two cells' segments counted once).
    steps : int
        Refinement steps run (at most ``max_steps``; fewer once every boundary cell
        touches all N basins).
    tolerance : float
        The verdict's tolerance.
    verdict : str
        ``"Wada"`` if ``W_N >= 1 - tolerance``; ``"partially Wada"`` if not, but the
        cells touching three or more basins are at least `PARTIAL_SHARE` (0.1) of the
        boundary; ``"not Wada"`` otherwise. A summary: read `history` (`table`).
    """

    m: np.ndarray
    fractions: np.ndarray
    counts: np.ndarray
    history: np.ndarray
    touching: np.ndarray
    basins: int
    labels: np.ndarray
    boundary_cells: int
    trajectories: int
    steps: int
    tolerance: float
    verdict: str

    def table(self) -> str:
        """``W_m`` as a Markdown table, one column per refinement step."""
        head = "| m | grid | " + " | ".join(f"step {q}" for q in range(1, self.steps + 1))
        rows = [head.rstrip(" |") + " |",
                "|" + " --- |" * (self.steps + 2)]
        for m in self.m:
            cells = " | ".join(f"{w:.3f}" for w in self.history[:, m - 1])
            rows.append(f"| {m} | {cells} |")
        return "\n".join(rows)


@dataclass(frozen=True)
class WadaMerging:
    """The merging method's answer (`wada_merging`); arrays are read-only.

    Attributes
    ----------
    labels : ndarray of int, shape (N,)
        The basins' labels.
    distances : ndarray of int, shape (N,)
        Per basin k, in cells (chessboard distance): the farthest cell of the whole
        boundary from the boundary of the map with every basin but k merged (their
        Hausdorff distance, since the merged boundary lies on the whole one).
    shares : ndarray of float, shape (N,)
        Per basin, the share of the whole boundary's cells farther than ``radius``
        cells from the merged map's boundary.
    boundary_cells : int
        Cells of the whole boundary (3 x 3 neighbourhood holding two or more basins).
    radius : int
    tolerance : float
    verdict : str
        ``"Wada"`` if every share is at most ``tolerance``, ``"not Wada"`` otherwise
        (some part of the boundary is not every basin's: a partially Wada map
        included).
    """

    labels: np.ndarray
    distances: np.ndarray
    shares: np.ndarray
    boundary_cells: int
    radius: int
    tolerance: float
    verdict: str


def _frozen(array) -> np.ndarray:
    array = np.array(array)
    array.setflags(write=False)
    return array


def _check_labels(labels) -> tuple[np.ndarray, tuple | None]:
    """The label array as int64 and, for a 2-D DataArray, its two coordinates."""
    coords = None
    if hasattr(labels, "dims") and hasattr(labels, "coords"):  # an xarray DataArray
        if len(labels.dims) == 2 and all(d in labels.coords for d in labels.dims):
            coords = tuple(np.asarray(labels.coords[d].values) for d in labels.dims)
        labels = labels.values
    array = np.asarray(labels)
    if array.ndim != 2 or min(array.shape) < 2:
        raise ValueError(f"labels must be a 2-D array of at least 2 x 2 cells, got shape "
                         f"{array.shape}; accepted: a basin map such as "
                         "sweep.maps.basins(run) of a 2-D grid")
    if array.dtype.kind not in "iu":
        raise ValueError(f"labels must hold integer labels, got dtype {array.dtype}; "
                         "accepted: an integer array (>= 0 a basin, < 0 unresolved), e.g. "
                         "labels.astype(int) after replacing NaN by -1")
    return array.astype(np.int64), coords


def _check_axis(name: str, values, size: int) -> np.ndarray:
    if values is None:
        raise ValueError(f"{name} is needed with a plain label array; accepted: the "
                         f"{size} coordinates of the map's axis {0 if name == 'x' else 1}, "
                         "or labels as a 2-D xarray.DataArray with coordinates")
    array = np.asarray(values)
    if array.dtype.kind not in "iuf" or array.ndim != 1 or array.size != size:
        raise ValueError(f"{name} must be a 1-D array of {size} numbers (the map's axis "
                         f"{0 if name == 'x' else 1}), got {array.dtype} of shape "
                         f"{array.shape}")
    array = array.astype(np.float64)
    step = np.diff(array)
    if not np.isfinite(array).all() or not ((step > 0).all() or (step < 0).all()):
        raise ValueError(f"{name} must be finite and strictly monotonic (the grid's "
                         f"coordinates along axis {0 if name == 'x' else 1}), got "
                         f"{array[:4].tolist()}{' ...' if size > 4 else ''}")
    return array


def _basins(labels: np.ndarray) -> np.ndarray:
    """The map's basin labels (>= 0), checked: three or more, at most MAX_BASINS."""
    found = np.unique(labels[labels >= 0])
    if found.size < 3:
        raise ValueError(f"labels hold {found.size} basin(s) ({found.tolist()}); the Wada "
                         "property needs three or more; accepted: a map of >= 3 basins "
                         "(labels >= 0; negative labels are unresolved cells)")
    if found.size > MAX_BASINS:
        raise ValueError(f"labels hold {found.size} basins; accepted: at most {MAX_BASINS}")
    return found


def _bits(labels: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Per label, the uint64 bit of its basin in ``known`` (0 for a negative label)."""
    index = np.searchsorted(known, labels)
    index = np.minimum(index, known.size - 1)
    bits = np.left_shift(np.uint64(1), index.astype(np.uint64))
    return np.where(labels >= 0, bits, np.uint64(0))


def _neighbourhood(bits: np.ndarray) -> np.ndarray:
    """Per cell, the OR of its 3 x 3 neighbourhood's bits (clipped at the map's edges)."""
    padded = np.pad(bits, 1)
    n0, n1 = bits.shape
    out = np.zeros_like(bits)
    for di in range(3):
        for dj in range(3):
            out |= padded[di:di + n0, dj:dj + n1]
    return out


def _popcount(bits: np.ndarray) -> np.ndarray:
    """Set bits of each uint64."""
    count = np.zeros(bits.shape, dtype=np.int64)
    bits = bits.copy()
    while bits.any():
        count += (bits & np.uint64(1)).astype(np.int64)
        bits >>= np.uint64(1)
    return count


def _coordinate(axis: np.ndarray, fine: np.ndarray, level: int) -> np.ndarray:
    """The coordinate of fine index ``fine`` (cell index times ``2**level``), linear
    between the grid's values (a segment between grid points stays straight)."""
    scale = 1 << level
    cell, rest = np.divmod(fine, scale)
    upper = np.minimum(cell + 1, axis.size - 1)
    return axis[cell] + (rest / scale) * (axis[upper] - axis[cell])


def _call(labels_of, starts: np.ndarray) -> np.ndarray:
    """``labels_of(starts)`` as int64, checked."""
    out = np.asarray(labels_of(starts))
    if out.shape != (starts.shape[0],):
        raise ValueError(f"labels_of must return one label per start, shape "
                         f"({starts.shape[0]},), got shape {out.shape}; accepted: a "
                         "callable (m, 2) array -> m integer labels")
    if out.dtype.kind not in "iu":
        raise ValueError(f"labels_of must return integer labels, got dtype {out.dtype}; "
                         "accepted: >= 0 a basin, < 0 unresolved")
    return out.astype(np.int64)


def _probe(labels, x, y, labels_of, check: int) -> int:
    """Relabel ``check`` interior cells (their 3 x 3 neighbourhood one basin) and refuse
    a ``labels_of`` that numbers the basins otherwise than the map. Returns the
    trajectories computed."""
    if check == 0:
        return 0
    valid = labels >= 0
    bits = _bits(labels, np.unique(labels[valid]))
    interior = valid & (_popcount(_neighbourhood(bits)) == 1)
    cells = np.flatnonzero(interior if interior.any() else valid)
    cells = cells[np.linspace(0, cells.size - 1, min(check, cells.size)).round()
                  .astype(np.int64)]
    cells = np.unique(cells)
    rows, cols = np.unravel_index(cells, labels.shape)
    got = _call(labels_of, np.column_stack([x[rows], y[cols]]))
    wrong = np.flatnonzero(got != labels[rows, cols])
    if wrong.size:
        k = wrong[0]
        raise ValueError(
            f"labels_of labels the start ({x[rows[k]]:.6g}, {y[cols[k]]:.6g}) of cell "
            f"({rows[k]}, {cols[k]}) as {got[k]}, where the map has {labels[rows[k], cols[k]]} "
            f"({wrong.size} of {cells.size} interior cells differ); accepted: a labels_of "
            "that numbers the basins as the map does (for a forced pendulum, label both "
            "with one attractor catalogue), and x, y the map's own coordinates")
    return int(cells.size)


def wada(labels, labels_of, x=None, y=None, *, max_steps: int = 8,
         tolerance: float = 0.01, check: int = 16) -> Wada:
    """The Wada test of a 2-D basin map by the grid method (Daza et al. 2015).

    Every cell labelled >= 0 whose 3 x 3 neighbourhood holds two or more basins is a
    boundary cell, touching the basins of its neighbourhood. A boundary cell touching
    fewer than all N basins is refined: at step q = 1, 2, ... new trajectories start on
    the segments from the cell's grid point to each of its (up to 8) neighbours', at
    the fractions k / 2**q of the segment for odd k (the points halfway in between the
    ones computed so far: 2**(q-1) new points per segment, doubled at each step), and
    each new label joins the cell's basins. A cell stops once it touches all N basins;
    the others go on to ``max_steps``. ``W_m`` is the share of boundary cells touching
    m basins; a Wada map has ``W_N`` near 1, growing toward 1 with the steps.

    What was followed: the procedure of Daza, Wagemakers, Sanjuán, Yorke, Sci. Rep. 5,
    16579 (2015) (the box of a grid point and its neighbours, new trajectories on the
    segments between grid points, their number doubled at each step up to a maximum,
    ``W_m`` per step), read through the summaries of it and its authors' Julia code
    (Wagemakers' ``Basins.jl``, ``detect_wada_grid_method``). Two choices differ from
    that code: it refines one segment per cell (towards one neighbour of another
    basin), this refines the segments to all 8 neighbours (a third basin can lie
    between two points of one basin; it costs up to 8 times more per cell); and a point
    shared by two cells' segments is computed once. The grid method rather than the
    merging method (`wada_merging`) answers here because it looks below the grid's
    scale; the merging method is bound to the map's resolution.

    Parameters
    ----------
    labels : array_like of int, shape (n0, n1), or a 2-D xarray.DataArray
        The map: a basin label per grid point, >= 0 a basin, < 0 unresolved (ignored).
        Three or more basins.
    labels_of : callable
        ``labels_of(starts) -> labels``: ``starts`` an ``(m, 2)`` float array of
        points (column 0 along the map's axis 0, in the units of ``x``; column 1 along
        axis 1, in those of ``y``), returning ``m`` integer labels numbered as the
        map's (for a forced pendulum: both from one attractor catalogue).
    x, y : array_like, shape (n0,) and (n1,), optional
        The grid's coordinates along axes 0 and 1, strictly monotonic (not necessarily
        evenly spaced). Default: the DataArray's coordinates; needed for a plain array.
    max_steps : int, default 8
        The most refinement steps, 0 to 20 (0: the grid alone). A cell that never
        reaches N basins costs ``8 (2**max_steps - 1)`` trajectories at most.
    tolerance : float, default 0.01
        For the verdict, in [0, 1): Wada if ``W_N >= 1 - tolerance`` after the last
        step. On a Wada map the share of boundary cells below N roughly halves with
        each step (the forced pendulum at A = 1.66, 60 x 60 cells: 0.27 on the grid,
        0.003 after 6 steps); on a partially Wada one it levels off (A = 1.71: at
        about 0.02-0.03, a smooth piece of boundary between two of its four basins).
        Read ``history`` before trusting a verdict near the tolerance.
    check : int, default 16
        Interior cells (3 x 3 neighbourhood one basin) relabelled by ``labels_of``
        before anything else, which must give the map's labels; 0 skips the check.

    Returns
    -------
    Wada
        ``fractions`` (W_m), ``counts``, ``history`` per step, per-cell ``touching``,
        ``trajectories`` computed and the ``verdict``.

    Raises
    ------
    ValueError
        Before any trajectory: labels that are not a 2-D integer array of >= 3 basins
        (at most 64), coordinates of the wrong size or not monotonic, a ``labels_of``
        that is not callable, options out of range. Then if the check's labels differ
        from the map's, or ``labels_of`` returns the wrong shape or type.

    Examples
    --------
    Three sectors around the origin: only the centre touches all three.

    >>> import numpy as np
    >>> from sweep import maps
    >>> def sector(p):
    ...     return (np.floor((np.arctan2(p[:, 1], p[:, 0]) + np.pi) / (2 * np.pi / 3))
    ...             .astype(int) % 3)
    >>> x = y = np.linspace(-1, 1, 41)
    >>> grid = np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1).reshape(-1, 2)
    >>> result = maps.wada(sector(grid).reshape(41, 41), sector, x, y, max_steps=3)
    >>> result.verdict
    'not Wada'
    """
    array, coords = _check_labels(labels)
    if coords is not None:
        x = coords[0] if x is None else x
        y = coords[1] if y is None else y
    x = _check_axis("x", x, array.shape[0])
    y = _check_axis("y", y, array.shape[1])
    if not callable(labels_of):
        raise ValueError(f"labels_of must be a callable (m, 2) array of starts -> m "
                         f"integer labels, got {labels_of!r} ({type(labels_of).__name__})")
    max_steps = check_count("max_steps", max_steps, minimum=0, maximum=20)
    tolerance = check_quantity("tolerance", tolerance, minimum=0.0,
                               accepted="a number in [0, 1)")
    if tolerance >= 1:
        raise ValueError(f"tolerance must be a number in [0, 1), got {tolerance!r}")
    check = check_count("check", check, minimum=0)
    known = _basins(array)
    trajectories = _probe(array, x, y, labels_of, check)

    valid = array >= 0
    seen = _neighbourhood(_bits(array, known))
    boundary = valid & (_popcount(seen) >= 2)
    rows, cols = np.nonzero(boundary)
    cell_bits = seen[rows, cols]
    history = [_popcount(cell_bits)]
    steps = 0
    for level in range(1, max_steps + 1):
        open_ = np.flatnonzero(history[-1] < known.size)
        if open_.size == 0:
            break
        steps = level
        scale = 1 << level
        ks = np.arange(1, scale, 2, dtype=np.int64)
        r = rows[open_, None, None]
        c = cols[open_, None, None]
        di = _NEIGHBOURS[None, :, 0, None]
        dj = _NEIGHBOURS[None, :, 1, None]
        inside = ((r + di >= 0) & (r + di < array.shape[0]) & (c + dj >= 0)
                  & (c + dj < array.shape[1]))
        inside = np.broadcast_to(inside, (open_.size, 8, ks.size))
        fine_r = np.broadcast_to(r * scale + ks * di, inside.shape)[inside]
        fine_c = np.broadcast_to(c * scale + ks * dj, inside.shape)[inside]
        owner = np.broadcast_to(open_[:, None, None], inside.shape)[inside]
        points, where = np.unique(np.column_stack([fine_r, fine_c]), axis=0,
                                  return_inverse=True)
        starts = np.column_stack([_coordinate(x, points[:, 0], level),
                                  _coordinate(y, points[:, 1], level)])
        found = _call(labels_of, starts)
        trajectories += found.size
        new = np.setdiff1d(found[found >= 0], known)
        if new.size:  # a basin the grid missed
            if known.size + new.size > MAX_BASINS:
                raise ValueError(f"labels_of found {known.size + new.size} basins; "
                                 f"accepted: at most {MAX_BASINS}")
            old = known
            known = np.union1d(known, new)
            cell_bits = _rebit(cell_bits, old, known)
        np.bitwise_or.at(cell_bits, owner, _bits(found, known)[where.ravel()])
        history.append(_popcount(cell_bits))

    n = known.size
    m = np.arange(1, n + 1)
    table = np.array([np.bincount(h, minlength=n + 1)[1:] for h in history], dtype=np.int64)
    total = max(int(boundary.sum()), 1)
    fractions = table / total
    touching = np.zeros(array.shape, dtype=np.int8)
    touching[rows, cols] = history[-1]
    last = fractions[-1]
    if last[n - 1] >= 1 - tolerance:
        verdict = "Wada"
    elif last[2:].sum() >= PARTIAL_SHARE:
        verdict = "partially Wada"
    else:
        verdict = "not Wada"
    return Wada(m=_frozen(m), fractions=_frozen(last), counts=_frozen(table[-1]),
                history=_frozen(fractions), touching=_frozen(touching), basins=int(n),
                labels=_frozen(known), boundary_cells=int(boundary.sum()),
                trajectories=int(trajectories), steps=steps, tolerance=tolerance,
                verdict=verdict)


def _rebit(bits: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Cells' basin bits over the labels ``old`` renumbered over ``new`` (a superset)."""
    out = np.zeros_like(bits)
    for k, label in enumerate(old):
        has = (bits >> np.uint64(k)) & np.uint64(1)
        out |= has << np.uint64(np.searchsorted(new, label))
    return out


def wada_merging(labels, *, radius: int = 2, tolerance: float = 0.01) -> WadaMerging:
    """The Wada test of a 2-D basin map by the merging method (Daza et al. 2018), on
    the label array alone.

    The boundary is the set of cells labelled >= 0 whose 3 x 3 neighbourhood holds two
    or more basins. For each basin k, the map with every other basin merged into one
    has its own boundary (the cells whose neighbourhood holds k and another basin),
    part of the whole one. A Wada boundary is unchanged by the merging: every merged
    boundary is the whole boundary, up to the grid's resolution. Here each merged
    boundary is dilated by ``radius`` cells (chessboard distance) and must cover all
    but ``tolerance`` of the whole boundary's cells.

    What was followed: Daza, Wagemakers, Sanjuán, Sci. Rep. 8, 9954 (2018) (merge all
    basins but one, compare the boundaries after fattening them by a few cells; the
    Hausdorff distance between them stays a few cells for a Wada map), as Attractors.jl
    (``test_wada_merge``: the share of boundary cells farther than ``r`` cells) and
    Wagemakers' ``Basins.jl`` implement it.

    The grid's resolution limits it: it cannot tell a Wada boundary from boundaries
    closer together than ``radius`` cells, which `wada` (new trajectories below the
    grid's scale) can.

    Parameters
    ----------
    labels : array_like of int, shape (n0, n1), or a 2-D xarray.DataArray
        The map, >= 0 a basin, < 0 unresolved (ignored); three or more basins.
    radius : int, default 2
        Cells, >= 0: how far a merged boundary may lie from the whole one.
    tolerance : float, default 0.01
        In [0, 1): the share of the boundary a merged boundary may miss (as `wada`'s
        tolerance: the forced pendulum's 200 x 200 maps miss at most 0.0024 at
        A = 1.66, Wada, and up to 0.037 at A = 1.71, partially Wada).

    Returns
    -------
    WadaMerging

    Raises
    ------
    ValueError
        For labels that are not a 2-D integer array of >= 3 basins, or options out of
        range.
    """
    from scipy import ndimage

    array, _ = _check_labels(labels)
    radius = check_count("radius", radius, minimum=0)
    tolerance = check_quantity("tolerance", tolerance, minimum=0.0,
                               accepted="a number in [0, 1)")
    if tolerance >= 1:
        raise ValueError(f"tolerance must be a number in [0, 1), got {tolerance!r}")
    known = _basins(array)
    valid = array >= 0
    seen = _neighbourhood(_bits(array, known))
    boundary = valid & (_popcount(seen) >= 2)
    total = int(boundary.sum())
    distances, shares = [], []
    for k in range(known.size):
        bit = np.uint64(1) << np.uint64(k)
        merged = boundary & ((seen & bit) != 0)  # holds k and, being boundary, another
        if not merged.any():  # a basin touching no other: the boundary is all missed
            distances.append(max(array.shape))
            shares.append(1.0)
            continue
        far = ndimage.distance_transform_cdt(~merged, metric="chessboard")[boundary]
        distances.append(int(far.max()))
        shares.append(float((far > radius).sum()) / max(total, 1))
    shares = np.array(shares)
    verdict = "Wada" if (shares <= tolerance).all() else "not Wada"
    return WadaMerging(labels=_frozen(known), distances=_frozen(np.array(distances)),
                       shares=_frozen(shares), boundary_cells=total, radius=radius,
                       tolerance=tolerance, verdict=verdict)


def _scene_labels(scene, attractors, **run_kwargs):
    """``labels_of`` for a forced pendulum's basins: each start labelled by the index
    of the catalogued attractor its trajectory settles on (``sweep.run(...,
    attractors=catalogue)``'s ``attractor``), -1 where none matched. The map and its
    refinement labelled by one such function number the basins alike, across runs.

    Parameters
    ----------
    scene : Scene
    attractors : dict
        `sweep.maps.attractor_catalogue` (of a pilot, `sweep.maps.pilot_catalogue`).
    **run_kwargs
        `sweep.run` arguments (``t_end``, ``dt``, ``t_transient``, ``observe``,
        ``stop_early``, ...); ``progress`` defaults to False.
    """
    from .uncertainty import scene_labels

    return scene_labels(scene, attractors=attractors, **run_kwargs)

