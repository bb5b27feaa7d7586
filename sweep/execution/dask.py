"""Run the chunks of a sweep as tasks on a Dask cluster (`sweep.run(..., client=...)`).

Dask is optional (the extra ``dask``: ``pip install -e ".[dask]"`` in a checkout, or
``pip install "dask[distributed]"``) and imported only here, only when a client is
given: ``import sweep`` never imports dask.

How a run is distributed
------------------------
One small task holds the run's *context* (scene, grid axes, kernel spec, time
settings); the client submits it once, and every chunk task depends on it, so the grid
travels to each worker once rather than once per chunk (and, being a task rather than
scattered data, it is recomputed if the worker holding it is lost). Each chunk task
(`run_chunk_task`) builds its own parameter table from the grid, gets the kernel from
`sweep.kernels.build` (memoised in the worker process, and loaded from numba's on-disk
cache, so a kernel is compiled at most once per machine and never per task), runs it,
and returns that chunk's rows of every output array. The client gathers results *as
they complete* into the preallocated arrays of `run`, so client memory holds the result
and little more, and a checkpoint (if any) stores each chunk as it arrives.

The kernel is deterministic per trajectory and independent of chunking and threads, so
the dataset is bit-identical to a local run of the same grid.

Failures
--------
- A worker lost mid-task (killed, out of memory, node gone): the scheduler reassigns
  its tasks to other workers on its own (up to ``distributed.scheduler.allowed-failures``
  times per task, default 3); nothing is lost.
- A task that raises is retried ``retries`` times (`run` passes 2), then the run
  raises that error and cancels what is left.
- A trajectory that goes non-finite is not a failure: it is flagged in ``status`` inside
  its chunk exactly as locally.

Threads: each chunk runs the kernel on the worker's cores (`sweep.kernels.threads`,
numba's thread count: all the cores by default), so start workers with one Dask thread
each (``threads_per_worker=1``, ``--nthreads 1``). Several Dask threads in one worker
are safe (a per-process lock runs their kernels one at a time) but bring nothing.
"""

from __future__ import annotations

import threading
import time
import uuid

import numpy as np

from ..kernels import build
from .local import RunContext, allocate, integrate

__all__ = ["RunContext", "check_client", "run_chunk_task", "run_chunks"]

#: One kernel at a time per process: each uses all the cores already, and two at once
#: would only compete for them (a Dask worker may have several threads).
_KERNEL_LOCK = threading.Lock()


def run_chunk_task(context: RunContext, start: int, stop: int) -> dict:
    """Worker side: integrate trajectories ``start:stop`` of the run ``context``.

    Returns
    -------
    dict
        The chunk's rows of each array of `allocate` (``out``, ``status``, ``saved``,
        ``stats``) and ``"seconds"``: the wall time of kernel build/load plus
        integration in this task (a recompiling task would show it here).
    """
    began = time.perf_counter()
    kernel = build(context.spec)  # memoised per process; numba loads machine code from disk
    arrays = allocate(context.spec, context.settings, stop - start)
    table = context.table(start, stop)
    with _KERNEL_LOCK:
        integrate(kernel, table, context.settings, arrays, context.known)
    arrays["seconds"] = time.perf_counter() - began
    return arrays


def _context_task(context: RunContext) -> RunContext:
    return context


def check_client(client) -> None:
    """Refuse anything but a `dask.distributed.Client` (TypeError, naming it)."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - exercised only without dask
        raise TypeError(f"client={client!r} needs dask.distributed, which is not "
                        "installed; accepted: client=None, or pip install 'dask[distributed]'") \
            from None
    if not isinstance(client, Client):
        raise TypeError(f"client must be None or a dask.distributed.Client, got {client!r}")


def run_chunks(client, context: RunContext, chunks, arrays: dict[str, np.ndarray], done,
               *, retries: int = 2) -> None:
    """Integrate ``chunks`` (a list of ``(start, stop)``) on the cluster of ``client``.

    Each finished chunk's rows are copied into ``arrays[name][start:stop]`` as soon as
    it arrives, then ``done(start, stop)`` is called (checkpoint, progress).

    Raises
    ------
    Exception
        A task's own error after ``retries`` retries; the remaining tasks are cancelled.
    """
    from distributed import as_completed

    if not chunks:
        return
    run_id = uuid.uuid4().hex[:12]
    shared = client.submit(_context_task, context, key=f"sweep-context-{run_id}",
                           pure=False, retries=retries)
    pending = {}
    for start, stop in chunks:
        future = client.submit(run_chunk_task, shared, start, stop, pure=False,
                               retries=retries, key=f"sweep-chunk-{run_id}-{start:012d}")
        pending[future.key] = (future, start, stop)
    try:
        for future, result in as_completed([f for f, _, _ in pending.values()],
                                           with_results=True):
            _, start, stop = pending.pop(future.key)
            for name, target in arrays.items():
                target[start:stop] = result[name]
            del future, result  # the worker may drop the chunk's rows now
            done(start, stop)
    finally:
        if pending:
            client.cancel([f for f, _, _ in pending.values()])
        client.cancel([shared])
