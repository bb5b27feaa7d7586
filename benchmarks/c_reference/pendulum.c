/* C reference for sweep's RK4 kernel: the same algorithm, written for the hardware.
 *
 *   theta'' = A sin(W t + phi) - c theta' - w0sq sin(theta)      (LINEAR: theta)
 *
 * Classical RK4 with exactly sweep's operations and forcing-time convention: time of
 * step n is t_n = t0 + n*dt (never accumulated); the forcing is evaluated at t_n,
 * t_n + dt/2 and t_{n+1} = t0 + (n+1)*dt, and f(t_{n+1}) is carried to the next step.
 * All trajectories of a call share (w0sq, c, A, W, phi), as in a (theta0, omega0) grid,
 * so the forcing sine is never computed per trajectory:
 *
 *   default        once per step for a whole block of trajectories (as sweep's kernel)
 *   FORCING_TABLE  once per step for the whole call: a table f(t_n), f(t_n + dt/2)
 *                  computed before the parallel loop, read by every block (the same
 *                  values to the bit, one libm call per step and call instead of per
 *                  step and block; it matters for small blocks)
 *
 * Layout: OpenMP threads take blocks of BLOCK trajectories; within a block the time
 * loop is outside and the lane loop inside (`omp simd`), so the trajectories fill
 * the SIMD lanes.  The sine of theta is selected at compile time by -DSIN_VARIANT=n
 * (the designs, 0 to 5, are described in sines.h).
 *
 * Build (benchmarks/run_all.py does this and sweeps the options):
 *   gcc -O3 -march=native -fopenmp -shared -fPIC [-mprefer-vector-width=512]
 *       [-ffp-contract=fast|off] [-DSIN_VARIANT=n] [-DBLOCK=n] [-DFORCING_TABLE]
 *       [-DSIN_POLY=n] [-DESTRIN] [-DLINEAR] pendulum.c -o lib.so -lm
 * Never -ffast-math: reassociation would break the magic-number rounding and the
 * exact Cody-Waite reduction, and change RK4's sums. -ffp-contract=fast (gcc's
 * default for GNU C) fuses any a*b + c into an FMA, where sweep's kernels fuse only
 * what they write (vfma) and let LLVM fuse nothing; -ffp-contract=off keeps every
 * product rounded but the explicit fma() calls.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#ifndef SIN_VARIANT
#define SIN_VARIANT 0
#endif
#ifndef BLOCK
#define BLOCK 512
#endif

#include "sines.h"

#ifdef LINEAR
#define RESTORING(th) (th)
#else
#define RESTORING(th) SIN(th)
#endif

#define ACCEL(th, om, f) (-w0sq * RESTORING(th) - c * (om) + (f))

/* The build's options, for the benchmark's report. */
int64_t pendulum_block(void) { return BLOCK; }
int64_t pendulum_sin_variant(void) { return SIN_VARIANT; }

/* Integrate n trajectories from (th0[i], om0[i]) for n_steps steps; write the final
 * state to th_out, om_out. */
void pendulum_rk4(int64_t n, const double *th0, const double *om0, double w0sq,
                  double c, double A, double W, double phi, double t0, double dt,
                  int64_t n_steps, double *th_out, double *om_out) {
    const double cdt1 = dt * 0.5, dt_2 = dt / 2.0, dt_6 = dt / 6.0;
    const int64_t n_blocks = (n + BLOCK - 1) / BLOCK;
#ifdef FORCING_TABLE
    /* fnode[k] = f(t0 + k dt) for k = 0..n_steps, fhalf[k] = f(t0 + k dt + dt/2) */
    double *fnode = malloc(sizeof(double) * (size_t)(2 * n_steps + 1));
    double *fhalf = fnode + n_steps + 1;
    fnode[0] = A * sin(W * t0 + phi);
    for (int64_t step = 0; step < n_steps; step++) {
        fhalf[step] = A * sin(W * (t0 + (double)step * dt + cdt1) + phi);
        fnode[step + 1] = A * sin(W * (t0 + (double)(step + 1) * dt) + phi);
    }
#endif
#pragma omp parallel for schedule(static)
    for (int64_t b = 0; b < n_blocks; b++) {
        const int64_t start = b * BLOCK;
        const int64_t m = n - start < BLOCK ? n - start : BLOCK;
        double th[BLOCK] __attribute__((aligned(64)));
        double om[BLOCK] __attribute__((aligned(64)));
        for (int64_t j = 0; j < m; j++) {
            th[j] = th0[start + j];
            om[j] = om0[start + j];
        }
        /* pad a partial block so every lane runs the same code on finite data */
        for (int64_t j = m; j < BLOCK; j++) {
            th[j] = 0.0;
            om[j] = 0.0;
        }
#ifndef FORCING_TABLE
        double f0 = A * sin(W * t0 + phi);
#endif
        for (int64_t step = 0; step < n_steps; step++) {
#ifdef FORCING_TABLE
            const double f0 = fnode[step], f1 = fhalf[step], f2 = fnode[step + 1];
#else
            const double f1 = A * sin(W * (t0 + (double)step * dt + cdt1) + phi);
            const double f2 = A * sin(W * (t0 + (double)(step + 1) * dt) + phi);
#endif
#pragma omp simd aligned(th, om : 64)
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
#ifndef FORCING_TABLE
            f0 = f2;
#endif
        }
        for (int64_t j = 0; j < m; j++) {
            th_out[start + j] = th[j];
            om_out[start + j] = om[j];
        }
    }
#ifdef FORCING_TABLE
    free(fnode);
#endif
}
