"""Run chunks of a sweep in this process: the arrays a kernel writes, and the one call
of the kernel contract (`sweep.kernels`), shared by local runs and Dask workers."""

from __future__ import annotations

import numpy as np

from ..kernels import n_columns

__all__ = ["allocate", "integrate"]


def allocate(spec, settings, n: int) -> dict[str, np.ndarray]:
    """The per-trajectory arrays a kernel writes for ``n`` trajectories: ``out``,
    ``status``, and ``saved`` (with ``save_every``) and ``stats`` (adaptive methods)."""
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
