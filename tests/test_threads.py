"""sweep.kernels.threads: a kernel's blocks spread over threads.

The kernels' results not depending on the thread count is tested on real kernels in
tests/test_blocks.py and tests/test_refill.py; here the driver itself, with Python
stand-ins for a kernel's ``blocks`` (``time.sleep`` releases the GIL as the compiled
function does).
"""

import os
import signal
import threading
import time

import numba
import pytest

from sweep.kernels import threads


@pytest.fixture
def all_threads():
    before = numba.get_num_threads()
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    yield numba.config.NUMBA_NUM_THREADS
    numba.set_num_threads(before)


def _recorder():
    calls = []
    lock = threading.Lock()

    def blocks(*args):
        *passed, first, stop = args
        with lock:
            calls.append((tuple(passed), first, stop, threading.current_thread().name))

    return blocks, calls


@pytest.mark.parametrize("n_blocks", [1, 2, 3, 7, 8, 9, 100])
@pytest.mark.parametrize("n_threads", [1, 2])
def test_every_block_runs_once(n_blocks, n_threads, all_threads):
    """Whatever the counts: the pieces cover 0 .. n_blocks - 1 once, in ranges that do
    not overlap, each call with the kernel's arguments before the range."""
    if n_threads > all_threads:
        pytest.skip("numba has fewer threads here")
    numba.set_num_threads(n_threads)
    blocks, calls = _recorder()
    threads.run_blocks(blocks, n_blocks, "params", 0.5)
    assert all(passed == ("params", 0.5) for passed, *_ in calls)
    # first a call over no block, in the caller's thread (it compiles the kernel)
    assert calls[0][1:] == (0, 0, threading.current_thread().name)
    pieces = calls[1:]
    covered = sorted(b for _, first, stop, _ in pieces for b in range(first, stop))
    assert covered == list(range(n_blocks))
    assert all(stop > first for _, first, stop, _ in pieces)
    # no more pieces than PIECES_PER_THREAD per thread, no more threads than numba's
    assert len(pieces) <= max(1, threads.PIECES_PER_THREAD * n_threads)
    assert len({name for *_, name in pieces}) <= n_threads


def test_one_thread_runs_in_the_callers_thread(all_threads):
    numba.set_num_threads(1)
    blocks, calls = _recorder()
    threads.run_blocks(blocks, 5, "x")
    assert [(first, stop) for _, first, stop, _ in calls] == [(0, 0), (0, 5)]
    assert {name for *_, name in calls} == {threading.current_thread().name}


def test_no_block_still_calls_once_so_the_kernel_compiles(all_threads):
    """`sweep.engine.warm_up` runs a kernel on no trajectories to compile it."""
    blocks, calls = _recorder()
    threads.run_blocks(blocks, 0, "x")
    assert [(first, stop) for _, first, stop, _ in calls] == [(0, 0)]


def test_an_error_in_a_thread_reaches_the_caller_and_stops_the_others(all_threads):
    if all_threads < 2:
        pytest.skip("one thread: no pool")
    ran = []

    def blocks(first, stop):
        if first == stop:  # the compiling call
            return
        ran.append(first)
        if first == 1:
            raise FloatingPointError(f"block {first}")
        time.sleep(0.05)

    with pytest.raises(FloatingPointError, match="block 1"):
        threads.run_blocks(blocks, 8)  # 8 pieces of one block
    # the piece that failed and the one beside it, not the 6 pieces after them
    assert 1 in ran and len(ran) < 8


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="POSIX only")
def test_ctrl_c_waits_for_the_running_pieces_and_starts_no_more(all_threads):
    """A KeyboardInterrupt arriving while the threads run is raised in the caller only
    once no thread still writes: the pieces running end, no new piece starts."""
    if all_threads < 2:
        pytest.skip("one thread: no pool")
    spans, lock = [], threading.Lock()

    def blocks(first, stop):
        if first == stop:  # the compiling call
            return
        start = time.perf_counter()
        time.sleep(0.2)  # releases the GIL, as the compiled blocks do
        with lock:
            spans.append((first, start, time.perf_counter()))

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals reach the main thread only")
    # Python's own Ctrl-C handler (a pytest-xdist worker ignores SIGINT)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.05, signal.pthread_kill,
                            (threading.main_thread().ident, signal.SIGINT))
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            threads.run_blocks(blocks, 40)
        raised = time.perf_counter()
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert spans, "no piece ran"
    assert all(end <= raised for _, _, end in spans)  # none still running
    # the pieces the threads had begun (one each), not the 4 per thread of a whole run
    n_pieces = min(40, threads.PIECES_PER_THREAD * all_threads)
    assert len(spans) < n_pieces
    assert all(start < spans[0][1] + 0.1 for _, start, _ in spans)  # all from the start


@pytest.mark.skipif(not hasattr(os, "fork"), reason="POSIX only")
def test_a_forked_child_gets_its_own_pool(all_threads):
    """After a fork the parent's pool threads do not exist in the child: the child's
    first run must not wait on them forever (multiprocessing forks by default here)."""
    if all_threads < 2:
        pytest.skip("one thread: no pool")

    def blocks(*args):
        time.sleep(0.01)  # a piece takes time, as a kernel's does

    threads.run_blocks(blocks, 8, "x")  # the parent's pool exists
    pid = os.fork()
    if pid == 0:  # the child: exit 0 if a run on threads completes, killed by SIGALRM if not
        try:
            signal.alarm(10)
            threads.run_blocks(blocks, 8, "x")
            os._exit(0)
        finally:
            os._exit(1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
