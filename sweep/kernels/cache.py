"""Build a kernel: write its generated module once to the cache folder (named by the
hash of its text), import it, and let numba cache the machine code beside it, so a
fresh process loads the compiled kernel from disk. Built kernels are memoised in the
process too."""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path

from .. import _config
from .source import source
from .spec import KernelSpec

__all__ = ["build"]


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically unless an identical file is there
    (rewriting would change its mtime and invalidate numba's cache index)."""
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, path)


def _module_dir() -> Path:
    folder = _config.cache_dir() / "kernels"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".write-probe"
        probe.touch()
        probe.unlink()
    except OSError:
        folder = Path(tempfile.gettempdir()) / f"sweep-kernels-{os.getuid()}"
        folder.mkdir(parents=True, exist_ok=True)
    return folder


@functools.lru_cache(maxsize=None)
def build(spec: KernelSpec):
    """Return the compiled kernel for ``spec`` (memoised; disk-cached by numba).

    Parameters
    ----------
    spec : KernelSpec

    Returns
    -------
    callable
        The ``kernel`` of the generated module, compiled on first call: a numba
        dispatcher, or for a refill kernel (`sweep.kernels.refill`) a Python function
        that reads the thread count and calls one.
    """
    text = source(spec)
    digest = hashlib.sha1(text.encode()).hexdigest()[:16]
    name = f"sweep_kernel_{digest}"
    path = _module_dir() / f"{name}.py"
    _write_once(path, text)
    module_spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    module_spec.loader.exec_module(module)
    return module.kernel
