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


@pytest.mark.parametrize("system", [
    "sweep.DoublePendulum()",
    # the drives' phases in float64 (sweep.kernels.phases), the rest of the step float32
    "sweep.DoublePendulum(pivot_amplitude=0.05, pivot_frequency=30.0, "
    "effects=(sweep.Forcing(1.0, 3.0, 0.5, on='theta2'),))",
], ids=["free", "driven"])
def test_float32_system_kernel_computes_in_float32_vectors(tmp_path, system):
    """The machine code of the double pendulum's float32 kernel: its step is SIMD float32
    arithmetic (``<N x float>``); float64 vector arithmetic is only the minority kept
    float64 on purpose (the angles' updates, the sine's argument reduction and, when
    driven, the drives' phases). A float64 literal or parameter left in the
    accelerations would make most of the step double. Compiled afresh in a subprocess
    (numba cannot inspect cached code)."""
    script = textwrap.dedent("""
        import re, sys, numpy as np, sweep
        from sweep import kernels
        from sweep.engine_systems import prepare_system
        grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 16), theta2_0=np.linspace(-1, 1, 16))
        spec = prepare_system(eval(sys.argv[1]), grid, t_end=1.0, dt=0.0625,
                              observe=("final",), dtype="float32")[1]
        kernel = kernels.build(spec)
        n = 256
        params = np.zeros((n, len(spec.columns)))
        params[:, 4:] = 1.0
        kernel(params, 0.0, 0.0625, 4, 0, 1, np.empty((n, 4)), np.empty(n, dtype=np.int8),
               np.empty((0, 4, 0)))
        ir = "".join(kernels.compiled(kernel).inspect_llvm().values())
        print(len(re.findall(r"(?:fmul[^\\n]*<\\d+ x float>|@llvm\\.fma\\.v\\d+f32\\()", ir)),
              len(re.findall(r"(?:fmul[^\\n]*<\\d+ x double>|@llvm\\.fma\\.v\\d+f64\\()", ir)))
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", script, system], env=env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    single, double = map(int, result.stdout.split())
    # the step's products and FMAs: four accelerations per step, each a mass-matrix
    # solve in float32; float64 only for the angles' stage sums and the reductions.
    # A float64 value leaking into the accelerations turns most of them double, so a
    # float32 majority of 2x is the line (as tests/test_float32.py's)
    assert single > 0 and single > 2 * double, (single, double)


@pytest.mark.parametrize("system, kw, message", [
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


def test_a_float32_catalogue_samples_the_strobe_steps():
    """In float32 the ``attractor`` observable's drive period in steps (``ca_S``) comes
    from the float64 step, as ``strobe``'s (``sb_S``) does: from the float32 step (which
    differs from dt by up to 6e-8 of it) a period of 2 pi / (nu dt) ~ 1e7 steps could
    round to another count, and the catalogue would match states at other times than
    the samples the docs say it reads."""
    from sweep.engine_systems import prepare_system
    from sweep.kernels.source import system_module

    period = 2 * np.pi / 60.0
    catalogue = {"theta": np.zeros((1, 2, 16)), "omega": np.zeros((1, 2, 16)),
                 "period": np.array([1])}
    spec = prepare_system(sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=60.0),
                          sweep.Grid(theta1_0=np.linspace(-1, 1, 16)), t_end=20 * period,
                          dt=period / 40, observe=("strobe", "attractor"),
                          attractors=catalogue, dtype="float32")[1]
    text = system_module(spec)
    periods = [line.strip() for line in text.splitlines()
               if line.strip().startswith(("sb_S = round(", "ca_S = round("))]
    assert {line[:4] for line in periods} == {"sb_S", "ca_S"}
    assert all(line.endswith("* dt_clock))") for line in periods), periods


# --- dynamics that read the time: the drives' phases in float64 (sweep.kernels.phases) ---

PIVOT = {"m1": 1.2, "m2": 0.8, "l1": 0.9, "l2": 0.7, "c1": 0.3, "c2": 0.2, "a": 0.05,
         "nu": 30.0}
FORCE = (2.0, 3.0, 0.5)  # A [N m], W [rad/s], phase [rad] of Forcing(on="theta2")


def _pivot_system():
    return sweep.DoublePendulum(mass1=1.2, mass2=0.8, length1=0.9, length2=0.7, damping1=0.3,
                                damping2=0.2, pivot_amplitude=0.05, pivot_frequency=30.0)


def _forced_system():
    from test_system_effects import _double

    return _double((sweep.Forcing(*FORCE, on="theta2"),))


def _pivot_rhs(t, y):
    from test_systems import _lagrange

    return _lagrange(t, y, **PIVOT)


def _forced_rhs(t, y):
    from test_system_effects import textbook

    amplitude, frequency, phase = FORCE
    return textbook(t, y, lambda t, y: np.array([0.0, amplitude * np.sin(frequency * t
                                                                          + phase)]))


@pytest.mark.parametrize("make, rhs", [(_pivot_system, _pivot_rhs),
                                       (_forced_system, _forced_rhs)],
                         ids=["driven pivot", "Forcing on theta2"])
def test_float32_driven_systems_against_dop853(make, rhs):
    """A driven pivot (joint damping, a cos(nu t), nu = 30 rad/s) and a
    ``Forcing(2, 3, 0.5, on="theta2")`` on the double pendulum of
    tests/test_system_effects.py, in float32, against Lagrange's equations written out
    in the tests (SciPy's DOP853), over 5 s = 1280 steps of 1/256 s from the three
    regular starts above. The float64 run is within 1e-6 of DOP853 (RK4's error;
    measured 3.4e-7 and 7.5e-8). Rounding, as in the first test: at most N u |y|max =
    1280 * 2**-24 * |y|max (|y|max the largest |angle| or |velocity| on DOP853's
    trajectory, ~0.5 and ~3.5 here) on top of the float64 run's 1e-6 (measured 4.2e-7 and
    5.7e-6 in all)."""
    ds32, ds64 = (sweep.run(make(), _points(STARTS), t_end=5.0, dt=DT / 4, observe=("final",),
                            dtype=dtype, progress=False) for dtype in ("float32", "float64"))
    names = ("theta1_final", "theta2_final", "omega1_final", "omega2_final")
    for k, start in enumerate(STARTS):
        solution = solve_ivp(rhs, (0.0, 5.0), list(start), method="DOP853", rtol=1e-13,
                             atol=1e-13)
        exact, largest = solution.y[:, -1], np.max(np.abs(solution.y))
        got32 = np.array([float(ds32[n].values[k]) for n in names])
        got64 = np.array([float(ds64[n].values[k]) for n in names])
        assert np.max(np.abs(got64 - exact)) < 1e-6
        assert np.max(np.abs(got32 - exact)) < 1e-6 + 1280 * 2.0 ** -24 * largest
        assert np.max(np.abs(got32 - got64)) > 1e-9  # the float32 run is float32


NU = 2 * np.pi  # [rad/s]: a drive period of 1 s = 256 steps of 1/256 s


def _locked(frequency):
    """The damped double pendulum on a pivot a cos(nu t) with a torque A sin(nu t) on
    theta1 (A = 1 N m): from small starts it settles on the periodic orbit the two drives
    impose, a regular attractor."""
    return sweep.DoublePendulum(mass1=1.2, mass2=0.8, length1=0.9, length2=0.7,
                                damping1=0.3, damping2=0.2, pivot_amplitude=0.05,
                                pivot_frequency=frequency,
                                effects=(sweep.Forcing(1.0, frequency, on="theta1"),))


def test_float32_keeps_the_drive_phase_after_ten_thousand_seconds():
    """At t = 1e4 s (2.56e6 steps, 10^4 drive periods) the float32 run's stroboscopic
    samples are the float64 run's. On this damped, locked orbit rounding does not grow:
    the flow forgets a deviation in about 1 / (slowest decay rate) ~ 10 s = 2560 steps,
    so rounding moves the samples by at most ~2560 u |y| = 2560 * 6e-8 * 0.33 ~ 5e-5
    (measured 5.2e-7). A drive phase not kept in float64 drifts instead: nu rounded to
    float32 (2.8e-8 of itself) is 1.7e-3 rad off after 1e4 s; the float64 run with that
    rounded frequency is the teeth of the check (measured 1.1e-3 away, > 10 x the bound).
    The four samples agree with one another to 1e-9 in float64: a period-1 orbit."""
    points = sweep.Points(theta1_0=[0.3, -0.4], theta2_0=[-0.2, 0.3])
    kw = dict(t_end=1e4, dt=DT / 4, t_transient=1e4 - 4, observe=("strobe",),
              strobe_samples=4, progress=False)
    names = ("theta1_strobe", "theta2_strobe", "omega1_strobe", "omega2_strobe")

    def samples(frequency, dtype):
        ds = sweep.run(_locked(frequency), points, dtype=dtype, **kw)
        return np.stack([ds[n].values for n in names])

    reference, single = samples(NU, "float64"), samples(NU, "float32")
    rounded = samples(float(np.float32(NU)), "float64")
    bound = 2560 * 2.0 ** -24 * np.max(np.abs(reference))
    assert np.max(np.abs(reference - reference[..., :1])) < 1e-9
    assert np.max(np.abs(single - reference)) < bound
    assert np.max(np.abs(rounded - reference)) > 10 * bound


def _declared_pair():
    """Two pendula joined by a spring, the first driven through its Lagrangian by a
    torque A cos(2 pi f t + 0.1) [the phase's 2 pi f is hoisted, 0.1 a literal], each
    damped by a joint force -c v."""
    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    parameters = (
        Parameter("friction", "friction", "cf", "s-1", "1/s", "damping", minimum=0.0,
                  default=0.3),
        Parameter("spring", "spring", "kc", "s-2", "1/s^2", "coupling", minimum=0.0,
                  default=0.5),
        Parameter("amplitude", "amplitude", "af", "s-2", "1/s^2", "torque amplitude",
                  minimum=0.0, default=0.8),
        Parameter("frequency", "frequency", "fq", "Hz", "Hz", "drive frequency",
                  minimum=0.0, default=0.33))
    return SystemDeclaration(
        name="spring_pair_driven_in_time",
        coordinates=tuple(Coordinate(f"p{k}", f"v{k}", f"q{k}", f"w{k}") for k in (1, 2)),
        parameters=parameters,
        lagrangian="(w1**2 + w2**2)/2 + cos(q1) + cos(q2) - kc*(q1 - q2)**2/2 "
                   "+ af*q1*cos(2*pi*fq*t + 0.1)",
        forces=("-cf*w1", "-cf*w2"))


def _pair_rhs(t, y, f=0.33):
    """Its equations written out: q_i'' = -sin q_i -+ k (q1 - q2) - c w_i (+ the torque
    on q1)."""
    q1, q2, w1, w2 = y
    return [w1, w2, -np.sin(q1) - 0.5 * (q1 - q2) - 0.3 * w1
            + 0.8 * np.cos(2 * np.pi * f * t + 0.1),
            -np.sin(q2) + 0.5 * (q1 - q2) - 0.3 * w2]


def test_float32_declared_system_in_time_keeps_its_phase():
    """A DeclaredSystem whose Lagrangian reads t, in float32, at t = 5 s against its
    equations by DOP853 (bound as in test_float32_driven_systems_against_dop853: RK4's
    1e-6 plus N u |y|max, N = 640 steps of 1/128 s; measured 2.2e-7), and at t = 1e4 s
    (1.28e6 steps) against the float64 run. Damped (amplitudes decay at c / 2 = 0.15 /s:
    it forgets a deviation in ~7 s ~ 900 steps) and driven, it locks to the drive:
    rounding moves the final state by at most ~900 u |y| (1.5e-5 for |y| = 0.27;
    measured 1.6e-7). The drive's 2 pi f rounded to float32 (as a float32 hoisted value
    would be; f = 0.33 Hz is one whose 2 pi f rounds by 5.3e-8 of itself, near the
    worst) is 1.1e-3 rad off after 1e4 s: the float64 run with that rounded frequency,
    6e-4 away (measured), is the check's teeth."""
    declaration = _declared_pair()
    sweep.DeclaredSystem(declaration)  # registered: its axes name points
    names = ("p1_final", "p2_final", "v1_final", "v2_final")
    starts = sweep.Points(p1_0=[0.3, -0.5], p2_0=[0.1, 0.2])

    def finals(t_end, dtype, frequency=0.33):
        ds = sweep.run(sweep.DeclaredSystem(declaration, frequency=frequency), starts,
                       t_end=t_end, dt=DT / 2, observe=("final",), dtype=dtype,
                       progress=False)
        return np.stack([ds[n].values for n in names], axis=-1)

    short = finals(5.0, "float32")
    for k, start in enumerate([(0.3, 0.1, 0.0, 0.0), (-0.5, 0.2, 0.0, 0.0)]):
        solution = solve_ivp(_pair_rhs, (0.0, 5.0), start, method="DOP853", rtol=1e-13,
                             atol=1e-13)
        bound = 1e-6 + 640 * 2.0 ** -24 * np.max(np.abs(solution.y))
        assert np.max(np.abs(short[k] - solution.y[:, -1])) < bound
    reference, single = finals(1e4, "float64"), finals(1e4, "float32")
    rounded = finals(1e4, "float64", float(np.float32(2 * np.pi * 0.33)) / (2 * np.pi))
    bound = 900 * 2.0 ** -24 * np.max(np.abs(reference))
    assert np.max(np.abs(single - reference)) < bound
    assert np.max(np.abs(rounded - reference)) > 10 * bound


def test_the_phases_and_what_they_read_are_float64_the_rest_float32():
    """`sweep.kernels.phases` on a float32 physics function: the phase of ``vcos`` reads
    a hoisted 2 pi f (recomputed in float64 in place of its float32 read, with the
    hoisted value it reads in turn), a literal (float64 again) and the time; a temporary
    ``f t`` that the phase of ``vsin`` reads is float64, and read elsewhere it is rounded
    once, ``F(x0)``; ``vsin(q1)`` reads no time and is left alone, and so is every line
    that needs no change."""
    from sweep.kernels.phases import find, float64_function

    hoisted = ["x5 = m * m", "x1 = af * x5", "x6 = 2.0 * math.pi", "x2 = x6 * fq"]
    lines = ["x1 = hoisted_values[0, j]", "x2 = hoisted_values[1, j]", "x0 = fq * t",
             "x3 = F(0.3) * x0", "x4 = vfma(x1, vcos(vfma(x2, t, F(0.1))), vsin(x0))",
             "acc = vfma(x4, m, x3 - vsin(q1))", "return acc"]
    parameters = {"m", "af", "fq"}
    phases = find([lines], hoisted, parameters)
    assert phases.parameters == {"fq"}
    assert phases.hoisted == ("x6 = 2.0 * math.pi", "x2 = x6 * fq")
    assert float64_function(lines, phases.hoisted, phases.parameters) == [
        "x1 = hoisted_values[0, j]", "x6 = 2.0 * math.pi", "x2 = x6 * fq", "x0 = fq * t",
        "x3 = F(0.3) * F(x0)", "x4 = vfma(x1, vcos(vfma(x2, t, 0.1)), vsin(x0))",
        "acc = vfma(x4, m, x3 - vsin(q1))", "return acc"]


def test_a_float64_value_read_outside_a_phase_is_rounded_once():
    """A drive frequency read by a phase and also as a factor (``fq * w1``), and the time
    read outside any sine: both rounded to float32 there, so that the acceleration
    stays float32 arithmetic."""
    from sweep.kernels.phases import float64_function

    lines = ["x0 = vsin(fq * t)", "acc = F(0.5) * fq * w1 + x0 * t", "return acc"]
    assert float64_function(lines, (), {"fq"}) == [
        "x0 = vsin(fq * t)", "acc = F(0.5) * F(fq) * w1 + x0 * F(t)", "return acc"]


# --- lyapunov in float32: the state float32, the tangent vector float64 ---

def test_float32_lyapunov_follows_the_float32_trajectory_and_matches_dop853():
    """Three starts of tests/test_systems.py (one regular, two chaotic), 5 s in steps of
    1 ms. The tangent dynamics read the accelerations' own statements, so the state of
    the float32 lyapunov run is the plain float32 run's bit for bit (chaotic starts: one
    differing ulp would show). The regular start's exponent against Benettin's method
    on DOP853's variational equations (tests/test_systems.py): the float64 run is within
    1e-9 of it there (measured 3e-12); rounding moves log|d(T)| by at most ~N u on a
    regular orbit (each step's Jacobian read at a state rounded by ~u relative, the
    tangent float64), so the exponent log|d(T)| / T by N u / T = 5000 * 2**-24 / 5 = 6e-5
    (measured 1.4e-7). The chaotic starts' exponents are those of float32 trajectories
    that depart from the exact one within seconds: only their size is asserted."""
    from test_systems import _variational

    starts = [(0.1, 0.1, 0.0, 0.0), (2.0, 2.5, 0.0, 0.0), (3.0, 1.0, 0.0, 0.0)]
    kw = dict(t_end=5.0, dt=0.001, dtype="float32", progress=False)
    tangent = sweep.run(sweep.DoublePendulum(), _points(starts), observe=("final", "lyapunov"),
                        **kw)
    plain = sweep.run(sweep.DoublePendulum(), _points(starts), observe=("final",), **kw)
    for name in ("theta1_final", "theta2_final", "omega1_final", "omega2_final"):
        assert tangent[name].values.tobytes() == plain[name].values.tobytes(), name
    z = solve_ivp(_variational, (0.0, 5.0), list(starts[0]) + [0.5] * 4, method="DOP853",
                  rtol=1e-13, atol=1e-13).y[:, -1]
    reference = np.log(np.linalg.norm(z[4:])) / 5.0
    exponents = tangent.lyapunov_max.values
    assert abs(exponents[0] - reference) < 1e-9 + 5000 * 2.0 ** -24 / 5.0
    assert exponents[0] < 0.2 < 1.0 < min(exponents[1:])  # regular, then chaotic


def _forced_lyapunov(amplitude, frequency, dtype):
    """The largest exponent of the damped double pendulum (c = 0.3 /s at both joints)
    with a torque A sin(W t) on theta1, from 64 starts, over 250 s after 50 s."""
    system = sweep.DoublePendulum(damping1=0.3, damping2=0.3,
                                  effects=(sweep.Forcing(amplitude, frequency, on="theta1"),))
    grid = sweep.Grid(theta1_0=np.linspace(-1, 1, 8), theta2_0=np.linspace(-1, 1, 8))
    return sweep.run(system, grid, t_end=300.0, dt=0.01, t_transient=50.0,
                     observe=("lyapunov",), dtype=dtype,
                     progress=False).lyapunov_max.values.ravel()


def test_float32_lyapunov_of_a_driven_system_is_float64s():
    """A driven system's exponents in float32 (the drive's phase float64, the Jacobian
    float32, the tangent vector float64) against float64's, on two attractors.

    A = 8 N m, W = 1.5 rad/s: a periodic attractor (exponent ~ -0.03 /s). Rounding does
    not accumulate on it: each step changes log|d| by ~u through the Jacobian's rounding
    and ~u through the state's (a deviation the orbit contracts), so the exponent moves
    by at most ~2 u / dt = 1.2e-5 /s (measured 9e-8), at every start.

    A = 15 N m, W = 3 rad/s: a chaotic attractor (exponent ~ 0.92 /s). Float32 and
    float64 trajectories part within seconds, but the exponent is the attractor's: the
    two means over 64 starts are two samples of it, whose difference has a standard
    error of sqrt(2) std / sqrt(64) (std ~ 0.057 /s, float64's spread over the starts):
    asserted within 3 standard errors (measured 0.013 against 0.030)."""
    regular32, regular64 = (_forced_lyapunov(8.0, 1.5, d) for d in ("float32", "float64"))
    assert np.all(regular64 < -0.02)
    assert np.max(np.abs(regular32 - regular64)) < 2 * 2.0 ** -24 / 0.01
    chaotic32, chaotic64 = (_forced_lyapunov(15.0, 3.0, d) for d in ("float32", "float64"))
    assert chaotic64.mean() > 0.5
    error = np.sqrt(2) * chaotic64.std() / np.sqrt(chaotic64.size)
    assert abs(chaotic32.mean() - chaotic64.mean()) < 3 * error


def test_a_hoisted_pair_read_by_a_phase_is_recomputed_once():
    """A hoisted ``x7, x8 = vsincos(ph)`` whose sine a phase reads: the statement is
    recomputed once in place of both reads (x8 is then the recomputed value, read as
    ``F(x8)`` outside the phase)."""
    from sweep.kernels.phases import find, float64_function

    hoisted = ["x7, x8 = vsincos(ph)", "x9 = x7 * fq"]
    lines = ["x7 = hoisted_values[0, j]", "x8 = hoisted_values[1, j]",
             "y = vsin(x7 * t) + x8 * w", "return y"]
    phases = find([lines], hoisted, {"ph", "fq"})
    assert phases.parameters == {"ph"} and phases.hoisted == ("x7, x8 = vsincos(ph)",)
    assert float64_function(lines, phases.hoisted, phases.parameters) == [
        "x7, x8 = vsincos(ph)", "y = vsin(x7 * t) + F(x8) * w", "return y"]
