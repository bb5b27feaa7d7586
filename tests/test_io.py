"""netCDF round trips, other readers, and atomic writes."""

import os
import shutil
import stat
import subprocess

import numpy as np
import pytest
import xarray as xr

import sweep


@pytest.fixture(scope="module")
def dataset():
    scene = sweep.Scene(effects=(sweep.Damping(0.3), sweep.Forcing(1.0, 0.8, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 6), omega0=[-1.0, 0.0, 1.0],
                      forcing_amplitude=[0.5, 1.5])
    return sweep.run(scene, grid, t_end=4.0, dt=0.01, t_transient=1.0,
                     observe=("final", "winding", "theta_max", "amplitude", "tension",
                              "energy"), save_every=100)


def test_netcdf_round_trip_is_identical(dataset, tmp_path):
    path = sweep.save(dataset, tmp_path / "run.nc")
    loaded = sweep.load(path)
    xr.testing.assert_identical(loaded, dataset)
    assert loaded.status.dtype == np.int8


def test_h5netcdf_reads_the_same_values(dataset, tmp_path):
    path = sweep.save(dataset, tmp_path / "run.nc")
    with xr.open_dataset(path, engine="h5netcdf") as other:
        xr.testing.assert_identical(other.load(), dataset)


@pytest.mark.skipif(shutil.which("ncdump") is None,
                    reason="ncdump (Debian netcdf-bin) not installed; .ci/run installs it")
def test_ncdump_reads_the_file(dataset, tmp_path):
    path = sweep.save(dataset, tmp_path / "run.nc")
    header = subprocess.run(["ncdump", "-h", str(path)], capture_output=True, text=True,
                            check=True).stdout
    assert "double theta_final(theta0, omega0, forcing_amplitude)" in header
    assert 'status:flag_meanings = "ok nonfinite step_underflow angle_out_of_range"' in header
    assert ':Conventions = "CF-1.10"' in header


def test_interrupted_save_leaves_previous_file_intact(dataset, tmp_path, monkeypatch):
    path = sweep.save(dataset, tmp_path / "run.nc")
    before = path.read_bytes()

    def crash(self, target, *args, **kwargs):
        with open(target, "wb") as handle:  # a half-written file...
            handle.write(b"CDF\x01partial")
        raise KeyboardInterrupt  # ...then the user presses Ctrl-C

    monkeypatch.setattr(xr.Dataset, "to_netcdf", crash)
    with pytest.raises(KeyboardInterrupt):
        sweep.save(dataset.isel(theta0=[0]), path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]  # no temp file left


def test_save_refuses_missing_folder_and_load_missing_file(dataset, tmp_path):
    with pytest.raises(ValueError, match=r"folder .*nowhere.* does not exist"):
        sweep.save(dataset, tmp_path / "nowhere" / "run.nc")
    with pytest.raises(ValueError, match=r"is a folder; accepted: a file path"):
        sweep.save(dataset, tmp_path)
    with pytest.raises(FileNotFoundError, match=r"no such file"):
        sweep.load(tmp_path / "absent.nc")


def test_saved_file_gets_the_usual_permissions(dataset, tmp_path):
    umask = os.umask(0o022)
    try:
        path = sweep.save(dataset, tmp_path / "run.nc")
    finally:
        os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_adaptive_run_reproduces_from_its_attributes():
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.5, 2.0]), t_end=3.0, dt=0.1,
                   method="dopri5", rtol=1e-9, atol=1e-12, observe=("final",))
    kwargs = sweep.io.run_arguments(ds)
    assert kwargs["rtol"] == 1e-9 and kwargs["atol"] == 1e-12
    again = sweep.run(sweep.io.scene_from(ds), sweep.Grid(theta0=ds.theta0.values), **kwargs)
    assert again.drop_attrs().identical(ds.drop_attrs())
