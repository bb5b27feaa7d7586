/* The sine designs of the C references (pendulum.c, double_pendulum.c), selected at
 * compile time by -DSIN_VARIANT=n; each defines SIN(x), and SINCOS(x, s, c) gives the
 * sine and the cosine of one argument:
 *
 *   SIN_VARIANT 0  libm's scalar sin (a call per lane, not vectorised)
 *   SIN_VARIANT 1  glibc's vector sin (libmvec, _ZGV*_sin), declared `omp declare simd`
 *   SIN_VARIANT 2  the polynomial sin of sweep/kernels/vecmath.py (magic-number
 *                  quadrant, three-part Cody-Waite reduction by pi/2, fdlibm sin and
 *                  cos polynomials on [-pi/4, pi/4], select by quadrant), inlined:
 *                  the same operations in the same order, so the same accuracy
 *                  (<= ~2.2e-16 absolute for |x| <= 1e4); with FMA contraction the
 *                  roundings differ from sweep's where gcc and LLVM fuse other products
 *   SIN_VARIANT 3  as 2, but the quadrant's two low bits are read from the bits of
 *                  (x * 2/pi + 1.5 * 2**52) instead of converting kf to int64: the
 *                  same quadrant for |x| < 2**51 (where the magic-number rounding is
 *                  valid at all), one integer AND instead of a float -> int64 convert
 *   SIN_VARIANT 4  the polynomial sin of sweep/kernels/vecmath.py since 2026-11-25
 *                  (2 and 3 are its predecessor): quadrant from the bits as 3, the
 *                  reduction by pi/2 in two fused multiply-adds, and one polynomial
 *                  per call, the sine's or the cosine's by quadrant (coefficients
 *                  chosen by selects), evaluated by Estrin's scheme; every
 *                  multiply-add that sweep fuses written as C's fma(), so the same
 *                  operations in the same order whatever -ffp-contract says
 *   SIN_VARIANT 5  one reduction by pi (issue 29): k = round(x / pi) by the magic
 *                  number, r = x - k pi in two fused multiply-adds (pi = PI_HI + PI_LO
 *                  - 3.0e-33: the first FMA is exact, the second rounds once), one odd
 *                  polynomial sin r ~ r + r^3 P(r^2) on [-pi/2, pi/2] and the sign from
 *                  the parity of k (k's low bit is the magic sum's). The polynomial,
 *                  -DSIN_POLY=n, coefficients from benchmarks/fit_sine.py (its error
 *                  with float64 coefficients, in mpmath, on [0, pi/2 + 1e-4]):
 *                    0  Taylor, degree 19 (the kernel)   2.2e-16
 *                    1  Taylor, degree 21                         3.6e-17
 *                    2  minimax, degree 17 (relative error)       2.9e-19
 *                    3  minimax, degree 15                        1.5e-16
 *                  evaluated by Horner's scheme, or by Estrin's with -DESTRIN, or
 *                  with -DHEAD (SIN_POLY 2 only) as sweep/kernels/vecmath.py's sin
 *                  since 2026-11-27: c[1..7] by Estrin's scheme, c[0] added last, the
 *                  sign applied to r beside z instead of to the result (the same
 *                  bits); every multiply-add written as fma()
 *
 * vsincos(x, &s, &c), the sine and the cosine of one argument: variants 0 and 1 call
 * sin and cos (libm's, or libmvec's vector versions); 4 and 5 reduce once by pi/2 as
 * vecmath._reduce does and evaluate the sine's and the cosine's polynomial on r once
 * each (fdlibm's coefficients by Estrin's scheme, every multiply-add written as fma()),
 * then pick and sign them by quadrant: the bits of sweep.kernels.vecmath.sincos up to
 * 2026-11-27 (variant 4's sine and cosine). Since then sweep's sincos returns the bits
 * of its sin (variant 5 -DHEAD) and of its cos (variant 4's), two reductions; with
 * variant 5 this one is faster than that and its sine is not SIN's, which a C limit
 * may do and sweep does not (a kernel reading sin and cos must follow the trajectory
 * of one reading sin alone).
 * Variants 2 and 3 have no vsincos.
 */
#ifndef SWEEP_C_SINES_H
#define SWEEP_C_SINES_H
#include <math.h>
#include <stdint.h>
#include <string.h>

#ifndef SIN_VARIANT
#define SIN_VARIANT 0
#endif

#if SIN_VARIANT >= 2 && SIN_VARIANT <= 5
static const double TWO_OVER_PI = 0.6366197723675814;
static const double MAGIC = 6755399441055744.0;
static const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                    S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                    S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
static const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                    C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                    C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
static const double PIO2_HI = 1.5707963267948966, PIO2_LO = 6.123233995736766e-17;
#endif

#if SIN_VARIANT == 1
#pragma omp declare simd notinbranch
extern double sin(double);
#define SIN(x) sin(x)
#elif SIN_VARIANT == 2 || SIN_VARIANT == 3 || SIN_VARIANT == 4
static const double P1 = 1.570796325802803, P2 = 9.920935739593517e-10,
                    P3 = 5.721188726109832e-18;
#if SIN_VARIANT == 4
/* vecmath._reduce and _sine_of_reduced, operation for operation */
static inline double vsin(double x) {
    const double y = fma(x, TWO_OVER_PI, MAGIC);
    const double kf = y - MAGIC;
    const double r = fma(-kf, PIO2_LO, fma(-kf, PIO2_HI, x));
    int64_t q;
    memcpy(&q, &y, sizeof q);
    const int odd = (q & 1) != 0;
    const double z = r * r, z2 = z * z, z4 = z2 * z2;
    const double c0 = odd ? -0.5 : S1, c1 = odd ? C1 : S2, c2 = odd ? C2 : S3,
                 c3 = odd ? C3 : S4, c4 = odd ? C4 : S5, c5 = odd ? C5 : S6,
                 c6 = odd ? C6 : 0.0;
    const double p = fma(z4, fma(z2, c6, fma(z, c5, c4)),
                         fma(z2, fma(z, c3, c2), fma(z, c1, c0)));
    const double v = fma(odd ? z : z * r, p, odd ? 1.0 : r);
    return (q & 2) ? -v : v;
}
#else
static inline double vsin(double x) {
    const double y = x * TWO_OVER_PI + MAGIC;
    const double kf = y - MAGIC;
    const double r = ((x - kf * P1) - kf * P2) - kf * P3;
#if SIN_VARIANT == 2
    const int64_t q = fabs(kf) < 4.0e15 ? (int64_t)kf : 0;
#else
    int64_t q;
    memcpy(&q, &y, sizeof q); /* y = 1.5 * 2**52 + k: k's low bits are y's */
#endif
    /* vecmath._sin_poly and _cos_poly, operation for operation */
    const double z = r * r;
    const double v3 = z * r;
    const double ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    const double s = r + v3 * (S1 + z * ps);
    const double pc = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    const double hz = 0.5 * z, w = 1.0 - hz;
    const double c = w + (((1.0 - w) - hz) + z * pc);
    const double v = (q & 1) ? c : s;
    return (q & 2) ? -v : v;
}
#endif
#define SIN(x) vsin(x)
#elif SIN_VARIANT == 5
#ifndef SIN_POLY
#define SIN_POLY 2
#endif
static const double INV_PI = 0.3183098861837907;
static const double PI_HI = 3.141592653589793, PI_LO = 1.2246467991473532e-16;
/* P's coefficients c[0] + c[1] z + ...: sin r ~ r + r^3 P(r^2) (benchmarks/fit_sine.py) */
#if SIN_POLY == 0
#define N_POLY 9
static const double CP[N_POLY] = {
    -0.16666666666666666, 0.008333333333333333, -0.0001984126984126984,
    2.7557319223985893e-06, -2.505210838544172e-08, 1.6059043836821613e-10,
    -7.647163731819816e-13, 2.8114572543455206e-15, -8.22063524662433e-18};
#elif SIN_POLY == 1
#define N_POLY 10
static const double CP[N_POLY] = {
    -0.16666666666666666, 0.008333333333333333, -0.0001984126984126984,
    2.7557319223985893e-06, -2.505210838544172e-08, 1.6059043836821613e-10,
    -7.647163731819816e-13, 2.8114572543455206e-15, -8.22063524662433e-18,
    1.9572941063391263e-20};
#elif SIN_POLY == 2
#define N_POLY 8
static const double CP[N_POLY] = {
    -0.16666666666666666, 0.008333333333333207, -0.0001984126984121248,
    2.7557319211569482e-06, -2.505210690442292e-08, 1.6058941002310493e-10,
    -7.643019371886964e-13, 2.7214195512770984e-15};
#elif SIN_POLY == 3
#define N_POLY 7
static const double CP[N_POLY] = {
    -0.16666666666666186, 0.008333333333285474, -0.00019841269825037164,
    2.755731659808175e-06, -2.5051880112963566e-08, 1.6048090271699e-10,
    -7.373280725330603e-13};
#else
#error "SIN_POLY must be 0 .. 3"
#endif
static inline double poly_pi(double z) {
#ifdef ESTRIN
    /* pairs e_i = c[2i] + c[2i+1] z, then z^2, z^4, z^8: depth ~4 instead of N - 1 */
    const double z2 = z * z, z4 = z2 * z2;
    const double e0 = fma(z, CP[1], CP[0]), e1 = fma(z, CP[3], CP[2]),
                 e2 = fma(z, CP[5], CP[4]);
    const double lo = fma(z2, e1, e0);
#if N_POLY == 7
    return fma(z4, fma(z2, CP[6], e2), lo);
#else
    const double e3 = fma(z, CP[7], CP[6]);
    const double p8 = fma(z4, fma(z2, e3, e2), lo);
#if N_POLY == 8
    return p8;
#elif N_POLY == 9
    return fma(z4 * z4, CP[8], p8);
#else
    return fma(z4 * z4, fma(z, CP[9], CP[8]), p8);
#endif
#endif
#else
    double p = CP[N_POLY - 1];
#if N_POLY >= 10
    p = fma(p, z, CP[8]);
#endif
#if N_POLY >= 9
    p = fma(p, z, CP[7]);
#endif
#if N_POLY >= 8
    p = fma(p, z, CP[6]);
#endif
    p = fma(p, z, CP[5]);
    p = fma(p, z, CP[4]);
    p = fma(p, z, CP[3]);
    p = fma(p, z, CP[2]);
    p = fma(p, z, CP[1]);
    return fma(p, z, CP[0]);
#endif
}
#ifdef HEAD
#if N_POLY != 8
#error "-DHEAD needs SIN_POLY 2"
#endif
static inline double vsin(double x) {
    const double y = fma(x, INV_PI, MAGIC);
    const double kf = y - MAGIC;
    const double r = fma(-kf, PI_LO, fma(-kf, PI_HI, x));
    int64_t q;
    memcpy(&q, &y, sizeof q); /* y = 1.5 * 2**52 + k: k's parity is y's low bit */
    const double s = (q & 1) ? -r : r; /* sin is odd: the sign on r, beside z */
    const double z = r * r, z2 = z * z, z4 = z2 * z2;
    const double t = fma(z4, fma(z2, CP[7], fma(z, CP[6], CP[5])),
                         fma(z2, fma(z, CP[4], CP[3]), fma(z, CP[2], CP[1])));
    return fma(s * z, fma(z, t, CP[0]), s);
}
#else
static inline double vsin(double x) {
    const double y = fma(x, INV_PI, MAGIC);
    const double kf = y - MAGIC;
    const double r = fma(-kf, PI_LO, fma(-kf, PI_HI, x));
    int64_t q;
    memcpy(&q, &y, sizeof q); /* y = 1.5 * 2**52 + k: k's parity is y's low bit */
    const double z = r * r;
    const double v = fma(r * z, poly_pi(z), r);
    return (q & 1) ? -v : v;
}
#endif
#define SIN(x) vsin(x)
#else
#define SIN(x) sin(x)
#endif

#if SIN_VARIANT == 0 || SIN_VARIANT == 1
#if SIN_VARIANT == 1
#pragma omp declare simd notinbranch
extern double cos(double);
#endif
static inline void vsincos(double x, double *s, double *c) {
    *s = sin(x);
    *c = cos(x);
}
#elif SIN_VARIANT == 4 || SIN_VARIANT == 5
static inline void vsincos(double x, double *s, double *c) {
    const double y = fma(x, TWO_OVER_PI, MAGIC);
    const double kf = y - MAGIC;
    const double r = fma(-kf, PIO2_LO, fma(-kf, PIO2_HI, x));
    int64_t q;
    memcpy(&q, &y, sizeof q);
    const double z = r * r, z2 = z * z, z4 = z2 * z2;
    const double ps = fma(z4, fma(z, S6, S5), fma(z2, fma(z, S4, S3), fma(z, S2, S1)));
    const double pc = fma(z4, fma(z2, C6, fma(z, C5, C4)),
                          fma(z2, fma(z, C3, C2), fma(z, C1, -0.5)));
    const double sr = fma(z * r, ps, r), cr = fma(z, pc, 1.0);
    const int odd = (q & 1) != 0;
    const double vs = odd ? cr : sr, vc = odd ? sr : cr;
    *s = (q & 2) ? -vs : vs;
    *c = ((q + 1) & 2) ? -vc : vc; /* the cosine is the sine one quadrant on */
}
#endif

/* The design's sine on an array (the benchmarks measure its accuracy): the same inlined
 * code as in the kernels' lanes. */
void sines_sin(int64_t n, const double *x, double *out) {
#pragma omp simd
    for (int64_t i = 0; i < n; i++)
        out[i] = SIN(x[i]);
}
#endif /* SWEEP_C_SINES_H */
