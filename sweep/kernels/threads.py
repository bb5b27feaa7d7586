"""Spread a CPU kernel's blocks of trajectories over threads.

A generated CPU kernel (`sweep.kernels.fixed`, `sweep.kernels.adaptive`,
`sweep.kernels.refill`) compiles its work as one serial numba function,
``blocks(..., b_first, b_stop)``, which integrates the blocks ``b_first`` to
``b_stop - 1`` and releases the GIL (``nogil=True``); its ``kernel`` calls `run_blocks`,
which runs those blocks on a pool of threads. The blocks are independent, each trajectory
always runs in the same block and lane, so the results do not depend on the thread count
or on which thread ran which block (``tests/test_blocks.py``).

Why not numba's ``parallel=True`` and a ``prange`` over the blocks, as sweep did before:
running is as fast either way, but compiling a ``prange`` costs numba an array analysis,
a parfor pass and a second typing and lowering of the loop's body as a separate
function. For the forced scene's RK4 kernel (Zen 5, numba 0.68,
``benchmarks/compile_time.py``) compiling took 1.07 s with the ``prange`` and 0.40 s
serial, and each new scene, observable set or block size is a
kernel of its own: a researcher's first run of a scene, the explorer's first view of a
new effect and a cold test suite all wait for it. The thread count is numba's
(`numba.get_num_threads`, so ``numba.set_num_threads`` and ``NUMBA_NUM_THREADS`` work as
before); the pool is this module's, made on first use.

The blocks go to the threads in pieces, taken in turn by whichever thread is free, so a
thread whose blocks settle early (``stop_early``) takes more of them (numba's schedule
cut the blocks into one equal range per thread). A Ctrl-C or SIGTERM arriving while the
threads run does not leave them writing into the caller's arrays: no thread takes a new
piece, the pieces running finish, and then the interrupt is raised in the caller.
"""

from __future__ import annotations

import itertools
import os
import queue
import threading
from concurrent.futures import ThreadPoolExecutor

__all__ = ["PIECES_PER_THREAD", "run_blocks"]

#: Pieces of blocks per thread (fewer where there are fewer blocks): a thread that is
#: done early takes another piece, and each piece costs one call (microseconds).
PIECES_PER_THREAD = 4

_STARTED = object()  # a worker's first event

_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def _forget_pool() -> None:
    """In a forked child: the parent's pool threads do not exist there, so a task
    submitted to its pool would wait forever; the child makes its own."""
    global _pool, _pool_lock
    _pool, _pool_lock = None, threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def _executor() -> ThreadPoolExecutor:
    """The shared pool: as many workers as numba may use (``NUMBA_NUM_THREADS``), made on
    first use."""
    global _pool
    with _pool_lock:
        if _pool is None:
            import numba

            _pool = ThreadPoolExecutor(numba.config.NUMBA_NUM_THREADS,
                                       thread_name_prefix="sweep-blocks")
        return _pool


def run_blocks(blocks, n_blocks: int, *args) -> None:
    """Call ``blocks(*args, b_first, b_stop)`` over the blocks ``0 .. n_blocks - 1``, on
    numba's number of threads.

    ``blocks`` is first called over no block, in the caller's thread: that compiles it
    on its first call (once, where an error is raised once, and a Ctrl-C during the
    compile stops it before any thread starts), and is a dispatch of microseconds later.

    Parameters
    ----------
    blocks : numba dispatcher
        A generated kernel's serial function, compiled with ``nogil=True``.
    n_blocks : int
        Number of blocks (of trajectories, or of refill groups).
    *args
        The kernel's arguments, before the block range.

    Raises
    ------
    KeyboardInterrupt
        A Ctrl-C (or `sweep.cli.Terminated`) caught while the threads ran, raised once
        no thread computes a piece any more.
    Exception
        The first error of a thread's piece (the other threads take no new piece).
    """
    import numba

    blocks(*args, 0, 0)  # compiles (or loads) here; runs nothing
    threads = min(numba.get_num_threads(), n_blocks)
    if threads <= 1:  # one thread: no pool, no hand-over
        if n_blocks > 0:
            blocks(*args, 0, n_blocks)
        return
    n_pieces = min(n_blocks, PIECES_PER_THREAD * threads)
    bounds = [n_blocks * k // n_pieces for k in range(n_pieces + 1)]
    turn = itertools.count()  # next() on it is atomic under the GIL
    stop = threading.Event()
    # each worker says when it starts and when it ends (with its error, or None); the
    # caller reads them from a SimpleQueue, whose get() is C code that an interrupt
    # leaves consistent (concurrent.futures.wait takes locks in Python, where a signal
    # between two of them can leave one held and the next wait deadlocked)
    events = queue.SimpleQueue()

    def work() -> None:
        events.put(_STARTED)
        error = None
        try:
            for piece in turn:
                if piece >= n_pieces or stop.is_set():
                    break
                blocks(*args, bounds[piece], bounds[piece + 1])
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            stop.set()
            error = exc
        events.put(error)

    submitted = started = ended = 0
    interrupt = error = None
    try:
        pool = _executor()
        for _ in range(threads):
            pool.submit(work)
            submitted += 1
    except BaseException as exc:  # noqa: BLE001 - Ctrl-C, SIGTERM: re-raised below
        stop.set()
        interrupt = exc
    while True:
        if interrupt is None:
            if ended == submitted:
                break
        # interrupted: a worker that starts from now on sees ``stop`` and computes
        # nothing, so the ones to wait for are those that said they started
        elif ended == started and events.empty():
            break
        try:
            event = events.get()
        except BaseException as exc:  # noqa: BLE001 - Ctrl-C, SIGTERM: re-raised below
            # the threads write into the caller's arrays: they stop first
            stop.set()
            interrupt = interrupt or exc
            continue
        if event is _STARTED:
            started += 1
        else:
            ended += 1
            error = error or event
    if interrupt is not None:
        raise interrupt
    if error is not None:
        raise error
