"""Throughput of `sweep.run` on a Dask cluster beside the plain local run, in one run.

Workload (the performance issue's): damped, forced, nonlinear pendulum, g/L = 1,
c = 0.5, A = 1.2, W = 2/3, a 512 x 256 grid of (theta0 in [-pi, pi], omega0 in
[-2, 2]) x 2000 RK4 steps of dt = 0.01, final state only. Throughput is
trajectory-steps per second (trajectories x steps / wall seconds), both warm (kernel
compiled or loaded from numba's disk cache beforehand, on the client and on every
worker). The distributed results are checked bit-identical to the local ones.

By default the cluster is a `distributed.LocalCluster` on this machine (``--workers``
processes x 1 Dask thread, each worker's numba kernel using ``cores / workers``
threads), so the comparison shows the overhead of going through Dask. To measure a real
cluster instead, start one and give its scheduler; the science code (`sweep.run(...,
client=client)`) does not change:

    python benchmarks/cluster.py --scheduler tcp://HOST:8786
    python benchmarks/cluster.py --scheduler-file ~/scheduler.json   # dask-mpi, jobqueue

Writes ``benchmarks/results/cluster.json`` and ``.md``.

Usage::

    python benchmarks/cluster.py [--size 512] [--steps 2000] [--workers 2]
                                     [--chunk-sizes 65536,16384,4096]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

import sweep

try:  # the machine description of the basin benchmark
    from _machine import machine
except ImportError:  # pragma: no cover - run from elsewhere
    def machine() -> str:
        return f"{os.cpu_count()} cores"


def _workload(size: int, steps: int):
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3, 0.0)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-2.0, 2.0, max(size // 2, 1)))
    kwargs = dict(t_end=steps * 0.01, dt=0.01, observe=("final",), progress=False)
    return scene, grid, kwargs


def _timed(scene, grid, repeats=1, **kwargs):
    """The dataset and the best wall time of ``repeats`` runs."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        ds = sweep.run(scene, grid, **kwargs)
        best = min(best, time.perf_counter() - start)
    return ds, best


def _same(a, b) -> bool:
    a, b = a.copy(), b.copy()
    a.attrs.pop("history", None)
    b.attrs.pop("history", None)
    return a.identical(b)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="theta0 points (omega0: half)")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster processes")
    parser.add_argument("--chunk-sizes", default="65536,16384,4096",
                        help="comma-separated trajectories per task")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--scheduler-file", help="scheduler file of a running cluster")
    parser.add_argument("--repeats", type=int, default=1, help="best of N runs each")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    from distributed import Client, LocalCluster

    scene, grid, kwargs = _workload(args.size, args.steps)
    work = grid.size * args.steps
    chunk_sizes = [int(c) for c in args.chunk_sizes.split(",")]

    load_before = os.getloadavg()[0]
    sweep.engine.warm_up(scene, grid, **kwargs)  # compile or load, locally
    local, t_local = _timed(scene, grid, args.repeats, **kwargs)

    began = time.perf_counter()
    cluster = None
    if args.scheduler or args.scheduler_file:
        client = Client(args.scheduler, scheduler_file=args.scheduler_file)
        where = f"existing cluster {client.scheduler.address}"
    else:
        numba_threads = max(1, (os.cpu_count() or 1) // args.workers)
        # the Scheduler's HTTP server on a free port: 8787, its default even without a
        # dashboard, may be another cluster's (two at once raced for it)
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=":0",
                               env={"NUMBA_NUM_THREADS": str(numba_threads)})
        client = Client(cluster)
        client.wait_for_workers(args.workers, timeout=120)
        where = (f"LocalCluster, {args.workers} worker processes x 1 Dask thread, "
                 f"{numba_threads} numba thread(s) each")
    startup = time.perf_counter() - began
    workers = client.scheduler_info()["workers"]
    try:
        # warm every worker: one small task per worker loads the kernel
        warm = sweep.Grid(theta0=np.linspace(0.0, 0.1, len(workers)))  # distinct values
        sweep.run(scene, warm, client=client, chunk_size=1, **kwargs)
        rows = []
        for chunk in chunk_sizes:
            remote, t_remote = _timed(scene, grid, args.repeats, client=client,
                                      chunk_size=chunk, **kwargs)
            rows.append({"chunk_size": chunk, "tasks": -(-grid.size // chunk),
                         "seconds": t_remote, "steps_per_s": work / t_remote,
                         "identical": _same(local, remote)})
            assert rows[-1]["identical"], "distributed result differs from the local run"
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    load_after = os.getloadavg()[0]
    result = {"machine": machine(), "cluster": where, "cluster_startup_s": startup,
              "load_average_before": load_before, "load_average_after": load_after,
              "repeats": args.repeats,
              "trajectories": grid.size, "steps": args.steps,
              "local": {"seconds": t_local, "steps_per_s": work / t_local},
              "distributed": rows}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "cluster.json").write_text(json.dumps(result, indent=2))
    md = [f"# sweep on Dask vs the plain local run ({grid.shape[0]} x {grid.shape[1]} "
          f"trajectories x {args.steps} RK4 steps, damped + forced, final state)", "",
          f"Machine: {result['machine']}", "",
          f"Cluster: {where} (started in {startup:.1f} s, not counted below)", "",
          f"1-minute load average {load_before:.1f} before, {load_after:.1f} after "
          f"({os.cpu_count()} cores; above ~0.5 other processes shared the CPU and the "
          f"rates are lower bounds); best of {args.repeats} run(s) each.", "",
          "| run | tasks | wall time | trajectory-steps/s | vs local | identical |",
          "|---|---|---|---|---|---|",
          f"| local `sweep.run` | - | {t_local:.2f} s | {work / t_local / 1e6:.1f} M | 1.00x "
          "| - |"]
    md += [f"| Dask, chunk_size = {r['chunk_size']} | {r['tasks']} | {r['seconds']:.2f} s | "
           f"{r['steps_per_s'] / 1e6:.1f} M | {t_local / r['seconds']:.2f}x | "
           f"{'yes' if r['identical'] else 'NO'} |" for r in rows]
    (args.out / "cluster.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
