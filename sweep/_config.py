"""The one place that sets JIT flags and execution defaults.

`_kernels` reads these and nothing else; a test fails on a literal ``fastmath=`` in
`_kernels.py`. The flags are part of every kernel's memo and disk-cache key.
"""

from __future__ import annotations

import os
from pathlib import Path

#: numba ``fastmath``. Off: reassociation makes results drift from the NumPy
#: oracle and between machines. (The performance issue may switch on a set
#: *without* ``reassoc`` and justify it with a benchmark.)
FASTMATH: bool | frozenset = False

#: numba ``boundscheck``: off in production; tests index-check through the oracle.
BOUNDSCHECK = False

#: Trajectories per chunk: the unit of progress reporting (and, later, of
#: checkpoints and distributed tasks). Results do not depend on it.
CHUNK_SIZE = 1 << 16


def cache_dir() -> Path:
    """Folder for generated kernel sources and numba's on-disk cache.

    ``$SWEEP_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/sweep`` or ``~/.cache/sweep``.
    """
    explicit = os.environ.get("SWEEP_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "sweep"
