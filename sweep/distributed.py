"""Run the chunks of a sweep as tasks on a Dask cluster (`sweep.run(..., client=...)`).

Dask is optional (``pip install "sweep[dask]"``) and imported only here, only when a
client is given: ``import sweep`` never imports dask.

How a run is distributed
------------------------
One small task holds the run's *context* (scene, grid axes, kernel spec, time
settings); the client submits it once, and every chunk task depends on it, so the grid
travels to each worker once rather than once per chunk (and, being a task rather than
scattered data, it is recomputed if the worker holding it is lost). Each chunk task
(`run_chunk_task`) builds its own parameter table from the grid, gets the kernel from
`sweep._kernels.build` (memoised in the worker process, and loaded from numba's on-disk
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

Larger than memory
------------------
`run_to_netcdf` writes the result to a netCDF4 file block by block (blocks of rows of
the grid's first axis, each an ordinary `sweep.run` of that sub-grid, on the cluster or
in this process) as blocks finish, so neither the client nor a worker ever holds more
than a block; the file, loaded, is identical to the dataset of `sweep.run`.

Threads: each chunk runs the numba kernel with numba's own threads (all the worker's
cores by default), so start workers with one Dask thread each (``threads_per_worker=1``,
``--nthreads 1``) and let numba use the cores. Several Dask threads in one worker are
safe (a per-process lock runs their kernels one at a time) but bring nothing.
"""

from __future__ import annotations

import threading
import time
import uuid

import numpy as np

from ._validate import check_positive_int

__all__ = ["RunContext", "check_client", "run_chunk_task", "run_chunks", "run_to_netcdf"]

#: numba's default (workqueue) threading layer must not be entered by two threads of one
#: process at once; a Dask worker with several threads would do that.
_KERNEL_LOCK = threading.Lock()


class RunContext:
    """What every chunk task needs: scene, grid, kernel spec and time settings.

    A plain picklable object; `table` gives a chunk's parameter rows.
    """

    def __init__(self, scene, grid, spec, settings) -> None:
        self.scene = scene
        self.grid = grid
        self.spec = spec
        self.settings = settings

    def table(self, start: int, stop: int) -> np.ndarray:
        return self.grid.table(self.scene, start, stop)


def allocate(spec, settings, n: int) -> dict[str, np.ndarray]:
    """The per-trajectory arrays a kernel writes for ``n`` trajectories: ``out``,
    ``status``, and ``saved`` (with ``save_every``) and ``stats`` (adaptive methods)."""
    from ._kernels import n_columns

    arrays = {"out": np.empty((n, n_columns(spec)), dtype=np.float64),
              "status": np.empty(n, dtype=np.int8)}
    if settings.save_every is not None:
        n_saved = settings.n_steps // settings.save_every + 1
        arrays["saved"] = np.full((n, 2, n_saved), np.nan)
    if settings.adaptive:
        arrays["stats"] = np.zeros((n, 2), dtype=np.int64)
    return arrays


def integrate(kernel, table, settings, arrays: dict[str, np.ndarray]) -> None:
    """Run ``kernel`` on the parameter rows ``table``, writing into ``arrays`` (same
    rows): the one call of the kernel contract, shared by local runs and workers."""
    if settings.adaptive:
        kernel(table, settings.t0, settings.t_end, settings.dt, settings.t_transient,
               settings.rtol, settings.atol, arrays["out"], arrays["status"],
               arrays["stats"])
    else:
        saved = arrays.get("saved")
        kernel(table, settings.t0, settings.dt, settings.n_steps, settings.n_transient,
               settings.save_every or 1, arrays["out"], arrays["status"],
               saved if saved is not None else np.empty((0, 2, 0)))


def run_chunk_task(context: RunContext, start: int, stop: int) -> dict:
    """Worker side: integrate trajectories ``start:stop`` of the run ``context``.

    Returns
    -------
    dict
        The chunk's rows of each array of `allocate` (``out``, ``status``, ``saved``,
        ``stats``) and ``"seconds"``: the wall time of kernel build/load plus
        integration in this task (a recompiling task would show it here).
    """
    from ._kernels import build

    began = time.perf_counter()
    kernel = build(context.spec)  # memoised per process; numba loads machine code from disk
    arrays = allocate(context.spec, context.settings, stop - start)
    table = context.table(start, stop)
    with _KERNEL_LOCK:
        integrate(kernel, table, context.settings, arrays)
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
                        "installed; accepted: client=None, or pip install 'sweep[dask]'") \
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


# ------------------------------------------------------------------ streamed output
def _block_task(scene, grid, kwargs):
    """Worker side of `run_to_netcdf`: the plain `sweep.run` of one block of the grid
    (its non-finite warning is left to the client, which counts the whole run)."""
    import warnings

    from .engine import run

    with _KERNEL_LOCK, warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return run(scene, grid, progress=False, **kwargs)


_NOT_STREAMED = ("client", "checkpoint", "resume", "keep_checkpoint", "estimate_error",
                 "progress")


def run_to_netcdf(path, scene, grid, *, client=None, rows_per_task=None, retries=2,
                  progress=None, **run_kwargs):
    """`sweep.run` whose result is written to the netCDF4 file ``path`` block by block
    as blocks finish, so that the grid need not fit in memory (the client holds one
    block at a time; a worker, the block it computes).

    The grid is cut along its first axis into blocks of ``rows_per_task`` rows (default:
    as many rows as make about ``chunk_size`` trajectories, at least one); each block is
    an ordinary `sweep.run` of that sub-grid, on ``client``'s cluster or, without a
    client, one after another in this process. The file is written to a temporary name
    in the same folder and renamed into place once complete; ``sweep.load(path)`` then
    gives a dataset identical to ``sweep.run(scene, grid, **run_kwargs)`` (except the
    ``history`` timestamp).

    Parameters
    ----------
    path : str or Path
    scene, grid, **run_kwargs
        As for `sweep.run` (validated in full before any compute); not accepted here:
        ``checkpoint``, ``resume``, ``keep_checkpoint``, ``estimate_error``, ``client``
        in ``run_kwargs``.
    client : dask.distributed.Client, optional
    rows_per_task : int, optional
    retries : int, default 2
        Retries of a block whose task raised (a lost worker's blocks are rerun anyway).
    progress : bool, optional
        One progress line on stderr (default: when stderr is a tty).

    Returns
    -------
    pathlib.Path
    """
    import inspect
    import os
    import sys
    import tempfile
    import warnings

    from . import engine, io
    from ._kernels import Status
    from .grid import Grid

    for name in _NOT_STREAMED:
        if name in run_kwargs:
            raise ValueError(f"run_to_netcdf does not take {name}= (accepted: the other "
                             "arguments of sweep.run; client, progress and rows_per_task "
                             "as its own)")
    bound = inspect.signature(engine.run).bind(scene, grid, **run_kwargs)
    bound.apply_defaults()
    prepared = {k: v for k, v in bound.arguments.items()
                if k in inspect.signature(engine._prepare).parameters}
    _, _, chunk_size = engine._prepare(**prepared)  # whole-grid validation, no compute
    if client is not None:
        check_client(client)
    path = io.check_output_path(path)
    first, *rest = grid.dims
    axes = grid.axes
    inner = grid.size // grid.shape[0]
    if rows_per_task is None:
        rows_per_task = max(1, chunk_size // max(inner, 1))
    check_positive_int("rows_per_task", rows_per_task, "None or an int >= 1")
    blocks = [(i, min(i + int(rows_per_task), grid.shape[0]))
              for i in range(0, grid.shape[0], int(rows_per_task))]

    def block_grid(i0, i1):
        return Grid(**{name: (values[i0:i1] if name == first else values)
                       for name, values in axes.items()})

    report = engine._progress_printer(sys.stderr.isatty() if progress is None
                                      else bool(progress), grid.size)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    os.close(fd)
    nc = None
    done = failed = 0
    futures = {}
    try:
        def write(i0, i1, block):
            nonlocal nc, done, failed
            if nc is None:  # the layout from the first block to arrive, 0 rows long
                import netCDF4

                block.isel({first: slice(0, 0)}).to_netcdf(
                    tmp, engine="netcdf4", format="NETCDF4", unlimited_dims=[first])
                nc = netCDF4.Dataset(tmp, "a")
            for name, variable in block.variables.items():
                if variable.dims[:1] == (first,):
                    nc[name][i0:i1] = variable.values
            failed += int(np.count_nonzero(block.status.values != Status.OK))
            done += block.status.size
            report(done)

        kwargs = dict(run_kwargs)
        if client is None:
            for i0, i1 in blocks:
                write(i0, i1, _block_task(scene, block_grid(i0, i1), kwargs))
        else:
            from distributed import as_completed

            for i0, i1 in blocks:
                future = client.submit(_block_task, scene, block_grid(i0, i1), kwargs,
                                       pure=False, retries=retries)
                futures[future.key] = (future, i0, i1)
            for future, block in as_completed([f for f, _, _ in futures.values()],
                                              with_results=True):
                _, i0, i1 = futures.pop(future.key)
                del future
                write(i0, i1, block)
        nc.close()
        nc = None
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if futures:
            client.cancel([f for f, _, _ in futures.values()])
        if nc is not None:
            nc.close()
        if os.path.exists(tmp):
            os.unlink(tmp)
    if failed:
        warnings.warn(f"{failed} of {grid.size} trajectories became non-finite; see "
                      "ds.status", RuntimeWarning, stacklevel=2)
    return path


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask
