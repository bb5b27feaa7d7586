"""Running the chunks of a sweep: in this process or as Dask tasks (one call,
`execute`, two back ends), with per-chunk checkpoints and a progress bar. Reads
`sweep.kernels` and `sweep.grid`; imports nothing above."""

from __future__ import annotations

from .local import RunContext

__all__ = ["RunContext", "execute"]


def execute(context: RunContext, chunks, arrays, done, *, client=None, retries: int = 2):
    """Integrate ``chunks`` (``(start, stop)`` pairs of flat trajectory indices) of the run
    ``context`` into ``arrays`` (the run's per-trajectory arrays, `local.allocate`).

    Parameters
    ----------
    context : RunContext
    chunks : list of (int, int)
    arrays : dict of ndarray
        Each chunk's rows are written into ``arrays[name][start:stop]``.
    done : callable
        ``done(start, stop)`` after each chunk's rows are in place (checkpoint,
        progress); chunks arrive in order locally, as they finish on a cluster.
    client : dask.distributed.Client, optional
        Run each chunk as a task on its cluster (`sweep.execution.dask`); a task that
        raises is retried ``retries`` times.
    """
    if client is None:
        from .local import run_chunks

        run_chunks(context, chunks, arrays, done)
    else:
        from .dask import run_chunks

        run_chunks(client, context, chunks, arrays, done, retries=retries)
