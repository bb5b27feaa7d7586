"""The seed notebook's seven cases: linear versus nonlinear simple pendulum.
=========================================================================

Reproduces the seven cases of the worked example the project grew out of (the
Portuguese notebook "Pendulo Simples", ``/work/shared/seed``): each case integrates the
small-angle ("linear") and the exact ("nonlinear") pendulum from the same initial state
with a classical RK4 step, ``g = 9.8 m/s^2``, ``L = 1 m``, ``dt = 0.05 s`` and
``N = 1000`` steps (``t_end = 50 s``), and plots the angle against time and the phase
portrait, both models overlaid. Run it as::

    python examples/seed_cases.py [--out FOLDER] [--netcdf]

It writes ``seed_case_1.png`` ... ``seed_case_7.png`` (and, with ``--netcdf``,
``seed_cases.nc`` holding every trajectory) to ``FOLDER`` (default
``examples/output/seed_cases``) and prints a table of the key numbers.

The equation of motion, per unit ``m L`` (the seed's ``ksi`` is ``c = C/m``, in 1/s,
and multiplies ``theta'`` directly; every case has no forcing)::

    theta'' = - c theta' - (g/L) f(theta),    f = sin (nonlinear) or identity (linear)

and the rod tension per unit mass, from the radial component of Newton's law,
``T/m = L theta'^2 + g cos(theta)``.

Notes
-----
Two facts organise all seven cases. Write ``w0 = sqrt(g/L) = 3.13 rad/s`` (small-angle
period ``T0 = 2 pi / w0 = 2.007 s``) and the mechanical energy per unit ``m L^2``

* nonlinear: ``E = theta'^2 / 2 + w0^2 (1 - cos theta)``,
* linear:    ``E = theta'^2 / 2 + w0^2 theta^2 / 2``.

Without damping ``E`` is conserved. The nonlinear potential is periodic with maxima
``2 w0^2 = 2 g/L`` at the inverted position: a trajectory with ``E < 2 g/L`` librates
(swings back and forth), one with ``E > 2 g/L`` goes over the top and rotates; the
level ``E = 2 g/L`` is the *separatrix*, ``theta' = +-2 w0 cos(theta/2)``. The linear
potential is a parabola with no maximum, so the linear model has no separatrix: every
trajectory is an ellipse ``theta = A cos(w0 t - phi)`` with
``A = sqrt(theta0^2 + (theta0'/w0)^2)`` and period ``T0``, however large ``A``.
With damping, ``dE/dt = -c theta'^2 <= 0`` for both models.

The seed table's remarks, case by case (``E0`` from the initial state):

1. theta0 = -10 deg, theta0' = 0, c = 0 -- *small angle: linear and nonlinear agree*.
   ``sin theta ~ theta`` to 0.5 % at 10 deg. The nonlinear period is
   ``T = (4 / w0) K(sin^2(theta0/2)) ~ T0 (1 + theta0^2/16)``: 0.19 % longer. Both
   start at rest so both keep amplitude 10 deg; the only difference is a slow phase
   drift, ``2 pi (50 s / T0) theta0^2/16 ~ 0.3 rad`` after 50 s, i.e. at most
   ``2 theta0 sin(0.15) ~ 3 deg`` apart at the end.
2. theta0 = -120 deg, theta0' = 0, c = 0 -- *large angle: the nonlinearity shows*.
   ``E0 = 0.75 (2 g/L)``: the nonlinear pendulum librates with the same 120 deg
   amplitude as the linear one (energy conservation from rest) but its period is
   ``(4 / w0) K(sin^2 60 deg) = 2.76 s``, 37 % longer than ``T0``, so after 50 s the
   two are completely out of phase (18 versus 25 swings). The waveform is flattened
   near the turning points (the torque ``sin theta`` is weaker than ``theta``), and
   the phase curve is an eye-shaped closed orbit, not an ellipse. The tension per unit
   mass runs from ``g cos theta0 = -4.9 m/s^2`` at the turning points (the rod is in
   compression: a string would go slack) to ``g (3 - 2 cos theta0) = 4 g`` at the
   bottom.
3. theta0 = -120 deg, theta0' = 200 deg/s, c = 0 -- *nonzero initial velocity*.
   ``E0 = 1.06 (2 g/L)``, 6 % above the separatrix: the nonlinear pendulum creeps over
   the top and rotates, slowly near the inverted position (rotation period 1.76 s,
   about 28 turns in 50 s), while the linear one librates with amplitude
   ``sqrt(theta0^2 + (theta0'/w0)^2) = 136 deg``. (The seed's plot limits hide the
   rotation; the energy says it must happen.)
4. theta0 = -120 deg, theta0' = 500 deg/s, c = 0 -- *the linear model behaves
   unphysically; the nonlinear one rotates*. ``E0 = 2.69 (2 g/L)``: the nonlinear
   pendulum rotates about 73 times in 50 s (rotation period 0.68 s), its angular
   velocity never vanishing. The linear model has no separatrix, so it just
   oscillates with a huge amplitude of 200 deg: the bob passes the top and then falls
   back the way it came, which no unforced pendulum can do; its restoring torque
   ``g theta`` keeps growing past 180 deg where the true torque ``g sin theta`` has
   changed sign.
5. theta0 = -10 deg, theta0' = 0, c = 0.08 /s -- *damped: exponential decay*.
   Underdamped (damping ratio ``c / (2 w0) = 0.013``): the amplitude decays as
   ``exp(-c t / 2)`` (to 1.35 deg at 50 s) and the energy as ``exp(-c t)``; at small
   angle the two models still agree.
6. theta0 = -120 deg, theta0' = 0, c = 0.08 /s -- *damped, large angle*. Both decay;
   early on the nonlinear period is long (as in case 2) so the phases drift apart, and
   as the amplitude decays the nonlinear period falls back towards ``T0``: the drift
   stops growing, though the accumulated offset remains.
7. theta0 = -120 deg, theta0' = 500 deg/s, c = 0.2 /s -- *damped, rotating start*.
   The nonlinear pendulum starts above the separatrix and rotates a few turns (4 here)
   while damping drains its energy; once ``E < 2 g/L`` it is trapped in the well
   ``theta = 360 k deg`` and swings there with decaying amplitude (the unwrapped
   angle ends near ``4 x 360 deg``). The linear one simply decays from its 200 deg
   oscillation, again swinging past 180 deg at first.

In the figures the nonlinear angle is wrapped to [-180, 180) deg (the physical
position of the bob), which turns rotation into a saw-tooth and puts the phase
portrait on the cylinder where the separatrix (grey, dotted) is drawn; the linear
angle is not wrapped, since the linear model is not periodic in ``theta``. Tension
is reported for the nonlinear model only: the formula is the exact radial equation of
motion, which the linear model does not satisfy.

References
----------
.. [1] "Pendulo Simples", the seed notebook, ``/work/shared/seed/000_07d964be92dc4ca8.txt``.
.. [2] L. D. Landau and E. M. Lifshitz, *Mechanics*, 3rd ed., section 11 (the pendulum
   period as a complete elliptic integral).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

import sweep

__all__ = [
    "CASES",
    "Case",
    "DT",
    "GRAVITY",
    "LENGTH",
    "MODELS",
    "N_STEPS",
    "T_END",
    "main",
    "plot_case",
    "run_case",
    "summary",
]

#: The seed's constants: g [m/s^2], L [m], dt [s], N steps.
GRAVITY = 9.8
LENGTH = 1.0
DT = 0.05
N_STEPS = 1000
#: Final time [s]: N dt.
T_END = N_STEPS * DT

#: The two models compared in every case.
MODELS = ("linear", "nonlinear")

#: What each run observes besides the sampled trajectory.
OBSERVE = ("final", "winding", "theta_max", "tension", "energy")

#: Length [s] of the zoomed angle-versus-time panel (about five small-angle periods).
ZOOM = 10.0

DEFAULT_OUT = Path(__file__).resolve().parent / "output" / "seed_cases"


@dataclass(frozen=True)
class Case:
    """One case of the seed's table.

    Attributes
    ----------
    number : int
        1 to 7, as in the seed.
    theta0_deg : float
        Initial angle [deg] from the downward vertical.
    omega0_deg : float
        Initial angular velocity [deg/s].
    damping : float
        Viscous damping ``c = C/m`` [1/s] (the seed's ``ksi``).
    remark : str
        The seed's remark, in English.
    physics : str
        Why, in one line (the module docstring has the details).
    """

    number: int
    theta0_deg: float
    omega0_deg: float
    damping: float
    remark: str
    physics: str

    @property
    def theta0(self) -> float:
        """Initial angle [rad]."""
        return math.radians(self.theta0_deg)

    @property
    def omega0(self) -> float:
        """Initial angular velocity [rad/s]."""
        return math.radians(self.omega0_deg)


#: The seed's seven cases.
CASES = (
    Case(1, -10.0, 0.0, 0.0, "small angle: linear and nonlinear agree",
         "sin(theta) ~ theta; the nonlinear period is longer by only theta0^2/16 = 0.19 %"),
    Case(2, -120.0, 0.0, 0.0, "large angle: the nonlinearity shows",
         "same 120 deg amplitude, but the nonlinear period is 37 % longer (2.76 s vs 2.01 s)"),
    Case(3, -120.0, 200.0, 0.0, "nonzero initial velocity",
         "E0 = 1.06 x 2g/L, just above the separatrix: the nonlinear pendulum goes over the "
         "top; the linear one swings to 136 deg"),
    Case(4, -120.0, 500.0, 0.0,
         "the linear model behaves unphysically; the nonlinear one rotates",
         "E0 = 2.7 x 2g/L: the nonlinear pendulum rotates; the linear model has no "
         "separatrix and swings to 200 deg, past the top and back"),
    Case(5, -10.0, 0.0, 0.08, "damped: exponential decay",
         "amplitude ~ exp(-c t / 2), energy ~ exp(-c t); at small angle the models agree"),
    Case(6, -120.0, 0.0, 0.08, "damped, large angle",
         "the nonlinear period starts 28 % long and returns towards 2.01 s as the "
         "amplitude decays"),
    Case(7, -120.0, 500.0, 0.2, "damped, rotating start",
         "the nonlinear pendulum rotates until damping drains E below 2g/L, then "
         "swings down into the well it is in"),
)


def scene_for(case: Case, model: str) -> sweep.Scene:
    """The seed's pendulum under ``model``, damped only if the case is.

    Parameters
    ----------
    case : Case
    model : {"linear", "nonlinear"}

    Returns
    -------
    sweep.Scene
    """
    effects = (sweep.Damping(case.damping),) if case.damping > 0 else ()
    return sweep.Scene(gravity=GRAVITY, length=LENGTH, model=model, effects=effects)


def run_case(case: Case) -> dict[str, xr.Dataset]:
    """Integrate one case under both models.

    Parameters
    ----------
    case : Case

    Returns
    -------
    dict of {"linear", "nonlinear"} to xarray.Dataset
        Each dataset has one dimension, ``time`` (1001 samples, every step), with
        ``theta`` [rad, unwrapped] and ``omega`` [rad/s]; the scalar observables
        ``theta_final``, ``omega_final``, ``winding``, ``theta_max``, ``tension_min``,
        ``tension_max`` [m/s^2], ``energy_initial``, ``energy_final`` [1/s^2, per unit
        m L^2, of that model]; and scalar coordinates ``theta0``, ``omega0``.
    """
    grid = sweep.Grid(theta0=[case.theta0], omega0=[case.omega0])
    return {
        model: sweep.run(scene_for(case, model), grid, t_end=T_END, dt=DT,
                         observe=OBSERVE, save_every=1).squeeze(("theta0", "omega0"))
        for model in MODELS
    }


def _wrapped_curve(theta_deg: np.ndarray, *others: np.ndarray) -> tuple[np.ndarray, ...]:
    """Wrap an unwrapped angle [deg] to [-180, 180) for a line plot.

    Where the angle crosses +-180 deg between two samples, the crossing is
    interpolated linearly (in ``theta`` and in each of ``others``, e.g. time or
    angular velocity): the curve runs to the edge, breaks (NaN) and resumes from the
    opposite edge, so the plot shows neither the jump nor a gap short of the edge.
    Assumes less than a turn between samples (at most ~30 deg here).

    Returns
    -------
    tuple of ndarray
        The wrapped angle, then each of ``others``, all the same length.
    """
    u = np.asarray(theta_deg, dtype=float)
    turn = np.floor((u + 180.0) / 360.0)           # which 360-deg sheet each sample is on
    pieces = [[] for _ in range(1 + len(others))]
    begin = 0
    for j in np.flatnonzero(np.diff(turn) != 0) + 1:
        up = turn[j] > turn[j - 1]
        edge = 360.0 * (turn[j] if up else turn[j - 1]) - 180.0   # crossing, unwrapped
        f = (edge - u[j - 1]) / (u[j] - u[j - 1])
        inserted = (np.array([180.0, np.nan, -180.0]) if up
                    else np.array([-180.0, np.nan, 180.0]))
        for k, a in enumerate((u, *others)):
            a = np.asarray(a, dtype=float)
            if k == 0:
                pieces[0] += [a[begin:j] - 360.0 * turn[begin:j], inserted]
            else:
                x = a[j - 1] + f * (a[j] - a[j - 1])
                pieces[k] += [a[begin:j], np.array([x, np.nan, x])]
        begin = j
    for k, a in enumerate((u, *others)):
        a = np.asarray(a, dtype=float)
        pieces[k].append(a[begin:] - 360.0 * turn[begin:] if k == 0 else a[begin:])
    return tuple(np.concatenate(p) for p in pieces)


def _nonlinear_label(ds: xr.Dataset) -> str:
    turns = int(ds.winding)
    if turns == 0:
        return "nonlinear"
    return f"nonlinear ({abs(turns)} turns over the top; angle wrapped to [-180, 180) deg)"


def plot_case(case: Case, results: dict[str, xr.Dataset], path: Path) -> Path:
    """Draw theta(t) and the phase portrait of one case, both models; save a PNG.

    Parameters
    ----------
    case : Case
    results : dict
        As returned by `run_case`.
    path : Path
        The PNG to write.

    Returns
    -------
    Path
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lin, nl = results["linear"], results["nonlinear"]
    t = lin.time.values
    lin_th, lin_om = np.degrees(lin.theta.values), np.degrees(lin.omega.values)
    nl_th = np.degrees(nl.theta.values)
    nl_om = np.degrees(nl.omega.values)

    fig = plt.figure(figsize=(13.0, 6.6), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=(1.25, 1.0))
    ax_t = fig.add_subplot(grid[0, 0])
    ax_z = fig.add_subplot(grid[1, 0])
    ax_p = fig.add_subplot(grid[:, 1])
    style_lin = dict(color="tab:blue", lw=1.6, alpha=0.8, label="linear (small-angle)")
    style_nl = dict(color="tab:red", lw=1.1, label=_nonlinear_label(nl))

    for ax, t_max, title in ((ax_t, t[-1], f"Angle versus time, whole run (0-{t[-1]:g} s)"),
                             (ax_z, ZOOM, f"Angle versus time, first {ZOOM:g} s")):
        ax.plot(t, lin_th, **style_lin)
        ax.plot(*_wrapped_curve(nl_th, t)[::-1], **style_nl)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.set_xlim(t[0], t_max)
        ax.set_ylabel(r"angle $\theta$ [deg]")
        ax.set_title(title, fontsize=10.5)
    ax_z.set_xlabel("time t [s]")

    ax_p.plot(lin_th, lin_om, **style_lin)
    ax_p.plot(*_wrapped_curve(nl_th, nl_om), **style_nl)
    ax_p.plot(lin_th[0], lin_om[0], "ko", ms=5, label="initial state", zorder=5)
    # the separatrix matters (and fits the axes) only for a swing that reaches near it
    w0 = math.sqrt(GRAVITY / LENGTH)
    if float(nl.energy_initial) > 0.25 * 2.0 * w0**2:
        th = np.linspace(-180.0, 180.0, 361)
        sep = np.degrees(2.0 * w0 * np.cos(np.radians(th) / 2.0))
        ax_p.plot(th, sep, ":", color="0.45", lw=1.2,
                  label=r"separatrix $E = 2g/L$ of the nonlinear model")
        ax_p.plot(th, -sep, ":", color="0.45", lw=1.2)
    ax_p.set_xlabel(r"angle $\theta$ [deg]")
    ax_p.set_ylabel(r"angular velocity $\dot\theta$ [deg/s]")
    ax_p.set_title("Phase portrait", fontsize=10.5)
    fig.legend(*ax_p.get_legend_handles_labels(), loc="outside lower center", ncol=4,
               fontsize=9.5, frameon=False)

    damping = f"c = {case.damping:g} 1/s" if case.damping else "undamped"
    fig.suptitle(
        f"Case {case.number}: $\\theta_0$ = {case.theta0_deg:g} deg, "
        f"$\\dot\\theta_0$ = {case.omega0_deg:g} deg/s, {damping} "
        f"(g = {GRAVITY:g} m/s$^2$, L = {LENGTH:g} m, dt = {DT:g} s)\n"
        f"Seed: {case.remark}.\nPhysics: {case.physics}.",
        fontsize=11,
    )
    path = Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def summary(case: Case, results: dict[str, xr.Dataset]) -> dict[str, float]:
    """The numbers the table prints for one case.

    Returns
    -------
    dict
        ``theta_max_linear``, ``theta_max_nonlinear`` [deg, max |theta| of the
        unwrapped angle], ``winding_nonlinear`` (net passes over the top), ``rotated`` (bool),
        ``tension_min``, ``tension_max`` [m/s^2, nonlinear model, per unit mass].
    """
    lin, nl = results["linear"], results["nonlinear"]
    winding = int(nl.winding)
    return {
        "theta_max_linear": math.degrees(float(lin.theta_max)),
        "theta_max_nonlinear": math.degrees(float(nl.theta_max)),
        "winding_nonlinear": winding,
        "rotated": winding != 0,
        "tension_min": float(nl.tension_min),
        "tension_max": float(nl.tension_max),
    }


def _table(rows: list[tuple[Case, dict[str, float]]]) -> str:
    header = (f"{'case':>4} {'theta0':>7} {'omega0':>7} {'c':>5}  "
              f"{'max|theta| [deg]':>19}  {'nonlinear':>14}  {'T/m [m/s^2]':>17}")
    sub = (f"{'':>4} {'[deg]':>7} {'[deg/s]':>7} {'[1/s]':>5}  "
           f"{'linear':>9} {'nonlin.':>9}  {'rotated (turns)':>14}  {'min':>8} {'max':>8}")
    lines = [header, sub, "-" * len(sub)]
    for case, s in rows:
        rotated = f"yes ({s['winding_nonlinear']:+d})" if s["rotated"] else "no"
        lines.append(
            f"{case.number:>4} {case.theta0_deg:>7g} {case.omega0_deg:>7g} {case.damping:>5g}  "
            f"{s['theta_max_linear']:>9.1f} {s['theta_max_nonlinear']:>9.1f}  {rotated:>14}  "
            f"{s['tension_min']:>8.2f} {s['tension_max']:>8.2f}"
        )
    return "\n".join(lines)


def _to_netcdf(all_results: dict[int, dict[str, xr.Dataset]], path: Path) -> Path:
    """One file: every variable with dims (case, model[, time])."""
    per_case = []
    for number, results in all_results.items():
        both = xr.concat(
            [results[m] for m in MODELS],
            dim=xr.Variable("model", list(MODELS)),
        )
        case = CASES[number - 1]
        both = both.assign_coords(damping=case.damping)
        per_case.append(both)
    ds = xr.concat(per_case, dim=xr.Variable("case", list(all_results)))
    ds["damping"].attrs = {"units": "s-1", "long_name": "viscous damping coefficient c = C/m"}
    ds["case"].attrs = {"long_name": "case number in the seed notebook's table"}
    for name in ("theta0", "omega0"):
        ds[name].attrs = dict(zip(("units", "long_name"),
                                  sweep.physics.PARAMETER_INFO[name]))
    ds.attrs = {
        "Conventions": "CF-1.10",
        "title": "the seed notebook's seven pendulum cases, linear and nonlinear",
        "source": f"examples/seed_cases.py, sweep {sweep.__version__}",
        "gravity": GRAVITY, "length": LENGTH, "dt": DT, "t_end": T_END,
        "method": "rk4",
    }
    return sweep.save(ds, path)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the seven cases, write one PNG per case, print the summary table.

    Parameters
    ----------
    argv : sequence of str, optional
        Command-line arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success.
    """
    parser = argparse.ArgumentParser(
        description="Reproduce the seed notebook's seven linear/nonlinear pendulum cases.")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help="output folder for the PNGs (created if missing; "
                             "default: %(default)s)")
    parser.add_argument("--netcdf", action="store_true",
                        help="also write every trajectory to OUT/seed_cases.nc")
    args = parser.parse_args(argv)

    start = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows, all_results = [], {}
    for case in CASES:
        results = run_case(case)
        all_results[case.number] = results
        plot_case(case, results, out / f"seed_case_{case.number}.png")
        rows.append((case, summary(case, results)))
    if args.netcdf:
        _to_netcdf(all_results, out / "seed_cases.nc")

    print(f"Seed cases: g = {GRAVITY} m/s^2, L = {LENGTH} m, dt = {DT} s, "
          f"{N_STEPS} RK4 steps (t_end = {T_END:g} s)")
    print(_table(rows))
    print("max|theta| is of the unwrapped angle; rotated = the nonlinear pendulum's "
          "net passes over the top (winding) != 0;\nT/m = L theta'^2 + g cos(theta) of the "
          "nonlinear model (negative: the rod is in compression).")
    print(f"Wrote {len(CASES)} figures to {out} in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    main()  # no SystemExit: the docs' gallery runs the script in-process
