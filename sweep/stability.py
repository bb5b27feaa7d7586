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

Whether the step resolves a drive
---------------------------------
A drive (the forcing ``A sin(W t + phase)``, the pivot's ``cos(nu t + psi)``) is
sampled at the stages' times ``t + c_i dt``; with too few steps per drive period the
run describes another drive (at ``W dt = 10`` rad per step, RK4 sees no sinusoid at
all). `drive_error` measures a method on a sinusoid: the steady response of the forced
double integrator ``theta'' = e^{i W t}`` computed by the method, a periodic solution
``(theta_n, omega_n) = (Y, V) e^{i W n dt}`` of its stage equations (a linear system
in ``Y``, ``V`` and the stages), against the exact ``(-1/W^2, -i/W)``: the relative
error of the amplitude and phase of both. It depends on ``x = W dt`` alone; RK4:
``~ x^4 / 1000``. `drive_step_limit` is the largest ``x`` below which that error stays
within `DRIVE_TOLERANCE` (1 %): RK4 1.70 rad per step (3.7 steps per period), RK38
2.06, DOPRI5 3.26 (its largest step), Heun 0.347, Euler 0.0100 (Euler's drive lags
half a step: an error ``~ x / 1``). `check_drive` refuses a run whose largest drive
frequency on the grid exceeds it. This is a floor, not accuracy: a drive resolved to
1 % still needs the convergence study for a given error.
"""

from __future__ import annotations

import functools
import math
from fractions import Fraction
from itertools import pairwise

import numpy as np

from .methods import ButcherTableau, SplittingMethod

__all__ = ["DRIVE_TOLERANCE", "StepLimit", "check", "check_drive", "drive_error",
           "drive_step_limit", "eigenvalues", "max_stable_step", "ray_limit",
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
    """``-c/2 +- sqrt(c^2/4 - w^2)`` of ``theta'' + c theta' + w^2 theta = 0``.

    Written without ``c^2`` (``sqrt(c/2 - w) sqrt(c/2 + w)``) so that a huge damping,
    such as quadratic drag's ``2 k omega_max`` for a start of 1e300 rad/s, gives
    eigenvalues rather than an overflow; the small real root is ``w^2`` over the large
    one (their product), free of cancellation."""
    half, w = damping / 2.0, math.sqrt(w2)
    if half >= w:
        root = math.sqrt(half - w) * math.sqrt(half + w)
        large = -half - root
        return (large, w2 / large if large != 0.0 else 0.0)
    root = complex(0.0, math.sqrt(w - half) * math.sqrt(w + half))
    return (-half - root, -half + root)


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
    bad = [(name, v) for name, values in (("damping", dampings), ("stiffness", w2s))
           for v in values if not math.isfinite(float(v))]
    if bad:
        name, value = bad[0]
        raise ValueError(
            f"the scene linearised at the bottom has a {name} of {value!r} "
            f"({'1/s' if name == 'damping' else '1/s^2'}) at an extreme of the grid (an "
            "overflow from huge parameters or starts); no step dt is stable for it; "
            "accepted: finite g/L, damping, drag k omega_max and pivot a nu^2/L, or "
            "check_stability=False to integrate anyway (the affected trajectories are "
            "then flagged)")
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


#: Largest relative error of a method's steady response to a sinusoidal drive that
#: `check_drive` accepts (1 %: the drive's amplitude and phase as the run sees them).
DRIVE_TOLERANCE = 0.01


def drive_error(tableau: ButcherTableau, x: float) -> float:
    """Relative error of ``tableau``'s steady response to a drive of ``x = W dt`` rad
    per step (see the module notes).

    Parameters
    ----------
    tableau : ButcherTableau
    x : float
        Drive phase advance per step, ``W dt`` [rad], ``0 < x < 2 pi``.

    Returns
    -------
    float
        ``max(|Y/Y_exact - 1|, |V/V_exact - 1|)`` for ``theta'' = e^{i W t}``
        (dimensionless); inf where the method has no periodic response (resonance of
        its stage equations).
    """
    s = tableau.stages
    a = np.array([[float(v) for v in row] for row in tableau.a])
    b = np.array([float(v) for v in tableau.b])
    c = np.array([float(v) for v in tableau.c])
    jac = np.array([[0.0, 1.0], [0.0, 0.0]])  # (theta, omega)' = J (theta, omega) + drive
    # unknowns, in units dt = 1: (Y, V), then each stage's derivative k_j (2 each)
    m = np.zeros((2 + 2 * s, 2 + 2 * s), dtype=np.complex128)
    rhs = np.zeros(2 + 2 * s, dtype=np.complex128)
    m[:2, :2] = (np.exp(1j * x) - 1.0) * np.eye(2)  # y_{n+1} - y_n = sum b_j k_j
    for j in range(s):
        rows = slice(2 + 2 * j, 4 + 2 * j)
        m[:2, rows] -= b[j] * np.eye(2)
        m[rows, rows] += np.eye(2)  # k_j = J (y_n + sum a_jl k_l) + e^{i x c_j} e_2
        m[rows, :2] -= jac
        for col in range(s):
            m[rows, 2 + 2 * col:4 + 2 * col] -= a[j, col] * jac
        rhs[3 + 2 * j] = np.exp(1j * x * c[j])
    try:
        y, v = np.linalg.solve(m, rhs)[:2] * np.array([x * x, x])  # W = x, amplitude 1
    except np.linalg.LinAlgError:
        return math.inf
    return float(max(abs(y / -1.0 - 1.0), abs(v / -1j - 1.0)))


@functools.cache
def drive_step_limit(tableau: ButcherTableau, tolerance: float = DRIVE_TOLERANCE) -> float:
    """Largest ``x = W dt`` [rad per step] up to which `drive_error` stays within
    ``tolerance``: a scan in steps of 1 % from 1e-6, then bisection."""
    x = 1e-6
    while drive_error(tableau, x * 1.01) <= tolerance and x < 2 * math.pi:
        x *= 1.01
    lo, hi = x, x * 1.01
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if drive_error(tableau, mid) <= tolerance else (lo, mid)
    return lo


def check_drive(method, dt: float, frequencies) -> None:
    """Refuse a step that does not resolve a drive (see the module notes).

    Parameters
    ----------
    method : ButcherTableau or SplittingMethod
        The integrator (splitting methods integrate no drive: nothing to check).
    dt : float
        The step [s] (an adaptive method's first and largest step).
    frequencies : iterable of (str, float)
        ``(axis, frequency)``: each drive's largest angular frequency on the grid
        [rad/s], named by its grid axis (``"forcing_frequency"``).

    Raises
    ------
    ValueError
        Naming the axis, its frequency, ``W dt``, the steps per period, the method's
        error there and the largest accepted ``dt``.
    """
    if not isinstance(method, ButcherTableau):
        return
    limit = drive_step_limit(method)
    for axis, frequency in frequencies:
        x = abs(float(frequency)) * dt
        if x <= limit:
            continue
        name = display_name(method)
        error = drive_error(method, x) if x < 2 * math.pi else math.inf
        seen = (f"{name}'s steady response to a sinusoidal drive is off by {error:.2g} "
                "(relative)") if math.isfinite(error) and error < 1 else \
            f"{name} sees no sinusoid at all (its response is off by more than 100 %)"
        raise ValueError(
            f"{axis} = {float(frequency)!r} rad/s is not resolved by dt = {dt!r} s: "
            f"{x:.4g} rad per step ({2 * math.pi / x:.3g} steps per period), where {seen}; "
            f"accepted: dt <= {_floor3(limit / abs(float(frequency))):.3g} s ({axis} x dt "
            f"<= {limit:.3g} rad, {2 * math.pi / limit:.3g} steps per period, where the "
            f"error is {DRIVE_TOLERANCE:.0%}), or check_stability=False to integrate anyway"
        )
