"""The physics of a sweep: a pendulum and the effects acting on it.

The equation of motion is

    theta'' = A sin(W t + phase) - c theta' - (g / L) f(theta)

with ``f = sin`` for the ``"nonlinear"`` model and ``f(theta) = theta`` for the
``"linear"`` (small-angle) model. Gravity is always present; damping (``c``) and
forcing (``A``, ``W``, ``phase``) are *effects*: a scene simulates only the effects
it lists, and the compiled kernel contains no term for an absent effect.

Everything here is frozen, validated, hashable dataclasses, so a scene can key the
kernel memo; nothing here compiles or computes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .._validate import check_choice, check_real

__all__ = ["Damping", "Forcing", "Scene", "MODELS", "PARAMETERS", "PARAMETER_INFO"]

#: Valid values of ``Scene.model``.
MODELS = ("nonlinear", "linear")

#: Every per-trajectory parameter, in the column order of the kernel's table.
PARAMETERS = (
    "theta0",
    "omega0",
    "damping",
    "forcing_amplitude",
    "forcing_frequency",
    "forcing_phase",
    "length",
    "gravity",
)

#: Units (UDUNITS strings) and long names of every parameter.
PARAMETER_INFO = {
    "theta0": ("rad", "initial angle from the downward vertical"),
    "omega0": ("rad s-1", "initial angular velocity"),
    "damping": ("s-1", "viscous damping coefficient c = C/m"),
    "forcing_amplitude": ("rad s-2", "forcing amplitude A (angular acceleration)"),
    "forcing_frequency": ("rad s-1", "forcing angular frequency W"),
    "forcing_phase": ("rad", "forcing phase (A sin(W t + phase))"),
    "length": ("m", "pendulum length L"),
    "gravity": ("m s-2", "gravitational acceleration g"),
}


@dataclass(frozen=True)
class Damping:
    """Linear viscous damping, the term ``-c theta'``.

    Parameters
    ----------
    coefficient : float
        ``c = C/m`` in 1/s (the seed's ``ksi``); finite and >= 0.
    """

    coefficient: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self,
            "coefficient",
            check_real("Damping.coefficient", self.coefficient, minimum=0.0,
                       accepted="a finite number >= 0 (1/s)"),
        )


@dataclass(frozen=True)
class Forcing:
    """Harmonic forcing, the term ``A sin(W t + phase)``.

    Parameters
    ----------
    amplitude : float
        ``A`` in rad/s^2 (force per unit ``m L``); finite.
    frequency : float
        ``W`` in rad/s; finite and >= 0.
    phase : float, default 0
        In rad; ``phase = pi/2`` gives ``A cos(W t)``, the convention of most literature.
    """

    amplitude: float
    frequency: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude", check_real("Forcing.amplitude", self.amplitude))
        object.__setattr__(
            self,
            "frequency",
            check_real("Forcing.frequency", self.frequency, minimum=0.0,
                       accepted="a finite number >= 0 (rad/s)"),
        )
        object.__setattr__(self, "phase", check_real("Forcing.phase", self.phase))


_EFFECT_TYPES = (Damping, Forcing)


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
    effects : tuple of Damping and Forcing, default ()
        At most one of each. Only the effects listed are simulated.

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
        if isinstance(effects, _EFFECT_TYPES):
            effects = (effects,)
        if not isinstance(effects, (tuple, list)):
            raise TypeError(
                f"effects must be a tuple of sweep.Damping / sweep.Forcing, got {effects!r}"
            )
        seen = set()
        for effect in effects:
            if not isinstance(effect, _EFFECT_TYPES):
                raise TypeError(
                    f"effects: {effect!r} is not an effect; accepted: sweep.Damping(c), "
                    "sweep.Forcing(amplitude, frequency, phase)"
                )
            if type(effect) in seen:
                raise ValueError(
                    f"effects: {type(effect).__name__} given twice; accepted: at most one of each"
                )
            seen.add(type(effect))
        # canonical order, so that equal scenes compare and hash equal
        effects = tuple(sorted(effects, key=lambda e: _EFFECT_TYPES.index(type(e))))
        object.__setattr__(self, "effects", effects)

    # -- which effects are present ------------------------------------------------
    def effect(self, kind: type) -> Any:
        """Return the effect of type ``kind`` in this scene, or None."""
        for effect in self.effects:
            if isinstance(effect, kind):
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
            Keys are `PARAMETERS` minus ``theta0``/``omega0``.
        """
        damping, forcing = self.damping, self.forcing
        return {
            "damping": damping.coefficient if damping else 0.0,
            "forcing_amplitude": forcing.amplitude if forcing else 0.0,
            "forcing_frequency": forcing.frequency if forcing else 0.0,
            "forcing_phase": forcing.phase if forcing else 0.0,
            "length": self.length,
            "gravity": self.gravity,
        }

    def to_dict(self) -> dict[str, Any]:
        """A plain, JSON- and TOML-friendly description (see `Scene.from_dict`)."""
        out: dict[str, Any] = {"gravity": self.gravity, "length": self.length,
                               "model": self.model}
        if self.damping:
            out["damping"] = {"coefficient": self.damping.coefficient}
        if self.forcing:
            f = self.forcing
            out["forcing"] = {"amplitude": f.amplitude, "frequency": f.frequency,
                              "phase": f.phase}
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
        accepted = ("gravity", "length", "model", "damping", "forcing")
        unknown = sorted(set(spec) - set(accepted))
        if unknown:
            raise ValueError(
                f"scene: unknown key(s) {', '.join(map(repr, unknown))}; "
                f"accepted: {', '.join(accepted)}"
            )
        effects = []
        if "damping" in spec:
            d = spec["damping"]
            effects.append(Damping(**_table("scene.damping", d, ("coefficient",))))
        if "forcing" in spec:
            f = spec["forcing"]
            effects.append(Forcing(**_table("scene.forcing", f,
                                            ("amplitude", "frequency", "phase"))))
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
