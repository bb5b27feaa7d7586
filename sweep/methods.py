"""Integrators as data: Butcher tableaux, symplectic splitting coefficients, a registry.

A method is a frozen, validated data object, not a loop: `sweep.kernels` generates the
step source from the coefficients. Adding a method means adding data and a `METHODS`
entry; ``sweep.run(..., method="rk38")`` and ``sweep.run(..., method=RK38)`` are the
same run.

Three kinds
-----------
`ButcherTableau` (``kind == "explicit"``)
    Fixed-step explicit Runge-Kutta: `EULER` (1), `HEUN` (2), `RK4` (4, the default),
    `RK38` (4). Forcing is evaluated at the stage times ``t_n + c_i dt`` with
    ``t_n = t0 + n dt``.
`ButcherTableau` with ``b_hat`` (``kind == "adaptive"``)
    An embedded pair with per-trajectory step-size control: `DOPRI5` (5(4)). Each
    trajectory adapts its own step to ``rtol``/``atol``, so one fast trajectory does not
    slow its neighbours.
`SplittingMethod` (``kind == "symplectic"``)
    Kick-drift compositions for the conservative pendulum ``theta'' = -(g/L) f(theta)``:
    `VERLET` (Stormer-Verlet, 2) and `YOSHIDA4` (Yoshida / Forest-Ruth, 4). Their
    energy error stays bounded over long runs (no secular drift). They are refused for
    scenes with damping or forcing, where they are neither symplectic nor of their
    nominal order in this form.

Coefficients given as ints, `fractions.Fraction` or strings such as ``"1/3"`` are kept
exact, and the checks on them (row sums, weights, order conditions) are exact too;
floats (for irrational coefficients) are checked to a few ulps.

References
----------
.. [HNW] E. Hairer, S. P. Norsett, G. Wanner, *Solving Ordinary Differential Equations
   I*, 2nd ed., Springer 1993 (tableaux, order conditions, step-size control II.4).
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
   Springer 2006 (Stormer-Verlet, compositions, bounded energy error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import cache

__all__ = [
    "ButcherTableau",
    "SplittingMethod",
    "Method",
    "METHODS",
    "DEFAULT_METHOD",
    "EULER",
    "HEUN",
    "RK4",
    "RK38",
    "DOPRI5",
    "VERLET",
    "YOSHIDA4",
    "resolve",
    "rooted_trees",
]

Number = Fraction | float

# Float coefficients (irrational ones, e.g. cube roots) are exact only to rounding: a sum
# of a handful of O(1) terms is off by a few ulps of 1, so 64 eps is a safe bound for
# the identity checks (row sums, sum of weights) yet far below any genuine error.
_FLOAT_SLACK = 64 * 2.0 ** -52


def _number(name: str, value) -> Number:
    """Coerce one coefficient: exact (Fraction) for ints, Fractions and ``"p/q"``
    strings; float otherwise."""
    if isinstance(value, bool):
        raise TypeError(f"{name}: coefficients must be numbers, got {value!r}")
    if isinstance(value, (int, Fraction)):
        return Fraction(value)
    if isinstance(value, str):
        try:
            return Fraction(value)
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"{name}: {value!r} is not a number or a fraction 'p/q'") \
                from None
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: coefficients must be numbers, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{name}: coefficients must be finite, got {value!r}")
    return number


def _vector(name: str, values) -> tuple[Number, ...]:
    try:
        items = tuple(values)
    except TypeError:
        raise TypeError(f"{name} must be a sequence of numbers, got {values!r}") from None
    return tuple(_number(f"{name}[{k}]", v) for k, v in enumerate(items))


def _exact(*numbers: Number) -> bool:
    return all(isinstance(x, Fraction) for x in numbers)


def _equal(x: Number, y: Number) -> bool:
    """Exact equality for Fractions; a few ulps of slack once a float is involved."""
    if _exact(x, y):
        return x == y
    return abs(float(x) - float(y)) <= _FLOAT_SLACK * max(1.0, abs(float(y)))


def _is_zero(x: Number) -> bool:
    return x == 0


# ------------------------------------------------------------------ order conditions
@cache
def rooted_trees(order: int) -> tuple[tuple, ...]:
    """All rooted trees with ``order`` nodes, each as a canonical nested tuple (the
    sorted tuple of its subtrees; a leaf is ``()``).

    The number of trees of order 1..6 is 1, 1, 2, 4, 9, 20 ([HNW] II.2); each gives
    one order condition of a Runge-Kutta method.
    """
    if order < 1:
        return ()
    if order == 1:
        return ((),)

    def grow(tree):
        """Every tree made by attaching one new leaf to some node of ``tree``."""
        yield tuple(sorted(tree + ((),)))  # a new child of the root
        for k, child in enumerate(tree):
            for bigger in grow(child):
                yield tuple(sorted(tree[:k] + (bigger,) + tree[k + 1:]))

    return tuple(sorted({t for smaller in rooted_trees(order - 1) for t in grow(smaller)}))


def _tree_size(tree) -> int:
    return 1 + sum(_tree_size(child) for child in tree)


def _density(tree) -> int:
    """gamma(t) = |t| prod gamma(children)."""
    return _tree_size(tree) * math.prod(_density(child) for child in tree)


def _stage_weights(tree, a) -> list:
    """The vector Phi_i(t): 1 for a leaf; prod over children of (A Phi(child))_i."""
    s = len(a)
    result = [Fraction(1)] * s
    for child in tree:
        inner = _stage_weights(child, a)
        result = [result[i] * sum(a[i][j] * inner[j] for j in range(s)) for i in range(s)]
    return result


def _condition_residual(tree, a, b) -> Number:
    """b . Phi(t) - 1/gamma(t): zero when the method satisfies the condition of ``tree``."""
    phi = _stage_weights(tree, a)
    return sum(b[i] * phi[i] for i in range(len(b))) - Fraction(1, _density(tree))


def _order_of(a, b, limit: int) -> int:
    """Largest p <= limit with every order condition up to p satisfied."""
    for p in range(1, limit + 1):
        for tree in rooted_trees(p):
            residual = _condition_residual(tree, a, b)
            if _exact(residual):
                failed = not _is_zero(residual)
            else:  # float coefficients: a residual of rounding size counts as zero
                failed = abs(float(residual)) > 1e3 * _FLOAT_SLACK
            if failed:
                return p - 1
    return limit


# ------------------------------------------------------------------------- tableaux
@dataclass(frozen=True)
class ButcherTableau:
    """An explicit Runge-Kutta method (and optionally an embedded pair), as data.

    Parameters
    ----------
    name : str
        Registry key and the ``method`` attribute of a dataset.
    a : sequence of sequences, shape (s, s) or the s ragged rows of the lower triangle
        Stage coefficients; must be strictly lower-triangular (explicit).
    b : sequence, length s
        Weights of the propagated solution; ``sum(b) == 1``.
    c : sequence, length s
        Nodes (stage times ``t + c_i dt``); ``c_i == sum_j a_ij``.
    order : int
        Order of ``b``; verified against the order conditions (rooted trees) up to
        ``order`` exactly, and ``order + 1`` must fail (the claim is sharp).
    source : str
        Where the coefficients come from.
    b_hat : sequence, length s, optional
        Embedded weights for error estimation; makes the method adaptive.
    embedded_order : int, optional
        Order of ``b_hat`` (required with ``b_hat``), verified like ``order``.
    fsal : bool
        First stage of the next step is the last stage of this one (requires
        ``c[-1] == 1`` and last row of ``a`` equal to ``b``); an accepted step then
        costs one stage less.

    Raises
    ------
    ValueError
        Naming the tableau and the violated property.
    """

    name: str
    a: tuple
    b: tuple
    c: tuple
    order: int
    source: str
    b_hat: tuple | None = None
    embedded_order: int | None = None
    fsal: bool = False

    def __post_init__(self) -> None:
        who = f"ButcherTableau {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"ButcherTableau.name must be a non-empty string, got "
                             f"{self.name!r}")
        b = _vector(f"{who}: b", self.b)
        c = _vector(f"{who}: c", self.c)
        s = len(b)
        if s == 0:
            raise ValueError(f"{who}: b is empty; accepted: at least one stage")
        if len(c) != s:
            raise ValueError(f"{who}: c has {len(c)} entries but b has {s}")
        try:
            rows = tuple(self.a)
        except TypeError:
            raise TypeError(f"{who}: a must be a sequence of rows, got {self.a!r}") from None
        if len(rows) != s:
            raise ValueError(f"{who}: a has {len(rows)} rows but there are {s} stages")
        a = []
        for i, row in enumerate(rows):
            row = _vector(f"{who}: a[{i}]", row)
            if len(row) > s:
                raise ValueError(f"{who}: a[{i}] has {len(row)} entries; accepted: at most {s}")
            row = row + (Fraction(0),) * (s - len(row))
            upper = [j for j in range(i, s) if not _is_zero(row[j])]
            if upper:
                raise ValueError(
                    f"{who}: a must be strictly lower-triangular (explicit method), "
                    f"but a[{i}][{upper[0]}] = {row[upper[0]]}"
                )
            if not _equal(sum(row, Fraction(0)), c[i]):
                raise ValueError(f"{who}: row sum of a[{i}] is {float(sum(row)):.17g} but "
                                 f"c[{i}] = {float(c[i]):.17g}; they must be equal")
            a.append(row)
        a = tuple(a)
        if not _equal(sum(b, Fraction(0)), Fraction(1)):
            raise ValueError(f"{who}: sum(b) = {float(sum(b)):.17g}; it must be 1")
        if not _is_zero(c[0]):
            raise ValueError(f"{who}: c[0] = {c[0]}; an explicit method starts at c[0] = 0")
        if isinstance(self.order, bool) or not isinstance(self.order, int) or self.order < 1:
            raise ValueError(f"{who}: order must be an int >= 1, got {self.order!r}")
        actual = _order_of(a, b, self.order + 1)
        if actual != self.order:
            raise ValueError(f"{who}: claimed order {self.order} but its weights b satisfy "
                             f"the order conditions up to order {actual}")
        b_hat = None
        if self.b_hat is not None:
            b_hat = _vector(f"{who}: b_hat", self.b_hat)
            if len(b_hat) != s:
                raise ValueError(f"{who}: b_hat has {len(b_hat)} entries but b has {s}")
            if not _equal(sum(b_hat, Fraction(0)), Fraction(1)):
                raise ValueError(f"{who}: sum(b_hat) = {float(sum(b_hat)):.17g}; it must be 1")
            eo = self.embedded_order
            if isinstance(eo, bool) or not isinstance(eo, int) or not 1 <= eo < self.order:
                raise ValueError(f"{who}: embedded_order must be an int in [1, order), got "
                                 f"{eo!r}")
            actual = _order_of(a, b_hat, eo + 1)
            if actual != eo:
                raise ValueError(f"{who}: claimed embedded order {eo} but b_hat satisfies "
                                 f"the order conditions up to order {actual}")
        elif self.embedded_order is not None:
            raise ValueError(f"{who}: embedded_order given without b_hat")
        if self.fsal and not (_equal(c[-1], Fraction(1))
                              and all(_equal(x, y) for x, y in zip(a[-1], b))):
            raise ValueError(f"{who}: fsal needs c[-1] == 1 and the last row of a equal to b")
        if not isinstance(self.source, str) or not self.source.strip():
            raise ValueError(f"{who}: source must say where the coefficients come from")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "b_hat", b_hat)

    @property
    def stages(self) -> int:
        """Number of stages s."""
        return len(self.b)

    @property
    def kind(self) -> str:
        """``"adaptive"`` for an embedded pair, else ``"explicit"``."""
        return "adaptive" if self.b_hat is not None else "explicit"

    @property
    def adaptive(self) -> bool:
        return self.b_hat is not None

    @property
    def conservative_only(self) -> bool:
        return False

    @property
    def rhs_per_step(self) -> int:
        """Right-hand-side evaluations per step (per attempted step for a pair); with
        FSAL the first stage comes from the previous step."""
        return self.stages - 1 if self.fsal else self.stages

    @property
    def rhs_initial(self) -> int:
        """Evaluations made once before the first step (the FSAL first stage)."""
        return 1 if self.fsal else 0

    @property
    def error_weights(self) -> tuple[Number, ...]:
        """``b - b_hat``: the local error estimate is ``dt * sum_i e_i k_i``."""
        if self.b_hat is None:
            raise ValueError(f"{self.name!r} has no embedded weights")
        return tuple(x - y for x, y in zip(self.b, self.b_hat))


# ------------------------------------------------------------------------ splitting
@dataclass(frozen=True)
class SplittingMethod:
    """A symplectic kick-drift composition for ``q' = p, p' = F(q)``, as data.

    One step of size ``dt`` is, for ``i = 0 .. s-1``::

        p += kick[i] * dt * F(q)      (skipped when kick[i] == 0)
        q += drift[i] * dt * p        (skipped when drift[i] == 0)

    A kick right after another kick (or at the start of a step, after the previous
    step's last kick) reuses the force at the same ``q``, so Stormer-Verlet
    (``kick = (1/2, 1/2)``, ``drift = (1, 0)``) costs one force evaluation per step.

    Parameters
    ----------
    name : str
    kick, drift : sequence of numbers, same length
        Each must sum to 1 (consistency).
    order : int
        Nominal order (checked numerically by the test suite).
    source : str
        Where the coefficients come from.

    Notes
    -----
    Only for conservative scenes (no damping, no forcing): `sweep.run` refuses the
    others before any compute.
    """

    name: str
    kick: tuple
    drift: tuple
    order: int
    source: str

    def __post_init__(self) -> None:
        who = f"SplittingMethod {self.name!r}"
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"SplittingMethod.name must be a non-empty string, got "
                             f"{self.name!r}")
        kick = _vector(f"{who}: kick", self.kick)
        drift = _vector(f"{who}: drift", self.drift)
        if not kick or len(kick) != len(drift):
            raise ValueError(f"{who}: kick and drift must be non-empty and of equal length, "
                             f"got {len(kick)} and {len(drift)}")
        for label, coeffs in (("kick", kick), ("drift", drift)):
            if not _equal(sum(coeffs, Fraction(0)), Fraction(1)):
                raise ValueError(f"{who}: sum({label}) = {float(sum(coeffs)):.17g}; it must "
                                 "be 1")
        if isinstance(self.order, bool) or not isinstance(self.order, int) or self.order < 1:
            raise ValueError(f"{who}: order must be an int >= 1, got {self.order!r}")
        if not isinstance(self.source, str) or not self.source.strip():
            raise ValueError(f"{who}: source must say where the coefficients come from")
        object.__setattr__(self, "kick", kick)
        object.__setattr__(self, "drift", drift)

    kind = "symplectic"
    adaptive = False
    conservative_only = True

    def _evaluations(self) -> tuple[int, int]:
        """(force evaluations per step, before the first step), following the reuse
        rule of the class docstring: the force is stale only after a drift."""
        stale, per_step = False, 0
        for k, d in zip(self.kick, self.drift):
            if not _is_zero(k) and stale:
                per_step += 1
                stale = False
            if not _is_zero(d):
                stale = True
        if stale:  # refresh at the end of the step, for the next step's first kick
            per_step += 1
        return per_step, 1

    @property
    def rhs_per_step(self) -> int:
        return self._evaluations()[0]

    @property
    def rhs_initial(self) -> int:
        return self._evaluations()[1]


Method = ButcherTableau | SplittingMethod

# --------------------------------------------------------------------------- the data
F = Fraction

EULER = ButcherTableau(
    name="euler", a=((0,),), b=(1,), c=(0,), order=1,
    source="L. Euler, Institutiones calculi integralis (1768); [HNW] I.7",
)

HEUN = ButcherTableau(
    name="heun", a=((0, 0), (1, 0)), b=(F(1, 2), F(1, 2)), c=(0, 1), order=2,
    source="K. Heun, Z. Math. Phys. 45 (1900) 23-38; [HNW] II.1, Table 1.1 (RK2, "
           "explicit trapezoidal rule)",
)

RK4 = ButcherTableau(
    name="rk4",
    a=((0, 0, 0, 0), (F(1, 2), 0, 0, 0), (0, F(1, 2), 0, 0), (0, 0, 1, 0)),
    b=(F(1, 6), F(1, 3), F(1, 3), F(1, 6)),
    c=(0, F(1, 2), F(1, 2), 1),
    order=4,
    source="W. Kutta, Z. Math. Phys. 46 (1901) 435-453; [HNW] II.1, Table 1.2 left "
           "(classical Runge-Kutta)",
)

RK38 = ButcherTableau(
    name="rk38",
    a=((0, 0, 0, 0), (F(1, 3), 0, 0, 0), (F(-1, 3), 1, 0, 0), (1, -1, 1, 0)),
    b=(F(1, 8), F(3, 8), F(3, 8), F(1, 8)),
    c=(0, F(1, 3), F(2, 3), 1),
    order=4,
    source="W. Kutta, Z. Math. Phys. 46 (1901) 435-453; [HNW] II.1, Table 1.2 right "
           "(3/8 rule)",
)

DOPRI5 = ButcherTableau(
    name="dopri5",
    a=(
        (),
        (F(1, 5),),
        (F(3, 40), F(9, 40)),
        (F(44, 45), F(-56, 15), F(32, 9)),
        (F(19372, 6561), F(-25360, 2187), F(64448, 6561), F(-212, 729)),
        (F(9017, 3168), F(-355, 33), F(46732, 5247), F(49, 176), F(-5103, 18656)),
        (F(35, 384), 0, F(500, 1113), F(125, 192), F(-2187, 6784), F(11, 84)),
    ),
    b=(F(35, 384), 0, F(500, 1113), F(125, 192), F(-2187, 6784), F(11, 84), 0),
    b_hat=(F(5179, 57600), 0, F(7571, 16695), F(393, 640), F(-92097, 339200),
           F(187, 2100), F(1, 40)),
    c=(0, F(1, 5), F(3, 10), F(4, 5), F(8, 9), 1, 1),
    order=5,
    embedded_order=4,
    fsal=True,
    source="J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19-26; "
           "[HNW] II.5, Table 5.2 (DOPRI5, local extrapolation: the 5th-order "
           "solution is propagated)",
)

VERLET = SplittingMethod(
    name="verlet", kick=(F(1, 2), F(1, 2)), drift=(1, 0), order=2,
    source="C. Stormer (1907); L. Verlet, Phys. Rev. 159 (1967) 98-103; [HLW] I.3.1 "
           "(velocity form: kick dt/2, drift dt, kick dt/2)",
)

_CBRT2 = 2.0 ** (1.0 / 3.0)
_W1 = 1.0 / (2.0 - _CBRT2)  # outer sub-step of the triple jump
_W0 = -_CBRT2 / (2.0 - _CBRT2)  # the backward middle sub-step

YOSHIDA4 = SplittingMethod(
    name="yoshida4",
    kick=(_W1 / 2, (_W1 + _W0) / 2, (_W0 + _W1) / 2, _W1 / 2),
    drift=(_W1, _W0, _W1, 0),
    order=4,
    source="H. Yoshida, Phys. Lett. A 150 (1990) 262-268 (triple jump of Stormer-Verlet, "
           "w1 = 1/(2 - 2^(1/3)), w0 = -2^(1/3)/(2 - 2^(1/3))); identical to E. Forest, "
           "R. D. Ruth, Physica D 43 (1990) 105-117; [HLW] II.4",
)

#: Every method by name. RK4 is the default.
METHODS: dict[str, Method] = {
    m.name: m for m in (EULER, HEUN, RK4, RK38, DOPRI5, VERLET, YOSHIDA4)
}

DEFAULT_METHOD = "rk4"


def resolve(method) -> Method:
    """The method object for a registry name or a method object.

    Parameters
    ----------
    method : str, ButcherTableau or SplittingMethod

    Raises
    ------
    ValueError
        For an unknown name or another kind of object, listing the valid names.
    """
    if isinstance(method, (ButcherTableau, SplittingMethod)):
        return method
    if isinstance(method, str) and method in METHODS:
        return METHODS[method]
    raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))} (or a "
                     f"sweep.methods.ButcherTableau / SplittingMethod), got {method!r}")
