"""The scene: a pendulum, its model and the effects acting on it.

The equation of motion is

    theta'' = - (g / L) f(theta) + (the terms of the effects present)

with ``f = sin`` for the ``"nonlinear"`` model and ``f(theta) = theta`` for the
``"linear"`` (small-angle) model. Gravity is always present; damping, forcing and any
other registered effect (`sweep.physics.effects`) are simulated only when the scene
lists them: the compiled kernel contains no term for an absent effect.

Everything here is frozen, validated, hashable dataclasses, so a scene can key the
kernel memo; nothing here compiles or computes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .._validate import check_choice, check_real
from .effect import EFFECTS, Effect, Parameter
from .effects import Damping, Forcing

__all__ = ["BASE_PARAMETERS", "Damping", "Forcing", "MODELS", "Scene", "check_pendulum_scene",
           "parameter_info",
           "parameter_names", "parameter_table", "parameters"]

#: Valid values of ``Scene.model``.
MODELS = ("nonlinear", "linear")

#: The parameters every trajectory has, whatever its effects: the initial state and
#: the pendulum (their columns come first in the parameter table).
BASE_PARAMETERS = (
    Parameter("theta0", "theta0", "th0", "rad", "rad", "initial angle from the downward "
              "vertical", default=0.0, angle=True),
    Parameter("omega0", "omega0", "om0", "rad s-1", "rad/s", "initial angular velocity",
              default=0.0, angle=True),
    Parameter("length", "length", "L", "m", "m", "pendulum length L", minimum=0.0,
              strict=True),
    Parameter("gravity", "gravity", "g", "m s-2", "m/s^2", "gravitational acceleration g",
              minimum=0.0, strict=True),
)


def parameters() -> tuple[Parameter, ...]:
    """Every per-trajectory parameter, in the column order of the kernel's table: the
    base parameters, then each registered effect's, in registration order."""
    return BASE_PARAMETERS + tuple(p for cls in EFFECTS.values()
                                   for p in cls.declaration.parameters)


def parameter_names() -> tuple[str, ...]:
    """Names (grid axes, table columns) of `parameters`, in column order."""
    return tuple(p.axis for p in parameters())


def parameter_info() -> dict[str, tuple[str, str]]:
    """``{name: (units, long_name)}`` of every parameter (UDUNITS units)."""
    return {p.axis: (p.units, p.long_name) for p in parameters()}


def parameter_table() -> str:
    """The table of the scene's effects and parameters, as Markdown, written from the
    declarations (the documentation's page on scenes includes it, written when the site
    is built; a ``|`` inside a cell is escaped so that the row keeps its columns)."""
    rows = ["| effect | term in theta'' | conservative | argument | grid axis | units | "
            "meaning |", "|---|---|---|---|---|---|---|"]
    state, pendulum = BASE_PARAMETERS[:2], BASE_PARAMETERS[2:]
    groups = [("initial state", "", "", [(p, "(grid only)") for p in state]),
              ("`Scene` (always)", "- (g/L) f(theta)", "yes",
               [(p, f"`{p.field}`") for p in pendulum])]
    groups += [(f"`{cls.__name__}`", cls.declaration.equation.replace("|", "\\|"),
                "yes" if cls.declaration.conservative else "no",
                [(p, f"`{p.field}`") for p in cls.declaration.parameters])
               for cls in EFFECTS.values()]
    for effect, term, conservative, params in groups:
        for k, (p, argument) in enumerate(params):
            head = (effect, term, conservative) if k == 0 else ("", "", "")
            rows.append(f"| {' | '.join(head)} | {argument} | `{p.axis}` | {p.unit_text} | "
                        f"{p.long_name} |")
    return "\n".join(rows) + "\n"


def _effect_types() -> tuple[type[Effect], ...]:
    return tuple(EFFECTS.values())


def _accepted_effects() -> str:
    return ", ".join(cls.signature() for cls in _effect_types())


@dataclass(frozen=True)
class Scene:
    """A pendulum and the effects acting on it.

    Parameters
    ----------
    gravity : float, default 9.81
        ``g`` in m/s^2; finite and > 0.
    length : float, default 1.0
        ``L`` in m; finite and > 0. Only ``g/L`` enters the motion; ``L`` and ``g``
        also enter the rod tension ``T/m = L theta'^2 + g cos(theta)``.
    model : {"nonlinear", "linear"}
        ``"linear"`` replaces ``sin(theta)`` by ``theta`` (small-angle model).
    effects : tuple of effects, default ()
        `Damping`, `Forcing` (any registered effect), at most one of each. Only the
        effects listed are simulated.

    Examples
    --------
    >>> import sweep
    >>> scene = sweep.Scene(effects=(sweep.Damping(0.5),
    ...                              sweep.Forcing(amplitude=1.2, frequency=2 / 3)))
    >>> scene.natural_frequency
    3.1320919526731652
    """

    gravity: float = 9.81
    length: float = 1.0
    model: str = "nonlinear"
    effects: tuple = field(default=())

    def __post_init__(self) -> None:
        positive = "a finite number > 0"
        object.__setattr__(self, "gravity", check_real("gravity", self.gravity, minimum=0.0,
                                                       strict=True, accepted=positive + " (m/s^2)"))
        object.__setattr__(self, "length", check_real("length", self.length, minimum=0.0,
                                                      strict=True, accepted=positive + " (m)"))
        check_choice("model", self.model, MODELS)
        effects = self.effects
        if isinstance(effects, Effect):
            effects = (effects,)
        if not isinstance(effects, (tuple, list)):
            raise TypeError(f"effects must be a tuple of effects ({_accepted_effects()}), "
                            f"got {effects!r}")
        order = _effect_types()
        seen = set()
        for effect in effects:
            if not isinstance(effect, order):
                raise TypeError(f"effects: {effect!r} is not an effect; accepted: "
                                f"{_accepted_effects()}")
            if effect.coordinate is not None:
                raise ValueError(
                    f"effects: {effect!r} names a coordinate (on={effect.coordinate!r}), but "
                    "a sweep.Scene has one coordinate, theta, that every effect acts on; "
                    f"accepted: {type(effect).__name__} without on= in a Scene, or on= in "
                    "the effects of a system with several coordinates (sweep.DoublePendulum, "
                    "sweep.CoupledPendula, sweep.DeclaredSystem)")
            if type(effect) in seen:
                raise ValueError(
                    f"effects: {type(effect).__name__} given twice; accepted: at most one of each"
                )
            seen.add(type(effect))
        # canonical order, so that equal scenes compare and hash equal
        effects = tuple(sorted(effects, key=lambda e: order.index(type(e))))
        object.__setattr__(self, "effects", effects)

    # -- which effects are present ------------------------------------------------
    def effect(self, kind: type | str) -> Any:
        """The effect of type (or declared name) ``kind`` in this scene, or None."""
        for effect in self.effects:
            if (effect.declaration.name == kind if isinstance(kind, str)
                    else isinstance(effect, kind)):
                return effect
        return None

    @property
    def damping(self) -> Damping | None:
        """The scene's `Damping`, or None."""
        return self.effect(Damping)

    @property
    def forcing(self) -> Forcing | None:
        """The scene's `Forcing`, or None."""
        return self.effect(Forcing)

    @property
    def natural_frequency(self) -> float:
        """Small-angle angular frequency ``sqrt(g/L)`` in rad/s."""
        return math.sqrt(self.gravity / self.length)

    def parameters(self) -> dict[str, float]:
        """Values of every parameter except the initial state.

        Absent effects contribute zeros (which the kernel never reads).

        Returns
        -------
        dict
            Keys are `parameter_names` minus ``theta0``/``omega0``.
        """
        values = {"length": self.length, "gravity": self.gravity}
        for cls in _effect_types():
            values.update({p.axis: 0.0 for p in cls.declaration.parameters})
        for effect in self.effects:
            values.update(effect.values())
        return values

    def to_dict(self) -> dict[str, Any]:
        """A plain, JSON- and TOML-friendly description (see `Scene.from_dict`)."""
        out: dict[str, Any] = {"gravity": self.gravity, "length": self.length,
                               "model": self.model}
        for effect in self.effects:
            out[effect.declaration.name] = {p.field: getattr(effect, p.field)
                                            for p in effect.declaration.parameters}
        return out

    @classmethod
    def from_dict(cls, spec: dict[str, Any]) -> Scene:
        """Build a scene from the description `to_dict` writes (and TOML ``[scene]``).

        Raises
        ------
        ValueError
            On unknown keys, naming them and the accepted ones.
        """
        if not isinstance(spec, dict):
            raise ValueError(f"scene: expected a table of settings, got {spec!r}")
        accepted = ("gravity", "length", "model") + tuple(EFFECTS)
        unknown = sorted(set(spec) - set(accepted))
        if unknown:
            raise ValueError(
                f"scene: unknown key(s) {', '.join(map(repr, unknown))}; "
                f"accepted: {', '.join(accepted)}"
            )
        effects = []
        for name, effect_type in EFFECTS.items():
            if name in spec:
                fields = tuple(p.field for p in effect_type.declaration.parameters)
                effects.append(effect_type(**_table(f"scene.{name}", spec[name], fields)))
        kwargs = {k: spec[k] for k in ("gravity", "length", "model") if k in spec}
        return cls(effects=tuple(effects), **kwargs)


def _table(name: str, value: Any, accepted: tuple[str, ...]) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"{name}: expected a table with keys {', '.join(accepted)}, "
                         f"got {value!r}")
    unknown = sorted(set(value) - set(accepted))
    if unknown:
        raise ValueError(f"{name}: unknown key(s) {', '.join(map(repr, unknown))}; "
                         f"accepted: {', '.join(accepted)}")
    return value


def check_pendulum_scene(function: str, scene: Any) -> None:
    """Refuse a ``scene`` that is not a `sweep.Scene`, for a ``function`` made for the
    single pendulum only (a system such as `sweep.DoublePendulum` is refused by name).

    Raises
    ------
    ValueError
        ``"scene must be a sweep.Scene (the single pendulum), got {type}; accepted:
        ..."``, naming ``function``.
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a sweep.Scene (the single pendulum), got "
                         f"{type(scene).__name__}; accepted: a sweep.Scene ({function} "
                         "supports the single pendulum only, not a system such as "
                         "sweep.DoublePendulum or sweep.DeclaredSystem)")
