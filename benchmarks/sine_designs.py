"""sweep's sine against other designs in numba (issues 29 and 38).

The designs, written with the conventions of `sweep.kernels.vecmath` (explicit
`vecmath.fma`, the kernels' JIT flags, i.e. no fast-math, branch-free selects):

* **sweep** (`vecmath.sin` since 2026-11-27): ``k = round(x/pi)`` by the magic number,
  ``r = x - k pi`` in two FMAs (|r| <= pi/2), one odd polynomial ``r + r^3 P(r^2)``
  (the minimax fit of degree 17 from ``fit_sine.py``) with ``P = M1 + z T``, T by
  Estrin's scheme and M1 added last, the sign from k's parity applied to ``r`` beside
  ``z = r^2``;
* **quadrant** (`sin_quadrant`: `vecmath.sin` before, and `vecmath.cos` still): ``k =
  round(x 2/pi)``, ``r = x - k pi/2`` (|r| <= pi/4), one of two fdlibm polynomials
  (sine or cosine) chosen by the quadrant through selects, Estrin, the sign by quadrant;
* **pi** (`sin_pi`, the C limit's sine): the reduction by pi, the same polynomial by
  Horner's scheme. ``cos_pi`` reduces by the odd multiples of pi/2 (``x = (2k + 1) pi/2
  + r``, the same polynomial; not exact for tiny x, which a test of vecmath asks), and
  ``sincos_pi`` is the pair; ``pi_split`` evaluates the tail by Estrin and the head by
  Horner; ``pi_estrin`` all by Estrin (misses the contract: 3 ulps at about one
  argument in 1e8).

Default run, each timing the best of ``--repeats`` rounds in which the designs
alternate (the machine is shared, so single timings are noisy):

* **throughput**: a numba loop ``out[i] = sin(x[i])`` over 2**22 arguments in [-50, 50]
  (vectorised by LLVM: checked in the machine code), sines per second;
* **latency**: one dependent chain ``x = sin(x) * 3 + 0.5`` (chaotic, all quadrants;
  10**7 calls), ns per call, and in cycles by the latency of a chain of dependent FMAs
  timed in the same process (4 cycles an FMA on Zen 4/5 and on Intel's AVX-512 cores);
* **in an RK4 kernel**: run_all's full scene (2**17 trajectories x 2000 steps of the
  forced damped pendulum) in blocks of lanes with each sine (M trajectory-steps/s), and
  one trajectory alone (the narrow path: its steps wait on each other's sines);
* **sweep.run itself** on that scene, its kernels built on the pi sine against sweep's
  (fresh processes, vecmath's sin/cos/sincos replaced before a kernel is generated, a
  cache folder each; the designs alternate, 3 rounds);
* **accuracy**: the inputs and bounds of ``tests/test_vecmath.py`` (2**-52 absolute up
  to 1e12, 2.3e-16 |x| for small x, 4.5e-16 relative next to multiples of pi, the
  cosine equal to np.cos for tiny x, the same bits under a caller's FMA contraction,
  sincos = (sin, cos), NaN and inf), each design checked, plus the error past 1e12.

``--in-kernels`` (issue 38) instead times sweep's own kernels with each of
`KERNEL_DESIGNS` (sin, cos and sincos as vecmath would export them): a worker process
per design, the workloads of `KERNEL_SIZES` (the full scene, a basins map with early
stop and lane refill, the double pendulum, float32, one trajectory alone, the tangent
dynamics of ``lyapunov``), designs and workloads interleaved round by round; medians,
spreads and round-by-round ratios, and the outputs' digests. Writes
``results/sine_designs_kernels.{json,md}``; the default run ``results/sine_designs.*``.

Usage::

    python benchmarks/sine_designs.py                        # ~1 min
    python benchmarks/sine_designs.py --in-kernels --repeats 21   # ~10 min on 2 cores
    python benchmarks/sine_designs.py --quick                # small sizes: a smoke test
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit, prange

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from sweep import _config  # noqa: E402
from sweep.kernels import vecmath  # noqa: E402
from sweep.kernels.vecmath import fma  # noqa: E402

from _timing import best_alternating  # noqa: E402

_JIT = _config.jit_options()
_bits_of = vecmath._bits_of  # the IEEE bits of a float64 (a bitcast)
#: the C references' base flags (`_c_builds.C_BASE_FLAGS`): compile_library adds them
C_BASE_FLAGS_SET = {"-O3", "-march=native", "-fopenmp", "-shared", "-fPIC"}

# ------------------------------------------------------------------- the candidate
INV_PI = 0.3183098861837907
#: pi = PI_HI + PI_LO - 3.0e-33: the reduction's two parts (``k PI_HI`` is subtracted
#: exactly by the first FMA, ``k PI_LO`` with one rounding by the second)
PI_HI = 3.141592653589793         # 0x1.921fb54442d18p+1
PI_LO = 1.2246467991473532e-16    # 0x1.1a62633145c07p-53
PIO2_HI, PIO2_LO = vecmath.PIO2_HI, vecmath.PIO2_LO
_MAGIC = 6755399441055744.0       # 1.5 * 2**52
#: sin r ~ r + r^3 P(r^2) on |r| <= pi/2 + 1e-4: the minimax fit of the relative error,
#: degree 17 (``benchmarks/fit_sine.py``; its error with these float64 coefficients,
#: in mpmath: 2.9e-19)
M1 = -0.16666666666666666
M2 = 0.008333333333333207
M3 = -0.0001984126984121248
M4 = 2.7557319211569482e-06
M5 = -2.505210690442292e-08
M6 = 1.6058941002310493e-10
M7 = -7.643019371886964e-13
M8 = 2.7214195512770984e-15


@njit(cache=True, **_JIT)
def _odd_poly(r):
    """sin r for |r| <= pi/2 (+1e-4): r + r^3 P(r^2), P by Horner, every multiply-add
    fused (`fma`)."""
    z = r * r
    p = fma(fma(fma(fma(fma(fma(fma(M8, z, M7), z, M6), z, M5), z, M4), z, M3), z, M2),
            z, M1)
    return fma(r * z, p, r)


@njit(cache=True, **_JIT)
def _odd_poly_estrin(r):
    """The same polynomial by Estrin's scheme (pairs, then z^2, z^4): depth 4 instead of
    8, one more rounding path (misses the contract: 3 ulps, rarely)."""
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    p = fma(z4, fma(z2, fma(z, M8, M7), fma(z, M6, M5)),
            fma(z2, fma(z, M4, M3), fma(z, M2, M1)))
    return fma(r * z, p, r)


@njit(cache=True, **_JIT)
def sin_pi(x):
    """sin(x) by one reduction by pi: ``k = round(x/pi)`` (the magic number: valid for
    |x/pi| < 2**51), ``r = x - k pi`` (two FMAs), ``sin x = (-1)**k sin r``; k's parity
    is the low bit of the magic sum."""
    y = fma(x, INV_PI, _MAGIC)
    kf = y - _MAGIC
    r = fma(-kf, PI_LO, fma(-kf, PI_HI, x))
    v = _odd_poly(r)
    return -v if (_bits_of(y) & 1) else v


@njit(cache=True, **_JIT)
def cos_pi(x):
    """cos(x) = (-1)**(k+1) sin(r) with ``x = (2k + 1) pi/2 + r``, ``k = round(x/pi -
    1/2)``: the reduction by the odd multiples of pi/2 (|r| <= pi/2), the sine's
    polynomial. (cos(x) as sin(x + pi/2) would round x + pi/2 first.)"""
    y = fma(x, INV_PI, -0.5) + _MAGIC
    kf = y - _MAGIC
    mf = 2.0 * kf + 1.0
    r = fma(-mf, PIO2_LO, fma(-mf, PIO2_HI, x))
    v = _odd_poly(r)
    return v if (_bits_of(y) & 1) else -v


@njit(cache=True, **_JIT)
def sincos_pi(x):
    """(sin_pi(x), cos_pi(x)): two reductions and two polynomials, the bits of each."""
    return sin_pi(x), cos_pi(x)


@njit(cache=True, **_JIT)
def sin_pi_estrin(x):
    y = fma(x, INV_PI, _MAGIC)
    kf = y - _MAGIC
    r = fma(-kf, PI_LO, fma(-kf, PI_HI, x))
    v = _odd_poly_estrin(r)
    return -v if (_bits_of(y) & 1) else v


@njit(cache=True, **_JIT)
def _odd_poly_split(r):
    """The same polynomial, its tail ``M3 + M4 z + ... + M8 z^5`` by Estrin's scheme (in
    z and z^2: it adds less than 2e-4 to P, so its roundings are below 1e-19 of the
    sine) and its head ``M1 + z (M2 + z tail)`` by Horner, as ``_odd_poly``: depth 6
    multiply-adds after ``z`` instead of 8, the head's roundings (the error) unchanged."""
    z = r * r
    z2 = z * z
    t = fma(z2, fma(z2, fma(z, M8, M7), fma(z, M6, M5)), fma(z, M4, M3))
    p = fma(fma(t, z, M2), z, M1)
    return fma(r * z, p, r)


@njit(cache=True, **_JIT)
def sin_pi_split(x):
    """`sin_pi` with `_odd_poly_split`."""
    y = fma(x, INV_PI, _MAGIC)
    kf = y - _MAGIC
    r = fma(-kf, PI_LO, fma(-kf, PI_HI, x))
    v = _odd_poly_split(r)
    return -v if (_bits_of(y) & 1) else v


@njit(cache=True, **_JIT)
def cos_pi_split(x):
    """`cos_pi` with `_odd_poly_split`."""
    y = fma(x, INV_PI, -0.5) + _MAGIC
    kf = y - _MAGIC
    mf = 2.0 * kf + 1.0
    r = fma(-mf, PIO2_LO, fma(-mf, PIO2_HI, x))
    v = _odd_poly_split(r)
    return v if (_bits_of(y) & 1) else -v


@njit(cache=True, **_JIT)
def sincos_pi_split(x):
    return sin_pi_split(x), cos_pi_split(x)


@njit(cache=True, **_JIT)
def sincos_split_sweep_cos(x):
    """(sin_pi_split(x), vecmath.cos(x))."""
    return sin_pi_split(x), vecmath.cos(x)


@njit(cache=True, **_JIT)
def sin_quadrant(x):
    """vecmath.sin up to 2026-11-27 (its cos still): the reduction by pi/2, the sine's
    or the cosine's fdlibm polynomial by quadrant (coefficients chosen by selects),
    Estrin's scheme, the sign by quadrant."""
    r, q = vecmath._reduce(x)
    return vecmath._sine_of_reduced(r, q)


@njit(cache=True, **_JIT)
def sincos_once_each(x):
    """(sin_quadrant(x), vecmath.cos(x)) from one reduction by pi/2, the sine's and the
    cosine's polynomial evaluated once each, then swapped and signed by quadrant (the
    same bits as `sincos_select_twice`)."""
    r, q = vecmath._reduce(x)
    z = r * r
    z2 = z * z
    z4 = z2 * z2
    ps = fma(z4, fma(z, vecmath.S6, vecmath.S5),
             fma(z2, fma(z, vecmath.S4, vecmath.S3), fma(z, vecmath.S2, vecmath.S1)))
    pc = fma(z4, fma(z2, vecmath.C6, fma(z, vecmath.C5, vecmath.C4)),
             fma(z2, fma(z, vecmath.C3, vecmath.C2), fma(z, vecmath.C1, -0.5)))
    s_r = fma(z * r, ps, r)
    c_r = fma(z, pc, 1.0)
    odd = (q & 1) != 0
    s = c_r if odd else s_r
    c = s_r if odd else c_r
    s = -s if (q & 2) else s
    c = -c if ((q + 1) & 2) else c
    return s, c


@njit(cache=True, **_JIT)
def sincos_select_twice(x):
    """vecmath.sincos before 2026-11-27: the select-by-quadrant polynomial twice, for
    the quadrant and the next (the bits of `sin_quadrant` and vecmath.cos)."""
    r, q = vecmath._reduce(x)
    return vecmath._sine_of_reduced(r, q), vecmath._sine_of_reduced(r, q + 1)


#: The designs timed inside sweep's own kernels (`in_kernels`): (sin, cos, sincos) as
#: `sweep.kernels.vecmath` would export them; the attribute names are looked up in this
#: module or, prefixed ``vecmath.``, in vecmath.
KERNEL_DESIGNS = {
    "before": ("sin_quadrant", "vecmath.cos", "sincos_select_twice"),
    "before_once": ("sin_quadrant", "vecmath.cos", "sincos_once_each"),
    "pi": ("sin_pi", "cos_pi", "sincos_pi"),
    "pi_split": ("sin_pi_split", "vecmath.cos", "sincos_split_sweep_cos"),
    "sweep": ("vecmath.sin", "vecmath.cos", "vecmath.sincos"),
}
KERNEL_DESCRIPTION = {
    "before": "sweep's sine up to 2026-11-27 (`sin_quadrant`; `vecmath.cos`; sincos = "
              "the select-by-quadrant polynomial twice)",
    "before_once": "the same, sincos evaluating the sine's and the cosine's polynomial "
                   "once each (the same bits)",
    "pi": "one reduction by pi, degree-17 minimax by Horner (the C limit's sine); cos "
          "by the odd multiples of pi/2 (not exact for tiny x: fails a test); sincos = "
          "two reductions",
    "pi_split": "the pi sine, its polynomial's tail by Estrin, head by Horner; "
                "`vecmath.cos`; sincos = (sin, cos)",
    "sweep": "vecmath today: the pi sine, M2.. by Estrin and M1 last, the sign folded "
             "into r; `vecmath.cos`; sincos = (sin, cos)",
}


DESIGNS = {"sweep": vecmath.sin, "quadrant": sin_quadrant, "pi": sin_pi,
           "pi_estrin": sin_pi_estrin, "pi_split": sin_pi_split}
DESCRIPTION = {
    "sweep": "sweep's vecmath.sin since 2026-11-27: one reduction by pi, minimax degree "
             "17, M2.. by Estrin and M1 last, the sign folded into r",
    "quadrant": "sweep's sine before: reduction by pi/2, sine or cosine polynomial by "
                "quadrant (selects), Estrin",
    "pi": "the C limit's: one reduction by pi, minimax degree-17 odd polynomial, Horner",
    "pi_estrin": "one reduction by pi, the same polynomial by Estrin (misses the contract)",
    "pi_split": "one reduction by pi, the same polynomial, its tail by Estrin, head by Horner",
}


# ------------------------------------------------------------------ timing harnesses
def _loop(sine):
    @njit(cache=False, **_JIT)
    def loop(x, out):
        for i in range(x.size):
            out[i] = sine(x[i])
    return loop


def _chain(sine):
    @njit(cache=False, **_JIT)
    def chain(x, n):
        for _ in range(n):
            x = fma(sine(x), 3.0, 0.5)
        return x
    return chain


@njit(cache=False, **_JIT)
def fma_chain(x, n):
    """n dependent FMAs (4 cycles each on Zen 4/5 and Intel's AVX-512 cores): the clock."""
    for _ in range(n):
        x = fma(x, 0.9999999, 1e-7)
    return x


def _rk4(sine):
    """run_all's full scene in numba, as the C limit lays it out: blocks of lanes
    (prange over blocks, time loop, lane loop innermost), a forcing table per call."""
    block = 512

    @njit(parallel=True, cache=False, **_JIT)
    def rk4(th0, om0, fnode, fhalf, steps, w0sq, c, dt):
        n = th0.size
        th_out, om_out = np.empty(n), np.empty(n)
        dt_2, dt_6 = dt / 2.0, dt / 6.0
        for b in prange((n + block - 1) // block):
            start = b * block
            m = min(block, n - start)
            th, om = np.zeros(block), np.zeros(block)
            th[:m], om[:m] = th0[start:start + m], om0[start:start + m]
            for step in range(steps):
                f0, f1, f2 = fnode[step], fhalf[step], fnode[step + 1]
                for j in range(block):
                    x, v = th[j], om[j]
                    k1t = v
                    k1o = -w0sq * sine(x) - c * k1t + f0
                    k2t = v + dt_2 * k1o
                    k2o = -w0sq * sine(x + dt_2 * k1t) - c * k2t + f1
                    k3t = v + dt_2 * k2o
                    k3o = -w0sq * sine(x + dt_2 * k2t) - c * k3t + f1
                    k4t = v + dt * k3o
                    k4o = -w0sq * sine(x + dt * k3t) - c * k4t + f2
                    th[j] = x + dt_6 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
                    om[j] = v + dt_6 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o)
            th_out[start:start + m], om_out[start:start + m] = th[:m], om[:m]
        return th_out, om_out
    return rk4


def _one(sine):
    """One trajectory alone: every step waits on the previous step's sines."""
    @njit(cache=False, **_JIT)
    def one(th, om, fnode, fhalf, steps, w0sq, c, dt):
        dt_2, dt_6 = dt / 2.0, dt / 6.0
        for step in range(steps):
            f0, f1, f2 = fnode[step], fhalf[step], fnode[step + 1]
            k1t = om
            k1o = -w0sq * sine(th) - c * k1t + f0
            k2t = om + dt_2 * k1o
            k2o = -w0sq * sine(th + dt_2 * k1t) - c * k2t + f1
            k3t = om + dt_2 * k2o
            k3o = -w0sq * sine(th + dt_2 * k2t) - c * k3t + f1
            k4t = om + dt * k3o
            k4o = -w0sq * sine(th + dt * k3t) - c * k4t + f2
            th = th + dt_6 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
            om = om + dt_6 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o)
        return th, om
    return one


def forcing(steps, amplitude=1.2, frequency=2.0 / 3.0, dt=0.01):
    """f(t_n) for n = 0..steps and f(t_n + dt/2): sweep's forcing times."""
    n = np.arange(steps + 1)
    fnode = amplitude * np.sin(frequency * (n * dt))
    fhalf = amplitude * np.sin(frequency * (n[:-1] * dt + dt * 0.5))
    return fnode, fhalf


def vectorised(fn) -> bool:
    asm = "".join(fn.inspect_asm().values())
    return re.search(r"\bv(?:mul|add|sub|fmadd\w*)pd\s+%?[yz]mm", asm) is not None


# ------------------------------------------------------------- sweep.run with each sine
#: One process: sweep.run on run_all's full scene with sweep's kernels built on the
#: given sine (vecmath's sin/cos/sincos replaced before any kernel is generated: the
#: kernel modules import them when built; a cache folder of its own per design, so no
#: kernel of the other design is loaded from disk). Prints best seconds and the state.
SWEEP_RUN = """
import json, sys, time
import numpy as np
sys.path.insert(0, {bench!r})
import sweep
from sweep.kernels import vecmath
if {design!r} == "pi":
    import sine_designs as sd
    vecmath.sin, vecmath.cos, vecmath.sincos = sd.sin_pi, sd.cos_pi, sd.sincos_pi
from _c_builds import AMPLITUDE, DAMPING, DT, FREQUENCY, G_OVER_L, PHASE, grid_axes
theta0, omega0 = grid_axes({n})
scene = sweep.Scene(gravity=G_OVER_L, length=1.0, effects=(sweep.Damping(DAMPING),
                    sweep.Forcing(AMPLITUDE, FREQUENCY, PHASE)))
grid = sweep.Grid(theta0=theta0, omega0=omega0)
kw = dict(t_end={steps} * DT, dt=DT, observe=("final",), progress=False)
sweep.run(scene, grid, **kw)
best = float("inf")
for _ in range({repeats}):
    start = time.perf_counter()
    ds = sweep.run(scene, grid, **kw)
    best = min(best, time.perf_counter() - start)
np.save({state!r}, np.stack([ds.theta_final.values.ravel(), ds.omega_final.values.ravel()]))
print(json.dumps({{"seconds": best, "trajectories": int(theta0.size * omega0.size)}}))
"""


def sweep_run_with_each_sine(n, steps, rounds, repeats=2) -> dict:
    """sweep.run on the full scene with sweep's sine and with the candidate: fresh
    processes, the designs alternating for ``rounds`` rounds, each process the best of
    ``repeats`` runs after a warm-up; the first round compiles (its own cache folder)."""
    out = {name: {"seconds": math.inf} for name in ("sweep", "pi")}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(rounds):
            for name, v in out.items():
                state = str(Path(tmp) / f"{name}.npy")
                code = SWEEP_RUN.format(bench=str(HERE), design=name, n=n, steps=steps,
                                        repeats=repeats, state=state)
                env = dict(os.environ, SWEEP_CACHE_DIR=str(Path(tmp) / f"cache_{name}"),
                           PYTHONPATH=str(HERE.parent))
                proc = subprocess.run([sys.executable, "-c", code], capture_output=True,
                                      text=True, env=env, check=False)
                if proc.returncode != 0:
                    raise RuntimeError(proc.stderr)
                got = json.loads(proc.stdout.strip().splitlines()[-1])
                v["seconds"] = min(v["seconds"], got["seconds"])
                v["traj_steps_per_s"] = got["trajectories"] * steps / v["seconds"]
        a, b = np.load(Path(tmp) / "sweep.npy"), np.load(Path(tmp) / "pi.npy")
    out["pi"]["max_abs_diff_from_sweep_sine"] = float(np.max(np.abs(a - b)))
    return out


# ------------------------------------------- sweep's own kernels on each design (issue 38)
#: One worker process per design: vecmath's sin/cos/sincos replaced before any kernel is
#: generated (the generated modules import them when they are executed), its own cache
#: folders, each workload run once to compile, then one timed run per line read from
#: stdin (the workload's name), answered with the seconds and a digest of the outputs.
KERNEL_WORKER = """
import hashlib, json, math, sys, time
import numpy as np
sys.path.insert(0, {bench!r})
import sweep
from sweep.kernels import vecmath
import sine_designs as sd
def get(name):
    return getattr(vecmath, name[8:]) if name.startswith("vecmath.") else getattr(sd, name)
vecmath.sin, vecmath.cos, vecmath.sincos = [get(n) for n in {names!r}]
from _c_builds import AMPLITUDE, DAMPING, DT, FREQUENCY, G_OVER_L, PHASE, grid_axes
import double_pendulum as dp
sizes = {sizes!r}
scene = sweep.Scene(gravity=G_OVER_L, length=1.0, effects=(sweep.Damping(DAMPING),
                    sweep.Forcing(AMPLITUDE, FREQUENCY, PHASE)))
full = sweep.Grid(**dict(zip(("theta0", "omega0"), grid_axes(sizes.get("full", (2, 1))[0]))))
kw = dict(dt=DT, observe=("final",), progress=False)
period = 2 * math.pi
basin_scene = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.2),
                          sweep.Forcing(1.66, 1.0, math.pi / 2)))
nb = sizes.get("basins", (2, 1))[0]
basin_grid = sweep.Grid(theta0=np.linspace(-math.pi, math.pi, nb),
                        omega0=np.linspace(-4.0, 4.0, nb))
th1, th2 = dp.start_axes(sizes.get("double", (2, 1))[0])
lyap = sweep.Grid(**dict(zip(("theta0", "omega0"), grid_axes(sizes.get("lyapunov", (2, 1))[0]))))
work = {{
    "full": lambda: sweep.run(scene, full, t_end=sizes["full"][1] * DT, **kw),
    "basins": lambda: sweep.run(basin_scene, basin_grid, t_end=sizes["basins"][1] * period,
                                dt=period / 100, t_transient=20 * period,
                                observe=("strobe",), stop_early=True, progress=False),
    "double": lambda: dp.run_sweep(th1, th2, sizes["double"][1]),
    "float32": lambda: sweep.run(scene, full, t_end=sizes["float32"][1] * DT,
                                 dtype="float32", **kw),
    "one": lambda: sweep.run(scene, sweep.Grid(theta0=[0.1], omega0=[0.0]),
                             t_end=sizes["one"][1] * DT, **kw),
    "lyapunov": lambda: sweep.run(scene, lyap, t_end=sizes["lyapunov"][1] * DT, dt=DT,
                                  observe=("lyapunov",), progress=False),
}}
work = {{k: v for k, v in work.items() if k in sizes}}
def digest(ds):
    return hashlib.sha1(b"".join(np.ascontiguousarray(ds[v].values).tobytes()
                                 for v in sorted(ds.data_vars))).hexdigest()[:16]
for fn in work.values():
    fn(); fn()
print(json.dumps({{"ready": True}}), flush=True)
for line in sys.stdin:
    fn = work[line.strip()]
    start = time.perf_counter()
    ds = fn()
    seconds = time.perf_counter() - start
    print(json.dumps({{"seconds": seconds, "digest": digest(ds)}}), flush=True)
"""

#: The workloads of `in_kernels`: (trajectories, steps) (basins: periods of 100 steps,
#: early stop with lane refill; its work is reported per started trajectory and period).
KERNEL_SIZES = {"full": (2**16, 1000), "basins": (100, 320), "double": (2**15, 1000),
                "float32": (2**16, 1000), "one": (1, 5 * 10**5), "lyapunov": (2**14, 1000)}
KERNEL_SIZES_QUICK = {"full": (2**10, 100), "basins": (16, 40), "double": (2**10, 50),
                      "float32": (2**10, 100), "one": (1, 10**4), "lyapunov": (2**10, 50)}
KERNEL_WHAT = {
    "full": "run_all's full scene (damped, forced), final state",
    "basins": "forced basins map (damping 0.2, forcing 1.66), strobe, early stop with lane "
              "refill (rate: started trajectories x periods x 100 steps)",
    "double": "double pendulum (double_pendulum.py's grid), final state",
    "float32": "the full scene in float32 (sin32: not changed by the float64 designs; "
               "a control of the noise)",
    "one": "one trajectory of the full scene alone (the narrow path: the sine's latency)",
    "lyapunov": "the full scene with observe=('lyapunov',) (tangent dynamics: sincos)",
}


def _start_worker(name: str, sizes: dict, tmp: str):
    """The worker process of design ``name`` (`KERNEL_WORKER`), once it has compiled."""
    env = dict(os.environ, SWEEP_CACHE_DIR=str(Path(tmp) / f"c_{name}"),
               NUMBA_CACHE_DIR=str(Path(tmp) / f"n_{name}"), PYTHONPATH=str(HERE.parent))
    code = KERNEL_WORKER.format(bench=str(HERE), names=KERNEL_DESIGNS[name], sizes=sizes)
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    if not proc.stdout.readline():
        raise RuntimeError(f"the worker of design {name!r} failed")
    return proc


def _ask(proc, workload: str) -> dict:
    proc.stdin.write(workload + "\n")
    proc.stdin.flush()
    return json.loads(proc.stdout.readline())


#: --vs-c-limit: run_all's and double_pendulum.py's workloads at full size.
LIMIT_SIZES = {"full": (2**17, 2000), "double": (2**17, 1000)}
LIMIT_SIZES_QUICK = {"full": (2**10, 100), "double": (2**10, 50)}


def vs_c_limit(designs, rounds: int, quick: bool, log=print) -> dict:
    """``sweep.run`` with each design against the C limits of ``run_all.py`` (the
    pendulum) and ``double_pendulum.py``, all timed in one process, round by round: the
    C limit's build as committed in ``results/run_all.json`` and
    ``results/double_pendulum.json`` (the minimax sine by Horner) and the same build
    with sweep's sine (``-DHEAD``); the limit is the faster of the two (best time)."""
    sys.path.insert(0, str(HERE))
    import double_pendulum as dp

    from _c_builds import build_c_one, call_c, grid_axes, initial_states

    sizes = LIMIT_SIZES_QUICK if quick else LIMIT_SIZES
    limits = {"full": json.loads((HERE / "results" / "run_all.json").read_text())
              ["c_limit"]["flags"],
              "double": json.loads((HERE / "results" / "double_pendulum.json").read_text())
              ["c_limit"]["flags"]}
    th0, om0 = initial_states(*grid_axes(sizes["full"][0]))
    state = dp.starts(*dp.start_axes(sizes["double"][0]))
    calls, times = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for w, flags in limits.items():
            flags = [f for f in flags if f not in C_BASE_FLAGS_SET]
            for label, extra in (("C limit (Horner)", []), ("C, sweep's sine", ["-DHEAD"])):
                if w == "full":
                    fn = build_c_one(Path(tmp), label, flags + extra)
                    calls[(w, label)] = (lambda fn=fn: call_c(fn, th0, om0, sizes["full"][1]))
                else:
                    fn = dp.build_double(Path(tmp), flags + extra)
                    calls[(w, label)] = (lambda fn=fn: dp.call_double(fn, state,
                                                                      sizes["double"][1]))
                if isinstance(fn, str) or fn is None:
                    raise RuntimeError(f"{w} {label}: {fn}")
        workers = {}
        try:
            for name in designs:
                workers[name] = _start_worker(name, sizes, tmp)
                log(f"  worker {name}: compiled", flush=True)
            for call in calls.values():
                call()  # warm
            for _ in range(rounds):
                for w in sizes:
                    for (cw, label), call in calls.items():
                        if cw == w:
                            start = time.perf_counter()
                            call()
                            times.setdefault((w, label), []).append(
                                time.perf_counter() - start)
                    for name, proc in workers.items():
                        times.setdefault((w, name), []).append(_ask(proc, w)["seconds"])
        finally:
            for proc in workers.values():
                proc.stdin.close()
                proc.wait()
    out = {}
    for w, (n, steps) in sizes.items():
        c_labels = [label for (cw, label) in calls if cw == w]
        best_c = min(c_labels, key=lambda label: min(times[(w, label)]))
        c = np.array(times[(w, best_c)])
        row = {"trajectories": int(n), "steps": steps, "c_limit": best_c,
               "c_flags": limits[w], "rows": {}}
        for label in c_labels + list(designs):
            t = np.array(times[(w, label)])
            row["rows"][label] = {
                "seconds": t.tolist(), "best_M_per_s": n * steps / t.min() / 1e6,
                "median_M_per_s": float(np.median(n * steps / t / 1e6)),
                "over_c_limit_best": float(c.min() / t.min()),
                "over_c_limit_paired_median": float(np.median(c / t)),
                "over_c_limit_paired_quartiles": [float(q) for q in
                                                  np.percentile(c / t, [25, 75])]}
        out[w] = row
    return out


def vs_c_limit_markdown(r: dict) -> list[str]:
    lines = ["## sweep.run against the C limits, each design (one process, round by "
             "round)", "",
             "M trajectory-steps/s (best and median of the rounds) and the ratio to the C "
             "limit (the faster C build by best time): of the best times, and the median "
             "[quartiles] of the round-by-round ratios.", ""]
    for w, row in r.items():
        lines += [f"### {w} ({row['trajectories']} x {row['steps']}); C limit: "
                  f"{row['c_limit']}", "", "| what | best | median | vs C limit (best) | "
                  "vs C limit, paired median [quartiles] |", "|---|---|---|---|---|"]
        for label, v in row["rows"].items():
            q = v["over_c_limit_paired_quartiles"]
            lines.append(f"| {label} | {v['best_M_per_s']:.0f} | {v['median_M_per_s']:.0f} | "
                         f"{v['over_c_limit_best']:.3f} | "
                         f"{v['over_c_limit_paired_median']:.3f} [{q[0]:.2f} - {q[1]:.2f}] |")
        lines.append("")
    return lines


def in_kernels(designs, rounds: int, quick: bool, log=print) -> dict:
    """sweep.run's kernels on each design: a worker per design (`KERNEL_WORKER`), the
    designs and workloads interleaved, ``rounds`` timed runs of each; per workload and
    design the median, min and max rate (M trajectory-steps/s) and the outputs' digest
    (equal digests: bit-identical results)."""
    sizes = KERNEL_SIZES_QUICK if quick else KERNEL_SIZES
    workers, times = {}, {w: {d: [] for d in designs} for w in sizes}
    digests = {w: {} for w in sizes}
    with tempfile.TemporaryDirectory() as tmp:
        try:
            for name in designs:
                workers[name] = _start_worker(name, sizes, tmp)
                log(f"  worker {name}: compiled", flush=True)
            for _ in range(rounds):
                for w in sizes:
                    for name, proc in workers.items():
                        got = _ask(proc, w)
                        times[w][name].append(got["seconds"])
                        digests[w][name] = got["digest"]
        finally:
            for proc in workers.values():
                proc.stdin.close()
                proc.wait()
    out = {}
    for w, (n, steps) in sizes.items():
        work = n * n * steps * 100 if w == "basins" else n * steps
        out[w] = {"what": KERNEL_WHAT[w], "trajectories": n * n if w == "basins" else n,
                  "steps": steps * 100 if w == "basins" else steps, "designs": {}}
        base = np.array(times[w][designs[0]])
        for name in designs:
            t = np.array(times[w][name])
            rates = work / t / 1e6
            paired = base / t  # speed over the first design's, round by round
            out[w]["designs"][name] = {
                "seconds": t.tolist(), "median_M_per_s": float(np.median(rates)),
                "min_M_per_s": float(rates.min()), "max_M_per_s": float(rates.max()),
                "paired_ratio_median": float(np.median(paired)),
                "paired_ratio_quartiles": [float(q) for q in np.percentile(paired, [25, 75])],
                "best_ratio": float(base.min() / t.min()), "digest": digests[w][name]}
    return out


def in_kernels_markdown(r: dict, designs) -> list[str]:
    lines = ["## Inside sweep's kernels (`sweep.run`, a worker per design, interleaved)", "",
             "M trajectory-steps/s: median and [min - max] of the rounds; speed over the "
             f"first design (`{designs[0]}`): the median [quartiles] of the ratios taken "
             "round by round (the designs of a round run back to back, so a burst of the "
             "other sessions' work hits them alike), and the ratio of the best times; "
             "digest: the outputs' bits.", ""]
    lines += [f"- **{d}**: {KERNEL_DESCRIPTION[d]}" for d in designs]
    for w, row in r.items():
        lines += ["", f"### {w}: {row['what']} ({row['trajectories']} x {row['steps']})", "",
                  "| design | median | min - max | paired ratio [quartiles] | best ratio | "
                  "digest |", "|---|---|---|---|---|---|"]
        for d in designs:
            v = row["designs"][d]
            q = v["paired_ratio_quartiles"]
            lines.append(f"| {d} | {v['median_M_per_s']:.1f} | {v['min_M_per_s']:.1f} - "
                         f"{v['max_M_per_s']:.1f} | {v['paired_ratio_median']:.3f} "
                         f"[{q[0]:.2f} - {q[1]:.2f}] | {v['best_ratio']:.3f} | "
                         f"`{v['digest']}` |")
    return lines


# ------------------------------------------------------------------------- accuracy
def _vector(sine, jit=None):
    """``sine`` over an array, in parallel, compiled with ``jit`` (default: the kernels'
    options)."""
    @njit(parallel=True, cache=False, **(_JIT if jit is None else jit))
    def apply(x):
        out = np.empty_like(x)
        for i in prange(x.size):
            out[i] = sine(x[i])
        return out
    return apply


def _vector_sincos(sincos):
    @njit(parallel=True, cache=False, **_JIT)
    def apply(x):
        s, c = np.empty_like(x), np.empty_like(x)
        for i in prange(x.size):
            s[i], c[i] = sincos(x[i])
        return s, c
    return apply


def _neighbours(x, n=4):
    parts, up, down = [x], x.copy(), x.copy()
    for _ in range(n):
        up, down = np.nextafter(up, np.inf), np.nextafter(down, -np.inf)
        parts += [up, down]
    return np.concatenate(parts)


def accuracy(sin, cos, sincos, scale=1.0) -> dict:
    """tests/test_vecmath.py's checks for one design: {check: (measured, bound, ok)}.
    ``scale`` shrinks the random samples (--quick)."""
    rng = np.random.default_rng(2029)
    vs, vc, vsc, vcon = _vector(sin), _vector(cos), _vector_sincos(sincos), \
        _vector(sin, {"fastmath": {"contract"}})
    tol = 2.0**-52
    n = lambda k: max(1000, int(k * scale))  # noqa: E731
    out = {}

    def err(f, ref, x):
        return float(np.max(np.abs(f(x) - ref(x))))

    def check(name, measured, bound):
        out[name] = (measured, bound, bool(measured <= bound))

    x = rng.uniform(-1e4, 1e4, n(4_000_000))
    check("uniform |x| <= 1e4: sin", err(vs, np.sin, x), tol)
    check("uniform |x| <= 1e4: cos", err(vc, np.cos, x), tol)
    x = 10.0 ** rng.uniform(-300, 4, n(2_000_000)) * rng.choice([-1.0, 1.0], n(2_000_000))
    check("all magnitudes to 1e4: sin", err(vs, np.sin, x), tol)
    small = x[np.abs(x) < 1e-3]
    check("|x| < 1e-3: |err| / |x| (sin)",
          float(np.max(np.abs(vs(small) - np.sin(small)) / np.abs(small))), 2.3e-16)
    for fraction in (2, 4):
        k = np.arange(-int(1e4 * fraction / np.pi) - 1, int(1e4 * fraction / np.pi) + 2)
        x = _neighbours(k * (np.pi / fraction))
        x = x[np.abs(x) <= 1e4]
        check(f"k pi/{fraction} and 4 neighbours: sin", err(vs, np.sin, x), tol)
        check(f"k pi/{fraction} and 4 neighbours: cos", err(vc, np.cos, x), tol)
    x = _neighbours(np.array([np.pi, -np.pi, 2 * np.pi, 1e4 * np.pi / 2]), 64)
    want = np.sin(x)
    check("next to k pi: |err| / |sin|", float(np.max(np.abs(vs(x) - want) / np.abs(want))),
          4.5e-16)
    x = np.concatenate([np.arange(-10_000, 10_001, dtype=float),
                        np.arange(-20_000, 20_001) / 2.0, np.arange(-40_000, 40_001) / 4.0,
                        np.arange(-2**20, 2**20) / 2.0**10, 2.0 ** np.arange(-1074, 14)])
    check("dyadic multiples: sin", err(vs, np.sin, x), tol)
    check("dyadic multiples: cos", err(vc, np.cos, x), tol)
    x = np.concatenate([[5e-324, 1e-320, 2.2250738585072014e-308, 1e-200, 1e-20, 1e-8],
                        10.0 ** np.linspace(-300, -3, 10_000)])
    x = np.concatenate([x, -x])
    check("tiny x: |err| / |x| (sin)", float(np.max(np.abs(vs(x) - np.sin(x)) / np.abs(x))),
          2.3e-16)
    check("tiny x: cos != np.cos (count)", float(np.sum(vc(x) != np.cos(x))), 0.0)
    x = np.concatenate([rng.uniform(-1e6, 1e6, n(2_000_000)),
                        rng.uniform(-1e8, 1e8, n(1_000_000)),
                        10.0 ** rng.uniform(8, 12, n(1_000_000))
                        * rng.choice([-1.0, 1.0], n(1_000_000))])
    check("1e4 < |x| <= 1e12: sin", err(vs, np.sin, x), tol)
    check("1e4 < |x| <= 1e12: cos", err(vc, np.cos, x), tol)
    k = np.arange(int(1e4 * 2 / np.pi), int(1e6 * 2 / np.pi), 7)
    check("k pi/2 to 1e6 and 2 neighbours: sin", err(vs, np.sin, _neighbours(k * np.pi / 2, 2)),
          tol)
    x = 10.0 ** rng.uniform(12, np.log10(3e15), n(1_000_000))
    check("1e12 < |x| <= 3e15: sin (documented bound)", err(vs, np.sin, x), 1e-13)
    x = np.array([np.nan, np.inf, -np.inf, -np.nan])
    check("NaN and inf give NaN (count not NaN)",
          float(np.sum(~np.isnan(vs(x))) + np.sum(~np.isnan(vc(x)))), 0.0)
    check("sin(+-0) != +0 (count)", float(np.sum(vs(np.array([0.0, -0.0])) != 0.0)), 0.0)
    x = np.concatenate([rng.uniform(-1e4, 1e4, n(1_000_000)),
                        _neighbours(np.arange(-6366, 6367) * (np.pi / 2))])
    check("caller's FMA contraction changes bits (count)", float(np.sum(vcon(x) != vs(x))), 0.0)
    x = np.concatenate([rng.uniform(-1e4, 1e4, n(200_000)), np.arange(-64, 65) * np.pi / 4,
                        rng.uniform(-1e8, 1e8, 1000), [0.0, -0.0]])
    s, c = vsc(x)
    check("sincos != (sin, cos) bits (count)",
          float(np.sum(s != vs(x)) + np.sum(c != vc(x))), 0.0)
    return out


# ------------------------------------------------------------------------------ main
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes: a smoke test")
    parser.add_argument("--repeats", type=int, default=5, help="alternating rounds")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    parser.add_argument("--in-kernels", action="store_true",
                        help="only time sweep's own kernels on each design (issue 38): "
                             "results/sine_designs_kernels.{json,md}")
    parser.add_argument("--vs-c-limit", action="store_true",
                        help="only sweep.run with each design against the C limits of "
                             "run_all.py and double_pendulum.py: "
                             "results/sine_designs_limit.{json,md}")
    parser.add_argument("--designs", nargs="+", default=list(KERNEL_DESIGNS),
                        choices=list(KERNEL_DESIGNS), help="with --in-kernels, --vs-c-limit")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(HERE))
    from _machine import machine
    if args.in_kernels:
        return main_in_kernels(args, machine())
    if args.vs_c_limit:
        return main_vs_c_limit(args, machine())

    quick = args.quick
    n_vec, n_chain = (2**16, 10**5) if quick else (2**22, 10**7)
    n_traj, steps, one_steps = (2**10, 100, 10**4) if quick else (2**17, 2000, 10**6)
    rounds = 1 if quick else max(1, args.repeats)
    result = {"machine": machine(), "quick": quick, "rounds": rounds,
              "designs": DESCRIPTION, "throughput": {}, "latency": {}, "rk4": {},
              "one_trajectory": {}, "accuracy": {}}
    print(result["machine"], flush=True)

    x = np.random.default_rng(0).uniform(-50.0, 50.0, n_vec)
    out = np.empty_like(x)
    loops = {name: _loop(f) for name, f in DESIGNS.items()}
    chains = {name: _chain(f) for name, f in DESIGNS.items()}
    rk4s = {name: _rk4(f) for name, f in DESIGNS.items()}
    ones = {name: _one(f) for name, f in DESIGNS.items()}
    for name in DESIGNS:  # compile: not timed
        loops[name](x[:8], out[:8])
        chains[name](0.1, 10)
    fma_chain(0.1, 10)

    # throughput and latency, alternating
    calls = {name: (lambda f=f: f(x, out)) for name, f in loops.items()}
    best = best_alternating(calls, rounds)
    calls = {name: (lambda f=f: f(0.1, n_chain)) for name, f in chains.items()}
    calls["fma"] = lambda: fma_chain(0.1, n_chain)
    lat = best_alternating(calls, rounds)
    ns_fma = lat.pop("fma") / n_chain * 1e9
    print(f"clock: a dependent FMA takes {ns_fma:.3f} ns (4 cycles: "
          f"{4 / ns_fma:.2f} GHz)", flush=True)
    for name in DESIGNS:
        loops[name](x, out)
        ns = lat[name] / n_chain * 1e9
        result["throughput"][name] = {"sines_per_s": x.size / best[name],
                                      "vectorised": vectorised(loops[name]),
                                      "max_abs_error_vs_np_sin":
                                          float(np.max(np.abs(out - np.sin(x))))}
        # the chain's own FMA (x = sin(x) * 3 + 0.5) is one of those 4-cycle steps
        result["latency"][name] = {"ns_per_call": ns,
                                   "cycles_per_call": 4 * ns / ns_fma - 4}
        print(f"  {name:10s} {x.size / best[name] / 1e6:9.1f} M sin/s (vectorised: "
              f"{result['throughput'][name]['vectorised']})   latency {ns:6.2f} ns = "
              f"{result['latency'][name]['cycles_per_call']:5.1f} cycles", flush=True)

    # in the RK4 kernel
    fnode, fhalf = forcing(max(steps, one_steps))
    th_axis = np.linspace(-np.pi, np.pi, max(1, round(math.sqrt(2 * n_traj))))
    om_axis = np.linspace(-2.0, 2.0, max(1, n_traj // th_axis.size))
    th0, om0 = (a.ravel().copy() for a in np.meshgrid(th_axis, om_axis, indexing="ij"))
    args_rk4 = (fnode, fhalf, steps, 1.0, 0.5, 0.01)
    args_one = (fnode, fhalf, one_steps, 1.0, 0.5, 0.01)
    for name in DESIGNS:
        rk4s[name](th0[:8], om0[:8], fnode, fhalf, 2, 1.0, 0.5, 0.01)
        ones[name](0.1, 0.0, fnode, fhalf, 2, 1.0, 0.5, 0.01)
    calls = {name: (lambda f=f: f(th0, om0, *args_rk4)) for name, f in rk4s.items()}
    calls.update({f"one:{name}": (lambda f=f: f(0.1, 0.0, *args_one))
                  for name, f in ones.items()})
    best = best_alternating(calls, rounds)
    ref = rk4s["sweep"](th0, om0, *args_rk4)
    for name in DESIGNS:
        got = rk4s[name](th0, om0, *args_rk4)
        result["rk4"][name] = {
            "traj_steps_per_s": th0.size * steps / best[name],
            "max_abs_diff_from_sweep_sine": float(max(np.max(np.abs(got[0] - ref[0])),
                                                      np.max(np.abs(got[1] - ref[1]))))}
        result["one_trajectory"][name] = {"steps_per_s": one_steps / best[f"one:{name}"]}
        print(f"  {name:10s} RK4 in lanes {th0.size * steps / best[name] / 1e6:8.1f} M "
              f"traj-steps/s; one trajectory "
              f"{one_steps / best[f'one:{name}'] / 1e6:6.2f} M steps/s", flush=True)
    # sweep.run itself, its kernels built on each sine (fresh processes, alternating)
    result["sweep_run"] = sweep_run_with_each_sine(n_traj, steps, 1 if quick else 3)
    for name, v in result["sweep_run"].items():
        print(f"  {name:10s} sweep.run, full scene, its kernels on this sine: "
              f"{v['traj_steps_per_s'] / 1e6:8.1f} M traj-steps/s", flush=True)
    result["workload"] = {"trajectories": int(th0.size), "steps": steps,
                          "one_trajectory_steps": one_steps, "sin_loop_points": n_vec,
                          "chain_calls": n_chain}

    # accuracy: tests/test_vecmath.py's checks
    scale = 0.05 if quick else 1.0
    pairs = {"sweep": (vecmath.sin, vecmath.cos, vecmath.sincos),
             "quadrant": (sin_quadrant, vecmath.cos, sincos_select_twice),
             "pi": (sin_pi, cos_pi, sincos_pi)}
    for name, fns in pairs.items():
        result["accuracy"][name] = acc = accuracy(*fns, scale=scale)
        failed = [k for k, v in acc.items() if not v[2]]
        print(f"  {name:10s} accuracy: {len(acc) - len(failed)}/{len(acc)} test_vecmath "
              f"checks pass{'; FAILS ' + ', '.join(failed) if failed else ''}", flush=True)

    args.out.mkdir(parents=True, exist_ok=True)
    stem = "sine_designs_quick" if quick else "sine_designs"
    (args.out / f"{stem}.json").write_text(json.dumps(result, indent=2))
    md = markdown(result)
    (args.out / f"{stem}.md").write_text(md)
    print(md)
    return 0


def main_in_kernels(args, machine_text: str) -> int:
    """--in-kernels: `in_kernels` on ``args.designs``, written to the results folder."""
    rounds = 1 if args.quick else max(1, args.repeats)
    print(machine_text, flush=True)
    result = {"machine": machine_text, "load_1min_start": os.getloadavg()[0],
              "quick": args.quick, "rounds": rounds,
              "designs": {d: KERNEL_DESCRIPTION[d] for d in args.designs},
              "in_kernels": in_kernels(args.designs, rounds, args.quick)}
    result["load_1min_end"] = os.getloadavg()[0]
    md = "\n".join([f"# sine designs inside sweep's kernels ({rounds} rounds)", "",
                     f"Machine: {machine_text}; 1-minute load {result['load_1min_start']:.1f}"
                     f" at the start, {result['load_1min_end']:.1f} at the end.", ""]
                    + in_kernels_markdown(result["in_kernels"], args.designs)) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "sine_designs_kernels_quick" if args.quick else "sine_designs_kernels"
    (args.out / f"{stem}.json").write_text(json.dumps(result, indent=2))
    (args.out / f"{stem}.md").write_text(md)
    print(md)
    return 0


def main_vs_c_limit(args, machine_text: str) -> int:
    """--vs-c-limit: `vs_c_limit` on ``args.designs``, written to the results folder."""
    rounds = 1 if args.quick else max(1, args.repeats)
    print(machine_text, flush=True)
    result = {"machine": machine_text, "load_1min_start": os.getloadavg()[0],
              "quick": args.quick, "rounds": rounds,
              "designs": {d: KERNEL_DESCRIPTION[d] for d in args.designs},
              "vs_c_limit": vs_c_limit(args.designs, rounds, args.quick)}
    result["load_1min_end"] = os.getloadavg()[0]
    md = "\n".join([f"# sweep.run with each sine against the C limits ({rounds} rounds)", "",
                     f"Machine: {machine_text}; 1-minute load {result['load_1min_start']:.1f}"
                     f" at the start, {result['load_1min_end']:.1f} at the end.", ""]
                    + [f"- **{k}**: {v}" for k, v in result["designs"].items()] + [""]
                    + vs_c_limit_markdown(result["vs_c_limit"])) + "\n"
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "sine_designs_limit_quick" if args.quick else "sine_designs_limit"
    (args.out / f"{stem}.json").write_text(json.dumps(result, indent=2))
    (args.out / f"{stem}.md").write_text(md)
    print(md)
    return 0


def markdown(r) -> str:
    w = r["workload"]
    lines = [f"# sine designs in numba ({'quick' if r['quick'] else 'full'}, best of "
             f"{r['rounds']} alternating rounds)", "", f"Machine: {r['machine']}", ""]
    lines += [f"- **{k}**: {v}" for k, v in r["designs"].items()]
    lines += ["", f"| design | M sin/s (loop of {w['sin_loop_points']}) | vectorised | "
              f"latency ns/call | cycles/call | RK4 in lanes, M traj-steps/s "
              f"({w['trajectories']} x {w['steps']}) | one trajectory, M steps/s |",
              "|---|---|---|---|---|---|---|"]
    for name in r["designs"]:
        t, lat = r["throughput"][name], r["latency"][name]
        lines.append(f"| {name} | {t['sines_per_s'] / 1e6:.0f} | {t['vectorised']} | "
                     f"{lat['ns_per_call']:.2f} | {lat['cycles_per_call']:.0f} | "
                     f"{r['rk4'][name]['traj_steps_per_s'] / 1e6:.0f} | "
                     f"{r['one_trajectory'][name]['steps_per_s'] / 1e6:.2f} |")
    if "sweep_run" in r:
        lines += ["", "`sweep.run` itself on the full scene, its kernels built on each sine "
                  "(fresh processes alternating, best of each; the same workload as the "
                  "lanes column):", "", "| design | M traj-steps/s | max abs diff from "
                  "sweep's sine |", "|---|---|---|"]
        for name, v in r["sweep_run"].items():
            diff = v.get("max_abs_diff_from_sweep_sine")
            lines.append(f"| {name} | {v['traj_steps_per_s'] / 1e6:.0f} | "
                         f"{'' if diff is None else f'{diff:.1e}'} |")
    lines += ["", "Cycles: the chain's ns per call over a dependent FMA's ns, times 4 (an "
              "FMA's latency on Zen 4/5 and Intel's AVX-512 cores), less the chain's own FMA.",
              "", "## Accuracy: tests/test_vecmath.py's checks", "",
              "| check | bound | " + " | ".join(r["accuracy"]) + " |",
              "|---|---|" + "---|" * len(r["accuracy"])]
    names = list(r["accuracy"])
    for check in r["accuracy"][names[0]]:
        bound = r["accuracy"][names[0]][check][1]
        cells = []
        for name in names:
            value, _, ok = r["accuracy"][name][check]
            cells.append(f"{value:.3g}{'' if ok else ' **FAILS**'}")
        lines.append(f"| {check} | {bound:.3g} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
