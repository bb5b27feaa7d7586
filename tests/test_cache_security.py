"""The kernel cache refuses folders another user could change (issue 25).

Generated kernel modules, Python's bytecode and numba's pickled machine code are
executed from the cache folder, so a folder that is not the user's alone (or that sits
in a folder others can rename things in) is refused with one warning per process, and
kernels go to a private 0700 folder. The in-process tests reset the module's state
(the private folder and the warned-once flag) and keep temporary folders under
``tmp_path``; the two end-to-end tests compile in a subprocess (one compile each).
"""

import contextlib
import hashlib
import importlib.util
import json
import marshal
import math
import os
import stat
import subprocess
import sys
import tempfile
import textwrap
import warnings

import pytest

from sweep import kernels
from sweep.kernels import cache

#: The spec `sweep.run` builds for one trajectory of the linear model (checked below:
#: the run's build is a memo hit).
SPEC = kernels.KernelSpec("linear", (), ("final",), block=1)
NAME = "sweep_kernel_" + hashlib.sha1(kernels.source(SPEC).encode()).hexdigest()[:16]
OTHER_UID = 4242  # not the test's user (root in CI)

needs_root = pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0,
                                reason="making a folder owned by another uid (chown) "
                                       "needs root; CI runs the tests as root")

SCRIPT = textwrap.dedent(f"""
    import json, stat, sys, warnings
    import sweep
    from sweep import kernels
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = sweep.run(sweep.Scene(model="linear"), sweep.Grid(theta0=[0.1]), t_end=1.0,
                       dt=0.01, observe=("final",))
        kernel = kernels.build(kernels.{SPEC!r})
        kernels.cache._module_dir()  # again, after the first warning
    module = sys.modules["{NAME}"].__file__
    from pathlib import Path
    print(json.dumps({{
        "theta": float(ds.theta_final[0]),
        "misses": kernels.build.cache_info().misses,
        "hits": sum(kernels.compiled(kernel).stats.cache_hits.values()),
        "module": module,
        "mode": stat.S_IMODE(Path(module).parent.stat().st_mode),
        "warnings": [str(w.message) for w in caught
                     if w.category.__name__ == "UnsafeCacheWarning"],
    }}))
""")


def _run(cache_dir):
    """Run SCRIPT with ``SWEEP_CACHE_DIR=cache_dir``; its JSON report."""
    env = dict(os.environ, SWEEP_CACHE_DIR=str(cache_dir))
    for name in ("NUMBA_CACHE_DIR", "PYTHONPYCACHEPREFIX"):  # keep caches beside modules
        env.pop(name, None)
    result = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads(result.stdout)
    assert report["misses"] == 1  # the run built SPEC: the module is NAME
    assert math.isclose(report["theta"], 0.1 * math.cos(math.sqrt(9.81)), abs_tol=1e-7)
    return report


def _mode(path):
    return stat.S_IMODE(os.lstat(path).st_mode)


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """The cache module's process state reset; temporary folders under ``tmp_path/tmp``;
    returns a function setting ``SWEEP_CACHE_DIR``."""
    monkeypatch.setattr(cache, "_private", None)
    monkeypatch.setattr(cache, "_warned", False)
    tmp = tmp_path / "tmp"
    tmp.mkdir(mode=0o700)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    return lambda folder: monkeypatch.setenv("SWEEP_CACHE_DIR", str(folder))


@contextlib.contextmanager
def _no_warning():
    """A context turning an UnsafeCacheWarning into an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", cache.UnsafeCacheWarning)
        yield


# ------------------------------------------------------------------ end to end
def test_a_world_writable_cache_dir_is_not_used(tmp_path):
    """A 0777 SWEEP_CACHE_DIR holding a planted kernel: the genuine module's text with
    bytecode beside it that writes a marker and raises (its header matches the module's
    mtime and size, so an import from this folder would run it). sweep warns once and
    builds and runs the kernel from a private 0700 folder instead."""
    shared = tmp_path / "shared"
    folder = shared / "kernels"
    folder.mkdir(parents=True)
    for path in (shared, folder):
        path.chmod(0o777)
    module = folder / f"{NAME}.py"
    module.write_text(kernels.source(SPEC))
    marker = tmp_path / "planted-code-ran"
    code = compile(f"open({str(marker)!r}, 'w').close()\nraise RuntimeError('planted')",
                   str(module), "exec")
    info = module.stat()
    pyc = importlib.util.MAGIC_NUMBER + (0).to_bytes(4, "little") \
        + (int(info.st_mtime) & 0xFFFFFFFF).to_bytes(4, "little") \
        + (info.st_size & 0xFFFFFFFF).to_bytes(4, "little") + marshal.dumps(code)
    bytecode = importlib.util.cache_from_source(str(module))
    os.makedirs(os.path.dirname(bytecode), mode=0o777)
    with open(bytecode, "wb") as handle:
        handle.write(pyc)

    report = _run(shared)

    assert not marker.exists()
    private = os.path.dirname(report["module"])
    assert os.path.basename(report["module"]) == f"{NAME}.py"
    assert os.path.basename(private).startswith("sweep-kernels-")
    assert report["mode"] == 0o700
    [message] = report["warnings"]  # once, though the folder was asked for again
    assert str(shared) in message and "0777" in message and private in message
    assert "chmod 700" in message and "SWEEP_CACHE_DIR" in message


def test_a_safe_cache_dir_is_used_without_warning_and_caches_across_processes(tmp_path):
    """A fresh SWEEP_CACHE_DIR (its parent made here, umask 022): no warning, the module
    and numba's index in ``kernels`` and its ``__pycache__`` (both 0700), and the next
    process loads the machine code from there, the module's mtime kept."""
    root = tmp_path / "cache"
    old = os.umask(0o022)
    try:
        first = _run(root)
    finally:
        os.umask(old)
    folder = root / "kernels"
    assert first["warnings"] == [] and first["hits"] == 0
    assert first["module"] == str(folder / f"{NAME}.py")
    assert [_mode(p) for p in (root, folder, folder / "__pycache__")] == [0o700] * 3
    assert any(p.suffix == ".nbi" for p in (folder / "__pycache__").iterdir())
    mtime = os.stat(first["module"]).st_mtime_ns
    second = _run(root)
    assert second["warnings"] == [] and second["hits"] == 1
    assert os.stat(second["module"]).st_mtime_ns == mtime


# ------------------------------------------------------------------ layouts, in process
def _world_writable_parent(tmp_path):
    parent = tmp_path / "open"
    parent.mkdir()
    parent.chmod(0o777)
    (parent / "cache").mkdir(mode=0o700)
    return parent / "cache", parent, "0777"


def _group_writable_kernels(tmp_path):
    (tmp_path / "cache" / "kernels").mkdir(parents=True)
    (tmp_path / "cache" / "kernels").chmod(0o770)
    return tmp_path / "cache", tmp_path / "cache" / "kernels", "0770"


def _unsafe_fallback(tmp_path):
    """The configured folder cannot be made (a file in the way); the predictable
    fallback ``<tmp>/sweep-kernels-<uid>`` was planted world-writable."""
    (tmp_path / "file").write_text("")
    planted = tmp_path / "tmp" / f"sweep-kernels-{os.getuid()}"
    planted.mkdir()
    planted.chmod(0o777)
    return tmp_path / "file" / "cache", planted, "0777"


def _other_owner(tmp_path):
    (tmp_path / "cache").mkdir(mode=0o700)
    os.chown(tmp_path / "cache", OTHER_UID, OTHER_UID)
    return tmp_path / "cache", tmp_path / "cache", f"uid {OTHER_UID}"


def _other_owner_kernels(tmp_path):
    (tmp_path / "cache" / "kernels").mkdir(parents=True, mode=0o700)
    os.chown(tmp_path / "cache" / "kernels", OTHER_UID, OTHER_UID)
    return tmp_path / "cache", tmp_path / "cache" / "kernels", f"uid {OTHER_UID}"


def _others_symlink(tmp_path):
    """A symlink owned by another user, to a folder of ours."""
    (tmp_path / "mine").mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(tmp_path / "mine")
    os.lchown(tmp_path / "link", OTHER_UID, OTHER_UID)
    return tmp_path / "link", tmp_path / "link", f"symlink owned by uid {OTHER_UID}"


def _check_refused(tmp_path, set_cache_dir, layout):
    configured, culprit, what = layout(tmp_path)
    set_cache_dir(configured)
    with pytest.warns(cache.UnsafeCacheWarning) as caught:
        private = cache._module_dir()
    [message] = [str(w.message) for w in caught]
    assert f"{culprit} " in message and what in message and str(private) in message
    assert private.parent == tmp_path / "tmp" and private.name.startswith("sweep-kernels-")
    assert _mode(private) == 0o700 and not list(private.glob("*.py"))
    with _no_warning():  # warned once per process; the same private folder
        assert cache._module_dir() == private


@pytest.mark.parametrize("layout", [_world_writable_parent, _group_writable_kernels,
                                    _unsafe_fallback])
def test_folders_others_can_write_are_refused(fresh, tmp_path, layout):
    _check_refused(tmp_path, fresh, layout)


@needs_root
@pytest.mark.parametrize("layout", [_other_owner, _other_owner_kernels, _others_symlink])
def test_folders_owned_by_another_user_are_refused(fresh, tmp_path, layout):
    _check_refused(tmp_path, fresh, layout)


def test_folders_sweep_creates_are_0700(fresh, tmp_path):
    """Under umask 0 (which would leave mkdir's default 0777): every missing component
    of the configured folder, the predictable fallback and the private folder."""
    old = os.umask(0)
    try:
        fresh(tmp_path / "a" / "b")
        folder = cache._module_dir()
        assert folder == tmp_path / "a" / "b" / "kernels"
        made = [tmp_path / "a", tmp_path / "a" / "b", folder, folder / "__pycache__"]
        (tmp_path / "file").write_text("")
        fresh(tmp_path / "file" / "cache")  # cannot be made: the predictable fallback
        fallback = cache._module_dir()
        assert fallback == tmp_path / "tmp" / f"sweep-kernels-{os.getuid()}"
        made += [fallback, fallback / "__pycache__"]
        (tmp_path / "open").mkdir()
        (tmp_path / "open").chmod(0o777)
        fresh(tmp_path / "open" / "cache")  # refused: the private folder
        with pytest.warns(cache.UnsafeCacheWarning):
            private = cache._module_dir()
        made += [private, private / "__pycache__"]
    finally:
        os.umask(old)
    assert {str(p): oct(_mode(p)) for p in made} == {str(p): "0o700" for p in made}


def _sticky_parent(tmp_path):
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared").chmod(0o1777)  # like /tmp
    return tmp_path / "shared" / "cache"


def _own_symlink(tmp_path):
    (tmp_path / "mine").mkdir(mode=0o700)
    (tmp_path / "link").symlink_to(tmp_path / "mine")
    return tmp_path / "link"


def _earlier_0755(tmp_path):
    """A cache made by an earlier sweep (mkdir's default mode under umask 022)."""
    (tmp_path / "cache" / "kernels" / "__pycache__").mkdir(parents=True)
    for path in (tmp_path / "cache", tmp_path / "cache" / "kernels",
                 tmp_path / "cache" / "kernels" / "__pycache__"):
        path.chmod(0o755)
    return tmp_path / "cache"


@pytest.mark.parametrize("layout", [_sticky_parent, _own_symlink, _earlier_0755])
def test_safe_folders_are_used_without_warning(fresh, tmp_path, layout):
    configured = layout(tmp_path)
    fresh(configured)
    with _no_warning():
        assert cache._module_dir() == configured / "kernels"
    assert cache._private is None
