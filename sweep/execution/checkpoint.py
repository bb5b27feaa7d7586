"""Chunk checkpoints: a long sweep that is interrupted resumes where it stopped.

`sweep.run(..., checkpoint=FOLDER)` writes each finished chunk of trajectories to
``FOLDER``; `sweep.run(..., checkpoint=FOLDER, resume=True)` loads the chunks already
there instead of recomputing them. The kernel is deterministic and its results do not
depend on the chunking, so a resumed run returns a dataset bit-identical to an
uninterrupted one.

Layout of a checkpoint folder::

    FOLDER/manifest.json                     fingerprint of the run (see `fingerprint`)
    FOLDER/chunk-000000000000-000000000100.npz   rows start:stop of the outputs
    ...

Every file is written to a temporary file in the folder, fsynced and renamed into place
(`os.replace`, then the folder is fsynced): a chunk file either exists complete or not
at all, whatever kills the process (Ctrl-C, SIGTERM, SIGKILL, power loss). Temporary
files a killed process left behind are ignored and cleaned up. A chunk file that cannot
be read (a damaged zip archive: numpy's ``.npz`` checks each array's CRC-32) or does not
hold the expected shapes and dtypes is recomputed, with a `DamagedChunkWarning` naming
the file and why. A failed write (a full disk) raises an OSError naming the file; the
chunks stored before it stay.

One writer per folder: ``FOLDER/lock`` names the process (pid, host) whose run writes
the folder, and a second run (another process, or another thread) is refused while
that one is alive, naming it; a lock left by a dead process on this host is taken over
(`sweep.execution.lock`). The lock is released when the run completes or fails.

The manifest records a fingerprint of everything that determines the results: the
scene, the grid (axis names, sizes and a SHA-256 of each axis's values), the
time-stepping settings, the kernel spec, the attractor catalogue (a SHA-256 of the
kernel's ``catalogue`` argument), the chunk size and the sweep version. Resuming
with a checkpoint whose fingerprint differs is refused with a ValueError that names
each difference.

When the run completes, `sweep.run` removes the checkpoint files it wrote (and the
folder, if that leaves it empty) unless ``keep_checkpoint=True``; the ``sweep run``
command keeps them until the output file is saved, then removes them.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import tempfile
import warnings
from pathlib import Path

import numpy as np

from . import lock as _lock

__all__ = ["Checkpoint", "DamagedChunkWarning", "fingerprint", "open_checkpoint", "remove",
           "size_bound", "stored_bytes"]

MANIFEST = "manifest.json"

#: Checkpoint layout version; bumped when the file layout changes.
FORMAT = 1

_CHUNK = re.compile(r"^chunk-(\d{12})-(\d{12})\.npz$")
_TEMP_PREFIX = ".tmp-"

#: Bytes `size_bound` allows per chunk file besides its arrays: the ``.npz`` archive's
#: zip and ``.npy`` headers (988 bytes for four arrays, measured) and the file system's
#: rounding up to a whole block (4 KiB).
CHUNK_FILE_BYTES = 8 * 1024

#: Bytes `size_bound` allows for the manifest and the lock file (2 KiB, each rounded up
#: to a whole block).
FOLDER_BYTES = 16 * 1024


class DamagedChunkWarning(UserWarning):
    """A stored chunk could not be used on resume and is recomputed (the message
    names the file and why)."""


def _chunk_name(start: int, stop: int) -> str:
    return f"chunk-{start:012d}-{stop:012d}.npz"


def fingerprint(*, scene, grid, settings, spec, chunk_size: int, version: str,
                catalogue=None) -> dict:
    """JSON-ready description of everything that determines a run's results.

    Parameters
    ----------
    scene : Scene
    grid : Grid
    settings : sweep.engine.RunSettings
    spec : sweep.kernels.KernelSpec
    chunk_size : int
    version : str
        The sweep version.
    catalogue : numpy.ndarray, optional
        The kernel's ``catalogue`` argument (the ``attractor`` observable's,
        `sweep.kernels.snippets.catalogue_argument`): data, not part of the spec.

    Returns
    -------
    dict
        Nested dicts of str, int, float, bool, None and lists only.
    """
    from .. import _config

    integrator = settings.integrator
    fp = {
        "format": FORMAT,
        "sweep_version": version,
        "scene": scene.to_dict(),
        "grid": {
            "dims": list(grid.dims),
            "shape": list(grid.shape),
            "sha256": {name: hashlib.sha256(np.ascontiguousarray(values, dtype="<f8")
                                            .tobytes()).hexdigest()
                       for name, values in grid.axes.items()},
        },
        "run": {
            "t0": settings.t0, "t_end": settings.t_end, "dt": settings.dt,
            "t_transient": settings.t_transient, "n_steps": settings.n_steps,
            "n_transient": settings.n_transient, "save_every": settings.save_every,
            "method": settings.method, "rtol": settings.rtol, "atol": settings.atol,
            "integrator": integrator.name if _is_registered(integrator) else repr(integrator),
        },
        # every field of the spec (what changes the compiled code), and the JIT flags
        "kernel": {**{field.name: _plain(getattr(spec, field.name))
                      for field in dataclasses.fields(spec)},
                   "fastmath": repr(_config.FASTMATH)},
        "chunk_size": int(chunk_size),
    }
    if catalogue is not None:
        fp["catalogue"] = {"shape": list(np.shape(catalogue)), "sha256": hashlib.sha256(
            np.ascontiguousarray(catalogue, dtype="<f8").tobytes()).hexdigest()}
    return json.loads(json.dumps(fp))  # tuples -> lists, as they read back


def _plain(value):
    """A JSON value for a KernelSpec field: scalars and tuples as such, objects (a
    custom method) as their repr."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, (tuple, list)):
        return [_plain(item) for item in value]
    return repr(value)


def _is_registered(method) -> bool:
    from ..methods import METHODS

    return METHODS.get(getattr(method, "name", None)) == method


def _flatten(value, prefix: str = "") -> dict:
    if isinstance(value, dict):
        flat = {}
        for key, item in value.items():
            flat.update(_flatten(item, f"{prefix}.{key}" if prefix else str(key)))
        return flat
    return {prefix: value}


def _differences(stored: dict, current: dict) -> list[str]:
    a, b = _flatten(stored), _flatten(current)
    lines = []
    for key in sorted(set(a) | set(b)):
        if a.get(key, "<absent>") != b.get(key, "<absent>"):
            lines.append(f"{key}: checkpoint {_short(a.get(key, '<absent>'))}, "
                         f"this run {_short(b.get(key, '<absent>'))}")
    return lines


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def size_bound(spec, settings, n: int, chunk_size: int) -> int:
    """An upper bound, in bytes, of a complete checkpoint of a run of ``n`` trajectories
    in chunks of ``chunk_size``: every chunk file (the rows of the arrays the kernel
    writes, `sweep.execution.local.allocate`, stored uncompressed, plus
    `CHUNK_FILE_BYTES`) and `FOLDER_BYTES`.

    Parameters
    ----------
    spec : sweep.kernels.KernelSpec
    settings : sweep.engine.RunSettings
    n, chunk_size : int

    Returns
    -------
    int
    """
    from .local import allocate

    row = sum(array.dtype.itemsize * int(np.prod(array.shape[1:]))
              for array in allocate(spec, settings, 0).values())
    chunks = -(-int(n) // int(chunk_size))
    return int(n) * row + chunks * CHUNK_FILE_BYTES + FOLDER_BYTES


def stored_bytes(folder) -> int:
    """Bytes of the chunk files in the checkpoint folder ``folder`` (0 if absent)."""
    folder = Path(folder)
    if not folder.is_dir():
        return 0
    total = 0
    for path in folder.iterdir():
        if _CHUNK.match(path.name):
            try:
                total += path.stat().st_size
            except OSError:
                pass
    return total


def _write_atomically(folder: Path, name: str, write) -> None:
    """``write(handle)`` into a temporary file in ``folder``, fsync, rename to ``name``.

    Raises
    ------
    OSError
        Naming the file (``folder / name``), with the errno of the failure (a full
        disk: ENOSPC); the temporary file is gone.
    """
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f"{_TEMP_PREFIX}{name}.")
    try:
        with os.fdopen(fd, "wb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, folder / name)
        _sync_folder(folder)
    except BaseException as exc:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno is not None and exc.filename is None:
            raise OSError(exc.errno, f"cannot write checkpoint file "
                          f"{str(folder / name)!r}: {exc.strerror}") from None
        raise


def _sync_folder(folder: Path) -> None:
    """fsync the folder so that a rename survives a power loss (best effort)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms that cannot open folders
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


class Checkpoint:
    """An open checkpoint folder: `restore` and `store` chunks of a run.

    Use `open_checkpoint` to create one (it checks the fingerprint).
    """

    def __init__(self, folder: Path, chunks: dict[tuple[int, int], Path]) -> None:
        self.folder = folder
        self.lock = None   #: the folder's `sweep.execution.lock.FolderLock`, once taken
        self._chunks = chunks
        self.resumed = 0   #: chunks loaded instead of computed
        self.stored = 0    #: chunks computed and written

    @property
    def chunks(self) -> list[tuple[int, int]]:
        """``(start, stop)`` of the chunks present in the folder."""
        return sorted(self._chunks)

    def restore(self, start: int, stop: int, arrays: dict[str, np.ndarray]) -> bool:
        """Fill ``arrays[name][start:stop]`` from the stored chunk; False if absent.

        A chunk file that cannot be read or does not have the expected shapes and
        dtypes is treated as absent (recomputed and rewritten), with a
        `DamagedChunkWarning` naming the file and why.
        """
        path = self._chunks.get((start, stop))
        if path is None:
            return False
        try:
            with np.load(path, allow_pickle=False) as stored:
                loaded = {name: stored[name] for name in arrays}
        except Exception as exc:  # noqa: BLE001 - any damage (BadZipFile, EOFError, ...)
            reason = " ".join(str(exc).split())
            return _damaged(path, f"{type(exc).__name__}: {reason}" if reason else
                            type(exc).__name__)
        for name, target in arrays.items():
            part = target[start:stop]
            if loaded[name].shape != part.shape or loaded[name].dtype != part.dtype:
                return _damaged(path, f"its {name!r} is {loaded[name].dtype}"
                                f"{list(loaded[name].shape)}, expected {part.dtype}"
                                f"{list(part.shape)}")
        for name, target in arrays.items():
            target[start:stop] = loaded[name]
        self.resumed += 1
        return True

    def store(self, start: int, stop: int, arrays: dict[str, np.ndarray]) -> None:
        """Write rows ``start:stop`` of each array as one chunk file, atomically."""
        name = _chunk_name(start, stop)
        parts = {key: np.ascontiguousarray(value[start:stop]) for key, value in arrays.items()}
        _write_atomically(self.folder, name, lambda handle: np.savez(handle, **parts))
        self._chunks[(start, stop)] = self.folder / name
        self.stored += 1

    def release(self) -> None:
        """Let go of the folder's lock (idempotent): another run may then write it."""
        if self.lock is not None:
            self.lock.release()

    def remove(self) -> None:
        """Delete the files of this checkpoint (and the folder if that empties it)."""
        self.release()
        remove(self.folder)


def _damaged(path: Path, why: str) -> bool:
    """Warn that the chunk file ``path`` cannot be used (``why``); return False."""
    warnings.warn(f"checkpoint chunk {str(path)!r} is damaged ({why}); it is recomputed",
                  DamagedChunkWarning, stacklevel=3)
    return False


def _is_ours(name: str) -> bool:
    return (name in (MANIFEST, _lock.LOCK) or bool(_CHUNK.match(name))
            or name.startswith(_TEMP_PREFIX))


def remove(folder) -> None:
    """Delete a checkpoint's manifest, chunk and temporary files; then the folder if
    it is empty. Other files are never touched; a missing folder is no error."""
    folder = Path(folder)
    if not folder.is_dir():
        return
    for path in folder.iterdir():  # a lock file is its owner's to remove
        if _is_ours(path.name) and path.name != _lock.LOCK and path.is_file():
            path.unlink(missing_ok=True)
    try:
        folder.rmdir()
    except OSError:
        pass  # not empty: the user's own files stay


def open_checkpoint(folder, fp: dict, *, resume: bool) -> Checkpoint:
    """Open (or create) the checkpoint folder ``folder`` for the run ``fp``.

    Parameters
    ----------
    folder : str or Path
        Created if missing (its parent must exist).
    fp : dict
        The run's `fingerprint`.
    resume : bool
        True: reuse the chunks of a checkpoint of the same run (an absent or empty
        checkpoint starts from scratch). False: the folder must not hold a checkpoint
        already, so that an hour of work is never overwritten by mistake.

    Raises
    ------
    ValueError
        The folder's parent is missing, the path is not a folder, it holds another
        run's checkpoint (each difference named), it holds a checkpoint and ``resume``
        is False, or it holds other files but no checkpoint.
    sweep.execution.lock.CheckpointInUseError
        (a ValueError) Another live run writes the folder; its pid and host are named.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"checkpoint {str(folder)!r} exists and is not a folder; accepted: "
                         "a folder path (created if missing)")
    if not folder.exists():
        parent = folder.parent if str(folder.parent) else Path(".")
        if not parent.is_dir():
            raise ValueError(f"checkpoint {str(folder)!r}: folder {str(parent)!r} does not "
                             "exist; accepted: a path in an existing folder")
        folder.mkdir()
    lock = _lock.acquire(folder)
    try:
        checkpoint = _open_locked(folder, fp, resume=resume)
    except BaseException:
        lock.release()
        raise
    checkpoint.lock = lock
    return checkpoint


def _open_locked(folder: Path, fp: dict, *, resume: bool) -> Checkpoint:
    """`open_checkpoint` once the folder exists and its lock is held."""
    names = [p.name for p in folder.iterdir() if p.name != _lock.LOCK]
    manifest = folder / MANIFEST
    if MANIFEST not in names:
        foreign = [n for n in names if not _is_ours(n)]
        if foreign:
            raise ValueError(f"checkpoint folder {str(folder)!r} holds other files "
                             f"({foreign[0]!r}, ...) and no sweep checkpoint; accepted: an "
                             "empty or new folder, or a sweep checkpoint folder")
        remove_stale = [folder / n for n in names]  # chunks without a manifest: orphans
        for path in remove_stale:
            path.unlink(missing_ok=True)
        _write_manifest(folder, fp)
        return Checkpoint(folder, {})
    try:
        stored = json.loads(manifest.read_text())["fingerprint"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"checkpoint {str(folder)!r}: unreadable {MANIFEST} ({exc}); "
                         "accepted: a checkpoint written by sweep (remove the folder to "
                         "start over)") from None
    chunks = {}
    for name in names:
        match = _CHUNK.match(name)
        if match:
            chunks[(int(match[1]), int(match[2]))] = folder / name
    if not resume:
        raise ValueError(f"checkpoint {str(folder)!r} already holds a run ({len(chunks)} "
                         "finished chunks); accepted: resume=True (sweep run --resume) to "
                         "continue it, or remove the folder to start over")
    differences = _differences(stored, fp)
    if differences:
        raise ValueError(f"checkpoint {str(folder)!r} belongs to a different run: "
                         + "; ".join(differences)
                         + "; accepted: the same scene, grid and run settings (or remove "
                         "the folder to start over)")
    for name in names:  # temporary files of a process killed while writing
        if name.startswith(_TEMP_PREFIX):
            (folder / name).unlink(missing_ok=True)
    return Checkpoint(folder, chunks)


def _write_manifest(folder: Path, fp: dict) -> None:
    text = json.dumps({"fingerprint": fp}, indent=1, sort_keys=True).encode()
    _write_atomically(folder, MANIFEST, lambda handle: handle.write(text))
