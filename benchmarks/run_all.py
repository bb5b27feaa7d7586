"""The benchmark suite: sweep beside the alternatives, every ratio from the same run.

Workload (the performance issue's): damped, forced, nonlinear pendulum
theta'' = A sin(W t) - c theta' - (g/L) sin(theta), g/L = 1, c = 0.5, A = 1.2, W = 2/3,
2**17 trajectories (512 x 256 grid of theta0 in [-pi, pi], omega0 in [-2, 2]) x 2000
RK4 steps of dt = 0.01, float64, final state only. Throughput is trajectory-steps per
second (trajectories x steps / wall seconds).

Measured:

* ``sweep.run`` per effect combination (linear/nonlinear x damping x forcing), each
  beside the general kernel fed zeros (``specialize=False``);
* the same work in vectorised NumPy RK4, SciPy ``solve_ivp`` DOP853 per trajectory
  (subset, extrapolated), a seed-style pure-Python RK4 (subset, extrapolated), a naive
  numba kernel (prange over trajectories, ``math.sin``), the C reference
  (``benchmarks/c_reference/pendulum.c``, built here with gcc when present: libm sin,
  glibc's vector sin, the polynomial sin of ``sweep.kernels.vecmath``, with and without
  FMA contraction), JAX when importable;
* **the C limit**: the fastest C of the same algorithm (polynomial sine in SIMD lanes,
  FMA contraction, ``-mprefer-vector-width=512`` where /proc/cpuinfo has ``avx512f``,
  the forcing sine once per step), found by a block-size sweep (64 .. 4096 trajectories
  per block, OpenMP over blocks), then one option changed at a time, then the sine's
  design (issue 29: one reduction by pi and one odd polynomial, Taylor or minimax from
  ``fit_sine.py``, Horner or Estrin; the fastest of them swept over the block sizes
  again); timed again in alternation with ``sweep.run`` on the full scene, and the ratio
  sweep / C limit printed. Every C build is checked against sweep's final state after
  100 steps (``C_CHECK_TOL``; the full horizon's difference is shown too, but the scene
  is chaotic and amplifies rounding differences), and its sine against np.sin over
  |x| <= 1e4 and 1e4 < |x| <= 1e12: only a build whose sine meets sweep's contract
  (``SINE_CONTRACT``: 2**-52 absolute on both) may be the limit;
* the kernel with the forcing sine per lane (as for a grid over forcing frequency),
  and the full scene under each set of fast-math flags (``sweep._config.FASTMATH``);
* ``sweep.kernels.vecmath.sin`` against ``math.sin`` in a numba loop (fastmath flags without
  ``reassoc``), and whether the loop vectorises;
* compile time cold (fresh ``SWEEP_CACHE_DIR``, new process) and warm (next process),
  ``import sweep`` time, peak memory of a 2048 x 2048 final-state run (``VmHWM``;
  ``ru_maxrss`` beside it, which on Linux also counts the parent's memory at exec),
  scaling with trajectories (1e3 .. 1e6; 1e7 with ``--full``) and threads (1 vs 2).

Writes ``benchmarks/results/run_all.json``, ``run_all.md`` and ``run_all.png``, with the
machine (CPU model from lscpu, cores, SIMD flags, gcc's version and what it takes
``-march=native`` for, numba)
(``--quick``: ``run_all_quick.*``, so a smoke test leaves the full results alone).

Usage::

    python benchmarks/run_all.py            # the issue's workload (~3 min on 2 cores)
    python benchmarks/run_all.py --quick    # small sizes, a smoke test (~1 min)
    python benchmarks/run_all.py --full     # adds 1e7 trajectories to the scaling
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import sweep
from sweep import _config
from sweep import kernels as _kernels
from sweep.kernels import vecmath as _vecmath

# the C reference and the full scene, and the machine's description: re-exported, so
# run_all.X names them as before (tests/test_benchmark_scripts.py, float32.py)
from _c_builds import (  # noqa: F401
    AMPLITUDE,
    C_BASE_FLAGS,
    C_BLOCKS,
    C_CHECK_STEPS,
    C_CHECK_TOL,
    C_FIXED,
    C_SOURCE,
    DAMPING,
    DT,
    FREQUENCY,
    G_OVER_L,
    NARROW,
    PHASE,
    PI_SINES,
    SINE_CONTRACT,
    SINE_RANGES,
    WIDE,
    build_c,
    build_c_one,
    c_limit_candidates,
    c_limit_sine_designs,
    c_limit_variations,
    call_c,
    grid_axes,
    initial_states,
    sine_accuracy,
    sine_text,
)
from _machine import (  # noqa: F401
    cpu_flags,
    gcc_info,
    machine,
    machine_details,
    machine_lines,
    native_vector_registers,
)

REPEATS = 1  # best of at least this many calls (--repeats)
MIN_SECONDS = 0.0  # every timing repeats until this much wall time (--quick: 0.3 s)
VEC_FLAGS = set(_config.FASTMATH)  # sweep's kernels' fast-math flags (no reassoc)


# ----------------------------------------------------------------------------- helpers
def timed(fn, *, repeats=1, min_seconds=0.0):
    """Best wall time of ``fn()`` over ``repeats`` calls (more calls, up to 50, while
    the total is under ``min_seconds``); returns (seconds, last result)."""
    min_seconds = max(min_seconds, MIN_SECONDS)
    repeats = max(repeats, REPEATS)
    best, total, calls, result = math.inf, 0.0, 0, None
    while calls < repeats or (total < min_seconds and calls < 50):
        start = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - start
        best, total, calls = min(best, elapsed), total + elapsed, calls + 1
    return best, result


def scene_of(model="nonlinear", damping=True, forcing=True):
    effects = []
    if damping:
        effects.append(sweep.Damping(DAMPING))
    if forcing:
        effects.append(sweep.Forcing(AMPLITUDE, FREQUENCY, PHASE))
    return sweep.Scene(gravity=G_OVER_L, length=1.0, model=model, effects=tuple(effects))


def run_kernel(spec, scene, theta0, omega0, steps):
    """sweep's kernel for ``spec`` called directly on the grid's parameter table
    (for variants `sweep.run` picks only for other grids); final theta, omega."""
    table = sweep.Grid(theta0=theta0, omega0=omega0).table(scene)
    out = np.empty((table.shape[0], _kernels.n_columns(spec)))
    status = np.empty(table.shape[0], dtype=np.int8)
    _kernels.build(spec)(table, 0.0, DT, steps, 0, 1, out, status, np.empty((0, 2, 0)))
    return out[:, 0], out[:, 1]


def warm_kernel(scene, theta0, omega0, steps, **options):
    """Compile (or load) the kernel `run_sweep` will use on this very grid: the
    grid's size sets the kernel's block, so a one-start stand-in would compile
    another kernel and leave this one's compilation inside the timing."""
    sweep.engine.warm_up(scene, sweep.Grid(theta0=theta0, omega0=omega0),
                         t_end=steps * DT, dt=DT, observe=("final",), **options)


def run_sweep(scene, theta0, omega0, steps, **options):
    grid = sweep.Grid(theta0=theta0, omega0=omega0)
    return sweep.run(scene, grid, t_end=steps * DT, dt=DT, observe=("final",),
                     progress=False, **options)


# --------------------------------------------------------------------- alternatives
def numpy_rk4(th0, om0, steps):
    """RK4 vectorised across trajectories, sweep's operations and forcing times."""
    th, om = th0.copy(), om0.copy()
    w0sq, c, A, W, phi = G_OVER_L, DAMPING, AMPLITUDE, FREQUENCY, PHASE
    dt_2, dt_6, cdt1 = DT / 2.0, DT / 6.0, DT * 0.5

    def accel(x, v, f):
        return -w0sq * np.sin(x) - c * v + f

    f0 = A * math.sin(W * 0.0 + phi)
    for step in range(steps):
        f1 = A * math.sin(W * (step * DT + cdt1) + phi)
        f2 = A * math.sin(W * ((step + 1) * DT) + phi)
        k1t = om
        k1o = accel(th, k1t, f0)
        k2t = om + dt_2 * k1o
        k2o = accel(th + dt_2 * k1t, k2t, f1)
        k3t = om + dt_2 * k2o
        k3o = accel(th + dt_2 * k2t, k3t, f1)
        k4t = om + DT * k3o
        k4o = accel(th + DT * k3t, k4t, f2)
        th = th + dt_6 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
        om = om + dt_6 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o)
        f0 = f2
    return th, om


def python_rk4(th0, om0, steps):
    """Seed-style textbook RK4: pure Python floats, one trajectory at a time."""
    def f(t, th, om):
        return om, AMPLITUDE * math.sin(FREQUENCY * t + PHASE) - DAMPING * om \
            - G_OVER_L * math.sin(th)

    out_th, out_om = [], []
    for th, om in zip(th0.tolist(), om0.tolist()):
        for n in range(steps):
            t = n * DT
            a1, b1 = f(t, th, om)
            a2, b2 = f(t + DT / 2, th + DT / 2 * a1, om + DT / 2 * b1)
            a3, b3 = f(t + DT / 2, th + DT / 2 * a2, om + DT / 2 * b2)
            a4, b4 = f(t + DT, th + DT * a3, om + DT * b3)
            th = th + DT / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            om = om + DT / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        out_th.append(th)
        out_om.append(om)
    return np.array(out_th), np.array(out_om)


def scipy_dop853(th0, om0, steps, rtol=1e-10, atol=1e-12):
    from scipy.integrate import solve_ivp

    def f(t, y):
        return (y[1], AMPLITUDE * math.sin(FREQUENCY * t + PHASE) - DAMPING * y[1]
                - G_OVER_L * math.sin(y[0]))

    th, om = [], []
    for a, b in zip(th0, om0):
        sol = solve_ivp(f, (0.0, steps * DT), (a, b), method="DOP853", rtol=rtol, atol=atol)
        th.append(sol.y[0, -1])
        om.append(sol.y[1, -1])
    return np.array(th), np.array(om)


@njit(parallel=True, cache=True)
def numba_naive(th0, om0, steps, w0sq, c, A, W, phi, dt):
    """prange over trajectories, time loop inside, math.sin: the obvious numba kernel."""
    n = th0.size
    th_out = np.empty(n)
    om_out = np.empty(n)
    for i in prange(n):
        th, om = th0[i], om0[i]
        for step in range(steps):
            t = step * dt
            f0 = A * math.sin(W * t + phi)
            f1 = A * math.sin(W * (t + 0.5 * dt) + phi)
            f2 = A * math.sin(W * (t + dt) + phi)
            k1t = om
            k1o = -w0sq * math.sin(th) - c * k1t + f0
            k2t = om + 0.5 * dt * k1o
            k2o = -w0sq * math.sin(th + 0.5 * dt * k1t) - c * k2t + f1
            k3t = om + 0.5 * dt * k2o
            k3o = -w0sq * math.sin(th + 0.5 * dt * k2t) - c * k3t + f1
            k4t = om + dt * k3o
            k4o = -w0sq * math.sin(th + dt * k3t) - c * k4t + f2
            th = th + dt / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
            om = om + dt / 6.0 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o)
        th_out[i] = th
        om_out[i] = om
    return th_out, om_out


def jax_rk4(th0, om0, steps):
    import jax
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    def one(th, om):
        def step(state, n):
            th, om = state
            t = n * DT

            def acc(x, v, t):
                return AMPLITUDE * jnp.sin(FREQUENCY * t + PHASE) - DAMPING * v \
                    - G_OVER_L * jnp.sin(x)
            k1t, k1o = om, acc(th, om, t)
            k2t = om + DT / 2 * k1o
            k2o = acc(th + DT / 2 * k1t, k2t, t + DT / 2)
            k3t = om + DT / 2 * k2o
            k3o = acc(th + DT / 2 * k2t, k3t, t + DT / 2)
            k4t = om + DT * k3o
            k4o = acc(th + DT * k3t, k4t, t + DT)
            return (th + DT / 6 * (k1t + 2 * k2t + 2 * k3t + k4t),
                    om + DT / 6 * (k1o + 2 * k2o + 2 * k3o + k4o)), None
        (th, om), _ = jax.lax.scan(step, (th, om), jnp.arange(steps, dtype=jnp.float64))
        return th, om
    f = jax.jit(jax.vmap(one))
    a, b = jnp.asarray(th0), jnp.asarray(om0)
    jax.block_until_ready(f(a[:8], b[:8]))  # compile for another shape: not timed
    jax.block_until_ready(f(a, b))  # compile for this shape
    start = time.perf_counter()
    th, om = jax.block_until_ready(f(a, b))
    return time.perf_counter() - start, (np.asarray(th), np.asarray(om))


# ------------------------------------------------------------------ vecmath in numba
# not cached: numba cannot show the machine code of a kernel loaded from its disk cache
@njit(fastmath=VEC_FLAGS, cache=False)
def loop_vsin(x, out):
    for i in range(x.size):
        out[i] = _vecmath.sin(x[i])


@njit(fastmath=VEC_FLAGS, cache=False)
def loop_math_sin(x, out):
    for i in range(x.size):
        out[i] = math.sin(x[i])


@njit(cache=False)
def loop_vsin_strict(x, out):
    for i in range(x.size):
        out[i] = _vecmath.sin(x[i])


def vectorised(fn) -> bool:
    """Whether fn's machine code does packed double arithmetic on ymm/zmm registers
    (vmulpd, vaddpd, vsubpd, vfmadd...pd): the loop body runs several lanes at once."""
    asm = "".join(fn.inspect_asm().values())
    return re.search(r"\bv(?:mul|add|sub|fmadd\w*)pd\s+%?[yz]mm", asm) is not None


# ------------------------------------------------------------------- subprocesses
def in_subprocess(code: str, env_extra=None) -> dict:
    env = dict(os.environ, **(env_extra or {}))
    env["PYTHONPATH"] = str(HERE.parent) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], check=False, env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr)
    return json.loads(proc.stdout.strip().splitlines()[-1])


FIRST_CALL = """
    import json, time
    start = time.perf_counter()
    import numpy as np
    import sweep
    imported = time.perf_counter() - start
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.5),
                        sweep.Forcing(1.2, 2 / 3, 0.0)))
    start = time.perf_counter()
    sweep.run(scene, sweep.Grid(theta0=np.linspace(-1, 1, 64), omega0=[0.0]), t_end=0.1,
              dt=0.01, observe=("final",), progress=False)
    first = time.perf_counter() - start
    print(json.dumps({"import_s": imported, "first_run_s": first}))
"""

MEMORY = """
    import json, resource, time
    import numpy as np
    import sweep

    def status(key):  # kB -> MiB, from /proc/self/status (Linux)
        with open("/proc/self/status") as handle:
            for line in handle:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) / 1024

    n, steps = {n}, {steps}
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.5),
                        sweep.Forcing(1.2, 2 / 3, 0.0)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n), omega0=np.linspace(-2, 2, n))
    sweep.engine.warm_up(scene, grid, t_end=steps * 0.01, dt=0.01, observe=("final",))
    hwm_before, rss_before = status("VmHWM"), status("VmRSS")
    start = time.perf_counter()
    ds = sweep.run(scene, grid, t_end=steps * 0.01, dt=0.01, observe=("final",),
                   progress=False)
    seconds = time.perf_counter() - start
    print(json.dumps({{"peak_MiB": status("VmHWM"), "hwm_before_run_MiB": hwm_before,
                      "rss_before_run_MiB": rss_before,
                      "ru_maxrss_MiB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                      "trajectories": n * n, "steps": steps, "seconds": seconds,
                      "output_MiB": ds.nbytes / 2**20}}))
"""


# --------------------------------------------------------------------------- main
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="small sizes: a smoke test")
    size.add_argument("--full", action="store_true", help="scaling up to 1e7 trajectories")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    parser.add_argument("--repeats", type=int, default=1,
                        help="best of N for each throughput timing (default 1)")
    args = parser.parse_args(argv)

    global MIN_SECONDS, REPEATS
    REPEATS = max(1, args.repeats)
    if args.quick:
        MIN_SECONDS = 0.3
        n_traj, steps, sub_scipy, sub_python = 2**12, 200, 4, 8
        scaling_n, scaling_steps, mem_side, mem_steps = [10**3, 10**4, 10**5], 50, 256, 20
        thread_steps, vec_points = 100, 10**6
        c_blocks, c_rounds = (64, 512), 1
    else:
        n_traj, steps, sub_scipy, sub_python = 2**17, 2000, 32, 64
        scaling_n, scaling_steps, mem_side, mem_steps = [10**3, 10**4, 10**5, 10**6], 200, \
            2048, 20
        thread_steps, vec_points = 500, 10**7
        c_blocks, c_rounds = C_BLOCKS, 3
        if args.full:
            scaling_n.append(10**7)
    total = time.perf_counter()
    load_start = os.getloadavg()[0]
    n_threads = numba.get_num_threads()
    result = {"machine": machine(), "machine_details": machine_details(),
              "mode": "quick" if args.quick else ("full" if args.full else "default"),
              "repeats": REPEATS,
              "workload": {"trajectories": n_traj, "steps": steps, "dt": DT,
                           "g_over_L": G_OVER_L, "damping": DAMPING, "amplitude": AMPLITUDE,
                           "frequency": FREQUENCY, "observe": "final", "dtype": "float64"},
              "throughput": {}, "agreement": {}, "notes": []}
    thr = result["throughput"]

    def record(name, seconds, trajectories=n_traj, n_steps=steps, **extra):
        rate = trajectories * n_steps / seconds
        thr[name] = {"seconds": seconds, "trajectories": trajectories, "steps": n_steps,
                     "traj_steps_per_s": rate, **extra}
        print(f"  {name:55s} {rate / 1e6:10.2f} M/s  ({seconds:.3f} s)", flush=True)

    theta0, omega0 = grid_axes(n_traj)
    n_traj = theta0.size * omega0.size
    result["workload"]["trajectories"] = n_traj
    th0, om0 = initial_states(theta0, omega0)
    print(f"{result['machine']}\nworkload: {n_traj} trajectories x {steps} RK4 steps",
          flush=True)

    # --- sweep per effect combination, and the general kernel fed zeros
    print("sweep.run per effect combination:", flush=True)
    reference = None
    for model in ("nonlinear", "linear"):
        for damping in (True, False):
            for forcing in (True, False):
                scene = scene_of(model, damping, forcing)
                label = f"{model}, {'damping' if damping else 'no damping'}, " \
                        f"{'forcing' if forcing else 'no forcing'}"
                for specialize in (True, False):
                    # compile (or load from the disk cache) first: not timed
                    warm_kernel(scene, theta0, omega0, steps, specialize=specialize)
                    seconds, ds = timed(lambda s=scene, k=specialize: run_sweep(
                        s, theta0, omega0, steps, specialize=k))
                    name = f"sweep: {label}" + ("" if specialize else " [general kernel]")
                    record(name, seconds, group="sweep", model=model, damping=damping,
                           forcing=forcing, specialize=specialize)
                    if model == "nonlinear" and damping and forcing and specialize:
                        reference = (ds.theta_final.values.ravel(),
                                     ds.omega_final.values.ravel())
    full_name = "sweep: nonlinear, damping, forcing"
    sweep_full = thr[full_name]["traj_steps_per_s"]

    # the forcing sine per lane, as when the grid varies the forcing frequency or phase
    spec = _kernels.KernelSpec("nonlinear", ("damping", "forcing"), ("final",),
                               shared_forcing=False)
    run_kernel(spec, scene_of(), [0.1], [0.0], 1)
    seconds, got = timed(lambda: run_kernel(spec, scene_of(), theta0, omega0, steps))
    per_lane = "sweep: nonlinear, damping, forcing [forcing sine per lane, as when W varies]"
    record(per_lane, seconds, group="sweep", model="nonlinear", damping=True, forcing=True)
    result["agreement"][per_lane] = max(float(np.max(np.abs(got[0] - reference[0]))),
                                        float(np.max(np.abs(got[1] - reference[1]))))

    # one trajectory: the narrow path sweep.run takes for a handful (a block of one lane),
    # against the same trajectory in a block of 64 lanes (63 of them padding)
    one_steps = 10**4 if args.quick else 10**6
    for label, block in (("one trajectory alone (the narrow path sweep.run takes)", 1),
                         ("one trajectory in a block of 64 lanes (63 padding)", 64)):
        spec = _kernels.KernelSpec("nonlinear", ("damping", "forcing"), ("final",),
                                   shared_forcing=True, block=block)
        run_kernel(spec, scene_of(), [0.1], [0.0], 1)  # compile: not timed
        seconds, _ = timed(lambda s=spec: run_kernel(s, scene_of(), [0.1], [0.0], one_steps))
        record(f"sweep: {label}", seconds, trajectories=1, n_steps=one_steps, group="sweep",
               model="nonlinear", damping=True, forcing=True)

    # the fast-math flags of the kernels (sweep._config.FASTMATH), each measured here
    print("fast-math flags of sweep's kernels (full scene):", flush=True)
    default = _config.FASTMATH
    result["fastmath"] = {}
    try:
        for flags in (False, {"nsz"}, {"contract"}, {"contract", "nsz"}):
            _config.FASTMATH = flags if flags is False else frozenset(flags)
            _kernels.build.cache_clear()
            warm_kernel(scene_of(), theta0, omega0, steps)  # compile: not timed
            seconds, ds = timed(lambda: run_sweep(scene_of(), theta0, omega0, steps))
            label = "none" if flags is False else ", ".join(sorted(flags))
            diff = max(float(np.max(np.abs(ds.theta_final.values.ravel() - reference[0]))),
                       float(np.max(np.abs(ds.omega_final.values.ravel() - reference[1]))))
            rate = n_traj * steps / seconds
            result["fastmath"][label] = {"traj_steps_per_s": rate,
                                         "max_abs_diff_from_default": diff,
                                         "default": frozenset(_config.FASTMATH or ())
                                         == frozenset(default or ())}
            print(f"  {label:55s} {rate / 1e6:10.2f} M/s  max |diff| {diff:.1e}", flush=True)
    finally:
        _config.FASTMATH = default
        _kernels.build.cache_clear()

    def agree(name, got, rows=slice(None)):
        diff = max(float(np.max(np.abs(got[0] - reference[0][rows]))),
                   float(np.max(np.abs(got[1] - reference[1][rows]))))
        result["agreement"][name] = diff
        print(f"  {'':55s} max |difference| from sweep: {diff:.2e}", flush=True)

    print("the same work, other ways:", flush=True)
    seconds, got = timed(lambda: numpy_rk4(th0, om0, steps))
    record("NumPy RK4, vectorised across trajectories", seconds, group="alternative")
    agree("NumPy RK4, vectorised across trajectories", got)

    pick = np.linspace(0, n_traj - 1, sub_scipy).round().astype(int)
    seconds, got = timed(lambda: scipy_dop853(th0[pick], om0[pick], steps))
    record("SciPy solve_ivp DOP853 (rtol 1e-10), per trajectory", seconds,
           trajectories=len(pick), group="alternative", extrapolated_from=len(pick))
    agree("SciPy solve_ivp DOP853 (rtol 1e-10), per trajectory", got, pick)

    pick = np.linspace(0, n_traj - 1, sub_python).round().astype(int)
    seconds, got = timed(lambda: python_rk4(th0[pick], om0[pick], steps))
    record("pure-Python RK4 (seed style), per trajectory", seconds, trajectories=len(pick),
           group="alternative", extrapolated_from=len(pick))
    agree("pure-Python RK4 (seed style), per trajectory", got, pick)

    args_naive = (steps, G_OVER_L, DAMPING, AMPLITUDE, FREQUENCY, PHASE, DT)
    numba_naive(th0[:2], om0[:2], *args_naive)
    seconds, got = timed(lambda: numba_naive(th0, om0, *args_naive))
    record("numba naive (prange, time loop inside, math.sin)", seconds, group="alternative")
    agree("numba naive (prange, time loop inside, math.sin)", got)

    try:
        import jax  # noqa: F401
    except ImportError:
        result["notes"].append("JAX not installed: skipped")
        print("  JAX not installed: skipped", flush=True)
    else:
        try:
            seconds, got = jax_rk4(th0, om0, steps)
        except Exception as error:  # noqa: BLE001 - a broken JAX install must not sink the suite
            result["notes"].append(f"JAX failed ({type(error).__name__}: {error}): skipped")
            print(f"  JAX failed: {error}", flush=True)
        else:
            record("JAX jit(vmap(scan))", seconds, group="alternative")
            agree("JAX jit(vmap(scan))", got)

    # --- C: the weaker builds as named rows, then the search for the limit
    c_build = tempfile.TemporaryDirectory(prefix="sweep_c_")
    c_limit = None
    result["c_check"], result["c_limit_search"], result["c_sine"] = {}, [], {}
    if shutil.which("gcc") is None:
        result["notes"].append("gcc not found: C reference skipped")
        print("  gcc not found: C reference skipped", flush=True)
    else:
        build_dir = Path(c_build.name)
        avx512 = result["machine_details"]["avx512f"]
        short = {}  # sweep's final state after C_CHECK_STEPS, per model
        for model in ("nonlinear", "linear"):
            ds = run_sweep(scene_of(model), theta0, omega0, C_CHECK_STEPS)
            short[model] = (ds.theta_final.values.ravel(), ds.omega_final.values.ravel())

        def check_c(label, fn, model="nonlinear"):
            """max |C - sweep| of the final state after C_CHECK_STEPS steps."""
            got, ref = call_c(fn, th0, om0, C_CHECK_STEPS), short[model]
            diff = max(float(np.max(np.abs(got[0] - ref[0]))),
                       float(np.max(np.abs(got[1] - ref[1]))))
            ok = bool(diff <= C_CHECK_TOL)
            result["c_check"][label] = {"steps": C_CHECK_STEPS, "max_abs_diff": diff,
                                        "tolerance": C_CHECK_TOL, "ok": ok}
            if not ok:
                result["notes"].append(f"{label}: max |difference| from sweep after "
                                       f"{C_CHECK_STEPS} steps {diff:.1e} > {C_CHECK_TOL:g}")
            return diff, ok

        fixed = dict(C_FIXED)
        for name, flags in fixed.items():
            fn = build_c_one(build_dir, name, flags)
            if isinstance(fn, str):
                result["notes"].append(f"{name}: {fn}")
                print(f"  {name}: {fn}", flush=True)
                continue
            model = "linear" if "-DLINEAR" in flags else "nonlinear"
            check, ok = check_c(name, fn, model)
            if model == "nonlinear":
                result["c_sine"][name] = sine = sine_accuracy(fn)
                print(f"  {'':55s} its sine: {sine_text(sine)}", flush=True)
            call_c(fn, th0[:8], om0[:8], 2)
            seconds, got = timed(lambda f=fn: call_c(f, th0, om0, steps), min_seconds=1.0)
            record(name, seconds, group="C", flags=[*C_BASE_FLAGS, *flags])
            print(f"  {'':55s} after {C_CHECK_STEPS} steps: max |diff| from sweep "
                  f"{check:.1e} ({'ok' if ok else 'FAILS'})", flush=True)
            if model == "linear":
                ds = run_sweep(scene_of("linear"), theta0, omega0, steps)
                ref = (ds.theta_final.values.ravel(), ds.omega_final.values.ravel())
                diff = max(float(np.max(np.abs(got[0] - ref[0]))),
                           float(np.max(np.abs(got[1] - ref[1]))))
                result["agreement"][name] = diff
                print(f"  {'':55s} max |difference| from sweep (linear): {diff:.2e}")
            else:
                agree(name, got)

        print("the C limit: block-size sweep, then one option changed at a time:",
              flush=True)

        def search(candidates):
            for name, flags in candidates.items():
                fn = build_c_one(build_dir, name, flags)
                if isinstance(fn, str):
                    result["notes"].append(f"{name}: {fn}")
                    print(f"  {name}: {fn}", flush=True)
                    continue
                check, ok = check_c(name, fn)
                result["c_sine"][name] = sine = sine_accuracy(fn)
                call_c(fn, th0[:8], om0[:8], 2)
                seconds, _ = timed(lambda f=fn: call_c(f, th0, om0, steps))
                rate = n_traj * steps / seconds
                block = int(next(f for f in flags if f.startswith("-DBLOCK="))[8:])
                result["c_limit_search"].append({
                    "name": name, "flags": [*C_BASE_FLAGS, *flags], "block": block,
                    "traj_steps_per_s": rate, "check_max_abs_diff": check, "check_ok": ok,
                    "sine_max_abs_error": sine["max_abs_error"],
                    "sine_eligible": sine["eligible"]})
                print(f"  {name:55s} {rate / 1e6:10.2f} M/s  (check {check:.1e}"
                      f"{'' if ok else ' FAILS'}; sine {sine_text(sine)})", flush=True)
                yield name, flags, fn, rate, ok and sine["eligible"]

        found = [c for c in search(c_limit_candidates(avx512, c_blocks)) if c[4]]
        if found:
            best = max(found, key=lambda c: c[3])
            found += [c for c in search(c_limit_variations(best[1], avx512)) if c[4]]
            # the sine's design at the best block, then the fastest eligible design
            # at every other block size (a cheaper sine may move the best block)
            designs = [c for c in search(c_limit_sine_designs(best[1], avx512)) if c[4]]
            if designs:
                top = max(designs, key=lambda c: c[3])
                block = next(f for f in top[1] if f.startswith("-DBLOCK="))[8:]
                others = [str(b) for b in c_blocks if str(b) != block]
                design = {k: v for k, v in c_limit_sine_designs(top[1], avx512,
                                                                others).items()
                          if [f for f in v if not f.startswith("-DBLOCK=")]
                          == [f for f in top[1] if not f.startswith("-DBLOCK=")]}
                designs += [c for c in search(design) if c[4]]
            found += designs
            name, flags, fn, rate, _ = max(found, key=lambda c: c[3])
            c_limit = {"name": name.removeprefix("C limit search: "), "fn": fn,
                       "flags": [*C_BASE_FLAGS, *flags],
                       "block": int(next(f for f in flags if f.startswith("-DBLOCK="))[8:]),
                       "search_rate": rate}
            print(f"  best: {c_limit['name']}", flush=True)

    # --- vecmath sin in a numba loop
    print("sweep.kernels.vecmath.sin vs math.sin in a numba loop:", flush=True)
    x = np.random.default_rng(0).uniform(-50.0, 50.0, vec_points)
    out = np.empty_like(x)
    vec = {}
    flags = "/".join(sorted(VEC_FLAGS)) or "none"
    loops = [(f"math.sin, the kernels' fastmath flags ({flags})", loop_math_sin),
             (f"_vecmath.sin, the kernels' fastmath flags ({flags})", loop_vsin)]
    if VEC_FLAGS:
        loops.append(("_vecmath.sin, no fastmath", loop_vsin_strict))
    for name, fn in loops:
        fn(x[:8], out[:8])
        seconds, _ = timed(lambda f=fn: f(x, out), repeats=3)
        vec[name] = {"seconds": seconds, "sines_per_s": x.size / seconds,
                     "vectorised": vectorised(fn),
                     "max_abs_error_vs_np_sin": float(np.max(np.abs(out - np.sin(x))))}
        print(f"  {name:55s} {x.size / seconds / 1e6:10.1f} M sin/s  vectorised: "
              f"{vec[name]['vectorised']}  max err {vec[name]['max_abs_error_vs_np_sin']:.1e}",
              flush=True)
    result["vecmath"] = vec

    # --- compile and import time, memory (subprocesses)
    print("compile, import, memory (fresh processes):", flush=True)
    with tempfile.TemporaryDirectory() as cache:
        env = {"SWEEP_CACHE_DIR": cache}
        cold = in_subprocess(FIRST_CALL, env)
        warm = in_subprocess(FIRST_CALL, env)
    result["startup"] = {"import_sweep_s": warm["import_s"],
                         "first_run_cold_cache_s": cold["first_run_s"],
                         "first_run_warm_cache_s": warm["first_run_s"]}
    print(f"  import sweep {warm['import_s']:.2f} s; first run: cold cache "
          f"{cold['first_run_s']:.2f} s, warm cache {warm['first_run_s']:.2f} s", flush=True)
    # twice: the first run may compile (numba's compiler alone peaks at a few 100 MiB);
    # the second loads the kernel from the disk cache, as a user's run does
    in_subprocess(MEMORY.format(n=mem_side, steps=1))
    mem = in_subprocess(MEMORY.format(n=mem_side, steps=mem_steps))
    result["memory"] = mem
    print(f"  {mem_side} x {mem_side} final-state run: peak RSS {mem['peak_MiB']:.0f} MiB "
          f"(before the run: peak {mem['hwm_before_run_MiB']:.0f} MiB, resident "
          f"{mem['rss_before_run_MiB']:.0f} MiB)", flush=True)

    # --- scaling with trajectories and threads
    print("scaling:", flush=True)
    scene = scene_of()
    scaling = []
    for n in scaling_n:
        th_axis, om_axis = grid_axes(n)  # the main workload's states, n of them
        n = th_axis.size * om_axis.size
        # at least `scaling_steps`, more for few trajectories so that each call does
        # ~2e7 trajectory-steps (quick: 2e6) and the fixed per-call cost of sweep.run
        # (dataset construction, ~ms) does not hide the kernel's time per step
        n_steps = max(scaling_steps, min(20_000, (2 * 10**6 if args.quick else 2 * 10**7)
                                         // n))
        warm_kernel(scene, th_axis, om_axis, n_steps)
        seconds, _ = timed(lambda a=th_axis, b=om_axis, k=n_steps: run_sweep(scene, a, b, k),
                           repeats=1, min_seconds=1.0)
        rate = n * n_steps / seconds
        scaling.append({"trajectories": n, "steps": n_steps, "seconds": seconds,
                        "traj_steps_per_s": rate, "ns_per_traj_step": 1e9 / rate})
        print(f"  {n:>10d} trajectories x {n_steps} steps: {rate / 1e6:8.2f} M/s "
              f"({1e9 / rate:.2f} ns per trajectory-step)", flush=True)
    result["scaling_trajectories"] = scaling
    threads = {}
    for k in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
        numba.set_num_threads(k)
        seconds, _ = timed(lambda: run_sweep(scene, theta0, omega0, thread_steps))
        threads[k] = n_traj * thread_steps / seconds
        print(f"  {k} thread(s): {threads[k] / 1e6:8.2f} M/s", flush=True)
    numba.set_num_threads(n_threads)
    result["scaling_threads"] = {"steps": thread_steps, "traj_steps_per_s": threads,
                                 "speedup_2_vs_1": threads.get(2, math.nan) / threads[1]}

    # --- the full scene again, now (the denominator of every ratio): on a shared
    # machine a burst of other work during its first timing would skew all ratios
    seconds, _ = timed(lambda: run_sweep(scene_of(), theta0, omega0, steps))
    first = thr[full_name]
    first["seconds_each_time"] = [first["seconds"], seconds]
    if seconds < first["seconds"]:
        first["seconds"] = seconds
        first["traj_steps_per_s"] = n_traj * steps / seconds
    sweep_full = first["traj_steps_per_s"]
    print(f"  {full_name} (timed again at the end; best kept): "
          f"{sweep_full / 1e6:.2f} M/s", flush=True)

    # --- the C limit and sweep side by side: alternating calls, best of each
    if c_limit is not None:
        rounds = max(c_rounds, REPEATS)
        best_c = best_sweep = math.inf
        for _ in range(rounds):
            seconds, _ = timed(lambda: run_sweep(scene_of(), theta0, omega0, steps),
                               repeats=1)
            best_sweep = min(best_sweep, seconds)
            seconds, _ = timed(lambda: call_c(c_limit["fn"], th0, om0, steps), repeats=1)
            best_c = min(best_c, seconds)
        first["seconds_each_time"].append(best_sweep)
        if best_sweep < first["seconds"]:
            first["seconds"] = best_sweep
            first["traj_steps_per_s"] = n_traj * steps / best_sweep
        sweep_full = first["traj_steps_per_s"]
        label = f"the C limit: {c_limit['name']}"
        record(label, best_c, group="C", flags=c_limit["flags"])
        agree(label, call_c(c_limit["fn"], th0, om0, steps))
        c_rate, sweep_rate = n_traj * steps / best_c, n_traj * steps / best_sweep
        result["c_limit"] = {
            "variant": c_limit["name"], "row": label, "flags": c_limit["flags"],
            "compile": " ".join(["gcc", *c_limit["flags"], "pendulum.c", "-lm"]),
            "block": c_limit["block"], "traj_steps_per_s": c_rate,
            "sweep_traj_steps_per_s": sweep_rate, "sweep_over_c_limit": sweep_rate / c_rate,
            "rounds": rounds, "check": result["c_check"][f"C limit search: {c_limit['name']}"],
            "sine": result["c_sine"][f"C limit search: {c_limit['name']}"]}
        print(f"\nthe C limit: {c_rate / 1e6:.1f} M trajectory-steps/s\n"
              f"  {c_limit['name']}\n  {result['c_limit']['compile']}\n"
              f"  its sine: {sine_text(result['c_limit']['sine'])}\n"
              f"sweep.run, full scene: {sweep_rate / 1e6:.1f} M trajectory-steps/s\n"
              f"sweep / C limit: {sweep_rate / c_rate:.3f}  (best of {rounds} alternating "
              "calls each)\n", flush=True)
    c_build.cleanup()

    # --- ratios (all from this run)
    ratios = {name: v["traj_steps_per_s"] / sweep_full for name, v in thr.items()}
    result["ratio_to_sweep_full_scene"] = ratios
    if "c_limit" in result:
        result["sweep_over_c_limit"] = result["c_limit"]["sweep_over_c_limit"]
        c_libm = thr.get("C, -march=native, libm sin, no FMA")
        if c_libm:
            result["sweep_over_C_libm"] = sweep_full / c_libm["traj_steps_per_s"]
    result["total_seconds"] = time.perf_counter() - total
    result["load_average_1min"] = {"start": load_start, "end": os.getloadavg()[0]}

    args.out.mkdir(parents=True, exist_ok=True)
    stem = "run_all_quick" if args.quick else "run_all"  # a smoke test keeps the results
    (args.out / f"{stem}.json").write_text(json.dumps(result, indent=2))
    md = markdown(result)
    (args.out / f"{stem}.md").write_text(md)
    chart(result, args.out / f"{stem}.png")
    print(md)
    print(f"wrote {args.out / stem}.json, .md, .png ({result['total_seconds']:.0f} s)")
    return 0


def load_warning(r) -> list[str]:
    """A warning line when other processes were busy on the machine during the run."""
    load = r["load_average_1min"]
    cores = os.cpu_count() or 1
    if load["start"] < 0.25 * cores:
        return []
    return [f"**Note:** the 1-minute load average was {load['start']:.1f} when this run "
            f"started ({load['end']:.1f} at its end, {cores} cores; it averages the minute "
            "before, earlier benchmarks included): if other processes were using the CPU, "
            "the rates below are lower bounds and the ratios noisy. The full scene and its "
            "general kernel (the same kernel) show how noisy. Re-run on an idle machine or "
            "with `--repeats 3` to be sure.", ""]


def markdown(r) -> str:
    w = r["workload"]
    lines = [f"# sweep benchmark suite ({r['mode']}, best of {r['repeats']})", "",
             f"Machine: {r['machine']}", "",
             *machine_lines(r), "",
             f"Workload: damped (c = {w['damping']}), forced (A = {w['amplitude']}, "
             f"W = {w['frequency']:.4g}), nonlinear pendulum, g/L = {w['g_over_L']}, "
             f"{w['trajectories']} trajectories x {w['steps']} RK4 steps (dt = {w['dt']}), "
             "float64, final state only. All numbers from this one run; rates in "
             "trajectory-steps per second; ratio to `sweep.run` on the full scene.", "",
             *load_warning(r),
             "| what | M traj-steps/s | ratio | max abs diff from sweep | note |",
             "|---|---|---|---|---|"]
    for name, v in r["throughput"].items():
        note = f"{v['trajectories']} trajectories, extrapolated" \
            if "extrapolated_from" in v else ""
        diff = r["agreement"].get(name)
        lines.append(f"| {name} | {v['traj_steps_per_s'] / 1e6:.3g} | "
                     f"{r['ratio_to_sweep_full_scene'][name]:.3g} | "
                     f"{'' if diff is None else f'{diff:.1e}'} | {note} |")
    lines += [""] + [f"- {n}" for n in r["notes"]]
    lines += [
        "- `[general kernel]`: `sweep.run(..., specialize=False)`, every term present and "
        "the absent effects fed zeros. For the full scene it is the same kernel as the "
        "specialised one, so that pair shows the run-to-run noise. The full scene is timed "
        "at the start and again at the end of the run; the better time is shown.",
        "- Max abs diff: final theta and omega against `sweep.run`'s, over the same "
        "trajectories. sweep uses the polynomial sine of `sweep.kernels.vecmath` and fuses "
        "the multiply-adds it writes explicitly (FMA); the alternatives use libm's or glibc's "
        "vector sine "
        "(each within an ulp of sin) and fuse other products or none. This workload is "
        "chaotic (c = 0.5, A = 1.2, W = 2/3): over 2000 steps it amplifies those "
        "last-bit differences to about 1e-10. That is the same work done with "
        "different (equally accurate) roundings. DOP853 differs by its own error and "
        "RK4's.",
        "- `[forcing sine per lane]`: the kernel `sweep.run` uses when the grid varies "
        "the forcing frequency or phase: sin(W t + phase) for every trajectory instead "
        "of once per step for a block of 64; the same bits (`tests/test_blocks.py`).",
        "- SciPy and pure Python run a subset of the trajectories, and the throughput is "
        "extrapolated (the trajectories are independent).",
    ]
    if "c_limit" in r:
        c = r["c_limit"]
        lines += [
            "", "## The C limit", "",
            f"The fastest C of the same algorithm this run could build, "
            f"`benchmarks/c_reference/pendulum.c`: **{c['traj_steps_per_s'] / 1e6:.0f} M "
            f"trajectory-steps/s**, {c['variant']} (block {c['block']} trajectories), "
            f"built with `{c['compile']}`; its sine: {sine_text(c['sine'])}. "
            f"`sweep.run` on the same full scene in the same "
            f"window: **{c['sweep_traj_steps_per_s'] / 1e6:.0f} M/s**, "
            f"**sweep / C limit = {c['sweep_over_c_limit']:.2f}** (target >= 0.9; best of "
            f"{c['rounds']} alternating calls of each). sweep / C with libm sin: "
            f"{r.get('sweep_over_C_libm', math.nan):.2f}.", "",
            "The search: one build per block size (sweep's polynomial sine in SIMD "
            "lanes, FMA contraction, the forcing sine computed once per step for the "
            "whole call), then, at the best block, one option changed at a time, then "
            "the sine's design: one reduction by pi (`k = round(x/pi)` by the magic "
            "number, `r = x - k pi` in two FMAs), one odd polynomial on [-pi/2, pi/2] "
            "(Taylor, or a minimax fit from `benchmarks/fit_sine.py`), Horner or Estrin, "
            "the sign from k's parity; the fastest eligible design then at every other "
            "block size. Each build is timed once on the full workload (differences "
            "under ~5 % are noise on this machine) and must pass the agreement check "
            "below. **The sine contract**: sweep's sine is within "
            f"{SINE_CONTRACT:.3g} (2**-52, two ulps of values in [0.5, 1)) of np.sin for "
            "|x| <= 1e4 and up to |x| = 1e12 (`tests/test_vecmath.py`; it measures "
            "1.1e-16); each build's own sine (`sines_sin`, the same inlined code) is "
            "measured against np.sin on the tests' kinds of arguments (random, every "
            "magnitude, next to multiples of pi/2 and pi/4, dyadic steps; beyond 1e4 "
            "random to 1e12 and multiples of pi/2 to 1e6), and a build that misses the "
            "contract is shown but cannot be the limit. The limit is the fastest build "
            "passing both, timed again beside `sweep.run`.", "",
            "| build | flags beyond `" + " ".join(C_BASE_FLAGS) + "` | M traj-steps/s "
            "| check: max abs diff from sweep | sine: max abs err, "
            + " / ".join(SINE_RANGES) + " | eligible |", "|---|---|---|---|---|---|"]
        for row in r["c_limit_search"]:
            extra = " ".join(f for f in row["flags"] if f not in C_BASE_FLAGS)
            errors = " / ".join(f"{e:.1e}" for e in row["sine_max_abs_error"].values())
            lines.append(f"| {row['name'].removeprefix('C limit search: ')} | `{extra}` | "
                         f"{row['traj_steps_per_s'] / 1e6:.0f} | "
                         f"{row['check_max_abs_diff']:.1e}"
                         f"{'' if row['check_ok'] else ' FAILS'} | {errors} | "
                         f"{'yes' if row['sine_eligible'] else '**no**'} |")
    if r.get("c_sine"):
        lines += ["", "Sine accuracy of every C build (max abs error against np.sin; "
                  f"contract {SINE_CONTRACT:.3g}):", "",
                  "| build | " + " | ".join(SINE_RANGES) + " |", "|---|---|---|"]
        seen = set()
        for name, v in r["c_sine"].items():
            name = re.sub(r", block \d+$", "", name.removeprefix("C limit search: "))
            if name in seen:
                continue  # one row per design: the block size does not change the sine
            seen.add(name)
            lines.append(f"| {name} | "
                         + " | ".join(f"{e:.1e}" for e in v["max_abs_error"].values())
                         + " |")
    if r.get("c_check"):
        worst = max(v["max_abs_diff"] for v in r["c_check"].values())
        lines += [
            "", f"Agreement check of every C build: the same trajectories, the full scene "
            f"for {C_CHECK_STEPS} steps (t = {C_CHECK_STEPS * DT:g}), final state against "
            f"`sweep.run`'s: max abs difference <= {C_CHECK_TOL:g} required; the largest "
            f"seen in this run is {worst:.1e}. Why a short horizon: the builds place FMAs "
            "differently from sweep's LLVM kernels (or use none, or another sine within an "
            "ulp), so each step differs by rounding (~1e-16 relative); over the full 2000 "
            "steps this scene, which is chaotic, amplifies such differences to ~1e-11 to "
            "1e-10 (the table's column), while over 100 steps they stay near 1e-15 and "
            f"{C_CHECK_TOL:g} leaves room for their growth but not for a different "
            "algorithm (a forcing evaluated at other times, a term missing, a less "
            "accurate sine: each changes the state after 100 steps by far more)."]
    lines += ["", "## Fast-math flags of the kernels", "",
              "The full scene with each set of numba fast-math flags (`reassoc` is never "
              "considered: it would reorder sums, drift from the NumPy oracle and break "
              "the exact argument reduction of `sweep.kernels.vecmath.sin`). `contract` lets "
              "LLVM fuse any a*b + c into one FMA, one rounding instead of two; the kernels "
              "write the FMAs they want explicitly (`vfma`) and run without it, because "
              "LLVM's choice of which product to fuse depended on the surrounding code, so "
              "on the block size. The flags apply to the kernel's own code; "
              "`sweep.kernels.vecmath.sin` is compiled once, at import, with the default "
              "flags, so every row keeps its sine.", "",
              "| flags | M traj-steps/s | max abs diff from the default | default |",
              "|---|---|---|---|"]
    for name, v in r["fastmath"].items():
        lines.append(f"| {name} | {v['traj_steps_per_s'] / 1e6:.3g} | "
                     f"{v['max_abs_diff_from_default']:.1e} | "
                     f"{'yes' if v['default'] else ''} |")
    lines += ["", "## sin in a numba loop", "",
              "| loop | M sin/s | vectorised (packed ymm/zmm arithmetic in its machine code) "
              "| max abs error vs np.sin |",
              "|---|---|---|---|"]
    for name, v in r["vecmath"].items():
        lines.append(f"| {name} | {v['sines_per_s'] / 1e6:.1f} | {v['vectorised']} | "
                     f"{v['max_abs_error_vs_np_sin']:.1e} |")
    s, m = r["startup"], r["memory"]
    lines += ["", "## Start-up and memory", "",
              f"- `import sweep`: {s['import_sweep_s']:.2f} s",
              f"- first `sweep.run` in a fresh process, cold cache (compiles): "
              f"{s['first_run_cold_cache_s']:.2f} s; warm on-disk cache: "
              f"{s['first_run_warm_cache_s']:.2f} s (target < 1 s)",
              f"- peak memory (VmHWM), {m['trajectories']} trajectories "
              f"({math.isqrt(m['trajectories'])}^2 grid), final state, {m['steps']} steps: "
              f"{m['peak_MiB']:.0f} MiB (VmHWM; before the run, after import and loading "
              f"the kernel: peak {m['hwm_before_run_MiB']:.0f} MiB, resident "
              f"{m['rss_before_run_MiB']:.0f} MiB; ru_maxrss {m['ru_maxrss_MiB']:.0f} MiB, "
              "which on Linux also counts the parent's memory at exec; "
              f"dataset {m['output_MiB']:.0f} MiB; target < 1024 MiB)",
              "", "## Scaling", "",
              "| trajectories | steps | M traj-steps/s | ns per traj-step |", "|---|---|---|---|"]
    for row in r["scaling_trajectories"]:
        lines.append(f"| {row['trajectories']:.3g} | {row['steps']} | "
                     f"{row['traj_steps_per_s'] / 1e6:.2f} | {row['ns_per_traj_step']:.2f} |")
    t = r["scaling_threads"]
    lines += ["", "| threads | M traj-steps/s |", "|---|---|"]
    for k, v in t["traj_steps_per_s"].items():
        lines.append(f"| {k} | {v / 1e6:.2f} |")
    lines += ["", f"2 threads / 1 thread: {t['speedup_2_vs_1']:.2f} (target >= 1.8)", ""]
    return "\n".join(lines)


def chart(r, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    items = sorted(r["throughput"].items(), key=lambda kv: kv[1]["traj_steps_per_s"])
    colours = {"sweep": "tab:blue", "alternative": "tab:gray", "C": "tab:orange"}
    fig, ax = plt.subplots(figsize=(10, 0.32 * len(items) + 1.5))
    ax.barh([name for name, _ in items], [v["traj_steps_per_s"] for _, v in items],
            color=[colours.get(v.get("group"), "tab:gray") for _, v in items])
    ax.set_xscale("log")
    ax.set_xlabel("trajectory-steps per second (log)")
    w = r["workload"]
    ax.set_title(f"{w['trajectories']} trajectories x {w['steps']} RK4 steps, float64\n"
                 f"{r['machine']}", fontsize=9)
    ax.tick_params(axis="y", labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
