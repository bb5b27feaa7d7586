"""Run chunks of a sweep in this process: what a chunk needs (`RunContext`), the arrays
a kernel writes, and the one call of the kernel contract (`sweep.kernels`), shared by
local runs and Dask workers."""

from __future__ import annotations

import numpy as np

from ..kernels import build, n_columns
from ..kernels.network import NetworkSpec, network_outputs
from ..kernels.system import SystemSpec
from ..kernels.system import n_outputs as system_outputs

__all__ = ["RunContext", "allocate", "integrate", "run_chunks"]


class RunContext:
    """What every chunk needs: scene, grid, kernel spec and time settings, and the
    kernel's arguments after ``saved`` (``stats``) (``known``: the ``attractor``
    observable's catalogue, `sweep.kernels.snippets.catalogue_argument`, then for a
    spec with ``known_cells`` `sweep._known.known_arguments`; a system's catalogue,
    `sweep.system_attractors.catalogue_arguments`; a swing network's arrays,
    `sweep.kernels.network.network_arguments`, on the CPU; else ``()``).

    A plain picklable object (a Dask task carries it); `table` gives a chunk's
    parameter rows.
    """

    def __init__(self, scene, grid, spec, settings, known: tuple = ()) -> None:
        self.scene = scene
        self.grid = grid
        self.spec = spec
        self.settings = settings
        self.known = tuple(known)

    def table(self, start: int, stop: int):
        """The rows ``start:stop`` for the kernel: a table on the CPU, described
        (`sweep.grid.GridRows`) for the GPU, whose threads build their own rows."""
        if self.spec.device == "cuda":
            return self.grid.rows(self.scene, start, stop)
        return self.grid.table(self.scene, start, stop)


def allocate(spec, settings, n: int) -> dict[str, np.ndarray]:
    """The per-trajectory arrays a kernel writes for ``n`` trajectories: ``out``,
    ``status``, and ``saved`` (with ``save_every``: the single pendulum's angle and
    velocity; a system's every coordinate, then every velocity; a network's every
    node's angles, then velocities) and ``stats`` (adaptive methods)."""
    if isinstance(spec, NetworkSpec):
        width, n_saved_rows = network_outputs(spec), 2 * spec.n_nodes
    elif isinstance(spec, SystemSpec):
        width, n_saved_rows = system_outputs(spec), 2 * len(spec.system.coordinates)
    else:
        width, n_saved_rows = n_columns(spec), 2
    arrays = {"out": np.empty((n, width), dtype=np.float64),
              "status": np.empty(n, dtype=np.int8)}
    if settings.save_every is not None:
        n_saved = settings.n_steps // settings.save_every + 1
        arrays["saved"] = np.full((n, n_saved_rows, n_saved), np.nan)
    if settings.adaptive:
        arrays["stats"] = np.zeros((n, 2), dtype=np.int64)
    return arrays


def integrate(kernel, table, settings, arrays: dict[str, np.ndarray], known: tuple = ()) -> None:
    """Run ``kernel`` on the parameter rows ``table``, writing into ``arrays`` (same
    rows): the one call of the kernel contract, shared by local runs and workers
    (``known``: the arguments the kernel takes after ``saved``, or ``stats``:
    `RunContext`)."""
    if settings.adaptive:
        kernel(table, settings.t0, settings.t_end, settings.dt, settings.t_transient,
               settings.rtol, settings.atol, arrays["out"], arrays["status"],
               arrays["stats"], *known)
    else:
        saved = arrays.get("saved")
        kernel(table, settings.t0, settings.dt, settings.n_steps, settings.n_transient,
               settings.save_every or 1, arrays["out"], arrays["status"],
               saved if saved is not None else np.empty((0, 2, 0)), *known)


def run_chunks(context: RunContext, chunks, arrays: dict[str, np.ndarray], done) -> None:
    """Integrate ``chunks`` (``(start, stop)`` pairs) in this process, in order, writing
    each into ``arrays[name][start:stop]`` and then calling ``done(start, stop)``."""
    if not chunks:
        return
    kernel = build(context.spec)
    for start, stop in chunks:
        integrate(kernel, context.table(start, stop), context.settings,
                  {name: array[start:stop] for name, array in arrays.items()}, context.known)
        done(start, stop)
