"""Long sweeps survive interruption: chunk checkpoints, --resume, real SIGINT/SIGTERM/SIGKILL.

A resumed run must give a dataset bit-identical to an uninterrupted one (the kernel is
deterministic and chunk-size independent), a checkpoint of another run must be refused
naming what differs, and an interrupted run or save must never leave a partial output.
Every wait on a subprocess is bounded, so no test can hang.
"""

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from shared_kernels import EVERY, EVERY_ADAPTIVE, WADA_PILOT, WADA_SCENE

import sweep
from sweep import cli
from sweep.execution import checkpoint as ckpt
from sweep.execution import local
from sweep.toml_spec import load_run

SCENE = sweep.Scene(effects=(sweep.Damping(0.3),))
GRID = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 9), omega0=np.linspace(-2.0, 2.0, 5))
KWARGS = {"t_end": 3.0, "dt": 0.01, "observe": ("final", "winding", "energy")}
CHUNK = 7  # 45 trajectories -> 7 chunks, the last one short


def identical(a: xr.Dataset, b: xr.Dataset) -> None:
    """Bit-identical data, coordinates and attributes, apart from the timestamp."""
    a, b = a.copy(), b.copy()
    a.attrs.pop("history", None)
    b.attrs.pop("history", None)
    xr.testing.assert_identical(a, b)
    for name in a.data_vars:  # assert_identical treats NaN == NaN; check the bits too
        assert a[name].values.tobytes() == b[name].values.tobytes(), name


class Interrupt:
    """Wraps the `build` that local execution calls: the kernel raises
    KeyboardInterrupt on call ``after + 1`` (like a Ctrl-C during that chunk) and counts
    its calls."""

    def __init__(self, monkeypatch, after: int | None) -> None:
        self.after, self.calls = after, 0
        real = local.build

        def build(spec):
            kernel = real(spec)

            def wrapped(*args):
                if self.after is not None and self.calls >= self.after:
                    raise KeyboardInterrupt
                self.calls += 1
                return kernel(*args)

            return wrapped

        monkeypatch.setattr(local, "build", build)


def chunk_files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.glob("chunk-*.npz")) if folder.is_dir() else []


def interrupted(monkeypatch, folder, after, scene=SCENE, grid=GRID, **kwargs):
    """Run with a checkpoint until the kernel is interrupted after ``after`` chunks."""
    Interrupt(monkeypatch, after)
    with pytest.raises(KeyboardInterrupt):
        sweep.run(scene, grid, chunk_size=CHUNK, checkpoint=folder, **{**KWARGS, **kwargs})
    monkeypatch.undo()
    assert len(chunk_files(folder)) == after


# ------------------------------------------------------------------------------- API
@pytest.mark.parametrize("extra", [
    {},
    # the observables of kernels that other files compile (tests/shared_kernels.py: the
    # damped scene's saving kernel of test_naive, the dopri5 one of test_points): what is
    # resumed, not which observables, is tested
    {"save_every": 50, "observe": EVERY},
    {"method": "dopri5", "rtol": 1e-8, "observe": EVERY_ADAPTIVE},  # and step statistics
], ids=["observables", "save_every", "adaptive"])
def test_resumed_run_is_bit_identical_and_skips_finished_chunks(extra, tmp_path,
                                                                 monkeypatch):
    reference = sweep.run(SCENE, GRID, **{**KWARGS, **extra})
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 3, **extra)
    assert (folder / ckpt.MANIFEST).is_file()
    counter = Interrupt(monkeypatch, None)
    resumed = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, resume=True,
                        **{**KWARGS, **extra})
    assert counter.calls == 7 - 3  # the finished chunks were loaded, not recomputed
    identical(resumed, reference)
    assert not folder.exists()  # removed once the run is complete


def test_keep_checkpoint_and_a_complete_checkpoint_computes_nothing(tmp_path, monkeypatch):
    folder = tmp_path / "ck"
    first = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, keep_checkpoint=True,
                      **KWARGS)
    assert len(chunk_files(folder)) == 7
    counter = Interrupt(monkeypatch, None)
    again = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, resume=True,
                      **KWARGS)
    assert counter.calls == 0
    identical(again, first)


def test_progress_counts_resumed_chunks(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 4)
    capsys.readouterr()
    sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, resume=True, progress=True,
              **KWARGS)
    err = capsys.readouterr().err
    assert err.count("\n") == 1  # one bar, redrawn in place
    # the bar starts at the 4 resumed chunks of 7 (they do not count in the rate)
    assert " 28/45 [" in err and " 45/45 [" in err


def test_damaged_chunk_and_stale_temporary_file_are_recomputed(tmp_path, monkeypatch):
    reference = sweep.run(SCENE, GRID, **KWARGS)
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 3)
    (folder / chunk_files(folder)[1]).write_bytes(b"PK\x03\x04 not a zip")
    (folder / ".tmp-chunk-000000000021-000000000028.npz.abc").write_bytes(b"half")
    counter = Interrupt(monkeypatch, None)
    with pytest.warns(ckpt.DamagedChunkWarning, match=chunk_files(folder)[1]):
        resumed = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, resume=True,
                            keep_checkpoint=True, **KWARGS)
    assert counter.calls == 7 - 2
    identical(resumed, reference)
    assert not list(folder.glob(".tmp-*"))


@pytest.mark.parametrize("change, message", [
    ({"kwargs": {"dt": 0.005}}, r"run\.dt: checkpoint 0\.01, this run 0\.005"),
    ({"kwargs": {"t_end": 4.0}}, r"run\.t_end: checkpoint 3\.0, this run 4\.0"),
    ({"grid": sweep.Grid(theta0=np.linspace(-3.0, 3.1, 9),
                         omega0=np.linspace(-2.0, 2.0, 5))}, r"grid\.sha256\.theta0"),
    ({"scene": sweep.Scene(effects=(sweep.Damping(0.4),))},
     r"scene\.damping\.coefficient: checkpoint 0\.3, this run 0\.4"),
    ({"kwargs": {"observe": ("final",)}}, r"kernel\.observe"),
    ({"chunk_size": 5}, r"chunk_size: checkpoint 7, this run 5"),
], ids=["dt", "t_end", "grid", "scene", "observe", "chunk_size"])
def test_checkpoint_of_another_run_is_refused_naming_the_difference(change, message,
                                                                    tmp_path, monkeypatch):
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 2)
    before = sorted(p.name for p in folder.iterdir())
    counter = Interrupt(monkeypatch, None)
    with pytest.raises(ValueError, match=r"belongs to a different run: .*" + message):
        sweep.run(change.get("scene", SCENE), change.get("grid", GRID),
                  chunk_size=change.get("chunk_size", CHUNK), checkpoint=folder, resume=True,
                  **{**KWARGS, **change.get("kwargs", {})})
    assert counter.calls == 0  # refused before any compute
    assert sorted(p.name for p in folder.iterdir()) == before  # and nothing touched


def test_a_resume_with_another_attractor_catalogue_is_refused(wada_catalogue, tmp_path,
                                                                monkeypatch):
    """The catalogue is the kernel's data, not part of its spec: the fingerprint holds
    its digest, so a resume with another catalogue (one attractor fewer) is refused
    before any compute, and one with the same catalogue gives the uninterrupted run."""
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 9), omega0=np.linspace(-4, 4, 9))
    run = dict(WADA_PILOT, attractors=wada_catalogue)
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 2, scene=WADA_SCENE, grid=grid, **run)
    partial = {name: values[1:] for name, values in wada_catalogue.items()}
    counter = Interrupt(monkeypatch, None)
    with pytest.raises(ValueError, match=r"belongs to a different run: .*catalogue\.sha256"):
        sweep.run(WADA_SCENE, grid, chunk_size=CHUNK, checkpoint=folder, resume=True,
                  **{**KWARGS, **run, "attractors": partial})
    assert counter.calls == 0
    resumed = sweep.run(WADA_SCENE, grid, chunk_size=CHUNK, checkpoint=folder, resume=True,
                        **{**KWARGS, **run})
    assert counter.calls == len(range(0, grid.size, CHUNK)) - 2
    identical(resumed, sweep.run(WADA_SCENE, grid, **run))


def test_sweep_version_is_part_of_the_fingerprint(tmp_path, monkeypatch):
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 1)
    manifest = json.loads((folder / ckpt.MANIFEST).read_text())
    manifest["fingerprint"]["sweep_version"] = "0.0.1"
    (folder / ckpt.MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match=r"sweep_version: checkpoint '0\.0\.1', this run"):
        sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, resume=True, **KWARGS)


def test_bad_checkpoint_arguments_are_refused_before_any_compute(tmp_path, monkeypatch):
    folder = tmp_path / "ck"
    interrupted(monkeypatch, folder, 2)
    def run(**kw):
        return sweep.run(SCENE, GRID, chunk_size=CHUNK, **KWARGS, **kw)

    with pytest.raises(ValueError, match=r"already holds a run \(2 finished chunks\); "
                                         r"accepted: resume=True"):
        run(checkpoint=folder)  # never overwrite finished work by mistake
    assert len(chunk_files(folder)) == 2
    with pytest.raises(ValueError, match=r"resume=True needs checkpoint="):
        run(resume=True)
    with pytest.raises(TypeError, match=r"resume must be True or False, got 'yes'"):
        run(checkpoint=folder, resume="yes")
    with pytest.raises(TypeError, match=r"checkpoint must be None or a folder path"):
        run(checkpoint=3)
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match=r"exists and is not a folder"):
        run(checkpoint=tmp_path / "file")
    with pytest.raises(ValueError, match=r"does not exist"):
        run(checkpoint=tmp_path / "missing" / "ck")
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match=r"holds other files \('notes.txt', \.\.\.\) and no "
                                         r"sweep checkpoint"):
        run(checkpoint=other, resume=True)
    (folder / ckpt.MANIFEST).write_text("{not json")
    with pytest.raises(ValueError, match=r"unreadable manifest.json"):
        run(checkpoint=folder, resume=True)


def test_resume_without_a_checkpoint_starts_from_scratch(tmp_path):
    ds = sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=tmp_path / "new", resume=True,
                   **KWARGS)
    identical(ds, sweep.run(SCENE, GRID, **KWARGS))
    assert not (tmp_path / "new").exists()


def test_removing_a_checkpoint_never_touches_other_files(tmp_path):
    folder = tmp_path / "ck"
    sweep.run(SCENE, GRID, chunk_size=CHUNK, checkpoint=folder, keep_checkpoint=True,
              **KWARGS)
    (folder / "notes.txt").write_text("mine")
    ckpt.remove(folder)
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt"]


# ------------------------------------------------------------------------------- CLI
RUN_FILE = """\
[scene]
[scene.damping]
coefficient = 0.3

[grid]
theta0 = {start = -3.0, stop = 3.0, num = 9}
omega0 = {start = -2.0, stop = 2.0, num = 5}

[run]
t_end = 3.0
dt = 0.01
observe = ["final", "winding", "energy"]
chunk_size = 7
"""


def call(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def test_cli_ctrl_c_exits_130_with_a_resume_hint_then_resume_completes(tmp_path,
                                                                       monkeypatch):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    out = tmp_path / "out.nc"
    folder = tmp_path / "out.nc.checkpoint"  # the default folder of --resume
    Interrupt(monkeypatch, 3)
    code, stdout, stderr = call("run", run_file, "-o", out, "--resume", "--no-progress")
    monkeypatch.undo()
    assert code == 130
    note, stderr = stderr.split("\n", 1)  # no checkpoint yet: the run started afresh
    assert note == (f"sweep: note: --resume: no checkpoint in '{folder}'; the run starts "
                    "from the beginning")
    assert stderr.count("\n") == 1 and stderr.startswith("sweep: interrupted; 3 finished "
                                                         "chunks are checkpointed in")
    assert f"resume with: sweep run {run_file} -o {out} --resume" in stderr
    assert not out.exists() and len(chunk_files(folder)) == 3
    counter = Interrupt(monkeypatch, None)
    code, stdout, stderr = call("run", run_file, "-o", out, "--resume", "--no-progress")
    assert (code, stderr) == (0, "") and stdout.startswith(f"wrote {out}")
    assert counter.calls == 4
    assert not folder.exists()  # removed once out.nc is written
    scene, grid, kwargs = load_run(run_file)
    identical(sweep.load(out), sweep.run(scene, grid, **kwargs))


def test_cli_ctrl_c_without_checkpoint_says_how_to_make_runs_resumable(tmp_path,
                                                                       monkeypatch):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    Interrupt(monkeypatch, 1)
    code, _, stderr = call("run", run_file, "-o", tmp_path / "out.nc")
    assert code == 130
    assert stderr == ("sweep: interrupted; no output written; run with --checkpoint DIR "
                      "(or --resume) to make a run resumable\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]


def test_cli_interrupted_save_keeps_previous_output_and_the_checkpoint(tmp_path,
                                                                       monkeypatch):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    out, folder = tmp_path / "out.nc", tmp_path / "ck"
    assert call("run", run_file, "-o", out)[0] == 0
    before = out.read_bytes()

    def crash(self, target, *args, **kwargs):  # as in test_io: half a file, then Ctrl-C
        with open(target, "wb") as handle:
            handle.write(b"CDF\x01partial")
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(xr.Dataset, "to_netcdf", crash)
        code, _, stderr = call("run", run_file, "-o", out, "--checkpoint", folder)
    assert code == 130 and "7 finished chunks" in stderr
    assert f"--checkpoint {folder} --resume" in stderr
    assert out.read_bytes() == before  # previous output intact, no temporary file left
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ck", "out.nc", "run.toml"]
    counter = Interrupt(monkeypatch, None)
    assert call("run", run_file, "-o", out, "--checkpoint", folder, "--resume")[0] == 0
    assert counter.calls == 0  # everything came from the checkpoint
    assert not folder.exists()


def test_cli_checkpoint_of_another_run_is_one_line_error(tmp_path, monkeypatch):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    out = tmp_path / "out.nc"
    Interrupt(monkeypatch, 2)
    assert call("run", run_file, "-o", out, "--resume")[0] == 130
    monkeypatch.undo()
    run_file.write_text(RUN_FILE.replace("dt = 0.01", "dt = 0.02"))
    code, stdout, stderr = call("run", run_file, "-o", out, "--resume")
    assert code == 2 and stdout == "" and stderr.count("\n") == 1
    assert "belongs to a different run: run.dt: checkpoint 0.01, this run 0.02" in stderr
    code, _, stderr = call("run", run_file, "-o", out)  # no --resume: nothing is touched
    assert code == 0 and len(chunk_files(tmp_path / "out.nc.checkpoint")) == 2
    run_file.write_text(RUN_FILE.replace("chunk_size = 7", "chunk_size = 0"))
    code, _, stderr = call("run", run_file, "-o", out)
    assert code == 2 and "[run] chunk_size must be an integer >= 1" in stderr


# ---------------------------------------------------------------- real interruptions
# About 3 s of compute on 2 cores in 150 chunks: ample time to interrupt part way.
SLOW_RUN_FILE = """\
[scene]
[scene.damping]
coefficient = 0.3

[grid]
theta0 = {start = -3.0, stop = 3.0, num = 60}
omega0 = {start = -2.0, stop = 2.0, num = 25}

[run]
t_end = 500.0
dt = 0.01
observe = ["final", "winding", "energy"]
chunk_size = 10
"""
WAIT_S = 120  # bound on every wait: generous for a cold JIT cache on a slow machine


@pytest.fixture(scope="module")
def slow_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("slow")
    run_file = folder / "run.toml"
    run_file.write_text(SLOW_RUN_FILE)
    scene, grid, kwargs = load_run(run_file)
    return run_file, sweep.run(scene, grid, **kwargs)


# ``python -m sweep ARGV`` with SIGINT handled as in a command typed at a terminal.
# A job started in the background of a non-interactive shell (``pytest ... &`` in a
# script, a CI step run that way) inherits SIGINT *ignored* (POSIX: the shell sets it
# so for asynchronous commands), and Python keeps an inherited ignore, as every program
# should: such a ``sweep run`` is not stopped by SIGINT and runs to the end. That was
# the "flaky" interruption test: whether it failed depended on how the suite was
# started, not on timing. The child therefore restores Python's default handler itself.
_FOREGROUND = ("import runpy, signal, sys; "
               "signal.signal(signal.SIGINT, signal.default_int_handler); "
               "sys.argv[0] = 'sweep'; runpy.run_module('sweep', run_name='__main__')")


def _sweep(*argv) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen([sys.executable, "-c", _FOREGROUND, *map(str, argv)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)


def _finish(process: subprocess.Popen) -> tuple[int, str, str]:
    try:
        stdout, stderr = process.communicate(timeout=WAIT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail(f"sweep did not finish within {WAIT_S} s")
    return process.returncode, stdout, stderr


def _interrupt(run_file, out, folder, sig):
    """Start ``sweep run`` with a checkpoint, send ``sig`` once 2 chunks are stored;
    return (exit code, stderr, chunks stored, seconds from the signal to the exit)."""
    process = _sweep("run", run_file, "-o", out, "--checkpoint", folder)
    deadline = time.monotonic() + WAIT_S
    try:
        while len(chunk_files(folder)) < 2:
            if process.poll() is not None:
                pytest.fail(f"sweep exited ({process.returncode}) before 2 chunks were "
                            f"checkpointed: {process.communicate()}")
            if time.monotonic() > deadline:
                pytest.fail(f"no 2 checkpointed chunks within {WAIT_S} s")
            time.sleep(0.01)
        process.send_signal(sig)
    except BaseException:
        process.kill()  # never leave a run behind
        process.communicate()
        raise
    sent = time.monotonic()
    code, _, stderr = _finish(process)
    return code, stderr, len(chunk_files(folder)), time.monotonic() - sent


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL],
                         ids=["SIGINT", "SIGTERM", "SIGKILL"])
def test_real_killed_run_resumes_to_a_bit_identical_file(sig, slow_run, tmp_path):
    run_file, reference = slow_run
    out, folder = tmp_path / "out.nc", tmp_path / "ck"
    # The signal is sent once 2 of the 150 chunks are checkpointed (about 5 s of work
    # left). SIGKILL ends the process at once; SIGINT raises KeyboardInterrupt, and
    # SIGTERM (a batch system's stop) its subclass cli.Terminated, as soon as the
    # running chunk's compiled kernel returns to the interpreter (a chunk is ~20 ms:
    # numba code does not look at signals), so the run stops within a chunk or two,
    # never at the end.
    code, stderr, done, waited = _interrupt(run_file, out, folder, sig)
    assert 2 <= done < 150, f"interrupted part way (exit {code}): {stderr[-500:]}"
    assert waited < WAIT_S
    assert not out.exists()
    assert not list(tmp_path.glob(".out.nc.*"))  # no half-written output either
    if sig == signal.SIGKILL:
        assert code == -signal.SIGKILL
    else:
        assert code == {signal.SIGINT: 130, signal.SIGTERM: 143}[sig], stderr
        word = {signal.SIGINT: "interrupted", signal.SIGTERM: "terminated"}[sig]
        assert stderr.count("\n") == 1, stderr  # one line, no traceback
        assert stderr == (f"sweep: {word}; {done} finished chunks are checkpointed in "
                          f"'{folder}'; resume with: sweep run {run_file} -o {out} "
                          f"--checkpoint {folder} --resume\n")
        assert not (folder / "lock").exists()  # the next run need not take it over
        if sig == signal.SIGTERM:  # after the running pieces, well within the watchdog's wait
            assert waited < cli.TERMINATE_WAIT_S
    code, _, stderr = _finish(_sweep("run", run_file, "-o", out, "--checkpoint", folder,
                                     "--resume"))
    assert code == 0, stderr
    assert not folder.exists()
    identical(sweep.load(out), reference)
