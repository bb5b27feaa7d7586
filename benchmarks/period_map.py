"""Time a periodicity map end to end: ``sweep.run`` (strobe samples) then
``maps.period``, over forcing amplitude x forcing frequency from one start.

Workload (``examples/orbit_diagram.py``'s map): g/L = 1, c = 0.5, ``size`` values of A
in [0.8, 1.6] x ``size`` values of W in [0.4, 1.0] (their periods distinct whole numbers
of steps: dt = 0.05 s up to 189 values, dt = 0.05 / 3 s for 400), 500 s of transient and
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
    from _machine import machine
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
    observe = ("strobe", "lyapunov") if args.lyapunov else ("strobe",)
    scene, grid, kwargs = _example().periodicity_run(args.size, observe=observe)
    sweep.engine.warm_up(scene, grid, **kwargs)  # compile or load first
    start = time.perf_counter()
    ds = sweep.run(scene, grid, **kwargs)
    run_s = time.perf_counter() - start
    start = time.perf_counter()
    periods = maps.period(ds)
    period_s = time.perf_counter() - start
    n = int(periods.size)
    work = n * int(ds.attrs["n_steps"])
    result = {"machine": machine(), "size": args.size, "trajectories": n,
              "steps": int(ds.attrs["n_steps"]), "dt": float(ds.attrs["dt"]),
              "observe": ds.attrs["observe"], "run_s": run_s, "period_s": period_s,
              "steps_per_s": work / run_s,
              "resolved_fraction": float((periods > 0).mean())}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "period_map.json").write_text(json.dumps(result, indent=2))
    text = (f"# Periodicity map\n\n{machine()}; {args.size} x {args.size} (A, W) from one "
            f"start ({n} trajectories), {result['steps']} RK4 steps of {result['dt']:.4g} s "
            f"each, observing {result['observe']}: "
            f"sweep.run {run_s:.1f} s ({result['steps_per_s']:.3g} trajectory-steps/s), "
            f"maps.period {period_s:.2f} s; {result['resolved_fraction']:.3f} of the "
            "starts have a period <= 8.\n")
    (args.out / "period_map.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
