"""What accuracy costs: reference solutions, convergence order, work-precision studies.

- `exact` : the exact motion where one is known -- the Jacobi-elliptic solution of the
  undamped, unforced nonlinear pendulum (libration and rotation, any start) and the
  closed forms of the linear model (free, damped, forced).
- `reference` : the state at ``t_end`` from `exact` where it applies, otherwise from
  sweep's own adaptive Dormand-Prince pair at ``rtol = 1e-13`` (cross-checked against
  SciPy's DOP853 in the tests).
- `convergence` : the observed order of a fixed-step method from a ladder of steps.
- `work_precision` : error against cost (wall time, right-hand-side evaluations) for
  several methods, as an ``xarray.Dataset`` (integrator x level); `cost_at` reads off the
  step and the time per million trajectories needed for given errors.

The error of a trajectory is the state error at ``t_end`` measured in radians:
``max(|theta - theta_ref|, |omega - omega_ref| / omega_n)`` with
``omega_n = sqrt(g / L)``, so that angle and angular velocity count alike.

The Jacobi elliptic functions are computed here with the arithmetic-geometric mean
(numpy only): SciPy is not a runtime dependency of sweep.

References
----------
.. [AS] M. Abramowitz, I. A. Stegun, *Handbook of Mathematical Functions*, 16.4
   (AGM for am, sn, cn, dn), 17.6 (K by the AGM).
.. [C95] B. C. Carlson, Numerical computation of real or complex elliptic integrals,
   Numer. Algorithms 10 (1995) 13-26 (R_F by duplication).
.. [WP] SciML Benchmarks, work-precision diagrams (error vs time, log-log).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass

import numpy as np

from ._validate import check_numbers, check_positive_int
from .grid import Grid
from .physics import Scene, parameter_names

__all__ = [
    "jacobi_am",
    "jacobi_ellipj",
    "ellipk",
    "ellipf",
    "exact",
    "has_exact",
    "reference",
    "state_error",
    "ConvergenceResult",
    "convergence",
    "work_precision",
    "cost_at",
    "REFERENCE_RTOL",
]

_EPS = np.finfo(np.float64).eps

#: rtol (and atol, in rad and rad/s) of the numerical reference (sweep's dopri5).
REFERENCE_RTOL = 1e-13


# =========================================================================== elliptic
def _agm_sequence(m: float, m1: float) -> tuple[list[float], list[float]]:
    """a_n and c_n of the AGM of (1, sqrt(1 - m)) ([AS] 16.4), until c_n is negligible."""
    a, b, c = [1.0], math.sqrt(m1), [math.sqrt(m)]
    for _ in range(64):
        if abs(c[-1]) <= _EPS * a[-1]:
            break
        a_prev = a[-1]
        a.append(0.5 * (a_prev + b))
        c.append(0.5 * (a_prev - b))
        b = math.sqrt(a_prev * b)
    return a, c


def _complement(m, m1):
    m = float(m)
    m1 = 1.0 - m if m1 is None else float(m1)
    if not (0.0 <= m <= 1.0 and 0.0 <= m1 <= 1.0):
        raise ValueError(f"elliptic parameter m must be in [0, 1], got m = {m!r}")
    return m, m1


def jacobi_am(u, m: float, m1: float | None = None) -> np.ndarray:
    """Jacobi amplitude am(u | m) for real u (any size) and 0 <= m <= 1.

    Parameters
    ----------
    u : array_like
    m : float
        Parameter m = k^2.
    m1 : float, optional
        ``1 - m``, given separately to keep full accuracy as m -> 1.

    Returns
    -------
    ndarray
        am(u | m), continuous and increasing in u (am(u + 2K) = am(u) + pi).
    """
    m, m1 = _complement(m, m1)
    u = np.asarray(u, dtype=np.float64)
    if m1 == 0.0:  # separatrix: am(u | 1) = gd(u)
        return np.arctan(np.sinh(u))
    a, c = _agm_sequence(m, m1)
    n = len(a) - 1
    phi = (2.0 ** n) * a[n] * u
    for j in range(n, 0, -1):
        phi = 0.5 * (phi + np.arcsin(c[j] / a[j] * np.sin(phi)))
    return phi


def jacobi_ellipj(u, m: float, m1: float | None = None):
    """(sn, cn, dn, am) of u for 0 <= m <= 1, like ``scipy.special.ellipj``.

    ``dn = sqrt(m1 + m cn^2)`` keeps its accuracy near the separatrix (m -> 1).
    """
    m, m1 = _complement(m, m1)
    phi = jacobi_am(u, m, m1)
    sn, cn = np.sin(phi), np.cos(phi)
    dn = np.sqrt(m1 + m * cn * cn)
    return sn, cn, dn, phi


def ellipk(m: float, m1: float | None = None) -> float:
    """Complete elliptic integral of the first kind K(m) = pi / (2 AGM(1, sqrt(1-m)))."""
    m, m1 = _complement(m, m1)
    if m1 == 0.0:
        return math.inf
    a, b = 1.0, math.sqrt(m1)
    for _ in range(64):
        if abs(a - b) <= _EPS * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


def _carlson_rf(x, y, z):
    """Carlson's R_F(x, y, z) by duplication [C95]; arrays, x, y, z >= 0, at most one 0.

    Each duplication shrinks the spread of (x, y, z) by 4; 40 of them leave a relative
    spread below 1e-24, where the fifth-order series is exact to rounding.
    """
    x, y, z = (np.asarray(v, dtype=np.float64).copy() for v in (x, y, z))
    for _ in range(40):
        sx, sy, sz = np.sqrt(x), np.sqrt(y), np.sqrt(z)
        lam = sx * sy + sy * sz + sz * sx
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
    mean = (x + y + z) / 3.0
    dx, dy = 1.0 - x / mean, 1.0 - y / mean
    dz = -(dx + dy)
    e2 = dx * dy - dz * dz
    e3 = dx * dy * dz
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / np.sqrt(mean)


def ellipf(phi, m: float, m1: float | None = None) -> np.ndarray:
    """Incomplete elliptic integral of the first kind F(phi | m) for any real phi
    (F(phi + n pi) = F(phi) + 2 n K), 0 <= m < 1; the inverse of `jacobi_am`."""
    m, m1 = _complement(m, m1)
    phi = np.asarray(phi, dtype=np.float64)
    if m1 == 0.0:
        raise ValueError("F(phi | 1) is unbounded at phi = pi/2; m must be < 1")
    n = np.round(phi / np.pi)
    rest = phi - n * np.pi  # in [-pi/2, pi/2]
    s, c = np.sin(rest), np.cos(rest)
    # 1 - m sin^2 written as cos^2 + m1 sin^2: exact cancellation-free near m -> 1
    base = s * _carlson_rf(c * c, c * c + m1 * s * s, 1.0)
    return 2.0 * n * ellipk(m, m1) + base


# =========================================================================== exact
def has_exact(scene: Scene) -> bool:
    """Whether `exact` knows the motion of ``scene``: the linear model with damping and
    forcing only (closed form), or the nonlinear model whose damping and forcing are
    absent or zero (elliptic functions); never with any other effect."""
    names = {effect.declaration.name for effect in scene.effects}
    if not names <= _CLOSED_FORM_EFFECTS:
        return False
    p = scene.parameters()
    return scene.model == "linear" or (p["damping"] == 0.0 and p["forcing_amplitude"] == 0.0)


#: The effects the closed forms of `exact` include.
_CLOSED_FORM_EFFECTS = frozenset({"damping", "forcing"})


def _pendulum_exact(theta0, omega0, tau, w0):
    """Undamped, unforced nonlinear pendulum, one start (theta0, omega0), times tau."""
    # k^2 = E / (2 w0^2) with E = omega^2/2 + w0^2 (1 - cos theta)
    half_v = omega0 / (2.0 * w0)
    s_half, c_half = math.sin(theta0 / 2.0), math.cos(theta0 / 2.0)
    m = half_v * half_v + s_half * s_half
    m1 = c_half * c_half - half_v * half_v  # 1 - m without cancellation
    tau = np.asarray(tau, dtype=np.float64)
    if m1 > 0.0:  # libration: sin(theta/2) = k sn(u), omega = 2 k w0 cn(u)
        turns = round(theta0 / (2.0 * math.pi))
        reduced = theta0 - 2.0 * math.pi * turns  # in [-pi, pi]
        k = math.sqrt(m)
        if k == 0.0:
            return np.full_like(tau, theta0), np.zeros_like(tau)
        phase = math.atan2(math.sin(reduced / 2.0), half_v)  # am(u0): sn = s/k, cn = v/k
        u0 = float(ellipf(phase, m, m1))
        sn, cn, dn, _ = jacobi_ellipj(w0 * tau + u0, m, m1)
        theta = 2.0 * math.pi * turns + 2.0 * np.arctan2(k * sn, dn)
        return theta, 2.0 * k * w0 * cn
    if m1 < 0.0:  # rotation: theta/2 = am(s k w0 t + v0 | 1/k^2), omega = 2 s k w0 dn
        k = math.sqrt(m)
        mu, mu1 = 1.0 / m, -m1 / m
        sign = 1.0 if omega0 > 0 else -1.0
        v0 = float(ellipf(theta0 / 2.0, mu, mu1))
        sn, cn, dn, am = jacobi_ellipj(sign * k * w0 * tau + v0, mu, mu1)
        return 2.0 * am, 2.0 * sign * k * w0 * dn
    raise ValueError(f"start (theta0={theta0!r}, omega0={omega0!r}) lies exactly on the "
                     "separatrix, which takes infinitely long to traverse; accepted: a "
                     "start off the separatrix, or reference='dopri5'")


def _linear_exact(theta0, omega0, tau, t0, w0, c, amp, freq, phase):
    """theta'' + c theta' + w0^2 theta = amp sin(freq t + phase): homogeneous part fitted
    to the start after subtracting the steady (particular) solution."""
    tau = np.asarray(tau, dtype=np.float64)
    t = t0 + tau

    def particular(time):
        time = np.asarray(time, dtype=np.float64)
        if amp == 0.0:
            return np.zeros_like(time), np.zeros_like(time)
        arg = freq * time + phase
        det = (w0 * w0 - freq * freq) ** 2 + (c * freq) ** 2
        if det == 0.0:  # undamped resonance: secular growth
            x = -amp / (2.0 * freq) * time * np.cos(arg)
            v = -amp / (2.0 * freq) * (np.cos(arg) - freq * time * np.sin(arg))
            return x, v
        p, q = (w0 * w0 - freq * freq) / det, -c * freq / det
        x = amp * (p * np.sin(arg) + q * np.cos(arg))
        v = amp * freq * (p * np.cos(arg) - q * np.sin(arg))
        return x, v

    xp0, vp0 = particular(t0)
    x0, v0 = theta0 - float(xp0), omega0 - float(vp0)
    gamma = c / 2.0
    disc = w0 * w0 - gamma * gamma
    decay = np.exp(-gamma * tau)
    if disc > 0.0:
        wd = math.sqrt(disc)
        a, b = x0, (v0 + gamma * x0) / wd
        cos, sin = np.cos(wd * tau), np.sin(wd * tau)
        x = decay * (a * cos + b * sin)
        v = decay * ((b * wd - gamma * a) * cos - (a * wd + gamma * b) * sin)
    elif disc == 0.0:
        b = v0 + gamma * x0
        x = decay * (x0 + b * tau)
        v = decay * (b - gamma * (x0 + b * tau))
    else:
        r = math.sqrt(-disc)
        r1, r2 = -gamma + r, -gamma - r
        a1 = (v0 - r2 * x0) / (r1 - r2)
        a2 = x0 - a1
        e1, e2 = np.exp(r1 * tau), np.exp(r2 * tau)
        x = a1 * e1 + a2 * e2
        v = a1 * r1 * e1 + a2 * r2 * e2
    xp, vp = particular(t)
    return x + xp, v + vp


def exact(scene: Scene, theta0, omega0, t, *, t0: float = 0.0):
    """The exact state at times ``t`` of every start (theta0[j], omega0[j]).

    Parameters
    ----------
    scene : Scene
        Linear model (any effects), or nonlinear without damping and forcing.
    theta0, omega0 : array_like, shape (n,) (broadcast together)
        Starts [rad, rad/s] at time ``t0``.
    t : array_like, shape (n_t,)
        Times [s].
    t0 : float

    Returns
    -------
    theta, omega : ndarray, shape (n, n_t)

    Raises
    ------
    ValueError
        When no exact solution is known for ``scene`` (use `reference`), or a start
        lies exactly on the separatrix.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a sweep.Scene, got {scene!r}")
    if not has_exact(scene):
        raise ValueError("no exact solution is known for a nonlinear scene with damping or "
                         "forcing; accepted: a linear scene, a conservative nonlinear one "
                         "(either with no effect but damping and forcing), or "
                         "sweep.accuracy.reference(..., kind='dopri5')")
    theta0, omega0 = np.broadcast_arrays(np.atleast_1d(np.asarray(theta0, dtype=float)),
                                         np.atleast_1d(np.asarray(omega0, dtype=float)))
    tau = np.atleast_1d(np.asarray(t, dtype=np.float64)) - t0
    p = scene.parameters()
    w0 = math.sqrt(p["gravity"] / p["length"])
    theta = np.empty(theta0.shape + tau.shape)
    omega = np.empty_like(theta)
    for j, (th, om) in enumerate(zip(theta0.ravel(), omega0.ravel())):
        if scene.model == "nonlinear":
            theta[j], omega[j] = _pendulum_exact(float(th), float(om), tau, w0)
        else:
            theta[j], omega[j] = _linear_exact(
                float(th), float(om), tau, t0, w0, p["damping"], p["forcing_amplitude"],
                p["forcing_frequency"], p["forcing_phase"])
    return theta, omega


# =========================================================================== reference
def _sample_grid(sample) -> Grid:
    """A Grid of starts from a Grid or a mapping with theta0 and/or omega0."""
    grid = sample if isinstance(sample, Grid) else Grid(**dict(sample))
    extra = set(grid.dims) - {"theta0", "omega0"}
    if extra:
        raise ValueError(f"sample axes must be theta0 and/or omega0 (the scene fixes the "
                         f"other parameters), got {', '.join(sorted(extra))}")
    return grid


def _starts(scene: Scene, grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Flat theta0, omega0 of every trajectory of ``grid``, in the order of run's table."""
    table = grid.table(scene)
    names = parameter_names()
    return table[:, names.index("theta0")], table[:, names.index("omega0")]


def reference(scene: Scene, sample, *, t_end: float, t0: float = 0.0, kind: str = "auto"):
    """Reference state at ``t_end`` of every trajectory of ``sample``.

    Parameters
    ----------
    scene : Scene
    sample : Grid or mapping
        Starts: axes ``theta0`` and/or ``omega0`` only.
    t_end, t0 : float
    kind : {"auto", "exact", "dopri5"}
        ``"auto"``: `exact` where the scene has one, else ``"dopri5"`` (sweep's
        Dormand-Prince pair at ``rtol = atol = REFERENCE_RTOL``).

    Returns
    -------
    theta, omega : ndarray, shape (n,)
        In the flat order of the grid (as `sweep.run` stores it).
    kind : str
        The kind used.
    """
    grid = _sample_grid(sample)
    if kind not in ("auto", "exact", "dopri5"):
        raise ValueError(f"reference kind must be one of 'auto', 'exact', 'dopri5', got "
                         f"{kind!r}")
    if kind == "auto":
        kind = "exact" if has_exact(scene) else "dopri5"
    if kind == "exact":
        theta0, omega0 = _starts(scene, grid)
        theta, omega = exact(scene, theta0, omega0, [t_end], t0=t0)
        return theta[:, 0], omega[:, 0], kind
    from .engine import run

    span = t_end - t0
    ds = run(scene, grid, t_end=t_end, t0=t0, dt=min(span, 0.1), method="dopri5",
             rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL, observe=("final",), progress=False)
    return ds.theta_final.values.ravel(), ds.omega_final.values.ravel(), kind


def state_error(scene: Scene, theta, omega, theta_ref, omega_ref) -> np.ndarray:
    """Per-trajectory error [rad]: ``max(|d theta|, |d omega| / omega_n)``."""
    w0 = scene.natural_frequency
    return np.maximum(np.abs(np.asarray(theta) - theta_ref),
                      np.abs(np.asarray(omega) - omega_ref) / w0)


def _fit_order(x, err, floor):
    """Slope of log(err) against log(x) over the points with err above ``floor``."""
    x, err = np.asarray(x, dtype=float), np.asarray(err, dtype=float)
    keep = np.isfinite(err) & (err > floor) & np.isfinite(x) & (x > 0)
    if keep.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(x[keep]), np.log(err[keep]), 1)[0])


# =========================================================================== convergence
@dataclass(frozen=True)
class ConvergenceResult:
    """Outcome of `convergence`.

    Attributes
    ----------
    method : str
    nominal_order : int
    dts : ndarray
        Steps [s], as given.
    errors : ndarray
        Max over the trajectories of the state error at ``t_end`` [rad] per step.
    order : float
        Least-squares slope of log(error) against log(dt) over the steps whose error is
        above the round-off floor ``floor``.
    local_orders : ndarray, length len(dts) - 1
        Slopes between consecutive steps.
    floor : float
        Errors at or below this are round-off and are left out of the fit.
    reference : str
        Kind of reference used.
    """

    method: str
    nominal_order: int
    dts: np.ndarray
    errors: np.ndarray
    order: float
    local_orders: np.ndarray
    floor: float
    reference: str


def convergence(scene: Scene, theta0, omega0, t_end: float, method, dts, *,
                t0: float = 0.0, reference: str = "auto",
                floor: float = 1e-12) -> ConvergenceResult:
    """Observed order of a fixed-step method on ``scene`` from a ladder of steps.

    Parameters
    ----------
    scene : Scene
    theta0, omega0 : float or array_like
        Starts (all pairs of the two): a `Grid(theta0=..., omega0=...)`.
    t_end : float
        ``t_end - t0`` must be a whole number of every step in ``dts``.
    method : str or method object
        A fixed-step method (explicit Runge-Kutta or symplectic).
    dts : sequence of float
        Steps [s], at least two.
    reference : {"auto", "exact", "dopri5"}
        See `reference`.
    floor : float
        Errors at or below this [rad] are treated as round-off and left out of the
        fit (default 1e-12: a few thousand steps of rounding at 1e-16 each).

    Returns
    -------
    ConvergenceResult
    """
    from .engine import run, validate_method

    integrator = validate_method(method)
    if integrator.adaptive:
        raise ValueError(f"convergence needs a fixed-step method; {integrator.name!r} is "
                         "adaptive; accepted: a fixed-step method, or work_precision(..., "
                         "tolerances=...) for an adaptive one")
    dts = check_numbers("dts", dts)  # no booleans or strings taken as steps
    if dts.ndim != 1 or dts.size < 2:
        raise ValueError(f"dts must be a 1-D sequence of at least two steps, got {dts!r}")
    grid = Grid(theta0=theta0, omega0=omega0)
    theta_ref, omega_ref, kind = _reference(scene, grid, t_end, t0, reference)
    errors = np.empty(dts.size)
    for k, dt in enumerate(dts):
        ds = run(scene, grid, t_end=t_end, t0=t0, dt=float(dt), method=integrator,
                 observe=("final",), progress=False)
        errors[k] = np.max(state_error(scene, ds.theta_final.values.ravel(),
                                       ds.omega_final.values.ravel(), theta_ref, omega_ref))
    with np.errstate(divide="ignore", invalid="ignore"):
        local = np.diff(np.log(errors)) / np.diff(np.log(dts))
    return ConvergenceResult(method=integrator.name, nominal_order=integrator.order,
                             dts=dts, errors=errors, order=_fit_order(dts, errors, floor),
                             local_orders=local, floor=floor, reference=kind)


def _reference(scene, grid, t_end, t0, kind):
    return reference(scene, grid, t_end=t_end, t0=t0, kind=kind)


# =========================================================================== work-precision
def work_precision(scene: Scene, sample, methods, *, t_end: float, t0: float = 0.0,
                   dts=None, tolerances=None, dt_max: float | None = None,
                   reference: str = "auto", repeats: int = 3, floor: float = 1e-13,
                   dtype: str = "float64"):
    """Error against cost of several methods on the trajectories of ``sample``.

    Parameters
    ----------
    scene : Scene
    sample : Grid or mapping
        Starts: axes ``theta0`` and/or ``omega0``.
    methods : sequence of str or method objects
    t_end, t0 : float
        ``t_end - t0`` must be a whole number of every step in ``dts``.
    dts : sequence of float
        Steps [s] for the fixed-step methods (one level each).
    tolerances : sequence of float
        ``rtol`` for the adaptive methods (``atol = rtol`` in rad and rad/s).
    dt_max : float, optional
        First/largest step of the adaptive methods; default ``(t_end - t0) / 10``.
    reference : {"auto", "exact", "dopri5"}
    repeats : int
        Wall time is the best of this many runs, after one run that compiles.
    floor : float
        Errors at or below this [rad] are left out of the order fit.
    dtype : {"float64", "float32"}
        Working precision of the runs (`sweep.run`'s ``dtype``; float32 with
        fixed-step methods only): what float32's rounding costs in accuracy, against
        the same reference.

    Returns
    -------
    xarray.Dataset
        Dimensions ``integrator`` (the method names; not ``method``, which is a keyword
        of ``Dataset.sel``) and ``level`` (index into ``dts`` / ``tolerances``; NaN
        where a method has fewer levels). Variables: ``dt`` [s] (fixed-step; the
        largest step for adaptive), ``rtol``, ``error_max`` and ``error_rms`` [rad]
        (over the trajectories, of the state error at ``t_end``), ``wall_time`` [s],
        ``time_per_million`` [s per 10^6 trajectories], ``rhs_evaluations`` (mean per
        trajectory), ``observed_order`` (per method: -slope of log error against log
        rhs evaluations, i.e. the order in dt for a fixed-step method) and
        ``nominal_order``.
    """
    import xarray as xr

    from .engine import run, validate_method

    grid = _sample_grid(sample)
    integrators = [validate_method(m) for m in methods]
    if not integrators:
        raise ValueError("methods is empty; accepted: at least one method")
    fixed_levels = [] if dts is None else [float(x) for x in dts]
    adaptive_levels = [] if tolerances is None else [float(x) for x in tolerances]
    if any(not m.adaptive for m in integrators) and not fixed_levels:
        raise ValueError("fixed-step methods need dts=[...]")
    if any(m.adaptive for m in integrators) and not adaptive_levels:
        raise ValueError("adaptive methods need tolerances=[...]")
    check_positive_int("repeats", repeats)
    span = t_end - t0
    dt_max = span / 10.0 if dt_max is None else float(dt_max)
    n_levels = max(len(fixed_levels), len(adaptive_levels))
    shape = (len(integrators), n_levels)
    out = {name: np.full(shape, np.nan) for name in
           ("dt", "rtol", "error_max", "error_rms", "wall_time", "rhs_evaluations")}
    theta_ref, omega_ref, kind = _reference(scene, grid, t_end, t0, reference)
    n = grid.size
    for i, method in enumerate(integrators):
        levels = adaptive_levels if method.adaptive else fixed_levels
        for k, level in enumerate(levels):
            if method.adaptive:
                kwargs = dict(dt=dt_max, rtol=level, atol=level)
                warm = dict(kwargs, t_end=t0 + min(dt_max, span))
            else:
                kwargs = dict(dt=level)
                warm = dict(kwargs, t_end=t0 + level)
            # unstable steps are data points of the diagram, not errors
            common = dict(t0=t0, method=method, observe=("final",), progress=False,
                          check_stability=False, dtype=dtype)
            run(scene, grid, **warm, **common)  # compile (or load) the kernel first
            best = math.inf
            for _ in range(repeats):
                start = time.perf_counter()
                ds = run(scene, grid, t_end=t_end, **kwargs, **common)
                best = min(best, time.perf_counter() - start)
            err = state_error(scene, ds.theta_final.values.ravel(),
                              ds.omega_final.values.ravel(), theta_ref, omega_ref)
            if method.adaptive:
                steps = (ds.steps_accepted.values + ds.steps_rejected.values).astype(float)
                out["rtol"][i, k] = level
                out["dt"][i, k] = dt_max
            else:
                steps = np.full(n, ds.attrs["n_steps"], dtype=float)
                out["dt"][i, k] = level
            out["rhs_evaluations"][i, k] = method.rhs_initial + method.rhs_per_step * \
                float(np.mean(steps))
            out["error_max"][i, k] = float(np.max(err))
            out["error_rms"][i, k] = float(np.sqrt(np.mean(err * err)))
            out["wall_time"][i, k] = best
    orders = np.array([-_fit_order(out["rhs_evaluations"][i], out["error_max"][i], floor)
                       for i in range(len(integrators))])
    # "integrator", not "method": Dataset.sel(method=...) is xarray's own keyword, so a
    # dimension named "method" could not be selected by name with .sel
    dims = ("integrator", "level")
    units = {"dt": ("s", "step (fixed-step) or largest step (adaptive)"),
             "rtol": ("1", "relative (and absolute) tolerance of an adaptive method"),
             "error_max": ("rad", "max over trajectories of the state error at t_end"),
             "error_rms": ("rad", "RMS over trajectories of the state error at t_end"),
             "wall_time": ("s", f"wall time of the run, best of {repeats}"),
             "rhs_evaluations": ("1", "right-hand-side evaluations per trajectory (mean)")}
    data = {name: (dims, values, {"units": units[name][0], "long_name": units[name][1]})
            for name, values in out.items()}
    data["time_per_million"] = (dims, out["wall_time"] / n * 1e6,
                                {"units": "s", "long_name": "wall time per 10^6 trajectories"})
    data["observed_order"] = ("integrator", orders, {
        "units": "1", "long_name": "-slope of log(error_max) vs log(rhs_evaluations) "
                                   f"over errors > {floor:g} rad"})
    data["nominal_order"] = ("integrator", np.array([m.order for m in integrators]),
                             {"units": "1", "long_name": "order of the method"})
    data["kind"] = ("integrator", np.array([m.kind for m in integrators]),
                    {"long_name": "explicit, symplectic or adaptive"})
    return xr.Dataset(
        data,
        coords={"integrator": [m.name for m in integrators], "level": np.arange(n_levels)},
        attrs={"scene": json.dumps(scene.to_dict(), sort_keys=True),
               "model": scene.model, "t0": t0, "t_end": t_end,
               "n_trajectories": n, "reference": kind, "dtype": dtype,
               "error": "max(|theta - theta_ref|, |omega - omega_ref| / sqrt(g/L)) at t_end",
               "sample_axes": " ".join(grid.dims)},
    )


def cost_at(wp, errors=(1e-4, 1e-8, 1e-12)):
    """Step (or tolerance) and time per million trajectories needed to reach each error.

    Interpolates ``wp`` (a `work_precision` Dataset) log-linearly between the levels
    that bracket each target; NaN where no level reaches it (or the target is coarser
    than every level).

    Returns
    -------
    xarray.Dataset
        ``dt``, ``rtol``, ``time_per_million`` with dimensions (integrator, error).
    """
    import xarray as xr

    targets = np.asarray(errors, dtype=float)
    shape = (wp.sizes["integrator"], targets.size)
    result = {name: np.full(shape, np.nan) for name in ("dt", "rtol", "time_per_million")}
    for i in range(wp.sizes["integrator"]):
        err = wp.error_max.values[i]
        ok = np.isfinite(err)
        for j, target in enumerate(targets):
            for k in range(err.size - 1):
                e1, e2 = err[k], err[k + 1]
                if not (ok[k] and ok[k + 1]) or not min(e1, e2) <= target <= max(e1, e2):
                    continue
                w = 0.0 if e1 == e2 else (math.log(target) - math.log(e1)) / \
                    (math.log(e2) - math.log(e1))
                for name in result:
                    v1, v2 = wp[name].values[i, k], wp[name].values[i, k + 1]
                    if np.isfinite(v1) and np.isfinite(v2) and v1 > 0 and v2 > 0:
                        result[name][i, j] = math.exp((1 - w) * math.log(v1) +
                                                      w * math.log(v2))
                break
    dims = ("integrator", "error")
    return xr.Dataset({name: (dims, v) for name, v in result.items()},
                      coords={"integrator": wp.integrator.values, "error": targets})


# ------------------------------------------------------------ error estimate on a run
def estimate_error(scene: Scene, grid: Grid, *, sample: int = 32, seed: int = 0,
                   **run_kwargs) -> dict:
    """Estimate the global error of a run from a random sample of its trajectories
    (what ``sweep.run(..., estimate_error=N)`` attaches; see `sweep.engine.estimate_error`
    for the method and the attributes returned)."""
    from .engine import estimate_error as _estimate

    return _estimate(scene, grid, sample=sample, seed=seed, **run_kwargs)
