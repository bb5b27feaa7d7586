"""The C reference (``c_reference/pendulum.c``) built with gcc and called through ctypes,
on run_all.py's full scene, and the C limit that forced_basins.py and refine.py set
their maps against (`c_limit`). Shared by run_all.py, forced_basins.py and refine.py
(and run_all re-exports these names for the tests).
"""

from __future__ import annotations

import ctypes
import functools
import itertools
import json
import math
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from _machine import C_SOURCE, cpu_flags
from _timing import best_of

#: run_all.py's full scene: g/L, damping, forcing amplitude, frequency and phase; step
G_OVER_L, DAMPING, AMPLITUDE, FREQUENCY, PHASE = 1.0, 0.5, 1.2, 2.0 / 3.0, 0.0
DT = 0.01


def grid_axes(n):
    """(theta0, omega0) axes with n trajectories: 2 x 1 aspect like 512 x 256."""
    cols = max(1, round(math.sqrt(n / 2)))
    rows = max(1, n // cols)
    return np.linspace(-np.pi, np.pi, rows), np.linspace(-2.0, 2.0, cols)


def initial_states(theta0, omega0):
    th, om = np.meshgrid(theta0, omega0, indexing="ij")
    return th.ravel().copy(), om.ravel().copy()


# ------------------------------------------------------------------------ C reference
# Every build: gcc C_BASE_FLAGS + the variant's flags. Never -ffast-math (reassociation
# would break the sine's magic-number rounding and exact reduction). -ffp-contract=fast
# fuses a*b + c into FMAs wherever gcc likes (sweep's kernels write theirs explicitly,
# sweep._config.FASTMATH, but the fastest C may fuse more); -ffp-contract=off fuses
# none but the sine's explicit fma() calls.
C_BASE_FLAGS = ["-O3", "-march=native", "-fopenmp", "-shared", "-fPIC"]
C_BLOCKS = (64, 128, 256, 512, 1024, 2048, 4096)  # the limit's block-size sweep
C_CHECK_STEPS = 100  # the agreement check's horizon (t = 1)
C_CHECK_TOL = 1e-12  # max |C - sweep| of the final state allowed after C_CHECK_STEPS
WIDE = "-mprefer-vector-width=512"

#: The weaker builds, kept as rows named for what they are. (gcc 12.2 takes this Zen 4
#: for znver3 under -march=native but, with AVX-512 enabled and no 256-bit tuning for
#: AMD, still emits 512-bit zmm code by default: `native_vector_registers` checks.)
NARROW = "-mprefer-vector-width=256"
C_FIXED = {
    "C, -march=native, libm sin, no FMA":
        ["-DSIN_VARIANT=0", "-ffp-contract=off"],
    "C, -march=native, glibc vector sin (libmvec), no FMA":
        ["-DSIN_VARIANT=1", "-ffp-contract=off"],
    "C, -march=native, polynomial sin, FMA only where written (its fma())":
        ["-DSIN_VARIANT=4", "-ffp-contract=off"],
    "C, 256-bit (-mprefer-vector-width=256), polynomial sin, FMA":
        [NARROW, "-DSIN_VARIANT=4", "-ffp-contract=fast"],
    "C, -march=native, previous polynomial sin (both polynomials), FMA":
        ["-DSIN_VARIANT=2", "-ffp-contract=fast"],
    "C, -march=native, glibc vector sin (libmvec), FMA":
        ["-DSIN_VARIANT=1", "-ffp-contract=fast"],
    "C, linear model (no sin), -march=native, no FMA":
        ["-DLINEAR", "-ffp-contract=off"],
}


def c_limit_candidates(avx512: bool, blocks=C_BLOCKS) -> dict[str, list[str]]:
    """The limit search, first phase: the same algorithm at its fastest (polynomial
    sine in SIMD lanes, FMA contraction, forcing sine once per step for the whole call,
    512-bit vectors where the CPU has AVX-512), one build per block size."""
    width = [WIDE] if avx512 else []
    label = "512-bit" if avx512 else "-march=native"
    return {f"C limit search: {label}, polynomial sin, FMA, forcing table, block {b}":
            [*width, "-DSIN_VARIANT=4", "-ffp-contract=fast", "-DFORCING_TABLE",
             f"-DBLOCK={b}"] for b in blocks}


#: The one-reduction-by-pi sines (pendulum.c's SIN_VARIANT 5): -DSIN_POLY, evaluation
#: scheme -> the row's words. Their polynomials come from fit_sine.py.
PI_SINES = {
    ("0", "Horner"): "Taylor degree 19",
    ("1", "Horner"): "Taylor degree 21",
    ("2", "Horner"): "minimax degree 17",
    ("3", "Horner"): "minimax degree 15",
    ("0", "Estrin"): "Taylor degree 19",
    ("1", "Estrin"): "Taylor degree 21",
    ("2", "Estrin"): "minimax degree 17",
    ("2", "Estrin, M1 last"): "minimax degree 17",  # -DHEAD: sweep's sine since 2026-11-27
}


def c_limit_sine_designs(best_flags: list[str], avx512: bool, blocks=None,
                         forcing_table: bool = True) -> dict[str, list[str]]:
    """Third phase (issue 29): the sine's design, at the best block (or at each of
    ``blocks``): one reduction by pi and one odd polynomial, Taylor or minimax, by
    Horner or Estrin; each must also pass the sine contract (`sine_accuracy`).
    ``forcing_table``: pendulum.c's -DFORCING_TABLE (a system without forcing, as
    double_pendulum.c, has none)."""
    width = [WIDE] if avx512 else []
    label = "512-bit" if avx512 else "-march=native"
    table = ["-DFORCING_TABLE"] if forcing_table else []
    if blocks is None:
        blocks = [next(f for f in best_flags if f.startswith("-DBLOCK="))[8:]]
    out = {}
    for n in blocks:
        for (poly, scheme), words in PI_SINES.items():
            out[f"C limit search: {label}, sin by one reduction by pi, {words} odd "
                f"polynomial, {scheme}, FMA{', forcing table' if table else ''}, "
                f"block {n}"] = [
                *width, "-DSIN_VARIANT=5", f"-DSIN_POLY={poly}",
                *{"Estrin": ["-DESTRIN"], "Estrin, M1 last": ["-DHEAD"]}.get(scheme, []),
                "-ffp-contract=fast",
                *table, f"-DBLOCK={n}"]
    return out


def c_limit_variations(best_flags: list[str], avx512: bool) -> dict[str, list[str]]:
    """Second phase, at the best block: one option changed at a time."""
    block = next(f for f in best_flags if f.startswith("-DBLOCK="))
    width = [WIDE] if avx512 else []
    label = "512-bit" if avx512 else "-march=native"
    n = block.split("=")[1]
    out = {
        f"C limit search: {label}, previous polynomial sin (both polynomials, quadrant "
        f"from bits), FMA, forcing table, block {n}":
            [*width, "-DSIN_VARIANT=3", "-ffp-contract=fast", "-DFORCING_TABLE", block],
        f"C limit search: {label}, polynomial sin, FMA, forcing per block and step "
        f"(sweep's layout), block {n}":
            [*width, "-DSIN_VARIANT=4", "-ffp-contract=fast", block],
    }
    if avx512:
        out[f"C limit search: 256-bit (-mprefer-vector-width=256), polynomial sin, FMA, "
            f"forcing table, block {n}"] = [NARROW, "-DSIN_VARIANT=4", "-ffp-contract=fast",
                                            "-DFORCING_TABLE", block]
    return out


_LIB_NUMBER = itertools.count()


def compile_library(build_dir: Path, source: Path, flags: list[str]):
    """Compile a C reference ``source`` with gcc, C_BASE_FLAGS and ``flags`` into a
    shared library in ``build_dir``; the loaded library (ctypes), or an error string,
    or None if gcc is absent."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    lib = build_dir / f"{source.stem}_{next(_LIB_NUMBER)}.so"
    cmd = [gcc, *C_BASE_FLAGS, *flags, str(source), "-o", str(lib), "-lm"]
    proc = subprocess.run(cmd, check=False, capture_output=True, text=True)
    if proc.returncode != 0:
        return "build failed: " + (proc.stderr.strip().splitlines() or ["?"])[-1]
    return ctypes.CDLL(str(lib))


def build_c_one(build_dir: Path, key: str, flags: list[str]):
    """Compile pendulum.c with ``flags``; a ctypes function, or an error string, or
    None if gcc is absent."""
    loaded = compile_library(build_dir, C_SOURCE, flags)
    if loaded is None or isinstance(loaded, str):
        return loaded
    fn = loaded.pendulum_rk4
    fn.restype = None
    p = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [ctypes.c_int64, p, p, *[ctypes.c_double] * 7, ctypes.c_int64, p, p]
    fn.sine = loaded.sines_sin  # the build's sine on an array (`sine_accuracy`)
    fn.sine.restype = None
    fn.sine.argtypes = [ctypes.c_int64, p, p]
    return fn


def build_c(build_dir: Path, variants=None):
    """{variant: ctypes function or error string}; None if gcc is absent."""
    if shutil.which("gcc") is None:
        return None
    variants = C_FIXED if variants is None else variants
    return {name: build_c_one(build_dir, name, flags) for name, flags in variants.items()}


def call_c(fn, th0, om0, steps):
    n = th0.size
    th, om = np.empty(n), np.empty(n)
    p = ctypes.POINTER(ctypes.c_double)
    fn(n, th0.ctypes.data_as(p), om0.ctypes.data_as(p), G_OVER_L, DAMPING, AMPLITUDE,
       FREQUENCY, PHASE, 0.0, DT, steps, th.ctypes.data_as(p), om.ctypes.data_as(p))
    return th, om


# ------------------------------------------------------------------ the sine contract
#: sweep's sine contract (`sweep.kernels.vecmath.sin`, tests/test_vecmath.py): within
#: 2**-52 = 2.2e-16 absolute of np.sin (glibc's, within half an ulp of sin) for
#: |x| <= 1e4, and the same up to |x| = 1e12 (`vecmath.SIN_RANGE`). 2**-52 is two ulps of
#: values in [0.5, 1); sweep's sine itself measures 2.2e-16 since 2026-11-27 (the
#: reduction by pi, SIN_VARIANT 5 -DHEAD) and measured 1.1e-16 before (one ulp; variant
#: 4, the "sweep's sine" of the older rows). A C limit candidate whose sine misses it is
#: printed but is not eligible to be the limit.
SINE_CONTRACT = 2.0**-52
SINE_RANGES = ("|x| <= 1e4", "1e4 < |x| <= 1e12")


#: Arguments where a candidate sine was found 3 ulps (3.3e-16) from np.sin in a search
#: of ~1.5e8 random arguments of |x| <= 1e4 (the minimax degree-17 polynomial by
#: Estrin: about one argument in 1e8; Horner's evaluation of it: none found).
HARD_SINE_ARGUMENTS = np.array([-2766.1844312596486])


def _neighbours(x, n):
    """x and its n floating-point neighbours on each side."""
    parts, up, down = [x], x, x
    for _ in range(n):
        up, down = np.nextafter(up, np.inf), np.nextafter(down, -np.inf)
        parts += [up, down]
    return np.concatenate(parts)


@functools.cache
def contract_arguments() -> tuple[np.ndarray, np.ndarray]:
    """The arguments of the sine contract's check, one array for each of SINE_RANGES:
    those of tests/test_vecmath.py (uniform, every magnitude down to 1e-300, multiples
    of pi/2 and pi/4 and their 4 neighbours each side, dyadic steps; beyond 1e4:
    uniform to 1e6 and 1e8, log-uniform to 1e12, multiples of pi/2 up to 1e6 and 2
    neighbours each side), and for the one-reduction-by-pi sines, whose rounding
    errors are largest where |sin x| ~ 1 (|r| near pi/2, where the polynomial's r**3 P
    is ~ -0.57): 4e6 arguments k pi + r with 0.9 <= |r| <= pi/2, and
    HARD_SINE_ARGUMENTS. A maximum over a sample: an error that one argument in 1e8
    reaches may be missed."""
    rng = np.random.default_rng(29)
    sign = rng.choice([-1.0, 1.0], 4_000_000)
    small = np.concatenate([
        rng.uniform(-1e4, 1e4, 4_000_000),
        10.0 ** rng.uniform(-300, 4, 2_000_000) * sign[:2_000_000],
        rng.integers(-3183, 3184, 4_000_000) * np.pi + sign * rng.uniform(0.9, np.pi / 2,
                                                                           4_000_000),
        HARD_SINE_ARGUMENTS,
        _neighbours(np.arange(-6367, 6368) * (np.pi / 2), 4),
        _neighbours(np.arange(-12733, 12734) * (np.pi / 4), 4),
        np.arange(-2**20, 2**20) / 2.0**10])
    small = small[np.abs(small) <= 1e4]
    large = np.concatenate([
        rng.uniform(-1e6, 1e6, 2_000_000), rng.uniform(-1e8, 1e8, 1_000_000),
        10.0 ** rng.uniform(8, 12, 1_000_000) * sign[:1_000_000],
        _neighbours(np.arange(6367, 636620, 7) * (np.pi / 2), 2)])
    large = large[np.abs(large) > 1e4]
    return small, large


@functools.cache
def sine_points() -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """(x, np.sin(x)) for each of SINE_RANGES (`contract_arguments`)."""
    return tuple((x, np.sin(x)) for x in contract_arguments())


def contract_accuracy(evaluate, points) -> dict:
    """``evaluate(x)`` (a C build's sine or cosine on an array) against the reference
    values of ``points`` (`sine_points`, or the same arguments with np.cos): max abs
    error per range, and whether it meets SINE_CONTRACT on both."""
    errors = [float(np.max(np.abs(evaluate(x) - want))) for x, want in points]
    return {"max_abs_error": dict(zip(SINE_RANGES, errors)), "contract": SINE_CONTRACT,
            "eligible": all(e <= SINE_CONTRACT for e in errors)}


def sine_accuracy(fn) -> dict:
    """A C build's sine (sines.h's ``sines_sin``) against np.sin on `sine_points`: max
    abs error per range, and whether it meets SINE_CONTRACT on both."""
    p = ctypes.POINTER(ctypes.c_double)

    def evaluate(x):
        got = np.empty_like(x)
        fn.sine(x.size, x.ctypes.data_as(p), got.ctypes.data_as(p))
        return got

    return contract_accuracy(evaluate, sine_points())


def sine_text(sine) -> str:
    """A C build's sine accuracy in one phrase (`sine_accuracy`'s result)."""
    errors = ", ".join(f"{e:.1e} for {r}" for r, e in sine["max_abs_error"].items())
    return f"max |err| {errors}: " + ("meets the contract" if sine["eligible"]
                                      else f"NOT eligible (> {SINE_CONTRACT:.2g})")


def c_limit(repeats: int = 3) -> dict | None:
    """The C limit's throughput, best of ``repeats`` calls on run_all's full-scene
    workload (2^17 trajectories x 2000 steps); None without gcc."""
    flags = None
    try:
        found = json.loads((Path(__file__).parent / "results" / "run_all.json").read_text())
        flags = [f for f in found["c_limit"]["flags"] if f not in C_BASE_FLAGS]
    except (OSError, KeyError, ValueError):
        pass
    if flags is None:  # no search on record: its first 512-bit candidate at block 4096
        flags = c_limit_candidates("avx512f" in cpu_flags(), (4096,))
        flags = next(iter(flags.values()))
    n, steps = 2**17, 2000
    th0, om0 = initial_states(*grid_axes(n))
    with tempfile.TemporaryDirectory() as tmp:
        fn = build_c_one(Path(tmp), "limit", flags)
        if not callable(fn):
            return None
        call_c(fn, th0[:64], om0[:64], 10)  # load the library, warm the threads
        best = best_of(lambda: call_c(fn, th0, om0, steps), repeats)
    return {"flags": " ".join(flags), "traj_steps_per_s": th0.size * steps / best}

