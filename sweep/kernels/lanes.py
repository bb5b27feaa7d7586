"""Lanes of a block: per-trajectory code inside the kernels' blocks of SIMD lanes
(fixed-step, refill and adaptive), with per-lane state in small arrays
``lane_<name>``."""

from __future__ import annotations

import re
import textwrap

__all__ = ["ASSIGNED", "IDENTIFIER", "allocate", "indent", "lane_loop", "lane_snippet",
           "skip_unless"]

IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")
ASSIGNED = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:[-+*/]?=)(?!=)", re.MULTILINE)


def lane_snippet(code: str) -> str:
    """A per-trajectory snippet inside a block: ``out[i, ...]`` becomes the block's
    row buffer ``obuf[j, ...]`` (padding lanes then write nowhere shared)."""
    return code.replace("out[i,", "obuf[j,")


def lane_loop(body: str, lane: dict[str, str], *, level: int, head: str = "",
              stores: list[str] | None = None, count: str = "BLOCK",
              load: bool = True) -> str:
    """``for j in range(count):`` around ``body``: loads each lane variable the body
    reads from its array ``lane_<name>[j]`` first (unless ``load`` is False) and
    stores back those it assigns (or ``stores``)."""
    used = set(IDENTIFIER.findall(body)) if load else set()
    loads = [f"{name} = lane_{name}[j]" for name in lane if name in used]
    if stores is None:
        stores = [name for name in lane if name in set(ASSIGNED.findall(body))]
    lines = loads + [body] + [f"lane_{name}[j] = {name}" for name in stores]
    return indent(f"for j in range({count}):\n{head}" + indent("\n".join(lines), 1),
                  level)


def indent(code: str, level: int) -> str:
    """``code`` indented by ``level`` levels of four spaces ("" stays "")."""
    return textwrap.indent(code, "    " * level) if code else ""


def allocate(lane: dict[str, str]) -> list[str]:
    """The lines that make each lane variable's array ``lane_<name>`` (name -> dtype)."""
    return [f"lane_{name} = np.empty(BLOCK, dtype=np.{dtype})" for name, dtype in lane.items()]


def skip_unless(flag: str) -> str:
    """A `lane_loop` head that skips the lanes whose boolean ``lane_<flag>`` is False."""
    return f"    if not lane_{flag}[j]:\n        continue\n"
