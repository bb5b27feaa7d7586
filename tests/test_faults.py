"""Faults a long run meets: SIGTERM from a batch system (or Ctrl-C) during a long chunk, a full
disk (refused before compute by the size estimate; a write that fails anyway keeps the
checkpoint), and a damaged checkpoint chunk (recomputed, with a warning).

SIGTERM between kernel pieces is tested with SIGINT and SIGKILL in test_resume.py
(test_real_killed_run_resumes_to_a_bit_identical_file). Every wait on a subprocess is
bounded. The tmpfs tests mount a 2 MiB file system (root only; skipped elsewhere, and
the same paths are covered by simulated failures).
"""

import errno
import os
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from shared_kernels import EVERY_ADAPTIVE

import sweep
import sweep.distributed
from sweep import cli, diskspace
from sweep import io as sweep_io
from sweep.execution import checkpoint as ckpt
from sweep.execution import lock as _lock
from sweep.toml_spec import load_run

from test_resume import RUN_FILE, SLOW_RUN_FILE, WAIT_S, Interrupt, call, chunk_files, identical

SCENE = sweep.Scene(effects=(sweep.Damping(0.3),))
FORCED = sweep.Scene(effects=(sweep.Damping(0.3), sweep.Forcing(1.0, 2.0)))


def _grid(n: int) -> sweep.Grid:
    return sweep.Grid(theta0=np.linspace(-3.0, 3.0, n), omega0=np.linspace(-2.0, 2.0, n))


def _run_file(folder: Path, text: str = RUN_FILE) -> Path:
    path = folder / "run.toml"
    path.write_text(text)
    return path


# ------------------------------------------------------------------ SIGTERM, Ctrl-C
# One chunk of ~30 s or more (1500 trajectories x 5e6 steps: pieces of ~7 s on 2
# threads, sweep.kernels.threads), in a child whose wait for the running pieces is cut
# to 1 s, with its kernel loaded beforehand (the first call
# of a numba kernel loads it from the cache: interpreted code, where a signal would be
# handled at once), and which creates MARKER as it calls the kernel. SIGINT gets
# Python's own handler, as in a command typed at a terminal (a child of a background
# job inherits it ignored: see test_resume._FOREGROUND).
_LONG_RUN_FILE = SLOW_RUN_FILE.replace("t_end = 500.0", "t_end = 50000.0") \
    .replace("chunk_size = 10", "chunk_size = 1500")
_WATCHED = ("import pathlib, signal, sys, sweep; "
            "signal.signal(signal.SIGINT, signal.default_int_handler); "
            "from sweep import cli; from sweep.execution import local; "
            "from sweep.toml_spec import load_run; "
            "cli.TERMINATE_WAIT_S = 1.0; marker = pathlib.Path(sys.argv[1]); "
            "scene, grid, kwargs = load_run(sys.argv[3]); "
            "sweep.engine.warm_up(scene, grid, **kwargs); "
            "real = local.integrate; "
            "local.integrate = lambda *a: (marker.touch(), real(*a)); "
            "sys.exit(cli.main(sys.argv[2:]))")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "Ctrl-C"])
def test_a_stop_during_a_long_chunk_ends_within_the_bound(sig, tmp_path):
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
        time.sleep(0.2)  # inside the kernel, whose pieces run ~7 s and never look at signals
        assert (folder / _lock.LOCK).exists()
        process.send_signal(sig)
        sent = time.monotonic()
        _, stderr = process.communicate(timeout=WAIT_S)
        waited = time.monotonic() - sent
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    # the watchdog stopped it after its 1 s, not the kernel's running pieces after ~7 s
    word, what, code = {signal.SIGTERM: ("terminated", "SIGTERM", 143),
                        signal.SIGINT: ("interrupted", "Ctrl-C", 130)}[sig]
    assert process.returncode == code, stderr
    assert 1.0 <= waited < 6.0, waited
    assert stderr == (f"sweep: {word} (the running chunk did not end within 1 s of "
                      f"{what} and was abandoned); 0 finished chunks are checkpointed in "
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


# ----------------------------------------------------------------- size estimates
_CASES = {
    "observables": (SCENE, 150, {"t_end": 1.0, "dt": 0.01, "observe": (
        "final", "winding", "energy", "theta_max", "amplitude")}),
    "save_every": (SCENE, 40, {"t_end": 1.0, "dt": 0.01, "save_every": 5}),
    # every observable dopri5 takes: test_points' and test_resume's kernel of SCENE
    "adaptive": (SCENE, 100, {"t_end": 1.0, "dt": 0.01, "method": "dopri5", "rtol": 1e-8,
                              "observe": EVERY_ADAPTIVE}),
    "strobe": (FORCED, 60, {"t_end": 10 * np.pi, "dt": np.pi / 100,
                            "observe": ("final", "strobe")}),
}


@pytest.mark.parametrize("case", list(_CASES))
def test_size_estimate_bounds_the_written_files(case, tmp_path):
    scene, n, kwargs = _CASES[case]
    grid = _grid(n)
    estimate = diskspace.estimate_size(scene, grid, **kwargs)
    ds = sweep.run(scene, grid, **kwargs)
    assert sweep_io.file_size_bound(ds) == estimate  # the layout is the dataset's
    layout = diskspace.layout(scene, grid, **kwargs)
    assert list(layout.variables) == list(ds.variables)
    for name, variable in ds.variables.items():
        assert (layout[name].dims, layout[name].dtype) == (variable.dims, variable.dtype)
    saved = os.path.getsize(sweep.save(ds, tmp_path / "saved.nc"))
    streamed = os.path.getsize(sweep.distributed.run_to_netcdf(tmp_path / "streamed.nc",
                                                               scene, grid, **kwargs))
    # sweep's outputs compress 1.6-2.7x in these runs: the estimate (uncompressed) is
    # above each file and within 3x of it
    for size in (saved, streamed):
        assert size <= estimate <= 3 * size, (size, estimate)


@pytest.mark.parametrize("n", [180, 400])
def test_size_estimate_is_tight_for_incompressible_data(n, tmp_path):
    # random bits do not compress: the file is the size of the values, and the estimate
    # is within 1.1x of it from 1 MiB on (1.06x at 1.3 MiB, 1.015x at 4 MiB measured)
    kwargs = {"t_end": 1.0, "dt": 0.01, "observe": ("final", "winding", "energy")}
    rng = np.random.default_rng(20261125)
    ds = diskspace.layout(SCENE, _grid(n), **kwargs).copy(deep=True)
    for name, variable in ds.data_vars.items():
        bits = rng.bytes(variable.size * variable.dtype.itemsize)
        ds[name] = (variable.dims, np.frombuffer(bits, variable.dtype)
                    .reshape(variable.shape), variable.attrs)
    size = os.path.getsize(sweep.save(ds, tmp_path / "random.nc"))
    estimate = diskspace.estimate_size(SCENE, _grid(n), **kwargs)
    assert size > 1 << 20
    assert size <= estimate <= 1.1 * size, (size, estimate)


def test_checkpoint_estimate_bounds_its_chunk_files(tmp_path):
    scene, n, kwargs = _CASES["save_every"]
    folder = tmp_path / "ck"
    sweep.run(scene, _grid(n), chunk_size=300, checkpoint=folder, keep_checkpoint=True,
              **kwargs)
    settings, spec, chunk_size = sweep.engine.prepare(scene, _grid(n), chunk_size=300,
                                                      **kwargs)
    bound = ckpt.size_bound(spec, settings, n * n, chunk_size)
    stored = ckpt.stored_bytes(folder)
    assert len(chunk_files(folder)) == 6
    assert stored <= bound <= 1.15 * stored, (stored, bound)


# ------------------------------------------------------------------- a full disk
@pytest.fixture
def small_disk(tmp_path):
    """A 2 MiB tmpfs (root only): a full disk for real."""
    mount = tmp_path / "small"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mount)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here (needs root): {done.stderr.strip()}")
    try:
        yield mount
    finally:  # lazily if a file is still open in it (the test failed): never left mounted
        if subprocess.run(["umount", str(mount)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(mount)], check=True)


# 400 x 400 trajectories: 3.6 MiB compressed, 6.4 MiB estimated; 0.1 s of compute
_BIG_RUN_FILE = RUN_FILE.replace("num = 9", "num = 400").replace("num = 5", "num = 400") \
    .replace("t_end = 3.0", "t_end = 0.1").replace("chunk_size = 7", "chunk_size = 60000")


# 180 x 180 trajectories: the file alone (1.3 MiB estimated) fits, with its checkpoint's
# chunks (1.3 MiB more) it may not
_MEDIUM_RUN_FILE = _BIG_RUN_FILE.replace("num = 400", "num = 180")


@pytest.mark.parametrize("with_checkpoint", [False, True], ids=["output", "checkpoint"])
def test_a_run_that_cannot_fit_is_refused_before_any_compute(with_checkpoint, small_disk,
                                                             tmp_path, no_compute):
    run_file = _run_file(tmp_path, _MEDIUM_RUN_FILE if with_checkpoint else _BIG_RUN_FILE)
    out = small_disk / "out.nc"
    extra = ["--checkpoint", small_disk / "ck"] if with_checkpoint else []
    code, stdout, stderr = call("run", run_file, "-o", out, *extra)
    free = shutil.disk_usage(small_disk).free
    assert (code, stdout) == (2, "") and stderr.count("\n") == 1
    assert stderr.startswith(f"sweep: error: not enough free disk space: the output file "
                             f"'{out}' up to ")
    assert "(its uncompressed size: sweep compresses with zlib, so it is usually smaller" \
        in stderr
    assert f"but '{small_disk}' has {sweep_io._size(free)} free" in stderr
    if with_checkpoint:  # the file alone would fit; with the checkpoint's chunks it may not
        assert f"and the checkpoint '{small_disk / 'ck'}' up to " in stderr
        scene, grid, kwargs = load_run(run_file)
        assert diskspace.check_space(out, scene, grid, **kwargs) < free
    assert list(small_disk.iterdir()) == []


def test_a_run_that_cannot_fit_is_refused_with_simulated_free_space(tmp_path, monkeypatch,
                                                                    no_compute):
    real = shutil.disk_usage
    monkeypatch.setattr(shutil, "disk_usage", lambda p: real(p)._replace(free=50_000))
    run_file = _run_file(tmp_path)
    scene, grid, kwargs = load_run(run_file)
    estimate = diskspace.estimate_size(scene, grid, **kwargs)
    code, _, stderr = call("run", run_file, "-o", tmp_path / "out.nc")
    assert code == 2 and stderr.count("\n") == 1
    assert (f"the output file '{tmp_path / 'out.nc'}' up to {sweep_io._size(estimate)} "
            f"(its uncompressed size") in stderr
    assert f"but '{tmp_path}' has 48.8 KiB free; accepted: a folder with at least " in stderr
    with pytest.raises(ValueError, match="not enough free disk space"):
        sweep.distributed.run_to_netcdf(tmp_path / "x.nc", SCENE, _grid(9), t_end=1.0,
                                        dt=0.01)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]


# 250 x 250 trajectories: 1.3 MiB compressed, 2.5 MiB estimated (uncompressed): the file
# fits on the 2 MiB tmpfs only because it is compressed
_COMPRESSIBLE_RUN_FILE = _BIG_RUN_FILE.replace("num = 400", "num = 250")


def test_no_space_check_writes_a_compressed_file_the_bound_refuses(small_disk, tmp_path):
    run_file = _run_file(tmp_path, _COMPRESSIBLE_RUN_FILE)
    out = small_disk / "out.nc"
    code, _, stderr = call("run", run_file, "-o", out)
    assert code == 2 and "not enough free disk space" in stderr
    assert stderr.endswith("or, if the compressed file will fit, no check (sweep run "
                           "--no-space-check; run_to_netcdf(..., check_space=False))\n")
    code, stdout, stderr = call("run", run_file, "-o", out, "--no-space-check")
    assert stdout.startswith(f"wrote {out}: 62500 trajectories")
    assert (code, stderr) == (0, ""), stderr
    scene, grid, kwargs = load_run(run_file)
    assert os.path.getsize(out) < shutil.disk_usage(small_disk).total \
        < diskspace.estimate_size(scene, grid, **kwargs)
    assert sorted(p.name for p in small_disk.iterdir()) == ["out.nc"]


def test_no_space_check_skips_the_bound_with_simulated_free_space(tmp_path, monkeypatch):
    run_file = _run_file(tmp_path)
    scene, grid, kwargs = load_run(run_file)
    free = diskspace.estimate_size(scene, grid, **kwargs) - 1  # refused: one byte short
    real = shutil.disk_usage
    monkeypatch.setattr(shutil, "disk_usage", lambda p: real(p)._replace(free=free))
    out, streamed = tmp_path / "out.nc", tmp_path / "streamed.nc"
    assert call("run", run_file, "-o", out)[0] == 2
    with pytest.raises(ValueError, match="not enough free disk space"):
        sweep.distributed.run_to_netcdf(streamed, scene, grid, **kwargs)
    with pytest.raises(TypeError, match="check_space must be True or False, got 'no'"):
        sweep.distributed.run_to_netcdf(streamed, scene, grid, check_space="no", **kwargs)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]
    code, _, stderr = call("run", run_file, "-o", out, "--no-space-check")
    assert (code, stderr) == (0, ""), stderr
    sweep.distributed.run_to_netcdf(streamed, scene, grid, check_space=False, **kwargs)
    for path in (out, streamed):  # the compressed files are well within that free space
        assert os.path.getsize(path) < free
        identical(sweep.load(path), sweep.run(scene, grid, **kwargs))


def test_a_write_that_fails_on_a_real_full_disk_keeps_the_checkpoint(small_disk, tmp_path,
                                                                     monkeypatch):
    monkeypatch.setattr(diskspace, "check_space", lambda *a, **k: 0)  # let it try
    run_file = _run_file(tmp_path, _BIG_RUN_FILE)
    out, folder = small_disk / "out.nc", tmp_path / "ck"
    code, stdout, stderr = call("run", run_file, "-o", out, "--checkpoint", folder)
    assert (code, stdout) == (2, "") and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"sweep: error: [Errno 28] cannot write '{out}': No space left "
                             "on device (netCDF4 reported 'NetCDF: HDF error' with ")
    assert stderr.endswith(f"; nothing was written; 3 finished chunks are checkpointed in "
                           f"'{folder}'; resume with: sweep run {run_file} -o {out} "
                           f"--checkpoint {folder} --resume (once there is room; another -o "
                           "writes the file elsewhere, without recomputing)\n")
    assert list(small_disk.iterdir()) == []  # no partial file, its space given back
    assert shutil.disk_usage(small_disk).used == 0
    assert len(chunk_files(folder)) == 3 and not (folder / _lock.LOCK).exists()
    monkeypatch.undo()
    counter = Interrupt(monkeypatch, None)
    elsewhere = tmp_path / "out.nc"
    code, stdout, stderr = call("run", run_file, "-o", elsewhere, "--checkpoint", folder,
                                "--resume")
    assert (code, stderr) == (0, "") and counter.calls == 0  # nothing recomputed
    assert not folder.exists()
    scene, grid, kwargs = load_run(run_file)
    identical(sweep.load(elsewhere), sweep.run(scene, grid, **kwargs))


@pytest.mark.parametrize("failure", ["ENOSPC", "HDF error, full", "HDF error, room"])
def test_a_write_that_fails_says_why_and_keeps_the_checkpoint(failure, tmp_path,
                                                              monkeypatch):
    run_file = _run_file(tmp_path)
    out, folder = tmp_path / "out.nc", tmp_path / "out.nc.checkpoint"

    def full(self, target, *args, **kwargs):  # half a file, then the disk is full
        Path(target).write_bytes(b"CDF\x01partial")
        if failure == "ENOSPC":
            raise OSError(errno.ENOSPC, "No space left on device")
        raise RuntimeError("NetCDF: HDF error")

    real = shutil.disk_usage
    free = 0 if failure == "HDF error, full" else 10**12
    monkeypatch.setattr(diskspace, "check_space", lambda *a, **k: 0)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: real(p)._replace(free=free))
    monkeypatch.setattr(xr.Dataset, "to_netcdf", full)
    code, stdout, stderr = call("run", run_file, "-o", out, "--resume")
    note, stderr = stderr.split("\n", 1)  # no checkpoint yet: the run started afresh
    assert note.startswith("sweep: note: --resume: no checkpoint in"), note
    cause = {"ENOSPC": "[Errno 28] cannot write '{}': No space left on device; ",
             "HDF error, full": "[Errno 28] cannot write '{}': No space left on device "
                                "(netCDF4 reported 'NetCDF: HDF error' with 0 bytes free in",
             "HDF error, room": "cannot write '{}': NetCDF: HDF error; "}[failure]
    assert (code, stdout) == (2, "") and stderr.count("\n") == 1, stderr
    assert stderr.startswith("sweep: error: " + cause.format(out)), stderr
    assert f"nothing was written; 7 finished chunks are checkpointed in '{folder}'; resume " \
           f"with: sweep run {run_file} -o {out} --checkpoint {folder} --resume (once" \
           in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.nc.checkpoint", "run.toml"]
    monkeypatch.undo()
    counter = Interrupt(monkeypatch, None)
    other = tmp_path / "other.nc"  # the checkpoint's identity is not the output path
    assert call("run", run_file, "-o", other, "--checkpoint", folder, "--resume")[0] == 0
    assert counter.calls == 0 and not folder.exists()
    scene, grid, kwargs = load_run(run_file)
    identical(sweep.load(other), sweep.run(scene, grid, **kwargs))


def test_a_chunk_that_cannot_be_stored_names_its_file(tmp_path, monkeypatch):
    calls = []
    real = np.savez

    def savez(handle, **arrays):  # the disk fills up at the fourth chunk
        calls.append(1)
        if len(calls) == 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(handle, **arrays)

    monkeypatch.setattr(ckpt.np, "savez", savez)
    run_file, folder = _run_file(tmp_path), tmp_path / "ck"
    code, _, stderr = call("run", run_file, "-o", tmp_path / "out.nc", "--checkpoint", folder)
    assert code == 2 and stderr.count("\n") == 1
    assert stderr == (f"sweep: error: [Errno 28] cannot write checkpoint file "
                      f"'{folder / 'chunk-000000000021-000000000028.npz'}': No space left on "
                      f"device; 3 finished chunks are checkpointed in '{folder}'; resume "
                      f"with: sweep run {run_file} -o {tmp_path / 'out.nc'} --checkpoint "
                      f"{folder} --resume\n")
    assert len(chunk_files(folder)) == 3 and not list(folder.glob(".tmp-*"))
    assert not (folder / _lock.LOCK).exists()


def test_a_streamed_file_that_cannot_be_written_leaves_nothing(tmp_path, monkeypatch):
    def full(self, target, *args, **kwargs):
        Path(target).write_bytes(b"CDF\x01partial")
        raise RuntimeError("NetCDF: HDF error")

    real = shutil.disk_usage
    monkeypatch.setattr(diskspace, "check_space", lambda *a, **k: 10**6)
    monkeypatch.setattr(shutil, "disk_usage", lambda p: real(p)._replace(free=0))
    monkeypatch.setattr(xr.Dataset, "to_netcdf", full)
    path = tmp_path / "streamed.nc"
    with pytest.raises(OSError, match=r"cannot write '.*streamed\.nc': No space left on "
                       r"device \(netCDF4 reported 'NetCDF: HDF error'") as raised:
        sweep.distributed.run_to_netcdf(path, SCENE, _grid(9), t_end=1.0, dt=0.01)
    assert raised.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------ a damaged checkpoint
def _flip_a_byte(chunk: Path) -> None:
    """Flip one byte of the ``out`` array's values (its CRC-32 no longer matches)."""
    data = bytearray(chunk.read_bytes())
    with zipfile.ZipFile(chunk) as archive:
        start = archive.getinfo("out.npy").header_offset
    magic = data.index(b"\x93NUMPY", start)
    header = int.from_bytes(data[magic + 8:magic + 10], "little")  # .npy format 1.0
    data[magic + 10 + header + 3] ^= 0x40
    chunk.write_bytes(bytes(data))


def test_a_damaged_chunk_is_recomputed_with_a_warning_naming_it(tmp_path, monkeypatch):
    run_file = _run_file(tmp_path)
    out, folder = tmp_path / "out.nc", tmp_path / "ck"
    Interrupt(monkeypatch, 3)
    assert call("run", run_file, "-o", out, "--checkpoint", folder)[0] == 130
    monkeypatch.undo()
    damaged = folder / chunk_files(folder)[1]
    _flip_a_byte(damaged)
    counter = Interrupt(monkeypatch, None)
    code, stdout, stderr = call("run", run_file, "-o", out, "--checkpoint", folder,
                                "--resume")
    assert code == 0 and stdout.startswith(f"wrote {out}")
    assert stderr == (f"sweep: warning: checkpoint chunk '{damaged}' is damaged (BadZipFile: "
                      "Bad CRC-32 for file 'out.npy'); it is recomputed\n")
    assert counter.calls == 7 - 3 + 1
    scene, grid, kwargs = load_run(run_file)
    identical(sweep.load(out), sweep.run(scene, grid, **kwargs))
