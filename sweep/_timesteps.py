"""Whole numbers of fixed steps: a time span ``t_end - t0`` divided into steps ``dt``,
and the first step of the steady window after ``t_transient``. Pure arithmetic, shared
by the engine and the maps."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["WHOLE_STEPS_RTOL", "check_sampling_period", "transient_steps", "whole_steps"]

# A time span must be a whole number of steps to within this relative slack:
# (t_end - t0) / dt is computed in floating point, so 300 / 0.01 = 30000.000000000004.
WHOLE_STEPS_RTOL = 1e-9
# ... and never more than this many steps: from 1e9 steps on the relative slack would
# reach a whole step (a span 1 step off accepted, a transient ending a step early),
# while the rounding of span / dt stays far below it (2e-16 relative: 2e-4 steps at
# 1e12 steps).
_MAX_SLACK_STEPS = 0.25


def _slack(steps: float) -> float:
    """The slack [steps] of a count of ``steps`` (`WHOLE_STEPS_RTOL`, at most
    `_MAX_SLACK_STEPS`)."""
    return min(WHOLE_STEPS_RTOL * max(1.0, abs(steps)), _MAX_SLACK_STEPS)


def whole_steps(name: str, span: float, dt: float) -> int:
    """Number of steps ``dt`` in ``span``; ValueError (suggesting a dt) unless whole."""
    exact = span / dt
    n = round(exact)
    if abs(exact - n) > _slack(exact):
        suggestion = span / max(n, 1)
        raise ValueError(
            f"{name} = {span!r} is not a whole number of steps dt = {dt!r} "
            f"({exact:.6g} steps); accepted: a dt that divides it, e.g. dt = {suggestion!r}"
        )
    return n


def transient_steps(t_transient: float, dt: float) -> int:
    """First step index n whose time ``t0 + n dt`` is >= ``t0 + t_transient`` (a
    transient meant to end on a step counts as ending there, despite rounding)."""
    steps = t_transient / dt
    return math.ceil(steps - _slack(steps))


def check_sampling_period(name: str, frequencies, dt: float, *,
                          axis: str = "forcing_frequency", period: str = "forcing") -> None:
    """Refuse a drive frequency at which an observable that samples once per period
    could not: every value must be > 0 with a period ``2 pi / W`` that is a whole number
    of steps ``dt`` (so every sample is at the same phase).

    Parameters
    ----------
    name : str
        The observable (``"strobe"``), for the message.
    frequencies : array_like
        The run's drive frequencies W [rad/s] (a grid axis' values, or the one value).
    dt : float
        The step [s].
    axis, period : str
        The frequency's axis name and what the period is called, for the message.

    Raises
    ------
    ValueError
        Naming the first bad frequency and what would be accepted.
    """
    for frequency in np.unique(frequencies):
        if frequency <= 0:  # W = 0: no drive, so no period to sample once per
            raise ValueError(f"observable {name!r} samples once per {period} period 2 pi / "
                             f"{axis} and needs {axis} > 0, got {float(frequency)!r}; "
                             f"accepted: {axis} > 0 rad/s (every value, a {period} period "
                             f"that is a whole number of steps dt = {dt!r}), or observe "
                             f"without {name!r}")
        steps = 2 * np.pi / (frequency * dt)
        if abs(steps - round(steps)) > WHOLE_STEPS_RTOL * max(1.0, steps) * 1e3:
            raise ValueError(
                f"observable {name!r}: the {period} period 2 pi / {float(frequency)!r} is "
                f"not a whole number of steps dt = {dt!r} ({steps:.6g}); "
                f"accepted: dt = period / N, e.g. dt = "
                f"{float(2 * np.pi / (frequency * max(round(steps), 1)))!r}")
