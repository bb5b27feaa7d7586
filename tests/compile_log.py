"""Where a test run's time goes to numba compiling: a pytest plugin.

``SWEEP_COMPILE_LOG=compile.jsonl python -m pytest ...`` writes one JSON line per numba
compile (a cache miss: loads from numba's disk cache are not compiles) with the test
that triggered it, the function (``sweep_kernel_<hash>.blocks`` or ``.grouped`` for a
generated kernel, with its `KernelSpec`), and the seconds it took, wall clock and CPU
(the compiling thread's: on a busy machine the wall clock also counts the time others
held the core), nested compiles (the helpers a kernel calls) counted in the outermost
one. It also writes one line per test with the CPU seconds the whole test took (setup,
call and teardown: this process's threads and the child processes it waited for, such
as a benchmark script or a second Python), compiling or not, so that what a warm run
spends shows too, and one line per test and generated kernel it uses (``"uses"``, from
the memo of `sweep.kernels.cache` as well as from numba's disk cache), so that a kernel
only one test needs can be found. Under pytest-xdist every worker writes
``compile.<worker>.jsonl``. ``python tests/compile_log.py compile*.jsonl`` sums them:
per test file, per test, per spec, the specs that several tests compiled, and the
functions that more than one worker compiled (each loads from numba's disk cache what
another has already written, so only near-simultaneous first uses compile twice).

tests/conftest.py calls its hooks; they do nothing unless the variable is set.
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import sys
import time
from collections import defaultdict

_ENV = "SWEEP_COMPILE_LOG"


class _Recorder:
    """A numba event listener (numba.core.event.Listener's on_start / on_end)."""

    def __init__(self, path):
        self.handle = open(path, "a")  # noqa: SIM115 - open for the whole run
        self.test = "<collection>"
        self.depth = 0
        self.started = 0.0
        self.started_cpu = 0.0
        self.specs = {}  # generated module name -> repr of its KernelSpec
        self.used = set()  # (test, generated module name) already logged

    def on_start(self, event):
        if self.depth == 0:
            self.started = time.perf_counter()
            self.started_cpu = time.thread_time()
        self.depth += 1

    def on_end(self, event):
        self.depth -= 1
        if self.depth:
            return
        dispatcher = event.data["dispatcher"]
        func = getattr(dispatcher, "py_func", None)
        module = getattr(func, "__module__", "?")
        name = f"{module}.{getattr(func, '__qualname__', '?')}"
        self.handle.write(json.dumps({
            "test": self.test, "function": name, "spec": self.specs.get(module),
            "seconds": round(time.perf_counter() - self.started, 4),
            "cpu": round(time.thread_time() - self.started_cpu, 4),
            "args": str(event.data.get("args"))[:200],
        }) + "\n")
        self.handle.flush()


def pytest_configure(config):
    path = os.environ.get(_ENV)
    if not path:
        return
    worker = os.environ.get("PYTEST_XDIST_WORKER")
    if worker:
        root, ext = os.path.splitext(path)
        path = f"{root}.{worker}{ext}"
    import hashlib

    from numba.core import event

    import sweep.kernels.cache as cache

    class Recorder(_Recorder, event.Listener):
        pass

    recorder = Recorder(path)
    event.register("numba:compile", recorder)
    source = cache.source

    def recording_source(spec):  # cache.build names the module by the source's hash
        text = source(spec)
        name = "sweep_kernel_" + hashlib.sha1(text.encode()).hexdigest()[:16]
        recorder.specs[name] = repr(spec)
        return text

    cache.source = recording_source
    built = cache._build  # the memo, which cache.build calls for every kernel a run uses

    def recording_build(spec, *settings):
        name = "sweep_kernel_" + hashlib.sha1(source(spec).encode()).hexdigest()[:16]
        if (recorder.test, name) not in recorder.used:
            recorder.used.add((recorder.test, name))
            recorder.specs.setdefault(name, repr(spec))
            recorder.handle.write(json.dumps({"test": recorder.test, "uses": name,
                                              "spec": recorder.specs[name]}) + "\n")
        return built(spec, *settings)

    # cache.build (imported by name everywhere) calls the recorder instead of the memo,
    # which stays cache._build: pickled by name (build.cache_info, sent to Dask workers),
    # it must be the module's own
    cache._recording_build = recording_build
    code = cache.build.__code__
    cache.build.__code__ = code.replace(co_names=tuple(
        "_recording_build" if n == "_build" else n for n in code.co_names))
    config._sweep_compile_log = recorder


def pytest_runtest_setup(item):
    recorder = getattr(item.config, "_sweep_compile_log", None)
    if recorder is not None:
        recorder.test = item.nodeid


def _cpu_now():
    """CPU seconds (user + system) of this process and of its waited-for children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@contextlib.contextmanager
def test_cpu(item):
    """Around one test's setup, call and teardown: log its CPU seconds (a line with
    ``"test_cpu"``) when the log is on."""
    recorder = getattr(item.config, "_sweep_compile_log", None)
    if recorder is None:
        yield
        return
    started, wall = _cpu_now(), time.perf_counter()
    try:
        yield
    finally:
        recorder.handle.write(json.dumps({
            "test": item.nodeid, "test_cpu": round(_cpu_now() - started, 4),
            "test_seconds": round(time.perf_counter() - wall, 4)}) + "\n")
        recorder.handle.flush()


def _compiled_by_several(rows):
    """How many functions (a generated kernel's spec, or a function with its argument
    types) more than one log file compiled, and the CPU seconds of all but each one's
    cheapest process: what sharing the work between the processes cost in compiling."""
    cpu = defaultdict(lambda: defaultdict(float))  # function -> log file -> CPU seconds
    for r in rows:
        cpu[(r["spec"], r["function"], r["args"])][r["log"]] += r.get("cpu", 0.0)
    several = [sorted(by_log.values()) for by_log in cpu.values() if len(by_log) > 1]
    return len(several), sum(sum(seconds[1:]) for seconds in several)


def _summary(paths):
    rows, tests, uses = [], [], []
    for path in paths:
        with open(path) as handle:
            for line in handle:
                row = json.loads(line)
                row["log"] = path  # one file per process (pytest-xdist worker)
                (tests if "test_cpu" in row else uses if "uses" in row else rows).append(row)
    if tests:
        test_cpu = defaultdict(float)
        for r in tests:
            test_cpu[r["test"].split("::")[0]] += r["test_cpu"]
        print(f"{len(tests)} tests, {sum(test_cpu.values()):.0f} s CPU in all "
              f"(compiling or not, child processes included)")
        print("\nper test file: CPU seconds of its tests")
        for name, c in sorted(test_cpu.items(), key=lambda kv: -kv[1])[:60]:
            print(f"{c:8.1f}  {name}")
        print("\nper test: CPU seconds")
        for r in sorted(tests, key=lambda r: -r["test_cpu"])[:40]:
            print(f"{r['test_cpu']:8.1f}  {r['test']}")
        print()
    total = sum(r["seconds"] for r in rows)
    cpu = sum(r.get("cpu", 0.0) for r in rows)
    per_test, per_spec, tests_of = defaultdict(float), defaultdict(float), defaultdict(set)
    for r in rows:
        per_test[r["test"]] += r["seconds"]
        key = r["spec"] or r["function"]
        per_spec[key] += r["seconds"]
        tests_of[key].add(r["test"].split("::")[0])
    kernels = {r["spec"] for r in rows if r["spec"]}
    print(f"{len(rows)} compiles, {total:.0f} s ({cpu:.0f} s CPU); "
          f"{len(kernels)} generated kernels")
    twice, extra = _compiled_by_several(rows)
    print(f"{twice} compiled by more than one process (each worker compiles what numba's "
          f"disk cache did not yet hold when it needed it): {extra:.1f} s CPU beyond "
          f"each one's cheapest copy")
    print("\nper test file: compiles, seconds, CPU seconds")
    per_file = defaultdict(lambda: [0, 0.0, 0.0])
    for r in rows:
        row = per_file[r["test"].split("::")[0]]
        row[0] += 1
        row[1] += r["seconds"]
        row[2] += r.get("cpu", 0.0)
    for name, (n, s, c) in sorted(per_file.items(), key=lambda kv: -kv[1][1])[:60]:
        print(f"{n:4d} {s:8.1f} {c:8.1f}  {name}")
    print("\nper test:")
    for name, s in sorted(per_test.items(), key=lambda kv: -kv[1])[:40]:
        print(f"{s:8.1f}  {name}")
    print("\nper spec or function:")
    for name, s in sorted(per_spec.items(), key=lambda kv: -kv[1])[:40]:
        print(f"{s:8.1f}  {name[:300]}  [{', '.join(sorted(tests_of[name]))[:200]}]")
    if uses:
        users = defaultdict(set)
        for r in uses:
            users[r["uses"]].add(r["test"])
        alone = [name for name, who in users.items() if len(who) == 1]
        print(f"\n{len(users)} generated kernels used, {len(alone)} of them by one test only")


if __name__ == "__main__":
    _summary(sys.argv[1:])
