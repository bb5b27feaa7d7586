"""Everything "Is my map right?" measures about one 2-D label map, in one call: the
basin fractions, the basin entropy, the fractality test, the uncertainty exponent at the
grid's scale and, on request, below it (`uncertainty_sampled`) and the Wada test
(`wada`). The command ``sweep boundary`` prints it; the explorer shows it for its view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_count
from .labels import UNRESOLVED
from .metrics import (
    BasinEntropy,
    FractalityTest,
    UncertaintyExponent,
    basin_entropy,
    basin_fractions,
    fractality_test,
    uncertainty_exponent,
)
from .uncertainty import SampledUncertainty, uncertainty_sampled
from .wada import Wada, wada

__all__ = ["BoundaryReport", "RADII_PER_AXIS", "SAMPLED_EPS", "describe_boundary",
           "fractality_radius", "label_grid"]

#: The fractality test's ball: this many radii per axis of the map at least (Puy et
#: al.'s advice; Attractors.jl warns below 50), 3 cells at least, 20 at most.
RADII_PER_AXIS = 40

#: Below this many radii per axis the test is not run: through balls a fifth of the map
#: wide or more every boundary of an 8 x 8 map read "fractal" (a smooth damped
#: pendulum's wells, Sbb 0.25 against the smooth 0.44-0.50); from 101 cells per axis at
#: radius 3 (34 radii) it read smooth (`tests/test_boundary.py`).
MIN_RADII = 10

#: `BoundaryReport.lines` qualifies the fractality verdict when this share of its
#: boundary balls hold three labels or more: each raises Sbb by up to about 0.4 nats
#: (log 3 against the smooth 0.44), so 2 % of them shift it by about one standard
#: error of 1000 balls (0.006-0.009).
MULTI_LABEL_SHARE = 0.02

#: The perturbations of the sampled uncertainty exponent, as fractions of the box's
#: side: eight decades from 1e-9 (far below any grid) to 1e-2.
SAMPLED_EPS = tuple(10.0 ** -k for k in range(9, 1, -1))


@dataclass(frozen=True)
class BoundaryReport:
    """What `describe_boundary` measured on one label map.

    Attributes
    ----------
    shape : tuple of int
        The map's cells (n_x, n_y).
    fractions : dict of int to float
        Each label's share of the cells, the unresolved label's (``unresolved``)
        included.
    entropy : BasinEntropy
        Sb and Sbb [nats] over 5 x 5 boxes, with the log-2 criterion.
    fractality : FractalityTest or None
        Puy et al.'s test with balls of ``max(3, min(20, min(shape) // 40))`` cells
        (`RADII_PER_AXIS`); None where the map has one basin or too little boundary
        for it (``fractality_note`` says why).
    fractality_note : str
    uncertainty : UncertaintyExponent or None
        alpha at the grid's scale (radii of 1, 2, 4, ... cells); None on a map smaller
        than 32 cells along an axis.
    sampled : SampledUncertainty or None
        alpha below the grid's scale (`uncertainty_sampled`), when asked for.
    wada : Wada or None
        The grid method's Wada test (`wada`), when asked for and the map has three basins
        or more.
    """

    shape: tuple[int, int]
    fractions: dict
    entropy: BasinEntropy
    fractality: FractalityTest | None
    fractality_note: str
    uncertainty: UncertaintyExponent | None
    sampled: SampledUncertainty | None = None
    wada: Wada | None = None
    unresolved: int | None = None

    @property
    def basins(self) -> int:
        """The basins of the map: its labels but ``unresolved``."""
        return sum(1 for k in self.fractions if k != self.unresolved)

    def _name(self, label) -> str:
        return "unresolved" if label == self.unresolved else str(label)

    def lines(self) -> list[str]:
        """The report as lines of text (what ``sweep boundary`` prints)."""
        out = [f"map: {self.shape[0]} x {self.shape[1]} cells, {self.basins} basins"]
        out.append("fractions: " + ", ".join(f"{self._name(k)}: {v:.4f}"
                                              for k, v in sorted(self.fractions.items())))
        e = self.entropy
        out.append(f"basin entropy: Sb = {e.sb:.4f}, Sbb = {e.sbb:.4f} nats "
                   f"({e.n_boundary_boxes} of {e.n_boxes} 5x5 boxes on the boundary; "
                   f"Sbb > log 2: {'yes, fractal' if e.fractal_boundary else 'no'})")
        if self.fractality is not None:
            f = self.fractality
            out.append(f"fractality test (radius {f.radius} cells): "
                       f"{'fractal' if f.fractal else 'smooth'} "
                       f"(Sbb {f.sbb:.4f} +- {f.sbb_error:.4f} against smooth "
                       f"{f.smooth_low:.4f}-{f.smooth_high:.4f})")
            if f.multi_label_balls >= MULTI_LABEL_SHARE * f.n_balls:
                out[-1] += (f"; but {f.multi_label_balls} of its {f.n_balls} boundary "
                            "balls hold three labels or more, which the smooth reference "
                            "(two basins cut by a line) does not cover: smooth bands "
                            "narrower than the ball raise Sbb too")
        else:
            out.append(f"fractality test: not computed ({self.fractality_note})")
        if self.uncertainty is not None:
            u = self.uncertainty
            out.append(f"uncertainty exponent at the grid's scale: alpha = {u.alpha:.3f} "
                       f"(radii {', '.join(str(int(r)) for r in u.epsilons)} cells), "
                       f"boundary dimension {u.boundary_dimension:.3f}")
        if self.sampled is not None and not np.isfinite(self.sampled.alpha):
            out.append("uncertainty exponent below the grid's scale: not enough levels "
                       "with uncertain pairs to fit (more pairs per level: --sampled)")
        elif self.sampled is not None:
            s = self.sampled
            out.append(f"uncertainty exponent below the grid's scale: alpha = "
                       f"{s.alpha:.3f} +- {s.alpha_error:.3f} (eps "
                       f"{min(s.eps):.0e} to {max(s.eps):.0e} of the box), boundary "
                       f"dimension {s.dimension:.3f}")
        if self.wada is not None:
            w = self.wada
            shares = ", ".join(f"W{m} = {v:.3f}" for m, v in zip(w.m, w.fractions))
            out.append(f"Wada test (grid method, {w.steps} steps, {w.trajectories} new "
                       f"trajectories): {w.verdict} ({shares})")
        return out

    def to_dict(self) -> dict:
        """The numbers as plain JSON-able values."""
        e = self.entropy
        out = {"shape": list(self.shape),
               "basins": self.basins,
               "fractions": {self._name(k): float(v) for k, v in self.fractions.items()},
               "sb": e.sb, "sbb": e.sbb, "log2_criterion": bool(e.fractal_boundary)}
        if self.fractality is not None:
            f = self.fractality
            out["fractality"] = {"fractal": bool(f.fractal), "sbb": f.sbb,
                                 "sbb_error": f.sbb_error, "smooth_low": f.smooth_low,
                                 "smooth_high": f.smooth_high, "radius": int(f.radius),
                                 "multi_label_balls": int(f.multi_label_balls)}
        if self.uncertainty is not None:
            out["alpha_grid"] = float(self.uncertainty.alpha)
        if self.sampled is not None:
            s = self.sampled
            out["alpha_sampled"] = {"alpha": s.alpha, "alpha_error": s.alpha_error,
                                    "dimension": s.dimension,
                                    "eps": [float(v) for v in s.eps],
                                    "f": [float(v) for v in s.f]}
        if self.wada is not None:
            w = self.wada
            out["wada"] = {"verdict": w.verdict, "steps": int(w.steps),
                           "trajectories": int(w.trajectories),
                           "W": {str(int(m)): float(v) for m, v in zip(w.m, w.fractions)}}
        return out


def label_grid(labels_of, x, y) -> np.ndarray:
    """The map ``labels_of`` gives on the grid ``x`` x ``y``, in one call.

    Parameters
    ----------
    labels_of : callable
        ``(m, 2) starts -> m int labels``.
    x, y : array_like of float, shapes (n_x,), (n_y,)

    Returns
    -------
    numpy.ndarray of int, shape (n_x, n_y)
        ``labels[i, j]``: the label of the start ``(x[i], y[j])``.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    starts = np.stack(np.meshgrid(x, y, indexing="ij"), axis=-1).reshape(-1, 2)
    return np.asarray(labels_of(starts)).reshape(x.size, y.size)


def fractality_radius(shape) -> tuple[int, bool]:
    """The fractality test's ball for a map of ``shape`` cells: its radius [cells], a
    `RADII_PER_AXIS`-th of the shorter side (3 to 20), and whether the map is too small
    for the test (fewer than `MIN_RADII` radii a side), as `describe_boundary` and the
    explorer's numbers take them."""
    side = min(shape)
    radius = max(3, min(20, side // RADII_PER_AXIS))
    return radius, side < MIN_RADII * radius


def describe_boundary(labels, x, y, labels_of=None, *, sampled: int = 0,
                      wada_steps: int = 0, seed: int = 0,
                      unresolved: int | None = None) -> BoundaryReport:
    """Measure a 2-D label map's boundary: fractions, basin entropy, fractality, the
    uncertainty exponent, and on request the sampled exponent and the Wada test.

    Parameters
    ----------
    labels : array_like of int, shape (n_x, n_y)
        The map, ``labels[i, j]`` the label of the start ``(x[i], y[j])``; every label
        is a basin but ``unresolved``.
    x, y : array_like of float, shapes (n_x,), (n_y,)
        The grid's coordinates along each axis (increasing).
    labels_of : callable, optional
        ``(m, 2) starts -> m int labels``, numbering the basins as ``labels`` does (for
        a pendulum `sweep.maps.scene_labels`): needed by ``sampled`` and ``wada_steps``.
    sampled : int, default 0
        Pairs per eps level of `uncertainty_sampled` over the map's box (eps
        `SAMPLED_EPS`); 0: not computed.
    wada_steps : int, default 0
        Refinement steps of the Wada test; 0: not computed (nor on a map of fewer than
        three basins).
    seed : int, default 0
        Seed of every random draw (the fractality test's balls, the sampled pairs).
    unresolved : int, optional
        The label of unresolved or failed starts (not a basin), the map's own: -1 for
        `sweep.maps.basins` and ``period``, -127 for ``motion``, ``NAN_LABEL`` for
        `well`'s NaN. Default: ``labels_of.unresolved`` (`sweep.maps.scene_labels`
        says it), else -1 (`sweep.maps.UNRESOLVED`).

    Returns
    -------
    BoundaryReport

    Raises
    ------
    ValueError
        A map that is not 2-D integer labels matching ``x`` and ``y``, a negative
        ``sampled``, ``wada_steps`` or ``seed``, or ``sampled``/``wada_steps`` without a
        ``labels_of``; all before anything is computed.
    """
    labels = np.asarray(labels)
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if labels.ndim != 2 or labels.dtype.kind not in "iu":
        raise ValueError(f"labels must be a 2-D integer array, got shape {labels.shape} "
                         f"and dtype {labels.dtype}; accepted: integer labels, one per cell")
    if x.shape != (labels.shape[0],) or y.shape != (labels.shape[1],):
        raise ValueError(f"x and y must have the map's shape {labels.shape}, got "
                         f"{x.shape} and {y.shape}; accepted: one coordinate per row and "
                         "per column")
    sampled = check_count("sampled", sampled, minimum=0,
                          accepted="an int >= 0 (pairs per eps level; 0: none)")
    wada_steps = check_count("wada_steps", wada_steps, minimum=0,
                             accepted="an int >= 0 (refinement steps; 0: none)")
    seed = check_count("seed", seed, minimum=0, accepted="an int >= 0")
    if (sampled or wada_steps) and labels_of is None:
        raise ValueError("sampled and wada_steps compute new trajectories and need "
                         "labels_of; accepted: a labels_of callable, or sampled=0 and "
                         "wada_steps=0")
    if sampled and sampled < 100:
        raise ValueError(f"sampled must be 0 or >= 100 pairs per eps level, got "
                         f"{sampled!r}; accepted: 0 or an int >= 100")
    if unresolved is None:
        unresolved = getattr(labels_of, "unresolved", UNRESOLVED)
    fractions = basin_fractions(labels)
    basins = sum(1 for k in fractions if k != unresolved)
    entropy = basin_entropy(labels, box_size=min(5, *labels.shape))
    fractality, note = None, ""
    radius, too_small = fractality_radius(labels.shape)
    if basins < 2:
        note = "one basin"
    elif too_small:
        note = (f"the map is too small for it: {min(labels.shape)} cells on its shorter "
                f"axis, fewer than {MIN_RADII} radii of the smallest ball ({radius} cells); "
                f"a finer grid ({MIN_RADII * radius} cells per axis or more) would allow it")
    else:
        try:
            fractality = fractality_test(labels, radius=radius, n_balls=1000, rng=seed)
        except ValueError as error:  # too little boundary at this radius
            note = str(error)
    uncertainty = uncertainty_exponent(labels) if min(labels.shape) >= 32 else None
    found = None
    if sampled:
        box = ((float(x[0]), float(x[-1])), (float(y[0]), float(y[-1])))
        found = uncertainty_sampled(labels_of, box, eps=SAMPLED_EPS, n=sampled, seed=seed)
    tested = None
    if wada_steps and basins >= 3:
        if any(k < 0 for k in fractions if k != unresolved) or unresolved != UNRESOLVED:
            tested = wada(_wada_codes(labels, unresolved),
                          lambda starts: _wada_codes(np.asarray(labels_of(starts)),
                                                     unresolved),
                          x, y, max_steps=wada_steps)
        else:
            tested = wada(labels, labels_of, x, y, max_steps=wada_steps)
    return BoundaryReport(shape=tuple(int(n) for n in labels.shape), fractions=fractions,
                          entropy=entropy, fractality=fractality, fractality_note=note,
                          uncertainty=uncertainty, sampled=found, wada=tested,
                          unresolved=int(unresolved))


def _wada_codes(labels: np.ndarray, unresolved: int) -> np.ndarray:
    """Labels as `wada` reads them: ``unresolved`` -1, every other label a code >= 0,
    one per label (k >= 0: 2 k, k < 0: -2 k - 1), the same in every call."""
    labels = np.asarray(labels, dtype=np.int64)
    codes = np.where(labels >= 0, 2 * labels, -2 * labels - 1)
    return np.where(labels == unresolved, -1, codes)
