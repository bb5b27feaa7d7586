"""The one place that sets JIT flags and execution defaults, and the cache folder.

`sweep.kernels` reads these and nothing else; a test fails on a literal ``fastmath=`` in
`sweep/kernels/`. The flags are part of every kernel's memo and disk-cache key.
"""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

#: numba ``fastmath`` flags of the kernels and `sweep.kernels.vecmath`: none. Never
#: ``reassoc`` (it would let LLVM reorder sums, so results would drift from the NumPy
#: oracle and break `sweep.kernels.vecmath`'s exact argument reduction), nor
#: ``nnan``/``ninf`` (non-finite states must be detected), and no longer ``contract``:
#: the fused multiply-adds the kernels want are written explicitly (``vfma``,
#: `sweep.kernels.vecmath.fma`: the RK stages and updates, gravity onto the other
#: terms, the sine), because with ``contract`` LLVM chose which product of an
#: ``a * b + c * d`` to fuse by the code around it, so a lone trajectory, an unrolled
#: block of 8 and a vectorised block of 64 gave different last bits (measured, once
#: the sine changed). ``benchmarks/run_all.py`` times the flag sets (its flag table).
FASTMATH: bool | frozenset = frozenset()

#: Trajectories per block of the fixed-step kernels: the lanes one thread advances
#: together, step by step (a multiple of the SIMD width). Results do not depend on
#: it. Measured on the benchmark workload (2 cores, AVX-512): 64 -> 0.91, 128 -> 0.94,
#: 256 -> 0.95-0.98 of the C reference; 8 is not vectorised (0.12).
BLOCK = 128

#: The block for small grids (fewer than 16 blocks of BLOCK: less padding, and the
#: blocks still spread over the threads) and for early stop (a block ends when its
#: slowest lane is settled, so smaller blocks stop sooner).
SMALL_BLOCK = 64

#: Lanes per block of the adaptive kernel (`sweep.kernels.adaptive`). A block tries
#: steps until its slowest trajectory is done, so it costs BLOCK x the most attempts
#: of its trajectories. ``benchmarks/work_precision.py`` (its last table, 8192
#: trajectories): blocks of 16 are 16-24 % slower than blocks of 64 on the four
#: work-precision scenes and 12-14 % slower on an uneven grid (the phase plane with omega0
#: in [-20, 20] along the block); a block of 8 is left scalar by LLVM.
ADAPTIVE_BLOCK = 64

#: The adaptive kernels compute the step-size controller's factor ``err ** -0.2`` with
#: the lanes, vectorised (`sweep.kernels.vecmath.inverse_fifth_root`); False: with
#: libm's power, lane by lane (not vectorisable, but the faster choice for one
#: trajectory at a time: ``benchmarks/work_precision.py`` uses it for its baseline).
#: Step choices are the same (the two agree to 3 ulp); results differ in the last bits.
VECTOR_CONTROLLER = True

#: Early-stopped runs refill lanes (`sweep.kernels.refill`): a lane whose trajectory
#: settled takes the next waiting one instead of idling until its block's slowest
#: trajectory is done. Results do not depend on it; ``benchmarks/stop_early.py`` turns
#: it off to measure what it saves.
REFILL = True

#: Longest run (in steps) for which an early-stopped run with refill reads a shared
#: drive's sines from a table over the steps (8 bytes per step and sine: 2^21 steps of
#: RK4 forcing take 32 MiB); longer runs evaluate them per lane.
SINE_TABLE_STEPS = 1 << 21

#: Grids of fewer trajectories than this run one trajectory per block (no padding
#: lanes, the lanes plain variables: `sweep.kernels.lanes.scalar_lanes`): one trajectory
#: x 10^6 RK4 steps of the full scene runs at 35 M useful steps/s alone, 6.2 M/s in a
#: block of 64 (``benchmarks/run_all.py``); from 4 trajectories on, blocks of
#: `TINY_BLOCK` are faster (``benchmarks/blocks.py``, 2026-11-25, AMD EPYC Zen 5, 2 cores:
#: 1, 2, 4 trajectories 35 / 69 / 68 M/s narrow against 22 / 42 / 84 in blocks of 16).
NARROW_BELOW = 4

#: Lanes per block for grids of `NARROW_BELOW` to `TINY_BELOW` trajectories (without
#: early stop): blocks of 64 would leave a core idle there (one block for 64 starts), and
#: blocks of 8 are not vectorised. Measured (``benchmarks/blocks.py``, the full scene,
#: M useful trajectory-steps/s, 16 / 64 lanes): 8 starts 165 / 47, 32 starts 626 / 186,
#: 64 starts 630 / 370, 128 starts 631 / 712.
TINY_BLOCK = 16
TINY_BELOW = 128

#: dopri5's narrow path (one trajectory per block) below this many trajectories: it
#: beat blocks of 64 up to 12 trajectories (4.5 against 4.9 ms) and lost from 16 on
#: (4.4 against 4.0 ms; ``benchmarks/blocks.py``, same machine).
ADAPTIVE_NARROW_BELOW = 16

#: numba ``boundscheck``: off in production; tests index-check through the oracle.
BOUNDSCHECK = False

#: Most trajectories per chunk: the unit of progress reporting, checkpoints and Dask
#: tasks. Results do not depend on it.
CHUNK_SIZE = 1 << 16

#: Trajectory-steps of work per chunk when `sweep.run` chooses the chunk size: about one
#: second of the full scene on 2 cores (~3e8 trajectory-steps/s), so that a long run's
#: progress moves every second or so (a chunk of CHUNK_SIZE trajectories x 30,000 steps
#: would take 6 s). Never fewer than CHUNK_MIN trajectories, so that a chunk still has
#: blocks for every thread.
CHUNK_WORK = 3 * 10**8

#: Fewest trajectories per chunk chosen by `sweep.run` (16 blocks of BLOCK).
CHUNK_MIN = 16 * BLOCK


def jit_options() -> dict:
    """numba options of sweep's compiled helpers (`sweep.kernels.vecmath`): `FASTMATH`, in the
    form ``njit`` accepts (a set or a bool), and `BOUNDSCHECK`."""
    fastmath = FASTMATH if isinstance(FASTMATH, bool) else (set(FASTMATH) or False)
    return {"fastmath": fastmath, "boundscheck": BOUNDSCHECK}


#: SIMD vector width of the CPU kernels (`sweep.kernels.vectors`): ``"auto"`` (512 bits
#: where the CPU has AVX-512, else LLVM's choice), ``"llvm"`` (LLVM's tuning for the CPU:
#: 256 bits on Intel's AVX-512 cores), or 128, 256, 512. ``$SWEEP_VECTOR_WIDTH``
#: overrides it. Results do not depend on it.
VECTOR_WIDTH: str | int = "auto"

VECTOR_WIDTHS = ("auto", "llvm", 128, 256, 512)

#: Byte alignment of the arrays a CPU kernel allocates (its lanes; numba's default is
#: 32, `sweep.kernels.vectors`): 64, a 512-bit register, so that no vector load or store
#: of a lane array straddles two cache lines.
LANE_ALIGNMENT = 64

#: float32 CPU kernels are vectorised with as many lanes as a register holds float32s
#: (LLVM's ``-vectorizer-maximize-bandwidth``, set only while they compile:
#: `sweep.kernels.vectors`); False: as many as it holds float64s, the kernel's widest
#: type (the angle of the nonlinear pendulum stays float64). Results do not depend on it.
SINGLE_BY_NARROWEST = True


def vector_width() -> str | int:
    """The kernels' vector width setting: ``$SWEEP_VECTOR_WIDTH`` if set, else
    `VECTOR_WIDTH`.

    Returns
    -------
    {"auto", "llvm", 128, 256, 512}

    Raises
    ------
    ValueError
        For any other value, naming where it came from.
    """
    explicit = os.environ.get("SWEEP_VECTOR_WIDTH")
    where = "SWEEP_VECTOR_WIDTH" if explicit else "sweep._config.VECTOR_WIDTH"
    value = explicit.strip().lower() if explicit else VECTOR_WIDTH
    for accepted in VECTOR_WIDTHS:
        if str(value) == str(accepted):
            return accepted
    raise ValueError(f"{where}={value!r} is not a vector width; accepted: "
                     + ", ".join(str(w) for w in VECTOR_WIDTHS) + " (bits)")


def cache_dir() -> Path:
    """Folder for generated kernel sources and numba's on-disk cache.

    ``$SWEEP_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/sweep`` or ``~/.cache/sweep``.
    """
    explicit = os.environ.get("SWEEP_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sweep"


# ---------------------------------------------------------------- the cache folder, checked
# The kernel cache folder holds code that is executed (generated kernel modules, Python's
# bytecode, numba's pickled machine code, derived systems' source), so it is used only if
# nobody else can change it (`sweep.kernels.cache`'s docstring). These checks live here,
# below both of their users (`sweep.kernels.cache` and `sweep.physics.derive`).

def folder_problem(path: Path, own: bool) -> str | None:
    """What lets another user change the folder ``path``, or None.

    Parameters
    ----------
    path : Path
        An existing folder, or a symlink to one (NotADirectoryError otherwise).
    own : bool
        True for a folder of the cache itself (it must be the user's and writable by
        the user alone), False for a folder above it (the user's or root's, and not
        writable by others unless sticky).

    Returns
    -------
    str or None
        The problem (``"is owned by uid 1001 ..."``, ``"has mode 0777 ..."``), or None.
    """
    uid = os.getuid()
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode):
        if info.st_uid not in (uid, 0):
            return f"is a symlink owned by uid {info.st_uid}"
        info = os.stat(path)
    if not stat.S_ISDIR(info.st_mode):
        raise NotADirectoryError(f"{path} is not a folder")
    if info.st_uid != uid and (own or info.st_uid != 0):
        return f"is owned by uid {info.st_uid} (you are uid {uid})"
    mode = stat.S_IMODE(info.st_mode)
    if mode & 0o022 and (own or not mode & stat.S_ISVTX):
        return f"has mode {mode:04o} (writable by others{'' if own else ', not sticky'})"
    return None


def checked_folder(folder: Path, root: Path) -> str | None:
    """Create ``folder`` (each missing component 0700, once the one above it passed)
    and check it, its ancestors and, through symlinks, the real ones.

    Parameters
    ----------
    folder : Path
        The folder to use.
    root : Path
        ``folder`` or a folder above it: it and the folders below it must be the user's
        alone (``own``); the folders above it are checked as ancestors.

    Returns
    -------
    str or None
        ``"<path> <problem>"`` for the first unsafe component, None if all are safe.

    Raises
    ------
    OSError
        When a folder cannot be made (not writable, a file in the way).
    """
    if not hasattr(os, "getuid"):  # Windows: no POSIX owners and modes to check
        folder.mkdir(parents=True, exist_ok=True)
        return None
    folder, root = Path(os.path.abspath(folder)), Path(os.path.abspath(root))
    for lexical in (True, False):
        if not lexical:  # the folders the path leads to, past any symlink
            folder, root = Path(os.path.realpath(folder)), Path(os.path.realpath(root))
        for path in (*reversed(folder.parents), folder):
            if lexical and not os.path.lexists(path):
                try:
                    path.mkdir(mode=0o700)
                except FileExistsError:  # made meanwhile: checked below
                    pass
            problem = folder_problem(path, own=path == root or root in path.parents)
            if problem:
                return f"{path} {problem}"
    return None


def probe_writable(folder: Path) -> None:
    """Create a file in ``folder`` and remove it at once: what tells whether a file can be
    made there (`os.access` answers yes to root whatever the mode, and on a read-only
    file system). The file is this call's own (`tempfile.mkstemp`), so that concurrent
    probes of one folder never touch each other's.

    Raises
    ------
    OSError
        Where no file can be created in ``folder``.
    """
    fd, probe = tempfile.mkstemp(dir=folder, prefix=".write-probe-")
    os.close(fd)
    os.unlink(probe)


def kernel_folder() -> tuple[Path, str | None]:
    """The folder of generated kernel modules and derived systems' source, and what makes
    it unsafe, if anything.

    ``<cache_dir>/kernels`` (`cache_dir`), with its ``__pycache__``; if that cannot be
    made or written, ``<tmp>/sweep-kernels-<uid>`` (checked the same way).

    Returns
    -------
    folder : Path
    problem : str or None
        ``"<path> <problem>"`` (`checked_folder`) if another user could change it (the
        caller must then not use it), else None.
    """
    root = cache_dir()
    try:
        folder = root / "kernels"
        problem = checked_folder(folder / "__pycache__", root)
        if not problem:  # writable? A probe of this process's own (mkstemp): with one
            # shared name, two processes' touch and unlink raced (FileNotFoundError), and
            # the loser took the fallback folder below, so it compiled its kernels anew
            probe_writable(folder)
    except OSError:
        root = folder = Path(tempfile.gettempdir()) / f"sweep-kernels-{os.getuid()}"
        try:
            problem = checked_folder(folder / "__pycache__", root)
        except OSError as error:
            problem = f"{folder} cannot be made ({error})"
    return folder, problem
