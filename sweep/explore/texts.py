"""Numbers and grids as the text the explorer writes: Python source (`grid_text`) and run
files (`grid_lines`, `toml_value`) that read back exactly the same floats, and numbers
for the hover text (`number_text`)."""

from __future__ import annotations

import json
import math

import numpy as np

from ..grid import Grid

__all__ = ["exact_text", "grid_lines", "grid_text", "number_text", "toml_value"]


def exact_text(value: float) -> str:
    """A float as Python and TOML read it back exactly."""
    return repr(float(value))



def grid_text(grid: Grid) -> str:
    """``sweep.Grid(...)`` source giving exactly ``grid``'s floats."""
    axes = []
    for name, values in grid.axes.items():
        values = np.asarray(values)
        if values.size == 1:
            axes.append(f"{name}=[{exact_text(values[0])}]")
        else:
            axes.append(f"{name}=np.linspace({exact_text(values[0])}, {exact_text(values[-1])}, "
                        f"{values.size})")
    return f"sweep.Grid({', '.join(axes)})"


def grid_lines(axes: dict) -> tuple[list[str], Grid]:
    """A run file's ``[grid]`` lines of ``axes`` (each an array, a number or a ``{start,
    stop, num}`` table), and the `Grid` that `sweep.toml_spec` reads back from them
    (``np.linspace`` of a table)."""
    lines, rows = [], {}
    for name, value in axes.items():
        if isinstance(value, np.ndarray):
            value = float(value[0]) if value.size == 1 else [float(x) for x in value]
        lines.append(f"{name} = {toml_value(value)}")
        rows[name] = np.linspace(value["start"], value["stop"], value["num"]) \
            if isinstance(value, dict) else np.atleast_1d(np.asarray(value, dtype=float))
    return lines, Grid(**rows)


def number_text(value) -> str:
    value = float(value)
    if not math.isfinite(value):
        return "NaN"
    return f"{int(value):d}" if value == int(value) and abs(value) < 1e15 else f"{value:.6g}"


def toml_value(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return exact_text(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} to a run file")
