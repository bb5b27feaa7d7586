"""Small pure validators: each returns the cleaned value or raises a message that
names the parameter, the bad value and what would be accepted."""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np


def check_real(
    name: str,
    value: Any,
    *,
    minimum: float | None = None,
    strict: bool = False,
    accepted: str = "a finite number",
) -> float:
    """Return ``value`` as a finite float, checking an optional lower bound.

    Raises
    ------
    TypeError
        If ``value`` is not a real number (booleans and strings are refused).
    ValueError
        If it is not finite or is below ``minimum`` (or equal, when ``strict``).
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be {accepted}, got {value!r} ({type(value).__name__})")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    if minimum is not None and (value < minimum or (strict and value == minimum)):
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    return value


def check_positive_int(name: str, value: Any, accepted: str = "an int >= 1") -> int:
    """Return ``value`` as an int if it is an integer >= 1 (booleans refused).

    Raises
    ------
    ValueError
        ``"{name} must be {accepted}, got {value!r}"``.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
            or value < 1:
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    return int(value)


def check_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices``; otherwise raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(
            f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}"
        )
    return value


def check_axis(name: str, values: Any) -> np.ndarray:
    """Return ``values`` as a 1-D, C-contiguous, finite, non-empty float64 array.

    Raises
    ------
    ValueError
        Naming the axis and what is wrong with it.
    """
    if isinstance(values, (str, bytes)):
        raise ValueError(f"grid axis {name!r} must be a 1-D array of numbers, got {values!r}")
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"grid axis {name!r} must be a 1-D array of numbers, got {values!r}"
        ) from None
    if array.ndim == 0:
        array = array.reshape(1)
    if array.ndim != 1:
        raise ValueError(
            f"grid axis {name!r} must be 1-D, got an array of shape {array.shape}; "
            "each axis is one dimension of the grid"
        )
    if array.size == 0:
        raise ValueError(f"grid axis {name!r} is empty; accepted: at least one value")
    bad = ~np.isfinite(array)
    if bad.any():
        raise ValueError(
            f"grid axis {name!r} has non-finite value {float(array[bad][0])!r} at index "
            f"{int(np.flatnonzero(bad)[0])}; accepted: finite numbers"
        )
    return np.ascontiguousarray(array)
