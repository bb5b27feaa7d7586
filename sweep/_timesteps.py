"""Whole numbers of fixed steps: a time span ``t_end - t0`` divided into steps ``dt``,
and the first step of the steady window after ``t_transient``. Pure arithmetic, shared
by the engine and the maps."""

from __future__ import annotations

import math

__all__ = ["WHOLE_STEPS_RTOL", "transient_steps", "whole_steps"]

# A time span must be a whole number of steps to within this relative slack:
# (t_end - t0) / dt is computed in floating point, so 300 / 0.01 = 30000.000000000004.
WHOLE_STEPS_RTOL = 1e-9


def whole_steps(name: str, span: float, dt: float) -> int:
    """Number of steps ``dt`` in ``span``; ValueError (suggesting a dt) unless whole."""
    exact = span / dt
    n = round(exact)
    if abs(exact - n) > WHOLE_STEPS_RTOL * max(1.0, exact):
        suggestion = span / max(n, 1)
        raise ValueError(
            f"{name} = {span!r} is not a whole number of steps dt = {dt!r} "
            f"({exact:.6g} steps); accepted: a dt that divides it, e.g. dt = {suggestion!r}"
        )
    return n


def transient_steps(t_transient: float, dt: float) -> int:
    """First step index n whose time ``t0 + n dt`` is >= ``t0 + t_transient`` (a
    transient meant to end on a step counts as ending there, despite rounding)."""
    return math.ceil(t_transient / dt - WHOLE_STEPS_RTOL * max(1.0, t_transient / dt))
