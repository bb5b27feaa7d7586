"""``device="cuda"``: the CUDA kernels against the CPU kernels and the oracles.

CI has no GPU: these run under numba's CUDA simulator (switched on in conftest), which
executes the generated CUDA kernel in Python threads, so the grids are small. On a
machine with a GPU, ``SWEEP_REAL_CUDA=1 pytest tests/test_cuda.py`` runs the same tests
on the device.

Tolerance against the CPU: the GPU's sine and cosine (CUDA's libdevice, or Python's
math under the simulator) are not `sweep.kernels.vecmath`'s, so every evaluation may
differ by an ulp or two; over the few hundred steps of these runs the flow amplifies
that to ~1e-13 (measured); asserted 1e-10, far below any physical difference and far
above rounding noise.
"""

import math
import subprocess
import sys

import numpy as np
import pytest

import sweep

cuda = pytest.importorskip("numba.cuda")

TOL = 1e-10

FULL = sweep.Scene(gravity=9.81, length=1.0, effects=(
    sweep.Damping(0.3), sweep.Forcing(1.2, 2.0), sweep.Torque(0.2),
    sweep.QuadraticDrag(0.05), sweep.PivotDrive(0.01, 20.0)))


def _pair(scene, grid, **kwargs):
    kwargs.setdefault("progress", False)
    return (sweep.run(scene, grid, device="cuda", **kwargs),
            sweep.run(scene, grid, **kwargs))


def _assert_close(gpu, cpu, tol=TOL):
    assert gpu.attrs["device"] == "cuda"
    for name in cpu.data_vars:
        np.testing.assert_allclose(gpu[name], cpu[name], rtol=0, atol=tol, err_msg=name)


@pytest.mark.parametrize("method", ["euler", "heun", "rk4", "rk38"])
def test_every_explicit_method_matches_the_cpu(method):
    grid = sweep.Grid(theta0=[-2.0, 0.5, 3.0], omega0=[0.0, 1.5], forcing_frequency=[1.5, 2.0])
    # Euler resolves W = 2 rad/s to 1 % only from 628 steps per period (the drive guard):
    # the devices are compared here, not the accuracy
    gpu, cpu = _pair(FULL, grid, t_end=3.0, dt=0.01, observe=("final", "winding"),
                     method=method, check_stability=method != "euler")
    _assert_close(gpu, cpu)


@pytest.mark.parametrize("method", ["verlet", "yoshida4"])
def test_symplectic_methods_match_the_cpu(method):
    scene = sweep.Scene(effects=(sweep.Torque(0.5),))
    grid = sweep.Grid(theta0=[0.3, 2.5], omega0=[0.0, 5.0])
    gpu, cpu = _pair(scene, grid, t_end=3.0, dt=0.01, observe=("final", "energy"),
                     method=method)
    _assert_close(gpu, cpu)


def test_every_observable_with_a_transient_and_saving():
    """All observables that the full scene allows (strobe needs a forcing period that
    is a whole number of steps: W = 2 rad/s, dt = pi/200), the linear model too, and
    the saved samples."""
    observe = ("final", "winding", "theta_max", "amplitude", "omega_mean", "strobe",
               "tension", "energy", "top_distance", "lyapunov")
    grid = sweep.Grid(theta0=[-1.0, 2.0], omega0=[0.0, 3.0])
    for model in ("nonlinear", "linear"):
        scene = sweep.Scene(gravity=9.81, length=1.0, model=model,
                            effects=FULL.effects)
        gpu, cpu = _pair(scene, grid, t_end=3 * np.pi, dt=np.pi / 200,
                         t_transient=np.pi, observe=observe, save_every=25)
        _assert_close(gpu, cpu)
        assert np.isfinite(gpu["strobe_theta"].isel(strobe=-1)).all()


def test_stop_early_gives_the_cpus_answer():
    """A thread whose trajectory is captured leaves the loop: the wells and capture
    times are the CPU's (capture time exactly: the same step)."""
    scene = sweep.Scene(effects=(sweep.Damping(1.0),))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 5), omega0=[0.0, 8.0, -12.0])
    gpu, cpu = _pair(scene, grid, t_end=30.0, dt=0.01, observe=("capture",),
                     stop_early=True)
    _assert_close(gpu, cpu, tol=0.0)


@pytest.mark.parametrize("stop_early", [False, True])
def test_other_strobe_counts_give_the_cpus_samples(stop_early):
    """``strobe_samples = 5`` (odd, the ring rotated by 26 mod 5 = 1 in the final
    pass): the CUDA kernel's samples, and with ``stop_early`` where its threads stop
    (the early-stop test looks for periods 1 and 2 in the ring of 5), are the CPU's.
    Eight starts: the CPU runs them with the kernels of test_strobe_samples.py's count
    of 5 (its early stop's block of 64 lanes, its resume test's block of 16)."""
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.3), sweep.Forcing(1.1, 1.3, 0.4)))
    grid = sweep.Grid(theta0=[-1.0, 0.5, 2.0, 3.0], omega0=[0.0, 1.5])
    period = 2 * np.pi / 1.3
    gpu, cpu = _pair(scene, grid, t_end=35 * period, dt=period / 40, t_transient=10 * period,
                     observe=("strobe",), strobe_samples=5, stop_early=stop_early)
    assert gpu.sizes["strobe"] == 5 and gpu.attrs["strobe_samples"] == 5
    assert np.isfinite(gpu["strobe_theta"]).all()
    _assert_close(gpu, cpu)


def test_small_angle_closed_form():
    """Linear model, undamped: theta0 cos(w t) + (omega0 / w) sin(w t); RK4's global
    error at w dt = 0.031 over 2 s is ~(w dt)^4 w t / 120 ~ 1e-8 rad; asserted 1e-7."""
    w = math.sqrt(9.81)
    scene = sweep.Scene(model="linear")
    grid = sweep.Grid(theta0=[0.01, 0.1], omega0=[0.0, 0.2])
    ds = sweep.run(scene, grid, t_end=2.0, dt=0.01, device="cuda", progress=False)
    th0, om0 = np.meshgrid(grid.axes["theta0"], grid.axes["omega0"], indexing="ij")
    exact = th0 * np.cos(w * 2.0) + om0 / w * np.sin(w * 2.0)
    np.testing.assert_allclose(ds["theta_final"], exact, rtol=0, atol=1e-7)


def test_chunks_and_checkpoint_resume(tmp_path):
    """Chunks stream through the device: any chunk size gives the same bits, and a
    resumed checkpoint too."""
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 7), omega0=[0.0, 2.0])
    kwargs = dict(t_end=2.0, dt=0.02, device="cuda", progress=False)
    whole = sweep.run(FULL, grid, **kwargs)
    chunked = sweep.run(FULL, grid, chunk_size=3, checkpoint=tmp_path / "cp",
                        keep_checkpoint=True, **kwargs)
    resumed = sweep.run(FULL, grid, chunk_size=3, checkpoint=tmp_path / "cp",
                        resume=True, **kwargs)
    for other in (chunked, resumed):
        assert other.drop_attrs().identical(whole.drop_attrs())


# the simulator computes in NumPy scalars, in its own threads (np.errstate does not
# reach them), which warn on overflow; a GPU does not
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning",
                            "ignore:invalid value encountered:RuntimeWarning")
def test_failed_trajectory_is_flagged():
    scene = sweep.Scene(gravity=100.0, length=1.0, model="linear")
    with pytest.warns(RuntimeWarning, match="1 of 1 trajectories became non-finite"):
        ds = sweep.run(scene, sweep.Grid(theta0=[0.5], omega0=[0.0]), t_end=300.0, dt=1.0,
                       check_stability=False, device="cuda", progress=False)
    assert int(ds.status.item()) == int(sweep.Status.NONFINITE)
    assert np.isnan(ds.theta_final.item())


# ------------------------------------------------------------------ refusals
def test_no_gpu_is_refused_before_compute(monkeypatch, no_compute):
    import sweep.kernels.cuda as cuda_kernels

    monkeypatch.setattr(cuda_kernels, "available", lambda: "no CUDA GPU was found")
    with pytest.raises(ValueError, match="device='cuda' cannot run here: no CUDA GPU was "
                                         "found; accepted: device='cpu'"):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1], omega0=[0.0]), t_end=1.0,
                  dt=0.1, device="cuda")


@pytest.mark.parametrize("device, message", [
    ("gpu", "device must be one of 'cpu', 'cuda', got 'gpu'"),
    (None, "device must be one of 'cpu', 'cuda', got None"),
])
def test_unknown_device_is_refused(device, message, no_compute):
    with pytest.raises(ValueError, match=message):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1], omega0=[0.0]), t_end=1.0,
                  dt=0.1, device=device)


def test_adaptive_method_on_the_gpu_is_refused(no_compute):
    with pytest.raises(ValueError, match="device='cuda' runs fixed-step methods; method "
                                         "'dopri5' is adaptive; accepted: one of 'euler'"):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1], omega0=[0.0]), t_end=1.0,
                  dt=0.1, device="cuda", method="dopri5")


def test_import_sweep_never_imports_cuda():
    """``import sweep`` and a CPU run leave numba's CUDA target unimported."""
    code = ("import sys, sweep; sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1], "
            "omega0=[0.0]), t_end=0.1, dt=0.05, progress=False); "
            "print('numba.cuda' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == "False"


def test_run_file_and_command_line_device(tmp_path):
    """``[run] device`` and ``--device`` reach `sweep.run`; a bad value is one line."""
    from sweep import cli

    run_file = tmp_path / "gpu.toml"
    run_file.write_text("[scene]\n[grid]\ntheta0 = [0.1, 0.2]\nomega0 = [0.0]\n"
                        '[run]\nt_end = 0.5\ndt = 0.05\ndevice = "cuda"\n')
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "a.nc"),
                     "--no-progress"]) == 0
    assert sweep.load(tmp_path / "a.nc").attrs["device"] == "cuda"
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "b.nc"), "--device", "cpu",
                     "--no-progress"]) == 0
    assert "device" not in sweep.load(tmp_path / "b.nc").attrs
    run_file.write_text(run_file.read_text().replace('"cuda"', '"tpu"'))
    with pytest.raises(ValueError, match="device must be one of 'cpu', 'cuda', got 'tpu'"):
        sweep.toml_spec.load_run(run_file)


def test_a_table_and_its_description_give_the_same_bits():
    """The GPU kernel takes a chunk as `sweep.grid.GridRows` (what `sweep.run` passes:
    each thread reads its own parameters) or as a table (`GridRows.from_table`): the
    same rows give the same bits either way."""
    from sweep.execution.local import RunContext, allocate, integrate
    from sweep.kernels import build

    grid = sweep.Grid(theta0=[-2.0, 0.5, 3.0], omega0=[0.0, 1.5], forcing_frequency=[1.5, 2.0])
    settings, spec, _ = sweep.engine._prepare(
        FULL, grid, t_end=1.0, dt=0.01, t0=0.0, t_transient=0.0, observe=("final",),
        save_every=None, method="rk4", rtol=None, atol=None, chunk_size=None,
        specialize=True, check_stability=True, estimate_error=None, stop_early=False,
        device="cuda")
    context = RunContext(FULL, grid, spec, settings)
    results = []
    for rows in (context.table(2, 11), grid.table(FULL, 2, 11)):
        arrays = allocate(spec, settings, 9)
        integrate(build(spec), rows, settings, arrays)
        results.append(arrays["out"])
    assert type(context.table(2, 11)).__name__ == "GridRows"
    np.testing.assert_array_equal(results[0], results[1])
