"""The block sizes `sweep.run` picks (`sweep._config`), measured: where one trajectory per
block (the narrow path) stops paying, and the adaptive method's lanes per block.

1. **Fixed-step RK4, few trajectories** (run_all.py's full scene: damped, forced,
   nonlinear): for n = 1 .. 128 trajectories, ``sweep.run`` with every trajectory in its
   own block of one lane (the narrow path, taken below ``NARROW_BELOW``) against blocks
   of 8, 16 and 64 lanes (padding filling the last one). The crossover is the smallest n
   at which a block beats the narrow path: ``NARROW_BELOW``; the fastest block below
   128 trajectories: ``TINY_BLOCK`` and ``TINY_BELOW``.
2. **dopri5** (rtol 1e-8, atol 1e-10, the same scene over 20 s): blocks of 8 .. 128
   lanes (``ADAPTIVE_BLOCK``) on a grid of 8192 starts, and one lane per block against
   blocks of 64 for n = 1 .. 64 (over 20 s x 256 / n, at least 20 s):
   ``ADAPTIVE_NARROW_BELOW``.

Every configuration is timed as ``sweep.run`` (best of ``--repeats``; its kernel compiled
beforehand), the configurations of one n in alternation; rates are useful
trajectory-steps per second (padding lanes not counted). Writes
``benchmarks/results/blocks.{json,md}``.

Usage::

    python benchmarks/blocks.py            # ~3 min on 2 cores
    python benchmarks/blocks.py --quick    # a smoke test
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import sweep  # noqa: E402
from sweep import _config  # noqa: E402

from _c_builds import AMPLITUDE, DAMPING, DT, FREQUENCY, G_OVER_L, PHASE  # noqa: E402
from _machine import stamp, write_results  # noqa: E402
from _timing import best_of  # noqa: E402

SCENE = sweep.Scene(gravity=G_OVER_L, length=1.0, model="nonlinear",
                    effects=(sweep.Damping(DAMPING), sweep.Forcing(AMPLITUDE, FREQUENCY, PHASE)))
FIXED_BLOCKS = (1, 8, 16, 64)
ADAPTIVE_BLOCKS = (8, 16, 32, 64, 128)


def grid_of(n: int) -> sweep.Grid:
    """n starts on the chaotic scene's phase plane (a line through it)."""
    return sweep.Grid(theta0=np.linspace(-3.0, 3.0, n), omega0=0.3)


def configured(block: int, adaptive: bool):
    """The `_config` settings that make `sweep.run` use ``block`` lanes per block."""
    if block == 1:
        return {"NARROW_BELOW": 10**12, "ADAPTIVE_NARROW_BELOW": 10**12}
    if adaptive:
        return {"ADAPTIVE_NARROW_BELOW": 0, "ADAPTIVE_BLOCK": block}
    return {"NARROW_BELOW": 0, "TINY_BELOW": 0, "SMALL_BLOCK": block, "BLOCK": block}


def timed_run(grid, block, adaptive, t_end, repeats):
    """Best seconds of `sweep.run` with ``block`` lanes per block (compiled first)."""
    saved = {name: getattr(_config, name) for name in (
        "NARROW_BELOW", "TINY_BELOW", "SMALL_BLOCK", "BLOCK", "ADAPTIVE_NARROW_BELOW",
        "ADAPTIVE_BLOCK")}
    options = dict(t_end=t_end, dt=DT, observe=("final",), progress=False)
    if adaptive:
        options.update(method="dopri5", rtol=1e-8, atol=1e-10, dt=0.1)
    try:
        for name, value in configured(block, adaptive).items():
            setattr(_config, name, value)
        spec = sweep.engine.prepare(SCENE, grid, **{k: v for k, v in options.items()
                                                     if k != "progress"})[1]
        assert spec.block == block, (spec.block, block)
        sweep.run(SCENE, grid, **{**options, "t_end": options["dt"] * 4})  # compile
        best = best_of(lambda: sweep.run(SCENE, grid, **options), repeats)
    finally:
        for name, value in saved.items():
            setattr(_config, name, value)
    return best


def fixed_crossover(sizes, work, repeats, blocks=FIXED_BLOCKS):
    """Per n: M useful trajectory-steps/s for each block size."""
    rows = {}
    for n in sizes:
        steps = max(2000, int(work / n))
        grid = grid_of(n)
        rows[n] = {b: n * steps / timed_run(grid, b, False, steps * DT, repeats) / 1e6
                   for b in blocks}
        print(f"RK4 n = {n}: " + ", ".join(f"block {b}: {r:.1f}" for b, r in rows[n].items()),
              flush=True)
    return rows


def adaptive_blocks(n_large, sizes, t_end, repeats, blocks=ADAPTIVE_BLOCKS):
    """dopri5: seconds per block size on a large grid, and narrow vs 64 for small n."""
    large = {b: timed_run(grid_of(n_large), b, True, t_end, repeats) for b in blocks}
    print("dopri5, " + str(n_large) + " starts: " +
          ", ".join(f"block {b}: {s:.3f} s" for b, s in large.items()), flush=True)
    small = {}
    for n in sizes:
        longer = t_end * max(1, 256 // n)  # enough work that the call's overhead is small
        small[n] = {b: timed_run(grid_of(n), b, True, longer, repeats) for b in (1, 64)}
        print(f"dopri5 n = {n}: narrow {small[n][1]:.4f} s, block 64 {small[n][64]:.4f} s",
              flush=True)
    return large, small


def markdown(r) -> str:
    fixed_blocks, adaptive = r["fixed_blocks"], r["adaptive_blocks"]
    lines = [f"# Block sizes ({r['date']})", "",
             f"Machine: {r['machine']} (LLVM: {r['details']['llvm_cpu']}); `sweep.run`, best of "
             f"{r['repeats']}, configurations of one size in alternation.", "",
             "## Fixed-step RK4, full scene: M useful trajectory-steps/s", "",
             "| trajectories | " + " | ".join("narrow (1 lane)" if b == 1 else f"block {b}"
                                              for b in fixed_blocks) + " | fastest |",
             "|---" * (len(fixed_blocks) + 2) + "|"]
    for n, row in r["fixed"].items():
        best = max(row, key=row.get)
        lines.append(f"| {n} | " + " | ".join(f"{row[b]:.1f}" for b in fixed_blocks) +
                     f" | {'narrow' if best == 1 else best} |")
    lines += ["", f"Smallest n where a block beats the narrow path: **{r['crossover']}** "
              f"(`NARROW_BELOW` is {r['narrow_below']}; `TINY_BLOCK` {r['tiny_block']} below "
              f"{r['tiny_below']} trajectories).", "",
              f"## dopri5 (rtol 1e-8), {r['n_large']} starts: seconds per run", "",
              "| " + " | ".join(f"block {b}" for b in adaptive) + " |",
              "|---" * len(adaptive) + "|",
              "| " + " | ".join(f"{r['adaptive_large'][b]:.3f}" for b in adaptive) + " |",
              "", f"`ADAPTIVE_BLOCK` is {r['adaptive_block']}, the narrow path below "
              f"{r['adaptive_narrow_below']} trajectories.", "",
              "| trajectories | t_end (s) | narrow (s) | block 64 (s) |", "|---|---|---|---|"]
    for n, row in r["adaptive_small"].items():
        lines.append(f"| {n} | {r['t_end'] * max(1, 256 // int(n)):g} | {row[1]:.4f} | "
                     f"{row[64]:.4f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (a smoke test)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    if args.quick:  # few kernels: each block is a kernel compiled for seconds
        sizes, work, n_large, t_end, repeats = (1, 8), 2e4, 256, 2.0, 1
        fixed_blocks, adaptive = (1, 16), (64,)
    else:
        sizes, work, n_large, t_end, repeats = ((1, 2, 4, 6, 8, 12, 16, 24, 32, 48, 64, 128),
                                                2e7, 8192, 20.0, args.repeats)
        fixed_blocks, adaptive = FIXED_BLOCKS, ADAPTIVE_BLOCKS
    fixed = fixed_crossover(sizes, work, repeats, fixed_blocks)
    crossover = next((n for n, row in fixed.items() if max(row, key=row.get) != 1), None)
    large, small = adaptive_blocks(n_large, [n for n in sizes if n <= 64], t_end, repeats,
                                   adaptive)
    result = {**stamp(), "repeats": repeats, "fixed_blocks": fixed_blocks,
              "adaptive_blocks": adaptive,
              "fixed": fixed, "crossover": crossover,
              "narrow_below": _config.NARROW_BELOW, "tiny_block": _config.TINY_BLOCK,
              "tiny_below": _config.TINY_BELOW, "n_large": n_large,
              "adaptive_large": large, "adaptive_small": small,
              "adaptive_block": _config.ADAPTIVE_BLOCK,
              "adaptive_narrow_below": _config.ADAPTIVE_NARROW_BELOW, "t_end": t_end}
    write_results(args.out / ("blocks_quick" if args.quick else "blocks"), result,
                  markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
