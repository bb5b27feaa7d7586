"""What a run of a system with several coordinates can observe (`sweep.physics.system`).

The single pendulum's observables (`sweep.observables`) read its state ``th, om``; a
system's read every coordinate. Each is declared here as data (its variables per
coordinate, units, meaning); `sweep.kernels.system` writes their kernel source and
`sweep.io` their dataset variables, in this order.

- ``final``: every coordinate and velocity at ``t_end`` (``theta1_final``, ...);
- ``winding``: per angle, the wells crossed (``round(theta_final / 2 pi) -
  round(theta0 / 2 pi)``, half to even, as the single pendulum's `winding`): the net
  signed number of passes over the top;
- ``energy``: the system's energy at the start and at ``t_end`` (``energy_initial``,
  ``energy_final``; a conservative run's drift is their difference);
- ``flip``: ``flip_time``, the first time any angle passes an upright position (an odd
  multiple of pi), interpolated linearly within the step; NaN where no angle flipped
  before ``t_end`` (the trajectory's ``status`` says it is ok). With ``stop_early`` a
  trajectory stops at its first flip: the time-to-first-flip map of the double
  pendulum costs only the time each start takes to flip;
- ``lyapunov``: ``lyapunov_max`` [1/s], the largest Lyapunov exponent over the steady
  window (Benettin's method on the integrator's step map, from the system's derived
  Jacobian), as the single pendulum's;
- ``strobe``: stroboscopic samples, as the single pendulum's ``strobe``: every
  coordinate and velocity (``theta1_strobe``, ..., ``omega1_strobe``, ...; angles
  unwrapped) at the last ``strobe_samples`` times ``t0 + n_transient dt + m 2 pi / nu``
  (``nu`` the system's drive frequency, `sweep.physics.System.drive_frequency_parameter`),
  oldest first, over a last dimension ``strobe``; NaN for samples the run did not reach.
  They are the state at those steps exactly, the same bits as ``save_every`` saves.
- ``attractor``: as the single pendulum's ``attractor`` (the same variable, units and
  meaning): the index of the attractor of the run's catalogue (``sweep.run(...,
  attractors=sweep.maps.attractor_catalogue(pilot))``) on which the trajectory's
  stroboscopic points (every coordinate and velocity, angles modulo 2 pi; at the
  ``strobe`` observable's times ``t0 + n_transient dt + m 2 pi / nu``, every one of
  them) fell within ``ATTRACTOR_TOL`` of that orbit's successive points for
  ``ATTRACTOR_MATCHES`` drive periods running; -1 if none did. With ``stop_early`` a
  trajectory stops there, so a driven system's basin map costs only each start's
  transient. The catalogue enters the kernel as arrays (`sweep.kernels.system`).
"""

from __future__ import annotations

from dataclasses import dataclass

from .observables import COMMENTS, LYAPUNOV_EVERY, OBSERVABLES

__all__ = ["SYSTEM_OBSERVABLES", "SystemObservable", "comments", "resolve_system_observe",
           "variables"]


@dataclass(frozen=True)
class SystemObservable:
    """One observable of a system run.

    Attributes
    ----------
    name : str
    per : {"coordinate", "angle", "system"}
        Whether it has a variable per coordinate (position and velocity), per angular
        coordinate, or one set for the system.
    stops : bool
        Whether ``stop_early`` may stop a trajectory on it (its answer is final).
    sampled : bool
        Each variable has ``strobe_samples`` columns (dimension ``strobe``), not one.
    """

    name: str
    per: str
    stops: bool = False
    sampled: bool = False


SYSTEM_OBSERVABLES = {o.name: o for o in (
    SystemObservable("final", "coordinate"),
    SystemObservable("winding", "angle"),
    SystemObservable("energy", "system"),
    SystemObservable("flip", "system", stops=True),
    SystemObservable("lyapunov", "system"),
    SystemObservable("strobe", "coordinate", sampled=True),
    SystemObservable("attractor", "system", stops=True),
)}


def resolve_system_observe(observe) -> tuple[str, ...]:
    """``observe`` checked and put in canonical order.

    Raises
    ------
    ValueError
        On an unknown name, naming it and the accepted ones.
    TypeError
        On something that is not a sequence of names.
    """
    if isinstance(observe, str):
        observe = (observe,)
    try:
        names = list(observe)
    except TypeError:
        raise TypeError(f"observe must be a sequence of observable names, got {observe!r}; "
                        f"accepted for a system: {', '.join(SYSTEM_OBSERVABLES)}") from None
    for name in names:
        if name not in SYSTEM_OBSERVABLES:
            raise ValueError(f"unknown observable {name!r} for a system; accepted: "
                             f"{', '.join(map(repr, SYSTEM_OBSERVABLES))}")
    return tuple(name for name in SYSTEM_OBSERVABLES if name in names)


def variables(name: str, coordinates, energy_units: str) -> list[tuple[str, str, str]]:
    """``(variable, units, long_name)`` of observable ``name`` for these coordinates, in
    the order of the kernel's output columns (a ``sampled`` observable's variable has
    ``strobe_samples`` columns each); the long names are short labels, and `comments`
    has what they leave out.

    Parameters
    ----------
    name : str
        A `SYSTEM_OBSERVABLES` name.
    coordinates : sequence of sweep.physics.Coordinate
    energy_units : str
        Units of the system's energy (its Lagrangian's).
    """
    return [row[:3] for row in _variables(name, coordinates, energy_units)]


def comments(name: str, coordinates) -> dict[str, str]:
    """The CF ``comment`` of each variable of observable ``name`` that has one
    (`variables`' full meaning), by variable name."""
    return {row[0]: row[3] for row in _variables(name, coordinates, "") if row[3]}


def _variables(name: str, coordinates, energy_units: str) -> list[tuple[str, str, str, str]]:
    """`variables` with each variable's comment ("" for none)."""
    if name == "final":
        return [(f"{c.name}_final", c.units, f"{c.long_name or c.name} at t_end",
                 "unwrapped (not reduced modulo 2 pi)" if c.angular else "")
                for c in coordinates] + \
            [(f"{c.velocity}_final", c.velocity_units, f"{c.velocity} at t_end", "")
             for c in coordinates]
    if name == "winding":
        return [(f"winding_{c.name}", "1", f"wells of {c.name} crossed from t0 to t_end",
                 f"round({c.name}_final / 2 pi) - round({c.name}_0 / 2 pi) (half to "
                 f"even): the net signed number of passes of {c.name} over the top")
                for c in coordinates if c.angular]
    if name == "energy":
        return [("energy_initial", energy_units, "energy of the system at t0", ""),
                ("energy_final", energy_units, "energy of the system at t_end", "")]
    if name == "flip":
        return [("flip_time", "s", "time of the first flip",
                 "the first time any angle passes an upright position (an odd multiple "
                 "of pi), interpolated within the step; NaN where none flipped before "
                 "t_end")]
    if name == "lyapunov":
        return [("lyapunov_max", "s-1", "largest Lyapunov exponent",
                 "over t >= t0 + t_transient; finite-time, of the integrator's step map "
                 "(one tangent vector from (1, ..., 1) / sqrt(2 m), renormalised every "
                 f"{LYAPUNOV_EVERY} steps)")]
    if name == "strobe":
        when = "at the last strobe_samples drive periods"
        samples = ("stroboscopic samples at t0 + n_transient dt + m 2 pi / nu, nu the "
                   "drive's frequency, oldest first")
        return [(f"{c.name}_strobe", c.units, f"{c.name} {when}",
                 (f"{c.long_name}; " if c.long_name else "") + samples
                 + ("; unwrapped" if c.angular else ""))
                for c in coordinates] + \
            [(f"{c.velocity}_strobe", c.velocity_units, f"{c.velocity} {when}", samples)
             for c in coordinates]
    if name == "attractor":  # the single pendulum's variable, units, meaning, comment
        variable = OBSERVABLES["attractor"].variables[0]
        return [(*variable, COMMENTS["attractor"])]
    raise ValueError(f"unknown system observable {name!r}")
