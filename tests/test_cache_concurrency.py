"""The kernel cache under concurrent writers: pytest-xdist's workers (and Dask's, on one
machine) compile into one cache folder at once.

sweep writes a generated module atomically (`sweep.kernels.cache._write_once`) and numba
writes each cache file atomically (a unique temporary file, then ``os.replace``), but
numba's update of a function's index is a read-modify-write without a lock:
`sweep.kernels.cache` serialises it (``_serialise_numba_index``), checked here by
forcing the interleaving that otherwise maps one signature to another's machine code.
"""

import json
import os
import subprocess
import sys
import textwrap
import threading
import time

from numba.core import caching

from sweep.kernels import cache

cache._serialise_numba_index()  # as build() does (conftest.py has too)

#: One process: wait for the start file, run the linear model's one-trajectory kernel,
#: report the result and whether the kernel was compiled or loaded from the disk cache.
#: With a barrier (``argv[3:5]``: this process's file and the other's), a generated
#: kernel's first look into numba's cache waits, once it missed, until the other process
#: missed too: both then compile at once whatever the load (on a busy CI one process
#: could otherwise start so late that it found the other's kernel on disk).
SCRIPT = textwrap.dedent("""
    import json, os, sys, time
    from numba.core import caching
    import sweep
    from sweep import kernels

    if len(sys.argv) > 3:
        mine, other = sys.argv[3:5]
        load = caching.Cache.load_overload

        def load_overload(self, sig, target_context):
            data = load(self, sig, target_context)
            generated = "bind" in getattr(self._py_func, "__globals__", {})
            if data is None and generated and not os.path.exists(mine):
                open(mine, "w").close()
                end = time.monotonic() + 120
                while not os.path.exists(other) and time.monotonic() < end:
                    time.sleep(0.005)
            return data

        caching.Cache.load_overload = load_overload
    open(sys.argv[2], "w").close()  # imported: ready to start
    while not os.path.exists(sys.argv[1]):
        time.sleep(0.005)
    ds = sweep.run(sweep.Scene(model="linear"), sweep.Grid(theta0=[0.1]), t_end=1.0,
                   dt=0.01, observe=("final",))
    kernel = kernels.build(kernels.KernelSpec("linear", (), ("final",), block=1))
    stats = kernels.compiled(kernel).stats
    print(json.dumps({"theta": float(ds.theta_final[0]),
                      "hits": sum(stats.cache_hits.values()),
                      "misses": sum(stats.cache_misses.values())}))
""")


def test_two_processes_compiling_one_kernel_at_once_share_the_cache(tmp_path):
    env = {**os.environ, "SWEEP_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("NUMBA_CACHE_DIR", None)  # numba's files beside the modules, in tmp_path
    start = tmp_path / "start"

    def launch(k, barrier=True):
        missed = [str(tmp_path / f"missed{k}"), str(tmp_path / f"missed{1 - k}")]
        return subprocess.Popen([sys.executable, "-c", SCRIPT, str(start),
                                 str(tmp_path / f"ready{k}")] + (missed if barrier else []),
                                env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)

    both = [launch(0), launch(1)]
    end = time.monotonic() + 120  # both have imported sweep (a fixed sleep was too short
    while not all((tmp_path / f"ready{k}").exists() for k in (0, 1)):  # on a busy CI)
        assert time.monotonic() < end and all(p.poll() is None for p in both)
        time.sleep(0.01)
    start.touch()  # then they compile together
    reports = []
    for process in both:
        out, err = process.communicate(timeout=300)
        assert process.returncode == 0, err
        reports.append(json.loads(out.splitlines()[-1]))
    assert reports[0]["theta"] == reports[1]["theta"]
    assert all(r["misses"] == 1 and r["hits"] == 0 for r in reports)  # both compiled
    assert all((tmp_path / f"missed{k}").exists() for k in (0, 1))  # the barrier held

    later = launch(2, barrier=False)
    out, err = later.communicate(timeout=300)  # start exists: runs at once
    assert later.returncode == 0, err
    report = json.loads(out.splitlines()[-1])
    assert report == {"theta": reports[0]["theta"], "hits": 1, "misses": 0}
    modules = sorted(p.name for p in (tmp_path / "cache" / "kernels").glob("*.py"))
    assert len(modules) == 1, modules  # one module, written once, no temporary left


def test_numba_index_updates_are_serialised(tmp_path, monkeypatch):
    """Two savers of different signatures of one function, each reading the index
    before the other wrote it (the read made slow): without the lock both take
    ``.1.nbc`` and one signature's entry names the other's data."""
    load = caching.IndexDataCacheFile._load_index

    def slow_load(self):
        overloads = load(self)
        time.sleep(0.3)
        return overloads

    monkeypatch.setattr(caching.IndexDataCacheFile, "_load_index", slow_load)
    stamp = (1.0, 100)

    def index():  # numba makes one per process and function
        return caching.IndexDataCacheFile(str(tmp_path), "f-1.py311", stamp)

    savers = [threading.Thread(target=index().save, args=(key, data))
              for key, data in (("float64 key", "float64 code"), ("int64 key", "int64 code"))]
    for thread in savers:
        thread.start()
    for thread in savers:
        thread.join()
    fresh = index()
    assert fresh.load("float64 key") == "float64 code"
    assert fresh.load("int64 key") == "int64 code"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f-1.py311.1.nbc", "f-1.py311.2.nbc",
                                                          "f-1.py311.nbi"]


def test_concurrent_processes_all_get_the_configured_kernel_folder(tmp_path, monkeypatch):
    """`sweep._config.kernel_folder` checks that the folder is writable with a probe
    file. It was one shared name, ``.write-probe``: when two callers (two Dask workers
    building their first kernel at once) touched and unlinked it together, one unlink
    raised FileNotFoundError and that caller fell back to a private temporary folder,
    so it compiled its kernels anew (seen once as a Dask worker compiling a kernel the
    client had cached; here 54 of 1600 threaded calls took the fallback). Eight threads
    calling it 200 times each must all get the configured folder."""
    from sweep import _config

    monkeypatch.setenv("SWEEP_CACHE_DIR", str(tmp_path / "cache"))
    want = _config.kernel_folder()
    assert want == (tmp_path / "cache" / "kernels", None)
    wrong = []

    def caller():
        for _ in range(200):
            got = _config.kernel_folder()
            if got != want:
                wrong.append(got)

    threads = [threading.Thread(target=caller) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not wrong, wrong[:3]
    assert not list((tmp_path / "cache" / "kernels").glob(".write-probe*"))  # none left
