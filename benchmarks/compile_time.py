"""What compiling a kernel costs: sweep's serial kernels on its own threads against the same
kernels compiled as numba parallel loops (``parallel=True``, a ``prange`` over the
blocks: how sweep compiled them until 0.3).

Every new scene, observable set, method, precision or block size is a kernel of its own,
compiled on its first run: a researcher's first map of a scene, the explorer's first view
of a new effect and a cold test suite (about 350 kernels) wait for it. The baseline is
built from sweep's own generated module (`sweep.kernels.source`), turned back into the
parallel loop (`as_prange`): the same arithmetic, block by block, so the results must be
the same bits, and this script checks them. Both designs carry the kernels' other code
settings (`sweep.kernels.vectors`: vector width, lane alignment, the stack realigned),
so the run times compare the threading alone.

For each workload, one process per design compiles the kernels of the workloads from
empty caches (sweep's and numba's; the vectorised sine and the other helpers compiled
beforehand with a kernel that is not counted), timing ``sweep.engine.warm_up`` (generate,
compile, write the disk cache), then times one run of each workload. The two designs'
processes alternate, ``--rounds`` times; the table gives each design's best round.
Writes ``benchmarks/results/compile_time.{json,md}``.

Usage::

    python benchmarks/compile_time.py            # ~1 min on 2 cores
    python benchmarks/compile_time.py --quick    # two workloads, one round: a smoke test
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _machine import stamp, write_results  # noqa: E402

DESIGNS = ("threads", "prange")

#: name -> (scene effects, grid size, sweep.run keywords): the kinds of kernel sweep builds
WORKLOADS = {
    "RK4, damped + forced, final state": ("forced", 256, dict(observe=("final",))),
    "RK4, damped, capture, stop_early": ("damped", 256, dict(observe=("capture",),
                                                              stop_early=True)),
    "RK4, one trajectory (one lane)": ("forced", 1, dict(observe=("final", "energy"))),
    "RK4, forced, strobe, stop_early (refill)": ("forced", 256, dict(observe=("strobe",),
                                                                     stop_early=True)),
    "dopri5, damped + forced": ("forced", 128, dict(method="dopri5", rtol=1e-8,
                                                    atol=1e-10)),
    "RK4 float32, damped + forced": ("forced", 256, dict(observe=("final",),
                                                         dtype="float32")),
}
QUICK = ("RK4, damped + forced, final state", "RK4, one trajectory (one lane)")


def as_prange(text: str) -> str:
    """A generated CPU module with its serial ``blocks`` (or ``grouped``) function and
    thread driver turned into one numba parallel function over the blocks, as sweep
    generated it before `sweep.kernels.threads`."""
    text = text.replace("from numba import get_num_threads, njit\n",
                        "from numba import get_num_threads, njit, prange\n", 1)
    # fixed-step, adaptive: kernel -> run_blocks(blocks, n_blocks, ...) -> blocks(...,
    # BLOCK, b_first, b_stop) becomes kernel -> blocks(..., BLOCK), one parallel loop
    text, fixed = re.subn(r"run_blocks\(blocks, \(params\.shape\[0\] \+ BLOCK - 1\) // BLOCK,"
                          r"\s*([^)]*)\)", lambda m: "blocks(" + " ".join(m.group(1).split())
                          + ")", text)
    text = re.sub(r"@njit\(nogil=True, \*\*JIT\)\ndef blocks\(([^)]*), b_first, b_stop\):",
                  r"@njit(parallel=True, **JIT)\ndef blocks(\1):", text)
    text = text.replace("for b in range(b_first, b_stop):",
                        "for b in prange((n + BLOCK - 1) // BLOCK):")
    # refill: run_blocks(grouped, n_groups, ..., n_groups) -> grouped(..., n_groups)
    text, refill = re.subn(r"run_blocks\(grouped, n_groups, ([^)]*)\)", r"grouped(\1)", text)
    text = re.sub(r"@njit\(nogil=True, \*\*JIT\)\ndef grouped\(([^)]*), g_first, g_stop\):",
                  r"@njit(parallel=True, **JIT)\ndef grouped(\1):", text)
    text = text.replace("for b in range(g_first, g_stop):", "for b in prange(n_groups):")
    text = text.replace("first = b  # group b's first trajectory",
                        "first = np.int64(b)  # the prange index may be unsigned")
    if fixed + refill != 1 or "run_blocks(" in text or "prange(" not in text:
        raise RuntimeError("the generated module no longer has the form as_prange expects")
    return text


#: One process: compiles every workload's kernel in the design it is given, then runs each.
WORKER = textwrap.dedent("""
    import hashlib, json, sys, time
    import numpy as np
    sys.path.insert(0, {here!r})
    import sweep
    from sweep.kernels import cache
    import compile_time
    if {design!r} == "prange":
        generate = cache.source
        cache.source = lambda spec: compile_time.as_prange(generate(spec))
    scenes = {{"forced": sweep.Scene(gravity=1.0, length=1.0, effects=(
                   sweep.Damping(0.2), sweep.Forcing(1.2, 2 / 3))),
               "damped": sweep.Scene(gravity=9.81, length=1.0,
                                     effects=(sweep.Damping(0.25),))}}
    def grid(n):
        return sweep.Grid(theta0=np.linspace(-3.0, 3.0, n), omega0=np.linspace(-2.0, 2.0, n))
    # the helpers (vectorised sine, fma, ...) compile here, with a kernel not counted
    sweep.engine.warm_up(scenes["forced"], grid(2), t_end=1.0, dt=0.01,
                         observe=("theta_max",))
    rows = {{}}
    for name in {names!r}:
        scene, n, kw = compile_time.WORKLOADS[name]
        # 4 forcing periods, 300 steps each (the strobe samples once a period)
        period = 2 * np.pi / (2 / 3)
        kw = dict(kw, t_end=4 * period, dt=period / 300 if "rtol" not in kw else 0.1)
        start = time.perf_counter()
        sweep.engine.warm_up(scenes[scene], grid(n), **kw)
        compile_s = time.perf_counter() - start
        start = time.perf_counter()
        ds = sweep.run(scenes[scene], grid(n), progress=False, **kw)
        run_s = time.perf_counter() - start
        digest = hashlib.sha1(b"".join(ds[v].values.tobytes()
                                       for v in sorted(ds.data_vars))).hexdigest()
        rows[name] = {{"compile_s": compile_s, "run_s": run_s, "digest": digest}}
    print(json.dumps(rows))
""")


def worker(design: str, names) -> dict:
    """One process of ``design`` compiling ``names`` from empty caches."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, SWEEP_CACHE_DIR=cache, NUMBA_CACHE_DIR=os.path.join(cache, "nb"))
        code = WORKER.format(here=str(HERE), design=design, names=list(names))
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True)
    if done.returncode:
        raise RuntimeError(f"the {design} worker failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def markdown(r) -> str:
    lines = [f"# Compile time of a kernel ({r['date']})", "",
             f"Machine: {r['machine']}. Each design's kernels compiled from empty caches in "
             f"a fresh process (helpers compiled beforehand), the designs' processes in "
             f"alternation; best of {r['rounds']} rounds. *threads*: sweep's serial kernel "
             "on `sweep.kernels.threads`; *prange*: the same module compiled as a numba "
             "parallel loop (sweep until 0.3). Run: one `sweep.run` of the workload "
             "(4 forcing periods, 1200 steps; dopri5: rtol 1e-8) after compiling.", "",
             "| workload | compile, threads (s) | compile, prange (s) | prange / threads | "
             "run, threads (s) | run, prange (s) | same bits |",
             "|---|---|---|---|---|---|---|"]
    for name, row in r["rows"].items():
        lines.append(f"| {name} | {row['threads']['compile_s']:.2f} | "
                     f"{row['prange']['compile_s']:.2f} | "
                     f"{row['prange']['compile_s'] / row['threads']['compile_s']:.2f} | "
                     f"{row['threads']['run_s']:.3f} | {row['prange']['run_s']:.3f} | "
                     f"{'yes' if row['same_bits'] else 'NO'} |")
    total = {d: sum(row[d]["compile_s"] for row in r["rows"].values()) for d in DESIGNS}
    lines += ["", f"Total compile: {total['threads']:.1f} s with threads, "
              f"{total['prange']:.1f} s with prange ({total['prange'] / total['threads']:.2f}x)."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two workloads, one round")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    names = QUICK if args.quick else tuple(WORKLOADS)
    rounds = 1 if args.quick else args.rounds
    best = {name: {} for name in names}
    for _ in range(rounds):
        for design in DESIGNS:
            for name, row in worker(design, names).items():
                kept = best[name].get(design)
                if kept is None or row["compile_s"] < kept["compile_s"]:
                    best[name][design] = {**row, "run_s": min(row["run_s"], kept["run_s"])
                                          if kept else row["run_s"]}
    rows = {name: {**designs, "same_bits": designs["threads"]["digest"] ==
                   designs["prange"]["digest"]} for name, designs in best.items()}
    result = {**stamp(), "rounds": rounds, "rows": rows}
    write_results(args.out / ("compile_time_quick" if args.quick else "compile_time"), result,
                  markdown(result))
    return 0 if all(row["same_bits"] for row in rows.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
