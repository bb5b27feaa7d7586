"""Time ``device="cuda"`` against the CPU kernels on the issue's workloads.

Workloads (the full scene of ``run_all.py``: damping and forcing, RK4), each in float64
and in float32:

1. 2^17 trajectories x 2000 steps (``run_all.py``'s workload), on the GPU and on the
   CPU side by side, trajectory-steps per second; the GPU's final angles are checked
   against the CPU's (``max_difference_rad``);
2. 2^24 trajectories x 2000 steps on the GPU (chunks of 2^20 streamed through it).

Each is reported end to end (``sweep.run``'s wall time, after a warm-up call so that
compilation and the CUDA context are excluded) and as the integration rate alone: the
extra time of a run twice as long over the same grid (the parameter table, the copies
and the dataset cost the same in both runs, so the difference is the kernel's own).

3. The 1200 x 1200 forced basin map of ``forced_basins.py``, float64, end to end
   (``sweep.run`` then ``maps.basins``): as specified, with ``stop_early`` (a settled
   thread leaves its loop; the rest of its warp goes on), and with ``stop_early`` and a
   pilot's attractor catalogue (pilot included); labels are compared with the full
   run's where it resolves one.

Without a GPU the script says so and exits with status 2; ``--size-scale`` shrinks
every workload (for the test suite, under numba's CUDA simulator: its rates mean
nothing).

Writes ``benchmarks/results/gpu.json`` and ``.md``.

Usage::

    python benchmarks/gpu.py [--size-scale S] [--steps N] [--skip-map] [--pilot N]
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
    from _machine import machine
    from forced_basins import OBSERVED_PERIODS, STEPS_PER_PERIOD, TRANSIENT_PERIODS
except ImportError:  # pragma: no cover - run from elsewhere
    sys.path.insert(0, str(Path(__file__).parent))
    from _machine import machine
    from forced_basins import OBSERVED_PERIODS, STEPS_PER_PERIOD, TRANSIENT_PERIODS

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
    """(dataset, seconds) of one run, compilation excluded: on the CPU by
    `sweep.engine.warm_up` on the run's own grid (its size picks the kernel's SIMD
    block), on the GPU by a run on a small grid (one CUDA kernel serves every grid
    size, and numba compiles it at its first launch)."""
    if kwargs.get("device") == "cuda":
        sweep.run(scene, sweep.Grid(theta0=[0.1, 0.2], omega0=[0.0]),
                  **{**kwargs, "progress": False})
    else:
        sweep.engine.warm_up(scene, grid, **kwargs)
    start = time.perf_counter()
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    return ds, time.perf_counter() - start


def _workload_rows(scene, n: int, steps: int, dtype: str, cpu: bool) -> dict:
    """One workload in one precision: the GPU end to end and, with ``cpu``, the CPU
    side by side; without it (the large workload), also the GPU's rate net of fixed
    costs: the difference between a run of ``2 steps`` and one of ``steps`` steps over
    the same grid is pure integration (the copies and the dataset cost the same in
    both). On the small workload that difference is a few milliseconds, within the
    timer's noise, so it is not reported there."""
    grid = _grid(n)
    kwargs = dict(dt=DT, observe=("final",), dtype=dtype)
    gpu, t_gpu = _timed(scene, grid, device="cuda", t_end=steps * DT, **kwargs)
    work = grid.size * steps
    row = {"workload": f"{grid.size} x {steps} steps", "dtype": dtype, "gpu_s": t_gpu,
           "gpu_steps_per_s": work / t_gpu}
    if cpu:
        reference, t_cpu = _timed(scene, grid, t_end=steps * DT, **kwargs)
        row.update(cpu_s=t_cpu, cpu_steps_per_s=work / t_cpu, max_difference_rad=float(
            np.nanmax(np.abs(gpu.theta_final - reference.theta_final))))
    else:
        _, t_double = _timed(scene, grid, device="cuda", t_end=2 * steps * DT, **kwargs)
        row["gpu_integration_steps_per_s"] = work / max(t_double - t_gpu, 1e-9)
    return row


def _basin_map(size: int, pilot: int) -> dict:
    """The 1200 x 1200 forced map on the GPU end to end (``run`` + ``maps.basins``): as
    specified, with ``stop_early``, and with ``stop_early`` and a pilot's attractor
    catalogue (the pilot's time counted); labels compared with the full run's."""
    period = 2 * np.pi
    forced = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    axes = dict(theta0=np.linspace(-np.pi, np.pi, size), omega0=np.linspace(-4.0, 4.0, size))
    grid = sweep.Grid(**axes)
    full = dict(t_end=(TRANSIENT_PERIODS + OBSERVED_PERIODS) * period,
                dt=period / STEPS_PER_PERIOD, t_transient=TRANSIENT_PERIODS * period,
                observe=("strobe",), device="cuda")
    early = dict(full, stop_early=True, t_transient=OBSERVED_PERIODS * period)
    found, labels = {}, {}
    for name, options in (("full", full), ("stop_early", early), ("catalogue", early)):
        pilot_s = 0.0  # compilation is kept out of every time (see _timed)
        if name == "catalogue":
            trial, pilot_s = _timed(forced, maps.pilot_grid(grid, pilot), **options)
            start = time.perf_counter()
            options = dict(options, attractors=maps.attractor_catalogue(trial))
            pilot_s += time.perf_counter() - start
        ds, run_s = _timed(forced, grid, **options)
        maps.basins(ds.isel(theta0=slice(0, 2)))  # compiles (or loads) the labelling
        start = time.perf_counter()
        labels[name] = maps.basins(ds)
        label_s = time.perf_counter() - start
        found[name] = {"seconds": pilot_s + run_s + label_s, "pilot_seconds": pilot_s,
                       "run_seconds": run_s, "labelling_seconds": label_s,
                       "attractors": len(labels[name].attrs["attractor_size"])}
    resolved = labels["full"].values != maps.UNRESOLVED
    for name in ("stop_early", "catalogue"):
        differ = (labels[name].values != labels["full"].values) & resolved
        found[name]["labels_differing_where_full_resolves"] = int(differ.sum())
    full_steps = size**2 * (TRANSIENT_PERIODS + OBSERVED_PERIODS) * STEPS_PER_PERIOD
    for entry in found.values():
        entry["effective_traj_steps_per_s"] = full_steps / entry["seconds"]
    return found


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size-scale", type=float, default=1.0,
                        help="multiply every workload's trajectory count by this")
    parser.add_argument("--steps", type=int, default=STEPS, help="steps per trajectory")
    parser.add_argument("--skip-map", action="store_true", help="skip the basin map")
    parser.add_argument("--pilot", type=int, default=41,
                        help="the catalogue variant's pilot: pilot x pilot starts")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    name = gpu_name()
    if name is None:
        from sweep.kernels.cuda import available

        print(f"benchmarks/gpu.py: nothing measured: {available()}", file=sys.stderr)
        return 2
    scene = full_scene()
    rows = []
    for dtype in ("float64", "float32"):
        for n, cpu in ((2**17, True), (2**24, False)):
            rows.append(_workload_rows(scene, max(2, int(n * args.size_scale)), args.steps,
                                       dtype, cpu))
            print(rows[-1], flush=True)
    basin = {}
    if not args.skip_map:
        basin = _basin_map(max(2, int(1200 * np.sqrt(args.size_scale))), args.pilot)
    result = {"machine": machine(), "gpu": name, "workloads": rows, "basin_map": basin}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "gpu.json").write_text(json.dumps(result, indent=2))
    (args.out / "gpu.md").write_text(markdown(result))
    print(markdown(result))
    return 0


def markdown(result: dict) -> str:
    """The results as the README's tables."""
    lines = ["# sweep on a GPU", "", f"GPU: {result['gpu']}; CPU: {result['machine']}.", "",
             "Full scene (damping, forcing), RK4. 'end to end': `sweep.run`'s wall time "
             "(copies and dataset included); 'integration': the extra time of a run twice "
             "as long, i.e. the kernel's own rate.", "",
             "| workload | dtype | GPU end to end (steps/s) | GPU integration (steps/s) "
             "| CPU end to end (steps/s) | GPU / CPU |",
             "| --- | --- | ---: | ---: | ---: | ---: |"]
    for row in result["workloads"]:
        cpu_rate, ratio, net = "-", "-", "-"
        if "cpu_steps_per_s" in row:
            cpu_rate = f"{row['cpu_steps_per_s']:.3g}"
            ratio = f"{row['gpu_steps_per_s'] / row['cpu_steps_per_s']:.1f}"
        if "gpu_integration_steps_per_s" in row:
            net = f"{row['gpu_integration_steps_per_s']:.3g}"
        lines.append(f"| {row['workload']} | {row['dtype']} | {row['gpu_steps_per_s']:.3g} "
                     f"| {net} | {cpu_rate} | {ratio} |")
    if result["basin_map"]:
        lines += ["", "Forced basin map (float64), end to end (pilot, `run`, `maps.basins` on "
                  "the CPU):", "",
                  "| variant | seconds | of which `maps.basins` | effective steps/s | attractors "
                  "| labels differing from the full run |",
                  "| --- | ---: | ---: | ---: | ---: | ---: |"]
        for label, entry in result["basin_map"].items():
            differ = entry.get("labels_differing_where_full_resolves", "-")
            lines.append(f"| {label} | {entry['seconds']:.2f} | {entry['labelling_seconds']:.2f} "
                         f"| {entry['effective_traj_steps_per_s']:.3g} | {entry['attractors']} "
                         f"| {differ} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
