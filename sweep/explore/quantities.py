"""The explorer's quantities: the maps it can draw of a single pendulum's scene, each with
the observables `sweep.run` computes for it, the `sweep.maps` function that makes it and
the Python expression the snippets write (systems and networks add theirs:
`sweep.explore.systems`, `sweep.explore.networks`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .. import maps
from ..physics import Scene

__all__ = ["QUANTITIES", "Quantity", "default_quantity", "effect_names", "forced"]


def effect_names(scene: Scene) -> set[str]:
    return {effect.declaration.name for effect in scene.effects}


def forced(scene: Scene) -> bool:
    return scene.forcing is not None


def _only_damping(scene: Scene) -> bool:
    return effect_names(scene) == {"damping"}


def _pivot(scene: Scene) -> bool:
    return "pivot" in effect_names(scene)


def _always(scene: Scene) -> bool:
    return True


@dataclass(frozen=True)
class Quantity:
    """One map the explorer can draw.

    Attributes
    ----------
    name : str
        Key (``"basins"``, ``"var:theta_final"``).
    label : str
        What the selector shows.
    observe : tuple of str
        The observables `sweep.run` computes for it.
    stop_early : bool
        Run with ``stop_early=True`` (only with settled observables).
    applies : callable
        ``applies(scene) -> bool``: offered for this scene.
    compute : callable
        ``compute(ds) -> xarray.DataArray``: the map (a `sweep.maps` function or a
        variable of the dataset).
    discrete : bool
        Integer labels with a legend (else a continuous colour bar).
    pilot : bool
        Forced basins: find the attractors first (`sweep.maps.pilot_catalogue`).
    expression : str
        The Python expression of the map of ``ds``, for the snippets.
    """

    name: str
    label: str
    observe: tuple[str, ...]
    stop_early: bool
    applies: Callable[[Scene], bool]
    compute: Callable[[Any], Any]
    discrete: bool
    pilot: bool = False
    expression: str = ""


def _variable(name: str, observable: str, label: str, applies=_always) -> Quantity:
    return Quantity(f"var:{name}", label, (observable,), False, applies,
                    lambda ds, name=name: ds[name], False, expression=f'ds["{name}"]')


#: Every quantity, in the order the selector lists them.
QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    Quantity("well", "final well (damped, unforced)", ("capture",), True, _only_damping,
             maps.well, True, expression="maps.well(ds)"),
    Quantity("basins", "attractor basins (forced)", ("strobe",), True, forced, maps.basins,
             True, pilot=True, expression="maps.basins(ds)"),
    Quantity("motion", "motion: rotation or libration", ("omega_mean",), False, _always,
             maps.motion, True, expression="maps.motion(ds)"),
    Quantity("period", "period map (forced)", ("strobe",), True, forced, maps.period, True,
             expression="maps.period(ds)"),
    Quantity("inverted", "stays inverted (pivot drive)", ("top_distance",), False, _pivot,
             maps.inverted, True, expression="maps.inverted(ds)"),
    Quantity("lyapunov_max", "largest Lyapunov exponent", ("lyapunov",), False, _always,
             lambda ds: ds["lyapunov_max"], False, expression='ds["lyapunov_max"]'),
    Quantity("amplitude", "steady amplitude (librations)", ("amplitude", "omega_mean"), False,
             _always, maps.amplitude, False, expression="maps.amplitude(ds)"),
    _variable("theta_final", "final", "observed: theta_final"),
    _variable("omega_final", "final", "observed: omega_final"),
    _variable("winding", "winding", "observed: winding"),
    _variable("theta_max", "theta_max", "observed: theta_max"),
    _variable("omega_mean", "omega_mean", "observed: omega_mean"),
    _variable("energy_final", "energy", "observed: energy_final"),
    _variable("tension_max", "tension", "observed: tension_max"),
    _variable("top_distance_max", "top_distance", "observed: top_distance_max"),
)}


def default_quantity(scene: Scene) -> str:
    """Forced scenes: basins; damping alone: the final well; otherwise motion."""
    if forced(scene):
        return "basins"
    if _only_damping(scene):
        return "well"
    return "motion"
