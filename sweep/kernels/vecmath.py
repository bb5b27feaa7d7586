"""A vectorisable ``sin`` for numba kernels: the sine of every sweep kernel.

numba >= 0.62 has no SVML, so ``math.sin``/``np.sin`` in a numba loop is a scalar call
into libm and the loop is never vectorised. `sin` here is straight-line arithmetic
(no calls, no data-dependent branches), so LLVM can put one trajectory in each SIMD
lane when the kernel's lane loop is innermost; and its dependency chain is short, so
one trajectory alone (whose steps wait on each other's sines) runs fast too.

Algorithm
---------
1. Quadrant: ``y = x * 2/pi + 1.5 * 2**52`` rounds ``x * 2/pi`` to the integer ``k``
   ("magic number"; valid for ``|x * 2/pi| < 2**51``; needs IEEE evaluation order,
   i.e. no ``reassoc`` fast-math flag): ``kf = y - 1.5 * 2**52`` exactly, and the low
   bits of ``y``'s IEEE pattern are ``k mod 4`` (two's complement), so the quadrant
   needs no float-to-integer conversion.
2. Cody-Waite reduction with two fused multiply-adds (`fma`, LLVM's ``llvm.fma``: one
   rounding, whatever the fast-math flags or the CPU), ``r = fma(-kf, PIO2_LO,
   fma(-kf, PIO2_HI, x))`` with ``pi/2 = PIO2_HI + PIO2_LO - ~1.5e-33``. The first
   FMA is exact (``x`` and ``k PIO2_HI`` are multiples of 2**-52 or finer, and their
   difference is below 1), the second rounds once, so ``r`` is within half an ulp of
   ``x - k pi/2`` (|r| <~ pi/4) but for the truncated pi/2, ``|k| * 1.5e-33``. Up to
   |x| ~ 1e12 that is all (tested); past ~1e13 the rounded ``x * 2/pi`` may choose the
   neighbouring quadrant, so |r| exceeds pi/4 a little and the error grows (1.9e-14
   measured at 3e15); past ``2**51 pi/2 ~ 3.5e15`` the quadrant trick fails and the
   results are not sines (finite up to ~4e39, NaN beyond).
3. One polynomial, by quadrant: ``sin r = r + r z P_s(z)`` on even quadrants and
   ``cos r = 1 + z P_c(z)`` on odd ones (``z = r^2``), with fdlibm's minimax
   coefficients (``__kernel_sin``/``__kernel_cos``, error < 2**-58 on [-pi/4, pi/4]);
   the coefficients, ``r`` or 1 and ``r z`` or ``z`` are chosen by ternary selects
   (blend instructions, not branches), so each call evaluates one polynomial, not two.
   The polynomial of degree 6 in ``z`` is evaluated by Estrin's scheme (pairs, then
   ``z^2``, ``z^4``): depth 3 multiply-adds instead of Horner's 6.
4. The sign: negated on quadrants 2 and 3 (a select).

Measured on this project's Zen 4: one call waits about 38 cycles for its argument (the
previous sine, which reduced with three Cody-Waite terms, converted the quadrant to an
integer, evaluated both polynomials by Horner and compensated ``1 - z/2``, waited about
59), and vectorised it gives 1.4x the sines per second (``benchmarks/run_all.py``
times both inside the kernels). Error: at most 1.1e-16 from ``np.sin`` (one ulp of
values below 1; the rounding of ``r``, of the polynomial and of its last multiply-add
add up to at most ~1.3e-16 from the true sine) for |x| <= 1e4, and the same up to 1e12
(``tests/test_vecmath.py``).

Compiled on its own with the kernels' fast-math flags (none since 2026-11-25: its
fused multiply-adds are written as `fma`, so its bits do not depend on what LLVM
would fuse; never ``reassoc``, which would break the reduction), and inlined into the
kernels by LLVM, where the lane loop is vectorised. Not marked ``inline="always"`` for
numba: inlining its IR into every stage of a kernel doubled the compile time, for the
same speed.

NaN and +-inf give NaN (``inf - inf`` in the reduction). The sign of zero is not kept
(``sin(-0.0)`` gives ``+0.0``), as under the ``nsz`` fast-math flag anyway.
`cos` is the same polynomial one quadrant on, and `sincos` returns both from one
reduction with the bits of `sin` and `cos` (the tangent dynamics read the cosine at
every stage beside the sine).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core.extending import intrinsic

from .. import _config

#: The kernels' JIT flags (`sweep._config.FASTMATH`: none; the multiply-adds to fuse
#: are written as `fma`), the same for the sine as for the kernels it is inlined into.
_JIT = _config.jit_options()

__all__ = ["P1", "P2", "PIO2_HI", "PIO2_LO", "SIN32_RANGE", "SIN_RANGE", "cos", "cos32", "fma",
           "inverse_fifth_root", "sin", "sin32", "sincos", "sincos32"]

TWO_OVER_PI = 0.6366197723675814
#: pi/2 = PIO2_HI + PIO2_LO (- 1.5e-33): the float64 reduction's two parts.
PIO2_HI = 1.5707963267948966   # 0x1.921fb54442d18p+0
PIO2_LO = 6.123233995736766e-17  # 0x1.1a62633145c07p-54
#: pi/2 = P1 + P2 (+ 5.7e-18): 27 + 27 significant bits, so that ``k P1`` and ``k P2``
#: are exact products for |k| < 2**26 without an FMA (the float32 sine's reduction, and
#: the GPU's in `sweep.kernels.cuda`).
P1 = 1.570796325802803        # 0x1.921fb54p+0
P2 = 9.920935739593517e-10    # 0x1.10b461p-30
_MAGIC = 6755399441055744.0   # 1.5 * 2**52: adding and subtracting it rounds to integer
#: Largest |x| [rad] up to which `sin`/`cos` are guaranteed as accurate as libm's
#: (within 2**-52, tested to there; past ~1e13 the quadrant may slip, past 3.5e15 the
#: values are not sines): the kernels refuse starts beyond it and flag a trajectory
#: whose angle ends beyond it (`sweep.kernels.Status.ANGLE_OUT_OF_RANGE`).
SIN_RANGE = 1e12
#: The same for `sin32`/`cos32` and the GPU's float32 sine (their ``P1``/``P2``
#: reduction is exact and its dropped rest below 1e-9 up to |x| ~ 1e8; tested to there).
SIN32_RANGE = 1e8

# fdlibm __kernel_sin / __kernel_cos minimax coefficients on [-pi/4, pi/4]
S1 = -1.66666666666666324348e-01
S2 = 8.33333333332248946124e-03
S3 = -1.98412698298579493134e-04
S4 = 2.75573137070700676789e-06
S5 = -2.50507602534068634195e-08
S6 = 1.58969099521155010221e-10
C1 = 4.16666666666666019037e-02
C2 = -1.38888888888741095749e-03
C3 = 2.48015872894767294178e-05
C4 = -2.75573143513906633035e-07
C5 = 2.08757232129817482790e-09
C6 = -1.13596475577881948265e-11


@intrinsic
def fma(typingctx, a, b, c):
    """``a * b + c`` rounded once: LLVM's ``llvm.fma`` (an FMA instruction, or libm's
    exact ``fma`` on a CPU without one), whatever the fast-math flags.

    The kernels write every fused multiply-add they want this way (as ``vfma``) and let
    LLVM fuse nothing else: which product of ``a * b + c * d`` LLVM's contraction would
    fuse depends on the code around it, which differs between a vectorised block, an
    unrolled one and a lone trajectory, and so would the last bits. Arguments float32
    or float64 (ints are widened); with any float64 the operation is float64.
    """
    kinds = (a, b, c)
    if not all(isinstance(t, (types.Float, types.Integer)) for t in kinds):
        return None
    result = types.float32 if all(t == types.float32 for t in kinds) else types.float64

    def codegen(context, builder, signature, args):
        values = [context.cast(builder, v, t, result) for v, t in zip(args, signature.args)]
        return builder.fma(*values)

    return result(a, b, c), codegen


@intrinsic
def _bits_of(typingctx, x):
    """The IEEE 754 bits of a float64, as an int64 (a reinterpretation: no instruction)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _float_of(typingctx, bits):
    """The float64 whose IEEE 754 bits are the int64 ``bits``."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@njit(cache=True, **_JIT)
def _reduce(x):
    """(r, q): x = k pi/2 + r with |r| <~ pi/4; ``q`` an int64 whose two low bits are
    ``k mod 4`` (the bits of the magic-number sum)."""
    y = fma(x, TWO_OVER_PI, _MAGIC)
    kf = y - _MAGIC
    r = fma(-kf, PIO2_LO, fma(-kf, PIO2_HI, x))
    return r, _bits_of(y)


@njit(cache=True, **_JIT)
def _sine_of_reduced(r, q):
    """sin(k pi/2 + r) from the reduced argument and ``q`` (``k mod 4`` in its low
    bits): sin r on even quadrants, cos r on odd ones, negated on quadrants 2 and 3."""
    odd = (q & 1) != 0
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    c0 = -0.5 if odd else S1
    c1 = C1 if odd else S2
    c2 = C2 if odd else S3
    c3 = C3 if odd else S4
    c4 = C4 if odd else S5
    c5 = C5 if odd else S6
    c6 = C6 if odd else 0.0
    p = fma(z4, fma(z2, c6, fma(z, c5, c4)), fma(z2, fma(z, c3, c2), fma(z, c1, c0)))
    y = fma(z if odd else z * r, p, 1.0 if odd else r)
    return -y if (q & 2) else y


@njit(cache=True, **_JIT)
def sin(x):
    """sin(x) in float64, branch-free (vectorisable); accurate for |x| <~ 1e12."""
    r, q = _reduce(x)
    return _sine_of_reduced(r, q)


@njit(cache=True, **_JIT)
def cos(x):
    """cos(x) = sin(x + pi/2): the same reduction, one quadrant on."""
    r, q = _reduce(x)
    return _sine_of_reduced(r, q + 1)


@njit(cache=True, **_JIT)
def sincos(x):
    """(sin(x), cos(x)) from one argument reduction, each polynomial evaluated once: the
    sine's and the cosine's (the operations of `_sine_of_reduced` on an even and on an
    odd quadrant), then swapped and signed by quadrant, so the bits are those of `sin`
    and `cos` (the tangent dynamics of `sweep.kernels` and the double pendulum's
    ``sin``/``cos`` of theta1 - theta2 need both at every stage). Evaluating the
    select-by-quadrant polynomial twice instead cost the double pendulum's kernel 7 %
    (``docs/guide/performance.md``)."""
    r, q = _reduce(x)
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    # the sine's polynomial; its seventh coefficient is 0, and fma(z2, 0, a) = a here
    # (a ~ S5 is never 0 and z2 is finite), so the term is left out
    ps = fma(z4, fma(z, S6, S5), fma(z2, fma(z, S4, S3), fma(z, S2, S1)))
    pc = fma(z4, fma(z2, C6, fma(z, C5, C4)), fma(z2, fma(z, C3, C2), fma(z, C1, -0.5)))
    s_r = fma(z * r, ps, r)
    c_r = fma(z, pc, 1.0)
    odd = (q & 1) != 0
    s = c_r if odd else s_r
    c = s_r if odd else c_r
    s = -s if (q & 2) else s
    c = -c if ((q + 1) & 2) else c
    return s, c


#: ``x ** -0.2`` read off the bits: a float64's bits are ``2**52 (log2 x + 1023 - s)``
#: with ``0 <= s < 0.09`` (``log2(1 + m) ~ m + s``), so the bits of ``x ** -0.2`` are
#: about ``1.2 * 2**52 (1023 - s) - bits(x) / 5``; ``s = 0.045`` keeps the guess within
#: 3.5 % on the controller's range.
_ROOT5_MAGIC = 1.2 * 2.0 ** 52 * (1023.0 - 0.045)


@njit(cache=True, inline="always", **_JIT)
def inverse_fifth_root(x):
    """x ** -0.2 for 1e-6 <= x <= 1e4, branch-free and without libm (vectorisable): the
    step-size controller's factor of a 5th-order pair (`sweep.kernels.adaptive`).

    A first guess from the float's bits (``_ROOT5_MAGIC``, the inverse-square-root
    trick for the fifth root: within 3.5 %), then four Newton steps for ``y ** -5 = x``
    (each squares the relative error, times ~3: 3.8e-3, 4.3e-5, 5.5e-9, then rounding),
    within 3 ulp of libm's power (``tests/test_vecmath.py``), so the controller makes
    the same choices as with it. No square root and no division (the previous version
    took four square roots for ``x ** (-3/16)``, a division and five Newton steps, and
    was within 2.8e-13); the lanes' speed did not change measurably with it
    (``benchmarks/work_precision.py``). The controller clips the factor to [0.2, 10],
    reached at ``x`` = 1845 and 5.9e-6, so ``x`` is clamped to the range first. Inlined
    into the kernel by numba (``inline="always"``): left to LLVM's inliner, a call
    stayed in the lane loop once the function grew, and the loop was not vectorised
    (measured: 5x slower).
    """
    x = min(max(x, 1e-6), 1e4)
    y = _float_of(np.int64(_ROOT5_MAGIC - 0.2 * np.float64(_bits_of(x))))
    y2 = y * y
    y = y * (6.0 - x * (y2 * y2 * y)) * 0.2
    y2 = y * y
    y = y * (6.0 - x * (y2 * y2 * y)) * 0.2
    y2 = y * y
    y = y * (6.0 - x * (y2 * y2 * y)) * 0.2
    y2 = y * y
    return y * (6.0 - x * (y2 * y2 * y)) * 0.2


# ---------------------------------------------------------------------------------------
# Single precision (``dtype="float32"`` kernels): the float32 polynomials after a
# float64 reduction, so that the result is float32 and an argument's size never costs
# accuracy.
#
# 1. The argument is taken in float64: the float32 kernels keep the angle of the
#    nonlinear pendulum in float64 (its unwrapped value grows with every turn, and in
#    float32 an angle of 4000 rad is known only to 2.4e-4), and a drive's phase
#    ``W t + phi`` is formed from the float64 clock. A float32 argument is widened
#    exactly.
# 2. ``k = rint(x * 2/pi)`` and ``r = (x - k P1) - k P2`` in float64 (two Cody-Waite
#    terms of 27 bits: exact products for |x| < ~1e8 without an FMA, and the dropped
#    rest of pi/2, ``k * 5.7e-18``, is below 1e-9 there, far under float32's
#    resolution), then ``r`` is rounded once to float32.
# 3. Cephes' sinf/cosf polynomials on [-pi/4, pi/4] in float32 (relative error ~ 1 ulp
#    of float32), Horner with the multiply-adds fused explicitly (`fma`: the kernels
#    let LLVM fuse nothing; unfused, the float32 kernel ran 16 % slower), one of the
#    two per call, chosen and signed by quadrant with selects (`_sine_of_reduced32`).
# Four float64 operations and two conversions per call; the rest of the sine, and of
# the kernel around it, is float32. Measured (``tests/test_vecmath.py``): max abs error
# against float64 ``np.sin`` 9.3e-8 (about 1.5 float32 ulps below 1; NumPy's own
# float32 sine: 6.2e-8) for |x| <= 1e4 and on to 1e8, with no growth in |x|.
# ---------------------------------------------------------------------------------------

_F32 = np.float32
SF1 = _F32(-1.6666654611e-1)
SF2 = _F32(8.3321608736e-3)
SF3 = _F32(-1.9515295891e-4)
CF1 = _F32(4.166664568298827e-2)
CF2 = _F32(-1.388731625493765e-3)
CF3 = _F32(2.443315711809948e-5)
_HALF32 = _F32(0.5)
_ONE32 = _F32(1.0)


@njit(cache=True, **_JIT)
def _reduce32(x):
    """(r, q): x = k pi/2 + r with |r| <~ pi/4 in float32, ``q`` an int64 whose two low
    bits are ``k mod 4`` (the bits of the magic-number sum, as in `_reduce`); the
    reduction in float64 (a float32 ``x`` is widened exactly)."""
    x = np.float64(x)
    y = x * TWO_OVER_PI + _MAGIC
    kf = y - _MAGIC
    r = (x - kf * P1) - kf * P2
    return _F32(r), _bits_of(y)


@njit(cache=True, **_JIT)
def _sine_of_reduced32(r, q):
    """sin(k pi/2 + r) in float32: Cephes' sinf polynomial on even quadrants, cosf's
    on odd ones, negated on quadrants 2 and 3. One polynomial per call, its
    coefficients chosen by selects (as `_sine_of_reduced`; the previous version
    evaluated both and chose after), with the same operations as each polynomial
    alone, so the bits are those of the two-polynomial version."""
    odd = (q & 1) != 0
    z = r * r
    p = fma(z, fma(z, CF3 if odd else SF3, CF2 if odd else SF2), CF1 if odd else SF1)
    y = fma(z * z if odd else r * z, p, fma(-_HALF32, z, _ONE32) if odd else r)
    return -y if (q & 2) else y


@njit(cache=True, **_JIT)
def sin32(x):
    """sin(x) in float32 (x float32 or float64), branch-free; see the single-precision
    notes."""
    r, q = _reduce32(x)
    return _sine_of_reduced32(r, q)


@njit(cache=True, **_JIT)
def cos32(x):
    """cos(x) in float32 through the same reduction (quadrant shifted by one)."""
    r, q = _reduce32(x)
    return _sine_of_reduced32(r, q + 1)


@njit(cache=True, **_JIT)
def sincos32(x):
    """(sin(x), cos(x)) in float32 from one reduction (the same bits as `sin32`,
    `cos32`)."""
    r, q = _reduce32(x)
    return _sine_of_reduced32(r, q), _sine_of_reduced32(r, q + 1)
