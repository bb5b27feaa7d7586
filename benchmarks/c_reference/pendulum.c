/* C reference for sweep's RK4 kernel: the same algorithm, written for the hardware.
 *
 *   theta'' = A sin(W t + phi) - c theta' - w0sq sin(theta)      (LINEAR: theta)
 *
 * Classical RK4 with exactly sweep's operations and forcing-time convention: time of
 * step n is t_n = t0 + n*dt (never accumulated); the forcing is evaluated at t_n,
 * t_n + dt/2 and t_{n+1} = t0 + (n+1)*dt, and f(t_{n+1}) is carried to the next step.
 * All trajectories of a call share (w0sq, c, A, W, phi), as in a (theta0, omega0) grid,
 * so the forcing is computed once per step for a whole block of trajectories.
 *
 * Layout: OpenMP threads take blocks of BLOCK trajectories; within a block the time
 * loop is outside and the lane loop inside (`omp simd`), so the trajectories fill
 * the SIMD lanes.  The sine of theta is selected at compile time:
 *
 *   SIN_VARIANT 0  libm's scalar sin (default; a call per lane, not vectorised)
 *   SIN_VARIANT 1  glibc's vector sin (libmvec, _ZGV*_sin), declared `omp declare simd`
 *   SIN_VARIANT 2  the polynomial sin of sweep/_vecmath.py (Cody-Waite + fdlibm
 *                  polynomials), inlined
 *
 * Build (the benchmark does this):
 *   gcc -O3 -march=native -fopenmp -shared -fPIC -ffp-contract=off [-DSIN_VARIANT=n]
 *       [-DLINEAR] pendulum.c -o lib.so -lm
 * No -ffast-math, and -ffp-contract=off: the operations and their order are exactly
 * sweep's (numba without fastmath does not contract a*b+c into an FMA), so with
 * SIN_VARIANT 0 the results are sweep's to the last bit. Without -ffp-contract=off
 * gcc contracts under -march=native and results differ in the last bits, which a
 * chaotic trajectory amplifies.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#ifndef SIN_VARIANT
#define SIN_VARIANT 0
#endif
#ifndef BLOCK
#define BLOCK 512
#endif

#if SIN_VARIANT == 1
#pragma omp declare simd notinbranch
extern double sin(double);
#define SIN(x) sin(x)
#elif SIN_VARIANT == 2
static inline double vsin(double x) {
    const double TWO_OVER_PI = 0.6366197723675814;
    const double P1 = 1.570796325802803, P2 = 9.920935739593517e-10,
                 P3 = 5.721188726109832e-18, MAGIC = 6755399441055744.0;
    const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                 S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                 S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
    const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                 C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                 C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
    double kf = (x * TWO_OVER_PI + MAGIC) - MAGIC;
    double r = ((x - kf * P1) - kf * P2) - kf * P3;
    int64_t q = fabs(kf) < 4.0e15 ? (int64_t)kf : 0;
    double z = r * r;
    double s = r + (z * r) * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    double p = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    double hz = 0.5 * z, w = 1.0 - hz;
    double c = w + (((1.0 - w) - hz) + z * p);
    double v = (q & 1) ? c : s;
    return (q & 2) ? -v : v;
}
#define SIN(x) vsin(x)
#else
#define SIN(x) sin(x)
#endif

#ifdef LINEAR
#define RESTORING(th) (th)
#else
#define RESTORING(th) SIN(th)
#endif

#define ACCEL(th, om, f) (-w0sq * RESTORING(th) - c * (om) + (f))

/* Integrate n trajectories from (th0[i], om0[i]) for n_steps steps; write the final
 * state to th_out, om_out. */
void pendulum_rk4(int64_t n, const double *th0, const double *om0, double w0sq,
                  double c, double A, double W, double phi, double t0, double dt,
                  int64_t n_steps, double *th_out, double *om_out) {
    const double cdt1 = dt * 0.5, dt_2 = dt / 2.0, dt_6 = dt / 6.0;
    const int64_t n_blocks = (n + BLOCK - 1) / BLOCK;
#pragma omp parallel for schedule(static)
    for (int64_t b = 0; b < n_blocks; b++) {
        const int64_t start = b * BLOCK;
        const int64_t m = n - start < BLOCK ? n - start : BLOCK;
        double th[BLOCK], om[BLOCK];
        for (int64_t j = 0; j < m; j++) {
            th[j] = th0[start + j];
            om[j] = om0[start + j];
        }
        /* pad a partial block so every lane runs the same code on finite data */
        for (int64_t j = m; j < BLOCK; j++) {
            th[j] = 0.0;
            om[j] = 0.0;
        }
        double f0 = A * sin(W * t0 + phi);
        for (int64_t step = 0; step < n_steps; step++) {
            const double f1 = A * sin(W * (t0 + (double)step * dt + cdt1) + phi);
            const double f2 = A * sin(W * (t0 + (double)(step + 1) * dt) + phi);
#pragma omp simd
            for (int64_t j = 0; j < BLOCK; j++) {
                const double x = th[j], v = om[j];
                const double k1t = v;
                const double k1o = ACCEL(x, k1t, f0);
                const double k2t = v + dt_2 * k1o;
                const double k2o = ACCEL(x + dt_2 * k1t, k2t, f1);
                const double k3t = v + dt_2 * k2o;
                const double k3o = ACCEL(x + dt_2 * k2t, k3t, f1);
                const double k4t = v + dt * k3o;
                const double k4o = ACCEL(x + dt * k3t, k4t, f2);
                th[j] = x + dt_6 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
                om[j] = v + dt_6 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o);
            }
            f0 = f2;
        }
        for (int64_t j = 0; j < m; j++) {
            th_out[start + j] = th[j];
            om_out[start + j] = om[j];
        }
    }
}
