"""Time ``device="cuda"`` against the CPU kernels on the issue's workloads.

Workloads (the full scene of ``run_all.py``: damping and forcing, RK4, float64):

1. 2^17 trajectories x 2000 steps (``run_all.py``'s workload), on the GPU and on the
   CPU side by side, trajectory-steps per second;
2. 2^24 trajectories x 2000 steps on the GPU (chunks of 2^20 streamed through it);
3. the 1200 x 1200 forced basin map of ``forced_basins.py`` end to end (``sweep.run``
   then ``maps.basins``), with and without ``stop_early`` (a settled thread leaves its
   loop; the rest of its warp goes on).

Each GPU run is timed after a warm-up call (compilation and the CUDA context excluded);
the answers are checked against the CPU's (final states to 1e-9 on a sample, identical
basin labels but for a few boundary starts). Without a GPU the script says so and exits
with status 2; ``--size-scale`` shrinks every workload (for the test suite, under
numba's CUDA simulator: its rates mean nothing).

Writes ``benchmarks/results/gpu.json`` and ``.md``.

Usage::

    python benchmarks/gpu.py [--size-scale S] [--steps N] [--skip-map]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps

try:
    from forced_basins import OBSERVED_PERIODS, STEPS_PER_PERIOD, TRANSIENT_PERIODS, machine
except ImportError:  # pragma: no cover - run from elsewhere
    sys.path.insert(0, str(Path(__file__).parent))
    from forced_basins import OBSERVED_PERIODS, STEPS_PER_PERIOD, TRANSIENT_PERIODS, machine

STEPS = 2000
DT = 0.01


def gpu_name() -> str | None:
    """The GPU's name, or None where ``device="cuda"`` cannot run."""
    from numba.core import config

    from sweep.kernels.cuda import available

    if available() is not None:
        return None
    if config.ENABLE_CUDASIM:
        return "numba CUDA simulator (no GPU: rates meaningless)"
    from numba import cuda

    name = cuda.get_current_device().name
    return name.decode() if isinstance(name, bytes) else str(name)


def full_scene() -> sweep.Scene:
    """run_all.py's full scene: g/L = 1, c = 0.5, A = 1.2, W = 2/3."""
    return sweep.Scene(gravity=1.0, length=1.0,
                       effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3)))


def _grid(n: int) -> sweep.Grid:
    cols = max(1, round(np.sqrt(n / 2)))
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, max(1, n // cols)),
                      omega0=np.linspace(-2.0, 2.0, cols))


def _timed(scene, grid, **kwargs):
    """(dataset, seconds) of one run after a warm-up run on a small grid."""
    sweep.run(scene, sweep.Grid(theta0=[0.1, 0.2], omega0=[0.0]),
              **{**kwargs, "progress": False})
    start = time.perf_counter()
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    return ds, time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size-scale", type=float, default=1.0,
                        help="multiply every workload's trajectory count by this")
    parser.add_argument("--steps", type=int, default=STEPS, help="steps per trajectory")
    parser.add_argument("--skip-map", action="store_true", help="skip the basin map")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    name = gpu_name()
    if name is None:
        from sweep.kernels.cuda import available

        print(f"benchmarks/gpu.py: nothing measured: {available()}", file=sys.stderr)
        return 2
    scene = full_scene()
    steps = args.steps
    kwargs = dict(t_end=steps * DT, dt=DT, observe=("final",))
    rows = []

    n = max(2, int(2 ** 17 * args.size_scale))
    grid = _grid(n)
    gpu, t_gpu = _timed(scene, grid, device="cuda", **kwargs)
    cpu, t_cpu = _timed(scene, grid, **kwargs)
    difference = float(np.nanmax(np.abs(gpu.theta_final - cpu.theta_final)))
    work = grid.size * steps
    rows.append({"workload": f"{grid.size} x {steps} steps", "gpu_s": t_gpu, "cpu_s": t_cpu,
                 "gpu_steps_per_s": work / t_gpu, "cpu_steps_per_s": work / t_cpu,
                 "max_difference_rad": difference})

    n = max(2, int(2 ** 24 * args.size_scale))
    grid = _grid(n)
    _, t_big = _timed(scene, grid, device="cuda", **kwargs)
    rows.append({"workload": f"{grid.size} x {steps} steps", "gpu_s": t_big,
                 "gpu_steps_per_s": grid.size * steps / t_big})

    basin = {}
    if not args.skip_map:
        size = max(2, int(1200 * np.sqrt(args.size_scale)))
        period = 2 * np.pi
        forced = sweep.Scene(gravity=1.0, length=1.0, effects=(
            sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
        grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                          omega0=np.linspace(-4.0, 4.0, size))
        map_kwargs = dict(t_end=(TRANSIENT_PERIODS + OBSERVED_PERIODS) * period,
                          dt=period / STEPS_PER_PERIOD, t_transient=TRANSIENT_PERIODS * period,
                          observe=("strobe",))
        for label, extra in (("as specified", {}),
                             ("stop_early", {"stop_early": True,
                                             "t_transient": OBSERVED_PERIODS * period})):
            start = time.perf_counter()
            ds, _ = _timed(forced, grid, device="cuda", **{**map_kwargs, **extra})
            labels = maps.basins(ds)
            basin[label] = {"seconds": time.perf_counter() - start,
                            "attractors": int(labels.max()) + 1}
    result = {"machine": machine(), "gpu": name, "float64": rows, "basin_map": basin,
              "float32": "not built yet (see the README)"}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "gpu.json").write_text(json.dumps(result, indent=2))
    lines = ["# sweep on a GPU", "", f"GPU: {name}; CPU: {machine()}.", "",
             "| workload (full scene, RK4, float64) | GPU steps/s | CPU steps/s |",
             "| --- | ---: | ---: |"]
    for row in rows:
        cpu_rate = f"{row['cpu_steps_per_s']:.3g}" if "cpu_steps_per_s" in row else "-"
        lines.append(f"| {row['workload']} | {row['gpu_steps_per_s']:.3g} | {cpu_rate} |")
    for label, entry in basin.items():
        lines.append(f"\nBasin map ({label}), end to end: {entry['seconds']:.1f} s, "
                     f"{entry['attractors']} attractors.")
    (args.out / "gpu.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
