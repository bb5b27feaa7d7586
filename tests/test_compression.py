"""`sweep.save` and `run_to_netcdf` write compressed, chunked variables that read back
bit-identical (netCDF4 and h5netcdf), whatever the dataset went through before."""

import math

import netCDF4
import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import io
from sweep.distributed import run_to_netcdf

SCENE = sweep.Scene(effects=(sweep.Damping(0.3),))
GRID = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 300), omega0=np.linspace(-2.0, 2.0, 500))
# the observables of the damped runs of test_cli, test_resume and test_faults: the
# kernel of run_to_netcdf's (no saving) 150,000 starts is test_faults' full-disk run's
RUN = {"t_end": 1.0, "dt": 0.05, "observe": ("final", "winding", "energy")}


def _bits_equal(a, b):
    assert list(a.data_vars) == list(b.data_vars)
    for name in a.variables:
        assert a[name].values.tobytes() == b[name].values.tobytes(), name


@pytest.fixture(scope="module")
def ds():
    return sweep.run(SCENE, GRID, save_every=10, **RUN)


def _check_compressed(path, names):
    with netCDF4.Dataset(path) as nc:
        for name in names:
            var = nc[name]
            filters = var.filters()
            assert filters["zlib"] and filters["complevel"] == io.COMPLEVEL, name
            assert filters["shuffle"], name
            chunks = var.chunking()
            assert chunks != "contiguous", name
            assert math.prod(chunks) * var.dtype.itemsize <= io.CHUNK_BYTES, name


def test_save_compresses_chunks_and_reads_back_identical(ds, tmp_path):
    path = sweep.save(ds, tmp_path / "a.nc")
    _check_compressed(path, ds.data_vars)
    _bits_equal(sweep.load(path), ds)
    _bits_equal(xr.load_dataset(path, engine="h5netcdf"), ds)  # a second reader
    # smaller than the raw bytes of the data (the theta(t) samples of nearby starts
    # are smooth, status and winding nearly constant)
    assert path.stat().st_size < 0.8 * sum(v.nbytes for v in ds.data_vars.values())


def test_a_loaded_or_sliced_dataset_saves_again(ds, tmp_path):
    first = sweep.load(sweep.save(ds, tmp_path / "a.nc"))  # carries the file's encoding
    part = first.isel(theta0=slice(0, 7), omega0=slice(3, 5))  # smaller than a chunk
    _bits_equal(sweep.load(sweep.save(part, tmp_path / "b.nc")), part)
    _bits_equal(sweep.load(sweep.save(first, tmp_path / "c.nc")), ds)


def test_chunk_shape_halves_the_largest_dimension():
    assert io._chunk_shape((4096, 4096), 8) == (256, 512)  # 1 MiB exactly
    assert io._chunk_shape((3, 5), 8) == (3, 5)  # small: one chunk
    assert io._chunk_shape((0, 5), 8) == (1, 5)  # HDF5 needs chunk sides >= 1
    assert math.prod(io._chunk_shape((10**6,), 1)) <= io.CHUNK_BYTES
    assert io.netcdf_encoding(xr.Dataset({"x": ("a", np.zeros(3))}), complevel=0) == {}


def test_run_to_netcdf_writes_compressed(ds, tmp_path):
    path = run_to_netcdf(tmp_path / "big.nc", SCENE, GRID, rows_per_task=64, **RUN)
    _check_compressed(path, ("theta_final", "omega_final", "winding", "energy_initial",
                             "energy_final", "status"))
    local = sweep.run(SCENE, GRID, **RUN)
    _bits_equal(sweep.load(path).drop_attrs(), local.drop_attrs())
