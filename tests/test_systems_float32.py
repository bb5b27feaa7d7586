"""``dtype="float32"`` for a system (`sweep.kernels.source._system_single`): the double
pendulum's float32 kernel against SciPy's DOP853, its bits across blocks, refill,
chunks and threads, its machine code, and the refusals.

As for the single pendulum (``tests/test_float32.py``): float32 rounds to u = 2**-24
~ 6e-8 relative, a step rounds the state a few times, so over N steps rounding alone
moves a regular trajectory by at most about N u |state| times the flow's sensitivity.
dt = 1/64 s is a float32 number, so the float32 state steps exactly the clock's dt.
"""

import os
import subprocess
import sys
import textwrap

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import sweep
from sweep import _config

G = 9.81
DT = 1 / 64  # [s], exact in float32
STARTS = [(0.3, -0.2, 0.0, 0.0), (0.1, 0.25, 0.2, -0.1), (-0.4, 0.3, 0.0, 0.5)]


def textbook(t, y):
    """The double pendulum with unit masses and lengths (tests/test_systems.py)."""
    th1, th2, w1, w2 = y
    d = th1 - th2
    den = 3 - np.cos(2 * d)
    a1 = (-3 * G * np.sin(th1) - G * np.sin(th1 - 2 * th2)
          - 2 * np.sin(d) * (w2 ** 2 + w1 ** 2 * np.cos(d))) / den
    a2 = 2 * np.sin(d) * (2 * w1 ** 2 + 2 * G * np.cos(th1) + w2 ** 2 * np.cos(d)) / den
    return [w1, w2, a1, a2]


def _points(starts):
    return sweep.Points(theta1_0=[s[0] for s in starts], theta2_0=[s[1] for s in starts],
                        omega1_0=[s[2] for s in starts], omega2_0=[s[3] for s in starts])


def test_float32_double_pendulum_against_dop853():
    """Three regular starts (small angles: normal-mode beating, no chaos) over 5 s =
    1280 steps of 1/256 s. RK4's own error there is below 5e-8 (measured; the float64
    run is checked against 1e-6); rounding: N u |state| = 1280 * 6e-8 * 2.5 (|omega| up
    to ~2.5 rad/s) ~ 2e-4 at worst (typically sqrt(N) u |state| ~ 5e-6; measured 3e-6).
    Bound 2e-4; and the float32 run must really be float32: away from the float64 run
    by more than 1e-9 (a float64 run twice differs by ~1e-15; float32 by ~1e-6)."""
    ds32 = sweep.run(sweep.DoublePendulum(), _points(STARTS), t_end=5.0, dt=DT / 4,
                     observe=("final",), dtype="float32", progress=False)
    ds64 = sweep.run(sweep.DoublePendulum(), _points(STARTS), t_end=5.0, dt=DT / 4,
                     observe=("final",), progress=False)
    assert ds32.attrs["dtype"] == "float32"
    names = ("theta1_final", "theta2_final", "omega1_final", "omega2_final")
    for k, start in enumerate(STARTS):
        exact = solve_ivp(textbook, (0.0, 5.0), list(start), method="DOP853", rtol=1e-13,
                          atol=1e-13).y[:, -1]
        got32 = np.array([float(ds32[n].values[k]) for n in names])
        got64 = np.array([float(ds64[n].values[k]) for n in names])
        assert np.max(np.abs(got64 - exact)) < 1e-6
        assert np.max(np.abs(got32 - exact)) < 2e-4
        assert np.max(np.abs(got32 - got64)) > 1e-9


def test_float32_bits_do_not_depend_on_blocks_refill_chunks_or_threads(monkeypatch):
    """The flip-time map in float32 (early stop): block kernel, refill, one thread,
    chunks of 97 and one trajectory alone give the same bits."""
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, 12), theta2_0=np.linspace(-3, 3, 12))
    kw = dict(t_end=20.0, dt=DT, observe=("flip",), stop_early=True, dtype="float32",
              progress=False)
    monkeypatch.setattr(_config, "REFILL", False)
    blocks = sweep.run(sweep.DoublePendulum(), grid, **kw)
    monkeypatch.setattr(_config, "REFILL", True)
    runs = {"refill": sweep.run(sweep.DoublePendulum(), grid, **kw),
            "chunks": sweep.run(sweep.DoublePendulum(), grid, chunk_size=97, **kw)}
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        runs["1 thread"] = sweep.run(sweep.DoublePendulum(), grid, **kw)
    finally:
        numba.set_num_threads(threads)
    for label, ds in runs.items():
        for name in blocks.data_vars:
            assert ds[name].values.tobytes() == blocks[name].values.tobytes(), (label, name)
    flips = np.isfinite(blocks.flip_time.values)
    assert 0.2 < flips.mean() < 0.9
    alone = sweep.run(sweep.DoublePendulum(), sweep.Points(theta1_0=[2.5], theta2_0=[3.0]),
                      **kw)
    at = blocks.sel(theta1_0=2.5, theta2_0=3.0, method="nearest")
    if abs(float(at.theta1_0) - 2.5) < 1e-12:  # the grid holds the start
        assert alone.flip_time.values[0] == at.flip_time.values


def test_float32_system_kernel_computes_in_float32_vectors(tmp_path):
    """The machine code of the double pendulum's float32 kernel: its step is SIMD float32
    arithmetic (``<N x float>``); float64 vector arithmetic is only the minority kept
    float64 on purpose (the angles' updates and the sine's argument reduction). A
    float64 literal or parameter left in the accelerations would make most of the step
    double. Compiled afresh in a subprocess (numba cannot inspect cached code)."""
    script = textwrap.dedent("""
        import re, numpy as np, sweep
        from sweep import kernels
        from sweep.engine_systems import prepare_system
        grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 16), theta2_0=np.linspace(-1, 1, 16))
        spec = prepare_system(sweep.DoublePendulum(), grid, t_end=1.0, dt=0.0625,
                              observe=("final",), dtype="float32")[1]
        kernel = kernels.build(spec)
        n = 256
        params = np.zeros((n, len(spec.columns)))
        params[:, 4:9] = 1.0
        kernel(params, 0.0, 0.0625, 4, 0, 1, np.empty((n, 4)), np.empty(n, dtype=np.int8),
               np.empty((0, 4, 0)))
        ir = "".join(kernels.compiled(kernel).inspect_llvm().values())
        print(len(re.findall(r"(?:fmul[^\\n]*<\\d+ x float>|@llvm\\.fma\\.v\\d+f32\\()", ir)),
              len(re.findall(r"(?:fmul[^\\n]*<\\d+ x double>|@llvm\\.fma\\.v\\d+f64\\()", ir)))
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stderr
    single, double = map(int, result.stdout.split())
    # the step's products and FMAs: four accelerations per step, each a mass-matrix
    # solve in float32; float64 only for the angles' stage sums and the reductions.
    # A float64 value leaking into the accelerations turns most of them double, so a
    # float32 majority of 2x is the line (as tests/test_float32.py's)
    assert single > 0 and single > 2 * double, (single, double)


@pytest.mark.parametrize("system, kw, message", [
    (sweep.DoublePendulum(), dict(observe=("lyapunov",)), "'lyapunov' is not available in "
                                                          "float32"),
    (sweep.DoublePendulum(pivot_amplitude=0.05, pivot_frequency=40.0), {}, "read the time"),
    (sweep.DoublePendulum(), dict(dtype="float16"), "dtype"),
])
def test_float32_refusals_come_before_compute(system, kw, message, no_compute):
    kw = {"dtype": "float32", **kw}
    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 4), theta2_0=[0.0])
    with pytest.raises(ValueError, match=message):
        sweep.run(system, grid, t_end=1.0, dt=DT, progress=False, **kw)


def test_float32_swing_network_is_refused(no_compute):
    network = sweep.SwingNetwork([[0, 1], [1, 0]], power=[1.0, -1.0], damping=0.1,
                                 coupling=4.0)
    grid = sweep.Grid(perturbed_node=[0.0], delta_theta=[0.1])
    with pytest.raises(ValueError, match=r"float32.*SwingNetwork|SwingNetwork.*float32"):
        sweep.run(network, grid, t_end=1.0, dt=DT, dtype="float32", progress=False)


def test_math_pi_is_float64_in_the_flip_lines():
    """The flip's thresholds (|theta - bottom| against pi) and 2 pi stay float64 in the
    float32 module: a float32 pi is 8.7e-8 above pi, and would move the upright position."""
    from sweep.engine_systems import prepare_system
    from sweep.kernels.source import source

    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 16), theta2_0=np.linspace(-1, 1, 16))
    spec = prepare_system(sweep.DoublePendulum(), grid, t_end=1.0, dt=DT, observe=("flip",),
                          dtype="float32")[1]
    text = source(spec)
    assert "F(math.pi)" not in text and "TWO_PI = 2.0 * math.pi" in text
    assert "* dt_clock" in text  # the flip time on the float64 clock
