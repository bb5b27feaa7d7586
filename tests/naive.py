"""A slow, obviously-correct reference integrator for the oracle tests.

Pure Python floats and NumPy; no numba, nothing imported from ``sweep``. One
trajectory at a time, the textbook classical Runge-Kutta scheme on the first-order
system y = (theta, omega):

    theta' = omega
    omega' = A sin(W t + phase) - c omega - (g/L) f(theta) + tau - k omega |omega|
             + (a nu^2 / L) cos(nu t + psi) f(theta),          f = sin or identity

with the step from t_n = t0 + n dt (computed from n, never accumulated) evaluating
the right-hand side at t_n, t_n + dt/2, t_n + dt/2 and t_n + dt. Every state
y_0 ... y_N is kept, and every observable is then computed from that list exactly as
it is defined, so that each definition can be read off in one or two lines.

Absent effects are simply zero parameters here: the reference always integrates the
full equation.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["energy", "integrate", "rhs", "rk4_step", "tension", "top_distance", "tops_crossed"]

TWO_PI = 2.0 * math.pi


def rhs(t, theta, omega, p):
    """Right-hand side (theta', omega') of the pendulum at time ``t``.

    ``p`` is a dict with keys model, gravity, length, damping, forcing_amplitude,
    forcing_frequency, forcing_phase, torque, drag, pivot_amplitude, pivot_frequency,
    pivot_phase.
    """
    w0sq = p["gravity"] / p["length"]
    restoring = math.sin(theta) if p["model"] == "nonlinear" else theta
    forcing = p["forcing_amplitude"] * math.sin(p["forcing_frequency"] * t
                                                + p["forcing_phase"])
    # the pivot's height a cos(nu t + psi) adds its acceleration to gravity
    pivot = p["pivot_amplitude"] * p["pivot_frequency"] ** 2 / p["length"] * \
        math.cos(p["pivot_frequency"] * t + p["pivot_phase"])
    return omega, (forcing - p["damping"] * omega - w0sq * restoring + p["torque"]
                   - p["drag"] * omega * abs(omega) + pivot * restoring)


def rk4_step(t, theta, omega, dt, p):
    """One classical RK4 step of size ``dt`` from state (theta, omega) at time ``t``."""
    k1t, k1o = rhs(t, theta, omega, p)
    k2t, k2o = rhs(t + dt / 2, theta + dt / 2 * k1t, omega + dt / 2 * k1o, p)
    k3t, k3o = rhs(t + dt / 2, theta + dt / 2 * k2t, omega + dt / 2 * k2o, p)
    k4t, k4o = rhs(t + dt, theta + dt * k3t, omega + dt * k3o, p)
    theta = theta + dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t)
    omega = omega + dt / 6 * (k1o + 2 * k2o + 2 * k3o + k4o)
    return theta, omega


def energy(theta, omega, p):
    """Mechanical energy per unit m L^2 of the model: omega^2/2 + (g/L) V(theta)."""
    w0sq = p["gravity"] / p["length"]
    if p["model"] == "nonlinear":
        potential = 1.0 - np.cos(theta)
    else:
        potential = theta ** 2 / 2
    return omega ** 2 / 2 + w0sq * potential


def tension(theta, omega, p, t=0.0):
    """Rod tension per unit mass, L omega^2 + (g + y'') cos(theta) (both models), with
    the pivot's acceleration y'' = -a nu^2 cos(nu t + psi)."""
    pivot = -p["pivot_amplitude"] * p["pivot_frequency"] ** 2 * \
        np.cos(p["pivot_frequency"] * t + p["pivot_phase"])
    return p["length"] * omega ** 2 + (p["gravity"] + pivot) * np.cos(theta)


def top_distance(theta):
    """Distance of theta from the upright position pi (mod 2 pi), in [0, pi]."""
    return np.abs(np.mod(theta, TWO_PI) - math.pi)


def tops_crossed(thetas):
    """Net signed passes over the top (theta = pi mod 2 pi) of the sampled path
    ``thetas``, counted step by step as a streaming observable would: each step adds
    the number of odd multiples of pi it crosses upward minus those it crosses downward.
    (The sweep observable takes the difference of the end's and the start's well index
    instead, the same number; at an angle exactly on a top the two may differ by one,
    which the tests that compare them exclude.)"""
    wells = np.floor((np.asarray(thetas, dtype=float) + math.pi) / TWO_PI)
    return float(np.sum(np.diff(wells)))


def integrate(theta0, omega0, *, t_end, dt, t0=0.0, t_transient=0.0, save_every=None,
              model="nonlinear", gravity=9.81, length=1.0, damping=0.0,
              forcing_amplitude=0.0, forcing_frequency=0.0, forcing_phase=0.0, torque=0.0,
              drag=0.0, pivot_amplitude=0.0, pivot_frequency=0.0, pivot_phase=0.0):
    """Integrate one trajectory with RK4 and compute every observable.

    Returns
    -------
    dict
        ``theta_final, omega_final, winding, theta_max, amplitude, omega_mean, tension_min,
        tension_max, energy_initial, energy_final, top_distance_max`` (floats),
        ``time_all, theta_all, omega_all`` (every state, arrays of length n_steps + 1) and, when
        ``save_every`` is given, ``time, theta, omega`` at steps 0, k, 2k, ...
    """
    p = {"model": model, "gravity": float(gravity), "length": float(length),
         "damping": float(damping), "forcing_amplitude": float(forcing_amplitude),
         "forcing_frequency": float(forcing_frequency),
         "forcing_phase": float(forcing_phase), "torque": float(torque), "drag": float(drag),
         "pivot_amplitude": float(pivot_amplitude), "pivot_frequency": float(pivot_frequency),
         "pivot_phase": float(pivot_phase)}
    n_steps = round((t_end - t0) / dt)
    assert abs((t_end - t0) / dt - n_steps) < 1e-9 * max(1.0, n_steps), \
        "t_end - t0 must be a whole number of steps"

    theta, omega = float(theta0), float(omega0)
    thetas, omegas = [theta], [omega]
    for n in range(n_steps):
        t_n = t0 + n * dt
        theta, omega = rk4_step(t_n, theta, omega, dt, p)
        thetas.append(theta)
        omegas.append(omega)
    thetas, omegas = np.array(thetas), np.array(omegas)
    times = t0 + np.arange(n_steps + 1) * dt

    # Steady observables use the states whose time is >= t0 + t_transient. A time
    # meant to lie exactly on a step (t_transient = 100 dt) counts as reached: the
    # slack of 1e-9 dt only absorbs the rounding of t0 + n dt, and is far smaller than
    # the distance dt between two steps.
    steady = times >= t0 + t_transient - 1e-9 * dt
    th_s, om_s = thetas[steady], omegas[steady]
    tensions = tension(th_s, om_s, p, times[steady])

    out = {
        "theta_final": theta,
        "omega_final": omega,
        "winding": tops_crossed(thetas),
        "theta_max": float(np.max(np.abs(th_s))),
        "amplitude": float(0.5 * (np.max(th_s) - np.min(th_s))),
        "omega_mean": float((th_s[-1] - th_s[0]) / ((th_s.size - 1) * dt)),
        "tension_min": float(np.min(tensions)),
        "tension_max": float(np.max(tensions)),
        "energy_initial": float(energy(float(theta0), float(omega0), p)),
        "energy_final": float(energy(theta, omega, p)),
        "top_distance_max": float(np.max(top_distance(th_s))),
        "time_all": times,
        "theta_all": thetas,
        "omega_all": omegas,
    }
    if save_every is not None:
        out["time"] = times[::save_every]
        out["theta"] = thetas[::save_every]
        out["omega"] = omegas[::save_every]
    return out
