"""Build a kernel: write its generated module once to the cache folder (named by the
hash of its text), import it, and let numba cache the machine code beside it, so a
fresh process loads the compiled kernel from disk. Built kernels are memoised in the
process too.

The cache folder holds code that is executed (the modules, Python's bytecode and
numba's pickled machine code in ``__pycache__``), so it is used only if nobody else
can change it: the folder, its ``__pycache__`` and the configured cache root must be
owned by the user and not writable by group or others, and every folder above them
owned by the user or root and not writable by others unless sticky (like ``/tmp``);
a symlink on the way must be the user's or root's. Folders sweep creates are 0700.
An unsafe folder is refused with one `UnsafeCacheWarning` per process and kernels
go to a private folder of the process (`tempfile.mkdtemp`), compiled anew by each
process.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib.util
import os
import shutil
import sys
import tempfile
import threading
import warnings
from pathlib import Path

from .. import _config
from .network import NetworkSpec
from .source import source
from .spec import KernelSpec

__all__ = ["UnsafeCacheWarning", "build", "compiled"]


class UnsafeCacheWarning(UserWarning):
    """The kernel cache folder could be changed by another user, so it is not used."""


_lock = threading.Lock()
_private: Path | None = None  # this process's fallback folder, made once
_warned = False


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically unless an identical file is there
    (rewriting would change its mtime and invalidate numba's cache index)."""
    if path.exists() and path.read_text() == text:
        return
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, path)


def _serialise_numba_index() -> None:
    """Make numba's update of a cache index one step for concurrent processes.

    numba (0.68) saves a compiled signature by reading the function's index (``.nbi``),
    picking the first free data file name (``<function>.1.nbc``, ``.2.nbc``, ...),
    rewriting the index and writing the data, each file atomically but the whole without
    a lock. Two processes saving *different* signatures of one function at once (two
    pytest-xdist workers or Dask workers compiling a `sweep.kernels.vecmath` helper for
    float32 and float64) can both pick ``.1.nbc``: the index left may then map one
    signature to the other's machine code, which a later process loads and runs
    (reproduced by forcing that interleaving; same-signature saves are harmless).
    Here each save holds an exclusive advisory lock (``flock``) on the cache folder, so
    the read, the choice and the writes of one save happen together. Without ``fcntl``
    (Windows) or a numba that moved the class, nothing changes. Called by `build` and
    `sweep.maps._strobe` (not at ``import sweep``, which imports no numba)."""
    try:
        import fcntl

        from numba.core.caching import IndexDataCacheFile
    except ImportError:  # pragma: no cover - Windows, or numba's internals moved
        return
    save = IndexDataCacheFile.save
    if getattr(save, "_sweep_serialised", False):
        return

    @functools.wraps(save)
    def serialised_save(self, key, data):
        try:
            folder = os.open(self._cache_path, os.O_RDONLY)
        except (OSError, AttributeError):  # pragma: no cover - as numba would have failed
            return save(self, key, data)
        try:
            fcntl.flock(folder, fcntl.LOCK_EX)
            return save(self, key, data)
        finally:
            os.close(folder)  # releases the lock

    serialised_save._sweep_serialised = True
    IndexDataCacheFile.save = serialised_save


def _private_folder() -> Path:
    """This process's own folder (0700, unpredictable name), made on first use and
    removed at exit."""
    global _private
    if _private is None:
        _private = Path(tempfile.mkdtemp(prefix="sweep-kernels-"))
        atexit.register(shutil.rmtree, _private, ignore_errors=True)
        (_private / "__pycache__").mkdir(mode=0o700)  # Python's and numba's caches
    return _private


def _module_dir() -> Path:
    """The folder of the generated modules: `sweep._config.kernel_folder` (``<cache_dir>/
    kernels``, or ``<tmp>/sweep-kernels-<uid>`` if that cannot be written), or, if the one
    chosen is unsafe, this process's private folder (with one warning per process)."""
    global _warned
    folder, problem = _config.kernel_folder()
    if not problem:
        return folder
    with _lock:
        private = _private_folder()
        if not _warned:
            _warned = True
            warnings.warn(
                f"sweep does not use the kernel cache folder: {problem}, so another user "
                f"could plant code that sweep runs. Kernels go to {private} instead, for "
                f"this process only (compiled anew by every process). To fix: make it a "
                f"folder of yours that only you can write (chmod 700), inside folders "
                f"others cannot change, or set SWEEP_CACHE_DIR to one.",
                UnsafeCacheWarning, stacklevel=3)
    return private


def build(spec: KernelSpec):
    """Return the compiled kernel for ``spec`` (memoised; disk-cached by numba).

    Parameters
    ----------
    spec : KernelSpec

    Returns
    -------
    callable
        The ``kernel`` of the generated module: a Python function that calls the
        module's numba function (compiled on its first call; `compiled`) on threads
        (`sweep.kernels.threads`), or on the GPU for ``device="cuda"``.

    Warns
    -----
    UnsafeCacheWarning
        Once per process, when the cache folder could be changed by another user (see
        the module's docstring); kernels are then built in a private folder.
    """
    if isinstance(spec, NetworkSpec):  # its CPU kernel takes the network as arguments
        spec = spec.code
    return _build(spec, _config.vector_width(), _config.LANE_ALIGNMENT,
                  _config.SINGLE_BY_NARROWEST)


@functools.cache
def _build(spec: KernelSpec, *settings):
    """`build` for one set of the `sweep._config` settings written into the source
    (`sweep.kernels.vectors`), which are so part of the memo key."""
    module = _module(source(spec))
    bind = getattr(module, "bind", None)  # a CPU kernel, for blocks of spec.block lanes
    return module.kernel if bind is None else bind(spec.block)


@functools.cache
def _module(text: str):
    """The kernel module of ``text``, written once and imported once per process: the
    specs that differ only by their block share it (`sweep.kernels.lanes.BIND`)."""
    _serialise_numba_index()
    digest = hashlib.sha1(text.encode()).hexdigest()[:16]
    name = f"sweep_kernel_{digest}"
    path = _module_dir() / f"{name}.py"
    _write_once(path, text)
    module_spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    module_spec.loader.exec_module(module)
    return module


def compiled(kernel):
    """The numba function that does the work of a CPU kernel from `build`: its
    ``blocks`` (a refill kernel's ``grouped``), for its machine code, types and cache
    statistics (``inspect_asm``, ``overloads``, ``stats``)."""
    names = kernel.__globals__
    return names["grouped"] if "grouped" in names else names["blocks"]


def _cache_clear() -> None:
    """Forget every built kernel and imported module (a new `build` imports the module
    again, and numba loads it from its disk cache)."""
    _build.cache_clear()
    _module.cache_clear()


build.cache_info = _build.cache_info  # the memo's statistics and reset, as on a
build.cache_clear = _cache_clear  # functools.cache'd build (tests, benchmarks)
