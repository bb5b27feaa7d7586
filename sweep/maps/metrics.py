"""Basin metrics on integer label maps: fractions, basin entropy, uncertainty exponent,
box-counting dimension of the boundary, and the basin-entropy test for fractal
boundaries (Puy et al. 2021).

Every function takes an array of integer labels (one label per grid cell, e.g. the
attractor or well that each initial condition ends in), either a NumPy array or an
``xarray.DataArray`` (read through ``numpy.asarray``; dimension names are not used), of
any number of dimensions >= 1. The label map need not come from `sweep`. Floats are
accepted when every value is a whole number (``2.0``); ``NaN`` is not a label, so
fill unresolved cells with a label of their own (the house convention is ``-1``).

The grid is taken as uniform and each axis is measured in cells: box sides and
perturbation radii are integer numbers of cells, so results are independent of the
physical units of the axes (rescaling an axis changes neither a slope nor an entropy),
but a box of ``s`` cells covers different physical lengths along axes of different
spacing.

Only NumPy is needed at import (no numba, no SciPy); the log-log fits use
`numpy.polyfit`.

References
----------
.. [1] A. Daza, A. Wagemakers, B. Georgeot, D. Guéry-Odelin, M. A. F. Sanjuán,
   "Basin entropy: a new tool to analyze uncertainty in dynamical systems",
   Sci. Rep. 6, 31416 (2016), doi:10.1038/srep31416.
.. [2] C. Grebogi, S. W. McDonald, E. Ott, J. A. Yorke, "Final state sensitivity: an
   obstruction to predictability", Phys. Lett. A 99, 415-418 (1983),
   doi:10.1016/0375-9601(83)90945-3.
.. [3] S. W. McDonald, C. Grebogi, E. Ott, J. A. Yorke, "Fractal basin boundaries",
   Physica D 17, 125-153 (1985), doi:10.1016/0167-2789(85)90001-6.
.. [4] K. Falconer, *Fractal Geometry: Mathematical Foundations and Applications*,
   3rd ed., Wiley (2014), ch. 2-3 (box-counting dimension).
.. [5] A. Puy, A. Daza, A. Wagemakers, M. A. F. Sanjuán, "A test for fractal boundaries
   based on the basin entropy", Commun. Nonlinear Sci. Numer. Simul. 95, 105588 (2021),
   doi:10.1016/j.cnsns.2020.105588.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "BasinEntropy",
    "BoxCountingDimension",
    "FractalityTest",
    "UncertaintyExponent",
    "basin_entropy",
    "basin_fractions",
    "box_counting_dimension",
    "fractality_test",
    "smooth_boundary_entropy",
    "uncertainty_exponent",
]

# A two-label box has entropy at most log 2, so a boundary with only two labels can
# never pass the log-2 criterion; this relative margin keeps a rounding error of one
# ulp in the mean (Sbb = log 2 computed as 0.69314718055994540 + 1 ulp) from flagging it.
_LOG2_MARGIN = 1e-12


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class BasinEntropy:
    """Result of `basin_entropy`.

    Attributes
    ----------
    sb : float
        Basin entropy Sb [nats]: the mean Gibbs entropy over all boxes, in
        ``[0, log(number of labels)]``.
    sbb : float
        Boundary basin entropy Sbb [nats]: the mean over the boxes holding more than one
        label; ``0.0`` when there is no such box.
    n_boxes : int
        Number of complete boxes used (incomplete edge boxes are dropped).
    n_boundary_boxes : int
        Number of those boxes holding more than one label.
    fractal_boundary : bool
        ``sbb > log 2``: the log-2 criterion of Daza et al. (2016), a *sufficient*
        condition for a fractal boundary (``False`` does not mean "smooth").
    """

    sb: float
    sbb: float
    n_boxes: int
    n_boundary_boxes: int
    fractal_boundary: bool


@dataclass(frozen=True)
class UncertaintyExponent:
    """Result of `uncertainty_exponent`.

    Attributes
    ----------
    alpha : float
        Uncertainty exponent, the least-squares slope of ``log f`` against ``log eps``
        over the radii with ``f > 0``; ``nan`` when fewer than two radii have ``f > 0``.
    epsilons : tuple of int
        Perturbation radii [cells], increasing.
    fractions : tuple of float
        Fraction ``f(eps)`` of uncertain cells, one per radius, in ``[0, 1]``.
    boundary_dimension : float
        ``D - alpha`` with ``D = labels.ndim``, the box-counting dimension of the
        boundary implied by the exponent (McDonald et al. 1985).
    """

    alpha: float
    epsilons: tuple[int, ...]
    fractions: tuple[float, ...]
    boundary_dimension: float


@dataclass(frozen=True)
class BoxCountingDimension:
    """Result of `box_counting_dimension`.

    Attributes
    ----------
    dimension : float
        Minus the least-squares slope of ``log N(s)`` against ``log s`` over the sizes
        with ``N(s) > 0``; ``nan`` when fewer than two sizes have ``N(s) > 0``.
    box_sizes : tuple of int
        Box sides ``s`` [cells], increasing.
    counts : tuple of int
        ``N(s)``, the number of complete boxes of side ``s`` holding part of the
        boundary (more than one label, or a label change across the box's upper faces;
        see `box_counting_dimension`), one per size.
    """

    dimension: float
    box_sizes: tuple[int, ...]
    counts: tuple[int, ...]


# ------------------------------------------------------------------------ validators


def _check_labels(labels: Any) -> np.ndarray:
    """Return ``labels`` as an integer ndarray with at least one dimension and one cell.

    Accepts NumPy arrays, ``xarray.DataArray`` (through ``__array__``) and nested
    sequences; booleans become 0/1 and floats must be whole numbers.
    """
    array = np.asarray(labels)  # xarray.DataArray and pandas objects via __array__
    if array.dtype == np.bool_:
        array = array.astype(np.int8)
    if array.ndim == 0:
        raise ValueError(
            f"labels must be an array with at least one dimension, got a scalar "
            f"{array.item()!r}; accepted: an integer array such as a 2-D label map"
        )
    if array.size == 0:
        raise ValueError(
            f"labels is empty (shape {array.shape}); accepted: an integer array with at "
            "least one cell"
        )
    if np.issubdtype(array.dtype, np.integer):
        return array
    if not np.issubdtype(array.dtype, np.floating):
        raise ValueError(
            f"labels must hold integers, got dtype {array.dtype}; accepted: an integer "
            "array, or floats that are whole numbers"
        )
    bad = ~np.isfinite(array) | (array != np.round(array)) | (np.abs(array) > 2.0**53)
    if bad.any():
        index = np.unravel_index(int(np.flatnonzero(bad)[0]), array.shape)
        raise ValueError(
            f"labels must hold integers, got {array[index].item()!r} at index "
            f"{tuple(int(i) for i in index)}; accepted: integers or whole-number floats "
            "(give unresolved cells a label of their own, e.g. -1, instead of NaN)"
        )
    return array.astype(np.int64)


def _check_int(name: str, value: Any, low: int, high: int | None, accepted: str) -> int:
    """Return ``value`` as an int in ``[low, high]`` or raise ValueError saying so."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        # ValueError, not TypeError: every bad parameter value raises ValueError here
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    value = int(value)
    if value < low or (high is not None and value > high):
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    return value


def _check_rng(rng: Any) -> np.random.Generator:
    """Return ``numpy.random.default_rng(rng)`` or raise ValueError naming ``rng``.

    Booleans are refused (``default_rng(True)`` would seed with 1)."""
    accepted = ("None, a seed (an int >= 0 or a sequence of them), a numpy.random."
                "Generator, BitGenerator or SeedSequence")
    if isinstance(rng, (bool, np.bool_, str, bytes)):
        # ValueError, not TypeError, as in _check_int
        raise ValueError(f"rng must be {accepted}, got {rng!r}")
    try:
        return np.random.default_rng(rng)
    except (TypeError, ValueError):
        raise ValueError(f"rng must be {accepted}, got {rng!r}") from None


def _check_sizes(name: str, values: Any, low: int, high: int, accepted: str) -> list[int]:
    """Return a sorted list of distinct ints in ``[low, high]`` (at least two)."""
    if isinstance(values, (numbers.Number, str, bytes)):
        raise ValueError(
            f"{name} must be a sequence of {accepted}, got {values!r}"
        )
    try:
        values = list(values)
    except TypeError:
        raise ValueError(f"{name} must be a sequence of {accepted}, got {values!r}") from None
    sizes = sorted({_check_int(name, v, low, high, accepted) for v in values})
    if len(sizes) < 2:
        raise ValueError(
            f"{name} must hold at least two distinct values to fit a slope, got "
            f"{values!r}; accepted: {accepted}"
        )
    return sizes


# --------------------------------------------------------------------------- helpers


def _boxes(labels: np.ndarray, size: int) -> np.ndarray:
    """View ``labels`` cropped to whole boxes as shape ``(b0, size, b1, size, ...)``.

    Incomplete boxes at the high-index edge of each axis are dropped.
    """
    nboxes = [n // size for n in labels.shape]
    cropped = labels[tuple(slice(0, b * size) for b in nboxes)]
    return cropped.reshape(tuple(x for b in nboxes for x in (b, size)))


def _fit_slope(x: Iterable[float], y: Iterable[float]) -> float:
    """Least-squares slope of ``log y`` against ``log x`` over the points with ``y > 0``."""
    x = np.asarray(list(x), dtype=np.float64)
    y = np.asarray(list(y), dtype=np.float64)
    keep = y > 0
    if keep.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(x[keep]), np.log(y[keep]), 1)[0])


# ------------------------------------------------------------------------ public API


def basin_fractions(labels: Any, ignore: int | Iterable[int] | None = None) -> dict[int, float]:
    """Fraction of the grid covered by each label.

    Parameters
    ----------
    labels : array_like of int, any shape with at least one cell
        Label map, e.g. an ``xarray.DataArray`` with dims ``("theta0", "omega0")``.
        Whole-number floats are accepted.
    ignore : int or iterable of int, optional
        Labels left out of the count, e.g. ``-1`` for unresolved cells. The fractions
        are then renormalised over the remaining cells, so they still sum to 1: they are
        fractions *of the resolved cells*, not of the grid. Labels in ``ignore`` that do
        not occur are harmless.

    Returns
    -------
    dict of int to float
        ``{label: fraction}`` for every label present (and not ignored), in increasing
        label order; each fraction is in ``(0, 1]`` and they sum to 1 (to rounding).

    Raises
    ------
    ValueError
        If ``labels`` is empty or not integer-valued, if ``ignore`` is not integer
        labels, or if every cell is ignored.

    Notes
    -----
    With ``n_j`` the number of cells labelled ``j`` and ``n`` the number of cells not
    ignored, the fraction is ``n_j / n``. On a uniform grid of initial conditions this
    estimates the relative volume of each basin in the region swept; its standard
    error is ``sqrt(p (1 - p) / n)`` if the cells were independent samples.

    References
    ----------
    .. [1] A. Daza et al., Sci. Rep. 6, 31416 (2016), where basin volumes enter the
       maximum entropy ``log N_A``.

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps.metrics import basin_fractions
    >>> basin_fractions(np.array([[0, 0, 1, -1]]), ignore=-1)
    {0: 0.6666666666666666, 1: 0.3333333333333333}
    """
    array = _check_labels(labels)
    values, counts = np.unique(array, return_counts=True)
    if ignore is not None:
        accepted = "an integer label, an iterable of integer labels, or None"
        items = [ignore] if isinstance(ignore, numbers.Number) else ignore
        try:
            dropped = {_check_int("ignore", v, -(2**63), None, accepted) for v in items}
        except TypeError:
            raise ValueError(f"ignore must be {accepted}, got {ignore!r}") from None
        keep = ~np.isin(values, list(dropped))
        values, counts = values[keep], counts[keep]
        if counts.sum() == 0:
            raise ValueError(
                f"every cell has a label in ignore={ignore!r}; nothing is left to take "
                "fractions of; accepted: an ignore that leaves at least one cell"
            )
    total = int(counts.sum())
    return {int(v): int(c) / total for v, c in zip(values, counts)}


def basin_entropy(labels: Any, box_size: int = 5) -> BasinEntropy:
    """Basin entropy Sb and boundary basin entropy Sbb of a label map.

    Parameters
    ----------
    labels : array_like of int, shape (n_0, n_1, ..., n_{D-1}), D >= 1
        Label map; any number of dimensions (boxes are hypercubes). Every label, ``-1``
        included, counts as a distinct outcome.
    box_size : int, default 5
        Side of the boxes [cells], ``1 <= box_size <= min(labels.shape)``. Sb and Sbb
        depend on it, so compare maps at the same box size; a box of side 1 always
        gives 0.

    Returns
    -------
    BasinEntropy
        ``sb`` and ``sbb`` in nats (natural log), ``n_boxes``, ``n_boundary_boxes`` and
        ``fractal_boundary`` (``sbb > log 2``).

    Raises
    ------
    ValueError
        If ``labels`` is empty or not integer-valued, or ``box_size`` is not an integer
        in ``[1, min(labels.shape)]``.

    Notes
    -----
    The grid is covered with non-overlapping boxes of ``box_size`` cells along every
    axis, starting at index 0; the incomplete boxes left at the high-index end of an
    axis whose length is not a multiple of ``box_size`` are dropped (their cells are not
    used), so every box holds exactly ``n = box_size**D`` cells. In box ``i`` with label
    frequencies ``p_ij`` the Gibbs entropy is

    .. math:: S_i = -\\sum_j p_{ij} \\log p_{ij},

    and with ``N`` boxes of which ``N_b`` hold more than one label,

    .. math:: S_b = \\frac{1}{N} \\sum_i S_i, \\qquad S_{bb} = \\frac{1}{N_b} \\sum_i S_i,

    the sums running over all boxes (single-label boxes contribute 0), so
    ``sb = sbb * N_b / N``. When ``N_b = 0`` the mean over boundary boxes is empty and
    ``sbb`` is defined as ``0.0`` (no uncertainty), not ``nan``, so that ``sbb > log 2``
    stays a plain comparison.

    Sb is 0 for a single basin and at most ``log`` (number of labels). Daza et al.
    show that ``Sbb > log 2`` implies a fractal boundary; the criterion is sufficient,
    not necessary: a fractal boundary between only two basins always has
    ``Sbb <= log 2`` (a two-label box has entropy at most ``log 2``), so it needs three
    or more labels mixing at the scale of a box to fire. The comparison uses a relative
    margin of 1e-12 so that rounding cannot lift a two-label ``Sbb = log 2`` over it.

    These are also the boxes and means of Attractors.jl's ``basin_entropy`` (boxes
    from the first cell, remainder dropped), so the values agree with it.

    The ``S_i`` are plug-in estimates from ``n`` cells; for labels that are random at
    the scale of a box with ``k`` equiprobable values they are biased low by about
    ``(k - 1) / (2 n)`` (Miller 1955; the next term, ``(1 - k**2) / (12 n**2)``, is
    given by Harris 1975).

    References
    ----------
    .. [1] A. Daza, A. Wagemakers, B. Georgeot, D. Guéry-Odelin, M. A. F. Sanjuán,
       "Basin entropy: a new tool to analyze uncertainty in dynamical systems",
       Sci. Rep. 6, 31416 (2016), doi:10.1038/srep31416.
    .. [2] G. A. Miller, "Note on the bias of information estimates", in *Information
       Theory in Psychology*, H. Quastler (ed.), Free Press (1955), pp. 95-100.
    .. [3] B. Harris, "The statistical estimation of entropy in the non-parametric
       case", in *Topics in Information Theory*, I. Csiszár, P. Elias (eds.),
       North-Holland (1975), pp. 323-355.

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps.metrics import basin_entropy
    >>> checkerboard = np.indices((8, 8)).sum(axis=0) % 2
    >>> result = basin_entropy(checkerboard, box_size=4)
    >>> round(result.sb, 6), result.n_boxes, result.fractal_boundary
    (0.693147, 4, False)
    """
    array = _check_labels(labels)
    smallest = min(array.shape)
    box_size = _check_int(
        "box_size", box_size, 1, smallest,
        f"an integer from 1 to the smallest axis length of labels ({smallest}, "
        f"labels.shape = {array.shape})",
    )
    ndim = array.ndim
    blocked = _boxes(array, box_size)
    # (b0, s, b1, s, ...) -> (b0, b1, ..., s, s, ...) -> one row of n cells per box
    order = tuple(range(0, 2 * ndim, 2)) + tuple(range(1, 2 * ndim, 2))
    cells = blocked.transpose(order).reshape(-1, box_size**ndim)
    n_boxes, n = cells.shape
    # entropy per box from the run lengths of its sorted labels: O(size) memory
    # whatever the number of distinct labels
    cells = np.sort(cells, axis=1)
    starts_run = np.ones(cells.shape, dtype=bool)
    starts_run[:, 1:] = cells[:, 1:] != cells[:, :-1]
    starts = np.flatnonzero(starts_run)
    p = np.diff(np.append(starts, cells.size)) / n
    box_of_run = starts // n
    entropy = np.bincount(box_of_run, weights=-p * np.log(p), minlength=n_boxes)
    n_labels = np.bincount(box_of_run, minlength=n_boxes)
    boundary = n_labels > 1
    n_boundary = int(boundary.sum())
    total = math.fsum(entropy[boundary])  # single-label boxes contribute exactly 0
    sb = total / n_boxes
    sbb = total / n_boundary if n_boundary else 0.0
    return BasinEntropy(
        sb=sb,
        sbb=sbb,
        n_boxes=int(n_boxes),
        n_boundary_boxes=n_boundary,
        fractal_boundary=bool(sbb > math.log(2.0) * (1.0 + _LOG2_MARGIN)),
    )


def uncertainty_exponent(
    labels: Any,
    epsilons: Iterable[int] | None = None,
    n_samples: int | None = None,
    rng: np.random.Generator | int | None = None,
) -> UncertaintyExponent:
    """Uncertainty exponent alpha of a label map: ``f(eps) ~ eps**alpha``.

    Parameters
    ----------
    labels : array_like of int, shape (n_0, ..., n_{D-1}), D >= 1
        Label map, any number of dimensions.
    epsilons : iterable of int, optional
        Perturbation radii [cells], at least two distinct integers with
        ``1 <= eps`` and ``2 * eps < min(labels.shape)``. Default: the powers of 2 from 1
        up to ``min(labels.shape) // 16`` (so the cells tested keep at least 7/8 of each
        axis and ``f`` stays well below saturation), which needs every axis to have at
        least 32 cells.
    n_samples : int, optional
        Test this many cells, drawn without replacement from the tested region (the
        same cells for every radius), instead of all of them. A number at least the
        size of that region tests all of it.
    rng : numpy.random.Generator or int, optional
        Generator or seed for the draw when ``n_samples`` is given; ``None`` draws
        from fresh OS entropy (pass a seed to reproduce a result). Unused otherwise.

    Returns
    -------
    UncertaintyExponent
        ``alpha``, the ``epsilons`` used, the ``fractions`` ``f(eps)`` and
        ``boundary_dimension = D - alpha``.

    Raises
    ------
    ValueError
        If ``labels`` is empty or not integer-valued, if ``epsilons`` holds fewer than
        two distinct radii or a radius outside ``[1, (min(labels.shape) - 1) // 2]``,
        if the default radii do not fit (an axis shorter than 32 cells), if
        ``n_samples`` is not a positive integer, or if ``rng`` is not a generator or a
        seed (checked even when ``n_samples`` is None).

    Notes
    -----
    A cell ``x`` is *eps-uncertain* when its label differs from that of at least one of
    the ``2 D`` cells ``x +- eps e_k`` (``e_k`` the unit step along axis ``k``): a
    perturbation of size ``eps`` of that initial condition can change its final state
    (Grebogi et al. 1983; McDonald et al. 1985 perturb along one direction; testing
    every axis gives the same exponent with a larger prefactor). ``f(eps)`` is the
    fraction of tested cells that are eps-uncertain. For a boundary of box-counting
    dimension ``d`` in a ``D``-dimensional grid, ``f(eps) ~ eps**(D - d)``: ``alpha = 1``
    for a smooth boundary, ``alpha < 1`` for a fractal one.

    There is no wrap-around. The tested cells are the same for every radius: those at
    least ``max(epsilons)`` cells from every edge, so that all their neighbours exist
    at every radius. (Shrinking the region with ``eps`` would change the denominator
    with ``eps`` and bias the slope.) ``alpha`` is the least-squares slope of
    ``log f`` against ``log eps`` over the radii with ``f > 0``, ``nan`` if fewer than
    two (e.g. a single-label map).

    On a grid the count is exact for a straight boundary that crosses the tested
    region from side to side: each line of cells across it (along the axis it is
    closer to being perpendicular to) holds exactly ``2 eps`` uncertain cells, and the
    cells uncertain along other axes lie among them, so ``alpha = 1`` to rounding.
    Smooth curves of radius ``R`` cells deviate by ``O(1/R)`` in ``f / eps`` while
    ``eps`` is small against ``R``; for large radii ``f`` saturates towards 1 and the
    fit bends down. For fractal boundaries the power law is only asymptotic (with
    log-periodic wiggles for self-similar ones), so fit radii spanning an order of
    magnitude or more, well below saturation.

    Attractors.jl's ``uncertainty_exponent`` estimates alpha instead as ``D - d``
    from box counting (`box_counting_dimension` here); the two agree for
    self-similar boundaries, not digit for digit on finite grids.

    References
    ----------
    .. [1] C. Grebogi, S. W. McDonald, E. Ott, J. A. Yorke, "Final state sensitivity:
       an obstruction to predictability", Phys. Lett. A 99, 415-418 (1983).
    .. [2] S. W. McDonald, C. Grebogi, E. Ott, J. A. Yorke, "Fractal basin
       boundaries", Physica D 17, 125-153 (1985).

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps.metrics import uncertainty_exponent
    >>> x = np.linspace(0.0, 1.0, 256)
    >>> half_plane = np.broadcast_to(x[:, None] > 0.3, (256, 256))
    >>> round(uncertainty_exponent(half_plane).alpha, 12)
    1.0
    """
    array = _check_labels(labels)
    if n_samples is not None:
        n_samples = _check_int("n_samples", n_samples, 1, None, "a positive integer or None")
    generator = _check_rng(rng)
    shape = array.shape
    smallest = min(shape)
    largest_eps = (smallest - 1) // 2
    accepted = (
        f"integers eps with 1 <= eps <= (min(labels.shape) - 1) // 2 = {largest_eps} "
        f"(labels.shape = {shape}), so that some cell has all its neighbours at +-eps"
    )
    if epsilons is None:
        top = smallest // 16
        eps_list = [2**k for k in range(top.bit_length())] if top >= 1 else []
        if len(eps_list) < 2:
            raise ValueError(
                f"labels of shape {shape} is too small for the default epsilons (powers "
                f"of 2 up to min(labels.shape) // 16 = {top}, at least two needed); pass "
                f"epsilons explicitly, as {accepted}, or use at least 32 cells per axis"
            )
    else:
        if largest_eps < 1:
            raise ValueError(
                f"labels of shape {shape} is too small for any radius: an axis needs at "
                f"least 3 cells so that a cell has neighbours at +-1; got epsilons="
                f"{epsilons!r}"
            )
        eps_list = _check_sizes("epsilons", epsilons, 1, largest_eps, accepted)
    margin = eps_list[-1]
    interior = tuple(slice(margin, n - margin) for n in shape)
    interior_shape = tuple(n - 2 * margin for n in shape)
    n_interior = math.prod(interior_shape)

    if n_samples is not None and n_samples < n_interior:
        flat = generator.choice(n_interior, size=n_samples, replace=False)
        points = tuple(
            idx + margin for idx in np.unravel_index(flat, interior_shape)
        )
        centre = array[points]
        n_tested = n_samples

        def neighbour(axis: int, offset: int) -> np.ndarray:
            moved = list(points)
            moved[axis] = points[axis] + offset
            return array[tuple(moved)]

    else:
        centre = array[interior]
        n_tested = n_interior

        def neighbour(axis: int, offset: int) -> np.ndarray:
            index = list(interior)
            index[axis] = slice(margin + offset, shape[axis] - margin + offset)
            return array[tuple(index)]

    fractions = []
    for eps in eps_list:
        uncertain = np.zeros(centre.shape, dtype=bool)
        for axis in range(array.ndim):
            for offset in (-eps, eps):
                uncertain |= neighbour(axis, offset) != centre
        fractions.append(int(np.count_nonzero(uncertain)) / n_tested)
    alpha = _fit_slope(eps_list, fractions)
    return UncertaintyExponent(
        alpha=alpha,
        epsilons=tuple(eps_list),
        fractions=tuple(fractions),
        boundary_dimension=array.ndim - alpha,
    )


def box_counting_dimension(
    labels: Any, box_sizes: Iterable[int] | None = None
) -> BoxCountingDimension:
    """Box-counting dimension of the boundary between labels.

    Parameters
    ----------
    labels : array_like of int, shape (n_0, ..., n_{D-1}), D >= 1
        Label map, any number of dimensions (boxes are hypercubes).
    box_sizes : iterable of int, optional
        Box sides ``s`` [cells], at least two distinct integers with
        ``1 <= s <= min(labels.shape)``. Default: the powers of 2 from 2 up to
        ``min(labels.shape) // 8``, so that every size has at least 8 boxes along each
        axis; this needs every axis to have at least 32 cells. (Size 1 is allowed but
        left out of the default: at one cell the staircase of cell faces is not yet a
        good stand-in for the boundary, see Notes.)

    Returns
    -------
    BoxCountingDimension
        ``dimension``, the ``box_sizes`` used and the ``counts`` ``N(s)``.

    Raises
    ------
    ValueError
        If ``labels`` is empty or not integer-valued, if ``box_sizes`` holds fewer than
        two distinct sizes or a size outside ``[1, min(labels.shape)]``, or if the
        default sizes do not fit (an axis shorter than 32 cells).

    Notes
    -----
    The boundary of a label map is the set of faces between adjacent cells (along an
    axis, no diagonals) whose labels differ. For each ``s`` the grid is covered with
    non-overlapping boxes of ``s`` cells along every axis, starting at index 0
    (incomplete boxes at the high-index edges are dropped), and ``N(s)`` counts the
    boxes that hold part of the boundary, each face belonging to the box of its
    lower-index cell: a box is counted when it holds more than one label *or* a cell
    whose label differs from that of its neighbour across the box's upper faces. These
    boxes tile the boundary without gaps or overlaps (they are the boxes of side ``s``
    containing the centres of the boundary faces, offset by half a cell). Counting
    only boxes that hold two labels inside would miss the boundary wherever it runs
    along box faces: a straight boundary on a box face would not be seen at all, and
    tilted lines and circles on a 512 x 512 grid would give dimensions of 0.82 to 0.90
    instead of 1 (the inner ``s - 1`` cells of a box's ``s`` catch the boundary).

    For a boundary of box-counting dimension ``d``, ``N(s) ~ s**(-d)`` (Falconer 2014,
    ch. 3); ``dimension`` is minus the least-squares slope of ``log N`` against
    ``log s`` over the sizes with ``N(s) > 0`` (``nan`` if fewer than two, e.g. a
    single-label map). It is ``D - 1`` for a smooth boundary and, by McDonald et al.
    (1985), ``D - alpha`` with ``alpha`` from `uncertainty_exponent`. Sizes with
    ``N(s) = 0`` are reported but left out of the fit.

    On a finite grid two effects bias the fit for a smooth curve of length ``L``
    (summed as ``|dx| + |dy|``), whose continuum count is ``L / s + O(1)``: at the
    largest sizes the curve spans few boxes, so one box more or less matters; and the
    boundary is known only at cell faces about one cell apart, which miss the boxes
    the curve clips by less than a cell, ``N(s) ~ (L / s)(1 - c / s)`` with
    ``0 <= c <= 1/2`` depending on the orientation, which lowers the fitted dimension
    by up to about 0.07 when the smallest size is 2. Over random straight lines and
    circles on grids of 301 to 1024 cells per axis the default sizes give 0.93 to
    1.06 (mean 0.98 to 1.00). Exactly self-similar maps aligned with the boxes, such
    as a Cantor set on ``3**k`` cells with ``box_sizes`` powers of 3, are exact.

    References
    ----------
    .. [1] K. Falconer, *Fractal Geometry: Mathematical Foundations and
       Applications*, 3rd ed., Wiley (2014), sections 2.1 and 3.1.
    .. [2] S. W. McDonald, C. Grebogi, E. Ott, J. A. Yorke, "Fractal basin
       boundaries", Physica D 17, 125-153 (1985).

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps.metrics import box_counting_dimension
    >>> i = np.arange(256)
    >>> half_plane = np.broadcast_to(i[:, None] >= 64, (256, 256))
    >>> result = box_counting_dimension(half_plane)
    >>> result.box_sizes, result.counts, round(result.dimension, 12)
    ((2, 4, 8, 16, 32), (128, 64, 32, 16, 8), 1.0)
    """
    array = _check_labels(labels)
    shape = array.shape
    smallest = min(shape)
    accepted = (
        f"integers s with 1 <= s <= min(labels.shape) = {smallest} "
        f"(labels.shape = {shape})"
    )
    if box_sizes is None:
        top = smallest // 8
        sizes = [2**k for k in range(1, top.bit_length())] if top >= 2 else []
        if len(sizes) < 2:
            raise ValueError(
                f"labels of shape {shape} is too small for the default box_sizes (powers "
                f"of 2 from 2 up to min(labels.shape) // 8 = {top}, at least two needed); "
                f"pass box_sizes explicitly, as {accepted}, or use at least 32 cells per "
                "axis"
            )
    else:
        sizes = _check_sizes("box_sizes", box_sizes, 1, smallest, accepted)
    # cell c is marked when its label differs from that of its forward neighbour
    # c + e_k along some axis k: each edge between adjacent cells belongs to the box
    # of its lower cell, so the boxes tile the boundary without gaps or overlaps
    changes = np.zeros(shape, dtype=bool)
    for axis in range(array.ndim):
        lower = [slice(None)] * array.ndim
        upper = [slice(None)] * array.ndim
        lower[axis] = slice(0, -1)
        upper[axis] = slice(1, None)
        changes[tuple(lower)] |= array[tuple(lower)] != array[tuple(upper)]
    box_axes = tuple(range(1, 2 * array.ndim, 2))
    counts = [int(np.count_nonzero(_boxes(changes, size).any(axis=box_axes))) for size in sizes]
    slope = _fit_slope(sizes, counts)
    return BoxCountingDimension(
        dimension=-slope,
        box_sizes=tuple(sizes),
        counts=tuple(counts),
    )


# ------------------------------------------------------------ fractality test (Puy 2021)


@dataclass(frozen=True)
class FractalityTest:
    """Result of `fractality_test`.

    Attributes
    ----------
    fractal : bool
        The verdict: ``sbb`` lies outside the smooth-boundary interval
        ``[smooth_low - sigmas * sbb_error, smooth_high + sigmas * sbb_error]``.
    sbb : float
        Mean Gibbs entropy [nats] of the sampled boundary balls (balls holding more
        than one label).
    sbb_error : float
        Standard error of ``sbb``: the sample standard deviation of the balls'
        entropies over ``sqrt(n_balls)``.
    smooth_sbb : float
        ``sbb`` of a smooth boundary between two basins in the continuum limit (a flat
        boundary through a D-ball at a uniform distance from its centre): 1/2 for
        D = 1, 0.43951 for D = 2, 0.39609 for D = 3.
    smooth_low, smooth_high : float
        The smooth interval's ends: the smallest and largest ``sbb`` of a flat boundary
        between two basins seen through the ball of cells actually used (``radius``),
        over the boundary's directions (uniform offsets, cells labelled by the side of
        their centres), and ``smooth_sbb``: the continuum value with the grid's
        discretisation bias, which depends on the direction (at radius 8, 0.434 along
        an axis to 0.457 at 22 degrees).
    radius : int
        Ball radius [cells].
    n_balls : int
        Boundary balls averaged.
    n_draws : int
        Balls drawn to find them (the others held one label).
    sigmas : float
        Width of the smooth interval in standard errors.
    multi_label_balls : int
        Of the ``n_balls`` boundary balls, those holding three labels or more: the
        smooth reference is a cut between two, so where many balls hold more (basins
        narrower than the ball, or several meeting), ``sbb`` rises above it whatever
        the boundary (a smooth one reads fractal at too large a radius).
    """

    fractal: bool
    sbb: float
    sbb_error: float
    smooth_sbb: float
    smooth_low: float
    smooth_high: float
    radius: int
    n_balls: int
    n_draws: int
    sigmas: float
    multi_label_balls: int = 0


def _entropy_of_rows(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gibbs entropy [nats] of the labels of each row of ``cells``, and the number of
    labels each row holds."""
    rows, n = cells.shape
    cells = np.sort(cells, axis=1)
    starts_run = np.ones(cells.shape, dtype=bool)
    starts_run[:, 1:] = cells[:, 1:] != cells[:, :-1]
    starts = np.flatnonzero(starts_run)
    p = np.diff(np.append(starts, cells.size)) / n
    return (np.bincount(starts // n, weights=-p * np.log(p), minlength=rows),
            starts_run.sum(axis=1))


def _binary_entropy(p: np.ndarray) -> np.ndarray:
    p = np.clip(p, 1e-300, 1.0)
    q = np.clip(1.0 - p, 1e-300, 1.0)
    return -p * np.log(p) - q * np.log(q)


def smooth_boundary_entropy(ndim: int) -> float:
    """``Sbb`` of a smooth boundary between two basins seen through small D-balls.

    A flat boundary cuts a unit D-ball at a distance ``d`` from its centre, uniform in
    ``[0, 1]`` over the balls it meets, leaving the fraction ``p(d)`` of the volume (a
    cap) on one side; the value is the mean of ``-p log p - (1 - p) log(1 - p)`` over
    ``d``: 1/2 for D = 1, 0.43951 for D = 2, 0.39609 for D = 3, 0.36319 for D = 4
    (Puy et al. 2021, the reference values of Attractors.jl's ``basins_fractal_test``).

    Parameters
    ----------
    ndim : int
        Dimension D >= 1 of the map.

    Returns
    -------
    float
        The reference ``Sbb`` [nats].
    """
    ndim = _check_int("ndim", ndim, 1, None, "an integer >= 1")
    # the cap beyond d holds int_d^1 (1 - t^2)^((D - 1)/2) dt of the ball's half
    # int_0^1 (same); Gauss-Legendre on [0, 1] gets the values above to 1e-10 or better
    nodes, weights = np.polynomial.legendre.leggauss(200)
    t = 0.5 * (nodes + 1.0)
    w = 0.5 * weights

    def section(x):
        return (1.0 - x * x) ** ((ndim - 1) / 2.0)

    half = float(np.sum(w * section(t)))
    # cap(d) = (1 - d) * mean over s in [d, 1] of section(s)
    d = t
    caps = (1.0 - d) * (section(d[:, None] + (1.0 - d[:, None]) * t[None, :]) @ w)
    p = 0.5 * caps / half
    return float(np.sum(w * _binary_entropy(p)))


def _ball_offsets(radius: int, ndim: int) -> np.ndarray:
    """Integer offsets of the cells within ``radius`` of a cell's centre, (K, ndim)."""
    axis = np.arange(-radius, radius + 1)
    grid = np.stack(np.meshgrid(*([axis] * ndim), indexing="ij"), axis=-1).reshape(-1, ndim)
    return grid[np.sum(grid**2, axis=1) <= radius**2]


def _smooth_entropy_on_cells(offsets: np.ndarray) -> np.ndarray:
    """Mean two-label entropy of the ball of cells ``offsets`` cut by a flat boundary at
    a uniform offset (over the offsets where it meets the ball), per direction of the
    boundary's normal: 720 evenly spaced angles in 2-D, 512 fixed random directions in
    more, the one direction in 1-D."""
    ndim = offsets.shape[1]
    if ndim == 1:
        directions = np.ones((1, 1))
    elif ndim == 2:
        angle = (np.arange(720) + 0.5) * np.pi / 720
        directions = np.column_stack([np.cos(angle), np.sin(angle)])
    else:
        directions = np.random.default_rng(0).normal(size=(512, ndim))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    k = offsets.shape[0]
    q = np.sort(offsets @ directions.T, axis=0)  # (k, directions)
    # the boundary at s in [q_j, q_{j+1}) leaves k - j - 1 cells beyond it
    h = _binary_entropy((k - 1 - np.arange(k - 1)) / k)
    return (h @ np.diff(q, axis=0)) / (q[-1] - q[0])


def fractality_test(
    labels: Any,
    radius: int = 20,
    n_balls: int = 1000,
    rng: np.random.Generator | int | None = None,
    sigmas: float = 2.0,
) -> FractalityTest:
    """Whether a map's basin boundary is fractal at the scale ``radius``, by the
    boundary basin entropy of random balls (Puy et al. 2021), whose smooth reference is
    a boundary between two basins (``multi_label_balls`` counts the balls holding more).

    Parameters
    ----------
    labels : array_like of int, shape (n_0, ..., n_{D-1}), D >= 1
        Label map, any number of dimensions, with at least two labels.
    radius : int, default 20
        Ball radius [cells], ``1 <= radius`` and ``2 radius + 1 <= min(labels.shape)``.
        The verdict is about this scale: a smooth boundary can look fractal through
        balls as large as its curvature radius, and a fractal one smooth when the grid
        does not resolve its structure (Puy et al. suggest at least 50 radii per axis).
    n_balls : int, default 1000
        Boundary balls to average, >= 100.
    rng : numpy.random.Generator or int, optional
        Generator or seed of the balls' centres; ``None`` draws from fresh OS entropy.
    sigmas : float, default 2.0
        Width, in standard errors of ``sbb``, of the interval around the smooth
        reference values inside which the boundary is called smooth; > 0.

    Returns
    -------
    FractalityTest
        The verdict ``fractal``, ``sbb``, ``sbb_error``, the smooth references and the
        counts.

    Raises
    ------
    ValueError
        If ``labels`` is empty, not integer-valued or holds a single label, if
        ``radius``, ``n_balls``, ``rng`` or ``sigmas`` is out of range, or if fewer
        than ``n_balls`` boundary balls turn up in ``1000 n_balls`` draws (a boundary
        too small to test at this radius).

    Notes
    -----
    Balls of ``radius`` cells (the cells whose centres are within ``radius`` of the
    ball's centre cell) are centred on cells drawn uniformly among those whose ball
    fits in the map; those holding more than one label are the boundary balls, and
    ``sbb`` is the mean of their Gibbs entropies ``-sum_j p_j log p_j``. Through balls
    small against its curvature a smooth boundary between two basins is a flat cut at
    a uniform distance from the centre, which fixes ``sbb`` for every system
    (`smooth_boundary_entropy`); a fractal boundary leaves a different share of each
    basin in the ball (more mixing: larger; thin filaments: smaller), so ``sbb``
    differs. On a grid the flat cut's value depends on the cut's direction (the
    discretisation bias, 0.434 to 0.457 at radius 8 against 0.4395 in the continuum);
    the boundary is called smooth when ``sbb`` lies within ``sigmas`` standard errors
    of the interval spanned by the continuum value and the flat cuts of the actual
    ball of cells in every direction (``smooth_low`` to ``smooth_high``), and fractal
    otherwise.

    What differs from the published test, as implemented in Attractors.jl's
    ``basins_fractal_test`` (which cites Puy et al.; the paper's own text was not
    available when this was written, and its reference values are those of that
    implementation, reproduced here by `smooth_boundary_entropy`): there the centres
    are continuous and the smooth interval is ``[S - e, S + e + 0.224 radius**-1.006]``
    with ``S`` the continuum value, ``e`` one standard error and the last term a
    fitted upper bound of the grid's bias. Here the centres are cells, the grid's bias
    is computed exactly for this ball of cells and every direction (from radius 3
    on, its largest value lies below that bound), and the interval is ``sigmas = 2``
    standard errors wide by default, so that a smooth boundary is called fractal about
    5 % of the time rather than about 16 %. Boundaries between three or more basins
    meeting at points, and curved smooth boundaries at a radius near their curvature
    radius, shift ``sbb`` a little; bands of basins narrower than the ball shift it a
    lot (a ball holding three labels has up to log 3 = 1.1 nats: the damped pendulum's
    wells, smooth, read fractal at 10 radii per axis, where most boundary balls hold
    three wells; ``multi_label_balls`` counts such balls). Choose ``radius`` well below
    the features of the map (at least about 40 radii per axis).

    References
    ----------
    .. [1] A. Puy, A. Daza, A. Wagemakers, M. A. F. Sanjuán, "A test for fractal
       boundaries based on the basin entropy", Commun. Nonlinear Sci. Numer. Simul. 95,
       105588 (2021), doi:10.1016/j.cnsns.2020.105588.
    .. [2] A. Daza et al., Sci. Rep. 6, 31416 (2016) (the basin entropy).

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps.metrics import fractality_test
    >>> i, j = np.indices((400, 400))
    >>> disk = (i - 200) ** 2 + (j - 200) ** 2 < 150 ** 2
    >>> fractality_test(disk, radius=8, rng=0).fractal
    False
    """
    array = _check_labels(labels)
    smallest = min(array.shape)
    radius = _check_int("radius", radius, 1, max(1, (smallest - 1) // 2),
                        f"an integer from 1 to (min(labels.shape) - 1) // 2 = "
                        f"{(smallest - 1) // 2} (labels.shape = {array.shape}), so that a "
                        "ball of 2 radius + 1 cells fits")
    if 2 * radius + 1 > smallest:
        raise ValueError(f"labels of shape {array.shape} is too small for any ball: an "
                         f"axis needs at least 3 cells; got radius={radius!r}")
    n_balls = _check_int("n_balls", n_balls, 100, None, "an integer >= 100")
    generator = _check_rng(rng)
    if isinstance(sigmas, (bool, np.bool_)) or not isinstance(sigmas, numbers.Real) \
            or not math.isfinite(sigmas) or sigmas <= 0:
        raise ValueError(f"sigmas must be a finite number > 0 (standard errors), got "
                         f"{sigmas!r}")
    if np.unique(array).size < 2:
        raise ValueError(f"labels holds a single label ({array.flat[0]!r}): there is no "
                         "boundary to test; accepted: a map with at least two labels")
    offsets = _ball_offsets(radius, array.ndim)
    flat_offsets = np.ravel_multi_index(tuple((offsets + radius).T),
                                        array.shape) - np.ravel_multi_index(
                                            (radius,) * array.ndim, array.shape)
    flat = array.ravel()
    batch = max(n_balls, 2_000_000 // offsets.shape[0])
    found, draws = [], 0
    count = multi = 0
    limit = 1000 * n_balls
    while count < n_balls and draws < limit:
        size = min(batch, limit - draws)
        centres = np.stack([generator.integers(radius, n - radius, size)
                            for n in array.shape])
        entropy, held = _entropy_of_rows(flat[np.ravel_multi_index(centres, array.shape)[:, None]
                                        + flat_offsets[None, :]])
        boundary = np.flatnonzero(entropy > 0)
        if count + boundary.size >= n_balls:  # keep the first n_balls, in draw order
            boundary = boundary[:n_balls - count]
            draws += int(boundary[-1]) + 1
        else:
            draws += size
        found.append(entropy[boundary])
        multi += int(np.count_nonzero(held[boundary] > 2))
        count += boundary.size
    if count < n_balls:
        raise ValueError(f"only {count} of {draws} random balls of radius {radius} held "
                         f"more than one label; n_balls={n_balls} boundary balls are "
                         "needed: use a smaller n_balls, a larger radius or a map with more "
                         "boundary")
    values = np.concatenate(found)
    sbb = float(np.mean(values))
    error = float(np.std(values, ddof=1) / math.sqrt(n_balls))
    smooth = smooth_boundary_entropy(array.ndim)
    on_cells = _smooth_entropy_on_cells(offsets)
    low, high = min(smooth, float(on_cells.min())), max(smooth, float(on_cells.max()))
    fractal = bool(sbb < low - sigmas * error or sbb > high + sigmas * error)
    return FractalityTest(fractal=fractal, sbb=sbb, sbb_error=error, smooth_sbb=smooth,
                          smooth_low=low, smooth_high=high, radius=radius,
                          n_balls=n_balls, n_draws=draws, sigmas=float(sigmas),
                          multi_label_balls=multi)
