"""Faults a long run meets: SIGTERM from a batch system during a long chunk.

SIGTERM at a chunk boundary is tested with SIGINT and SIGKILL in test_resume.py
(test_real_killed_run_resumes_to_a_bit_identical_file). Every wait on a subprocess is
bounded.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from sweep import cli
from sweep.execution import checkpoint as ckpt
from sweep.execution import lock as _lock
from test_resume import RUN_FILE, SLOW_RUN_FILE, WAIT_S, call

def _run_file(folder: Path, text: str = RUN_FILE) -> Path:
    path = folder / "run.toml"
    path.write_text(text)
    return path


# ------------------------------------------------------------------------- SIGTERM
# One chunk of ~30 s or more (1500 trajectories x 5e6 steps), in a child whose wait
# for a chunk boundary is cut to 1 s, with its kernel loaded beforehand (the first call
# of a numba kernel loads it from the cache: interpreted code, where SIGTERM would be
# handled at once), and which creates MARKER as it calls the kernel.
_LONG_RUN_FILE = SLOW_RUN_FILE.replace("t_end = 500.0", "t_end = 50000.0") \
    .replace("chunk_size = 10", "chunk_size = 1500")
_WATCHED = ("import pathlib, signal, sys, sweep; "
            "from sweep import cli; from sweep.execution import local; "
            "from sweep.toml_spec import load_run; "
            "cli.TERMINATE_WAIT_S = 1.0; marker = pathlib.Path(sys.argv[1]); "
            "scene, grid, kwargs = load_run(sys.argv[3]); "
            "sweep.engine.warm_up(scene, grid, **kwargs); "
            "real = local.integrate; "
            "local.integrate = lambda *a: (marker.touch(), real(*a)); "
            "sys.exit(cli.main(sys.argv[2:]))")


def test_sigterm_during_a_long_chunk_stops_within_the_bound(tmp_path):
    run_file = _run_file(tmp_path, _LONG_RUN_FILE)
    out, folder, marker = tmp_path / "out.nc", tmp_path / "ck", tmp_path / "kernel-started"
    process = subprocess.Popen([sys.executable, "-c", _WATCHED, str(marker), "run",
                                str(run_file), "-o", str(out), "--checkpoint", str(folder)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        deadline = time.monotonic() + WAIT_S
        while not marker.exists():
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline, f"the kernel did not start in {WAIT_S} s"
            time.sleep(0.01)
        time.sleep(0.2)  # inside the kernel, which runs ~30 s and never looks at signals
        assert (folder / _lock.LOCK).exists()
        process.send_signal(signal.SIGTERM)
        sent = time.monotonic()
        _, stderr = process.communicate(timeout=WAIT_S)
        waited = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    # the watchdog stopped it after its 1 s, not the kernel after its ~30 s
    assert process.returncode == 143, stderr
    assert 1.0 <= waited < 6.0, waited
    assert stderr == (f"sweep: terminated (the running chunk did not end within 1 s of "
                      f"SIGTERM and was abandoned); 0 finished chunks are checkpointed in "
                      f"'{folder}'; resume with: sweep run {run_file} -o {out} "
                      f"--checkpoint {folder} --resume\n")
    assert sorted(p.name for p in folder.iterdir()) == [ckpt.MANIFEST]  # no lock left
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ck", "kernel-started", "run.toml"]


def test_sigterm_handler_is_only_in_effect_during_the_run(tmp_path, monkeypatch):
    seen = {}

    def run(*args, **kwargs):  # what the run command sees, in place of the run
        seen["handler"] = signal.getsignal(signal.SIGTERM)
        raise cli.Terminated

    def wakeup_fd() -> int:
        fd = signal.set_wakeup_fd(-1)
        signal.set_wakeup_fd(fd)
        return fd

    monkeypatch.setattr(cli, "_run_quietly", run)
    before, before_fd = signal.getsignal(signal.SIGTERM), wakeup_fd()
    code, stdout, stderr = call("run", _run_file(tmp_path), "-o", tmp_path / "out.nc",
                                "--checkpoint", tmp_path / "ck")
    assert code == 143 and stdout == ""
    assert stderr.startswith("sweep: terminated; 0 finished chunks are checkpointed in")
    assert seen["handler"] not in (before, signal.SIG_DFL)
    assert signal.getsignal(signal.SIGTERM) is before and wakeup_fd() == before_fd

