"""The uncertainty exponent below a grid's scale, by Grebogi, McDonald, Ott and Yorke's
original method: random starts in a box, each paired with a start moved by ``eps``, the
fraction ``f(eps)`` of pairs whose labels differ, and ``alpha`` from the slope of
``log f`` against ``log eps``.

`uncertainty_sampled` takes any labelling callable (a plain function of the starts, so
that maps of known dimension test it exactly, or `scene_labels`' run of a pendulum
scene); `sweep.maps.metrics.uncertainty_exponent` is the same measure on a label array,
at the array's own resolution.

References
----------
.. [1] C. Grebogi, S. W. McDonald, E. Ott, J. A. Yorke, "Final state sensitivity: an
   obstruction to predictability", Phys. Lett. A 99, 415-418 (1983),
   doi:10.1016/0375-9601(83)90945-3.
.. [2] S. W. McDonald, C. Grebogi, E. Ott, J. A. Yorke, "Fractal basin boundaries",
   Physica D 17, 125-153 (1985), doi:10.1016/0167-2789(85)90001-6.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["NAN_LABEL", "SampledUncertainty", "scene_labels", "uncertainty_sampled"]

#: `scene_labels`' label of a NaN label without an unresolved value of its own
#: (`sweep.maps.well`'s uncaptured starts): the smallest int64, no well's index.
NAN_LABEL = int(np.iinfo(np.int64).min)

#: The unresolved label of the maps `scene_labels` knows, by name, before any call.
_KNOWN_UNRESOLVED = {"basins": -1, "period": -1, "motion": -127, "well": NAN_LABEL}

#: The smallest perturbation accepted, as a fraction of the box's side: below it a
#: perturbed start of a box far from 0 may round to the start itself in float64.
MIN_EPS = 1e-12


@dataclass(frozen=True)
class SampledUncertainty:
    """Result of `uncertainty_sampled`.

    Attributes
    ----------
    alpha : float
        Uncertainty exponent: the weighted least-squares slope of ``log f`` against
        ``log eps`` over the levels used; ``nan`` when fewer than 3 levels are used.
    alpha_error : float
        Standard error of ``alpha`` (see `uncertainty_sampled`, Notes); ``nan`` when
        ``alpha`` is.
    dimension : float
        ``2 - alpha``, the box-counting dimension of the boundary in the plane of the
        box (McDonald et al. 1985); its standard error is ``alpha_error``.
    reduced_chi2 : float
        Chi-square of the fit per degree of freedom (levels used - 2): about 1 when
        ``f`` follows a power law within its binomial errors.
    eps : tuple of float
        Perturbation sizes [fraction of the box's side along each axis], increasing.
    f : tuple of float
        Fraction of uncertain pairs at each ``eps``, in ``[0, 1]``.
    f_error : tuple of float
        Binomial standard error of each ``f``, ``sqrt(f (1 - f) / pairs)``.
    uncertain : tuple of int
        Number of pairs whose labels differ, per ``eps``.
    pairs : tuple of int
        Number of pairs drawn per ``eps``.
    used : tuple of bool
        Whether each level entered the fit (``0 < uncertain < pairs``).
    """

    alpha: float
    alpha_error: float
    dimension: float
    reduced_chi2: float
    eps: tuple[float, ...]
    f: tuple[float, ...]
    f_error: tuple[float, ...]
    uncertain: tuple[int, ...]
    pairs: tuple[int, ...]
    used: tuple[bool, ...]

    def to_dataset(self):
        """The table as an ``xarray.Dataset`` along ``eps``, the fit in its attributes."""
        import xarray as xr

        data = {name: ("eps", np.asarray(getattr(self, name)))
                for name in ("f", "f_error", "uncertain", "pairs", "used")}
        ds = xr.Dataset(data, coords={"eps": ("eps", np.asarray(self.eps))})
        ds["eps"].attrs = {"long_name": "perturbation size", "units": "fraction of box side"}
        ds["f"].attrs = {"long_name": "fraction of uncertain pairs", "units": "1"}
        ds.attrs = {"alpha": self.alpha, "alpha_error": self.alpha_error,
                    "dimension": self.dimension, "reduced_chi2": self.reduced_chi2}
        return ds


# ------------------------------------------------------------------------ validators


def _check_box(box: Any) -> np.ndarray:
    accepted = ("((lo0, hi0), (lo1, hi1)): two pairs of finite numbers with lo < hi, "
                "the ranges of the two coordinates of a start")
    try:
        array = np.asarray(box, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"box must be {accepted}, got {box!r}") from None
    if array.shape != (2, 2) or not np.isfinite(array).all() \
            or not (array[:, 0] < array[:, 1]).all():
        raise ValueError(f"box must be {accepted}, got {box!r}")
    return array


def _check_eps(eps: Any) -> np.ndarray:
    accepted = (f"a sequence of at least 3 distinct numbers in [{MIN_EPS:g}, 1] "
                "(fractions of the box's side), e.g. 10.0 ** -np.arange(1, 10)")
    if isinstance(eps, (numbers.Number, str, bytes)):
        raise ValueError(f"eps must be {accepted}, got {eps!r}")
    try:
        items = list(eps)
        if any(isinstance(v, (bool, np.bool_, str, bytes)) for v in items):
            raise TypeError
        values = np.asarray(items, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"eps must be {accepted}, got {eps!r}") from None
    if values.ndim != 1:
        raise ValueError(f"eps must be {accepted}, got {eps!r}")
    array = np.unique(values)
    bad = ~np.isfinite(array) | (array < MIN_EPS) | (array > 1.0)
    if bad.any():
        raise ValueError(f"eps must be {accepted}, got {eps!r} (bad value "
                         f"{array[bad][0].item()!r})")
    if array.size < 3:
        raise ValueError(f"eps must be {accepted}, got {eps!r} ({array.size} distinct, "
                         "but a slope and its standard error need at least 3 levels)")
    return array


def _check_n(n: Any) -> int:
    accepted = "an int >= 2 (random pairs per eps level)"
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, numbers.Integral) or n < 2:
        raise ValueError(f"n must be {accepted}, got {n!r}")
    return int(n)


def _check_seed(seed: Any) -> np.random.Generator:
    accepted = "an int >= 0 or a numpy.random.Generator (for reproducible pairs)"
    if isinstance(seed, np.random.Generator):
        return seed
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral) \
            or seed < 0:
        raise ValueError(f"seed must be {accepted}, got {seed!r}")
    return np.random.default_rng(int(seed))


def _check_labels(labels: Any, m: int) -> np.ndarray:
    accepted = (f"labels_of must return {m} integer labels, one per start (an array of "
                f"shape ({m},), integer or bool dtype, or floats that are whole numbers)")
    array = np.asarray(labels)
    if array.shape != (m,):
        raise ValueError(f"{accepted}; got shape {array.shape}")
    if array.dtype == np.bool_ or np.issubdtype(array.dtype, np.integer):
        return array.astype(np.int64)
    if not np.issubdtype(array.dtype, np.floating):
        raise ValueError(f"{accepted}; got dtype {array.dtype}")
    bad = ~np.isfinite(array) | (array != np.round(array))
    if bad.any():
        raise ValueError(f"{accepted}; got {array[bad][0].item()!r} at index "
                         f"{int(np.flatnonzero(bad)[0])} (give unresolved starts a label "
                         "of their own, e.g. -1, instead of NaN)")
    return array.astype(np.int64)


# --------------------------------------------------------------------------- the fit


def _fit(eps: np.ndarray, uncertain: np.ndarray, pairs: int):
    """Weighted least-squares slope of ``log f`` against ``log eps``, its standard error
    and the reduced chi-square, over the levels with ``0 < uncertain < pairs``."""
    used = (uncertain > 0) & (uncertain < pairs)
    if used.sum() < 3:
        return math.nan, math.nan, math.nan, used
    x = np.log(eps[used])
    k = uncertain[used].astype(np.float64)
    f = k / pairs
    y = np.log(f)
    # var(log f) = var(f) / f**2 = f (1 - f) / pairs / f**2 = (1 - f) / k
    w = k / (1.0 - f)
    xm = np.sum(w * x) / np.sum(w)
    ym = np.sum(w * y) / np.sum(w)
    sxx = np.sum(w * (x - xm) ** 2)
    slope = float(np.sum(w * (x - xm) * (y - ym)) / sxx)
    residual = y - ym - slope * (x - xm)
    reduced_chi2 = float(np.sum(w * residual**2) / (used.sum() - 2))
    error = math.sqrt(max(1.0, reduced_chi2) / sxx)
    return slope, error, reduced_chi2, used


# ------------------------------------------------------------------------ public API


def uncertainty_sampled(
    labels_of: Callable[[np.ndarray], Any],
    box: Any,
    *,
    eps: Any,
    n: int,
    seed: int | np.random.Generator,
) -> SampledUncertainty:
    """Uncertainty exponent ``alpha`` of a 2-D labelling, from random pairs of starts
    ``eps`` apart (Grebogi et al. 1983), for ``eps`` down to 1e-12 of the box.

    Parameters
    ----------
    labels_of : callable
        ``labels_of(starts) -> labels``: ``starts`` an ``(m, 2)`` float64 array, one
        start per row (its two coordinates in the units of ``box``), ``labels`` ``m``
        integer labels (bool, or whole-number floats, are accepted; NaN is not: give
        unresolved starts a label of their own, such as -1, which then counts as an
        outcome like any other). Called once, with every start of every level, so
        labels numbered per call (`sweep.maps.basins` numbers attractors by basin
        size) are comparable. See `scene_labels` for a pendulum scene.
    box : ((lo0, hi0), (lo1, hi1))
        The region the starts are drawn from, uniformly: finite, ``lo < hi``.
    eps : sequence of float
        Perturbation sizes as fractions of the box's side along each axis, at least 3
        distinct values in ``[1e-12, 1]``; decades, e.g. ``10.0 ** -np.arange(1, 10)``.
    n : int
        Random pairs per ``eps`` level, >= 2; ``labels_of`` gets ``2 n len(eps)``
        starts in all.
    seed : int or numpy.random.Generator
        Seed (>= 0) or generator of the random starts and directions.

    Returns
    -------
    SampledUncertainty
        ``alpha``, ``alpha_error``, ``dimension = 2 - alpha``, ``reduced_chi2`` and the
        table (``eps``, ``f``, ``f_error``, ``uncertain``, ``pairs``, ``used``).

    Raises
    ------
    ValueError
        Before ``labels_of`` is called: if ``labels_of`` is not callable, ``box`` not
        two ordered finite ranges, ``eps`` not at least 3 distinct sizes in
        ``[1e-12, 1]``, ``n`` not an int >= 2, or ``seed`` not an int >= 0 or a
        generator. After: if ``labels_of``'s result is not ``m`` integer labels.

    Notes
    -----
    Each level draws its own ``n`` starts ``x``, uniform in the box, and pairs each
    with ``x + eps (s0 cos phi, s1 sin phi)``, ``s0``, ``s1`` the box's sides and
    ``phi`` a direction uniform on the circle (Grebogi et al. perturb along one axis;
    a random direction measures the same exponent, with a prefactor averaged over
    directions, and does not favour an axis). The moved start may lie up to ``eps``
    outside the box. A pair is *uncertain* when its two labels differ, and ``f(eps)``
    is the fraction of uncertain pairs. Near a boundary of box-counting dimension
    ``d`` in the plane the starts within ``eps`` of it make up ``f ~ eps**(2 - d)``,
    so ``alpha = 2 - d``: 1 for a smooth boundary, less for a fractal one (McDonald
    et al. 1985).

    The levels are independent samples, so ``uncertain`` is binomial and ``log f`` has
    variance ``(1 - f) / uncertain`` (delta method). ``alpha`` is the slope of the
    straight line through ``(log eps, log f)`` weighted by the inverse of these
    variances, and ``alpha_error`` is its standard error,
    ``sqrt(max(1, reduced_chi2) / Sxx)`` with ``Sxx`` the weighted sum of squares of
    ``log eps`` about its weighted mean: the binomial error, widened by the scatter
    about the line where that is larger (the power law holds only asymptotically and
    self-similar boundaries add log-periodic wiggles). A level enters the fit only when
    ``0 < uncertain < n``: ``log 0`` is undefined and a level where every pair is
    uncertain has saturated (its variance would be 0). Fewer than 3 such levels give
    ``alpha = nan``, with the table, rather than an error, since the labels have
    been paid for. Keep ``eps`` where ``f`` is well below 1 and where each level has
    tens of uncertain pairs: the delta method needs them.

    References
    ----------
    .. [1] C. Grebogi, S. W. McDonald, E. Ott, J. A. Yorke, Phys. Lett. A 99, 415
       (1983).
    .. [2] S. W. McDonald, C. Grebogi, E. Ott, J. A. Yorke, Physica D 17, 125 (1985).

    Examples
    --------
    >>> import numpy as np
    >>> from sweep.maps import uncertainty_sampled
    >>> disk = lambda p: (p[:, 0] ** 2 + p[:, 1] ** 2 < 0.5).astype(int)
    >>> result = uncertainty_sampled(disk, ((-1, 1), (-1, 1)), eps=[1e-2, 1e-3, 1e-4],
    ...                              n=20000, seed=0)
    >>> abs(result.alpha - 1) < 3 * result.alpha_error
    True
    """
    if not callable(labels_of):
        raise ValueError(f"labels_of must be a callable mapping an (m, 2) array of starts "
                         f"to m integer labels, got {labels_of!r}")
    bounds = _check_box(box)
    levels = _check_eps(eps)
    n = _check_n(n)
    rng = _check_seed(seed)
    side = bounds[:, 1] - bounds[:, 0]
    count = levels.size * n
    starts = bounds[:, 0] + rng.random((count, 2)) * side
    phi = rng.uniform(0.0, 2.0 * np.pi, count)
    step = np.repeat(levels, n)[:, None] * side * np.column_stack([np.cos(phi), np.sin(phi)])
    points = np.concatenate([starts, starts + step])
    labels = _check_labels(labels_of(points), 2 * count)
    differ = (labels[:count] != labels[count:]).reshape(levels.size, n)
    uncertain = differ.sum(axis=1)
    f = uncertain / n
    alpha, error, reduced_chi2, used = _fit(levels, uncertain, n)
    return SampledUncertainty(
        alpha=alpha,
        alpha_error=error,
        dimension=2.0 - alpha,
        reduced_chi2=reduced_chi2,
        eps=tuple(float(v) for v in levels),
        f=tuple(float(v) for v in f),
        f_error=tuple(float(v) for v in np.sqrt(f * (1.0 - f) / n)),
        uncertain=tuple(int(v) for v in uncertain),
        pairs=(n,) * levels.size,
        used=tuple(bool(v) for v in used),
    )


def scene_labels(scene, label: Callable | None = None, *, axes=("theta0", "omega0"),
                 held: dict | None = None,
                 **run_kwargs) -> Callable[[np.ndarray], np.ndarray]:
    """A ``labels_of`` for `uncertainty_sampled`: run ``scene`` from the starts, label.

    Parameters
    ----------
    scene : sweep.Scene
        The pendulum scene.
    label : callable, default `sweep.maps.basins`
        ``label(ds) -> DataArray`` of one label per start (``sweep.maps.basins``,
        ``well``, ``motion``, ``period`` or a function of the dataset); NaN labels
        (``well``'s uncaptured starts) become the label's own unresolved value where
        it has one (an ``unresolved`` attribute or flag), else `NAN_LABEL` (not -1:
        a well of ``well`` is -1).
    axes : pair of str, default ("theta0", "omega0")
        The `sweep.Points` columns the two coordinates of a start set (a box's
        ``(lo0, hi0)`` is the range of ``axes[0]``): initial conditions [rad, rad/s]
        or any other parameter `sweep.Points` accepts.
    held : dict of str to float, optional
        Other `sweep.Points` columns, one value for every start (an explorer view's
        start: ``{"omega0": 0.5}`` beside ``axes=("theta0", "damping")``).
    **run_kwargs
        `sweep.run`'s keywords (``t_end`` and ``dt`` at least; ``progress`` defaults to
        False). For a forced scene pass ``observe=("strobe",)``, and for speed
        ``stop_early=True`` with ``attractors=sweep.maps.pilot_catalogue(...)``.

    Returns
    -------
    callable
        ``labels_of(starts)``: one `sweep.run` of ``sweep.Points`` over the rows of
        ``starts``, then ``label``, as an int64 array. Its attribute ``unresolved`` is
        the label of unresolved starts (-1 for ``basins`` and ``period``, -127 for
        ``motion``, `NAN_LABEL` for ``well``; after a call, the labels' own), which
        `describe_boundary` reads.

    Raises
    ------
    ValueError
        If ``scene`` is not a `sweep.Scene`, ``label`` not callable, ``axes`` not two
        distinct names of `sweep.Points` columns, or ``run_kwargs`` not what `sweep.run`
        accepts (checked here, on a start at 0 along both axes, computing nothing;
        each call's run checks its own starts again).

    Notes
    -----
    Labels are comparable within one call (one run): `sweep.maps.basins` numbers the
    attractors of each run by basin size, so two separate calls may number them
    differently. `uncertainty_sampled` labels every start in one call. With a catalogue
    (``attractors=``, e.g. `sweep.maps.pilot_catalogue`) and ``label`` `basins`, a start
    is labelled by the index of the catalogued attractor it settles on (-1: none), so
    separate calls agree (what `sweep.maps.wada` needs).
    """
    from .. import engine
    from ..grid import Points
    from ..physics import parameter_names
    from ..physics.scene import check_pendulum_scene
    from .fractions import _unresolved_code
    from .labels import UNRESOLVED, basins

    check_pendulum_scene("sweep.maps.scene_labels", scene)
    if label is None:
        label = basins
    if not callable(label):
        raise ValueError(f"label must be a callable ds -> DataArray such as "
                         f"sweep.maps.basins, got {label!r}")
    names = parameter_names()
    accepted = f"two distinct names of sweep.Points columns (of {names})"
    try:
        pair = tuple(axes) if not isinstance(axes, str) else ()
    except TypeError:
        pair = ()
    if len(pair) != 2 or len(set(pair)) != 2 or not set(pair) <= set(names):
        raise ValueError(f"axes must be {accepted}, got {axes!r}")
    axes = pair
    held = dict(held or {})
    if set(held) & set(axes) or not set(held) <= set(names):
        raise ValueError(f"held must name sweep.Points columns other than axes {axes} "
                         f"(of {names}), got {sorted(held)}")
    run_kwargs.setdefault("progress", False)
    # every run argument checked now, on one start, as sweep.run checks it (the starts'
    # own values are checked again by each call's run)
    engine.prepare(scene, Points(**{axes[0]: [0.0], axes[1]: [0.0]},
                                 **{k: [v] for k, v in held.items()}), **run_kwargs)

    catalogued = label is basins and run_kwargs.get("attractors") is not None

    def labels_of(starts: np.ndarray) -> np.ndarray:
        starts = np.asarray(starts, dtype=np.float64)
        columns = {k: np.full(len(starts), v, dtype=np.float64) for k, v in held.items()}
        ds = engine.run(scene, Points(**{axes[0]: starts[:, 0], axes[1]: starts[:, 1]},
                                      **columns), **run_kwargs)
        found = ds["attractor"] if catalogued else label(ds)
        own = UNRESOLVED if catalogued else _unresolved_code(found, None)
        if own is not None and np.isfinite(own):
            labels_of.unresolved = int(own)
        values = np.asarray(found, dtype=np.float64).ravel()
        return np.where(np.isfinite(values), values, labels_of.unresolved).astype(np.int64)

    labels_of.unresolved = UNRESOLVED if catalogued else _KNOWN_UNRESOLVED.get(
        getattr(label, "__name__", None), NAN_LABEL)
    return labels_of
