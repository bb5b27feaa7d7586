"""Systems with more than one angle on this machine (issue 35's speed section).

1. **sweep against the C limit on the double pendulum.** The undamped double pendulum
   with equal masses and lengths (m = 1 kg, l = 1 m, g = 9.81 m/s^2), started at rest
   from a 512 x 256 grid of (theta1_0, theta2_0) in [-3, 3]^2 rad (2**17 trajectories),
   1000 RK4 steps of dt = 0.01 s, float64, final state only. The C limit is the fastest
   build of ``c_reference/double_pendulum.c`` (the same RK4 on the same accelerations,
   blocks of SIMD lanes, OpenMP over blocks, the polynomial sines of
   ``c_reference/sines.h`` with one reduction for the sine and cosine of
   theta1 - theta2, explicit FMAs, every product of parameters alone hoisted out of
   the loops) that this run finds: sweep's sine design over the block sizes 64 .. 4096
   (512-bit vectors where /proc/cpuinfo has ``avx512f``), then, at the best block, one
   option changed at a time (no FMA contraction, 256-bit vectors, glibc's vector sin),
   then the one-reduction-by-pi sines of run_all.py's search, the fastest of them again
   over the block sizes; the fastest few eligible builds are timed again in turns, and
   the fastest of them is the limit. Every build is checked against sweep's final state after
   ``CHECK_STEPS`` steps (``CHECK_TOL``) and its sine and cosine against NumPy's on the
   sine contract's arguments (``_c_builds.SINE_CONTRACT``: 2**-52 absolute up to
   |x| = 1e12); only a build passing both may be the limit. The limit and ``sweep.run``
   are then timed in alternation (best of ``--rounds``), and their ratio reported.
   NumPy's vectorised RK4 of the same accelerations is a second baseline (fewer steps,
   extrapolated: its time is linear in the steps).
2. **A 1000 x 1000 flip-time map end to end**: theta1_0, theta2_0 in [-3, 3] from rest,
   ``observe=("flip",)``, ``stop_early=True``, up to t = 100 sqrt(l/g) with
   dt = sqrt(l/g)/100 (``examples/double_pendulum_flip.py``); the kernel is compiled
   (or loaded from the disk cache) first by a one-step run of the same grid, not timed.
   The same work without ``stop_early`` runs on a band of ``--flip-rows`` evenly spaced
   theta1_0 rows (all theta2_0 columns) and is extrapolated to the whole map (without
   stop_early every start costs the same steps); the band with ``stop_early`` must give
   the same flip times to the bit.
3. **A swing network's cost per step against its edges**: 100 nodes (half generators
   P = +1, half consumers P = -1, at random), a random spanning tree plus random extra
   lines, 100, 200 and 400 edges; single-node perturbations (16 nodes x 11 x 11 =
   1936) x 1000 steps of dt = 0.01 s each, the three networks timed in turns (best of
   3); ns per edge-step and a straight-line fit of the time per trajectory-step against
   the edges.

Writes ``benchmarks/results/double_pendulum.json`` and ``.md`` (``--quick``: small sizes,
``double_pendulum_quick.*``, a smoke test).

Usage::

    python benchmarks/double_pendulum.py            # ~6 min on 2 cores
    python benchmarks/double_pendulum.py --quick    # seconds
"""

from __future__ import annotations

import argparse
import ctypes
import functools
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import sweep  # noqa: E402

from _c_builds import (  # noqa: E402
    C_BASE_FLAGS,
    C_BLOCKS,
    NARROW,
    SINE_CONTRACT,
    SINE_RANGES,
    WIDE,
    c_limit_sine_designs,
    compile_library,
    contract_accuracy,
    contract_arguments,
    grid_axes,
    sine_points,
)
from _machine import machine_lines, stamp, write_results  # noqa: E402
from _timing import best_alternating, best_of, seconds  # noqa: E402

C_DOUBLE = HERE / "c_reference" / "double_pendulum.c"
MASS, LENGTH, GRAVITY = 1.0, 1.0, 9.81  # kg, m, m/s^2: both masses and both rods
DT = 0.01  # s (sqrt(l/g) = 0.32 s: 32 steps per natural time unit)
CHECK_STEPS = 100  # the agreement check's horizon (t = 1 s)
#: max |C - sweep| of the final angles and velocities allowed after CHECK_STEPS. The
#: builds round differently from sweep's kernel (gcc fuses other products under
#: -ffp-contract=fast, the parameters' products are grouped otherwise, libm's sines
#: differ in the last bit): ~1e-16 relative per operation, which 100 steps of this
#: chaotic motion (angular velocities up to ~10 rad/s) grow to ~1e-13 (measured: at
#: most 1.8e-13 over every build; sweep against itself from starts moved by one ulp,
#: ``rounding_scale``, 4.7e-13). 1e-11 leaves that room 20-fold, while a different
#: algorithm (a term missing, a sine of 1e-12 accuracy, another step) moves the state
#: after 100 steps by far more.
CHECK_TOL = 1e-11
FINALISTS, FINAL_ROUNDS = 4, 3  # the fastest eligible builds, timed again in turns


def system() -> sweep.DoublePendulum:
    return sweep.DoublePendulum(mass1=MASS, mass2=MASS, length1=LENGTH, length2=LENGTH,
                                gravity=GRAVITY)


def start_axes(n: int) -> tuple[np.ndarray, np.ndarray]:
    """theta1_0, theta2_0 axes in [-3, 3] rad with about n starts (2 x 1, as 512 x 256)."""
    rows, cols = (a.size for a in grid_axes(n))
    return np.linspace(-3.0, 3.0, rows), np.linspace(-3.0, 3.0, cols)


def starts(theta1, theta2) -> list[np.ndarray]:
    """The grid's starts, flattened in sweep's order: theta1, theta2, omega1, omega2."""
    a, b = np.meshgrid(theta1, theta2, indexing="ij")
    return [a.ravel().copy(), b.ravel().copy(), np.zeros(a.size), np.zeros(a.size)]


def run_sweep(theta1, theta2, steps: int, **options):
    """`sweep.run` on the grid for ``steps`` steps of DT: its Dataset."""
    return sweep.run(system(), sweep.Grid(theta1_0=theta1, theta2_0=theta2),
                     t_end=steps * DT, dt=DT, observe=("final",), progress=False, **options)


def final_state(ds) -> list[np.ndarray]:
    return [ds[f"{name}_final"].values.ravel() for name in ("theta1", "theta2", "omega1",
                                                            "omega2")]


def max_diff(got, ref) -> float:
    return max(float(np.max(np.abs(a - b))) for a, b in zip(got, ref))


# ------------------------------------------------------------------------ NumPy RK4
def numpy_accel(th1, th2, om1, om2):
    """The accelerations of sweep's derivation (the form of double_pendulum.c), NumPy."""
    m1 = m2 = MASS
    l1 = l2 = LENGTH
    d = th1 - th2
    s, c = np.sin(d), np.cos(d)
    x1 = l1 * l2 * m2 * s * om1 * om1 - l2 * m2 * GRAVITY * np.sin(th2)
    x5 = -l1 * l2 * m2 * s * om2 * om2 - (m1 + m2) * GRAVITY * l1 * np.sin(th1)
    x7 = 1.0 / (l1 * l1 * l2 * l2 * m2 * (m1 + m2 - m2 * c * c))
    return x7 * (l2 * l2 * m2 * x5 - l1 * l2 * m2 * c * x1), \
        x7 * ((m1 + m2) * l1 * l1 * x1 - l1 * l2 * m2 * c * x5)


def numpy_rk4(state, steps: int) -> list[np.ndarray]:
    """Classical RK4 vectorised across trajectories (NumPy arrays of every start)."""
    th1, th2, om1, om2 = (x.copy() for x in state)
    for _ in range(steps):
        a1, b1 = numpy_accel(th1, th2, om1, om2)
        a2, b2 = numpy_accel(th1 + DT / 2 * om1, th2 + DT / 2 * om2, om1 + DT / 2 * a1,
                             om2 + DT / 2 * b1)
        p1, p2 = om1 + DT / 2 * a1, om2 + DT / 2 * b1
        a3, b3 = numpy_accel(th1 + DT / 2 * p1, th2 + DT / 2 * p2, om1 + DT / 2 * a2,
                             om2 + DT / 2 * b2)
        q1, q2 = om1 + DT / 2 * a2, om2 + DT / 2 * b2
        a4, b4 = numpy_accel(th1 + DT * q1, th2 + DT * q2, om1 + DT * a3, om2 + DT * b3)
        r1, r2 = om1 + DT * a3, om2 + DT * b3
        th1 = th1 + DT / 6 * (om1 + 2 * p1 + 2 * q1 + r1)
        th2 = th2 + DT / 6 * (om2 + 2 * p2 + 2 * q2 + r2)
        om1 = om1 + DT / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        om2 = om2 + DT / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
    return [th1, th2, om1, om2]


# ------------------------------------------------------------------------- C builds
def build_double(build_dir: Path, flags: list[str]):
    """double_pendulum.c built with ``flags``: its ``dp_rk4`` (with ``.sine`` and
    ``.sincos`` for the contract), an error string, or None without gcc."""
    loaded = compile_library(build_dir, C_DOUBLE, flags)
    if loaded is None or isinstance(loaded, str):
        return loaded
    p = ctypes.POINTER(ctypes.c_double)
    fn = loaded.dp_rk4
    fn.restype = None
    fn.argtypes = [ctypes.c_int64, p, p, p, p, *[ctypes.c_double] * 6, ctypes.c_int64,
                   p, p, p, p]
    fn.sine, fn.sincos = loaded.sines_sin, loaded.dp_sincos
    fn.sine.restype = fn.sincos.restype = None
    fn.sine.argtypes = [ctypes.c_int64, p, p]
    fn.sincos.argtypes = [ctypes.c_int64, p, p, p]
    return fn


def call_double(fn, state, steps: int) -> list[np.ndarray]:
    """The C build on the starts ``state`` (theta1, theta2, omega1, omega2)."""
    p = ctypes.POINTER(ctypes.c_double)
    n = state[0].size
    out = [np.empty(n) for _ in range(4)]
    fn(n, *(x.ctypes.data_as(p) for x in state), MASS, MASS, LENGTH, LENGTH, GRAVITY, DT,
       steps, *(x.ctypes.data_as(p) for x in out))
    return out


@functools.cache
def cosine_points() -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """(x, np.cos(x)) on the sine contract's arguments."""
    return tuple((x, np.cos(x)) for x in contract_arguments())


def trig_accuracy(fn) -> dict:
    """A build's sine, and the sine and cosine of its one-reduction pair, against
    NumPy's on the contract's arguments; eligible if all three meet it."""
    p = ctypes.POINTER(ctypes.c_double)

    def sine(x):
        got = np.empty_like(x)
        fn.sine(x.size, x.ctypes.data_as(p), got.ctypes.data_as(p))
        return got

    def pair(x, which):
        s, c = np.empty_like(x), np.empty_like(x)
        fn.sincos(x.size, x.ctypes.data_as(p), s.ctypes.data_as(p), c.ctypes.data_as(p))
        return (s, c)[which]

    parts = {"sin": contract_accuracy(sine, sine_points()),
             "sincos: sin": contract_accuracy(lambda x: pair(x, 0), sine_points()),
             "sincos: cos": contract_accuracy(lambda x: pair(x, 1), cosine_points())}
    return {"parts": parts, "eligible": all(v["eligible"] for v in parts.values())}


def candidates(avx512: bool, blocks) -> dict[str, list[str]]:
    """First phase: sweep's sine design (pendulum.c's SIN_VARIANT 4, one reduction for
    sin and cos of theta1 - theta2), FMA contraction, widest vectors, per block."""
    width = [WIDE] if avx512 else []
    label = "512-bit" if avx512 else "-march=native"
    return {f"{label}, sweep's sine (reduction by pi/2), FMA, block {b}":
            [*width, "-DSIN_VARIANT=4", "-ffp-contract=fast", f"-DBLOCK={b}"]
            for b in blocks}


def variations(best: list[str], avx512: bool) -> dict[str, list[str]]:
    """Second phase, at the best block: one option changed at a time, and libm."""
    block = next(f for f in best if f.startswith("-DBLOCK="))
    width = [WIDE] if avx512 else []
    label = "512-bit" if avx512 else "-march=native"
    n = block[8:]
    out = {f"{label}, sweep's sine, FMA only where written (fma()), block {n}":
           [*width, "-DSIN_VARIANT=4", "-ffp-contract=off", block],
           f"{label}, glibc vector sin and cos (libmvec), FMA, block {n}":
           [*width, "-DSIN_VARIANT=1", "-ffp-contract=fast", block],
           f"{label}, libm sin and cos (scalar calls), FMA, block {n}":
           [*width, "-DSIN_VARIANT=0", "-ffp-contract=fast", block]}
    if avx512:
        out[f"256-bit, sweep's sine, FMA, block {n}"] = [
            NARROW, "-DSIN_VARIANT=4", "-ffp-contract=fast", block]
    return out


def search_c_limit(state, reference, n_steps: int, blocks, avx512: bool, build_dir: Path,
                   log) -> tuple[list[dict], dict | None]:
    """Every build of the search, checked and timed once; the fastest eligible."""
    rows, check_state = [], [x for x in state]

    def search(builds):
        for name, flags in builds.items():
            fn = build_double(build_dir, flags)
            if isinstance(fn, str):
                rows.append({"name": name, "flags": flags, "error": fn})
                log(f"  {name}: {fn}")
                continue
            diff = max_diff(call_double(fn, check_state, CHECK_STEPS), reference)
            accuracy = trig_accuracy(fn)
            call_double(fn, [x[:8] for x in state], 2)  # load, start the threads
            took = seconds(lambda f=fn: call_double(f, state, n_steps))
            row = {"name": name, "flags": [*C_BASE_FLAGS, *flags],
                   "block": int(next(f for f in flags if f.startswith("-DBLOCK="))[8:]),
                   "traj_steps_per_s": state[0].size * n_steps / took,
                   "check_max_abs_diff": diff, "check_ok": bool(diff <= CHECK_TOL),
                   "trig": {k: v["max_abs_error"] for k, v in accuracy["parts"].items()},
                   "trig_eligible": accuracy["eligible"], "fn": fn}
            rows.append(row)
            log(f"  {name:62s} {row['traj_steps_per_s'] / 1e6:8.1f} M/s  check "
                f"{diff:.1e}{'' if row['check_ok'] else ' FAILS'}; sin/cos "
                f"{'meet' if accuracy['eligible'] else 'MISS'} the contract")
            yield row

    def eligible(found):
        return [r for r in found if r["check_ok"] and r["trig_eligible"]]

    found = eligible(search(candidates(avx512, blocks)))
    if not found:
        return rows, None
    best = max(found, key=lambda r: r["traj_steps_per_s"])
    found += eligible(search(variations(best["flags"], avx512)))
    designs = {k.removeprefix("C limit search: ").replace(", FMA", ", sincos by "
                                                            "pi/2, FMA"): v
               for k, v in c_limit_sine_designs(best["flags"], avx512,
                                                forcing_table=False).items()}
    designs = eligible(search(designs))
    if designs:
        top = max(designs, key=lambda r: r["traj_steps_per_s"])
        others = [str(b) for b in blocks if b != top["block"]]
        same = [f for f in top["flags"] if not f.startswith("-DBLOCK=")
                and f not in C_BASE_FLAGS]
        more = {k.removeprefix("C limit search: ").replace(", FMA", ", sincos by "
                                                           "pi/2, FMA"): v
                for k, v in c_limit_sine_designs(top["flags"], avx512, others,
                                                 forcing_table=False).items()
                if [f for f in v if not f.startswith("-DBLOCK=")] == same}
        designs += eligible(search(more))
    found += designs
    # one timing per build is at the mercy of the machine's other work: the fastest
    # few are timed again in turns, and the best of those is the limit
    finalists = sorted(found, key=lambda r: -r["traj_steps_per_s"])[:FINALISTS]
    best = best_alternating({id(r): lambda f=r["fn"]: call_double(f, state, n_steps)
                             for r in finalists}, FINAL_ROUNDS)
    for r in finalists:
        r["final_traj_steps_per_s"] = state[0].size * n_steps / best[id(r)]
        log(f"  finalist: {r['name']:52s} {r['final_traj_steps_per_s'] / 1e6:8.1f} M/s")
    return rows, max(finalists, key=lambda r: r["final_traj_steps_per_s"])


# ------------------------------------------------------------------ flip-time map
def flip_map(size: int, band_rows: int, t_max: float, log) -> dict:
    """The flip-time map end to end with stop_early, and without it on a band."""
    unit = math.sqrt(LENGTH / GRAVITY)
    dt, n_steps = unit / 100, round(t_max * 100)
    angles = np.linspace(-3.0, 3.0, size)
    band = angles[np.linspace(0, size - 1, band_rows).round().astype(int)]
    kw = dict(t_end=n_steps * dt, dt=dt, observe=("flip",), progress=False)

    def run(theta1, stop_early):
        grid = sweep.Grid(theta1_0=theta1, theta2_0=angles)
        return sweep.run(system(), grid, **dict(kw, stop_early=stop_early))

    def warm(theta1, stop_early):  # the same grid's kernel: one step, not timed
        grid = sweep.Grid(theta1_0=theta1, theta2_0=angles)
        return seconds(lambda: sweep.run(system(), grid, **dict(kw, t_end=dt,
                                                                 stop_early=stop_early)))

    out = {"size": size, "steps": n_steps, "dt": dt, "t_max_natural_units": t_max,
           "band_rows": band_rows, "load_1min_before": os.getloadavg()[0]}
    out["warm_up_seconds"] = warm(angles, True)
    start = time.perf_counter()
    ds = run(angles, True)
    out["stop_early_seconds"] = time.perf_counter() - start
    flips = ds.flip_time.values
    out["never_flip_fraction"] = float(np.isnan(flips).mean())
    log(f"  {size} x {size}, stop_early: {out['stop_early_seconds']:.1f} s end to end "
        f"({out['never_flip_fraction']:.1%} never flip)")
    warm(band, False)
    warm(band, True)
    out["band_full_seconds"] = best_of(lambda: run(band, False), 1)
    full = run(band, False).flip_time.values
    out["band_stop_early_seconds"] = best_of(lambda: run(band, True), 1)
    early = run(band, True).flip_time.values
    out["band_same_bits"] = bool(np.array_equal(full, early, equal_nan=True))
    scale = size / band_rows
    out["full_seconds_extrapolated"] = out["band_full_seconds"] * scale
    out["speedup"] = out["full_seconds_extrapolated"] / out["stop_early_seconds"]
    out["band_speedup"] = out["band_full_seconds"] / out["band_stop_early_seconds"]
    out["full_traj_steps_per_s"] = band_rows * size * n_steps / out["band_full_seconds"]
    log(f"  without stop_early ({band_rows} rows, x{scale:g}): "
        f"{out['full_seconds_extrapolated']:.1f} s; speed-up {out['speedup']:.1f}x; "
        f"same bits on the band: {out['band_same_bits']}")
    return out


# -------------------------------------------------------------------- swing network
def random_network(n_nodes: int, n_edges: int, seed: int):
    """A connected random graph: a random recursive tree plus random extra lines; the
    powers +1 and -1 on half the nodes each, at random. (edges, powers)."""
    rng = np.random.default_rng(seed)
    edges = {(int(rng.integers(0, i)), i) for i in range(1, n_nodes)}
    while len(edges) < n_edges:
        a, b = sorted(int(x) for x in rng.choice(n_nodes, 2, replace=False))
        edges.add((a, b))
    power = rng.permutation(np.repeat([1.0, -1.0], [n_nodes // 2, n_nodes - n_nodes // 2]))
    if n_nodes % 2:
        power[power < 0] *= (n_nodes // 2) / (n_nodes - n_nodes // 2)
    return sorted(edges), power


def network_scaling(n_nodes: int, edge_counts, n_traj: int, steps: int, repeats: int,
                    log) -> dict:
    """Time per trajectory-step of a SwingNetwork against its edges."""
    graphs = {e: random_network(n_nodes, e, seed=e) for e in edge_counts}
    coupling = 8.0  # large enough for every graph's synchronous state (doubled until)
    while True:
        try:
            for edges, power in graphs.values():
                sweep.SwingNetwork(edges, power=power, coupling=coupling).synchronous_state()
            break
        except ValueError:
            coupling *= 2.0
    nodes = np.arange(min(16, n_nodes))
    per = max(1, n_traj // nodes.size)
    side = max(1, math.isqrt(per))
    grid = sweep.Grid(perturbed_node=nodes, delta_theta=np.linspace(-1.0, 1.0, side),
                      delta_omega=np.linspace(-2.0, 2.0, max(1, per // side)))
    kw = dict(t_end=steps * DT, dt=DT, observe=("synchrony",), progress=False)
    networks = {e: sweep.SwingNetwork(edges, power=power, damping=0.1, coupling=coupling)
                for e, (edges, power) in graphs.items()}
    for network in networks.values():
        sweep.run(network, grid, **dict(kw, t_end=DT))  # compile: not timed
    best = best_alternating({e: lambda n=network: sweep.run(n, grid, **kw)
                             for e, network in networks.items()}, repeats)
    rows = []
    for n_edges, took in best.items():
        per_step = took / (grid.size * steps)
        rows.append({"edges": n_edges, "seconds": took, "ns_per_traj_step": per_step * 1e9,
                     "ns_per_edge_step": per_step * 1e9 / n_edges})
        log(f"  {n_nodes} nodes, {n_edges} edges: {per_step * 1e9:8.1f} ns per "
            f"trajectory-step, {per_step * 1e9 / n_edges:.2f} ns per edge-step")
    e = np.array([r["edges"] for r in rows], dtype=float)
    t = np.array([r["ns_per_traj_step"] for r in rows])
    slope, intercept = np.polyfit(e, t, 1) if len(rows) > 1 else (t[0] / e[0], 0.0)
    fit = intercept + slope * e
    return {"nodes": n_nodes, "trajectories": grid.size, "steps": steps,
            "coupling": coupling, "rows": rows, "fit_ns_per_edge_step": float(slope),
            "fit_ns_per_traj_step_at_0_edges": float(intercept),
            "fit_max_relative_residual": float(np.max(np.abs(t - fit) / t))}


# --------------------------------------------------------------------------- main
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes: a smoke test")
    parser.add_argument("--rounds", type=int, default=5,
                        help="alternating calls of sweep and the C limit (best of each)")
    parser.add_argument("--flip-size", type=int, default=1000)
    parser.add_argument("--flip-rows", type=int, default=100,
                        help="rows of the band run without stop_early")
    parser.add_argument("--skip", nargs="*", default=(), choices=("c", "flip", "network"))
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    if args.quick:
        n_traj, n_steps, blocks = 2**10, 50, (64, 512)
        flip = (16, 4, 10.0)
        network = (10, (10, 20, 40), 64, 20, 1)
        args.rounds = min(args.rounds, 2)
    else:
        n_traj, n_steps, blocks = 2**17, 1000, C_BLOCKS
        flip = (args.flip_size, args.flip_rows, 100.0)
        network = (100, (100, 200, 400), 2048, 1000, 3)

    def log(text):
        print(text, flush=True)

    result = {**stamp(), "mode": "quick" if args.quick else "default",
              "load_1min_start": os.getloadavg()[0]}
    log(f"{result['machine']} ({result['date']}, load {result['load_1min_start']:.2f})")
    theta1, theta2 = start_axes(n_traj)
    state = starts(theta1, theta2)
    n = state[0].size
    work = {"trajectories": n, "steps": n_steps, "dt": DT, "mass": MASS, "length": LENGTH,
            "gravity": GRAVITY, "grid": [theta1.size, theta2.size]}
    result["workload"] = work
    log(f"double pendulum: {n} trajectories x {n_steps} RK4 steps")

    run_sweep(theta1, theta2, 1)  # compile (or load) the kernel of this grid: not timed
    reference = final_state(run_sweep(theta1, theta2, CHECK_STEPS))
    moved = [np.nextafter(x, np.inf) for x in state[:2]]
    bumped = sweep.run(system(), sweep.Points(theta1_0=moved[0], theta2_0=moved[1]),
                       t_end=CHECK_STEPS * DT, dt=DT, observe=("final",), progress=False)
    result["rounding_scale"] = max_diff(final_state(bumped), reference)
    log(f"  sweep against itself from starts one ulp on, after {CHECK_STEPS} steps: "
        f"{result['rounding_scale']:.1e}")
    sweep_s = best_of(lambda: run_sweep(theta1, theta2, n_steps), 1)
    log(f"  sweep.run: {n * n_steps / sweep_s / 1e6:.1f} M trajectory-steps/s")

    start = time.perf_counter()
    got = numpy_rk4(state, CHECK_STEPS)
    took = time.perf_counter() - start
    result["numpy"] = {"steps_timed": CHECK_STEPS, "seconds": took,
                       "traj_steps_per_s": n * CHECK_STEPS / took,
                       "check_max_abs_diff": max_diff(got, reference)}
    log(f"  NumPy RK4 (vectorised): {result['numpy']['traj_steps_per_s'] / 1e6:.2f} M/s, "
        f"after {CHECK_STEPS} steps {result['numpy']['check_max_abs_diff']:.1e} from sweep")

    result["c_search"], limit = [], None
    build = tempfile.TemporaryDirectory(prefix="sweep_c_")
    if "c" in args.skip or shutil.which("gcc") is None:
        result["c_note"] = "skipped" if "c" in args.skip else "gcc not found"
    else:
        log("the C limit: block sizes, then one option at a time, then the sine design")
        rows, limit = search_c_limit(state, reference, n_steps, blocks,
                                     result["details"]["avx512f"], Path(build.name), log)
        result["c_search"] = [{k: v for k, v in r.items() if k != "fn"} for r in rows]
    if limit is not None:
        best = best_alternating({"sweep": lambda: run_sweep(theta1, theta2, n_steps),
                                 "c": lambda: call_double(limit["fn"], state, n_steps)},
                                args.rounds)
        final = final_state(run_sweep(theta1, theta2, n_steps))
        result["c_limit"] = {
            "name": limit["name"], "flags": limit["flags"], "block": limit["block"],
            "compile": " ".join(["gcc", *limit["flags"], "double_pendulum.c", "-lm"]),
            "traj_steps_per_s": n * n_steps / best["c"],
            "sweep_traj_steps_per_s": n * n_steps / best["sweep"],
            "sweep_over_c_limit": best["c"] / best["sweep"], "rounds": args.rounds,
            "check_max_abs_diff": limit["check_max_abs_diff"], "trig": limit["trig"],
            "full_horizon_max_abs_diff": max_diff(call_double(limit["fn"], state, n_steps),
                                                  final)}
        log(f"sweep / C limit: {result['c_limit']['sweep_over_c_limit']:.3f} (sweep "
            f"{n * n_steps / best['sweep'] / 1e6:.1f}, C {n * n_steps / best['c'] / 1e6:.1f}"
            f" M/s, best of {args.rounds} alternating)")
        sweep_s = min(sweep_s, best["sweep"])
    build.cleanup()
    result["sweep"] = {"traj_steps_per_s": n * n_steps / sweep_s}

    if "flip" not in args.skip:
        log("flip-time map:")
        result["flip"] = flip_map(*flip, log)
    if "network" not in args.skip:
        log("swing network:")
        result["network"] = network_scaling(*network, log)
    result["load_1min_end"] = os.getloadavg()[0]
    stem = "double_pendulum_quick" if args.quick else "double_pendulum"
    write_results(args.out / stem, result, markdown(result))
    return 0


def markdown(r: dict) -> str:
    """The results as a Markdown page."""
    w = r["workload"]
    lines = [f"# Systems: the double pendulum and swing networks ({r['mode']})", "",
             f"{r['date']}; machine: {r['machine']}", "", *machine_lines(r), "",
             f"1-minute load average: {r['load_1min_start']:.2f} at the start, "
             f"{r['load_1min_end']:.2f} at the end (2 cores; above ~1 other work shared "
             "the CPU and the rates are lower bounds; the alternating ratio is the "
             "fairest number).", "",
             "## sweep against the C limit", "",
             f"Undamped double pendulum, m1 = m2 = {w['mass']:g} kg, l1 = l2 = "
             f"{w['length']:g} m, g = {w['gravity']:g} m/s^2, from rest on a "
             f"{w['grid'][0]} x {w['grid'][1]} grid of (theta1_0, theta2_0) in [-3, 3]^2 "
             f"rad: {w['trajectories']} trajectories x {w['steps']} RK4 steps of dt = "
             f"{w['dt']} s, float64, final state only. Rates in trajectory-steps per "
             "second.", ""]
    c = r.get("c_limit")
    if c:
        lines += [
            "| what | M traj-steps/s | / C limit |", "|---|---|---|",
            f"| `sweep.run` | {c['sweep_traj_steps_per_s'] / 1e6:.1f} | "
            f"**{c['sweep_over_c_limit']:.2f}** |",
            f"| the C limit: {c['name']} | {c['traj_steps_per_s'] / 1e6:.1f} | 1 |",
            f"| NumPy RK4, vectorised (timed on {r['numpy']['steps_timed']} steps) | "
            f"{r['numpy']['traj_steps_per_s'] / 1e6:.2f} | "
            f"{r['numpy']['traj_steps_per_s'] / c['traj_steps_per_s']:.3f} |", "",
            f"sweep and the C limit timed in alternation, best of {c['rounds']} calls each "
            f"(target: sweep / C limit >= 0.9). The limit: `{c['compile']}`. Its final "
            f"state after {CHECK_STEPS} steps differs from sweep's by at most "
            f"{c['check_max_abs_diff']:.1e} (allowed: {CHECK_TOL:g}; sweep against itself "
            f"from starts one ulp on: {r['rounding_scale']:.1e}); after all "
            f"{w['steps']} steps by {c['full_horizon_max_abs_diff']:.1e} (the motion is "
            "chaotic: rounding differences grow). NumPy after "
            f"{CHECK_STEPS} steps: {r['numpy']['check_max_abs_diff']:.1e}.", "",
            "The search (each build timed once: on a shared machine a single timing can be "
            f"off by 2x either way; the {FINALISTS} fastest eligible builds were timed again "
            f"in turns, best of {FINAL_ROUNDS}, last column). Sine contract: within "
            f"{SINE_CONTRACT:.3g} of NumPy's sin (and cos) for "
            + " and ".join(SINE_RANGES) + "; errors shown as the largest of the build's "
            "sin, and the sin and cos of its one-reduction pair, over both ranges.", "",
            "| build | flags beyond `" + " ".join(C_BASE_FLAGS) + "` | M traj-steps/s | "
            f"check after {CHECK_STEPS} steps | sin/cos max abs err | eligible | "
            "again, in turns |", "|---|---|---|---|---|---|---|"]
        for row in r["c_search"]:
            if "error" in row:
                lines.append(f"| {row['name']} | `{' '.join(row['flags'])}` | "
                             f"{row['error']} | | | no | |")
                continue
            extra = " ".join(f for f in row["flags"] if f not in C_BASE_FLAGS)
            worst = max(e for part in row["trig"].values() for e in part.values())
            again = row.get("final_traj_steps_per_s")
            lines.append(f"| {row['name']} | `{extra}` | {row['traj_steps_per_s'] / 1e6:.1f}"
                         f" | {row['check_max_abs_diff']:.1e}"
                         f"{'' if row['check_ok'] else ' FAILS'} | {worst:.1e} | "
                         f"{'yes' if row['check_ok'] and row['trig_eligible'] else '**no**'}"
                         f" | {'' if again is None else f'{again / 1e6:.1f}'} |")
    else:
        lines += [f"C limit: {r.get('c_note', 'no eligible build')}; `sweep.run`: "
                  f"{r['sweep']['traj_steps_per_s'] / 1e6:.1f} M/s; NumPy: "
                  f"{r['numpy']['traj_steps_per_s'] / 1e6:.2f} M/s."]
    f = r.get("flip")
    if f:
        lines += [
            "", f"## The {f['size']} x {f['size']} flip-time map", "",
            f"theta1_0, theta2_0 in [-3, 3] rad from rest, `observe=(\"flip\",)`, up to "
            f"t = {f['t_max_natural_units']:g} sqrt(l/g) with dt = sqrt(l/g)/100 "
            f"({f['steps']} steps). Wall time of `sweep.run`, end to end (parameter "
            "table, kernel, dataset); the kernel was compiled or loaded from the disk "
            f"cache first by a one-step run of the same grid ({f['warm_up_seconds']:.1f} "
            "s, not counted).", "",
            "| run | seconds |", "|---|---|",
            f"| `stop_early=True`, whole map | **{f['stop_early_seconds']:.1f}** |",
            f"| without stop_early, whole map (from {f['band_rows']} rows, extrapolated) | "
            f"{f['full_seconds_extrapolated']:.1f} |",
            f"| without stop_early / with | {f['speedup']:.1f}x (on the band alone: "
            f"{f['band_speedup']:.1f}x) |", "",
            f"{f['never_flip_fraction']:.1%} of the starts never flip within the horizon "
            "(most of them cannot: their energy is below the lowest flipping energy, and "
            "stop_early does not integrate them at all). Flip times with and without "
            f"stop_early on the band: {'the same bits' if f['band_same_bits'] else 'DIFFER'}."
            f" Without stop_early the kernel runs "
            f"{f['full_traj_steps_per_s'] / 1e6:.0f} M trajectory-steps/s (the flip "
            "observable included)."]
    net = r.get("network")
    if net:
        lines += [
            "", "## A swing network's cost per step against its edges", "",
            f"{net['nodes']} nodes (half P = +1, half P = -1), random connected graphs, "
            f"damping 0.1, coupling {net['coupling']:g}; {net['trajectories']} "
            f"perturbations x {net['steps']} RK4 steps of dt = {DT} s, "
            "`observe=(\"synchrony\",)`.", "",
            "| edges | seconds | ns per trajectory-step | ns per edge-step | ns per "
            "edge-step, the nodes' part (the fit's constant) taken off |",
            "|---|---|---|---|---|"]
        for row in net["rows"]:
            edge_part = (row["ns_per_traj_step"] - net["fit_ns_per_traj_step_at_0_edges"]) \
                / row["edges"]
            lines.append(f"| {row['edges']} | {row['seconds']:.2f} | "
                         f"{row['ns_per_traj_step']:.0f} | {row['ns_per_edge_step']:.2f} | "
                         f"{edge_part:.2f} |")
        lines += ["", f"Straight-line fit: {net['fit_ns_per_traj_step_at_0_edges']:.0f} ns "
                  f"per trajectory-step + {net['fit_ns_per_edge_step']:.2f} ns per edge "
                  f"(largest residual {net['fit_max_relative_residual']:.1%}): the cost "
                  "is linear in the edges; the constant is the nodes' own work (the RK4 "
                  "stages over every node)."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
