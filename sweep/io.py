"""Dataset construction (coordinates, CF attributes, provenance) and atomic save/load."""

from __future__ import annotations

import datetime
import errno
import gc
import json
import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from . import _config
from ._version import __version__
from .catalogue_drives import pendulum_drives
from .catalogue_scene import ATTRIBUTE as SCENE_ATTRIBUTE
from .catalogue_scene import from_attributes as scene_from_attributes
from .catalogue_scene import pendulum_values
from .grid import Grid, Points
from .kernels import Status, vectors
from .observables import OBSERVABLES, variable_attributes
from .physics import EFFECTS, Scene, parameter_info
from .strobe_phase import from_attributes, other_drives_attribute

__all__ = ["device_attributes", "origin_attributes", "run_attributes", "to_dataset",
           "status_variable", "save", "load", "scene_from", "grid_from",
           "run_arguments", "netcdf_encoding",
           "file_size_bound"]

#: zlib level of the variables `save` writes (with the byte shuffle filter), chosen by
#: measurement (``python benchmarks/compression.py``): level 1 gets nearly all of the
#: size reduction of higher levels at a fraction of their write time.
COMPLEVEL = 1

#: Target size of one netCDF/HDF5 chunk of a variable, in bytes (uncompressed): big
#: enough for compression and few chunk-index entries, small enough that reading one
#: map row or one point does not decompress much more than it needs.
CHUNK_BYTES = 1 << 20

#: Bytes `file_size_bound` allows for a file's structure besides its variables: the
#: HDF5 superblock, the root group with the global attributes (counted on top), and the
#: file system's rounding of the last block. Measured: 10-12 KiB for a file of one
#: variable (netCDF4 1.7, HDF5 1.14).
HEADER_BYTES = 32 * 1024

#: Bytes `file_size_bound` allows per variable (object header, dimension-scale links,
#: fill value; its attributes are counted on top). Measured: 2.5-3.5 KiB.
VARIABLE_BYTES = 8 * 1024

#: Bytes `file_size_bound` allows per compressed chunk for its entry in the variable's
#: chunk index (HDF5 B-tree nodes hold 64 entries of ~50 bytes); zlib's worst-case
#: expansion of incompressible data is counted on top (`_deflate_bound`).
CHUNK_INDEX_BYTES = 128

# Temporary files of saves in progress (`save`, `sweep.distributed.run_to_netcdf`):
# `discard_partial_files` deletes them for a process that ends without unwinding.
_PARTIAL: set[str] = set()


def to_dataset(*, scene, grid, settings, spec, out, status, saved=None) -> xr.Dataset:
    """Wrap flat kernel outputs into a labelled, self-describing Dataset.

    Parameters
    ----------
    scene : Scene
    grid : Grid or Points
    settings : sweep.engine.RunSettings
    spec : sweep.kernels.KernelSpec
    out : ndarray, shape (grid.size, n_columns), float64
        Observables in `sweep.kernels.n_columns` order.
    status : ndarray, shape (grid.size,), int8
    saved : ndarray, shape (grid.size, 2, n_saved), float64, optional
        Sampled theta [rad] and omega [rad/s].

    Returns
    -------
    xarray.Dataset
    """
    dims = grid.dims
    info = parameter_info()
    coords = {
        name: xr.Variable(dim, values, {"units": info[name][0], "long_name": info[name][1]})
        for name, dim, values in grid.coordinates()
    }
    data_vars = {}
    col = 0
    for observable in (OBSERVABLES[name] for name in spec.observe):
        width = observable.n_samples(spec)
        for name, units, long_name in observable.variables:
            attrs = variable_attributes(name, units, long_name)
            if observable.sample_dim is None:
                data_vars[name] = xr.Variable(dims, grid.unflatten(out[:, col]), attrs)
            else:
                data_vars[name] = xr.Variable(dims + (observable.sample_dim,),
                                              grid.unflatten(out[:, col:col + width]), attrs)
                coords[observable.sample_dim] = xr.Variable(
                    observable.sample_dim, np.arange(1 - width, 1),
                    {"units": "1", "long_name": "forcing periods before the last sample"})
            col += width
    if getattr(spec, "known_cells", False):  # the column after the observables
        data_vars["stopped_known"] = xr.Variable(
            dims, grid.unflatten(out[:, col]),
            {"units": "1", "long_name": "1 where the trajectory stopped on known cells "
                                        "(sweep.run's known_cells; its attractor is "
                                        "theirs), else 0"})
    data_vars["status"] = status_variable(grid, status)
    if saved is not None:
        n_saved = saved.shape[2]
        stride = settings.save_every
        coords["time"] = xr.Variable(
            "time", settings.t0 + np.arange(n_saved) * stride * settings.dt,
            {"units": "s", "long_name": "time (t0 + n dt at saved steps n)"},
        )
        for k, (name, units, long_name) in enumerate(
            (("theta", "rad", "angle, unwrapped"), ("omega", "rad s-1", "angular velocity"))
        ):
            data_vars[name] = xr.Variable(dims + ("time",),
                                          grid.unflatten(saved[:, k, :]),
                                          {"units": units, "long_name": long_name})

    simulated = [effect.name for effect in spec.effects]
    present = {axis for effect in spec.effects for axis in effect.axes}
    fixed = {k: v for k, v in scene.parameters().items()
             if k not in grid.axes and (k in ("length", "gravity") or k in present)}
    attrs = {
        **origin_attributes("pendulum parameter sweep"),
        "equation": equation(),
        "model": scene.model,
        "effects": " ".join(simulated) if simulated else "none",
        **{name: float(value) for name, value in fixed.items()},
        "scene": json.dumps(scene.to_dict(), sort_keys=True),
        **grid.provenance(),  # grid_axes (a Grid) or point_axes (Points): grid_from
        **run_attributes(settings, spec),
    }
    if "strobe" in spec.observe:  # and the scene an attractor catalogue of it is of
        attrs["strobe_samples"] = spec.strobe_samples
        attrs[SCENE_ATTRIBUTE] = json.dumps(pendulum_values(scene, grid), sort_keys=True)
        # the other drives whose phases a catalogue of it records
        attrs.update(other_drives_attribute(pendulum_drives(scene, grid)))
    attrs.update(device_attributes(spec))
    if spec.dtype != "float64":  # its working precision, when not the default
        attrs["dtype"] = spec.dtype
    return xr.Dataset(data_vars, coords, attrs)


def origin_attributes(title: str) -> dict:
    """A dataset's first attributes: CF convention, ``title``, and which sweep made it
    when."""
    return {
        "Conventions": "CF-1.10",
        "title": title,
        "source": f"sweep {__version__}",
        "history": f"{datetime.datetime.now(datetime.UTC).isoformat(timespec='seconds')}"
                   f" created by sweep {__version__}",
        "sweep_version": __version__,
    }


def run_attributes(settings, spec) -> dict:
    """The time settings and observables of a run (`sweep.engine.RunSettings` and its
    kernel spec's ``observe``): what, with the physics and the grid, reproduces it."""
    attrs = {
        "method": settings.method,
        "t0": settings.t0,
        "t_end": settings.t_end,
        "dt": settings.dt,
        "t_transient": settings.t_transient,
        "n_steps": settings.n_steps,
        "observe": " ".join(spec.observe),
    }
    if settings.save_every is not None:
        attrs["save_every"] = settings.save_every
    return attrs


def device_attributes(spec) -> dict:
    """Where the run's kernel ran: ``device`` when not the CPU, else the SIMD width the
    CPU kernels were compiled for (``vector_width``, `sweep.kernels.vectors`)."""
    if spec.device != "cpu":
        return {"device": spec.device}
    return {"vector_width": vectors.describe(_config.vector_width())}


def status_variable(grid, status) -> xr.Variable:
    """The ``status`` variable of a run over ``grid``: the flat `sweep.kernels.Status`
    codes in the grid's shape, with their CF flags (``flag_values``, ``flag_meanings``)
    and what each means."""
    codes = np.array([s.value for s in Status], dtype=np.int8)
    return xr.Variable(grid.dims, grid.unflatten(status), {
        "long_name": "per-trajectory integration status",
        "flag_values": codes,
        "flag_meanings": " ".join(s.name.lower() for s in Status),
        "comment": "; ".join(f"{s.name.lower()}: {s.message}" for s in Status),
    })


def warm_up() -> None:
    """Pay xarray's one-time costs of a process now: its first Dataset imports Dask
    where Dask is installed (0.29 s on a 2-core AMD EPYC), whatever the data."""
    xr.Dataset({"warm_up": ((), 0.0)})


def equation() -> str:
    """The equation of motion with the term of every registered effect, as text."""
    terms = " ".join(cls.declaration.equation for cls in EFFECTS.values())
    return f"theta'' = - (g/L) f(theta) {terms}".rstrip()


def scene_from(ds: xr.Dataset) -> Scene:
    """Rebuild the `Scene` a dataset was made with (from its ``scene`` attribute)."""
    return Scene.from_dict(json.loads(ds.attrs["scene"]))


def grid_from(ds: xr.Dataset):
    """Rebuild the `sweep.Grid` or `sweep.Points` a dataset was made with, from its
    coordinates and its ``grid_axes`` or ``point_axes`` attribute.

    Raises
    ------
    ValueError
        If the dataset has neither attribute (not made by `sweep.run`).
    """
    if "point_axes" in ds.attrs:
        return Points(**{name: ds[name].values for name in ds.attrs["point_axes"].split()})
    if "grid_axes" in ds.attrs:
        return Grid(**{name: ds[name].values for name in ds.attrs["grid_axes"].split()})
    raise ValueError("the dataset has neither a 'grid_axes' nor a 'point_axes' attribute; "
                     "accepted: a dataset made by sweep.run (or read by sweep.load)")


def run_arguments(ds: xr.Dataset) -> dict:
    """The keyword arguments of `sweep.run` that made ``ds`` (besides scene and grid).

    With `scene_from` and `grid_from` (the dataset's coordinates) this reproduces the
    run, of a `Grid` or of `Points`::

        sweep.run(sweep.io.scene_from(ds), sweep.io.grid_from(ds),
                  **sweep.io.run_arguments(ds))
    """
    a = ds.attrs
    kwargs = {"t0": float(a["t0"]), "t_end": float(a["t_end"]), "dt": float(a["dt"]),
              "t_transient": float(a["t_transient"]), "method": str(a["method"]),
              "observe": tuple(str(a["observe"]).split())}
    if "save_every" in a:
        kwargs["save_every"] = int(a["save_every"])
    if "strobe_samples" in a:
        kwargs["strobe_samples"] = int(a["strobe_samples"])
    if "dtype" in a:
        kwargs["dtype"] = str(a["dtype"])
    for tolerance in ("rtol", "atol"):  # adaptive methods
        if tolerance in a:
            kwargs[tolerance] = float(a[tolerance])
    if "attractors_theta" in a:  # the attractor catalogue (sweep.run's attractors=)
        samples = int(a["attractors_samples"])
        # a system's rings have a row per coordinate (sweep.system_attractors)
        shape = (-1, int(a["attractors_coordinates"]), samples) \
            if "attractors_coordinates" in a else (-1, samples)
        kwargs["attractors"] = {
            name: np.atleast_1d(np.asarray(a[f"attractors_{name}"], dtype=np.float64))
            .reshape(shape) for name in ("theta", "omega")}
        kwargs["attractors"]["period"] = np.atleast_1d(
            np.asarray(a["attractors_period"], dtype=np.int64))
        kwargs["attractors"].update(from_attributes(a))  # its drive phase, if any
        kwargs["attractors"].update(scene_from_attributes(a))  # its scene, if any
    return kwargs


def check_output_path(path) -> Path:
    """Return ``path`` as a Path if its folder exists and is writable, else raise.

    Called before any compute so that a run never ends in an unwritable file. Writable
    means a file can be made there: `os.access` first, then a file created and removed
    at once, since ``os.access`` answers yes to root whatever the mode, and on a
    read-only file system or one such as /proc, where nothing can be created.

    Raises
    ------
    ValueError
        One line naming the path and its folder: a folder path, a folder that does not
        exist or is a file, a folder that is not writable.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise ValueError(f"output path {str(path)!r} is a folder; accepted: a file path")
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"output path {str(path)!r}: {str(folder)!r} is a file, not a "
                         "folder; accepted: a path in an existing folder")
    if not folder.is_dir():
        raise ValueError(f"output path {str(path)!r}: folder {str(folder)!r} does not exist; "
                         "accepted: a path in an existing folder")
    reason = None if os.access(folder, os.W_OK) else "permission denied"
    if reason is None:
        try:
            _config.probe_writable(folder)
        except OSError as exc:
            reason = exc.strerror or type(exc).__name__
    if reason is not None:
        raise ValueError(f"output path {str(path)!r}: folder {str(folder)!r} is not "
                         f"writable (creating a file there fails: {reason}); accepted: a "
                         "path in a folder this user can write")
    return path


def _chunk_shape(shape: tuple[int, ...], itemsize: int) -> tuple[int, ...]:
    """A chunk of at most `CHUNK_BYTES` bytes: the whole variable, with its largest
    dimension halved (rounding up) until it fits. Leading dimensions are halved first
    on ties, so a chunk keeps whole rows of the last, fastest-varying axis as long as
    it can."""
    chunk = [max(1, n) for n in shape]
    while math.prod(chunk) * itemsize > CHUNK_BYTES and max(chunk) > 1:
        largest = chunk.index(max(chunk))
        chunk[largest] = (chunk[largest] + 1) // 2
    return tuple(chunk)


def netcdf_encoding(ds: xr.Dataset, *, complevel: int = COMPLEVEL,
                    sizes: dict[str, int] | None = None) -> dict[str, dict]:
    """netCDF4 encoding that compresses and chunks every data variable of ``ds``.

    zlib (deflate) with the byte shuffle filter: every netCDF4/HDF5 reader decodes it
    (``ncdump``, h5netcdf/h5py, Panoply), which zstd (a filter plugin) is not. Chunks
    are about `CHUNK_BYTES` (see `_chunk_shape`). Coordinates, scalars and strings are
    left as they are (small or not compressible by netCDF).

    Parameters
    ----------
    ds : xarray.Dataset
    complevel : int, default `COMPLEVEL`
        zlib level 1-9; 0 writes the variables uncompressed (contiguous).
    sizes : dict, optional
        Dimension sizes to chunk for instead of ``ds``'s (for a file written in
        blocks, whose first dimension grows).

    Returns
    -------
    dict
        ``{variable: {"zlib", "complevel", "shuffle", "chunksizes"}}`` for
        ``Dataset.to_netcdf(encoding=...)``.
    """
    sizes = {**ds.sizes, **(sizes or {})}
    encoding = {}
    if not complevel:
        return encoding
    for name, variable in ds.data_vars.items():
        if variable.ndim == 0 or variable.dtype.kind not in "biuf":
            continue
        shape = tuple(sizes[dim] for dim in variable.dims)
        encoding[name] = {"zlib": True, "complevel": int(complevel), "shuffle": True,
                          "chunksizes": _chunk_shape(shape, variable.dtype.itemsize)}
    return encoding


def save(ds: xr.Dataset, path) -> Path:
    """Write ``ds`` to netCDF4 atomically: a temporary file in the same folder, then
    an atomic rename. An interrupted or failed save leaves no partial file, and any
    previous file at ``path`` intact.

    Data variables are compressed (zlib level `COMPLEVEL`, byte shuffle) in chunks of
    about `CHUNK_BYTES` (`netcdf_encoding`); values read back bit-identical.

    Parameters
    ----------
    ds : xarray.Dataset
    path : str or Path

    Returns
    -------
    Path

    Raises
    ------
    OSError
        The file could not be written (a full disk, a quota, an I/O error): one line
        naming the file and the cause, with its ``errno`` where known. netCDF4 reports
        a full disk as ``RuntimeError: NetCDF: HDF error``; that is given as ENOSPC
        when the folder's free space is less than the file may still need
        (`write_error`).
    """
    path = check_output_path(path)
    tmp = _temporary(path)
    error = None
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4",
                     encoding=netcdf_encoding(ds))
        os.replace(tmp, path)
    except (OSError, RuntimeError) as exc:
        error = write_error(exc, path, tmp, file_size_bound(ds))
    except BaseException:
        _discard(tmp)
        raise
    if error is not None:
        _discard(tmp)
        release_failed_writer()
        raise error
    _PARTIAL.discard(tmp)
    return path


def release_failed_writer() -> None:
    """Close the files of a failed netCDF4 write, once its partial file is discarded.

    When a write fails (a full disk), netCDF4's close fails too and the file stays open
    in HDF5, held by a reference cycle of the error's traceback, and with it the disk
    space of the (deleted) file. `_discard` truncated the file, so a second close can
    flush; collecting the cycle makes netCDF4 close it.
    """
    gc.collect()


def _temporary(path: Path) -> str:
    """A new empty file next to ``path`` with the usual mode, registered in `_PARTIAL`."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part")
    os.close(fd)
    _PARTIAL.add(tmp)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a saved file gets the usual mode
    return tmp


def _discard(tmp: str) -> None:
    """Delete the temporary file ``tmp`` if it is there: truncated first, which frees
    its space at once even if a failed writer still holds it open."""
    _PARTIAL.discard(tmp)
    try:
        os.truncate(tmp, 0)
    except OSError:
        pass
    try:
        os.unlink(tmp)
    except FileNotFoundError:
        pass


def discard_partial_files() -> None:
    """Delete the temporary files of the saves this process has in progress: for a
    process about to end without unwinding (``os._exit``), so that it leaves no
    half-written file behind."""
    for tmp in list(_PARTIAL):
        try:
            _discard(tmp)
        except OSError:
            pass


def write_error(exc: BaseException, path, tmp=None, needed: int | None = None) -> OSError:
    """The one-line `OSError` for a failed write of the file ``path``.

    Parameters
    ----------
    exc : OSError or RuntimeError
        What the writer raised. netCDF4 reports a full disk (and any other HDF5 failure)
        as ``RuntimeError: NetCDF: HDF error``, with no errno.
    path : str or Path
        The file being written (named in the message).
    tmp : str, optional
        The partial file, still in place: its size counts as written.
    needed : int, optional
        An upper bound of the whole file's size (`file_size_bound`). A RuntimeError
        with less free space in the folder than the file may still need is reported
        as ENOSPC (the likely cause; the message says how much was free).

    Returns
    -------
    OSError
        ``errno`` set where known; its text names the file, the cause and that
        nothing was written.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    code = exc.errno if isinstance(exc, OSError) else None
    detail = (exc.strerror if isinstance(exc, OSError) and exc.strerror else
              " ".join(str(exc).split()) or type(exc).__name__)
    if code is None and needed is not None:
        try:
            free = shutil.disk_usage(folder).free
            written = os.path.getsize(tmp) if tmp is not None and os.path.exists(tmp) else 0
        except OSError:
            free = written = None
        if free is not None and free < needed - written:
            code = errno.ENOSPC
            detail = (f"{os.strerror(code)} (netCDF4 reported {detail!r} with "
                      f"{_size(free)} free in {str(folder)!r}, less than the "
                      f"{_size(needed - written)} the file could still need)")
    text = f"cannot write {str(path)!r}: {detail}; nothing was written"
    return OSError(code, text) if code is not None else OSError(text)


def _size(n: float) -> str:
    """``1536`` -> ``"1.5 KiB"``."""
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TiB"  # pragma: no cover


# ------------------------------------------------------------------ sizes and space
def _deflate_bound(n: int) -> int:
    """Most bytes zlib makes of ``n`` bytes (zlib's ``compressBound``): incompressible
    data grows by its block headers."""
    return n + (n >> 12) + (n >> 14) + (n >> 25) + 13


def _attribute_bytes(attrs: dict) -> int:
    total = 0
    for name, value in attrs.items():
        value = np.asarray(value)
        total += len(str(name)) + (len(str(value).encode()) if value.dtype.kind in "OSU"
                                   else value.nbytes)
    return total


def file_size_bound(ds: xr.Dataset) -> int:
    """An upper bound, in bytes, of the file `save` writes for ``ds``.

    Every variable's values uncompressed (compressed variables as their chunks store
    them: whole chunks at the edges, zlib's worst case for incompressible data, their
    chunk index), every attribute, and a margin for the file's structure
    (`HEADER_BYTES`, `VARIABLE_BYTES` per variable). `save` compresses (zlib with the
    byte shuffle), so the file is usually smaller -- 1.3-2x for float outputs, much
    more for a map of few values -- but only the uncompressed size bounds it before
    the values exist. For files of more than a few MiB the bound is within 1.05x of
    the same dataset written uncompressed.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of `sweep.run`, or its `sweep.diskspace.layout`.

    Returns
    -------
    int
    """
    encoding = netcdf_encoding(ds)
    total = HEADER_BYTES + _attribute_bytes(ds.attrs)
    for name, variable in ds.variables.items():
        total += VARIABLE_BYTES + _attribute_bytes(variable.attrs)
        itemsize = variable.dtype.itemsize if variable.dtype.kind in "biuf" else 8
        if name not in encoding:
            total += math.prod(variable.shape) * itemsize
            if variable.dtype.kind not in "biuf":  # strings: their text
                total += sum(len(str(v).encode()) for v in np.ravel(variable.values))
            continue
        chunks = encoding[name]["chunksizes"]
        count = math.prod(-(-n // c) for n, c in zip(variable.shape, chunks))
        chunk_bytes = math.prod(chunks) * itemsize
        total += count * (_deflate_bound(chunk_bytes) + CHUNK_INDEX_BYTES)
    return total


def load(path) -> xr.Dataset:
    """Read a dataset written by `save` fully into memory (the file is closed).

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such file: {str(path)!r}")
    return xr.load_dataset(path, engine="netcdf4")
