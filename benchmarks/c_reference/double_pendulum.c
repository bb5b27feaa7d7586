/* C reference for sweep's double-pendulum kernel (sweep.DoublePendulum, without
 * damping): the same algorithm, written for the hardware.
 *
 * Two point masses m1, m2 on massless rods l1, l2 under gravity g; theta1, theta2 from
 * the downward vertical (theta2 absolute). The accelerations are sweep's derived ones
 * (sweep.physics.derive: the mass matrix solved by Cramer's rule, the determinant
 * inverted once), with d = theta1 - theta2, s = sin d, c = cos d:
 *
 *   x1 = -l2 m2 g sin(theta2) + l1 l2 m2 s omega1^2
 *   x5 = -l1 l2 m2 s omega2^2 - (m1 + m2) g l1 sin(theta1)
 *   x7 = 1 / (l1^2 l2^2 m2 (m1 + m2 - m2 c^2))
 *   theta1'' = x7 (l2^2 m2 x5 - l1 l2 m2 c x1)
 *   theta2'' = x7 ((m1 + m2) l1^2 x1 - l1 l2 m2 c x5)
 *
 * All trajectories of a call share (m1, m2, l1, l2, g), as in a (theta1, theta2) grid,
 * so every product of parameters alone is computed once per call, outside the loops
 * (sweep's kernel reads the parameters per lane and multiplies them at every stage).
 * Classical RK4 with sweep's fused operations (k2 = om + dt/2 k1 as fma(dt/2, k1, om),
 * the update as fma(dt/6, fma(2, k3, fma(2, k2, k1)) + k4, x)), written as fma().
 *
 * Layout: OpenMP threads take blocks of BLOCK trajectories; within a block the time
 * loop is outside and the lane loop inside (`omp simd`), so the trajectories fill the
 * SIMD lanes. The sines come from sines.h (-DSIN_VARIANT=0, 1, 4 or 5; 5 also takes
 * -DSIN_POLY=n and -DESTRIN): sin(theta1) and sin(theta2) by the design's SIN, and the
 * sine and cosine of d from one reduction (vsincos).
 *
 * Build (benchmarks/double_pendulum.py does this and sweeps the options):
 *   gcc -O3 -march=native -fopenmp -shared -fPIC [-mprefer-vector-width=512]
 *       [-ffp-contract=fast|off] [-DSIN_VARIANT=n] [-DSIN_POLY=n] [-DESTRIN]
 *       [-DBLOCK=n] double_pendulum.c -o lib.so -lm
 * Never -ffast-math (see pendulum.c).
 */
#include <stdint.h>

#ifndef BLOCK
#define BLOCK 512
#endif

#include "sines.h"

#if SIN_VARIANT == 2 || SIN_VARIANT == 3
#error "double_pendulum.c takes SIN_VARIANT 0, 1, 4 or 5 (2 and 3 have no vsincos)"
#endif

/* The products of parameters alone, computed once per call. */
struct constants {
    double m2, mass, gl2m2, l1l2m2, gml1, det, l2l2m2, ml1l1;
};

struct accel {
    double a1, a2;
};

static inline __attribute__((always_inline)) struct accel
accel(double th1, double th2, double om1, double om2, const struct constants *k) {
    double s, c;
    vsincos(th1 - th2, &s, &c);
    const double p = k->l1l2m2 * s, q = k->l1l2m2 * c;
    const double x1 = p * om1 * om1 - k->gl2m2 * SIN(th2);
    const double x5 = -(p * om2) * om2 - k->gml1 * SIN(th1);
    const double x7 = 1.0 / (k->det * (k->mass - k->m2 * c * c));
    const struct accel a = {x7 * (k->l2l2m2 * x5 - q * x1), x7 * (k->ml1l1 * x1 - q * x5)};
    return a;
}

/* Integrate n trajectories from (th1_0[i], th2_0[i], om1_0[i], om2_0[i]) for n_steps
 * steps of dt; write the final state to th1, th2, om1, om2. */
void dp_rk4(int64_t n, const double *th1_0, const double *th2_0, const double *om1_0,
            const double *om2_0, double m1, double m2, double l1, double l2, double g,
            double dt, int64_t n_steps, double *th1_out, double *th2_out, double *om1_out,
            double *om2_out) {
    const struct constants k = {
        .m2 = m2, .mass = m1 + m2, .gl2m2 = l2 * m2 * g, .l1l2m2 = l1 * l2 * m2,
        .gml1 = (m1 + m2) * g * l1, .det = l2 * l2 * (l1 * l1) * m2,
        .l2l2m2 = l2 * l2 * m2, .ml1l1 = (m1 + m2) * (l1 * l1)};
    const double dt_2 = dt / 2.0, dt_6 = dt / 6.0;
    const int64_t n_blocks = (n + BLOCK - 1) / BLOCK;
#pragma omp parallel for schedule(static)
    for (int64_t b = 0; b < n_blocks; b++) {
        const int64_t start = b * BLOCK;
        const int64_t m = n - start < BLOCK ? n - start : BLOCK;
        double th1[BLOCK] __attribute__((aligned(64)));
        double th2[BLOCK] __attribute__((aligned(64)));
        double om1[BLOCK] __attribute__((aligned(64)));
        double om2[BLOCK] __attribute__((aligned(64)));
        /* a partial block's padding lanes repeat its last trajectory (finite data) */
        for (int64_t j = 0; j < BLOCK; j++) {
            const int64_t i = start + (j < m ? j : m - 1);
            th1[j] = th1_0[i];
            th2[j] = th2_0[i];
            om1[j] = om1_0[i];
            om2[j] = om2_0[i];
        }
        for (int64_t step = 0; step < n_steps; step++) {
#pragma omp simd aligned(th1, th2, om1, om2 : 64)
            for (int64_t j = 0; j < BLOCK; j++) {
                const double x = th1[j], y = th2[j], u = om1[j], v = om2[j];
                const struct accel k1 = accel(x, y, u, v, &k);
                const double k2x = fma(dt_2, k1.a1, u), k2y = fma(dt_2, k1.a2, v);
                const struct accel k2 = accel(fma(dt_2, u, x), fma(dt_2, v, y), k2x, k2y, &k);
                const double k3x = fma(dt_2, k2.a1, u), k3y = fma(dt_2, k2.a2, v);
                const struct accel k3 = accel(fma(dt_2, k2x, x), fma(dt_2, k2y, y), k3x, k3y,
                                              &k);
                const double k4x = fma(dt, k3.a1, u), k4y = fma(dt, k3.a2, v);
                const struct accel k4 = accel(fma(dt, k3x, x), fma(dt, k3y, y), k4x, k4y, &k);
                th1[j] = fma(dt_6, fma(2.0, k3x, fma(2.0, k2x, u)) + k4x, x);
                th2[j] = fma(dt_6, fma(2.0, k3y, fma(2.0, k2y, v)) + k4y, y);
                om1[j] = fma(dt_6, fma(2.0, k3.a1, fma(2.0, k2.a1, k1.a1)) + k4.a1, u);
                om2[j] = fma(dt_6, fma(2.0, k3.a2, fma(2.0, k2.a2, k1.a2)) + k4.a2, v);
            }
        }
        for (int64_t j = 0; j < m; j++) {
            th1_out[start + j] = th1[j];
            th2_out[start + j] = th2[j];
            om1_out[start + j] = om1[j];
            om2_out[start + j] = om2[j];
        }
    }
}

/* The build's sine-cosine pair on arrays (double_pendulum.py measures its accuracy;
 * sines.h's sines_sin gives the sine): the same inlined code as in the kernel's lanes. */
void dp_sincos(int64_t n, const double *x, double *s_out, double *c_out) {
#pragma omp simd
    for (int64_t i = 0; i < n; i++) {
        double s, c;
        vsincos(x[i], &s, &c);
        s_out[i] = s;
        c_out[i] = c;
    }
}

int64_t dp_block(void) { return BLOCK; }
