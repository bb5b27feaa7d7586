"""One writer per checkpoint folder (`sweep.execution.lock`): a second live run is
refused naming the holder, a dead holder's lock is taken over, and the lock goes away
when a run completes or fails. Real processes where it matters; every wait bounded."""

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import sweep
from sweep.execution import checkpoint as ckpt
from sweep.execution import lock as _lock

from test_resume import (
    CHUNK,
    GRID,
    KWARGS,
    SCENE,
    SLOW_RUN_FILE,
    WAIT_S,
    Interrupt,
    _finish,
    _sweep,
    chunk_files,
)

HOST = socket.gethostname()


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped): not alive any more."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait(timeout=WAIT_S)
    return process.pid


def _try_lock(folder) -> subprocess.CompletedProcess:
    """Another process tries to take the folder's lock (and lets go at once)."""
    code = ("import sys; from sweep.execution import lock\n"
            "try:\n    lock.acquire(sys.argv[1]).release()\n"
            "except lock.CheckpointInUseError as exc:\n    print(exc); sys.exit(3)\n")
    return subprocess.run([sys.executable, "-c", code, str(folder)], capture_output=True,
                          text=True, timeout=WAIT_S)


def test_a_second_process_is_refused_and_a_killed_holder_is_taken_over(tmp_path):
    run_file = tmp_path / "run.toml"
    run_file.write_text(SLOW_RUN_FILE)
    out, folder = tmp_path / "out.nc", tmp_path / "ck"
    first = _sweep("run", run_file, "-o", out, "--checkpoint", folder)
    try:
        deadline = time.monotonic() + WAIT_S
        while len(chunk_files(folder)) < 1:  # the lock is taken before any chunk runs
            assert first.poll() is None, first.communicate()
            assert time.monotonic() < deadline, "no chunk checkpointed in time"
            time.sleep(0.01)
        holder = json.loads((folder / _lock.LOCK).read_text())
        assert holder["pid"] == first.pid and holder["host"] == HOST
        # stopped, the first run holds its lock and stays alive however long the second
        # takes to start (its whole run takes ~3 s: on a busy machine, as under
        # pytest-xdist, it could end and release the lock before the second looked)
        first.send_signal(signal.SIGSTOP)
        # a second `sweep run` on the same folder while the first is alive
        second = subprocess.run([sys.executable, "-m", "sweep", "run", str(run_file), "-o",
                                 str(tmp_path / "other.nc"), "--checkpoint", str(folder),
                                 "--resume"], capture_output=True, text=True,
                                timeout=WAIT_S, env={**os.environ})
        assert second.returncode == 2, second.stderr
        assert second.stderr.count("\n") == 1 and "Traceback" not in second.stderr
        assert (f"sweep: error: checkpoint '{folder}' is in use by another run (pid "
                f"{first.pid} on host '{HOST}', started ") in second.stderr
        assert not (tmp_path / "other.nc").exists()
        assert first.poll() is None  # the first run was not disturbed
        first.send_signal(signal.SIGKILL)
    finally:
        if first.poll() is None:
            first.kill()
        first.communicate(timeout=WAIT_S)
    # the killed run left its lock file: stale (its pid is gone), taken over by --resume
    assert json.loads((folder / _lock.LOCK).read_text())["pid"] == first.pid
    code, _, stderr = _finish(_sweep("run", run_file, "-o", out, "--checkpoint", folder,
                                     "--resume"))
    assert code == 0, stderr
    assert out.is_file() and not folder.exists()  # lock released, checkpoint removed


def test_a_second_run_in_another_thread_is_refused(tmp_path):
    folder = tmp_path / "ck"
    folder.mkdir()
    held = _lock.acquire(folder)
    errors = []

    def other():
        try:
            sweep.run(SCENE, GRID, checkpoint=folder, resume=True, **KWARGS)
        except _lock.CheckpointInUseError as exc:
            errors.append(str(exc))

    thread = threading.Thread(target=other)
    thread.start()
    thread.join(WAIT_S)
    held.release()
    assert len(errors) == 1 and "is being written by another run in this process" in \
        errors[0]
    assert not (folder / _lock.LOCK).exists()


def test_stale_and_foreign_locks(tmp_path):
    folder = tmp_path / "ck"
    folder.mkdir()
    path = folder / _lock.LOCK
    path.write_text(json.dumps({"pid": _dead_pid(), "host": HOST, "started": 0.0}))
    lock = _lock.acquire(folder)  # stale on this host: taken over
    assert json.loads(path.read_text())["pid"] == os.getpid()
    lock.release()
    assert not path.exists()
    # a lock of another host cannot be checked from here: refused, naming file and host
    path.write_text(json.dumps({"pid": 1, "host": "elsewhere.example", "started": 0.0}))
    with pytest.raises(_lock.CheckpointInUseError,
                       match=r"in use by another run \(pid 1 on host 'elsewhere\.example', "
                             r"started .*lock file '.*/ck/lock'\).*delete the lock file"):
        _lock.acquire(folder)
    path.unlink()
    # a live holder in another process is refused; once it lets go, the folder is free
    assert _try_lock(folder).returncode == 0
    held = _lock.acquire(folder)
    refused = _try_lock(folder)
    assert refused.returncode == 3 and f"pid {os.getpid()} on host '{HOST}'" in refused.stdout
    held.release()
    assert _try_lock(folder).returncode == 0


def test_lock_released_on_completion_and_on_errors(tmp_path, monkeypatch):
    folder = tmp_path / "ck"
    sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, keep_checkpoint=True,
              **KWARGS)
    assert (folder / ckpt.MANIFEST).is_file() and not (folder / _lock.LOCK).exists()
    # refused inside open_checkpoint (a different run): the lock is let go at once
    with pytest.raises(ValueError, match="belongs to a different run"):
        sweep.run(SCENE, GRID, chunk_size=CHUNK + 1, checkpoint=folder, resume=True,
                  **KWARGS)
    assert not (folder / _lock.LOCK).exists()
    # interrupted in the middle of the chunks: once the exception is handled, another
    # process may take the folder
    Interrupt(monkeypatch, 2)
    try:
        sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=tmp_path / "ck2", **KWARGS)
    except KeyboardInterrupt:
        pass
    monkeypatch.undo()
    assert len(chunk_files(tmp_path / "ck2")) == 2
    assert _try_lock(tmp_path / "ck2").returncode == 0
    # and this thread may resume it, even while an old traceback keeps the run alive
    Interrupt(monkeypatch, 3)
    with pytest.raises(KeyboardInterrupt) as kept:
        sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=tmp_path / "ck2", resume=True,
                  **KWARGS)
    monkeypatch.undo()
    resumed = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=tmp_path / "ck2",
                        resume=True, **KWARGS)
    assert kept.value is not None and not (tmp_path / "ck2").exists()
    np.testing.assert_array_equal(resumed.theta_final, sweep.run(SCENE, GRID,
                                                                 **KWARGS).theta_final)
