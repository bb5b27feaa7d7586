"""Work-precision diagrams: what accuracy costs, per method, on four scenes.

    python benchmarks/work_precision.py [-o DIR] [--quick]

Scenes (issue 4): undamped libration (k = 0.5), near-separatrix libration (k = 0.999,
the classic hard case), rotation, and a damped forced scene over a short horizon. Each
scene is a sample of nearby starts; errors are against the exact elliptic solution
(the first three) or sweep's dopri5 at rtol 1e-13 (the forced scene).

Writes into DIR (default ``benchmarks/output/work_precision``):

- ``<scene>.png``: error against wall time per 10^6 trajectories, one line per method;
- ``work_precision.json``: every measured point and the cost table;
- ``work_precision.md``: for each method and scene, the dt (or rtol) and the time per
  million trajectories needed for errors of 1e-4, 1e-8 and 1e-12.

Timings are wall time of `sweep.run` (best of 3, kernel compiled beforehand) on this
machine, with its thread count; compare only numbers from the same machine.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numba
import numpy as np

import sweep
from sweep import accuracy

TARGETS = (1e-4, 1e-8, 1e-12)
G, L = 9.81, 1.0
W0 = math.sqrt(G / L)


def scenes(n: int):
    """(key, title, scene, sample, t_end) for each scene; ``n`` starts per sample."""
    spread = np.linspace(-1.0, 1.0, n)
    conservative = sweep.Scene(gravity=G, length=L)
    forced = sweep.Scene(gravity=G, length=L,
                         effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3, 0.0)))
    theta_half = 2 * math.asin(0.5)
    theta_sep = 2 * math.asin(0.999)
    return [
        ("libration", "undamped libration, k = 0.5", conservative,
         sweep.Grid(theta0=theta_half + 1e-3 * spread), 10.0),
        ("separatrix", "near-separatrix libration, k = 0.999", conservative,
         sweep.Grid(theta0=theta_sep + 1e-6 * spread), 10.0),
        ("rotation", "rotation, omega0 = 8 rad/s (k = 1.28)", conservative,
         sweep.Grid(omega0=8.0 + 1e-3 * spread), 10.0),
        ("forced", "damped (c = 0.5) forced (A = 1.2, W = 2/3), t_end = 10 s", forced,
         sweep.Grid(theta0=0.5 * spread), 10.0),
    ]


def methods_for(scene):
    names = ["euler", "heun", "rk4", "rk38", "dopri5"]
    if sweep.accuracy.has_exact(scene) and scene.model == "nonlinear" \
            and scene.damping is None and scene.forcing is None:
        names[4:4] = ["verlet", "yoshida4"]
    return names


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", default="benchmarks/output/work_precision")
    parser.add_argument("--quick", action="store_true",
                        help="few trajectories and levels (a smoke test, seconds)")
    args = parser.parse_args(argv)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    n = 16 if args.quick else 512
    repeats = 1 if args.quick else 3
    # dt = 10 s / 2^k: from 0.3 s (w0 dt ~ 1) down to 0.6 ms; Euler needs the finest
    exponents = range(5, 12) if args.quick else range(5, 17)
    dts = [10.0 / 2 ** k for k in exponents]
    tolerances = [10.0 ** -e for e in (range(3, 12, 2) if args.quick else range(3, 14))]

    import matplotlib

    matplotlib.use("Agg")
    import sweep.plot

    record = {
        "machine": {"python": sys.version.split()[0], "numba": numba.__version__,
                    "sweep": sweep.__version__, "platform": platform.platform(),
                    "cpu_count": os.cpu_count(), "threads": numba.get_num_threads()},
        "n_trajectories": n, "targets": list(TARGETS), "scenes": {},
    }
    md = ["# Work-precision: what accuracy costs", "",
          f"{n} trajectories per scene, t_end = 10 s, wall time best of {repeats} on "
          f"{os.cpu_count()} cores ({numba.get_num_threads()} threads), numba "
          f"{numba.__version__}. Error: max over the trajectories of "
          "max(|d theta|, |d omega|/omega_n) at t_end [rad]. Cells: step dt [s] (rtol for "
          "dopri5) / seconds per 10^6 trajectories needed for the error; `-`: not reached "
          "on the ladder.", ""]
    for key, title, scene, sample, t_end in scenes(n):
        started = time.perf_counter()
        names = methods_for(scene)
        wp = accuracy.work_precision(scene, sample, names, t_end=t_end, dts=dts,
                                     tolerances=tolerances, dt_max=0.25, repeats=repeats)
        cost = accuracy.cost_at(wp, TARGETS)
        fig = sweep.plot.work_precision(wp, x="time_per_million", title=title)
        sweep.plot.save_figure(fig, out / f"{key}.png")
        record["scenes"][key] = {
            "title": title, "t_end": t_end, "reference": wp.attrs["reference"],
            "points": {m: {v: [None if not np.isfinite(x) else float(x)
                               for x in wp[v].sel(integrator=m).values]
                           for v in ("dt", "rtol", "error_max", "error_rms", "wall_time",
                                     "time_per_million", "rhs_evaluations")}
                       for m in names},
            "observed_order": {m: float(wp.observed_order.sel(integrator=m)) for m in names},
            "cost": {m: {f"{t:g}": {"dt": _num(cost.dt.sel(integrator=m, error=t)),
                                    "rtol": _num(cost.rtol.sel(integrator=m, error=t)),
                                    "time_per_million": _num(
                                        cost.time_per_million.sel(integrator=m, error=t))}
                         for t in TARGETS} for m in names},
        }
        md += [f"## {title}", "", f"![{key}]({key}.png)", "",
               "| method | observed order | " + " | ".join(f"error {t:g}" for t in TARGETS)
               + " |", "|---|---|" + "---|" * len(TARGETS)]
        for m in names:
            cells = []
            for t in TARGETS:
                c = record["scenes"][key]["cost"][m][f"{t:g}"]
                step = c["rtol"] if c["rtol"] is not None else c["dt"]
                cells.append("-" if c["time_per_million"] is None else
                             f"{step:.3g} / {c['time_per_million']:.3g} s")
            md.append(f"| {m} | {record['scenes'][key]['observed_order'][m]:.2f} | "
                      + " | ".join(cells) + " |")
        md.append("")
        print(f"{key}: {time.perf_counter() - started:.1f} s", file=sys.stderr)
    record["dopri5_lanes"], lanes_md = dopri5_lanes(16 * n, repeats)
    md += lanes_md
    (out / "work_precision.json").write_text(json.dumps(record, indent=1) + "\n")
    (out / "work_precision.md").write_text("\n".join(md))
    print(f"wrote {out}/", file=sys.stderr)
    return 0


#: the lanes' block of the adaptive kernel before it was raised to 64, timed beside it
SMALL_ADAPTIVE_BLOCK = 16


def dopri5_lanes(n: int, repeats: int, tolerances=(1e-6, 1e-9)):
    """dopri5 in SIMD lanes against one trajectory at a time (the same kernel with a
    block of one lane and libm's power in its controller, as the adaptive kernel ran
    before it had lanes: the faster scalar choice), side by side in this process at
    the same rtol, so at equal error (the controllers agree to 3 ulp, the results to
    rounding): best of ``repeats`` alternating calls per scene and tolerance, on
    ``n`` trajectories (enough that sweep.run's ~1 ms of fixed costs do not weigh).

    Also timed: blocks of `SMALL_ADAPTIVE_BLOCK` lanes (a block tries steps until its
    slowest trajectory is done, so a smaller block wastes less where neighbouring
    trajectories need different step counts), and an uneven grid: the whole phase
    plane of the undamped pendulum, omega0 in [-20, 20] rad/s along the block (the
    grid's last axis), whose trajectories need 0.7-1.2x the median step count."""
    rows, table = [], ["## dopri5 in SIMD lanes against one trajectory at a time", "",
                       f"{n} trajectories, the same rtol (so the same error), best of "
                       f"{repeats} alternating calls.", "",
                       f"| scene | rtol | one at a time | blocks of {SMALL_ADAPTIVE_BLOCK} "
                       f"| blocks of {sweep._config.ADAPTIVE_BLOCK} (default) | speed-up |",
                       "|---|---|---|---|---|---|"]
    lanes_block = sweep._config.ADAPTIVE_BLOCK
    uneven = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 64),
                        omega0=np.linspace(-20.0, 20.0, max(1, n // 64)))
    cases = list(scenes(n)) + [
        ("uneven", "uneven: undamped, theta0 x omega0 in [-pi, pi] x [-20, 20]",
         sweep.Scene(), uneven, 10.0)]
    for key, title, scene, sample, t_end in cases:
        for rtol in tolerances:
            kwargs = dict(t_end=t_end, dt=0.25, method="dopri5", rtol=rtol,
                          atol=rtol * 1e-3, observe=("final",), progress=False)
            best = {"one": math.inf, "small": math.inf, "lanes": math.inf}
            for _ in range(repeats):
                for label in best:
                    if label == "one":  # the strongest one-at-a-time kernel: libm's pow
                        sweep._config.ADAPTIVE_BLOCK = 1
                        sweep._config.VECTOR_CONTROLLER = False
                    elif label == "small":
                        sweep._config.ADAPTIVE_BLOCK = SMALL_ADAPTIVE_BLOCK
                    sweep.kernels.build.cache_clear()
                    try:
                        sweep.engine.warm_up(scene, sample, **kwargs)
                        start = time.perf_counter()
                        sweep.run(scene, sample, **kwargs)
                        best[label] = min(best[label], time.perf_counter() - start)
                    finally:
                        sweep._config.ADAPTIVE_BLOCK = lanes_block
                        sweep._config.VECTOR_CONTROLLER = True
                        sweep.kernels.build.cache_clear()
            rows.append({"scene": key, "rtol": rtol, "one_at_a_time_s": best["one"],
                         "small_blocks_s": best["small"], "lanes_s": best["lanes"],
                         "speedup": best["one"] / best["lanes"]})
            table.append(f"| {title} | {rtol:g} | {best['one'] * 1e3:.1f} ms | "
                         f"{best['small'] * 1e3:.1f} ms | {best['lanes'] * 1e3:.1f} ms | "
                         f"{best['one'] / best['lanes']:.1f}x |")
    return rows, table + [""]


def _num(da):
    x = float(da)
    return None if not math.isfinite(x) else x


if __name__ == "__main__":
    raise SystemExit(main())
