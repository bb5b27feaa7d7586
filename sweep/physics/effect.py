"""What an effect is: one declaration that every layer reads.

An effect (damping, forcing, ...) is a frozen dataclass deriving from `Effect` whose
class attribute ``declaration`` says, once, everything the rest of sweep needs:

- its parameters (`Parameter`): constructor field, grid axis and parameter-table
  column, kernel symbol, units, long name, lower bound, default, whether TOML accepts
  degrees for it;
- its term in the acceleration ``theta''``, as kernel source in the state ``th, om``
  and its symbols (``"- c * om"``), and, for a time-dependent term, the harmonic
  `Drive` whose value ``amplitude * sin(frequency * t + phase)`` the kernel evaluates
  at every stage time (once per block when no trajectory differs in frequency and
  phase);
- what it adds to the linearisation at the bottom (``theta'' + C theta' + K theta``:
  ``linear_damping`` adds to C, ``linear_stiffness`` to K; the stability guard reads
  them) and to the rod tension per unit mass (``tension``);
- its Jacobian: the derivatives of its term with respect to ``theta`` and ``theta'``
  (``jacobian_theta``, ``jacobian_omega``), which the tangent dynamics of the
  ``lyapunov`` observable read;
- whether it is conservative (symplectic methods accept only conservative effects);
- its generalized force on one coordinate of a system (``generalized_force``), for the
  effects a system takes per coordinate (``sweep.Damping(0.1, on="theta1")``: see
  `sweep.physics.coordinate_effects`).

`register` adds an effect to `EFFECTS`; the kernel generator (`sweep.kernels`), the
grid, the dataset attributes, the TOML reader and the stability guard then take it
without any other change. Declarations are plain data (strings, numbers, tuples), so
they hash, compare and pickle: a kernel spec carries the declarations it was built
from, and a Dask worker needs no registry.

For developers: a new effect is a subclass plus `register`::

    @register
    @dataclass(frozen=True)
    class TorsionSpring(Effect):
        stiffness: float
        declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
            name="spring", term="- kappa * th", equation="- kappa theta",
            parameters=(Parameter("spring_stiffness", "stiffness", "kappa", "s-2", "1/s^2",
                                  "torsion spring stiffness", minimum=0.0),),
            conservative=True, linear_stiffness="kappa", switched_on_by_grid=True,
            jacobian_theta="- kappa")
"""

from __future__ import annotations

import keyword
import math
import re
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np

from .._validate import check_real

__all__ = ["Drive", "Effect", "EffectDeclaration", "EFFECTS", "Parameter", "RESERVED_SYMBOLS",
           "on_field", "register", "unregister"]

_IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")

#: Kernel names an effect's symbols must not take (state, base parameters, loop and
#: kernel variables).
RESERVED_SYMBOLS = frozenset({
    "th", "om", "th0", "om0", "L", "g", "w0sq", "t", "t0", "dt", "h", "i", "j", "b", "n",
    "step", "base", "params", "out", "status", "saved", "stats", "math", "np", "vsin",
    "vcos", "accel", "energy", "kernel", "prange", "njit", "JIT", "BLOCK", "TWO_PI",
    "acc", "tension", "done", "FTH", "TIME", "omega_max", "k", "p0", "f0", "DFTH",
    "vsincos", "accel_jac", "blocks", "grouped", "run_blocks", "b_first", "b_stop",
    "g_first", "g_stop", "n_groups",
})


@dataclass(frozen=True)
class Parameter:
    """One parameter of an effect.

    Attributes
    ----------
    axis : str
        Grid axis name and parameter-table column (``"forcing_amplitude"``); unique
        across effects.
    field : str
        Constructor argument and attribute of the effect (``"amplitude"``).
    symbol : str
        Kernel variable holding it (``"A"``).
    units : str
        UDUNITS string for the dataset (``"rad s-2"``).
    unit_text : str
        Units as written in messages (``"rad/s^2"``).
    long_name : str
        CF long name of the coordinate or attribute.
    minimum : float, optional
        Lower bound (inclusive unless ``strict``).
    strict : bool
    default : float, optional
        Value when the constructor is not given it; a parameter with a default need
        not be a grid axis for the grid alone to switch its effect on.
    angle : bool
        A TOML grid axis may give it in degrees (``units = "deg"``).
    """

    axis: str
    field: str
    symbol: str
    units: str
    unit_text: str
    long_name: str
    minimum: float | None = None
    strict: bool = False
    default: float | None = None
    angle: bool = False

    def accepted(self, plural: bool = False) -> str:
        """What values are accepted, for messages: ``"a finite number >= 0 (1/s)"``."""
        text = "finite numbers" if plural else "a finite number"
        if self.minimum is not None:
            text += f" {'>' if self.strict else '>='} {self.minimum:g} ({self.unit_text})"
        return text

    def is_outside(self, value) -> Any:
        """True (elementwise) where ``value`` violates the lower bound."""
        if self.minimum is None:
            return np.zeros(np.shape(value), dtype=bool)  # never, with the caller's shape
        return value <= self.minimum if self.strict else value < self.minimum


@dataclass(frozen=True)
class Drive:
    """A harmonic signal ``amplitude * sin(frequency * t + phase)`` of an effect.

    Attributes
    ----------
    value : str
        Kernel variable stem of the signal's value at a stage time (``"f"``); the
        effect's ``term`` uses it.
    amplitude, frequency, phase : str
        Symbols of the effect's parameters that make the signal (``amplitude`` may be
        an expression in them and in ``L``, ``g``).
    function : {"sin", "cos"}
        The harmonic function (``cos`` for a signal written ``a cos(nu t + psi)``).
    """

    value: str
    amplitude: str
    frequency: str
    phase: str
    function: str = "sin"


@dataclass(frozen=True)
class EffectDeclaration:
    """Everything sweep needs to know about an effect (see the module docstring).

    Attributes
    ----------
    name : str
        Lower-case key: the ``[scene.<name>]`` TOML table, the dataset's ``effects``
        attribute, the kernel spec.
    parameters : tuple of Parameter
    term : str
        Source of its term in ``theta''``, starting with its sign (``"- c * om"``); may
        read ``th``, ``om``, ``L``, ``g``, its symbols, its drive value and ``FTH``, the
        model's ``f(theta)`` (``vsin(th)`` or ``th``).
    equation : str
        The term as printed in the dataset's ``equation`` attribute (``"- c theta'"``).
    conservative : bool
        True if it derives from a potential (energy is conserved without others).
    jacobian_theta, jacobian_omega : str or None
        Source of the derivative of ``term`` with respect to ``th`` and to ``om``,
        with its sign (``"- c"``; ``"+ p * DFTH"``, where ``DFTH`` is the model's
        ``f'(theta)``: ``cos(theta)``, or 1 for the linear model); the ``lyapunov``
        observable integrates the tangent dynamics with them. ``""`` where the term
        does not read that variable (its derivative is zero); None (the default)
        where the term reads it: undeclared, and ``lyapunov`` is refused for a scene
        with this effect. `jacobian_missing` says which are missing.
    drive : Drive, optional
    linear_damping, linear_stiffness : str
        Expressions in its symbols (and ``L``, ``g``, ``omega_max``: a bound on
        ``|theta'|`` over the run, see ``speed_bound``) added to ``C`` and the largest
        ``K`` of the linearisation ``theta'' + C theta' + K theta = ...`` at the bottom
        ("" for none); the stability guard reads them.
    force_bound : str
        For an effect that can feed energy in (a torque, a drive): a bound on the
        magnitude of its term over every state and time of the nonlinear model, an
        expression in its symbols, ``L`` and ``g`` ("" for none).
    speed_bound : str
        For an effect that caps the speed (drag): a bound on ``|theta'|`` it enforces
        once ``|theta'|`` is above the starts', an expression in its symbols and
        ``force_max`` (``g/L`` plus every effect's ``force_bound``); ``math.inf`` where
        it caps nothing. The guard's ``omega_max``: without a speed-capping effect, the
        bound from the starts' energy (exact for an undriven pendulum); with one and no
        nonzero force, the smaller of that and ``max(|omega0|, speed_bound)``; with
        forces, ``max(|omega0|, speed_bound)`` (nonlinear model; the linear model keeps
        the energy bound, which forces can exceed).
    generalized_force : str
        Its generalized force on one coordinate of a system, in its symbols, the
        coordinate ``q``, its velocity ``v`` and time ``t`` (SymPy syntax: ``"-c*v"``);
        "" (the default) where it does not act on a system's coordinate. An effect that
        declares one has a keyword field ``on`` (`on_field`).
    """

    name: str
    parameters: tuple[Parameter, ...]
    term: str
    equation: str
    conservative: bool
    drive: Drive | None = None
    linear_damping: str = ""
    linear_stiffness: str = ""
    tension: str = ""
    switched_on_by_grid: bool = False
    force_bound: str = ""
    speed_bound: str = ""
    jacobian_theta: str | None = None
    jacobian_omega: str | None = None
    generalized_force: str = ""

    def jacobian(self, variable: str) -> str:
        """Source of d(term)/d(``variable``) (``"th"`` or ``"om"``), ``""`` for zero.

        Raises
        ------
        ValueError
            Where the term reads the variable and the declaration gives no derivative.
        """
        declared = self.jacobian_theta if variable == "th" else self.jacobian_omega
        if declared is None:
            if variable not in self.reads:
                return ""
            raise ValueError(f"effect {self.name!r} declares no jacobian_"
                             f"{'theta' if variable == 'th' else 'omega'} (the derivative of "
                             f"its term {self.term!r}), so its tangent dynamics are unknown")
        return declared

    @property
    def reads(self) -> frozenset[str]:
        """Which of the state variables ``th``, ``om`` its term reads (``FTH`` is f(th))."""
        names = set(_IDENTIFIER.findall(self.term))
        if "FTH" in names:
            names.add("th")
        return frozenset(names & {"th", "om"})

    def jacobian_missing(self) -> tuple[str, ...]:
        """The state variables (``"theta"``, ``"omega"``) its term reads without a
        declared derivative (empty when its tangent dynamics are known)."""
        missing = []
        for variable, word in (("th", "theta"), ("om", "omega")):
            try:
                self.jacobian(variable)
            except ValueError:
                missing.append(word)
        return tuple(missing)

    @property
    def symbols(self) -> tuple[str, ...]:
        """Kernel symbols of its parameters, in declaration order."""
        return tuple(p.symbol for p in self.parameters)

    @property
    def axes(self) -> tuple[str, ...]:
        """Grid axes (parameter-table columns) of its parameters."""
        return tuple(p.axis for p in self.parameters)

    def linearisation(self, values: dict[str, float]) -> tuple[float, float]:
        """``(C, K)`` it adds to the linearisation, for values by symbol (its own, and
        ``L``, ``g``, ``omega_max``)."""
        return (_evaluate(self.linear_damping, values, 0.0),
                _evaluate(self.linear_stiffness, values, 0.0))

    def bound(self, which: str, values: dict[str, float]) -> float | None:
        """Its ``force_bound`` or ``speed_bound`` (``which``) for values by symbol;
        None where it declares none."""
        return _evaluate(getattr(self, which), values, None)


def _evaluate(expression: str, values: dict[str, float], empty):
    """A declared expression's value (``empty`` for ""): only ``math``, ``abs`` and the
    given names are in scope."""
    if not expression:
        return empty
    return float(eval(expression, {"__builtins__": {}, "math": math, "abs": abs},
                      dict(values)))


def on_field():
    """The keyword field ``on`` of an effect that declares a ``generalized_force``:
    the name of the system coordinate it acts on (``"theta1"``), or None (default: on a
    `sweep.Scene`, its one coordinate; `sweep.Damping` on a system: mass-proportional).

    Keyword-only, so the effect's positional arguments stay its parameters, and left
    out of the generated ``repr`` (`Effect.__repr__` shows it only when given)."""
    return field(default=None, kw_only=True, repr=False)


class Effect:
    """Base class of the effects: a frozen dataclass with a ``declaration``.

    Every field is validated from its `Parameter` (a finite real number above the
    declared bound); the subclass declares the fields in the order of its parameters,
    then, if it declares a ``generalized_force``, the keyword field ``on``
    (`on_field`).
    """

    declaration: ClassVar[EffectDeclaration]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        for p in self.declaration.parameters:
            object.__setattr__(self, p.field, check_real(
                f"{owner}.{p.field}", getattr(self, p.field), minimum=p.minimum,
                strict=p.strict, accepted=p.accepted()))
        on = getattr(self, "on", None)
        if on is not None and (not isinstance(on, str) or not on.isidentifier()):
            raise ValueError(f"{owner}.on={on!r} is not accepted; accepted: None, or the "
                             "name of a system's coordinate (a string such as 'theta1')")

    @property
    def coordinate(self) -> str | None:
        """The system coordinate it acts on (its ``on``), or None."""
        return getattr(self, "on", None)

    def __repr__(self) -> str:
        """``Damping(coefficient=0.1)``; with ``on``: ``Damping(coefficient=0.1,
        on='theta1')`` (for the effects whose dataclass repr is switched off)."""
        shown = [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self)
                 if f.name != "on"]
        if self.coordinate is not None:
            shown.append(f"on={self.coordinate!r}")
        return f"{type(self).__name__}({', '.join(shown)})"

    def values(self) -> dict[str, float]:
        """Its parameter values by grid axis name."""
        return {p.axis: getattr(self, p.field) for p in self.declaration.parameters}

    @classmethod
    def signature(cls) -> str:
        """``sweep.Forcing(amplitude, frequency, phase)``, for messages."""
        return (f"sweep.{cls.__name__}("
                f"{', '.join(f.name for f in fields(cls) if f.name != 'on')})")


#: Registered effects by name, in canonical order (the order of their terms in the
#: acceleration, of their columns in the parameter table, of ``Scene.effects``).
EFFECTS: dict[str, type[Effect]] = {}


def _check_declaration(cls: type) -> EffectDeclaration:
    declaration = getattr(cls, "declaration", None)
    if not isinstance(declaration, EffectDeclaration):
        raise TypeError(f"{cls.__name__} needs a class attribute 'declaration' "
                        "(an EffectDeclaration)")
    if declaration.name in EFFECTS and EFFECTS[declaration.name] is not cls:
        raise ValueError(f"an effect named {declaration.name!r} is already registered "
                         f"({EFFECTS[declaration.name].__name__})")
    field_names = [f.name for f in fields(cls)]
    expected = [p.field for p in declaration.parameters]
    if declaration.generalized_force:
        expected.append("on")
    if field_names != expected:
        raise ValueError(f"{cls.__name__}: fields {field_names} must be its parameters' "
                         f"fields {expected[:len(declaration.parameters)]}, in order"
                         + (", then on (on_field())" if declaration.generalized_force
                            else ""))
    taken_axes = {p.axis for other in EFFECTS.values() if other is not cls
                  for p in other.declaration.parameters}
    taken_symbols = {s for other in EFFECTS.values() if other is not cls
                     for s in other.declaration.symbols}
    if declaration.drive is not None and declaration.drive.function not in ("sin", "cos"):
        raise ValueError(f"{cls.__name__}: drive function must be 'sin' or 'cos', got "
                         f"{declaration.drive.function!r}")
    if declaration.drive is not None:
        taken_values = {other.declaration.drive.value for other in EFFECTS.values()
                        if other is not cls and other.declaration.drive is not None}
        value = declaration.drive.value
        if (not value.isidentifier() or value in RESERVED_SYMBOLS or value in taken_values
                or value in declaration.symbols):
            raise ValueError(f"{cls.__name__}: drive value {value!r} is reserved, taken or "
                             "not an identifier")
    for p in declaration.parameters:
        if p.axis in taken_axes or p.axis in ("theta0", "omega0", "length", "gravity"):
            raise ValueError(f"{cls.__name__}: grid axis {p.axis!r} is taken")
        if (not p.symbol.isidentifier() or keyword.iskeyword(p.symbol)
                or p.symbol in RESERVED_SYMBOLS or p.symbol in taken_symbols):
            raise ValueError(f"{cls.__name__}: kernel symbol {p.symbol!r} is reserved, "
                             "taken or not an identifier")
    return declaration


def register(cls: type[Effect]) -> type[Effect]:
    """Add an effect class to `EFFECTS` (a class decorator); returns the class.

    Raises
    ------
    TypeError, ValueError
        On a missing or inconsistent declaration, or a name, axis or symbol that is
        taken.
    """
    declaration = _check_declaration(cls)
    EFFECTS[declaration.name] = cls
    return cls


def unregister(name: str) -> None:
    """Remove the effect ``name`` from `EFFECTS` (for tests that declare their own)."""
    EFFECTS.pop(name, None)
