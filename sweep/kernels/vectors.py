"""The SIMD vector width of the CPU kernels, chosen for sweep's kernels alone.

LLVM vectorises a kernel's lane loop with the registers its tuning for the CPU prefers.
On Intel cores with AVX-512 (Ice Lake, Rocket Lake, Sapphire Rapids...) that tuning
carries ``prefer-256-bit``, so the kernels ran on 256-bit ``ymm`` registers although the
CPU has 512-bit ``zmm`` ones: on a 2-core Rocket Lake Xeon the full benchmark scene ran
at 432-454 M trajectory-steps/s, and 597-610 M/s with that feature removed (issue 29,
measured with ``NUMBA_CPU_FEATURES``; bit-identical results). AMD's Zen 4 and Zen 5
are tuned for 512 bits already.

Removing the feature for the whole process (``NUMBA_CPU_FEATURES``) would change how
the user's *other* numba code is compiled too. Instead every function compiled for a
sweep kernel (the kernel's ``blocks`` function and the physics helpers compiled with
it) gets LLVM's function attribute
``"prefer-vector-width"="<bits>"``, which the x86 backend reads per function: it sets
the register width the loop vectoriser plans for and whether 512-bit registers are
used, for that function only. The attribute is added when numba lowers those functions
(`numba.core.cpu.CPUContext.post_lowering`, wrapped once), while a sweep kernel's
dispatcher compiles; no other compilation sees it.

The width chosen (`sweep._config.vector_width`): ``auto`` asks for 512 bits where the
CPU the kernels are compiled for has AVX-512 (``avx512f``) and leaves LLVM's choice
elsewhere; ``SWEEP_VECTOR_WIDTH=256`` (or 128, 512, ``llvm``) overrides it. It is
written into the kernel's generated source (so numba's disk cache keeps one kernel
per width) and into every dataset's ``vector_width`` attribute. Results do not depend
on it: the kernels have no fast-math reassociation and write their fused
multiply-adds explicitly, so each lane does the same operations in any width
(``tests/test_vector_width.py`` checks bits).

More settings of the kernels' machine code ride on the same hook, for the same
functions only: the arrays a kernel allocates (its lanes) are aligned to
`sweep._config.LANE_ALIGNMENT` bytes (numba's ``get_preferred_array_alignment``), a
float32 kernel is vectorised by its narrowest type (`_by_narrowest_type`,
`sweep._config.SINGLE_BY_NARROWEST`), and, with a width chosen, the functions realign
the stack to a vector register (LLVM's ``alignstack``). The x86-64 ABI aligns the stack
to 16 bytes only, so the 64-byte registers a kernel spills to it (dopri5's stages: 156
spills and reloads in its machine code) straddled cache lines or not depending on how
deep the calling thread's stack was: the same dopri5 blocks took 0.56 s called from one
Python frame and 0.49 s from one frame deeper (Zen 5, 2 threads, 8192 trajectories),
and 0.50-0.51 s either way once aligned.
"""

from __future__ import annotations

import contextlib
import functools
import threading

__all__ = ["compile_with", "describe", "install", "resolved"]

_state = threading.local()  # .options = (width, alignment) while a kernel compiles


def resolved(setting: str | int) -> int | None:
    """The width in bits that ``setting`` asks for here, or None for LLVM's choice.

    Parameters
    ----------
    setting : {"auto", "llvm", 128, 256, 512}
        As `sweep._config.vector_width` returns it (already checked).

    Returns
    -------
    int or None
        ``auto``: 512 where the kernels' target CPU has ``avx512f``, else None.
    """
    if setting == "llvm":
        return None
    if setting == "auto":
        return 512 if "avx512f" in target_features() else None
    return int(setting)


@functools.cache
def target_features() -> frozenset[str]:
    """The CPU features numba compiles for: ``NUMBA_CPU_FEATURES`` if set, else the
    host's (as LLVM detects them), as a set of names without the ``+``."""
    from numba.core import config

    if config.CPU_FEATURES:
        text = config.CPU_FEATURES
        return frozenset(part[1:] for part in text.split(",") if part.startswith("+"))
    import llvmlite.binding as llvm

    return frozenset(name for name, on in llvm.get_host_cpu_features().items() if on)


def describe(setting: str | int) -> str:
    """The choice as a dataset records it: ``"512"`` or ``"llvm"`` (LLVM's tuning for
    the CPU), and in parentheses the setting that chose it when it was ``auto``."""
    width = resolved(setting)
    text = "llvm" if width is None else str(width)
    return f"{text} (auto)" if setting == "auto" else text


def compile_with(namespace: dict, width: int | None, alignment: int = 32,
                 by_narrowest: bool = False, scheduler: bool = True) -> None:
    """Make every numba dispatcher defined in a generated kernel module (``namespace``,
    its globals) compile with ``"prefer-vector-width"="<width>"`` on its functions
    (none for ``width=None``), its arrays (``np.empty`` in the kernel: the lanes)
    aligned to ``alignment`` bytes (numba's default: 32), if ``by_narrowest``, with
    LLVM's loop vectoriser counting lanes by the loop's narrowest type, and without
    LLVM's machine instruction scheduler if not ``scheduler`` (`_llvm_options`).

    Called by the generated module itself, last.
    """
    install()
    from numba.core.dispatcher import Dispatcher

    options = ((("--vectorizer-maximize-bandwidth",) if by_narrowest else ())
               + (() if scheduler else ("--enable-misched=false",)))
    module = namespace["__name__"]
    for value in list(namespace.values()):
        if isinstance(value, Dispatcher) and value.py_func.__module__ == module:
            _compile_with(value, (width, alignment), options)


def _compile_with(dispatcher, options: tuple[int | None, int],
                  llvm_options: tuple[str, ...]) -> None:
    compile_ = dispatcher.compile

    @functools.wraps(compile_)
    def compile(sig):
        previous = getattr(_state, "options", None)
        _state.options = options
        try:
            if not llvm_options:
                return compile_(sig)
            with _llvm_options(llvm_options):
                return compile_(sig)
        finally:
            _state.options = previous

    dispatcher.compile = compile  # numba calls self.compile(sig) for a new signature


#: Each LLVM option `_llvm_options` sets, and the value that resets it (LLVM's default).
_RESETS = {"--vectorizer-maximize-bandwidth": "--vectorizer-maximize-bandwidth=false",
           "--enable-misched=false": "--enable-misched=true"}


@contextlib.contextmanager
def _llvm_options(options: tuple[str, ...]):
    """LLVM's command-line ``options`` while the block runs (each a key of `_RESETS`).

    ``--vectorizer-maximize-bandwidth``: the loop vectoriser may give a loop as many
    lanes as a register holds of its narrowest type (16 float32 in 512 bits), where it
    otherwise stops at its widest type's count (8 float64). A float32 kernel keeps the
    nonlinear pendulum's angle and the sine's reduction in float64
    (`sweep.kernels.precision`), so without it the float32 lanes filled half a
    register: 349 against 518 M trajectory-steps/s on the full scene (AMD EPYC Zen 5,
    measured side by side; the same bits).

    ``--enable-misched=false``: no machine instruction scheduler before register
    allocation. A system's lane loop (`sweep.kernels.system`: four inlined stages of
    several sines and a mass-matrix solve, one 644-instruction loop body on 512-bit
    registers) is scheduled by it for parallelism into more live registers than the
    32 the CPU has: 145 spills and reloads per iteration, against 35 in GCC's code of
    the same C kernel. Left in the order of its source, the double pendulum ran at 304
    against 285 M trajectory-steps/s (AMD EPYC Zen 5, 2 threads, side by side in one
    process, the same bits: a scheduler reorders, it does not change an operation).

    The options are global to LLVM, so they are set and reset while numba's compiler
    lock is held: no other compilation of the process runs meanwhile, and reset only
    when the outermost compilation (the kernel's, inside which its helpers compile) is
    done."""
    import llvmlite.binding as llvm
    from numba.core.compiler_lock import global_compiler_lock

    with global_compiler_lock:
        depth = getattr(_state, "llvm_depth", 0)  # the kernel's helpers compile inside it
        if depth == 0:
            for option in options:
                llvm.set_option("", option)
        _state.llvm_depth = depth + 1
        try:
            yield
        finally:
            _state.llvm_depth = depth
            if depth == 0:
                for option in options:
                    llvm.set_option("", _RESETS[option])


def install() -> None:
    """Wrap `numba.core.cpu.CPUContext.post_lowering` (once) to add the attribute to
    the functions of the module being lowered while a sweep kernel compiles, and
    ``get_preferred_array_alignment`` to align its arrays."""
    from numba.core.cpu import CPUContext

    original = CPUContext.post_lowering
    if getattr(original, "_sweep_vector_width", False):
        return
    preferred = CPUContext.get_preferred_array_alignment

    @functools.wraps(preferred)
    def get_preferred_array_alignment(context, ty):
        options = getattr(_state, "options", None)
        default = preferred(context, ty)
        return default if options is None else max(default, options[1])

    @functools.wraps(original)
    def post_lowering(self, mod, library):
        width = (getattr(_state, "options", None) or (None,))[0]
        if width is not None:
            # and the stack aligned to a register: with the ABI's 16 bytes a 64-byte
            # register spilled to the stack may straddle two cache lines
            attribute = f'"prefer-vector-width"="{width}"'
            for function in mod.functions:
                if not function.is_declaration:
                    # llvmlite's FunctionAttributes.add accepts only its known keyword
                    # attributes; a string attribute is written out as it is
                    set.add(function.attributes, attribute)
                    set.add(function.attributes, f"alignstack({width // 8})")
        return original(self, mod, library)

    post_lowering._sweep_vector_width = True
    CPUContext.post_lowering = post_lowering
    CPUContext.get_preferred_array_alignment = get_preferred_array_alignment
