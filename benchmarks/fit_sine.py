"""Fit the odd polynomials of the one-reduction-by-pi sine (issue 29): reproducible.

The sine design: ``k = round(x / pi)``, ``r = x - k pi`` (|r| <= pi/2, a little more
where ``x / pi`` rounds to the other integer: |x| 2**-54 / pi at most, 1.8e-5 at
|x| = 1e12), ``sin x = (-1)**k sin r`` with one odd polynomial
``sin r ~ r + r**3 P(r**2)``. This script fits P on [0, A**2], ``A = pi/2 + 1e-4``:

* **Taylor**: ``c_i = (-1)**i / (2i + 1)!`` rounded to float64, degree 19 (the issue's
  C kernel) and 21;
* **minimax**: the relative error ``(r + r**3 P(z) - sin r) / sin r`` minimised over P
  by Remez's exchange in mpmath (60 digits, a grid of 4000 points in z), then the
  coefficients rounded to float64 one at a time from the first (largest), the rest
  refitted after each rounding (the error of a rounded ``-1/6`` alone, 3.6e-17 at
  pi/2, would otherwise be most of the budget); degrees 13 to 19.

For each it prints the polynomial's own error with its float64 coefficients, computed
in mpmath on a grid of 20001 points of [0, A] (the rounding of its evaluation in
float64 comes on top: up to about half an ulp of the result; measured with the whole
sine by ``run_all.py`` and ``sine_designs.py``), and the coefficients as C and Python.
The coefficients in ``c_reference/pendulum.c`` and ``sine_designs.py`` are this
script's output (``python benchmarks/fit_sine.py``; needs mpmath, ~10 s).
"""

from __future__ import annotations

import argparse

import mpmath as mp

mp.mp.dps = 60
A = mp.pi / 2 + mp.mpf("1e-4")  # the interval's end: pi/2 and the slip of k's rounding


def target(z):
    """(sin r - r) / r**3 and the relative weight r**3 / sin r, at z = r**2 > 0."""
    r = mp.sqrt(z)
    s = mp.sin(r)
    return (s - r) / (r * z), r * z / s


def poly(c, z):
    """c[0] + c[1] z + ... (Horner, in mpmath)."""
    out = mp.mpf(0)
    for a in reversed(c):
        out = out * z + a
    return out


def remez(n, fixed, grid, iterations=30):
    """The n - len(fixed) free coefficients of P (degree n - 1 in z) after the fixed
    first ones: minimax of the relative error over the grid, by Remez's exchange."""
    m = len(fixed)
    free = n - m
    data = []
    for z in grid:
        g, w = target(z)
        # P = fixed(z) + z**m Q(z):  w (P - g) = (w z**m) (Q - (g - fixed(z)) / z**m)
        data.append((z, (g - poly(fixed, z)) / z**m, w * z**m))
    # start from Chebyshev extrema of the grid's range
    idx = [round((len(grid) - 1) * (1 - mp.cos(mp.pi * i / free)) / 2) for i in range(free + 1)]
    q = None
    for _ in range(iterations):
        rows, rhs = [], []
        for i, j in enumerate(idx):
            z, t, w = data[j]
            rows.append([z**p for p in range(free)] + [(-1) ** i / w])
            rhs.append(t)
        sol = mp.lu_solve(mp.matrix(rows), mp.matrix(rhs))
        q = [sol[p] for p in range(free)]
        err = [w * (poly(q, z) - t) for z, t, w in data]
        # new reference: the extremum of each run of one sign, then keep free + 1
        # alternating ones around the largest
        runs, start = [], 0
        for j in range(1, len(err) + 1):
            if j == len(err) or mp.sign(err[j]) != mp.sign(err[start]):
                runs.append(max(range(start, j), key=lambda k: abs(err[k])))
                start = j
        while len(runs) > free + 1:  # drop the smaller end
            runs.pop(0 if abs(err[runs[0]]) < abs(err[runs[-1]]) else -1)
        if len(runs) < free + 1 or runs == idx:
            break
        idx = runs
    return q


def fit_minimax(n, points=4000):
    """n float64 coefficients of P, rounded one at a time with the rest refitted."""
    grid = [A**2 * (1 - mp.cos(mp.pi * (i + 0.5) / points)) / 2 for i in range(points)]
    fixed = []
    while len(fixed) < n:
        q = remez(n, fixed, grid)
        fixed.append(mp.mpf(float(q[0])))
    return [float(c) for c in fixed]


def taylor(n):
    return [float((-1) ** i / mp.factorial(2 * i + 1)) for i in range(1, n + 1)]


def error(c, points=20001):
    """(max relative, max absolute) error of r + r**3 P(r**2) on (0, A], in mpmath."""
    rel = ab = mp.mpf(0)
    cm = [mp.mpf(a) for a in c]
    for i in range(1, points + 1):
        r = A * i / points
        s = mp.sin(r)
        e = r + r**3 * poly(cm, r * r) - s
        rel, ab = max(rel, abs(e / s)), max(ab, abs(e))
    return float(rel), float(ab)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--degrees", type=int, nargs="*", default=[13, 15, 17, 19])
    args = parser.parse_args(argv)
    fits = {f"taylor{2 * n + 1}": taylor(n) for n in (9, 10)}
    fits.update({f"minimax{d}": fit_minimax((d - 1) // 2) for d in args.degrees})
    print(f"r + r^3 P(r^2) on [0, pi/2 + 1e-4], float64 coefficients; error in mpmath "
          f"({mp.mp.dps} digits)")
    print(f"{'polynomial':>12s} {'terms':>5s} {'max rel err':>12s} {'max abs err':>12s}")
    for name, c in fits.items():
        rel, ab = error(c)
        print(f"{name:>12s} {len(c) + 1:5d} {rel:12.2e} {ab:12.2e}")
    for name, c in fits.items():
        print(f"\n{name}:")
        print("  C:      " + ", ".join(f"{a!r}" for a in c))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
