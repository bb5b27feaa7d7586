"""One writer per checkpoint folder: a lock file naming its owner.

``FOLDER/lock`` holds ``{"pid": ..., "host": ..., "started": ...}`` of the process
whose run writes the folder. While that run is alive, a second one (another process,
or another thread of the same process) is refused with `CheckpointInUseError`, naming
the holder. The owner keeps an exclusive ``flock`` on the file, which the kernel drops
when the process dies however it dies; a lock file left by a dead process on this host
(its pid no longer alive, or its flock gone) is stale and taken over. A lock of another
host cannot be checked from here: it is refused, and the message says which file to
delete if that run is gone.

The lock is released (file removed) when the run completes, and when it fails or is
interrupted: explicitly by `sweep.run`, or when the `Checkpoint` holding it is
collected; a later run in the same thread takes over a lock its own earlier, failed run
still holds (an interactive session keeps the last traceback, and with it that run). A
process about to end without unwinding (``os._exit``, which runs no finalizers: the
``sweep run`` command stopped by SIGTERM during a long chunk) calls `release_all`.
"""

from __future__ import annotations

import errno
import json
import os
import socket
import threading
import time
import weakref
from pathlib import Path

try:  # POSIX; elsewhere only the pid check guards the folder
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None

__all__ = ["LOCK", "CheckpointInUseError", "FolderLock", "acquire", "release_all"]

#: Name of the lock file in a checkpoint folder.
LOCK = "lock"

# folder (resolved) -> (weak reference to its FolderLock, id of the thread that took it)
_HELD: dict[str, tuple[weakref.ref, int]] = {}
_HELD_GUARD = threading.Lock()


class CheckpointInUseError(ValueError):
    """Another live run writes this checkpoint folder."""


def _pid_alive(pid: int) -> bool:
    """True if a process ``pid`` exists on this host (ours or another user's)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def _describe(holder: dict, path: Path) -> str:
    started = holder.get("started")
    when = (time.strftime(", started %Y-%m-%d %H:%M:%S", time.localtime(started))
            if isinstance(started, (int, float)) else "")
    return f"pid {holder.get('pid')!r} on host {holder.get('host')!r}{when}, lock file " \
           f"{str(path)!r}"


class FolderLock:
    """The lock of one checkpoint folder, held by this process (see the module
    docstring). Use `acquire`; `release` is idempotent."""

    def __init__(self, path: Path, fd: int) -> None:
        self.path = path
        self._fd = fd
        self._finalizer = weakref.finalize(self, FolderLock._drop, path, fd)

    @staticmethod
    def _drop(path: Path, fd: int) -> None:
        try:  # remove the file first: nobody may lock the old inode after we let go
            if os.fstat(fd).st_ino == os.stat(path).st_ino:
                os.unlink(path)
        except OSError:
            pass
        try:
            os.close(fd)
        except OSError:
            pass

    @property
    def held(self) -> bool:
        """True until `release`."""
        return self._finalizer.alive

    def release(self) -> None:
        """Remove the lock file and let go of the lock (no error if already released)."""
        self._finalizer()


def _read(fd: int) -> dict | None:
    os.lseek(fd, 0, os.SEEK_SET)
    data = b""
    while chunk := os.read(fd, 4096):
        data += chunk
    try:
        holder = json.loads(data.decode())
    except (UnicodeDecodeError, ValueError):
        return None
    return holder if isinstance(holder, dict) else None


def acquire(folder) -> FolderLock:
    """Take the lock of the checkpoint folder ``folder`` (which must exist).

    Returns
    -------
    FolderLock
        Held until its `release` (or until it is collected).

    Raises
    ------
    CheckpointInUseError
        A live run (this or another process, this host or another) holds the folder;
        the message names its pid, host and start time.
    """
    folder = Path(folder)
    path = folder / LOCK
    key = str(folder.resolve())
    me = {"pid": os.getpid(), "host": socket.gethostname()}
    with _HELD_GUARD:
        previous = _HELD.get(key)
        lock = previous[0]() if previous else None
        if lock is not None and lock.held:
            if previous[1] != threading.get_ident() and _thread_alive(previous[1]):
                raise CheckpointInUseError(
                    f"checkpoint {str(folder)!r} is being written by another run in this "
                    f"process (thread {previous[1]}); accepted: one run per checkpoint "
                    "folder at a time (wait for it, or give this run another folder)")
            lock.release()  # this thread's own earlier run, failed or interrupted
        for _ in range(100):  # retried only when the file is replaced under us
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                locked = _flock(fd)
                holder = _read(fd)
                if locked is False:
                    raise CheckpointInUseError(_in_use(folder, holder, path))
                if os.fstat(fd).st_ino != _inode(path):
                    os.close(fd)  # released and removed between our open and flock
                    continue
                if holder and not _stale(holder, me, locked):
                    raise CheckpointInUseError(_in_use(folder, holder, path))
                record = json.dumps({**me, "started": time.time()}).encode()
                os.ftruncate(fd, 0)
                os.pwrite(fd, record, 0)
                os.fsync(fd)
            except BaseException:
                os.close(fd)
                raise
            lock = FolderLock(path, fd)
            _HELD[key] = (weakref.ref(lock), threading.get_ident())
            return lock
    raise CheckpointInUseError(  # pragma: no cover
        f"checkpoint {str(folder)!r}: its lock file keeps changing; accepted: one run per "
        "checkpoint folder")


def release_all() -> None:
    """Release every checkpoint lock this process holds (any thread's): for a process
    about to end with ``os._exit``, which would leave the lock files behind."""
    with _HELD_GUARD:
        locks = [ref() for ref, _ in _HELD.values()]
    for lock in locks:
        if lock is not None:
            lock.release()


def _thread_alive(ident: int) -> bool:
    return any(t.ident == ident for t in threading.enumerate())


def _inode(path: Path) -> int | None:
    try:
        return os.stat(path).st_ino
    except FileNotFoundError:
        return None


def _flock(fd: int) -> bool | None:
    """True: exclusive flock taken; False: someone holds it; None: not supported here."""
    if fcntl is None:  # pragma: no cover
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            return False
        return None  # e.g. a file system without flock: rely on the pid check
    return True


def _stale(holder: dict, me: dict, locked: bool | None) -> bool:
    """Whether a lock file's holder is gone (so its lock may be taken over)."""
    if holder.get("host") != me["host"]:
        return False  # cannot tell from here whether a process elsewhere is alive
    pid = holder.get("pid")
    if not isinstance(pid, int) or not _pid_alive(pid):
        return True
    # alive on this host: stale only if we got its flock (the owner lets go of it only
    # by dying, so this pid was reused) -- or it is this very process, whose earlier
    # lock of this folder was released already
    return locked is True or pid == me["pid"]


def _in_use(folder: Path, holder: dict | None, path: Path) -> str:
    who = _describe(holder, path) if holder else f"lock file {str(path)!r}"
    return (f"checkpoint {str(folder)!r} is in use by another run ({who}); accepted: one "
            "run per checkpoint folder: wait for that run to finish, or give this run "
            "another folder (if that run is gone, delete the lock file)")
