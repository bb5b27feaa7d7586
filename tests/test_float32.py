"""``dtype="float32"``: the single-precision kernels against the oracles.

What float32 may cost is rounding, and the tests hold it to bounds derived from it.
float32 rounds to u = 2**-24 ~ 6e-8 relative. A step of a trajectory makes a few
roundings of the state, so over N steps the error from rounding alone grows at most
like N u |state| (all roundings of one sign) and typically like sqrt(N) u |state|; the
flow then amplifies it by its sensitivity (little in libration, a great deal near the
separatrix or on a chaotic attractor). Each tolerance below names its N and margin.

Where float32 is *not* enough, the tests say so by measuring it: a rotation's
unwrapped angle grows, and with it the absolute size of its rounding (``test_rotation_
loses_digits_as_its_angle_grows``).

The float32 step is ``F(dt) = float32(dt)`` in the state and the clock alike
(`sweep.kernels.precision`), so the exact solutions are evaluated at ``n F(dt)``.
"""

import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import sweep
from sweep import accuracy, kernels
from sweep.kernels import KernelSpec, Status

U32 = 2.0**-24  # float32's unit roundoff

FULL = sweep.Scene(gravity=9.81, length=1.0, effects=(
    sweep.Damping(0.3), sweep.Forcing(1.2, 2.0), sweep.Torque(0.2),
    sweep.QuadraticDrag(0.05), sweep.PivotDrive(0.01, 20.0)))


def _clock(n_steps, dt):
    """The time a float32 run has reached after ``n_steps`` steps of ``dt``."""
    return n_steps * float(np.float32(dt))


def _pair(scene, grid, **kwargs):
    kwargs.setdefault("progress", False)
    return (sweep.run(scene, grid, dtype="float32", **kwargs),
            sweep.run(scene, grid, **kwargs))


# ------------------------------------------------------------------ exact solutions
def test_small_angle_closed_form_over_ten_thousand_steps():
    """Linear undamped model: theta0 cos(w t) + (omega0 / w) sin(w t) at t = 10^4 F(dt).

    RK4's own error here is ~1.1e-6 rad (the float64 run's, measured); float32 rounding
    adds ~N u |theta| <= 1e4 x 6e-8 x 0.5 = 3e-4 at worst, ~sqrt(N) u |theta| ~ 3e-6
    typically (measured: 1.07e-6 in all). Asserted: 1e-5 rad, 10x the measured error
    and 30x below the worst-case rounding bound."""
    w = math.sqrt(9.81)
    grid = sweep.Grid(theta0=[0.01, 0.1, 0.5], omega0=[0.0, 0.2])
    ds = sweep.run(sweep.Scene(model="linear"), grid, t_end=100.0, dt=0.01, dtype="float32",
                   progress=False)
    assert ds.attrs["dtype"] == "float32" and ds.theta_final.dtype == np.float64
    t = _clock(10_000, 0.01)
    th0, om0 = np.meshgrid(grid.axes["theta0"], grid.axes["omega0"], indexing="ij")
    exact = th0 * np.cos(w * t) + om0 / w * np.sin(w * t)
    np.testing.assert_allclose(ds["theta_final"], exact, rtol=0, atol=1e-5)


def test_libration_against_the_elliptic_solution():
    """Nonlinear undamped libration (amplitudes 0.5 and 2 rad) against the exact
    Jacobi-elliptic motion after 10^4 steps, as the state error max(|d theta|,
    |d omega| / w0). Float64 RK4 is within 4e-6 here. In float32 the amplitude-0.5
    libration is within 4e-6 too, but the amplitude-2 one drifts in phase to 3.7e-4
    (measured): its period depends strongly on its energy (dT/dE grows towards the
    separatrix), so rounding the energy by ~u per step becomes a phase drift that grows
    with time. Asserted: 2e-5 and 1e-3 (5x and 2.7x the measured)."""
    scene = sweep.Scene(gravity=9.81, length=1.0)
    grid = sweep.Grid(theta0=[0.5, 2.0], omega0=[0.0])
    # final only: the one-lane kernel of test_error_estimate_of_a_float32_run_includes_its_rounding
    ds = sweep.run(scene, grid, t_end=100.0, dt=0.01, dtype="float32", progress=False,
                   observe=("final",))
    theta, omega = accuracy.exact(scene, [0.5, 2.0], [0.0, 0.0], _clock(10_000, 0.01))
    error = accuracy.state_error(scene, ds.theta_final.values.ravel(),
                                 ds.omega_final.values.ravel(), np.ravel(theta),
                                 np.ravel(omega))
    assert error[0] < 2e-5 and error[1] < 1e-3


def test_rotation_loses_digits_as_its_angle_grows():
    """The documented limit of float32: a rotation's unwrapped angle grows (here to
    ~520 rad in 100 s), and float32 holds 520 only to ulp(520) / 2 = 3e-5, so each
    step rounds the angle by that much. The exact motion's error is then ~N ulp / 2 at
    worst (0.3 rad) and ~sqrt(N) ulp (6e-3) typically, where float64 stays at 3e-5
    (RK4's error). Measured: 1.6e-2. Asserted: float32's error is between 10x
    float64's (it *is* worse, as documented) and 0.1 rad (it is bounded by the
    rounding estimate, not a blow-up)."""
    scene = sweep.Scene(gravity=9.81, length=1.0)
    grid = sweep.Grid(theta0=[0.5], omega0=[7.0])
    single, double = _pair(scene, grid, t_end=100.0, dt=0.01)
    exact32, _ = accuracy.exact(scene, [0.5], [7.0], _clock(10_000, 0.01))
    exact64, _ = accuracy.exact(scene, [0.5], [7.0], 100.0)
    error32 = abs(float(single.theta_final.item()) - float(np.ravel(exact32)[0]))
    error64 = abs(float(double.theta_final.item()) - float(np.ravel(exact64)[0]))
    assert abs(float(single.theta_final.item())) > 500.0
    assert 10 * error64 < error32 < 0.1


# ------------------------------------------------------------------ against float64
@pytest.mark.parametrize("method", ["euler", "heun", "rk4", "rk38"])
def test_every_explicit_method_with_every_effect_is_float64_to_rounding(method):
    """All five effects, 300 steps from varied starts: the float32 run is the float64
    run to rounding. Bound: 300 steps x u x |state| (<= 10) x a flow amplification of
    a few over 3 s = ~2e-4 worst case; measured ~1e-6. Asserted 1e-4 (rad and rad/s)."""
    grid = sweep.Grid(theta0=[-2.0, 0.5, 3.0], omega0=[0.0, 1.5], forcing_frequency=[1.5, 2.0])
    # Euler resolves W = 2 rad/s to 1 % only from 628 steps per period (the drive guard):
    # the precisions are compared here, not the accuracy
    single, double = _pair(FULL, grid, t_end=3.0, dt=0.01, method=method,
                           observe=("final", "winding"), check_stability=method != "euler")
    for name in double.data_vars:
        np.testing.assert_allclose(single[name], double[name], rtol=0, atol=1e-4,
                                   err_msg=name)


@pytest.mark.parametrize("method", ["verlet", "yoshida4"])
def test_symplectic_methods_in_float32(method):
    """A conservative scene with a torque: the same bound as the explicit methods."""
    scene = sweep.Scene(effects=(sweep.Torque(0.5),))
    grid = sweep.Grid(theta0=[0.3, 2.5], omega0=[0.0, 5.0])
    single, double = _pair(scene, grid, t_end=3.0, dt=0.01, method=method,
                           observe=("final", "energy"))
    for name in double.data_vars:
        np.testing.assert_allclose(single[name], double[name], rtol=0, atol=1e-4,
                                   err_msg=name)


def test_every_observable_and_saving_in_float32():
    """Every observable the full scene allows, a transient and saved samples, both
    models: the float32 values are float64's to float32 rounding (the same 1e-4 bound
    as above, relative to the size of the value: tension and energy are ~10-100); the
    outputs are float64 arrays; nothing is NaN."""
    observe = ("final", "winding", "theta_max", "amplitude", "omega_mean", "strobe",
               "tension", "energy", "top_distance", "lyapunov")
    grid = sweep.Grid(theta0=[-1.0, 2.0], omega0=[0.0, 3.0])
    for model in ("nonlinear", "linear"):
        scene = sweep.Scene(gravity=9.81, length=1.0, model=model, effects=FULL.effects)
        single, double = _pair(scene, grid, t_end=3 * np.pi, dt=np.pi / 200,
                               t_transient=np.pi, observe=observe, save_every=25)
        for name in double.data_vars:
            assert single[name].dtype == double[name].dtype, name
            if name == "status":
                np.testing.assert_array_equal(single[name], double[name])
                continue
            scale = max(1.0, float(np.nanmax(np.abs(double[name]))))
            # NaN where float64 has NaN (a strobe ring not yet full), nowhere else
            np.testing.assert_allclose(single[name], double[name], rtol=0,
                                       atol=1e-4 * scale, err_msg=f"{model} {name}")


def test_lyapunov_exponents_in_float32():
    """Baker & Gollub's chaotic pendulum (c = 0.5, A = 1.5, W = 2/3, g/L = 1): the
    largest exponent is a property of the attractor, not of the trajectory, so float32
    must find it though its trajectory departs from float64's within a few periods.
    float64 over 128 starts gives a spread of ~0.008 (tests/test_lyapunov.py); asserted:
    the float32 mean within 0.02 of float64's (2.5 spreads), and the sum of both
    exponents -c to 1e-3 (the tangent vectors' stages are float32 arithmetic, losing ~u
    per renormalisation interval, though the vectors and sums are kept in float64:
    1e5 steps / 64 x u ~ 1e-4 relative)."""
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.5), sweep.Forcing(1.5, 2 / 3)))
    grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 16), omega0=[0.0])
    period = 3 * np.pi
    single, double = _pair(scene, grid, t_end=400 * period, dt=period / 100,
                           t_transient=20 * period, observe=("lyapunov",))
    assert float(double.lyapunov_max.mean()) > 0.1  # chaotic
    assert abs(float(single.lyapunov_max.mean()) - float(double.lyapunov_max.mean())) < 0.02
    np.testing.assert_allclose(single.lyapunov_max + single.lyapunov_min, -0.5, atol=1e-3)


# ------------------------------------------------------------------ early stop
def test_wells_in_float32_are_the_float64_wells():
    """Damped basins with ``stop_early`` (the capture test is an energy threshold):
    the same wells as float64 on every start at least 1e-3 rad from a basin boundary
    (float32 rounding moves a trajectory by ~1e-6 here, so only starts that close to a
    boundary may flip; on this grid none is)."""
    scene = sweep.Scene(effects=(sweep.Damping(0.5),))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 13), omega0=np.linspace(-6, 6, 9))
    single, double = _pair(scene, grid, t_end=60.0, dt=0.01, observe=("capture",),
                           stop_early=True)
    np.testing.assert_array_equal(single.well, double.well)
    # capture times: the same step, or one apart where the energy crosses 2 g/L within
    # a float32 rounding of it
    assert float(np.nanmax(np.abs(single.capture_time - double.capture_time))) <= 0.0100001


def test_strobe_early_stop_in_float32_stops():
    """The strobe test in float32 uses `sweep.observables.STROBE_TOL_FLOAT32` (1e-8 is
    below float32's resolution, so no trajectory would ever stop). A trajectory that
    stops does not see the end of the run, so two runs of different lengths that both
    outlast every stop give the same bits: that shows every trajectory stopped. And the
    labels are those of float64's full run."""
    from sweep import maps

    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))  # three attractors
    axes = dict(theta0=np.linspace(-3, 3, 7), omega0=[-1.0, 0.0, 1.0])
    grid = sweep.Grid(**axes)
    period = 2 * np.pi
    kwargs = dict(dt=period / 100, t_transient=20 * period, observe=("strobe",),
                  progress=False)
    short = sweep.run(scene, grid, t_end=300 * period, stop_early=True, dtype="float32",
                      **kwargs)
    long = sweep.run(scene, grid, t_end=600 * period, stop_early=True, dtype="float32",
                     **kwargs)
    assert short.strobe_theta.values.tobytes() == long.strobe_theta.values.tobytes()
    labels = maps.basins(short).values.ravel()
    reference = maps.basins(sweep.run(scene, grid, t_end=300 * period, **kwargs)).values.ravel()
    assert (reference >= 0).all() and len(set(reference)) == 3 == len(set(labels))
    # the same partition of the starts (the catalogues may list the attractors in
    # another order), except at starts on a fractal basin boundary, where float64 itself
    # ends elsewhere when theta0 moves by 1e-5 rad: the size float32's roundings (6e-8
    # relative per step) reach as a random walk over the 30,000 steps. Every start that
    # float32 labels differently must be such a start (this grid has two: (-3, 0), next
    # to the inverted position, and (0, 1)); they are few, but how few depends on the
    # last bits, so the count is only bounded (a quarter of the starts)
    pairs = list(zip(labels, reference))
    match = {a: max(set(reference), key=lambda b: pairs.count((a, b))) for a in set(labels)}
    differ = np.flatnonzero([match[a] != b for a, b in pairs])
    assert len(differ) <= len(pairs) // 4
    theta0, omega0 = np.meshgrid(axes["theta0"], axes["omega0"], indexing="ij")
    for k in differ:
        near = sweep.run(scene, sweep.Grid(theta0=theta0.ravel()[k] + 1e-5 * np.arange(-4, 5),
                                           omega0=[omega0.ravel()[k]]),
                         t_end=300 * period, **kwargs)
        assert len(set(maps.basins(near).values.ravel())) > 1
    source = kernels.source(KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",),
                                       stop_early=True, dtype="float32"))
    assert "F(1e-06) + F(4.76837158203125e-07) * abs(" in source
    # 2 pi stays float64 for the observables' turns of the float64 angle
    # (sweep.kernels.source._precision patches the generated line back)
    assert "TWO_PI = 2.0 * math.pi" in source and "TWO_PI = F(" not in source


def test_refill_gives_the_same_bits_as_waiting_lanes_in_float32():
    """Lane refill is bookkeeping: in float32 as in float64, a refilled lane computes
    its trajectory bit for bit as a lane that waits for its block."""
    from test_refill import _call, _table

    params = _table(700)
    waiting = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), stop_early=True,
                         block=64, dtype="float32")
    refill = KernelSpec("nonlinear", ("damping", "forcing"), ("strobe",), stop_early=True,
                        block=64, refill=True, dtype="float32")
    out_w, status_w = _call(waiting, params)
    out_r, status_r = _call(refill, params)
    np.testing.assert_array_equal(status_r, status_w)
    assert out_r.tobytes() == out_w.tobytes()
    assert (status_w == Status.NONFINITE).sum() == 1  # the overflowing start is flagged


# ------------------------------------------------------------------ bits, chunks, code
@pytest.mark.parametrize("model", ["nonlinear", "linear"])
def test_one_trajectory_alone_gives_the_bits_of_a_block(model):
    """The narrow path (a block of one lane, its lanes plain variables:
    `sweep.kernels.lanes.scalar_lanes`) converts each lane variable as the lane arrays
    do, so the observables that keep float64 state in a float32 kernel (lyapunov's
    tangent vectors and sums, omega_mean's steady angle) stay float64 there too: the
    same bits as in blocks of 8 and 64, saved samples included."""
    from test_blocks import _call, _table

    params = _table(12)
    observe = ("final", "omega_mean", "energy", "lyapunov")
    specs = [KernelSpec(model, ("damping", "forcing"), observe, save=True, block=block,
                        dtype="float32") for block in (1, 8, 64)]
    alone = _call(specs[0], params, save_every=7)
    for spec in specs[1:]:
        for a, b in zip(alone, _call(spec, params, save_every=7)):
            np.testing.assert_array_equal(a, b)


def test_chunks_and_threads_do_not_change_the_bits():
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 37), omega0=[0.0, 2.0])
    kwargs = dict(t_end=5.0, dt=0.01, dtype="float32", progress=False,
                  observe=("final", "amplitude"))
    whole = sweep.run(FULL, grid, **kwargs)
    chunked = sweep.run(FULL, grid, chunk_size=10, **kwargs)
    for name in whole.data_vars:
        assert whole[name].values.tobytes() == chunked[name].values.tobytes(), name


def test_checkpoint_of_another_precision_is_refused(tmp_path):
    grid = sweep.Grid(theta0=np.linspace(-1, 1, 8), omega0=[0.0])
    sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, dtype="float32", progress=False,
              checkpoint=tmp_path / "ck", keep_checkpoint=True, chunk_size=4)
    with pytest.raises(ValueError, match="dtype"):
        sweep.run(sweep.Scene(), grid, t_end=1.0, dt=0.01, progress=False,
                  checkpoint=tmp_path / "ck", resume=True, chunk_size=4)


def test_float32_kernel_computes_in_float32_vectors(tmp_path):
    """The machine code of the float32 kernel for a damped scene: its step is SIMD
    float32 arithmetic (``<N x float>``), and float64 vector arithmetic is only the
    minority that `sweep.kernels.precision` keeps float64 on purpose (the angle's
    additions and the sine's argument reduction): were a float64 literal left in a
    stage line, every product of the step would be double. Compiled afresh in a
    subprocess: numba cannot inspect code loaded from its disk cache."""
    script = textwrap.dedent("""
        import re, numpy as np, sweep
        from sweep import kernels
        spec = kernels.KernelSpec("nonlinear", ("damping",), ("final",), block=64,
                                  dtype="float32")
        kernel = kernels.build(spec)
        params = np.zeros((64, len(sweep.physics.parameter_names())))
        out = np.empty((64, kernels.n_columns(spec)))
        kernel(params, 0.0, 0.01, 10, 0, 1, out, np.empty(64, dtype=np.int8),
               np.empty((0, 2, 0)))
        ir = "".join(kernels.compiled(kernel).inspect_llvm().values())
        # multiplies and fused multiply-adds (the kernels write theirs: llvm.fma)
        print(len(re.findall(r"(?:fmul[^\\n]*<\\d+ x float>|@llvm\\.fma\\.v\\d+f32\\()", ir)),
              len(re.findall(r"(?:fmul[^\\n]*<\\d+ x double>|@llvm\\.fma\\.v\\d+f64\\()", ir)))
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, check=True)
    single, double = map(int, result.stdout.split())
    # measured: 49 float32 and 17 float64 since the lanes are counted by float32
    # (`_config.SINGLE_BY_NARROWEST`; 57 and 17 before), each FMA declaration counted
    # once too; a float64 literal in a stage line would turn most of the step's 49 to
    # double, so a float32 majority of 2x is the line
    assert single > 0 and single > 2 * double


@pytest.mark.parametrize("model", ["nonlinear", "linear"])
def test_a_pivot_drive_keeps_the_step_in_float32(model, tmp_path):
    """The pivot's amplitude a nu^2 / L reads the drive frequency, which stays float64
    for the phase: its value must still enter the step as float32. From numba's types
    of the compiled float32 kernel (damping + pivot): the float64 variables are only
    those kept float64 on purpose (clock, drive frequency and phase, the nonlinear
    angle, 2 pi), never the velocity or a stage."""
    script = textwrap.dedent(f"""
        import numpy as np, sweep
        from sweep import kernels
        spec = kernels.KernelSpec("{model}", ("damping", "pivot"), ("final",), block=64,
                                  dtype="float32")
        kernel = kernels.build(spec)
        params = np.ones((64, len(sweep.physics.parameter_names())))
        kernel(params, 0.0, 0.01, 10, 0, 1, np.empty((64, kernels.n_columns(spec))),
               np.empty(64, dtype=np.int8), np.empty((0, 2, 0)))
        for cres in kernels.compiled(kernel).overloads.values():
            types = cres.type_annotation.typemap
            print(" ".join(sorted({{k.split(".")[0] for k, v in types.items()
                                   if str(v) == "float64" and not k.startswith(("$", "arg."))}})))
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, check=True)
    double = set(result.stdout.split())
    allowed = {"TWO_PI", "cdt0", "dt_clock", "nu", "psi", "t0", "th", "th0"}
    assert double <= allowed, double - allowed
    assert {"om", "k1o", "p0"}.isdisjoint(double)


# ------------------------------------------------------------------ estimates, refusals
def test_error_estimate_of_a_float32_run_includes_its_rounding():
    """The estimate re-runs in float64 at dt/2, so it sees float32's rounding: at
    dt = 1e-3 over 10^4 steps RK4's own error is ~1e-13 (the float64 estimate) while
    float32's rounding is ~1e-6 (sqrt(N) u |theta|, theta ~ 1)."""
    grid = sweep.Grid(theta0=np.linspace(0.5, 1.5, 8), omega0=[0.0])
    kwargs = dict(t_end=10.0, dt=1e-3, progress=False, estimate_error=4)
    single = sweep.run(sweep.Scene(), grid, dtype="float32", **kwargs)
    double = sweep.run(sweep.Scene(), grid, **kwargs)
    assert double.attrs["error_estimate_max"] < 1e-10
    assert 1e-8 < single.attrs["error_estimate_max"] < 1e-3
    assert "float64" in single.attrs["error_estimate_method"]


@pytest.mark.parametrize("dtype, message", [
    ("float16", "dtype must be one of 'float64', 'float32', got 'float16'"),
    (np.float32, "dtype must be one of 'float64', 'float32', got <class"),
])
def test_unknown_dtype_is_refused(dtype, message, no_compute):
    with pytest.raises(ValueError, match=message):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1]), t_end=1.0, dt=0.1, dtype=dtype)


def test_float32_with_an_adaptive_method_is_refused(no_compute):
    with pytest.raises(ValueError, match="dtype='float32' runs fixed-step methods; method "
                                         "'dopri5' is adaptive; accepted: one of 'euler'"):
        sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.1]), t_end=1.0, dt=0.1,
                  dtype="float32", method="dopri5")


def test_run_file_command_line_and_run_arguments(tmp_path):
    """``[run] dtype`` and ``--dtype`` reach `sweep.run`; the file records it and
    `sweep.io.run_arguments` gives it back; a bad value is refused naming it."""
    from sweep import cli, io

    run_file = tmp_path / "single.toml"
    run_file.write_text("[scene]\n[grid]\ntheta0 = [0.1, 0.2]\nomega0 = [0.0]\n"
                        '[run]\nt_end = 0.5\ndt = 0.05\ndtype = "float32"\n')
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "a.nc"),
                     "--no-progress"]) == 0
    ds = sweep.load(tmp_path / "a.nc")
    assert ds.attrs["dtype"] == "float32"
    assert io.run_arguments(ds)["dtype"] == "float32"
    assert cli.main(["run", str(run_file), "-o", str(tmp_path / "b.nc"), "--dtype",
                     "float64", "--no-progress"]) == 0
    assert "dtype" not in sweep.load(tmp_path / "b.nc").attrs
    run_file.write_text(run_file.read_text().replace('"float32"', '"half"'))
    with pytest.raises(ValueError, match="dtype must be one of 'float64', 'float32', got "
                                         "'half'"):
        sweep.toml_spec.load_run(run_file)


# ------------------------------------------------------------------ the GPU, simulated
def test_cuda_float32_matches_the_cpu_float32():
    """Under numba's CUDA simulator: the GPU's float32 kernel (CUDA's sinf of the
    float32 argument) against the CPU's (`vecmath.sin32`). Both sines are within ~1.5
    float32 ulps, so the two runs differ by float32 rounding: the 1e-4 bound above."""
    pytest.importorskip("numba.cuda")
    grid = sweep.Grid(theta0=[-2.0, 0.5, 3.0], omega0=[0.0, 1.5])
    kwargs = dict(t_end=3.0, dt=0.01, dtype="float32", progress=False,
                  observe=("final", "amplitude"))
    gpu = sweep.run(FULL, grid, device="cuda", **kwargs)
    cpu = sweep.run(FULL, grid, **kwargs)
    assert gpu.attrs["device"] == "cuda" and gpu.attrs["dtype"] == "float32"
    for name in cpu.data_vars:
        np.testing.assert_allclose(gpu[name], cpu[name], rtol=0, atol=1e-4, err_msg=name)
