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
    return _number(name, value, minimum, strict, False, accepted, TypeError)


class ArgumentTypeError(TypeError, ValueError):
    """A parameter of the wrong type (a str, a bool, None, a float where an int is
    meant), raised by `check_count` and `check_quantity`.

    A TypeError, which is what it is, and a ValueError too: the checks these replace in
    `sweep.maps` (`check_positive_int`, ``check_tolerance``, the continuation's) refused
    a value of the wrong type with a ValueError, so code that catches ValueError keeps
    catching it.
    """


def _got(value: Any) -> str:
    """``'3' (str)``: the repr and the type of a value of the wrong type."""
    return f"{value!r} ({type(value).__name__})"


def check_count(
    name: str,
    value: Any,
    *,
    minimum: int = 1,
    maximum: int | None = None,
    accepted: str | None = None,
) -> int:
    """Return ``value`` as an int in ``[minimum, maximum]``: a count, a size, a number
    of periods, samples or bins.

    Only integers are counts: booleans (``True`` would count as 1), floats (even
    ``2.0``), strings and None are refused.

    Raises
    ------
    ArgumentTypeError
        (a TypeError and a ValueError) ``"{name} must be {accepted}, got {value!r}
        ({type})"`` for a value that is not an int.
    ValueError
        ``"{name} must be {accepted}, got {value!r}"`` for one out of range.
    """
    if accepted is None:
        accepted = (f"an int >= {minimum}" if maximum is None
                    else f"an int from {minimum} to {maximum}")
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ArgumentTypeError(f"{name} must be {accepted}, got {_got(value)}")
    if value < minimum or (maximum is not None and value > maximum):
        raise ValueError(f"{name} must be {accepted}, got {value!r}")
    return int(value)


def check_quantity(
    name: str,
    value: Any,
    *,
    minimum: float | None = None,
    strict: bool = False,
    allow_inf: bool = False,
    accepted: str = "a finite number",
) -> float:
    """Return ``value`` as a float: a tolerance, a threshold, a fraction, a size.

    As `check_real` (NaN and -inf always refused; ``minimum`` excluded when
    ``strict``), except that ``+inf`` passes when ``allow_inf`` ("no threshold") and
    that a value of the wrong type raises `ArgumentTypeError`, a ValueError as well as
    a TypeError.

    Raises
    ------
    ArgumentTypeError
        For a value that is not a real number: booleans, strings, None, complex
        numbers, arrays.
    ValueError
        ``"{name} must be {accepted}, got {value!r}"`` for NaN, an infinity not
        allowed, or a value below ``minimum`` (or equal to it, when ``strict``).
    """
    return _number(name, value, minimum, strict, allow_inf, accepted, ArgumentTypeError)


def _number(name: str, value: Any, minimum: float | None, strict: bool, allow_inf: bool,
            accepted: str, wrong_type: type[Exception]) -> float:
    """`check_real` and `check_quantity`: ``value`` as a float; ``wrong_type`` for a
    value that is not a real number."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise wrong_type(f"{name} must be {accepted}, got {_got(value)}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond the float range
        raise ValueError(f"{name} must be {accepted}, got {value!r} (beyond the float "
                         "range)") from None
    finite = math.isfinite(number) or (allow_inf and number == math.inf)
    if not finite or (minimum is not None
                      and (number < minimum or (strict and number == minimum))):
        raise ValueError(f"{name} must be {accepted}, got {number!r}")
    return number


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


def check_flag(name: str, value: Any, *, allow_none: bool = False) -> bool | None:
    """Return ``value`` as a bool if it is True or False (or None, when allowed).

    Strings such as ``"no"`` and numbers such as ``0`` are refused: they would be taken
    by their truth value, which is rarely what was meant.

    Raises
    ------
    TypeError
        ``"{name} must be True or False, got {value!r}"``.
    """
    if value is None and allow_none:
        return None
    if not isinstance(value, (bool, np.bool_)):
        accepted = "True, False or None" if allow_none else "True or False"
        raise TypeError(f"{name} must be {accepted}, got {value!r}")
    return bool(value)


def check_keys(table: Any, accepted: Sequence[str], where: str = "",
               label: str = "accepted") -> None:
    """Refuse a run-file table with a key not in ``accepted``: ``unknown key 'k'<where>;
    <label>: a, b, ...`` (``where`` e.g. `` in coordinates[0]``; ``label`` e.g.
    ``accepted for DeclaredSystem``)."""
    unknown = [key for key in table if key not in accepted]
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r}{where}; {label}: "
                         f"{', '.join(accepted)}")


def check_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices``; otherwise raise ValueError."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(
            f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}"
        )
    return value


def _describe(value: Any) -> str:
    """``'1.0' (str)``, the repr shortened to 60 characters."""
    text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def check_numbers(what: str, values: Any) -> np.ndarray:
    """Return ``values`` as a float64 array if every element is a real number.

    Refused, because they would convert silently into numbers nobody meant:
    booleans (Python and NumPy, ``True`` -> 1.0), strings and bytes (``"1.0"``),
    ``None`` (-> NaN), complex numbers, datetimes and timedeltas, and masked elements of
    a masked array (the mask would be dropped). Integers and floats of any width are
    accepted.

    Parameters
    ----------
    what : str
        How to name the values in a message, e.g. ``"grid axis 'theta0'"``.
    values : array_like
        A scalar or an array of any shape.

    Returns
    -------
    ndarray, float64
        Same shape as ``values``.

    Raises
    ------
    ValueError
        Naming ``what``, the bad value, its index and what is accepted.
    """
    accepted = "accepted: real numbers (int or float)"
    if isinstance(values, (str, bytes)):
        raise ValueError(f"{what} must be a 1-D array of numbers, got {values!r}; {accepted}")
    if np.ma.isMaskedArray(values) and np.ma.getmaskarray(values).any():
        index = int(np.flatnonzero(np.ma.getmaskarray(values))[0])
        raise ValueError(f"{what} has a masked value at flat index {index}; {accepted} "
                         "(fill or drop masked values first)")
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a 1-D array of numbers, got {values!r}") from None
    if raw.dtype.kind == "b":
        raise ValueError(f"{what} holds booleans ({raw.reshape(-1)[:3].tolist()!r}...); "
                         f"booleans are not numbers here; {accepted}")
    if raw.dtype.kind in "fiu":
        if isinstance(values, (list, tuple)):
            _check_items(what, values, accepted)  # [True, 1.0] is a float64 array
        return raw.astype(np.float64, copy=False)
    if raw.ndim == 0 and raw.dtype.kind in "OV":
        item = raw.item()
        if isinstance(item, (bool, np.bool_)) or not isinstance(item, numbers.Real):
            raise ValueError(f"{what} must be a number or a 1-D array of numbers, got "
                             f"{_describe(item)}; {accepted}")
    if raw.dtype.kind in "USaOcmMV":
        _check_items(what, raw.reshape(-1).tolist() if raw.dtype.kind != "O"
                     else list(raw.reshape(-1)), accepted)
    try:
        return raw.astype(np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{what} must be an array of numbers, got {values!r}; "
                         f"{accepted}") from None


def _check_items(what: str, items: Sequence, accepted: str) -> None:
    """Refuse the first item of a flat or nested sequence that is not a real number."""
    for index, item in enumerate(items):
        if isinstance(item, (list, tuple)):
            _check_items(f"{what}[{index}]", item, accepted)
            continue
        bad = (isinstance(item, (bool, np.bool_)) or not isinstance(item, numbers.Real)
               or isinstance(item, (np.datetime64, np.timedelta64)))
        if bad:
            raise ValueError(f"{what} has {_describe(item)} at index {index}; {accepted}")
        try:
            float(item)
        except OverflowError:
            raise ValueError(f"{what} has {_describe(item)} at index {index}, beyond the float "
                             f"range; {accepted}") from None


def check_axis(name: str, values: Any) -> np.ndarray:
    """Return ``values`` as a 1-D, C-contiguous, finite, non-empty float64 array of
    distinct values, in the order given.

    An axis need not be sorted: the dataset keeps the order given (``.sel`` works
    either way). Booleans, strings, None, complex numbers and the like are refused
    (see `check_numbers`); so is a value given twice, which would make the dataset's
    coordinate non-unique and compute the same trajectories twice.

    Raises
    ------
    ValueError
        Naming the axis and what is wrong with it.
    """
    if isinstance(values, (str, bytes)):
        raise ValueError(f"grid axis {name!r} must be a 1-D array of numbers, got {values!r}")
    array = check_numbers(f"grid axis {name!r}", values)
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
    order = np.argsort(array, kind="stable")
    repeated = np.flatnonzero(array[order][1:] == array[order][:-1])
    if repeated.size:
        value = array[order][repeated[0]]
        indices = np.flatnonzero(array == value)
        raise ValueError(
            f"grid axis {name!r} has the value {float(value)!r} more than once (indices "
            f"{', '.join(map(str, indices.tolist()))}); each value is one grid point, so a "
            "repeat computes the same trajectories twice and makes the coordinate "
            "non-unique; accepted: distinct values (e.g. np.unique(values))"
        )
    return np.ascontiguousarray(array)
