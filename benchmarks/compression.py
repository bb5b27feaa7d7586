"""Size and write time of `sweep.save` for a big map, uncompressed and compressed.

A damped pendulum (c = 0.3 1/s) over an N x N grid of (theta0 in [-pi, pi] rad,
omega0 in [-10, 10] rad/s), t_end = 10 s, dt = 0.05 s, observing ``final``,
``winding`` and ``theta_max``: five variables (theta_final, omega_final, winding,
theta_max, status) with the structure of a real map. Each encoding writes the same
dataset; every file is read back and compared bit for bit.

    python benchmarks/compression.py                 # 4096 x 4096 (about 1 min of compute)
    python benchmarks/compression.py --size 512      # quick look

Writes ``benchmarks/results/compression.{json,md}`` (with ``--size 4096``).
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

import sweep
from sweep import io

RESULTS = Path(__file__).resolve().parent / "results"


def make_dataset(size: int) -> xr.Dataset:
    scene = sweep.Scene(effects=(sweep.Damping(0.3),))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-10.0, 10.0, size))
    return sweep.run(scene, grid, t_end=10.0, dt=0.05,
                     observe=("final", "winding", "theta_max"), progress=False)


def encodings(ds: xr.Dataset) -> dict[str, dict]:
    """Name -> netCDF4 encoding of every data variable."""
    import netCDF4

    options = {"none (before)": {}}
    for level in (1, 4, 9):
        options[f"zlib {level} + shuffle"] = io.netcdf_encoding(ds, complevel=level)
    options["zlib 1, no shuffle"] = {name: {**enc, "shuffle": False} for name, enc in
                                     io.netcdf_encoding(ds, complevel=1).items()}
    if getattr(netCDF4, "__has_zstandard_support__", False):
        for level in (1, 3):
            options[f"zstd {level} + shuffle (plugin needed to read)"] = {
                name: {"compression": "zstd", "complevel": level, "shuffle": True,
                       "chunksizes": enc["chunksizes"]}
                for name, enc in io.netcdf_encoding(ds).items()}
    return options


def measure(ds: xr.Dataset, folder: Path, repeats: int) -> list[dict]:
    rows = []
    for label, encoding in encodings(ds).items():
        path = folder / "map.nc"
        best = float("inf")
        for _ in range(repeats):
            path.unlink(missing_ok=True)
            start = time.perf_counter()
            ds.to_netcdf(path, engine="netcdf4", format="NETCDF4", encoding=encoding)
            best = min(best, time.perf_counter() - start)
        start = time.perf_counter()
        again = xr.load_dataset(path, engine="netcdf4")
        read = time.perf_counter() - start
        same = all(again[n].values.tobytes() == ds[n].values.tobytes() for n in ds.data_vars)
        rows.append({"encoding": label, "bytes": path.stat().st_size, "write_s": best,
                     "read_s": read, "identical": same})
        path.unlink()
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=4096)
    parser.add_argument("--repeats", type=int, default=2, help="writes per encoding (best)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    ds = make_dataset(args.size)
    compute = time.perf_counter() - start
    with tempfile.TemporaryDirectory(dir=".") as folder:
        rows = measure(ds, Path(folder), args.repeats)
    raw = sum(ds[n].nbytes for n in ds.data_vars)
    lines = [f"{args.size} x {args.size} map, variables {', '.join(ds.data_vars)} "
             f"({raw / 2**20:.0f} MiB in memory; run {compute:.1f} s), chunks of "
             f"{io.CHUNK_BYTES // 2**10} KiB, write time best of {args.repeats}, "
             f"{platform.node()}",
             "", "| encoding | file size | vs none | write | read | identical |",
             "|---|---|---|---|---|---|"]
    base = rows[0]["bytes"]
    for row in rows:
        lines.append(f"| {row['encoding']} | {row['bytes'] / 2**20:.1f} MiB | "
                     f"{row['bytes'] / base:.2f} | {row['write_s']:.2f} s | "
                     f"{row['read_s']:.2f} s | {row['identical']} |")
    text = "\n".join(lines)
    print(text)
    if args.size == 4096:
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / "compression.md").write_text(text + "\n")
        (RESULTS / "compression.json").write_text(json.dumps(
            {"size": args.size, "compute_s": compute, "raw_bytes": raw, "rows": rows},
            indent=1) + "\n")


if __name__ == "__main__":
    main()
