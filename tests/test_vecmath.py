"""The vectorisable sin of `sweep.kernels.vecmath` against NumPy's (glibc's) sin.

Tolerance: 2**-52 = 2.2e-16 absolute, two ulps of values just below 1: the issue's
target for |x| <= 1e4, sweep's sine contract. The bound behind it, for `sin` (one
reduction by pi, since 2026-11-27): the reduction's first fused multiply-add is exact
and its second rounds once, leaving ``r`` (|r| <= pi/2) within half an ulp of ``x - k
pi`` (up to 1.1e-16 for |r| >= 1, times |cos r| <= 0.54 there), the degree-17 minimax
polynomial is accurate to 3e-19, the rounding of ``r z`` and of the polynomial's head
reach at most ~0.3 ulp and its last multiply-add rounds by half an ulp of the result
(5.6e-17): at most ~1.6e-16 from the true sine, and glibc's np.sin is within half an
ulp (5.6e-17) of it. Measured: 2.2e-16 (two ulps of values in [0.5, 1), at about 3 in
1e5 arguments), never more in 2e8 arguments concentrated where |r| is near 1. For
`cos` (the reduction by pi/2 to |r| <= pi/4 and fdlibm's polynomials, as `sin` was
until then): ``r`` within 5.6e-17, polynomials within 2**-58: at most ~1.3e-16;
measured 1.1e-16.
The truncated pi (3.0e-33 per unit of k; pi/2: 1.5e-33) keeps the same bound up to
|x| ~ 1e12 (tested to there, hard spots next to multiples of pi/2 included); past ~1e13
the rounded ``x / pi`` may pick the neighbouring multiple and the error grows (tested
as a bound, not as a claim of accuracy).
"""

import numpy as np
import pytest
from numba import njit, prange, vectorize

from sweep import _config
from sweep.kernels import vecmath as _vecmath

TOL = 2.0 ** -52


# called as the kernels call it, from a loop with their fast-math flags (none since
# 2026-11-25; the sine is compiled with them too, its FMAs written out); `_vsin_contract`
# is a caller that lets LLVM fuse its own multiply-adds
KERNEL_FLAGS = set(_config.FASTMATH)


@njit(parallel=True, cache=True, fastmath=KERNEL_FLAGS)
def _vsin(x):
    out = np.empty_like(x)
    for i in prange(x.size):
        out[i] = _vecmath.sin(x[i])
    return out


@njit(parallel=True, cache=True, fastmath={"contract"})
def _vsin_contract(x):
    out = np.empty_like(x)
    for i in prange(x.size):
        out[i] = _vecmath.sin(x[i])
    return out


@njit(parallel=True, cache=True, fastmath=KERNEL_FLAGS)
def _vcos(x):
    out = np.empty_like(x)
    for i in prange(x.size):
        out[i] = _vecmath.cos(x[i])
    return out


def _max_error(x, f=_vsin, ref=np.sin):
    return float(np.max(np.abs(f(x) - ref(x))))


def _neighbours(x, n=4):
    """x and its n floating-point neighbours on each side."""
    parts = [x]
    up, down = x.copy(), x.copy()
    for _ in range(n):
        up, down = np.nextafter(up, np.inf), np.nextafter(down, -np.inf)
        parts += [up, down]
    return np.concatenate(parts)


def test_uniform_random_up_to_1e4(rng):
    x = rng.uniform(-1e4, 1e4, 4_000_000)
    assert _max_error(x) <= TOL
    assert _max_error(x, _vcos, np.cos) <= TOL


def test_all_magnitudes_up_to_1e4(rng):
    # log-uniform magnitudes from 1e-300 to 1e4, both signs
    x = 10.0 ** rng.uniform(-300, 4, 2_000_000) * rng.choice([-1.0, 1.0], 2_000_000)
    assert _max_error(x) <= TOL
    # relative accuracy for small arguments, where sin x ~ x
    small = x[np.abs(x) < 1e-3]
    assert np.all(np.abs(_vsin(small) - np.sin(small)) <= 2.3e-16 * np.abs(small))


@pytest.mark.parametrize("fraction", [2, 4])
def test_multiples_of_pi_over_2_and_4(fraction):
    """k pi/2 (sin or cos is ~1e-16 there: the reduction must cancel exactly) and
    k pi/4 (the edge of the polynomials' interval), with 4 neighbours each side."""
    k = np.arange(-int(1e4 * fraction / np.pi) - 1, int(1e4 * fraction / np.pi) + 2)
    x = _neighbours(k * (np.pi / fraction))
    x = x[np.abs(x) <= 1e4]
    assert _max_error(x) <= TOL
    assert _max_error(x, _vcos, np.cos) <= TOL


def test_near_zero_relative():
    x = _neighbours(np.array([np.pi, -np.pi, 2 * np.pi, 1e4 * np.pi / 2]), 64)
    got, want = _vsin(x), np.sin(x)
    # sin is ~1e-16 .. 1e-12 here: the error must be small relative to the value too.
    # The reduction's first FMA gives x - k PIO2_HI exactly, the second adds -k PIO2_LO
    # with one rounding relative to the result's own size, and the truncated pi/2 costs
    # |k| 1.5e-33: 2 ulp of the value is a bound with margin.
    assert np.all(np.abs(got - want) <= 4.5e-16 * np.abs(want))


def test_exactly_representable_multiples():
    """Integers, halves, quarters and dyadic steps: arguments whose reduction is most
    often got wrong by a reduction with too few bits of pi/2."""
    x = np.concatenate([np.arange(-10_000, 10_001, dtype=float),
                        np.arange(-20_000, 20_001) / 2.0,
                        np.arange(-40_000, 40_001) / 4.0,
                        np.arange(-2**20, 2**20) / 2.0**10,
                        2.0 ** np.arange(-1074, 14)])
    assert _max_error(x) <= TOL
    assert _max_error(x, _vcos, np.cos) <= TOL


def test_tiny_arguments():
    x = np.concatenate([[5e-324, 1e-320, 2.2250738585072014e-308, 1e-200, 1e-20, 1e-8],
                        10.0 ** np.linspace(-300, -3, 10_000)])
    x = np.concatenate([x, -x])
    got = _vsin(x)
    assert np.all(np.abs(got - np.sin(x)) <= 2.3e-16 * np.abs(x))
    assert np.all(_vcos(x) == np.cos(x))


def test_beyond_1e4_up_to_1e12(rng):
    x = np.concatenate([rng.uniform(-1e6, 1e6, 2_000_000),
                        rng.uniform(-1e8, 1e8, 1_000_000),
                        10.0 ** rng.uniform(8, 12, 1_000_000) * rng.choice([-1.0, 1.0], 1_000_000)])
    assert _max_error(x) <= TOL
    assert _max_error(x, _vcos, np.cos) <= TOL
    # hard spots out there: multiples of pi/2 up to 1e6 and their neighbours
    k = np.arange(int(1e4 * 2 / np.pi), int(1e6 * 2 / np.pi), 7)
    x = _neighbours(k * (np.pi / 2), 2)
    assert _max_error(x) <= TOL


def test_past_1e12_the_error_stays_below_1e_13_up_to_3e15(rng):
    """Documented degradation, not accuracy: past ~1e13 the rounded ``x / pi`` (off by
    up to |x| 2**-53) may choose the neighbouring multiple of pi, so the polynomial
    runs a little past |r| = pi/2, outside its interval (measured: 1.1e-15 up to 3e15;
    1.9e-14 with the reduction by pi/2 of the sine before 2026-11-27); 1e-13 bounds it
    with margin. Past 2**51 pi ~ 7e15 the magic-number rounding fails and the values
    are not sines (the module docstring)."""
    x = 10.0 ** rng.uniform(12, np.log10(3e15), 1_000_000)
    err = np.abs(_vsin(x) - np.sin(x))
    assert np.all(err <= 1e-13)


def test_nan_and_inf_propagate():
    x = np.array([np.nan, np.inf, -np.inf, -np.nan])
    assert np.all(np.isnan(_vsin(x)))
    assert np.all(np.isnan(_vcos(x)))
    assert np.array_equal(_vsin(np.array([0.0, -0.0])), [0.0, 0.0])



def test_a_caller_with_fma_contraction_gets_the_same_bits(rng):
    """The sine's fused multiply-adds are explicit (`vecmath.fma`) and its own code has
    no fast-math flags, so a caller that lets LLVM contract its own products gets the
    same bits, on random arguments and next to multiples of pi/2."""
    x = np.concatenate([rng.uniform(-1e4, 1e4, 10**6),
                        _neighbours(np.arange(-6366, 6367) * (np.pi / 2))])
    np.testing.assert_array_equal(_vsin_contract(x), _vsin(x))
    assert _max_error(x, f=_vsin_contract) <= TOL


@njit(parallel=True, cache=True, fastmath=KERNEL_FLAGS)
def _vsincos(x):
    s = np.empty_like(x)
    c = np.empty_like(x)
    for i in prange(x.size):
        s[i], c[i] = _vecmath.sincos(x[i])
    return s, c


def test_sincos_is_sin_and_cos_from_one_reduction(rng):
    """sincos gives exactly the bits of sin and cos (the same reduction and
    polynomials), so a kernel reading both is as accurate as each, and against NumPy
    within TOL on every quadrant, multiples of pi/2 and large arguments."""
    x = np.concatenate([rng.uniform(-1e4, 1e4, 200_000), np.arange(-64, 65) * np.pi / 4,
                        rng.uniform(-1e8, 1e8, 1000), [0.0, -0.0]])
    s, c = _vsincos(x)
    np.testing.assert_array_equal(s, _vsin(x))
    np.testing.assert_array_equal(c, _vcos(x))
    assert np.max(np.abs(s - np.sin(x))) <= TOL
    assert np.max(np.abs(c - np.cos(x))) <= TOL


@njit(parallel=True, cache=True, fastmath=KERNEL_FLAGS)
def _vsincos_quadrant(x):
    s = np.empty_like(x)
    c = np.empty_like(x)
    for i in prange(x.size):
        s[i], c[i] = _vecmath.sincos_quadrant(x[i])
    return s, c


def test_sincos_quadrant_keeps_the_contract_from_one_reduction(rng):
    """The systems' sincos (one reduction by pi/2, both fdlibm polynomials): its cosine
    is exactly `cos`'s bits (the same reduction and polynomial), and both halves are
    within TOL of NumPy's on every quadrant, next to multiples of pi/2 (where the
    reduction cancels most), at large arguments up to SIN_RANGE and at zero; its sine
    is not `sin`'s (it differs in last bits somewhere, which is why the single
    pendulum's tangent dynamics keep `sincos`)."""
    near = _neighbours(np.arange(-6366, 6367) * (np.pi / 2))
    x = np.concatenate([rng.uniform(-1e4, 1e4, 1_000_000), near,
                        rng.uniform(-_vecmath.SIN_RANGE, _vecmath.SIN_RANGE, 100_000),
                        [0.0, -0.0, 1e-300]])
    s, c = _vsincos_quadrant(x)
    np.testing.assert_array_equal(c, _vcos(x))
    assert np.max(np.abs(s - np.sin(x))) <= TOL
    assert np.max(np.abs(c - np.cos(x))) <= TOL
    assert np.any(s != _vsin(x))


# ------------------------------------------------------------------ float32 (dtype="float32")
@njit(parallel=True, cache=True, fastmath=KERNEL_FLAGS)
def _float32_sines(x):
    """sin32, cos32 and both halves of sincos32 of every element (float32 arrays)."""
    out = np.empty((4, x.size), dtype=np.float32)
    for i in prange(x.size):
        out[0, i] = _vecmath.sin32(x[i])
        out[1, i] = _vecmath.cos32(x[i])
        out[2, i], out[3, i] = _vecmath.sincos32(x[i])
    return out


#: float32's sine: 2 float32 ulps of 1 (2 x 2**-23 / 2 = 1.2e-7). The reduction is
#: done in float64 (its error below 1e-9 up to |x| ~ 1e8, see vecmath's notes), the
#: reduced argument is rounded once to float32 (half an ulp of r, <= 4.7e-8 on
#: [-pi/4, pi/4]), Cephes' polynomials add about an ulp, and the float32 result is
#: rounded once more: about 1.5 ulp in all. Measured: 9.3e-8 (NumPy's own float32
#: sine: 6.2e-8).
TOL32 = 1.2e-7


def test_float32_sine_up_to_1e4_and_beyond(rng):
    """float64 arguments (the kernels' angles and drive phases) and float32 ones, up
    to 1e4, 1e6 and 1e8, and next to multiples of pi/2: the same absolute bound, with
    no growth in |x| (the reduction is float64)."""
    x = np.concatenate([rng.uniform(-1e4, 1e4, 2_000_000),
                        rng.uniform(-1e6, 1e6, 500_000), rng.uniform(-1e8, 1e8, 500_000),
                        _neighbours(np.arange(-6366, 6367) * (np.pi / 2)),
                        10.0 ** rng.uniform(-30, 0, 100_000)])
    sines = _float32_sines(x)
    assert np.max(np.abs(sines[0] - np.sin(x))) <= TOL32
    assert np.max(np.abs(sines[1] - np.cos(x))) <= TOL32
    x32 = x.astype(np.float32)
    wide = x32.astype(np.float64)
    assert np.max(np.abs(_float32_sines(x32)[0] - np.sin(wide))) <= TOL32


def test_float32_sincos_is_sin32_and_cos32():
    sines = _float32_sines(np.linspace(-1e3, 1e3, 200_001))
    np.testing.assert_array_equal(sines[2], sines[0])
    np.testing.assert_array_equal(sines[3], sines[1])


def test_float32_nan_and_inf_propagate():
    assert np.all(np.isnan(_float32_sines(np.array([np.nan, np.inf, -np.inf]))))


# ------------------------------------------------------------------ the controller's root
#: the controller's root as a ufunc (its vectorisation inside the kernel is what
#: benchmarks/work_precision.py measures)
_vroot5 = vectorize(["float64(float64)"], cache=True)(_vecmath.inverse_fifth_root.py_func)


def test_inverse_fifth_root_is_libms_power_to_rounding(rng):
    """err ** -0.2 of the adaptive controller over its whole range (1e-6 .. 1e4, the
    clipping bounds of its factor beyond): within 3 ulp of NumPy's power, 6.7e-16
    relative (measured 4.4e-16 after four Newton steps from the bits' guess; the
    controller needs far less, this keeps its choices libm's); clamped outside, where
    the controller clips the factor anyway; vectorised (no libm call) by construction."""
    x = np.concatenate([np.geomspace(1e-6, 1e4, 1_000_001), 10 ** rng.uniform(-6, 4, 10**5)])
    np.testing.assert_allclose(_vroot5(x), x ** -0.2, rtol=3 * 2.0 ** -52, atol=0)
    np.testing.assert_allclose(_vroot5(np.array([0.0, 1e-9, 1e9, 1e300])),
                               [1e-6 ** -0.2, 1e-6 ** -0.2, 1e4 ** -0.2, 1e4 ** -0.2],
                               rtol=1e-12)
