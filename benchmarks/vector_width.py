"""The kernels' SIMD vector width (`sweep.kernels.vectors`): 256 against 512 bits.

run_all.py's full scene (damped, forced, nonlinear; 512 x 256 starts x 2000 RK4 steps,
final state) timed with ``SWEEP_VECTOR_WIDTH`` = 256, 512 and ``llvm`` (LLVM's own
tuning for the CPU), each width in its own process started once, the processes timed
in alternation (round robin, best of ``--rounds`` per process), so that the machine's
drift hits every width alike. Results are checked bit-identical across widths.

Where the host has AVX-512 the same is repeated with LLVM told the CPU is Intel's
Rocket Lake (``NUMBA_CPU_NAME=rocketlake``: the Xeon of issue 29, whose tuning prefers
256-bit vectors), so that the width this benchmark host would get on such a core can be
seen here. That is code tuned for another core run on this one: it shows the code
generation (how many ymm/zmm instructions), not Rocket Lake's speed.

Writes ``benchmarks/results/vector_width.json`` and ``.md``.

Usage::

    python benchmarks/vector_width.py            # ~2 min on 2 cores
    python benchmarks/vector_width.py --quick    # small grid, this CPU only: a smoke test
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import cpu_flags, stamp, write_results  # noqa: E402

WIDTHS = ("256", "512", "llvm")

#: One worker process: compiles its width's kernel, then times runs on request.
WORKER = textwrap.dedent("""
    import hashlib, json, re, sys, time
    import numpy as np
    sys.path.insert(0, {here!r})
    import sweep
    from sweep import kernels
    from _c_builds import AMPLITUDE, DAMPING, DT, FREQUENCY, G_OVER_L, PHASE, grid_axes
    theta0, omega0 = grid_axes({n})
    scene = sweep.Scene(gravity=G_OVER_L, length=1.0, model="nonlinear",
                        effects=(sweep.Damping(DAMPING),
                                 sweep.Forcing(AMPLITUDE, FREQUENCY, PHASE)))
    grid = sweep.Grid(theta0=theta0, omega0=omega0)
    kw = dict(t_end={steps} * DT, dt=DT, observe=("final",))
    spec = sweep.engine.warm_up(scene, grid, **kw)
    asm = "".join(kernels.compiled(kernels.build(spec)).inspect_asm().values())
    registers = {{r: len(re.findall(r"\\bv\\w+pd\\s+%" + r, asm)) for r in ("zmm", "ymm")}}
    print(json.dumps({{"ready": True, "registers": registers}}), flush=True)
    for line in sys.stdin:
        start = time.perf_counter()
        ds = sweep.run(scene, grid, progress=False, **kw)
        seconds = time.perf_counter() - start
        digest = hashlib.sha1(b"".join(ds[v].values.tobytes()
                                       for v in sorted(ds.data_vars))).hexdigest()
        print(json.dumps({{"seconds": seconds, "digest": digest,
                          "vector_width": ds.attrs["vector_width"]}}), flush=True)
""")


def start_worker(width: str, n: int, steps: int, cache: str, cpu_name: str | None):
    env = dict(os.environ, SWEEP_VECTOR_WIDTH=width, SWEEP_CACHE_DIR=cache,
               NUMBA_CACHE_DIR=os.path.join(cache, "numba"))
    if cpu_name:
        env["NUMBA_CPU_NAME"] = cpu_name
    code = WORKER.format(here=str(HERE), n=n, steps=steps)
    process = subprocess.Popen([sys.executable, "-c", code], env=env, text=True,
                               stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    ready = json.loads(process.stdout.readline())
    return process, ready["registers"]


def compare(n: int, steps: int, rounds: int, cpu_name: str | None) -> dict:
    """Time the widths in alternation; returns per width: best rate, registers, digest."""
    rows = {}
    with tempfile.TemporaryDirectory() as cache:  # fresh: the code is compiled here
        workers = {w: start_worker(w, n, steps, cache, cpu_name) for w in WIDTHS}
        timings = {w: [] for w in WIDTHS}
        for _ in range(rounds):
            for width, (process, _) in workers.items():
                process.stdin.write("go\n")
                process.stdin.flush()
                timings[width].append(json.loads(process.stdout.readline()))
        for width, (process, registers) in workers.items():
            process.stdin.close()
            process.wait()
            best = min(t["seconds"] for t in timings[width])
            rows[width] = {
                "rate": n * steps / best / 1e6, "seconds": [t["seconds"] for t in
                                                          timings[width]],
                "registers": registers, "digest": {t["digest"] for t in timings[width]}.pop(),
                "vector_width": timings[width][0]["vector_width"]}
    digests = {row["digest"] for row in rows.values()}
    return {"rows": rows, "bit_identical": len(digests) == 1}


def markdown(result: dict) -> str:
    lines = [f"# Kernel vector width ({result['date']})", "",
             f"Machine: {result['machine']} (LLVM calls it {result['details']['llvm_cpu']}, family "
             f"{result['details'].get('CPU family')} model {result['details'].get('Model')}); "
             f"{result['trajectories']} trajectories x "
             f"{result['steps']} RK4 steps of the full scene (final state), best of "
             f"{result['rounds']} runs per width, widths timed in alternation, each in "
             "its own process.", ""]
    for label, block in result["runs"].items():
        lines += [f"## {label}", "",
                  "| SWEEP_VECTOR_WIDTH | dataset's vector_width | M trajectory-steps/s "
                  "| ratio to 256 | packed zmm / ymm instructions |",
                  "|---|---|---|---|---|"]
        base = block["rows"]["256"]["rate"]
        for width, row in block["rows"].items():
            lines.append(f"| {width} | {row['vector_width']} | {row['rate']:.0f} | "
                         f"{row['rate'] / base:.2f} | {row['registers']['zmm']} / "
                         f"{row['registers']['ymm']} |")
        lines += ["", f"Bit-identical across widths: {block['bit_identical']}.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small grid (smoke test)")
    parser.add_argument("--rounds", type=int, default=5, help="timed runs per width")
    parser.add_argument("--out", type=Path, default=HERE / "results",
                        help="folder of the results (default benchmarks/results)")
    args = parser.parse_args(argv)
    n, steps, rounds = (4096, 200, 2) if args.quick else (512 * 256, 2000, args.rounds)
    runs = {"this CPU, LLVM's tuning for it": compare(n, steps, rounds, None)}
    if "avx512f" in cpu_flags() and not args.quick:  # (tests/test_vector_width.py
        # checks the emulated tuning's machine code)
        runs["LLVM told the CPU is Intel Rocket Lake (NUMBA_CPU_NAME=rocketlake), run "
             "here"] = compare(n, steps, rounds, "rocketlake")
    result = {**stamp(), "trajectories": n, "steps": steps, "rounds": rounds, "runs": runs}
    write_results(args.out / ("vector_width_quick" if args.quick else "vector_width"), result,
                  markdown(result))
    return 0 if all(block["bit_identical"] for block in runs.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
