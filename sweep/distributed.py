"""Grids larger than memory: `run_to_netcdf` streams a sweep to a netCDF4 file.

Larger than memory
------------------
`run_to_netcdf` writes the result to a netCDF4 file block by block (blocks of rows of
the grid's first axis, each an ordinary `sweep.run` of that sub-grid, on the cluster or
in this process) as blocks finish, so neither the client nor a worker ever holds more
than a block; the file, loaded, is identical to the dataset of `sweep.run`.

Chunks of one `sweep.run` on a Dask cluster are `sweep.execution.dask`'s work
(``sweep.run(..., client=...)``); this module sits above the engine and calls
`sweep.run` like a user.
"""

from __future__ import annotations

from ._validate import check_flag, check_positive_int
from .execution.dask import _KERNEL_LOCK, check_client

__all__ = ["run_to_netcdf"]


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
                  progress=None, check_space=True, **run_kwargs):
    """`sweep.run` whose result is written to the netCDF4 file ``path`` block by block
    as blocks finish, so that the grid need not fit in memory (the client holds one
    block at a time; a worker, the block it computes).

    The grid is cut along its first axis into blocks of ``rows_per_task`` rows (default:
    as many rows as make about ``chunk_size`` trajectories, at least one), and `Points`
    into ranges of ``rows_per_task`` points (default ``chunk_size``); each block is
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
        A progress bar on stderr (default as for `sweep.run`).
    check_space : bool, default True
        Refuse, before any compute, a file that may not fit in the free space of its
        folder (`sweep.diskspace.check_space`). Its bound is the uncompressed size, so
        a file that would fit compressed can be refused: False skips the check (a file
        that does not fit after all raises `OSError` when written, leaving nothing).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        Before any compute: bad arguments, or (with ``check_space``) the file may not
        fit in the free space of its folder (`sweep.diskspace.check_space`: its
        uncompressed size is the bound).
    OSError
        The file could not be written (a full disk after all): one line naming it and
        the cause (`sweep.io.write_error`); no partial file is left.
    """
    import contextlib
    import os
    import tempfile
    import warnings

    from . import diskspace, engine, io
    from .execution.progress import progress_bar
    from .grid import Grid, Points
    from .kernels import failure_summary, status_counts

    for name in _NOT_STREAMED:
        if name in run_kwargs:
            raise ValueError(f"run_to_netcdf does not take {name}= (accepted: the other "
                             "arguments of sweep.run; client, rows_per_task, retries, "
                             "progress and check_space as its own)")
    check_space = check_flag("check_space", check_space)
    _, _, chunk_size = engine.prepare(scene, grid, **run_kwargs)  # validation, no compute
    if client is not None:
        check_client(client)
    path = io.check_output_path(path)
    needed = (diskspace.check_space(path, scene, grid, **run_kwargs) if check_space
              else diskspace.estimate_size(scene, grid, **run_kwargs))
    first = grid.dims[0]
    axes = grid.axes
    inner = grid.size // grid.shape[0]
    if rows_per_task is None:
        rows_per_task = max(1, chunk_size // max(inner, 1))
    check_positive_int("rows_per_task", rows_per_task, "None or an int >= 1")
    blocks = [(i, min(i + int(rows_per_task), grid.shape[0]))
              for i in range(0, grid.shape[0], int(rows_per_task))]

    def block_grid(i0, i1):
        if isinstance(grid, Points):  # rows i0:i1, every column
            return Points(**{name: values[i0:i1] for name, values in axes.items()})
        return Grid(**{name: (values[i0:i1] if name == first else values)
                       for name, values in axes.items()})

    closing = contextlib.ExitStack()
    bar = closing.enter_context(progress_bar(progress, grid.size))
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    os.close(fd)
    io._PARTIAL.add(tmp)  # deleted by a process that must end at once (sweep run, SIGTERM)
    nc = None
    failed = False
    counts = {}
    futures = {}
    try:
        def write(i0, i1, block):
            nonlocal nc, failed
            try:
                if nc is None:  # the layout from the first block to arrive, 0 rows long
                    import netCDF4

                    empty = block.isel({first: slice(0, 0)})
                    empty.to_netcdf(tmp, engine="netcdf4", format="NETCDF4",
                                    unlimited_dims=[first],  # compressed as `sweep.save`
                                    encoding=io.netcdf_encoding(empty, sizes=dict(
                                        zip(grid.dims, grid.shape))))
                    nc = netCDF4.Dataset(tmp, "a")
                for name, variable in block.variables.items():
                    if variable.dims[:1] == (first,):
                        nc[name][i0:i1] = variable.values
            except (OSError, RuntimeError) as exc:  # a full disk: netCDF4's "HDF error"
                failed = True
                raise io.write_error(exc, path, tmp, needed) from None
            for code, k in status_counts(block.status.values).items():
                counts[code] = counts.get(code, 0) + k
            bar.update(block.status.size)

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
        try:
            nc.close()
            nc = None
            os.chmod(tmp, 0o666 & ~_umask())
            os.replace(tmp, path)
        except (OSError, RuntimeError) as exc:
            failed = True
            raise io.write_error(exc, path, tmp, needed) from None
    finally:
        closing.close()
        if futures:
            client.cancel([f for f, _, _ in futures.values()])
        io._discard(tmp)  # truncated first: a failed close below can then flush
        if nc is not None:
            try:
                nc.close()
            except (OSError, RuntimeError):  # the write failed already: that error stands
                pass
        if failed:
            io.release_failed_writer()
    failures = failure_summary(counts, grid.size)
    if failures:
        warnings.warn(failures, RuntimeWarning, stacklevel=2)
    return path


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask
