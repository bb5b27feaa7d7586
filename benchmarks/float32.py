"""What ``dtype="float32"`` buys in speed and costs in accuracy, side by side.

    python benchmarks/float32.py [--quick] [--size N] [--repeats R]

Four measurements, each float32 against float64 in the same run:

1. **Speed**: ``run_all.py``'s full-scene workload (2^17 trajectories x 2000 RK4 steps,
   damped forced nonlinear pendulum) and variants (damping only; forcing frequency per
   trajectory; the linear model), million trajectory-steps per second, best of R
   alternating calls.
2. **Accuracy against time**: RK4 on the work-precision scenes (libration, rotation,
   the damped forced scene), error at t_end against the exact or DOP853-quality
   reference, for a ladder of steps: where float32's rounding floor lies.
3. **Basin labels**: the forced basin map of the maps issue (c = 0.2, A = 1.66, W = 1,
   cos forcing, 300 transient + 20 observed periods, 100 steps per period) on an
   N x N grid, float64 against float32 (full run and ``stop_early``): how many starts
   change attractor, and how many become unresolved; beside them, float64 at dt / 2
   against float64 at dt, the share of the labels that the step itself decides (the
   basins' boundaries are fractal, so any perturbation flips the starts near them).
4. **Lyapunov exponents**: the largest exponent on Baker & Gollub's chaotic pendulum
   and on a periodic attractor, float32 against float64 (start by start, and the
   mean).

Writes ``benchmarks/results/float32.json`` and ``.md`` (``--output`` changes the
folder).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import accuracy, maps

import run_all
from _machine import machine

DTYPES = ("float64", "float32")


def _rate(fn, n_steps, repeats):
    """Best-of-``repeats`` M trajectory-steps/s of each dtype, calls alternating."""
    best = {d: math.inf for d in DTYPES}
    for d in DTYPES:
        fn(d)  # compile or load the kernel
    for _ in range(repeats):
        for d in DTYPES:
            start = time.perf_counter()
            fn(d)
            best[d] = min(best[d], time.perf_counter() - start)
    return {d: n_steps / best[d] / 1e6 for d in DTYPES}


def speed(n, steps, repeats):
    """Rates of the full-scene workload and variants (M trajectory-steps/s)."""
    theta0, omega0 = run_all.grid_axes(n)
    size = len(theta0) * len(omega0)
    rows = {}
    for key, scene, extra in (
            ("damping + forcing", run_all.scene_of(), {}),
            ("damping + forcing, W per trajectory", run_all.scene_of(),
             {"forcing_frequency": run_all.FREQUENCY * (1 + 1e-9 * np.arange(2))}),
            ("damping only", run_all.scene_of(forcing=False), {}),
            ("linear, damping + forcing", run_all.scene_of(model="linear"), {})):
        grid = sweep.Grid(theta0=theta0, omega0=omega0[: len(omega0) // 2] if extra
                          else omega0, **extra)
        trajectories = grid.size
        rows[key] = _rate(lambda d, g=grid, s=scene: sweep.run(
            s, g, t_end=steps * run_all.DT, dt=run_all.DT, observe=("final",),
            progress=False, dtype=d), trajectories * steps, repeats)
    return {"trajectories": size, "steps": steps, "rates": rows}


def precision(n, quick):
    """RK4's error at t_end against the reference, and time per 10^6 trajectories,
    for each dtype over a ladder of steps."""
    import work_precision

    exponents = range(5, 9) if quick else range(5, 15)
    dts = [10.0 / 2**k for k in exponents]
    out = {}
    for key, title, scene, sample, t_end in work_precision.scenes(n):
        if key == "separatrix":
            continue
        rows = {}
        for d in DTYPES:
            wp = accuracy.work_precision(scene, sample, ["rk4"], t_end=t_end, dts=dts,
                                         repeats=1 if quick else 3, dtype=d)
            rows[d] = {"error_max": [float(x) for x in wp.error_max.values[0]],
                       "time_per_million": [float(x) for x in
                                            wp.time_per_million.values[0]]}
        out[key] = {"title": title, "dt": dts, **rows}
    return out


def _forced_scene():
    return sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, math.pi / 2)))


def _matched(labels, reference):
    """``labels`` renamed to the reference's attractor labels: each label to the
    reference label most of its starts carry (the catalogues may order attractors
    differently)."""
    out = np.full_like(labels, -1)
    for label in np.unique(labels[labels >= 0]):
        members = reference[labels == label]
        members = members[members >= 0]
        if members.size:
            out[labels == label] = np.bincount(members).argmax()
    return out


def basins(size, transient=300, observed=20):
    """The forced map in float64 (full run), float32 (full run, stop_early): time,
    changed labels, unresolved starts."""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-4.0, 4.0, size))
    period = 2 * math.pi
    kwargs = dict(t_end=(transient + observed) * period, dt=period / 100,
                  t_transient=transient * period, observe=("strobe",), progress=False)
    results = {}
    for key, options in (("float64", {}), ("float32", {"dtype": "float32"}),
                         # early stop decides when to end: a short transient (as
                         # benchmarks/stop_early.py)
                         ("float32, stop_early", {"dtype": "float32", "stop_early": True,
                                                  "t_transient": 20 * period}),
                         ("float64, stop_early", {"stop_early": True,
                                                  "t_transient": 20 * period}),
                         # the discretisation's own share: the same map at dt / 2
                         ("float64, dt / 2", {"dt": period / 200})):
        options = {**kwargs, **options}
        # compile or load the kernel first (it does not depend on the times)
        sweep.run(_forced_scene(), grid, **{**options, "t_end": 2 * period,
                                            "t_transient": period})
        start = time.perf_counter()
        ds = sweep.run(_forced_scene(), grid, **options)
        seconds = time.perf_counter() - start
        results[key] = (maps.basins(ds).values.ravel(), seconds)
    reference = results["float64"][0]
    rows = {}
    for key, (labels, seconds) in results.items():
        same = _matched(labels, reference)
        resolved = reference >= 0
        rows[key] = {"seconds": seconds, "attractors": int(labels.max()) + 1,
                     "unresolved": int((labels < 0).sum()),
                     "changed": int(((same != reference) & resolved & (labels >= 0)).sum()),
                     "starts": int(labels.size)}
    return rows


def lyapunov(n, periods):
    """Largest exponent, float32 against float64: a chaotic and a periodic case."""
    out = {}
    for key, amplitude in (("chaotic (A = 1.5)", 1.5), ("periodic (A = 1.07)", 1.07)):
        scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
            sweep.Damping(0.5), sweep.Forcing(amplitude, 2 / 3)))
        grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, n), omega0=[0.0])
        period = 3 * math.pi
        values = {}
        for d in DTYPES:
            ds = sweep.run(scene, grid, t_end=periods * period, dt=period / 100,
                           t_transient=20 * period, observe=("lyapunov",), dtype=d,
                           progress=False)
            values[d] = ds.lyapunov_max.values.ravel()
        diff = np.abs(values["float32"] - values["float64"])
        out[key] = {"mean_float64": float(values["float64"].mean()),
                    "mean_float32": float(values["float32"].mean()),
                    "spread_float64": float(values["float64"].std()),
                    "max_start_difference": float(diff.max()),
                    "starts": n, "periods": periods}
    return out


def markdown(r) -> str:
    lines = ["# float32 against float64, side by side", "", f"Machine: {r['machine']}.", "",
             f"## Speed (M trajectory-steps/s, {r['speed']['trajectories']} trajectories x "
             f"{r['speed']['steps']} RK4 steps, best of {r['repeats']})", "",
             "| scene | float64 | float32 | ratio |", "|---|---|---|---|"]
    for key, rate in r["speed"]["rates"].items():
        lines.append(f"| {key} | {rate['float64']:.0f} | {rate['float32']:.0f} | "
                     f"{rate['float32'] / rate['float64']:.2f}x |")
    lines += ["", "## RK4's error at t_end against the reference (max over the starts, rad)",
              ""]
    for row in r["precision"].values():
        lines += [f"**{row['title']}**", "", "| dt [s] | float64 error | float32 error | "
                  "float64 s/1e6 traj. | float32 s/1e6 traj. |", "|---|---|---|---|---|"]
        for k, dt in enumerate(row["dt"]):
            lines.append(f"| {dt:.3g} | {row['float64']['error_max'][k]:.2g} | "
                         f"{row['float32']['error_max'][k]:.2g} | "
                         f"{row['float64']['time_per_million'][k]:.3g} | "
                         f"{row['float32']['time_per_million'][k]:.3g} |")
        lines.append("")
    b = r["basins"]
    starts = next(iter(b.values()))["starts"]
    lines += [f"## Forced basin map, {starts} starts (labels against float64's full run)", "",
              "| run | seconds | attractors | changed label | unresolved |",
              "|---|---|---|---|---|"]
    for key, row in b.items():
        lines.append(f"| {key} | {row['seconds']:.2f} | {row['attractors']} | "
                     f"{row['changed']} | {row['unresolved']} |")
    lines += ["", "## Largest Lyapunov exponent (1/s)", "",
              "| case | float64 mean | float32 mean | float64 spread | max difference, "
              "start by start |", "|---|---|---|---|---|"]
    for key, row in r["lyapunov"].items():
        lines.append(f"| {key}, {row['starts']} starts, {row['periods']} periods | "
                     f"{row['mean_float64']:.4f} | {row['mean_float32']:.4f} | "
                     f"{row['spread_float64']:.4f} | {row['max_start_difference']:.2g} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes (a smoke test)")
    parser.add_argument("--size", type=int, default=201, help="basin map: size x size")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--output", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args(argv)
    quick = args.quick
    result = {
        "machine": machine(), "repeats": args.repeats,
        "speed": speed(2**10 if quick else 2**17, 20 if quick else 2000,
                       1 if quick else args.repeats),
        "precision": precision(4 if quick else 64, quick),
        "basins": basins(9 if quick else args.size, *((40, 20) if quick else (300, 20))),
        "lyapunov": lyapunov(4 if quick else 64, 30 if quick else 400),
    }
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    (out / "float32.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "float32.md").write_text(markdown(result))
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
