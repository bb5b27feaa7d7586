"""Frequency-response curves by continuation: sweep the forcing frequency up and down,
each point starting from the previous point's final state, so the jump and the
hysteresis of the softening nonlinear resonance show.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import engine
from .._validate import check_axis, check_choice, check_count, check_quantity
from ..grid import Grid
from ..physics import Forcing, Scene
from . import labels as maps

__all__ = ["frequency_response"]

_DIRECTIONS = ("up", "down", "both")


def frequency_response(
    scene: Scene,
    frequencies,
    *,
    theta0: float = 0.0,
    omega0: float = 0.0,
    direction: str = "both",
    periods_transient: int = 100,
    periods_measure: int = 20,
    steps_per_period: int = 200,
) -> xr.Dataset:
    """Steady amplitude versus forcing frequency, by continuation.

    For each direction the frequencies are visited in increasing ("up") or decreasing
    ("down") order; the first point starts from ``(theta0, omega0)``, each later point
    from the previous point's final state (angle reduced to ``(-pi, pi]``). Each point
    integrates ``periods_transient + periods_measure`` forcing periods with
    ``dt = period / steps_per_period`` and measures over the last ``periods_measure``.

    Parameters
    ----------
    scene : Scene
        Must contain a `Forcing` (its frequency is replaced by each entry of
        ``frequencies``).
    frequencies : array_like, shape (n,)
        Forcing angular frequencies [rad/s], > 0.
    theta0, omega0 : float
        Initial state of the first point [rad, rad/s].
    direction : {"up", "down", "both"}
    periods_transient, periods_measure, steps_per_period : int
        Each >= 1 (booleans and floats such as ``20.0`` are refused).

    Returns
    -------
    xarray.Dataset
        Dims ``(direction, forcing_frequency)``; variables ``amplitude`` [rad] (NaN
        where the pendulum rotates), ``omega_mean`` [rad/s], ``motion`` (see
        `sweep.maps.motion`), ``theta_final``, ``omega_final``.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a sweep.Scene, got {scene!r}")
    if scene.forcing is None:
        raise ValueError("frequency_response needs a forcing in the scene; accepted: "
                         "a Scene with sweep.Forcing(amplitude, frequency, phase)")
    frequencies = np.sort(check_axis("frequencies", frequencies))
    if frequencies[0] <= 0:
        raise ValueError(f"frequencies must be > 0 (rad/s), got {float(frequencies[0])!r}")
    theta0 = check_quantity("theta0", theta0)
    omega0 = check_quantity("omega0", omega0)
    check_choice("direction", direction, _DIRECTIONS)
    periods_transient = check_count("periods_transient", periods_transient)
    periods_measure = check_count("periods_measure", periods_measure)
    steps_per_period = check_count("steps_per_period", steps_per_period)
    directions = ("up", "down") if direction == "both" else (direction,)

    names = ("amplitude", "omega_mean", "motion", "theta_final", "omega_final")
    results = {name: np.full((len(directions), frequencies.size), np.nan) for name in names}
    periods = periods_transient + periods_measure
    for d, which in enumerate(directions):
        order = range(frequencies.size) if which == "up" else range(frequencies.size - 1,
                                                                      -1, -1)
        state = (theta0, omega0)
        for k in order:
            period = 2 * np.pi / frequencies[k]
            forcing = Forcing(scene.forcing.amplitude, float(frequencies[k]),
                              scene.forcing.phase)
            point = Scene(gravity=scene.gravity, length=scene.length, model=scene.model,
                          effects=tuple(e for e in scene.effects
                                        if not isinstance(e, Forcing)) + (forcing,))
            dt = period / steps_per_period
            ds = engine.run(point, Grid(theta0=[state[0]], omega0=[state[1]]),
                            t_end=periods * period, dt=dt,
                            t_transient=periods_transient * period,
                            observe=("final", "amplitude", "omega_mean"), progress=False)
            results["amplitude"][d, k] = maps.amplitude(ds).item()
            results["motion"][d, k] = maps.motion(ds).item()
            for name in ("omega_mean", "theta_final", "omega_final"):
                results[name][d, k] = ds[name].item()
            theta_end = results["theta_final"][d, k]
            state = (float(np.angle(np.exp(1j * theta_end))), results["omega_final"][d, k])
            if not np.isfinite(state[0] + state[1]):
                state = (theta0, omega0)  # a failed point: restart the branch

    dims = ("direction", "forcing_frequency")
    coords = {"direction": list(directions),
              "forcing_frequency": ("forcing_frequency", frequencies,
                                    {"units": "rad s-1", "long_name": "forcing angular "
                                                                      "frequency W"})}
    units = {"amplitude": "rad", "omega_mean": "rad s-1", "motion": "1",
             "theta_final": "rad", "omega_final": "rad s-1"}
    out = xr.Dataset({name: (dims, values, {"units": units[name]})
                      for name, values in results.items()}, coords)
    out["amplitude"].attrs["long_name"] = "steady amplitude (NaN where rotating)"
    out.attrs = {"scene": str(scene.to_dict()), "periods_transient": periods_transient,
                 "periods_measure": periods_measure, "steps_per_period": steps_per_period,
                 "theta0": theta0, "omega0": omega0}
    return out
