"""A vectorisable ``sin`` for numba kernels: the sine of every sweep kernel.

numba >= 0.62 has no SVML, so ``math.sin``/``np.sin`` in a numba loop is a scalar call
into libm and the loop is never vectorised. `sin` here is straight-line arithmetic
(no calls, no data-dependent branches), so LLVM can put one trajectory in each SIMD
lane when the kernel's lane loop is innermost; and its dependency chain is short, so
one trajectory alone (whose steps wait on each other's sines) runs fast too.

Algorithm of `sin` (since 2026-11-27, sweep 0.3.0.dev1; issue 38)
--------------------------------------------------------------
1. ``y = x / pi + 1.5 * 2**52`` (one `fma`) rounds ``x / pi`` to the integer ``k``
   ("magic number"; valid for ``|x / pi| < 2**51``; needs IEEE evaluation order, i.e.
   no ``reassoc`` fast-math flag): ``kf = y - 1.5 * 2**52`` exactly, and the low bit
   of ``y``'s IEEE pattern is ``k``'s parity, so no float-to-integer conversion.
2. Cody-Waite reduction by pi in two fused multiply-adds (`fma`, LLVM's ``llvm.fma``:
   one rounding, whatever the fast-math flags or the CPU), ``r = fma(-kf, PI_LO,
   fma(-kf, PI_HI, x))`` with ``pi = PI_HI + PI_LO - 3.0e-33``: the first FMA is exact,
   the second rounds once, so ``r`` (|r| <~ pi/2) is within half an ulp of ``x - k
   pi`` but for the truncated pi, ``|k| * 3e-33``. Up to |x| ~ 1e12 that is all
   (tested); past it the rounded ``x / pi`` may choose the neighbouring multiple, |r|
   exceeds pi/2 a little and the error grows slowly (1.1e-15 measured up to 3e15);
   past ``2**51 pi ~ 7e15`` the magic number fails and the results are not sines.
3. ``sin x = (-1)**k sin r``, one odd polynomial on |r| <= pi/2: ``s + s z (M1 + z
   T(z))`` with ``z = r^2``, ``s = -r`` for odd ``k`` else ``r`` (a select beside
   ``z``: sin is odd and ``fma(-a, b, -c) = -fma(a, b, c)``, so this gives the bits of
   negating the result, off the critical path), the minimax coefficients of degree 17
   of ``benchmarks/fit_sine.py`` (2.9e-19 in mpmath) and ``T = M2 + ... + M8 z^6`` by
   Estrin's scheme (pairs, then ``z^2``, ``z^4``), ``M1`` added last as by Horner:
   T is below 0.0084, so its roundings reach the sine at most ``z r z < 10`` times
   over, below 3e-17, while the roundings that matter (the last two multiply-adds) are
   Horner's. No select between polynomials, no quadrant arithmetic.

Measured on this project's Zen 5 (``benchmarks/sine_designs.py``,
``docs/guide/performance.md``): 41 cycles from argument to result, as the previous
design (the reduction by pi/2, the sine's or the cosine's fdlibm polynomial on
[-pi/4, pi/4] chosen by quadrant with seven selects: 40), so one trajectory alone is
as fast; vectorised about 1.45x the sines per second (no selects). Error: at most
2**-52 = 2.2e-16 from ``np.sin`` (two ulps of values in [0.5, 1), at about 3 in 1e5
arguments with |r| near 1; the previous design: 1.1e-16) for |x| <= 1e12, within the
contract of ``tests/test_vecmath.py``, whose bounds did not change. Horner's scheme
for the whole polynomial (the C limit's sine in ``benchmarks/run_all.py``) has the
same error and 56 cycles of latency; Estrin's for the whole polynomial rounds ``M1``
three times and misses the contract (3 ulps).

`cos` keeps the reduction by pi/2 (`_reduce`: ``k = round(x 2/pi)``, ``r = x - k
pi/2`` in two FMAs, |r| <= pi/4, quadrant ``k mod 4`` from the bits of the magic sum)
and fdlibm's polynomials (``__kernel_sin``/``__kernel_cos``, error < 2**-58 on
[-pi/4, pi/4]), the cosine's on even quadrants and the sine's on odd ones, chosen by
selects and evaluated by Estrin's scheme (`_sine_of_reduced`): its error stays 1.1e-16
and ``cos`` of a tiny ``x`` is exactly 1, as ``np.cos`` (a cosine through the
reduction by pi reaches 1 from the polynomial near pi/2 and misses it by an ulp at
about 1 % of those arguments). `sincos` returns the bits of both, from their two
reductions: a kernel that reads ``sin`` and ``cos`` of an angle (the tangent
dynamics) must follow the trajectory of a kernel that reads ``sin`` alone, bit for bit.
The results of every kernel whose sine changed moved in their last bits with the
change (sweep 0.3.0.dev1: a checkpoint of an earlier version is not resumed); they are
the same on every machine with FMA
(``tests/test_vector_width.py``: Zen 4, Skylake-X at 256 and 512 bits and Haswell
targets, emulated).

Compiled on its own with the kernels' fast-math flags (none since 2026-11-25: its
fused multiply-adds are written as `fma`, so its bits do not depend on what LLVM
would fuse; never ``reassoc``, which would break the reduction), and inlined into the
kernels by LLVM, where the lane loop is vectorised. Not marked ``inline="always"`` for
numba: inlining its IR into every stage of a kernel doubled the compile time, for the
same speed.

NaN and +-inf give NaN (``inf - inf`` in the reduction). The sign of zero is not kept
(``sin(-0.0)`` gives ``+0.0``), as under the ``nsz`` fast-math flag anyway.
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
           "inverse_fifth_root", "sin", "sin32", "sincos", "sincos32",
           "sincos_quadrant"]

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
INV_PI = 0.3183098861837907
#: pi = PI_HI + PI_LO (- 3.0e-33): `sin`'s reduction by pi, in two parts.
PI_HI = 3.141592653589793         # 0x1.921fb54442d18p+1
PI_LO = 1.2246467991473532e-16    # 0x1.1a62633145c07p-53
#: Largest |x| [rad] up to which `sin`/`cos` are guaranteed as accurate as libm's
#: (within 2**-52, tested to there; past ~1e13 the rounded multiple of pi or pi/2 may
#: slip; past 3.5e15 `cos`'s values, past 7e15 `sin`'s, are not cosines or sines): the
#: kernels refuse starts beyond it and flag a trajectory
#: whose angle ends beyond it (`sweep.kernels.Status.ANGLE_OUT_OF_RANGE`).
SIN_RANGE = 1e12
#: The same for `sin32`/`cos32` and the GPU's float32 sine (their ``P1``/``P2``
#: reduction is exact and its dropped rest below 1e-9 up to |x| ~ 1e8; tested to there).
SIN32_RANGE = 1e8

#: sin r ~ r + r^3 (M1 + M2 r^2 + ... + M8 r^14) on |r| <= pi/2 + 1e-4: the minimax fit
#: of the relative error, degree 17 (``benchmarks/fit_sine.py``; with these float64
#: coefficients 2.9e-19, in mpmath): `sin`'s polynomial.
M1 = -0.16666666666666666
M2 = 0.008333333333333207
M3 = -0.0001984126984121248
M4 = 2.7557319211569482e-06
M5 = -2.505210690442292e-08
M6 = 1.6058941002310493e-10
M7 = -7.643019371886964e-13
M8 = 2.7214195512770984e-15

# fdlibm __kernel_sin / __kernel_cos minimax coefficients on [-pi/4, pi/4] (`cos`)
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
def _odd_polynomial(r, s):
    """sin(r) for |r| <= pi/2 (+1e-4), times the sign of ``s`` (``s`` is ``r`` or
    ``-r``): ``s + s z (M1 + z T)`` with ``z = r^2`` and ``T = M2 + M3 z + ... + M8
    z^6`` by Estrin's scheme (pairs, then ``z^2``, ``z^4``). T is below 0.0084, so
    its roundings reach the sine at most ``z r z < 10`` times over, below 3e-17; M1
    is added last, as by Horner, and the last multiply-add rounds once. The sign: sin
    is odd and ``fma(-a, b, -c) = -fma(a, b, c)`` exactly, so negating ``r`` (beside
    ``z``, off the critical path) gives the bits of negating the result."""
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    t = fma(z4, fma(z2, M8, fma(z, M7, M6)), fma(z2, fma(z, M5, M4), fma(z, M3, M2)))
    return fma(s * z, fma(z, t, M1), s)


@njit(cache=True, **_JIT)
def sin(x):
    """sin(x) in float64, branch-free (vectorisable): one reduction by pi, one odd
    polynomial; within 2**-52 of libm's for |x| <= 1e12 (`SIN_RANGE`)."""
    y = fma(x, INV_PI, _MAGIC)
    kf = y - _MAGIC
    r = fma(-kf, PI_LO, fma(-kf, PI_HI, x))
    return _odd_polynomial(r, -r if (_bits_of(y) & 1) else r)


@njit(cache=True, **_JIT)
def cos(x):
    """cos(x): the reduction by pi/2, then on even quadrants fdlibm's cosine polynomial,
    on odd ones its sine polynomial (`_sine_of_reduced`, one quadrant on)."""
    r, q = _reduce(x)
    return _sine_of_reduced(r, q + 1)


@njit(cache=True, **_JIT)
def sincos(x):
    """(sin(x), cos(x)): the bits of `sin` and `cos` (a kernel reading both, such as
    the tangent dynamics of `sweep.kernels` or the double pendulum's ``sin``/``cos``
    of theta1 - theta2, follows the trajectory of a kernel reading `sin` alone, bit
    for bit); two reductions, by pi and by pi/2."""
    return sin(x), cos(x)


@njit(cache=True, **_JIT)
def sincos_quadrant(x):
    """(sin(x), cos(x)) from one reduction by pi/2: the systems' ``vsincos``.

    The reduction of `cos` (`_reduce`), then fdlibm's sine and cosine polynomials on
    ``r`` once each, picked and signed by quadrant (the C limit's ``vsincos`` in
    ``benchmarks/c_reference/sines.h``, variant 4). The cosine is `cos`'s bits; the
    sine is the previous design's (sweep < 0.3.0.dev1), not `sin`'s: within 1.1e-16
    of libm's either way (the same contract, ``tests/test_vecmath.py``), one reduction
    and two short polynomials instead of `sincos`'s two reductions. Only the systems'
    kernels (`sweep.kernels.system`) call it, where a state's accelerations read the
    sine and the cosine of one argument (the double pendulum's theta1 - theta2) and
    the tangent dynamics read the accelerations' own statements, so their trajectory
    is the plain kernel's bit for bit; the single pendulum's tangent dynamics use
    `sincos` (its plain kernel reads `sin` alone)."""
    r, q = _reduce(x)
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    ps = fma(z4, fma(z, S6, S5), fma(z2, fma(z, S4, S3), fma(z, S2, S1)))
    pc = fma(z4, fma(z2, C6, fma(z, C5, C4)), fma(z2, fma(z, C3, C2), fma(z, C1, -0.5)))
    sr = fma(z * r, ps, r)
    cr = fma(z, pc, 1.0)
    odd = (q & 1) != 0
    s = cr if odd else sr
    c = sr if odd else cr
    return (-s if (q & 2) else s), (-c if ((q + 1) & 2) else c)


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
