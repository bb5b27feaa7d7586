"""Measure what stopping each trajectory once its fate is decided saves.

Two basin questions, each run three times side by side in one process (full run;
``stop_early=True`` with lanes that wait for their block's slowest trajectory; and
``stop_early=True`` with lane refill, the default), with identical answers checked:

- damped, unforced pendulum: the well each start ends in (observable ``capture``);
- the driven pendulum of the maps issue (c = 0.2, A = 1.66, W = 1, cos forcing, 300
  transient + 20 observed periods): its periodic attractor (observable ``strobe``).

Writes ``benchmarks/results/stop_early.json`` and ``.md``.

Usage::

    python benchmarks/stop_early.py [--size N]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import sweep
from sweep import maps

try:  # the machine description of the basin benchmark
    from _machine import machine
except ImportError:  # pragma: no cover - run from elsewhere
    def machine() -> str:
        return "unknown machine"


def _timed(scene, grid, refill=True, **kwargs):
    """One timed run (after compiling or loading its kernel); ``refill=False``: early
    stop with lanes that wait for their block's slowest trajectory."""
    before, sweep._config.REFILL = sweep._config.REFILL, refill
    try:
        sweep.engine.warm_up(scene, grid, **kwargs)  # compile or load first
        start = time.perf_counter()
        ds = sweep.run(scene, grid, **kwargs)
        return ds, time.perf_counter() - start
    finally:
        sweep._config.REFILL = before


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=201)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = parser.parse_args(argv)
    rows = []

    damped = sweep.Scene(effects=(sweep.Damping(0.25),))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, args.size),
                      omega0=np.linspace(-12.0, 12.0, args.size))
    kwargs = dict(t_end=60.0, dt=0.01, observe=("capture",), progress=False)
    full, t_full = _timed(damped, grid, **kwargs)
    waiting, t_wait = _timed(damped, grid, stop_early=True, refill=False, **kwargs)
    early, t_early = _timed(damped, grid, stop_early=True, **kwargs)
    assert early.drop_attrs().identical(full.drop_attrs())
    assert early.drop_attrs().identical(waiting.drop_attrs())
    rows.append(("damped basins (wells), c = 0.25, t_end = 60 s", t_full, t_wait, t_early))

    period = 2 * np.pi
    forced = sweep.Scene(gravity=1.0, length=1.0,
                         effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, args.size),
                      omega0=np.linspace(-4.0, 4.0, args.size))
    kwargs = dict(t_end=320 * period, dt=period / 100, t_transient=300 * period,
                  observe=("strobe",), progress=False)
    full, t_full = _timed(forced, grid, **kwargs)
    early_kwargs = dict(kwargs, t_transient=20 * period)  # stop decides when to end
    waiting, t_wait = _timed(forced, grid, stop_early=True, refill=False, **early_kwargs)
    early, t_early = _timed(forced, grid, stop_early=True, **early_kwargs)
    assert early.drop_attrs().identical(waiting.drop_attrs())  # refill: the same bits
    a, b = maps.basins(full), maps.basins(early)
    differ = int((a.values != b.values).sum())
    rows.append((f"forced basins (attractors), 320 periods; {differ} of {a.size} starts "
                 "labelled differently", t_full, t_wait, t_early))

    result = {"machine": machine(), "size": args.size,
              "runs": [{"case": c, "full_s": f, "lanes_wait_s": w, "stop_early_s": e,
                        "speedup": f / e, "refill_speedup": w / e}
                       for c, f, w, e in rows]}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "stop_early.json").write_text(json.dumps(result, indent=2))
    md = [f"# Stop early: what it saves ({args.size} x {args.size} grids)", "",
          f"Machine: {result['machine']}", "",
          "| question | full run | stop_early, lanes wait | stop_early (refill) "
          "| speed-up | refill's share |", "|---|---|---|---|---|---|"]
    md += [f"| {c} | {f:.2f} s | {w:.2f} s | {e:.2f} s | {f / e:.1f}x | {w / e:.2f}x |"
           for c, f, w, e in rows]
    (args.out / "stop_early.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
