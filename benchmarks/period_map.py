"""Time a periodicity map end to end: ``sweep.run`` (strobe samples) then
``maps.period``, over forcing amplitude x forcing frequency from one start.

Workload (``examples/orbit_diagram.py``'s map): g/L = 1, c = 0.5, A in [0.8, 1.6],
W in [0.4, 1.0] (periods a whole number of steps dt = 0.05 s), 500 s of transient and
16 forcing periods observed, RK4; ``--lyapunov`` also observes the exponents (for the
chaos colour). Prints and writes (``benchmarks/results/period_map.json``, ``.md``)
the time of each part and trajectory-steps per second.

Usage::

    python benchmarks/period_map.py [--size 400] [--lyapunov]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

import sweep
from sweep import maps

try:  # the machine description of the basin benchmark
    from forced_basins import machine
except ImportError:  # pragma: no cover - run from elsewhere
    def machine() -> str:
        return "unknown machine"


def _example():
    path = Path(__file__).resolve().parents[1] / "examples" / "orbit_diagram.py"
    spec = importlib.util.spec_from_file_location("orbit_diagram_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=400)
    parser.add_argument("--lyapunov", action="store_true")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    example = _example()
    example.periodicity(4)  # compile first
    start = time.perf_counter()
    ds = example.periodicity(args.size)
    if not args.lyapunov:  # the example observes both; time the run without lyapunov
        scene = sweep.io.scene_from(ds)
        grid = sweep.Grid(**{d: ds[d].values for d in ds.attrs["grid_axes"].split()})
        kwargs = sweep.io.run_arguments(ds)
        kwargs["observe"] = ("strobe",)
        sweep.run(scene, sweep.Grid(theta0=[0.0], omega0=[0.0],
                                    forcing_frequency=grid.axes["forcing_frequency"][:1]),
                  **{**kwargs, "progress": False})
        start = time.perf_counter()
        ds = sweep.run(scene, grid, progress=False, **kwargs)
    run_s = time.perf_counter() - start
    start = time.perf_counter()
    periods = maps.period(ds)
    period_s = time.perf_counter() - start
    n = int(periods.size)
    work = n * int(ds.attrs["n_steps"])
    result = {"machine": machine(), "trajectories": n, "steps": int(ds.attrs["n_steps"]),
              "observe": ds.attrs["observe"], "run_s": run_s, "period_s": period_s,
              "steps_per_s": work / run_s,
              "resolved_fraction": float((periods > 0).mean())}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "period_map.json").write_text(json.dumps(result, indent=2))
    text = (f"# Periodicity map\n\n{machine()}; {args.size} x {args.size} (A, W) from one "
            f"start, {result['steps']} RK4 steps each, observing {result['observe']}: "
            f"sweep.run {run_s:.1f} s ({result['steps_per_s']:.3g} trajectory-steps/s), "
            f"maps.period {period_s:.2f} s; {result['resolved_fraction']:.3f} of the "
            "starts have a period <= 8.\n")
    (args.out / "period_map.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
