"""The numbers of the explorer's current view: what share of the window each label takes
(with its standard error) and how mixed the labels are (basin entropy Sb, boundary basin
entropy Sbb and the log-2 fractality verdict of `sweep.maps.metrics.basin_entropy`),
computed on the labels the page shows; and, on request, slower numbers registered by
name (`ON_REQUEST`, `register_on_request`).

Plain Python (no Panel, no Bokeh): the page (`sweep.explore.app`) shows
`ViewNumbers.markdown` under the map and runs an on-request entry on a worker thread.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..maps.fractions import fractions as label_fractions
from ..maps.metrics import basin_entropy, fractality_test, uncertainty_exponent

__all__ = ["BELOW_GRID_PAIRS", "BELOW_GRID_SIDE", "BELOW_GRID_STEPS", "BOX_SIZE",
           "ON_REQUEST", "ViewNumbers", "register_on_request", "view_labels_of",
           "view_numbers"]

#: Side of the basin-entropy boxes [pixels] (Daza et al. 2016 use 5; Sb and Sbb depend
#: on it, so the page says which).
BOX_SIZE = 5


@dataclass(frozen=True)
class ViewNumbers:
    """The numbers of one final map of the explorer.

    Attributes
    ----------
    meanings : tuple of str
        Each label shown (the legend's text), in the legend's order (NaN's entry last).
    fractions : tuple of float
        Share of the window's pixels with each label, in [0, 1] (they sum to 1).
    errors : tuple of float
        Binomial standard error of each fraction, ``sqrt(p (1 - p) / n)``: exact for
        ``n`` independent random starts; on a grid of pixels it is what random starts
        would give (a grid near a smooth boundary does better).
    pixels : int
        ``n``, the pixels of the map.
    sb, sbb : float
        Basin entropy and boundary basin entropy [nats] over boxes of `box_size` pixels
        (`sweep.maps.metrics.basin_entropy`; every legend entry a distinct outcome).
    box_size : int
        Side of the boxes [pixels].
    n_boxes, n_boundary_boxes : int
        Boxes used, and those holding more than one label.
    fractal : bool
        ``sbb > log 2``: a *sufficient* condition for a fractal boundary (Daza et al.
        2016); False does not mean smooth (two basins never pass it).
    """

    meanings: tuple[str, ...]
    fractions: tuple[float, ...]
    errors: tuple[float, ...]
    pixels: int
    sb: float
    sbb: float
    box_size: int
    n_boxes: int
    n_boundary_boxes: int
    fractal: bool

    def verdict(self) -> str:
        """The fractality verdict in words."""
        if self.fractal:
            return "fractal boundary (Sbb > log 2)"
        if self.n_boundary_boxes == 0:
            return "no boundary at this box size"
        return ("not decided by Sbb <= log 2 (a sufficient test only: two basins never "
                "pass it)")

    def markdown(self) -> str:
        """A table of the fractions and a line of Sb, Sbb and the verdict."""
        lines = ["| label | share of the view | ± standard error |", "|---|---|---|"]
        for meaning, share, error in zip(self.meanings, self.fractions, self.errors,
                                         strict=True):
            lines.append(f"| {meaning} | {share:.4f} | {error:.4f} |")
        lines += ["", f"**Sb** = {self.sb:.4f}, **Sbb** = {self.sbb:.4f} nats (boxes of "
                  f"{self.box_size} x {self.box_size} pixels, {self.n_boundary_boxes} of "
                  f"{self.n_boxes} on a boundary): {self.verdict()}. Standard errors: "
                  f"binomial, as for {self.pixels} random starts."]
        return "\n".join(lines)


def view_numbers(result: Any, box_size: int = BOX_SIZE) -> ViewNumbers | None:
    """The numbers of a final map (`sweep.explore.model.MapResult`).

    Parameters
    ----------
    result : MapResult
        A discrete map (labels with a legend).
    box_size : int, default `BOX_SIZE`
        Side of the basin-entropy boxes [pixels]; a map smaller than it uses its
        smaller side.

    Returns
    -------
    ViewNumbers or None
        None for a map of continuous values (no labels to count).
    """
    if not result.legend:
        return None
    labels = np.asarray(result.image)
    if not np.isfinite(labels).all():  # every pixel of a discrete map has an entry
        raise ValueError("a discrete map's image indexes its legend at every pixel")
    labels = labels.astype(np.int64)
    table = label_fractions(labels)
    present = [int(v) for v in np.asarray(table["label"].values)]
    share = dict(zip(present, np.asarray(table["fraction"].values, dtype=float), strict=True))
    error = dict(zip(present, np.asarray(table["standard_error"].values, dtype=float),
                     strict=True))
    count = range(len(result.legend))
    entropy = basin_entropy(labels, box_size=max(1, min(box_size, *labels.shape)))
    return ViewNumbers(
        meanings=tuple(text for _, text in result.legend),
        fractions=tuple(float(share.get(k, 0.0)) for k in count),
        errors=tuple(float(error.get(k, 0.0)) for k in count),
        pixels=int(labels.size), sb=entropy.sb, sbb=entropy.sbb,
        box_size=max(1, min(box_size, *labels.shape)), n_boxes=entropy.n_boxes,
        n_boundary_boxes=entropy.n_boundary_boxes, fractal=entropy.fractal_boundary)


def _grid_uncertainty(result: Any, explorer: Any) -> str:
    """The uncertainty exponent of the view's labels at the grid's own scale
    (`sweep.maps.metrics.uncertainty_exponent`: its default radii, powers of 2 pixels
    up to 1/16 of the map's side; a fixed seed, so a view gives one answer)."""
    labels = np.asarray(result.image).astype(np.int64)
    out = uncertainty_exponent(labels, rng=0)
    if not math.isfinite(out.alpha):
        return "uncertainty exponent (grid): too few uncertain pixels to fit a slope"
    table = ", ".join(f"f({e}) = {f:.3g}" for e, f in zip(out.epsilons, out.fractions,
                                                           strict=True))
    return (f"**uncertainty exponent** (grid scale, radii in pixels) alpha = "
            f"{out.alpha:.3f}, boundary dimension {out.boundary_dimension:.3f}; {table}")


def _fractality(result: Any, explorer: Any) -> str:
    """Puy et al.'s fractality test (`sweep.maps.metrics.fractality_test`) of the view's
    labels, through balls of the radius `sweep.maps.describe_boundary` takes (a
    `RADII_PER_AXIS`-th of the map's side, 3 to 20 pixels; not run on a view of fewer
    than `MIN_RADII` radii a side; a fixed seed): unlike Sbb > log 2 it decides with
    two basins too."""
    from ..maps.boundary import MIN_RADII, fractality_radius

    labels = np.asarray(result.image).astype(np.int64)
    side = min(labels.shape)
    radius, too_small = fractality_radius(labels.shape)
    if np.unique(labels).size < 2:
        return "**fractality test**: one label in the view, no boundary"
    if too_small:
        return (f"**fractality test**: the view is too small ({side} pixels a side, "
                f"fewer than {MIN_RADII} radii of the smallest ball, {radius} pixels)")
    out = fractality_test(labels, radius=radius, n_balls=1000, rng=0)
    return (f"**fractality test** (balls of radius {out.radius} pixels): "
            f"{'fractal' if out.fractal else 'smooth'} boundary (Sbb of the balls "
            f"{out.sbb:.4f} ± {out.sbb_error:.4f}; a smooth boundary gives "
            f"{out.smooth_low:.4f} to {out.smooth_high:.4f})")


#: Side [pixels] of the map `_below_grid` labels afresh for the Wada test, and the
#: sampled pairs per eps level of its uncertainty exponent.
BELOW_GRID_SIDE = 64
BELOW_GRID_PAIRS = 500
#: Refinement steps of `_below_grid`'s Wada test (the forced Wada window: W3 = 0.986
#: after 4, enough to call it Wada after 6).
BELOW_GRID_STEPS = 6


def view_labels_of(result: Any, explorer: Any):
    """``labels_of`` for new starts of the view's window: one `sweep.run` of
    `sweep.Points` over the view's two axes (the view's other start values held), then
    the view's map; forced basins are labelled by the explorer's attractor catalogue, so
    that separate calls number the basins alike (`sweep.maps.wada` needs it).

    Raises
    ------
    ValueError
        For a systems explorer (its maps are not labelled per start this way yet).
    """
    from ..maps.uncertainty import scene_labels

    state = result.state
    if not hasattr(explorer, "quantity_info") or not hasattr(explorer, "uses_pilot"):
        raise ValueError("new starts of the view are labelled for a pendulum scene only, "
                         "not for a system yet")
    kwargs = dict(explorer.run_kwargs(state))
    if explorer.uses_pilot(state):
        kwargs["attractors"] = explorer.catalogue(state)
    x, y = state.view.x, state.view.y
    return scene_labels(state.scene, explorer.quantity_info(state.quantity).compute,
                        axes=(x, y),
                        held={k: v for k, v in state.start if k not in (x, y)}, **kwargs)


def _below_grid(result: Any, explorer: Any) -> str:
    """The uncertainty exponent below the grid's scale (`sweep.maps.uncertainty_sampled`:
    `BELOW_GRID_PAIRS` random pairs per eps level, eps 1e-9 to 1e-2 of the window) and
    the Wada test (`sweep.maps.wada`, `BELOW_GRID_STEPS` steps) of a `BELOW_GRID_SIDE`
    x `BELOW_GRID_SIDE` map of the window labelled afresh (`view_labels_of`), by
    `sweep.maps.describe_boundary`: new trajectories, seconds for a forced window."""
    from ..maps.boundary import describe_boundary, label_grid

    labels_of = view_labels_of(result, explorer)
    v = result.state.view
    side = BELOW_GRID_SIDE
    x = np.linspace(*v.x_range, side)
    y = np.linspace(*v.y_range, side)
    labels = label_grid(labels_of, x, y)
    report = describe_boundary(labels, x, y, labels_of, sampled=BELOW_GRID_PAIRS,
                               wada_steps=BELOW_GRID_STEPS, seed=0)
    lines = [line for line in report.lines()
             if line.startswith(("uncertainty exponent below", "Wada test"))]
    if report.wada is None:
        lines.append(f"Wada test: not run ({report.basins} basins in the window; it "
                     "needs three or more)")
    return "\n\n".join([f"**below the grid's scale** (a {side} x {side} map of the "
                         "window labelled afresh):"] + lines)


#: Numbers computed only when asked for (the page's "on request" selector): name ->
#: ``function(result, explorer) -> str`` (Markdown), run on a worker thread with the
#: final map of the view (`sweep.explore.model.MapResult`) and its explorer (whose
#: ``state``, ``grid`` and ``run_kwargs`` give the scene and settings to run more
#: starts). Add entries with `register_on_request`.
ON_REQUEST: dict[str, Callable[[Any, Any], str]] = {
    "uncertainty exponent (grid scale)": _grid_uncertainty,
    "fractality test (Puy et al.)": _fractality,
    "below the grid's scale: sampled exponent, Wada test": _below_grid,
}


def register_on_request(name: str, function: Callable[[Any, Any], str]) -> None:
    """Offer ``function(result, explorer) -> str`` (Markdown) under ``name`` in the
    page's "on request" numbers (for example the sampled uncertainty exponent below the
    grid's scale, or the Wada test, of the visible window); pages opened afterwards list
    it.

    Raises
    ------
    TypeError
        If ``name`` is not a non-empty string or ``function`` is not callable.
    """
    if not isinstance(name, str) or not name.strip():
        raise TypeError(f"name must be a non-empty string, got {name!r}")
    if not callable(function):
        raise TypeError(f"function must be callable as function(result, explorer), got "
                        f"{function!r}")
    ON_REQUEST[name] = function
