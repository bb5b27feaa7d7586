"""The CPU kernels' SIMD vector width (`sweep.kernels.vectors`): chosen for sweep's
kernels alone, it reaches their machine code, is recorded in the dataset, and does not
change a single bit of the results."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import sweep
from sweep import _config
from sweep.kernels import KernelSpec, vectors

SCENE = sweep.Scene(gravity=1.0, length=1.0, model="nonlinear",
                    effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3, 0.0)))
PERIOD = 2 * np.pi / (2 / 3)  # of the forcing; the strobe needs whole steps in it
AVX512 = "avx512f" in vectors.target_features()


@pytest.mark.parametrize("text, want", [("256", 256), (" 512 ", 512), ("128", 128),
                                        ("LLVM", "llvm"), ("auto", "auto")])
def test_the_environment_variable_sets_the_width(monkeypatch, text, want):
    monkeypatch.setenv("SWEEP_VECTOR_WIDTH", text)
    assert _config.vector_width() == want


@pytest.mark.parametrize("text", ["300", "wide", "512 bits", "0"])
def test_a_bad_width_is_refused_by_name_before_any_compute(monkeypatch, text):
    monkeypatch.setenv("SWEEP_VECTOR_WIDTH", text)
    grid = sweep.Grid(theta0=[0.1, 0.2], omega0=0.0)
    with pytest.raises(ValueError, match=r"SWEEP_VECTOR_WIDTH=.* is not a vector width; "
                                         r"accepted: auto, llvm, 128, 256, 512"):
        sweep.engine.prepare(SCENE, grid, t_end=1.0, dt=0.01)


def test_auto_asks_for_512_bits_exactly_where_the_target_has_avx512(monkeypatch):
    from numba.core import config

    features = vectors.target_features.__wrapped__  # the memoised function, uncached
    monkeypatch.setattr(config, "CPU_FEATURES", "+avx2,+fma,-avx512f,+avx512vl")
    assert features() == {"avx2", "fma", "avx512vl"}
    monkeypatch.setattr(vectors, "target_features", features)
    assert vectors.resolved("auto") is None  # LLVM's choice: nothing to ask for
    assert vectors.describe("auto") == "llvm (auto)"
    monkeypatch.setattr(config, "CPU_FEATURES", "+avx2,+avx512f")
    assert vectors.resolved("auto") == 512
    assert vectors.describe("auto") == "512 (auto)"
    assert vectors.resolved("llvm") is None and vectors.resolved(256) == 256


# (observe, run options): the fixed-step kernel with its tangent dynamics, the early-
# stopped kernel with lane refill, the adaptive kernel, float32 (each in the default
# width the kernel of another test: test_lyapunov's, test_refill's, and the dopri5 and
# float32 ones of test_benchmark_scripts' blocks and float32 scripts)
CASES = {
    "rk4 final+lyapunov": (("final", "lyapunov"), {}),
    "refill strobe": (("strobe",), {"stop_early": True}),
    "dopri5": (("final",), {"method": "dopri5", "rtol": 1e-8, "atol": 1e-10}),
    "float32": (("final",), {"dtype": "float32"}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_results_are_bit_identical_in_every_width(monkeypatch, case):
    """256-bit lanes and the default (512 bits on an AVX-512 host, LLVM's choice
    elsewhere) give the same bits: the kernels have no reassociation and explicit
    FMAs, so a lane's operations do not depend on how many lanes a register holds.
    (LLVM's own choice is 512 bits on this project's AMD machines and 256 on Intel's:
    the same machine code as one of the two, so not run a third time.) 300 starts:
    not a multiple of any block, so the last block has idle lanes."""
    observe, options = CASES[case]
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 20), omega0=np.linspace(-2.0, 2.0, 15))
    runs = {}
    for width in ("256", "auto"):
        monkeypatch.setenv("SWEEP_VECTOR_WIDTH", width)
        runs[width] = sweep.run(SCENE, grid, t_end=20 * PERIOD, dt=PERIOD / 120,
                                observe=observe, progress=False, **options)
        assert runs[width].attrs["vector_width"] == vectors.describe(width)
    assert runs["auto"].attrs["vector_width"] == ("512 (auto)" if AVX512 else "llvm (auto)")
    for name, variable in runs["256"].data_vars.items():
        assert variable.values.tobytes() == runs["auto"][name].values.tobytes(), name


def test_a_kernel_source_names_its_width(monkeypatch):
    """The width is in the generated text, so numba's disk cache keeps a kernel per
    width (a kernel compiled for 256 bits is never loaded for 512)."""
    spec = KernelSpec("nonlinear", ("damping",), ("final",))
    texts = {}
    for width in ("256", "512", "llvm"):
        monkeypatch.setenv("SWEEP_VECTOR_WIDTH", width)
        texts[width] = sweep.kernels.source(spec)
    assert texts["256"].endswith("compile_with(globals(), 256, 64, False)\n")
    assert texts["512"].endswith("compile_with(globals(), 512, 64, False)\n")
    assert texts["llvm"].endswith("compile_with(globals(), None, 64, False)\n")


_ASM = textwrap.dedent("""
    import json, re, sys
    import numpy as np, sweep
    from sweep import kernels
    scene = sweep.Scene(gravity=1.0, length=1.0, model="nonlinear",
                        effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3, 0.0)))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 64), omega0=np.linspace(-2, 2, 32))
    counts = {}
    for width in ("llvm", 256, 512):
        sweep._config.VECTOR_WIDTH = width
        spec = sweep.engine.warm_up(scene, grid, t_end=1.0, dt=0.01)  # runs nothing
        asm = "".join(kernels.compiled(kernels.build(spec)).inspect_asm().values())
        counts[str(width)] = {r: len(re.findall(r"\\bv\\w+pd\\s+%" + r, asm))
                              for r in ("zmm", "ymm")}
        llvm_ir = "".join(kernels.compiled(kernels.build(spec)).inspect_llvm().values())
        counts[str(width)]["alignments"] = sorted(set(re.findall(
            r"NRT_MemInfo_alloc_aligned\\(i64 [^,]+, i32 (\\d+)\\)", llvm_ir)))
    # plain numba code of the user's, compiled in the same process after the kernels
    from numba import njit
    @njit
    def user_loop(x):
        out = np.empty(x.size)
        for i in range(x.size):
            out[i] = x[i] * 1.5 + 2.0
        return out
    user_loop.compile("(float64[::1],)")
    asm = "".join(user_loop.inspect_asm().values())
    counts["user"] = {r: len(re.findall(r"\\bv\\w+pd\\s+%" + r, asm)) for r in ("zmm", "ymm")}
    counts["user"]["alignments"] = sorted(set(re.findall(
        r"NRT_MemInfo_alloc_aligned\\(i64 [^,]+, i32 (\\d+)\\)",
        "".join(user_loop.inspect_llvm().values()))))
    print(json.dumps(counts))
""")


@pytest.mark.skipif(not AVX512, reason="the host has no AVX-512: the tuning cannot be "
                                       "emulated without running code it lacks")
def test_intel_tuning_gets_512_bit_aligned_kernels_and_leaves_other_code_alone(tmp_path):
    """Under LLVM's tuning for Intel's Rocket Lake (``prefer-256-bit``, the issue's
    Xeon), emulated with ``NUMBA_CPU_NAME``: LLVM's own choice vectorises the kernel
    with 256-bit ymm registers, the 512 setting with zmm ones, 256 with ymm; the
    user's own numba loop compiled afterwards stays on LLVM's ymm. Kernels are only
    compiled (`sweep.engine.warm_up` integrates no trajectory) and inspected, in a
    fresh cache, so nothing is loaded from a cache that inspection cannot read."""
    env = dict(os.environ, NUMBA_CPU_NAME="rocketlake", SWEEP_CACHE_DIR=str(tmp_path),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env.pop("SWEEP_VECTOR_WIDTH", None)
    done = subprocess.run([sys.executable, "-c", _ASM], env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    counts = json.loads(done.stdout.splitlines()[-1])
    assert counts["llvm"]["zmm"] == 0 and counts["llvm"]["ymm"] > 20
    assert counts["512"]["zmm"] > 20 and counts["512"]["ymm"] == 0
    assert counts["256"]["zmm"] == 0 and counts["256"]["ymm"] > 20
    assert counts["user"]["zmm"] == 0 and counts["user"]["ymm"] > 0
    # the kernels' arrays (their lanes) start on 64-byte boundaries, the user's on
    # numba's 32 (sweep._config.LANE_ALIGNMENT)
    assert all(counts[w]["alignments"] == ["64"] for w in ("llvm", "256", "512"))
    assert counts["user"]["alignments"] == ["32"]


_USER_LOOP = '''
def user_loop(x, y, out):
    for i in range(x.size):
        out[i] = np.float32(np.sin(np.float64(x[i]) * y[i])) * x[i]
'''


def _user_loop_registers():
    """The instructions of a fresh numba loop mixing float32 and float64 (the user's
    own code)."""
    from numba import njit

    namespace = {"np": np}
    exec(_USER_LOOP, namespace)
    loop = njit(namespace["user_loop"])
    loop.compile("(float32[::1], float64[::1], float32[::1])")
    asm = "".join(loop.inspect_asm().values())
    # its instructions, without the names (each compile has its own)
    return [line.split()[0] for line in asm.splitlines()
            if line.startswith("\t") and not line.startswith("\t.")]


def test_float32_kernels_fill_the_register_and_give_the_same_bits(monkeypatch, tmp_path):
    """A float32 kernel of the nonlinear pendulum (float64 angle, float32 rest) compiled
    with lanes counted by float32 (`_config.SINGLE_BY_NARROWEST`) has more packed float32
    instructions on full-width registers than without, gives the same bits, and leaves
    LLVM's option as it found it for the user's code compiled afterwards. Fresh cache
    folder: machine code is inspected only where it was compiled."""
    import re

    monkeypatch.setenv("SWEEP_CACHE_DIR", str(tmp_path))
    # and not the process's memo, which may hold this kernel loaded from the disk cache
    # by another test (numba cannot inspect loaded code)
    sweep.kernels.build.cache_clear()
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 20), omega0=np.linspace(-2.0, 2.0, 15))
    before = _user_loop_registers()
    runs, packed = {}, {}
    for narrowest in (False, True):
        monkeypatch.setattr(_config, "SINGLE_BY_NARROWEST", narrowest)
        kw = dict(t_end=20 * PERIOD, dt=PERIOD / 120, observe=("final", "winding"),
                  dtype="float32")
        runs[narrowest] = sweep.run(SCENE, grid, progress=False, **kw)
        spec = sweep.engine.prepare(SCENE, grid, **kw)[1]
        kernel = sweep.kernels.compiled(sweep.kernels.build(spec))
        asm = "".join(kernel.inspect_asm().values())
        register = "zmm" if AVX512 else "ymm"
        packed[narrowest] = len(re.findall(r"\bv\w+ps\s+%" + register, asm))
    assert packed[True] > 2 * packed[False], packed
    for name, variable in runs[False].data_vars.items():
        assert variable.values.tobytes() == runs[True][name].values.tobytes(), name
    assert _user_loop_registers() == before  # the option was reset



def test_llvm_options_change_the_machine_code_inside_and_are_reset_after():
    """`vectors._llvm_options` sets LLVM's option while its block runs (the machine
    code of a function emitted then differs: no machine scheduler) and resets it after
    (the same function's code is again what it was), so the user's code compiled
    afterwards is untouched."""
    from numba import njit

    from sweep.kernels import vecmath

    @njit
    def chains(x, out):  # independent sines: a scheduler has work to reorder
        for i in range(x.shape[0]):
            a, b = vecmath.sin(x[i]), vecmath.sin(2.0 * x[i])
            out[i] = a * b + vecmath.sin(a - b)

    chains(np.linspace(0.0, 1.0, 64), np.empty(64))
    signature = chains.signatures[0]
    before = chains.inspect_asm(signature)  # emitted anew by each call
    with vectors._llvm_options(("--enable-misched=false",)):
        inside = chains.inspect_asm(signature)
    assert inside != before
    assert chains.inspect_asm(signature) == before


def test_system_kernels_without_the_machine_scheduler_give_the_same_bits(monkeypatch):
    """A system's kernels compile without LLVM's machine scheduler (faster:
    `vectors._llvm_options`), but for the tangent dynamics; a scheduler only reorders
    operations, so the double pendulum's chaotic trajectories (where one differing ulp
    grows visibly over 5 s) are the same bits either way, in blocks of SIMD lanes."""
    from sweep.engine_systems import prepare_system

    source_module = sys.modules["sweep.kernels.source"]
    system = sweep.DoublePendulum()
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 8), theta2_0=np.linspace(-2.5, 2.5, 8))
    kw = dict(t_end=5.0, dt=0.005)

    def module_text(**more):
        spec = prepare_system(system, grid, **kw, **more)[1]
        assert spec.block > 1  # lanes, not one trajectory alone
        return sweep.kernels.source(spec)

    assert module_text(observe=("final",)).rstrip().endswith(", scheduler=False)")
    assert "scheduler" not in module_text(observe=("final", "lyapunov"))
    runs = {}
    for scheduler in (False, True):
        monkeypatch.setattr(source_module, "SYSTEM_SCHEDULER", scheduler)
        runs[scheduler] = sweep.run(system, grid, observe=("final",), progress=False, **kw)
    for name, variable in runs[False].data_vars.items():
        assert variable.values.tobytes() == runs[True][name].values.tobytes(), name

#: The outputs' bits of every kind of kernel that reads `sweep.kernels.vecmath`, as a
#: digest per workload: the sine itself (sin, cos, sincos, sincos_quadrant of
#: arguments up to 1e4), the
#: fixed-step kernel of a damped forced pendulum, one trajectory alone (the narrow
#: path), the early-stop kernel with lane refill (a forced basins map's strobe), the
#: tangent dynamics (``lyapunov``: sincos), float32 (sin32) and the double pendulum (two
#: sines and a sincos_quadrant per stage).
_BITS = textwrap.dedent("""
    import hashlib, json, math
    import numpy as np, sweep
    from numba import njit
    from sweep.kernels import vecmath

    def digest(*arrays):
        return hashlib.sha1(b"".join(np.ascontiguousarray(a).tobytes()
                                     for a in arrays)).hexdigest()

    def of(ds):
        return digest(*(ds[v].values for v in sorted(ds.data_vars)))

    @njit
    def sines(x):
        out = np.empty((6, x.size))
        for i in range(x.size):
            out[0, i], out[1, i] = vecmath.sin(x[i]), vecmath.cos(x[i])
            out[2, i], out[3, i] = vecmath.sincos(x[i])
            out[4, i], out[5, i] = vecmath.sincos_quadrant(x[i])
        return out

    x = np.random.default_rng(38).uniform(-1e4, 1e4, 100_000)
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.5),
                        sweep.Forcing(1.2, 2 / 3, 0.0)))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 32), omega0=np.linspace(-2, 2, 16))
    kw = dict(t_end=5.0, dt=0.01, observe=("final",), progress=False)
    period = 2 * math.pi
    basins = sweep.Scene(gravity=1.0, length=1.0, effects=(sweep.Damping(0.2),
                         sweep.Forcing(1.66, 1.0, math.pi / 2)))
    double = sweep.DoublePendulum(mass1=1.0, mass2=1.0, length1=1.0, length2=1.0,
                                  gravity=9.81)
    print(json.dumps({
        "sines": digest(sines(x)),
        "fixed": of(sweep.run(scene, grid, **kw)),
        "one trajectory": of(sweep.run(scene, sweep.Grid(theta0=[2.5], omega0=[0.0]),
                                       **dict(kw, t_end=20.0))),
        "refill": of(sweep.run(basins, sweep.Grid(theta0=np.linspace(-3, 3, 24),
                                                  omega0=np.linspace(-4, 4, 24)),
                               t_end=60 * period, dt=period / 100, t_transient=20 * period,
                               observe=("strobe",), stop_early=True, progress=False)),
        "lyapunov": of(sweep.run(scene, grid, t_end=5.0, dt=0.01, observe=("lyapunov",),
                                 progress=False)),
        "float32": of(sweep.run(scene, grid, dtype="float32", **kw)),
        "double pendulum": of(sweep.run(double, sweep.Grid(
            theta1_0=np.linspace(-3, 3, 16), theta2_0=np.linspace(-3, 3, 8)), **kw)),
    }))
""")


@pytest.mark.slow
@pytest.mark.skipif(not AVX512, reason="the host has no AVX-512: the Zen 4 and Skylake-X "
                                       "targets cannot be emulated without running code "
                                       "it lacks")
def test_results_are_the_same_bits_on_every_emulated_cpu_with_fma(tmp_path):
    """A map computed on one machine and extended on another must not change a label
    (issue 38): every kernel kind's outputs, and the sine's own, have the same bits
    when LLVM compiles for AMD's Zen 4 (512-bit units), Intel's Skylake-X (AVX-512,
    tuned for 256-bit vectors) with 256- and 512-bit kernels, and Haswell (AVX2 and
    FMA, no AVX-512), emulated on this host with ``NUMBA_CPU_NAME`` (fresh caches:
    each target compiles its own code). The sine's operations are IEEE-rounded
    arithmetic and explicit fused multiply-adds (`sweep.kernels.vecmath.fma`), with no
    fast-math flag, so no target may round differently; this checks that no
    vectorisation, width or instruction choice changes that."""
    targets = {"znver4": {}, "skylake-avx512, 256": {"SWEEP_VECTOR_WIDTH": "256"},
               "skylake-avx512, 512": {"SWEEP_VECTOR_WIDTH": "512"}, "haswell": {}}
    digests = {}
    for label, extra in targets.items():
        cache = tmp_path / label.replace(", ", "_")
        env = dict(os.environ, NUMBA_CPU_NAME=label.split(",")[0],
                   SWEEP_CACHE_DIR=str(cache), NUMBA_CACHE_DIR=str(cache / "numba"), **extra)
        env.pop("NUMBA_CPU_FEATURES", None)
        if not extra:
            env.pop("SWEEP_VECTOR_WIDTH", None)
        done = subprocess.run([sys.executable, "-c", _BITS], env=env, capture_output=True,
                              text=True, timeout=900)
        assert done.returncode == 0, done.stderr
        digests[label] = json.loads(done.stdout.splitlines()[-1])
    first = digests["znver4"]
    assert len(first) == 7
    for label, got in digests.items():
        assert got == first, f"{label} differs from znver4 in " + ", ".join(
            k for k in first if got[k] != first[k])
