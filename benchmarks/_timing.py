"""Wall-clock helpers of the benchmark scripts: one call's seconds (`seconds`), the
best of several (`best_of`), and the best of each of several calls taken in turns
(`best_alternating`: on a shared machine a burst of other work then hits all of them
alike, so their ratio is fairer than from timings taken one after the other)."""

from __future__ import annotations

import math
import time

__all__ = ["best_alternating", "best_of", "seconds"]


def seconds(fn) -> float:
    """Wall seconds of one call ``fn()``."""
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def best_of(fn, repeats: int) -> float:
    """The best wall seconds of ``repeats`` (at least one) calls of ``fn()``."""
    return min(seconds(fn) for _ in range(max(1, repeats)))


def best_alternating(calls: dict, rounds: int) -> dict:
    """{name: best seconds}, the calls alternating in each round."""
    best = dict.fromkeys(calls, math.inf)
    for _ in range(rounds):
        for name, call in calls.items():
            best[name] = min(best[name], seconds(call))
    return best
