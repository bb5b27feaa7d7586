"""Smoke tests of the benchmark scripts: their code paths at tiny sizes.

Correctness only, never speed: the scripts' alternatives and every C build they make
must compute what ``sweep.run`` computes, and their entry points must run and write
their results. The C part is skipped when gcc is absent.
"""

from __future__ import annotations

import importlib
import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None,
                               reason="gcc not found: the C reference is not built")

STEPS = 60  # t = 0.6: the scene is chaotic only over much longer horizons


@pytest.fixture(scope="module")
def run_all():
    return importlib.import_module("run_all")


@pytest.fixture(scope="module")
def states(run_all):
    """A tiny grid of the benchmark's workload (100 trajectories: not a multiple of
    any block, so the C builds run a padded partial block) and sweep's final state."""
    theta0, omega0 = np.linspace(-np.pi, np.pi, 20), np.linspace(-2.0, 2.0, 5)
    th0, om0 = run_all.initial_states(theta0, omega0)
    ds = run_all.run_sweep(run_all.scene_of(), theta0, omega0, STEPS)
    ref = ds.theta_final.values.ravel(), ds.omega_final.values.ravel()
    return theta0, omega0, th0, om0, ref


def max_diff(got, ref):
    return max(float(np.max(np.abs(got[0] - ref[0]))),
               float(np.max(np.abs(got[1] - ref[1]))))


def test_alternatives_agree_with_sweep(run_all, states):
    _, _, th0, om0, ref = states
    args = (STEPS, run_all.G_OVER_L, run_all.DAMPING, run_all.AMPLITUDE,
            run_all.FREQUENCY, run_all.PHASE, run_all.DT)
    assert max_diff(run_all.numpy_rk4(th0, om0, STEPS), ref) < 1e-12
    assert max_diff(run_all.numba_naive(th0, om0, *args), ref) < 1e-12
    pick = [0, 37, 99]
    sub = [r[pick] for r in ref]
    assert max_diff(run_all.python_rk4(th0[pick], om0[pick], STEPS), sub) < 1e-12
    # DOP853 differs by RK4's error (dt = 0.01: ~1e-10 over 0.6 s) and its own
    assert max_diff(run_all.scipy_dop853(th0[pick[:2]], om0[pick[:2]], STEPS),
                    [r[:2] for r in sub]) < 1e-7


def test_timed_returns_the_result(run_all):
    seconds, value = run_all.timed(lambda: 42, repeats=2)
    assert value == 42 and 0.0 <= seconds < 1.0


def test_grid_axes_has_about_n_trajectories(run_all):
    for n in (1, 10, 1000, 2**17):
        theta0, omega0 = run_all.grid_axes(n)
        assert 0.9 * n <= theta0.size * omega0.size <= n


def test_machine_description(run_all):
    d = run_all.machine_details()
    assert d["cores"] >= 1 and isinstance(d["avx512f"], bool)
    assert {"cpu_model", "simd", "compiler", "numba", "numba_threads"} <= set(d)
    lines = run_all.machine_lines({"machine_details": d})
    assert len(lines) == 3 and lines[0].startswith("- CPU:")


def test_limit_search_options(run_all):
    for avx512 in (True, False):
        candidates = run_all.c_limit_candidates(avx512)
        assert len(candidates) == len(run_all.C_BLOCKS)
        for flags in candidates.values():
            assert (run_all.WIDE in flags) == avx512
            assert "-ffp-contract=fast" in flags and "-ffast-math" not in flags
        variations = run_all.c_limit_variations(next(iter(candidates.values())), avx512)
        assert all("-DBLOCK=64" in flags for flags in variations.values())
        assert len(variations) == (3 if avx512 else 2)
        designs = run_all.c_limit_sine_designs(next(iter(candidates.values())), avx512)
        assert len(designs) == len(run_all.PI_SINES)
        for flags in designs.values():
            assert "-DSIN_VARIANT=5" in flags and "-DBLOCK=64" in flags
            assert (run_all.WIDE in flags) == avx512 and "-ffast-math" not in flags
        at = run_all.c_limit_sine_designs([], avx512, blocks=["8", "4096"])
        assert len(at) == 2 * len(run_all.PI_SINES)


@needs_gcc
def test_every_c_build_agrees_with_sweep(run_all, states, tmp_path):
    """The named rows and the limit's candidates (two block sizes, one variation each)
    give sweep's final state to rounding: the check run_all applies to every build."""
    theta0, omega0, th0, om0, ref = states
    avx512 = run_all.machine_details()["avx512f"]
    variants = {k: v for k, v in run_all.C_FIXED.items() if avx512 or run_all.WIDE not in v}
    candidates = run_all.c_limit_candidates(avx512, blocks=(8, 64))
    variants.update(candidates)
    variants.update(run_all.c_limit_variations(next(iter(candidates.values())), avx512))
    variants.update(run_all.c_limit_sine_designs(next(iter(candidates.values())), avx512))
    built = run_all.build_c(tmp_path, variants)
    linear = run_all.run_sweep(run_all.scene_of("linear"), theta0, omega0, STEPS)
    linear = linear.theta_final.values.ravel(), linear.omega_final.values.ravel()
    for name, fn in built.items():
        assert not isinstance(fn, str), f"{name}: {fn}"
        expected = linear if "-DLINEAR" in variants[name] else ref
        diff = max_diff(run_all.call_c(fn, th0, om0, STEPS), expected)
        assert diff <= run_all.C_CHECK_TOL, f"{name}: {diff:.1e}"


@needs_gcc
def test_sine_contract_of_the_c_builds(run_all, tmp_path):
    """Each C build's sine is measured against np.sin (run_all's eligibility for the C
    limit): sweep's design and the minimax one-reduction-by-pi sine meet the contract
    (2**-52 up to 1e12), the degree-19 Taylor polynomial misses it (its truncation alone
    is 2.2e-16 at pi/2)."""
    built = run_all.build_c(tmp_path, {
        "sweep": ["-DSIN_VARIANT=4", "-DBLOCK=8"],
        "minimax17": ["-DSIN_VARIANT=5", "-DSIN_POLY=2", "-DBLOCK=8"],
        "taylor19": ["-DSIN_VARIANT=5", "-DSIN_POLY=0", "-DBLOCK=8"]})
    got = {name: run_all.sine_accuracy(fn) for name, fn in built.items()}
    assert got["sweep"]["eligible"] and got["minimax17"]["eligible"]
    assert not got["taylor19"]["eligible"]
    assert set(got["sweep"]["max_abs_error"]) == set(run_all.SINE_RANGES)
    assert max(got["sweep"]["max_abs_error"].values()) <= 1.2e-16


def test_sine_designs_script(tmp_path):
    """benchmarks/sine_designs.py --quick: every design timed, test_vecmath's checks run
    for sweep's sine, the previous one and the C limit's: sweep's and the previous
    pass all of them."""
    sine_designs = importlib.import_module("sine_designs")
    assert sine_designs.main(["--quick", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "sine_designs_quick.json").read_text())
    assert set(result["throughput"]) == set(sine_designs.DESIGNS)
    assert all(v["vectorised"] for v in result["throughput"].values())
    assert all(v[2] for v in result["accuracy"]["sweep"].values())
    assert all(v[2] for v in result["accuracy"]["quadrant"].values())
    # two sines within 2**-52 each: after the quick run's 100 RK4 steps their states
    # differ by rounding grown by the dynamics (measured 4.4e-16), far below what a
    # wrong sine (an error of 1e-12 or more per call) would leave
    assert result["rk4"]["pi"]["max_abs_diff_from_sweep_sine"] < 1e-12


@needs_gcc
def test_c_build_failure_is_reported(run_all, tmp_path):
    fn = run_all.build_c_one(tmp_path, "broken", ["-DSIN_VARIANT=2", "-DBLOCK=(", ])
    assert isinstance(fn, str) and fn.startswith("build failed")


def test_stop_early_script(tmp_path):
    stop_early = importlib.import_module("stop_early")
    assert stop_early.main(["--size", "6", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "stop_early.json").read_text())
    assert result["size"] == 6 and len(result["runs"]) == 2
    assert all(run["full_s"] > 0 and run["stop_early_s"] > 0 for run in result["runs"])
    assert (tmp_path / "stop_early.md").read_text().startswith("# Stop early")


def test_forced_basins_script(tmp_path):
    """The script's scene, run and pilot are conftest's Wada pilot: --pilot 21 gives the
    catalogue of the wada_catalogue fixture, so its kernel is the one other tests use
    (a 21 x 21 pilot runs in milliseconds; compiling a catalogue's kernel takes seconds)."""
    forced_basins = importlib.import_module("forced_basins")
    assert forced_basins.main(["--size", "8", "--rows", "2", "--pilot", "21", "--no-c-limit",
                              "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "forced_basins.json").read_text())
    assert result["grid"] == [2, 8] and result["full_grid"] == [8, 8]
    assert result["full"]["attractors"] >= 1
    for name in ("stop_early", "catalogue"):
        assert 0.0 <= result[name]["unresolved_fraction"] <= 1.0
        # the script's own check of the labels: none differs where the full run resolves
        assert result[name]["labels_differing_where_full_resolves"] == 0
    assert 0.0 < result["catalogue"]["matched_fraction"] <= 1.0
    assert result["catalogue"]["pilot_seconds"] > 0
    assert "attractor catalogue (21 x 21 pilot)" in (tmp_path / "forced_basins.md").read_text()


def test_forced_basins_script_with_known_cells(tmp_path):
    """The known-cells variants (issue 37) on a whole 40 x 40 map (its one background
    map: 20 x 20), against the full run; the pilot is conftest's (the wada_catalogue
    fixture's kernels)."""
    forced_basins = importlib.import_module("forced_basins")
    assert forced_basins.main(["--size", "40", "--pilot", "21", "--no-c-limit", "--variants",
                               "full,catalogue,known,refine_known", "--out",
                               str(tmp_path)]) == 0
    result = json.loads((tmp_path / "forced_basins.json").read_text())
    assert result["variants"] == ["full", "catalogue", "known", "refine_known"]
    for name in ("known", "refine_known"):
        assert isinstance(result[name]["labels_differing"], int)
        assert result[name]["cpu_seconds"] > 0
        assert result[name]["stopped_known_fraction"] > 0
    assert "known cells" in (tmp_path / "forced_basins.md").read_text()


def test_refine_script(tmp_path):
    """benchmarks/refine.py at 21 x 21 (forced) and 33 x 33 (wells), with its figure;
    its 21 x 21 pilot (the forced map's own starts) is conftest's Wada pilot, so the
    kernel of the catalogue is the wada_catalogue fixture's."""
    refine = importlib.import_module("refine")
    figure = tmp_path / "refine.png"
    assert refine.main(["--size", "21", "--step", "4", "--pilot", "21", "--well-size", "33",
                        "--well-step", "8", "--no-c-limit", "--out", str(tmp_path),
                        "--figure", str(figure)]) == 0
    result = json.loads((tmp_path / "refine.json").read_text())
    for case, cells in (("forced", 21 * 21), ("well", 33 * 33)):
        run = result[case]
        assert run["cells"] == cells
        assert 0 < run["refine"]["cells_computed"] <= cells
        assert sum(run["refine"]["cells_per_level"]) == run["refine"]["cells_computed"]
        assert run["refine"]["seconds"] > 0 and run["full"]["seconds"] > 0
        assert 0 <= run["labels_differing"] <= cells
    assert result["well"]["labels_differing"] == 0  # smooth boundaries
    assert result["forced"]["refine"]["pilot_cells"] == 21 * 21
    assert (tmp_path / "refine.md").read_text().startswith("# Adaptive boundary refinement")
    assert figure.stat().st_size > 0


def test_wada_script(tmp_path):
    """benchmarks/wada.py at 21 x 21 with 2 steps and its figure; its 21 x 21 pilot of
    the A = 1.66 map is conftest's Wada pilot (the same kernels)."""
    wada = importlib.import_module("wada")
    figure = tmp_path / "wada.png"
    assert wada.main(["--size", "21", "--steps", "2", "--pilot", "21", "--out",
                      str(tmp_path), "--figure", str(figure)]) == 0
    result = json.loads((tmp_path / "wada.json").read_text())
    assert [case["basins"] for case in result["cases"]] == [3, 4]
    for case in result["cases"]:
        grid = case["grid_method"]
        assert len(grid["W"]) == grid["steps"] + 1 == 3
        assert np.allclose(np.sum(grid["W"], axis=1), 1)
        assert len(case["merging_method"]["shares"]) == case["basins"]
    assert "| m | grid | step 1 | step 2 |" in (tmp_path / "wada.md").read_text()
    assert figure.stat().st_size > 0


def test_lyapunov_script(tmp_path):
    """Tiny sizes: the script runs, checks its NumPy baseline against sweep (the same
    step map, to rounding) and writes both result files."""
    lyapunov = importlib.import_module("lyapunov")
    assert lyapunov.main(["--size", "4", "--periods", "1", "--repeat", "1",
                          "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "lyapunov.json").read_text())
    assert [run["cost"] > 0 for run in result["runs"]] == [True, True]
    assert result["numpy"]["max_difference_to_sweep"] < 1e-8
    assert (tmp_path / "lyapunov.md").read_text().startswith("# Lyapunov exponents")


def test_gpu_script_under_the_simulator(tmp_path):
    """Tiny workloads under numba's CUDA simulator (conftest): the script runs, checks
    the GPU's answer against the CPU's and writes both files; its rates mean nothing
    here (the README's GPU numbers come from a run on an H100)."""
    gpu = importlib.import_module("gpu")
    assert gpu.main(["--size-scale", "1e-6", "--steps", "40", "--skip-map",
                     "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "gpu.json").read_text())
    # (SWEEP_REAL_CUDA=1 runs this on a GPU, whose name is there instead)
    assert result["gpu"].startswith("numba CUDA simulator") or "SWEEP_REAL_CUDA" in os.environ
    assert [row["dtype"] for row in result["workloads"]] == ["float64"] * 2 + ["float32"] * 2
    assert result["workloads"][0]["max_difference_rad"] < 1e-12
    # float32's own rounding (6e-8) amplified over 40 steps: well under 1e-5 rad
    assert result["workloads"][2]["max_difference_rad"] < 1e-5
    assert (tmp_path / "gpu.md").read_text().startswith("# sweep on a GPU")


def test_explore_script(tmp_path):
    explore = importlib.import_module("explore")
    assert explore.main(["--size", "16", "--zooms", "2", "--rss-zooms", "10", "--no-browser",
                         "--no-forced", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "explore.json").read_text())
    wells = result["scenes"]["damped wells"]
    assert wells["final_n"] == 2 and wells["final_median_s"] > 0
    assert len(wells["rss"]["rss_mib"]) == 2  # before, and after the 10 zooms
    assert "| damped wells |" in (tmp_path / "explore.md").read_text()


def test_period_map_script(tmp_path):
    period_map = importlib.import_module("period_map")
    assert period_map.main(["--size", "4", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "period_map.json").read_text())
    assert result["trajectories"] == 4 * 4 and result["run_s"] > 0
    assert 0.0 <= result["resolved_fraction"] <= 1.0
    assert (tmp_path / "period_map.md").read_text().startswith("# Periodicity map")


def test_vector_width_script(tmp_path):
    """benchmarks/vector_width.py --quick: the three widths timed in their processes,
    the dataset's attribute as asked, the same bits."""
    vector_width = importlib.import_module("vector_width")
    assert vector_width.main(["--quick", "--out", str(tmp_path)]) == 0  # 1: bits differ
    result = json.loads((tmp_path / "vector_width_quick.json").read_text())
    (block,) = result["runs"].values()
    assert block["bit_identical"]
    assert {w: row["vector_width"] for w, row in block["rows"].items()} == \
        {"256": "256", "512": "512", "llvm": "llvm"}
    assert all(row["rate"] > 0 for row in block["rows"].values())
    assert block["rows"]["256"]["registers"]["zmm"] == 0


def test_blocks_script(tmp_path):
    """benchmarks/blocks.py --quick: every block size it times is the block sweep.run
    used (asserted inside), and the tables are written."""
    blocks = importlib.import_module("blocks")
    assert blocks.main(["--quick", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "blocks_quick.json").read_text())
    assert set(result["fixed"]) == {"1", "8"}
    assert all(rate > 0 for row in result["fixed"].values() for rate in row.values())
    assert set(result["adaptive_large"]) == {"64"}  # --quick: one block per method
    assert "NARROW_BELOW" in (tmp_path / "blocks_quick.md").read_text()


def test_float32_benchmark_runs_and_writes_its_tables(tmp_path):
    """``benchmarks/float32.py --quick``: every part runs at tiny size, writes its JSON
    and Markdown, and its numbers are sane (rates positive, errors finite, the basin
    map's starts accounted for). Correctness of float32 itself: tests/test_float32.py."""
    float32 = importlib.import_module("float32")
    assert float32.main(["--quick", "--output", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "float32.json").read_text())
    for rate in result["speed"]["rates"].values():
        assert rate["float64"] > 0 and rate["float32"] > 0
    for row in result["precision"].values():
        assert np.all(np.isfinite(row["float32"]["error_max"]))
    for row in result["basins"].values():
        assert 0 <= row["changed"] + row["unresolved"] <= row["starts"] == 81
    assert result["basins"]["float64"]["unresolved"] < 81  # the map resolves something
    assert "| chaotic (A = 1.5)" in (tmp_path / "float32.md").read_text()


def test_dopri5_lanes_table_of_the_work_precision_script():
    """The work-precision script's dopri5 table on a few trajectories: every scene and
    the uneven grid, each with the three timings and the speed-up between them; the
    block setting is restored afterwards (rates mean nothing at this size)."""
    import sweep

    work_precision = importlib.import_module("work_precision")
    block = sweep._config.ADAPTIVE_BLOCK
    rows, table = work_precision.dopri5_lanes(64, 1, tolerances=(1e-6,))
    assert block == sweep._config.ADAPTIVE_BLOCK and sweep._config.VECTOR_CONTROLLER
    assert [row["scene"] for row in rows] == ["libration", "separatrix", "rotation",
                                              "forced", "uneven"]
    for row in rows:
        assert min(row["one_at_a_time_s"], row["small_blocks_s"], row["lanes_s"]) > 0
        assert row["speedup"] == row["one_at_a_time_s"] / row["lanes_s"]
    assert len(table) == 6 + len(rows) + 1 and table[-2].startswith("| uneven")


def test_compile_time_script(tmp_path):
    """benchmarks/compile_time.py --quick: both designs compile two workloads' kernels
    from empty caches and give the same bits (main returns 1 when they differ)."""
    compile_time = importlib.import_module("compile_time")
    assert compile_time.main(["--quick", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "compile_time_quick.json").read_text())
    assert list(result["rows"]) == list(compile_time.QUICK)
    for row in result["rows"].values():
        assert row["same_bits"]
        assert row["threads"]["compile_s"] > 0 and row["prange"]["compile_s"] > 0
    assert "| RK4, one trajectory (one lane) |" in \
        (tmp_path / "compile_time_quick.md").read_text()


def test_system_basins_script(tmp_path):
    """benchmarks/system_basins.py on the 12 x 12 map of tests/test_system_attractors.py
    (the same kernels) over 400 periods: the labels that differ from the full run's are
    counted and rerun twice as long, where each settles where the catalogue said (or
    was left at -1 by it); both files written."""
    system_basins = importlib.import_module("system_basins")
    assert system_basins.main(["--size", "12", "--pilot", "12", "--periods", "400",
                               "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "system_basins.json").read_text())
    assert result["grid"] == [12, 12] and result["attractors_catalogue"] >= 1
    assert result["full_seconds"] > 0 and result["map_seconds"] > 0
    rerun = result["differing_rerun_twice_as_long"]
    assert rerun["starts"] == result["differing"]
    assert rerun["agree_with_catalogue"] + rerun["catalogue_unresolved"] == rerun["starts"]
    text = (tmp_path / "system_basins.md").read_text()
    assert text.startswith("# A driven double pendulum's basin map by the attractor")


def test_double_pendulum_script(tmp_path):
    """benchmarks/double_pendulum.py --quick: sweep, NumPy and (with gcc) every C build
    checked against sweep after 100 steps, the flip map's band the same with and
    without stop_early, the network's three graphs timed; both files written."""
    double = importlib.import_module("double_pendulum")
    assert double.main(["--quick", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "double_pendulum_quick.json").read_text())
    assert result["numpy"]["check_max_abs_diff"] <= double.CHECK_TOL
    if shutil.which("gcc") is not None:
        built = [row for row in result["c_search"] if "error" not in row]
        assert built and all(row["check_ok"] for row in built)
        # sweep's own sine design meets the contract in C too
        assert all(row["trig_eligible"] for row in built if "-DSIN_VARIANT=4" in row["flags"])
        limit = result["c_limit"]
        assert limit["sweep_over_c_limit"] > 0 and limit["check_max_abs_diff"] <= double.CHECK_TOL
    flip = result["flip"]
    assert flip["band_same_bits"] and flip["stop_early_seconds"] > 0
    assert [row["edges"] for row in result["network"]["rows"]] == [10, 20, 40]
    assert all(row["ns_per_edge_step"] > 0 for row in result["network"]["rows"])
    text = (tmp_path / "double_pendulum_quick.md").read_text()
    assert text.startswith("# Systems: the double pendulum and swing networks")


def test_double_pendulum_c_agrees_with_sweep(tmp_path):
    """double_pendulum.c, each sine design, on a grid with a padded partial block:
    sweep's final state to rounding after 100 steps (the script's check)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not found: the C reference is not built")
    double = importlib.import_module("double_pendulum")
    theta1, theta2 = np.linspace(-3.0, 3.0, 20), np.linspace(-3.0, 3.0, 5)
    state = double.starts(theta1, theta2)
    ref = double.final_state(double.run_sweep(theta1, theta2, double.CHECK_STEPS))
    for flags in (["-DSIN_VARIANT=4", "-DBLOCK=64"], ["-DSIN_VARIANT=0", "-DBLOCK=8"],
                  ["-DSIN_VARIANT=5", "-DSIN_POLY=2", "-ffp-contract=off", "-DBLOCK=16"]):
        fn = double.build_double(tmp_path, flags)
        assert not isinstance(fn, str), fn
        got = double.call_double(fn, state, double.CHECK_STEPS)
        assert double.max_diff(got, ref) <= double.CHECK_TOL, flags
