"""The words of a discrete map: each label's meaning for the legend and the hover text, and
what a basins or period map found, for the status line."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MOTION_TEXT", "label_summary", "legend_of"]


MOTION_TEXT = {-1: "rotation, negative sense", 0: "libration", 1: "rotation, positive sense",
                -127: "unresolved (failed)"}


def legend_of(quantity: str, da, values: np.ndarray) -> tuple[list, np.ndarray]:
    """``(legend, image)`` of a discrete map: the distinct values present (NaN as its own
    entry) and each pixel's index into them."""
    v = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(v)
    found = np.unique(v[finite])
    image = np.full(v.shape, np.nan)
    image[finite] = np.searchsorted(found, v[finite])
    legend = [(float(value), _meaning(quantity, da, float(value))) for value in found]
    if not finite.all():
        nan_text = {"well": "not captured by t_end (or failed)"}.get(quantity, "none")
        image[~finite] = len(legend)
        legend.append((math.nan, nan_text))
    return legend, image


def _meaning(quantity: str, da, value: float) -> str:
    k = int(value)
    if quantity == "well":
        return f"well {k} (rest at theta = {k} x 2 pi)"
    if quantity == "motion":
        return MOTION_TEXT.get(k, str(k))
    if quantity == "period":
        return "no period found" if k < 0 else f"period {k}"
    if quantity == "inverted":
        return "stays up" if k else "falls"
    if quantity == "synchronized":  # a swing network (sweep.explore.networks)
        return {1: "back in the synchronous state", 0: "not synchronous"}.get(k, "failed")
    if quantity == "basins":
        if k < 0:
            return "unresolved"
        a = da.attrs
        try:
            period = int(np.atleast_1d(a["attractor_period"])[k])
            if "attractor_turns_per_period" in a:  # the pendulum
                turns = float(np.atleast_1d(a["attractor_turns_per_period"])[k])
                return f"attractor {k}: period {period}, {turns:+g} turns/period"
            # a system: turns per period of each angle (sweep.maps.basins' attributes)
            prefix = "attractor_turns_per_period_"
            turns = ", ".join(f"{key[len(prefix):]} {float(np.atleast_1d(a[key])[k]):+g}"
                              for key in a if key.startswith(prefix))
            return f"attractor {k}: period {period}" + \
                (f", turns/period {turns}" if turns else "")
        except (KeyError, IndexError):
            return f"attractor {k}"
    return f"{k}"


def label_summary(quantity: str, values: np.ndarray) -> str:
    """What a basins or period map's labels found, in words, for the status line:
    ``"3 attractors; 12 of 4096 starts unresolved (-1: not settled by t_end, chaotic, a
    period over max_period, or failed)"``; "" for other maps.

    Parameters
    ----------
    quantity : str
        ``"basins"`` or ``"period"`` (others give "").
    values : ndarray
        The map's labels (`sweep.maps.basins`: attractor labels, -1 unresolved;
        `sweep.maps.period`: periods in drive periods, -1 none found).
    """
    if quantity not in ("basins", "period"):
        return ""
    v = np.asarray(values)
    found = np.unique(v[v >= 0]).astype(np.int64)
    missing = int(np.count_nonzero(v < 0))
    if quantity == "basins":
        text = f"{found.size} attractor{'s' if found.size != 1 else ''}"
        why = "not settled by t_end, chaotic, a period over max_period, or failed"
        name = "unresolved"
    else:
        text = (f"periods {', '.join(str(int(p)) for p in found)}" if found.size else
                "no period")
        why = "not settled by t_end, chaotic, quasi-periodic, a longer period, or failed"
        name = "without a period"
    if missing:
        text += f"; {missing} of {v.size} starts {name} ({why})"
    return text
