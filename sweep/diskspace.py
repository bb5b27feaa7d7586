"""Output sizes and free space, before any compute: the dataset a run would return
(`layout`, without computing it), an upper bound of its file (`estimate_size`) and the
refusal of a run whose output or checkpoint may not fit (`check_space`).

It sits above the engine (it validates a run as `sweep.run` does) and below the
command line and `sweep.distributed`, which call it before computing.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import xarray as xr

from . import engine
from .io import _size, file_size_bound, to_dataset

__all__ = ["check_space", "estimate_size", "layout"]


def layout(scene, grid, **run_kwargs) -> xr.Dataset:
    """The dataset ``sweep.run(scene, grid, **run_kwargs)`` returns, without computing
    it: the same variables, dimensions, dtypes, coordinates and attributes, every
    per-trajectory value a read-only broadcast zero (no memory, whatever the grid).

    Built by the same `to_dataset` (and the engine's additions: step statistics of an
    adaptive method, the attractor catalogue's attributes) from zero-stride arrays of
    the shapes the kernel writes (`sweep.execution.local.allocate`).

    Parameters
    ----------
    scene, grid, **run_kwargs
        As for `sweep.run` (validated the same way).

    Returns
    -------
    xarray.Dataset
    """
    settings, spec, _ = engine.prepare(scene, grid, **run_kwargs)
    return _layout(scene, grid, settings, spec, run_kwargs.get("attractors"))


def _layout(scene, grid, settings, spec, attractors) -> xr.Dataset:
    """`layout` of a run whose arguments `sweep.engine.prepare` has checked."""
    from .execution.local import allocate
    from .kernels import KernelSpec

    rows = allocate(spec, settings, 0)  # the kernel's arrays, 0 trajectories long
    full = {name: np.broadcast_to(np.zeros((), array.dtype), (grid.size,) + array.shape[1:])
            for name, array in rows.items()}
    if not isinstance(spec, KernelSpec):  # a system's: sweep.engine_systems
        from .engine_systems import system_dataset

        return system_dataset(scene, grid, settings, spec, full)
    ds = to_dataset(scene=scene, grid=grid, settings=settings, spec=spec, out=full["out"],
                    status=full["status"], saved=full.get("saved"))
    ds.attrs.update(engine._catalogue_attrs(attractors))
    if settings.adaptive:
        engine._add_step_statistics(ds, grid, settings, full["stats"])
    return ds


def estimate_size(scene, grid, **run_kwargs) -> int:
    """An upper bound, in bytes, of the netCDF file `save` writes for the dataset of
    ``sweep.run(scene, grid, **run_kwargs)``, found before (and without) any compute:
    `file_size_bound` of its `layout`. The uncompressed size of the data variables and
    coordinates plus a margin for the file's structure: a safe bound, since `save`
    compresses (the file is usually 1.3-2x smaller, often much more).

    Parameters
    ----------
    scene, grid, **run_kwargs
        As for `sweep.run` (validated the same way: its errors are raised here).

    Returns
    -------
    int
    """
    return file_size_bound(layout(scene, grid, **run_kwargs))


def check_space(path, scene, grid, **run_kwargs) -> int:
    """Refuse, before any compute, a run whose output file (and checkpoint) may not fit
    in the free space of its file system (`shutil.disk_usage`).

    The output file takes at most `estimate_size`; a checkpoint (``checkpoint=`` in
    ``run_kwargs``) at most `sweep.execution.checkpoint.size_bound`, less the chunk
    files already in it. The checkpoint stays until the output file is written, so
    on one file system both must fit.

    The output file's bound is its uncompressed size: the file is compressed, and
    usually 1.6-2.7x smaller, but how much smaller is known only once the values
    exist. So a run whose compressed file would just fit can be refused; ``sweep run
    --no-space-check`` and ``run_to_netcdf(..., check_space=False)`` skip this check
    (a write that then fails leaves no partial file, and a checkpoint keeps its
    chunks).

    Parameters
    ----------
    path : str or Path
        The output file (its folder exists: `check_output_path`).
    scene, grid, **run_kwargs
        As for `sweep.run`.

    Returns
    -------
    int
        `estimate_size` of the output file.

    Raises
    ------
    ValueError
        One line naming the sizes, the folder and its free space.
    """
    from .execution import checkpoint as _checkpoint

    path = Path(path)
    settings, spec, chunk_size = engine.prepare(scene, grid, **run_kwargs)
    output = file_size_bound(_layout(scene, grid, settings, spec,
                                     run_kwargs.get("attractors")))
    folder = path.parent if str(path.parent) else Path(".")
    needs = {_device(folder): [folder, output, 0]}
    checkpoint = run_kwargs.get("checkpoint")
    if checkpoint is not None:
        checkpoint = Path(checkpoint)
        where = checkpoint if checkpoint.is_dir() else (
            checkpoint.parent if str(checkpoint.parent) else Path("."))
        if where.is_dir():  # else sweep.run refuses the folder itself, naming it
            chunks = max(0, _checkpoint.size_bound(spec, settings, grid.size, chunk_size)
                         - _checkpoint.stored_bytes(checkpoint))
            needs.setdefault(_device(where), [where, 0, 0])[2] += chunks
    for where, file_bytes, chunk_bytes in needs.values():
        try:
            free = shutil.disk_usage(where).free
        except OSError:  # a file system that does not say: the write itself will tell
            continue
        if file_bytes + chunk_bytes <= free:
            continue
        parts = []
        if file_bytes:
            parts.append(f"the output file {str(path)!r} up to {_size(file_bytes)} (its "
                         "uncompressed size: sweep compresses with zlib, so it is usually "
                         "smaller, but that is the only safe bound before computing)")
        if chunk_bytes:
            parts.append(f"the checkpoint {str(checkpoint)!r} up to {_size(chunk_bytes)} "
                         "(kept until the output file is written)")
        raise ValueError(f"not enough free disk space: {' and '.join(parts)}, but "
                         f"{str(where)!r} has {_size(free)} free; accepted: a folder with "
                         f"at least {_size(file_bytes + chunk_bytes)} free, a smaller "
                         "run (fewer trajectories or observables, a larger save_every), or, "
                         "if the compressed file will fit, no check (sweep run "
                         "--no-space-check; run_to_netcdf(..., check_space=False))")
    return output


def _device(folder: Path):
    """The file system ``folder`` is on (its ``st_dev``; the folder itself if unknown)."""
    try:
        return os.stat(folder).st_dev
    except OSError:
        return str(folder)
