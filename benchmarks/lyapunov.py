"""Measure what the ``lyapunov`` observable costs: trajectory-steps per second with
and without the tangent dynamics, side by side in one process, and against the same
work in plain NumPy.

Two scenes, each over an N x N grid of (theta0, omega0), RK4, 200 steps per forcing
period, ``--periods`` forcing periods:

- Baker & Gollub's chaotic pendulum (g/L = 1, c = 0.5, A = 1.5, W = 2/3);
- the full scene (damping, forcing, torque, drag, driven pivot).

For each: sweep observing ``final`` (the plain kernel) and ``final`` + ``lyapunov``
(best of ``--repeat`` runs each, kernels compiled first). The NumPy baseline is the
strongest plain-NumPy Benettin we could write for the chaotic scene: RK4 on whole
arrays of trajectories with the tangent vectors (sin and cos once per stage, in-place
where it helps), over chunks of trajectories whose size is swept (the best is kept);
it is timed over fewer steps (``--numpy-periods``) and checked against sweep's
exponents over the same steps.

Writes ``benchmarks/results/lyapunov.json`` and ``.md``.

Usage::

    python benchmarks/lyapunov.py [--size N] [--periods P] [--repeat R]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep

try:  # the machine description of the basin benchmark
    from _machine import machine
except ImportError:  # pragma: no cover - run from elsewhere
    def machine() -> str:
        return "unknown machine"

C, A, W = 0.5, 1.5, 2.0 / 3.0
PERIOD = 2 * np.pi / W
STEPS_PER_PERIOD = 200


def scenes() -> dict[str, sweep.Scene]:
    """The two scenes measured, by name."""
    return {
        "chaotic pendulum (damping, forcing)": sweep.Scene(
            gravity=1.0, length=1.0, effects=(sweep.Damping(C), sweep.Forcing(A, W))),
        "full scene (damping, forcing, torque, drag, pivot)": sweep.Scene(
            gravity=1.0, length=1.0, effects=(
                sweep.Damping(C), sweep.Forcing(A, W), sweep.Torque(0.1),
                sweep.QuadraticDrag(0.05), sweep.PivotDrive(0.01, 8.0))),
    }


def _best(scene, grid, repeat, **kwargs):
    """The dataset and the best wall time [s] of ``repeat`` runs (compiled first)."""
    sweep.engine.warm_up(scene, grid, **kwargs)
    best, ds = np.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        ds = sweep.run(scene, grid, **kwargs)
        best = min(best, time.perf_counter() - start)
    return ds, best


def numpy_lyapunov(theta0, omega0, n_steps, dt):
    """Both exponents of the chaotic scene over ``n_steps`` RK4 steps from t = 0, in
    plain NumPy: state and two tangent vectors as arrays over the trajectories,
    Gram-Schmidt every 64 steps and at the end (as sweep does).

    Parameters
    ----------
    theta0, omega0 : ndarray, shape (n,)
        Initial angle [rad] and velocity [rad/s].

    Returns
    -------
    ndarray, shape (2, n)
        The larger and the smaller exponent [1/s].
    """
    th, om = theta0.copy(), omega0.copy()
    u1, v1 = np.ones_like(th), np.zeros_like(th)
    u2, v2 = np.zeros_like(th), np.ones_like(th)
    sums = np.zeros((2, th.size))
    half = 0.5 * dt

    def f(t, th, om, u1, v1, u2, v2):
        s, c = np.sin(th), np.cos(th)
        acc = -s - C * om + A * np.sin(W * t)
        return om, acc, v1, -c * u1 - C * v1, v2, -c * u2 - C * v2

    state = [th, om, u1, v1, u2, v2]
    for n in range(n_steps):
        t = n * dt
        k1 = f(t, *state)
        k2 = f(t + half, *[y + half * k for y, k in zip(state, k1)])
        k3 = f(t + half, *[y + half * k for y, k in zip(state, k2)])
        k4 = f(t + dt, *[y + dt * k for y, k in zip(state, k3)])
        state = [y + (dt / 6) * (a + 2 * b + 2 * c + d)
                 for y, a, b, c, d in zip(state, k1, k2, k3, k4)]
        if (n + 1) % 64 == 0 or n + 1 == n_steps:
            th, om, u1, v1, u2, v2 = state
            n1 = np.hypot(u1, v1)
            r22 = (u1 * v2 - v1 * u2) / n1
            sums[0] += np.log(n1)
            sums[1] += np.log(np.abs(r22))
            u1, v1 = u1 / n1, v1 / n1
            state = [th, om, u1, v1, -v1, u1]
    rates = sums / (n_steps * dt)
    return np.sort(rates, axis=0)[::-1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--periods", type=int, default=10)
    parser.add_argument("--numpy-periods", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, args.size),
                      omega0=np.linspace(-2.0, 2.0, args.size))
    dt = PERIOD / STEPS_PER_PERIOD
    n_steps = args.periods * STEPS_PER_PERIOD
    work = grid.size * n_steps
    kwargs = dict(t_end=n_steps * dt, dt=dt, progress=False)
    rows = []
    for name, scene in scenes().items():
        plain, t_plain = _best(scene, grid, args.repeat, observe=("final",), **kwargs)
        tangent, t_tangent = _best(scene, grid, args.repeat, observe=("final", "lyapunov"),
                                   **kwargs)
        # the tangent dynamics do not touch the trajectory
        assert np.array_equal(plain.theta_final.values, tangent.theta_final.values)
        rows.append({"scene": name, "plain_s": t_plain, "lyapunov_s": t_tangent,
                     "plain_steps_per_s": work / t_plain,
                     "lyapunov_steps_per_s": work / t_tangent,
                     "cost": t_tangent / t_plain})

    # NumPy baseline on the chaotic scene, chunk size swept, checked against sweep
    theta0, omega0 = (a.ravel() for a in np.meshgrid(grid.axes["theta0"],
                                                     grid.axes["omega0"], indexing="ij"))
    numpy_steps = args.numpy_periods * STEPS_PER_PERIOD
    chunks = {}
    for chunk in sorted({min(c, theta0.size) for c in (1024, 4096, 16384, 65536)}):
        start = time.perf_counter()
        rates = np.concatenate([numpy_lyapunov(theta0[k:k + chunk], omega0[k:k + chunk],
                                               numpy_steps, dt)
                                for k in range(0, theta0.size, chunk)], axis=1)
        chunks[chunk] = time.perf_counter() - start
    best_chunk = min(chunks, key=chunks.get)
    check = sweep.run(scenes()["chaotic pendulum (damping, forcing)"], grid,
                      t_end=numpy_steps * dt, dt=dt, observe=("lyapunov",), progress=False)
    difference = float(np.max(np.abs(check.lyapunov_max.values.ravel() - rates[0])))
    assert difference < 1e-8, difference  # the same map, to rounding
    numpy_rate = theta0.size * numpy_steps / chunks[best_chunk]
    result = {"machine": machine(), "trajectories": grid.size, "steps": n_steps,
              "runs": rows,
              "numpy": {"steps": numpy_steps, "best_chunk": best_chunk,
                        "seconds_by_chunk": chunks, "steps_per_s": numpy_rate,
                        "max_difference_to_sweep": difference,
                        "sweep_over_numpy": rows[0]["lyapunov_steps_per_s"] / numpy_rate}}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "lyapunov.json").write_text(json.dumps(result, indent=2))
    lines = [
        "# Lyapunov exponents: what the tangent dynamics cost",
        "",
        f"{machine()}; {grid.size} trajectories x {n_steps} RK4 steps, best of "
        f"{args.repeat}, side by side in one process.",
        "",
        "| scene | plain kernel (steps/s) | with lyapunov (steps/s) | cost |",
        "| --- | ---: | ---: | ---: |",
    ]
    for row in rows:
        lines.append(f"| {row['scene']} | {row['plain_steps_per_s']:.3g} | "
                     f"{row['lyapunov_steps_per_s']:.3g} | {row['cost']:.2f}x |")
    lines += [
        "",
        f"Plain NumPy Benettin (chaotic scene, arrays of {best_chunk} trajectories, the "
        f"best of chunks {sorted(chunks)}): {numpy_rate:.3g} steps/s over {numpy_steps} "
        f"steps; sweep with lyapunov is {result['numpy']['sweep_over_numpy']:.0f}x "
        f"faster (exponents agree to {difference:.1e} /s).",
    ]
    (args.out / "lyapunov.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
