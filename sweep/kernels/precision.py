"""Single precision (``KernelSpec.dtype == "float32"``): the generated module made to
compute in float32.

numba types a float literal, ``math.pi`` and any float64 array element as float64, and
NumPy's promotion then turns ``float32 * float64`` into float64: one literal in a stage
line would make the whole step, and the lanes it is stored in, float64 arithmetic with
a float32 rounding at each store -- slower than float64 and no more accurate than
float32. So a float32 module is the float64 module's text with

- every float literal and ``math.pi`` wrapped as ``F(...)`` (``F = np.float32``: LLVM
  folds the conversion, so these are float32 constants);
- the working-precision lanes (state, parameters, stage values, drive sines) allocated
  as float32 (`sweep.kernels.fixed`), the drives' phases rounded once to float32 from
  the float64 clock (`sweep.kernels.terms.drive_sine`), the float32 sine
  (`sweep.kernels.vecmath.sin32`) imported as ``vsin``;
- the kernel renamed and wrapped by `wrapper`, which hands it the parameter table in
  float32 and the step ``F(dt)``.

What stays float64, on purpose: the clock ``t0 + n F(dt)`` (formed in float64 and
rounded once per use, so time is never accumulated in float32), the observables'
accumulators (a sum over 10^5 steps in float32 would lose ~1e-2 of itself) and the
outputs. The step of a float32 run is ``F(dt)``, consistently in the state and the
clock, so its time grid is ``t0 + n F(dt)`` (relative difference from ``dt`` below
6e-8). ``tests/test_float32.py`` checks from numba's type inference that the step's
variables are float32.
"""

from __future__ import annotations

import io
import re
import tokenize

__all__ = ["HEADER", "single", "wrapper"]

#: The float32 CPU module's import of the float32 sine (``F = np.float32`` is set
#: after NumPy's import).
HEADER = ("from sweep.kernels.vecmath import cos32 as vcos, sin32 as vsin, "
          "sincos32 as vsincos")

_FLOAT = re.compile(r"^(\d+\.\d*|\.\d+|\d+[eE][-+]?\d+|\d+\.\d*[eE][-+]?\d+)$")


def single(text: str) -> str:
    """``text`` (Python source) with every float literal and ``math.pi`` written
    ``F(...)``; strings, comments and integers are left alone."""
    tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    lines = text.splitlines(keepends=True)
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line))
    edits = []  # (start offset, end offset, replacement)
    for k, tok in enumerate(tokens):
        start = starts[tok.start[0] - 1] + tok.start[1]
        end = starts[tok.end[0] - 1] + tok.end[1]
        if tok.type == tokenize.NUMBER and _FLOAT.match(tok.string):
            edits.append((start, end, f"F({tok.string})"))
        elif (tok.type == tokenize.NAME and tok.string == "math" and k + 2 < len(tokens)
              and tokens[k + 1].string == "." and tokens[k + 2].string == "pi"):
            end = starts[tokens[k + 2].end[0] - 1] + tokens[k + 2].end[1]
            edits.append((start, end, "F(math.pi)"))
    for start, end, new in reversed(edits):
        text = text[:start] + new + text[end:]
    return text


def wrapper(name: str) -> str:
    """Source of ``kernel`` with the fixed-step contract over the float32 kernel
    ``name``: the parameter table converted to float32 (a copy of the chunk, half its
    size), the step rounded to float32; outputs stay float64."""
    return f'''

def kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved):
    """The float32 kernel {name} under the fixed-step contract (float64 arguments)."""
    {name}(np.ascontiguousarray(params, dtype=np.float32), t0, np.float32(dt), n_steps,
           n_transient, save_every, out, status, saved)
'''
