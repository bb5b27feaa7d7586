"""Single precision (``KernelSpec.dtype == "float32"``): the generated module made to
compute in float32.

numba types a float literal, ``math.pi`` and any float64 array element as float64, and
NumPy's promotion then turns ``float32 * float64`` into float64: one literal in a stage
line would make the whole step, and the lanes it is stored in, float64 arithmetic with
a float32 rounding at each store -- slower than float64 and no more accurate than
float32. So a float32 module is the float64 module's text with

- every float literal and ``math.pi`` wrapped as ``F(...)`` (``F = np.float32``: LLVM
  folds the conversion, so these are float32 constants);
- every parameter load ``x = params[...]`` (``x = _param(...)`` on the GPU) rounded to
  float32 (``F(params[...])``),
  except the ones that `float64_symbols` keeps: the start angle of the nonlinear
  pendulum and the drives' frequencies and phases; a drive's amplitude (which may read
  its frequency) rounded to float32 where it multiplies the drive's sine;
- the working-precision lanes (angular velocity, parameters, stage values, drive sines)
  allocated as float32 (`sweep.kernels.fixed`), the float32 sine
  (`sweep.kernels.vecmath.sin32`) imported as ``vsin``;
- the compiled function's step taken as ``dt_clock`` and stepped by ``F(dt_clock)``
  (`clock`); the module's ``kernel`` passes its float64 arguments on unchanged.

What stays float64, on purpose:

- the nonlinear pendulum's angle ``th``. Its unwrapped value grows by 2 pi every turn,
  and float32 would hold it only to ulp(|theta|) / 2: 3e-5 at 500 rad, 2.4e-4 past
  4000 rad, an absolute rounding of the angle at every step that grows with time and
  made every rotating attractor of a forced map unresolvable after a few hundred
  periods. In float64 only the increments ``k`` (float32, each rounded relative to
  itself) carry float32's rounding. The stage angles ``th + dt/2 k1`` and the update
  are float64 fused multiply-adds (``vfma`` widens its float32 factors, so the product
  is exact); `vecmath.sin32` reduces its float64 argument in
  float64 and evaluates in float32. (The linear model's ``th`` is a coordinate, not an
  angle, and stays float32.)
- the drives' phases ``W t + phi``: frequency and phase stay float64 and the clock
  ``t0 + n F(dt)`` is formed in float64, so the phase does not lose digits as ``t``
  grows (W rounded to float32 would shift it by 1e-4 rad after 2000 s).
- the observables' accumulators (a sum over 10^5 steps in float32 would lose ~1e-2 of
  itself) and the outputs.

The state steps by ``F(dt)``; the clock ``t0 + n dt`` stays float64 (`clock`), so
the state's own time runs ``F(dt) / dt = 1 + O(6e-8)`` faster or slower than the
clock's: a relative change of every time scale of that size, as if ``g/L`` were
rounded to float32 too (it is). The forcing, the stroboscopic samples and the saved
times stay on the float64 grid.
``tests/test_float32.py`` checks from the machine code that the step is float32 SIMD
arithmetic.
"""

from __future__ import annotations

import io
import re
import tokenize

__all__ = ["HEADER", "clock", "float64_symbols", "single", "single_drive_values", "single_loads"]

#: The float32 CPU module's import of the float32 sine (``F = np.float32`` is set
#: after NumPy's import).
HEADER = ("from sweep.kernels.vecmath import cos32 as vcos, fma as vfma, sin32 as vsin, "
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


_LOAD = re.compile(r"^(?P<lead>[ \t]*)(?P<name>\w+) = "
                   r"(?P<load>params\[[^\]\n]*\]|_param\([^)\n]*\))[ \t]*$", re.MULTILINE)


def float64_symbols(model: str, effects) -> set[str]:
    """The kernel symbols a float32 kernel keeps in float64: ``th0`` for the nonlinear
    model (its angle is float64, see the module notes) and each drive's frequency and
    phase (the drive's phase is formed in float64)."""
    keep = {"th0"} if model == "nonlinear" else set()
    for effect in effects:
        if effect.drive is not None:
            keep |= {effect.drive.frequency, effect.drive.phase}
    return keep


_DRIVE_VALUE = re.compile(r"^(?P<lead>[ \t]*)(?P<name>\w+) = (?P<amplitude>.+) \* s(?P=name)$",
                          re.MULTILINE)


def single_drive_values(text: str) -> str:
    """Each drive value ``x = amplitude * sx`` with its amplitude rounded to float32:
    an amplitude may read a drive frequency kept float64 (the pivot's ``a nu^2 / L``),
    and would otherwise make the value, and the whole step after it, float64."""
    return _DRIVE_VALUE.sub(lambda m: f"{m.group('lead')}{m.group('name')} = "
                                      f"F({m.group('amplitude')}) * s{m.group('name')}", text)


def single_loads(text: str, keep) -> str:
    """``text`` with every parameter load ``x = params[...]`` written
    ``x = F(params[...])``, except for the symbols in ``keep``."""
    return _LOAD.sub(lambda m: m.group(0) if m.group("name") in keep else
                     f"{m.group('lead')}{m.group('name')} = F({m.group('load')})", text)


# a compiled kernel's head: the step is its third parameter
_HEAD = re.compile(r"^(?P<head>@(?:njit|cuda\.jit)[^\n]*\ndef \w+\(params, t0, )dt"
                   r"(?P<rest>,[^)]*\):\n)(?P<indent>[ \t]+)", re.MULTILINE)
# products that are times: a step count times the step, a stage's offset c dt, a
# forcing period in steps
_TIMES = re.compile(r"(\b(?:step|k_state|ks)\b|\((?:step|ks) \+ 1\)|\(acc_n_steady - 1\)|"
                    r"\(n_steps - max\(n_transient, 0\)\)|\bW) \* dt\b")
_OFFSET = re.compile(r"^(?P<lead>[ \t]*cdt\d+) = dt \* F\((?P<c>[^()]*)\)$", re.MULTILINE)


def clock(text: str) -> str:
    """``text`` with the clock in float64 and the step in float32: each compiled
    kernel takes the float64 step as ``dt_clock`` and steps with ``dt = F(dt_clock)``;
    every time (``t0 + n dt_clock``, a stage's ``c dt_clock``, a window's length, the
    forcing period in steps) is formed from ``dt_clock``. So the drives' phases and
    the stroboscopic samples stay on the float64 time grid: a float32 clock
    ``n F(dt)`` would drift from the forcing period by ~3e-8 of itself, and a
    stroboscopic sequence with it (measured: 1e-6 rad/s per period, so ``stop_early``
    never stopped)."""
    text = _HEAD.sub(lambda m: f"{m.group('head')}dt_clock{m.group('rest')}"
                               f"{m.group('indent')}dt = F(dt_clock)\n{m.group('indent')}",
                     text)
    text = _OFFSET.sub(lambda m: f"{m.group('lead')} = dt_clock * {m.group('c')}", text)
    return _TIMES.sub(lambda m: f"{m.group(1)} * dt_clock", text)
