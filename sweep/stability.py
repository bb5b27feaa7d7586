"""Linear stability of the fixed-step integrators: the largest stable step for a scene.

What the guard covers
---------------------
The pendulum linearised at the bottom (``theta = 0``; for the linear model it *is* the
equation) is ``theta'' + c theta' + w^2 theta = forcing`` with ``w^2 = g/L``; its
eigenvalues are ``lambda = -c/2 +- sqrt(c^2/4 - w^2)``. A one-step method applied to
``y' = lambda y`` multiplies ``y`` by ``R(dt lambda)`` per step; if ``|R| > 1`` every
perturbation of that mode grows geometrically, however small ``dt lambda``'s error term
would be: this is the explosive instability that turns a stiff (``c = 100``) or fast
(``w dt ~ 3``) run into overflow or silent garbage. `max_stable_step` gives the largest
``dt`` for which ``dt lambda`` lies in the method's stability region for every eigenvalue.

Not covered, by design: the forcing (it does not change the homogeneous dynamics); the
nonlinear pendulum near the top, whose linearisation ``theta'' = +w^2 theta`` has a
positive real eigenvalue (a physical instability, which every method reproduces, not a
numerical one); and fast rotation, whose local frequency is ``omega`` itself rather than
``w`` (a rotating pendulum of speed ``omega`` needs ``omega dt`` well below the
imaginary-axis limit for accuracy, which the convergence order, not the guard, measures).

Methods
-------
- Explicit Runge-Kutta tableaux: ``R(z) = 1 + z b^T (I - z A)^-1 1``, a polynomial
  since ``A`` is strictly lower-triangular (``sum_k z^k/k!`` for ``k <= 4`` for RK4 and
  RK38). The boundary along the ray of ``lambda`` is the first ``r > 0`` where
  ``|R(r e^{i phi})|^2 - 1`` changes sign to positive, from the polynomial's roots. RK4:
  2.7853 on the negative real axis, ``2 sqrt 2 = 2.8284`` on the imaginary axis.
  Euler and Heun are unstable on the imaginary axis for *every* step (``|R(iy)| > 1``
  for all ``y > 0``): on an undamped scene each step amplifies by ``1 + O((w dt)^(p+1))``,
  an accuracy defect that shrinks with ``dt`` rather than a step limit, so no limit is
  given for such a ray.
- Symplectic splittings (Verlet, Yoshida4), conservative scenes only: the one-step map of
  the harmonic oscillator ``q' = p, p' = -w^2 q`` is a 2 x 2 matrix ``M(w dt)`` with
  ``det M = 1``; it is stable while ``|tr M| < 2``. Verlet: ``w dt < 2``; Yoshida4:
  ``w dt < 1.5734``.
- Adaptive methods control their own step: no limit.
"""

from __future__ import annotations

import math
from fractions import Fraction
from itertools import pairwise

import numpy as np

from .methods import ButcherTableau, SplittingMethod

__all__ = ["StepLimit", "check", "eigenvalues", "max_stable_step", "ray_limit",
           "splitting_limit", "stability_polynomial"]

_DISPLAY = {"euler": "Euler", "heun": "Heun", "rk4": "RK4", "rk38": "RK38",
            "verlet": "Verlet", "yoshida4": "Yoshida4", "dopri5": "DOPRI5"}


def display_name(method) -> str:
    return _DISPLAY.get(method.name, method.name)


def stability_polynomial(tableau: ButcherTableau) -> np.ndarray:
    """Coefficients ``r_k`` (k = 0 .. s, ascending) of ``R(z) = sum r_k z^k``.

    ``R(z) = 1 + z b^T (I - zA)^-1 1 = 1 + sum_k z^(k+1) b^T A^k 1`` (``A`` nilpotent).
    Computed in exact arithmetic when the tableau is rational.
    """
    s = tableau.stages
    a = [[tableau.a[i][j] for j in range(s)] for i in range(s)]
    vec = [Fraction(1)] * s if all(isinstance(x, Fraction) for row in a for x in row) \
        else [1.0] * s
    coefficients = [1.0]
    for _ in range(s):
        coefficients.append(float(sum(bi * vi for bi, vi in zip(tableau.b, vec))))
        vec = [sum(a[i][j] * vec[j] for j in range(s)) for i in range(s)]
    return np.array(coefficients, dtype=np.float64)


def _first_exit(poly: np.ndarray) -> float | None:
    """First r > 0 after which the real polynomial ``P`` (ascending coefficients,
    ``P(0) = 0``) becomes positive; None if it is positive right from 0 (no stable
    segment); inf if it never becomes positive."""
    trimmed = np.trim_zeros(poly, "b")
    scale = np.max(np.abs(trimmed))
    # P(r) = r^m Q(r): drop the root of multiplicity m at 0 (coefficients of rounding
    # size count as zero), so that it does not split into spurious small roots
    low = int(np.argmax(np.abs(trimmed) > 1e-14 * scale))
    trimmed = trimmed[low:]
    roots = np.roots(trimmed[::-1] / scale) if trimmed.size > 1 else np.array([])
    real = np.sort(roots.real[(np.abs(roots.imag) <= 1e-9 * np.maximum(1, np.abs(roots)))
                              & (roots.real > 1e-12)])
    edges = np.concatenate(([0.0], real, [real[-1] * 2 + 1 if real.size else 1.0]))
    value = np.polynomial.polynomial.polyval
    for left, right in pairwise(edges):
        mid = 0.5 * (left + right)
        if value(mid, trimmed) > 0:
            return None if left == 0.0 else float(left)
    return math.inf


def ray_limit(tableau: ButcherTableau, direction: complex) -> float | None:
    """Largest ``r`` with ``r * direction`` in the stability region of ``tableau`` for
    every step up to it (``|direction| = 1``); None if the ray leaves the region at once
    (e.g. Euler on the imaginary axis)."""
    r = stability_polynomial(tableau).astype(np.complex128)
    a = r * direction ** np.arange(r.size)  # R(rho d) = sum a_k rho^k
    n = a.size
    poly = np.zeros(2 * n - 1)
    for j in range(n):
        for k in range(n):
            poly[j + k] += (a[j] * np.conj(a[k])).real
    poly[0] -= 1.0  # |R|^2 - 1, zero at rho = 0
    poly[0] = 0.0
    return _first_exit(poly)


def splitting_limit(method: SplittingMethod) -> float:
    """Largest ``x = w dt`` for which the splitting is stable on ``q'' = -w^2 q``
    (``|tr M(x)| < 2``); found by scanning and bisection of ``|tr M| - 2``."""

    def excess(x: float) -> float:
        m = np.eye(2)
        for kick, drift in zip(method.kick, method.drift):
            m = np.array([[1.0, 0.0], [-float(kick) * x, 1.0]]) @ m  # p += kick x (-q)
            m = np.array([[1.0, float(drift) * x], [0.0, 1.0]]) @ m  # q += drift x p
        return abs(np.trace(m)) - 2.0

    step, x = 1e-3, 1e-3
    while excess(x) < 0 and x < 100:
        x += step
    lo, hi = x - step, x
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) < 0 else (lo, mid)
    return lo


def eigenvalues(damping: float, w2: float) -> tuple[complex, complex]:
    """``-c/2 +- sqrt(c^2/4 - w^2)`` of ``theta'' + c theta' + w^2 theta = 0``."""
    disc = damping * damping / 4.0 - w2
    root = complex(math.sqrt(disc), 0.0) if disc >= 0 else complex(0.0, math.sqrt(-disc))
    return (-damping / 2.0 - root, -damping / 2.0 + root)


class StepLimit:
    """The largest stable step of a method for a scene, and why."""

    def __init__(self, dt: float, method, damping: float, w2: float, eigenvalue: complex):
        self.dt, self.method = dt, method
        self.damping, self.w2, self.eigenvalue = damping, w2, eigenvalue

    def reason(self) -> str:
        """``damping c = 100 1/s, g/L = 9.81 1/s^2: eigenvalue -99.9``."""
        lam = self.eigenvalue
        if lam.imag == 0:
            shown = f"{lam.real:.4g}"
        elif lam.real == 0:
            shown = f"+-{abs(lam.imag):.4g}i"
        else:
            shown = f"{lam.real:.4g} +-{abs(lam.imag):.4g}i"
        if self.damping > 0:
            what = f"damping c = {self.damping:.6g} 1/s, g/L = {self.w2:.6g} 1/s^2"
        else:
            what = f"undamped, g/L = {self.w2:.6g} 1/s^2"
        return f"{what}: eigenvalue {shown}"


def _floor3(x: float) -> float:
    """``x`` rounded down to 3 significant digits (a step that is truly accepted)."""
    e = math.floor(math.log10(x)) - 2
    return math.floor(x / 10.0 ** e) * 10.0 ** e


def max_stable_step(method, dampings, w2s) -> StepLimit | None:
    """The smallest stable-step limit over every (c, w^2) pair given (the caller
    passes the extremes of the grid); None when no limit applies (adaptive method, or
    rays the method never covers, see the module notes)."""
    if getattr(method, "adaptive", False):
        return None
    best = None
    for c in dampings:
        for w2 in w2s:
            c, w2 = float(c), float(w2)
            if isinstance(method, SplittingMethod):
                lam = complex(0.0, math.sqrt(w2))
                dt = splitting_limit(method) / math.sqrt(w2)
                candidates = [(dt, lam)]
            else:
                candidates = []
                for lam in eigenvalues(c, w2):
                    size = abs(lam)
                    if size == 0.0:
                        continue
                    r = ray_limit(method, lam / size)
                    if r is not None and math.isfinite(r):
                        candidates.append((r / size, lam))
            for dt, lam in candidates:
                if best is None or dt < best.dt:
                    best = StepLimit(dt, method, c, w2, lam)
    return best


def check(method, dt: float, dampings, w2s) -> None:
    """Raise ValueError if ``dt`` exceeds the stable-step limit (see `max_stable_step`)."""
    limit = max_stable_step(method, dampings, w2s)
    if limit is None or dt <= limit.dt:
        return
    name = display_name(method)
    raise ValueError(
        f"dt = {dt!r} exceeds {name}'s stability limit {limit.dt:.3g} s for this scene "
        f"({limit.reason()}); accepted: dt <= {_floor3(limit.dt):.3g}, or "
        "check_stability=False to integrate anyway (the affected trajectories then grow "
        "without bound and are flagged non-finite)"
    )
