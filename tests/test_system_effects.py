"""Effects on one coordinate of a system (``sweep.Damping(c, on="theta1")``,
``sweep.Torque(tau, on=...)``, ``sweep.Forcing(A, W, on=...)``): generalized forces Q
in ``M(q) q'' = F + Q``, checked against oracles written out here (not read from
sweep): the textbook double pendulum plus ``M^-1 Q`` solved by SciPy's DOP853, a static
deflection computed by hand, and the energy balance ``dE/dt = Q . v``.

Tolerances: RK4's global error is C dt^4; the same case at dt and dt/2 differs by
D = (15/16) C dt^4, so ``2 D`` bounds the dt run's error with room for higher-order
terms (as in tests/test_systems.py). DOP853 at rtol = atol = 1e-13 adds ~1e-12.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp
from test_systems import textbook as free_textbook

import sweep

G = 9.81
M1, M2, L1, L2 = 1.2, 0.8, 1.0, 0.7


def textbook(t, y, q_force):
    """The double pendulum (absolute angles) in the textbook closed form
    (`test_systems.textbook`, myphysicslab's "Double Pendulum"), plus the generalized
    forces ``q_force(t, y)`` through the mass matrix of ``T = (m1 + m2) l1^2 w1^2 / 2 +
    m2 l2^2 w2^2 / 2 + m2 l1 l2 w1 w2 cos(th1 - th2)``."""
    th1, th2, w1, w2 = y
    d = th1 - th2
    _, _, a1, a2 = free_textbook(t, y, M1, M2, L1, L2, G)
    mass = np.array([[(M1 + M2) * L1 ** 2, M2 * L1 * L2 * np.cos(d)],
                     [M2 * L1 * L2 * np.cos(d), M2 * L2 ** 2]])
    extra = np.linalg.solve(mass, q_force(t, y))
    return [w1, w2, a1 + extra[0], a2 + extra[1]]


def _double(effects=()):
    return sweep.DoublePendulum(mass1=M1, mass2=M2, length1=L1, length2=L2, gravity=G,
                                effects=effects)


STARTS = [(0.3, -0.2, 0.0, 0.0), (2.0, 1.0, 0.5, -0.5), (1.0, 2.5, 0.0, 1.0)]
FINAL = ("theta1_final", "theta2_final", "omega1_final", "omega2_final")


def _points(starts):
    return sweep.Points(theta1_0=[s[0] for s in starts], theta2_0=[s[1] for s in starts],
                        omega1_0=[s[2] for s in starts], omega2_0=[s[3] for s in starts])


def _finals(ds):
    return np.stack([ds[name].values for name in FINAL], axis=-1)


def _check_against_dop853(system, q_force, t_end=2.0, dt=0.002, floor=1e-11):
    coarse = _finals(sweep.run(system, _points(STARTS), t_end=t_end, dt=dt,
                               observe=("final",)))
    fine = _finals(sweep.run(system, _points(STARTS), t_end=t_end, dt=dt / 2,
                             observe=("final",)))
    reference = np.array([solve_ivp(textbook, (0.0, t_end), list(s), method="DOP853",
                                    rtol=1e-13, atol=1e-13, args=(q_force,)).y[:, -1]
                          for s in STARTS])
    tol = 2 * np.abs(coarse - fine) + floor  # 2 D (module docstring) + DOP853's error
    assert np.all(tol < 1e-6), "dt resolves the motion, so the bound means something"
    np.testing.assert_array_less(np.abs(coarse - reference), tol)
    # the force changes the motion by far more than the tolerance: the check has teeth
    free = np.array([solve_ivp(textbook, (0.0, t_end), list(s), method="DOP853",
                               rtol=1e-13, atol=1e-13, args=(lambda t, y: np.zeros(2),)
                               ).y[:, -1] for s in STARTS])
    assert np.max(np.abs(free - reference)) > 1e-2


def test_joint_damping_on_theta1_alone_matches_dop853():
    """``Damping(c, on="theta1")`` is the generalized force ``Q = (-c omega1, 0)``: a
    damping torque at the pivot alone, which slows the second rod too, through M."""
    c = 0.6
    _check_against_dop853(_double((sweep.Damping(c, on="theta1"),)),
                          lambda t, y: np.array([-c * y[2], 0.0]))


def test_torque_forcing_and_mass_proportional_damping_combine():
    """A torque on theta1, a forcing on theta2 and the mass-proportional damping
    (``Damping(c)`` without on=, unchanged: every acceleration gains ``- c v_i``, the
    generalized force ``- c M v``)."""
    tau, amplitude, frequency, phase, c = 0.7, 2.0, 3.0, 0.5, 0.1

    def q_force(t, y):
        th1, th2, w1, w2 = y
        mass = np.array([[(M1 + M2) * L1 ** 2, M2 * L1 * L2 * np.cos(th1 - th2)],
                         [M2 * L1 * L2 * np.cos(th1 - th2), M2 * L2 ** 2]])
        return np.array([tau, amplitude * np.sin(frequency * t + phase)]) \
            - c * mass @ np.array([w1, w2])

    _check_against_dop853(_double((sweep.Torque(tau, on="theta1"),
                                   sweep.Forcing(amplitude, frequency, phase, on="theta2"),
                                   sweep.Damping(c))), q_force)


def test_quadratic_drag_on_theta2_matches_dop853():
    """``QuadraticDrag(k, on="theta2")`` is ``Q = (0, -k omega2 |omega2|)``."""
    k = 0.4
    # -k v|v| is not twice differentiable at v = 0, so the steps across a zero of
    # omega2 (a few in 2 s, for RK4 and DOP853 alike) are not of the methods' order and
    # 2 D does not bound them exactly (measured: 5e-11 beyond 2 D at one start); 1e-9
    # covers them with room, far below the drag's effect (> 1e-2)
    _check_against_dop853(_double((sweep.QuadraticDrag(k, on="theta2"),)),
                          lambda t, y: np.array([0.0, -k * y[3] * abs(y[3])]), floor=1e-9)


def test_the_jacobian_with_drag_matches_central_differences():
    """The derived Jacobian (the tangent dynamics of ``lyapunov``) with a drag on
    theta2 and a damping on theta1: the drag's ``d/dv (-k v |v|) = -2 k |v|`` written
    without a sign function. Central differences with h = 1e-5 err by ~h^2 |f'''| +
    1e-16 |f| / h, ~1e-9 of the largest entry (no sampled velocity is within h of 0,
    where |v| has a kink); 1e-7 leaves room, and a missing or wrong drag term is off by
    O(k)."""
    system = _double((sweep.Damping(0.3, on="theta1"), sweep.QuadraticDrag(0.4, on="theta2")))
    derived = system.derived(jacobian=True)
    declaration = system.declaration_with_effects
    rng = np.random.default_rng(35)
    values = {"t": 0.0, **{p.symbol: getattr(system, p.axis)
                           for p in system.declaration.parameters},
              "c_th1": 0.3, "kd_th2": 0.4}
    state = ["th1", "th2", "om1", "om2"]
    for symbol in state:
        values[symbol] = rng.uniform(-2.0, 2.0, 50)
    assert np.min(np.abs(values["om2"])) > 1e-3

    def run(lines, at):
        names = dict(at, vsin=np.sin, vcos=np.cos, vsincos=lambda x: (np.sin(x), np.cos(x)))
        exec("\n".join(lines), names)
        return names

    def accel(at):
        names = run(derived.accel_lines, at)
        return np.array([names["acc_th1"], names["acc_th2"]])

    got = run(derived.accel_lines + derived.jacobian_lines, values)
    assert not any("sign" in line for line in derived.jacobian_lines)
    assert [p.symbol for p in declaration.parameters][-2:] == ["c_th1", "kd_th2"]
    h = 1e-5
    for z in state:
        up, down = dict(values), dict(values)
        up[z], down[z] = values[z] + h, values[z] - h
        expected = (accel(up) - accel(down)) / (2 * h)
        for i, a in enumerate(("th1", "th2")):
            entry = np.broadcast_to(got[f"jac_{a}_{z}"], expected[i].shape)
            np.testing.assert_allclose(entry, expected[i], rtol=0,
                                       atol=1e-7 * np.max(np.abs(expected)))


def test_a_grid_axis_sweeps_the_damping_of_one_coordinate():
    """``damping_theta2`` as a grid axis switches ``Damping(0, on="theta2")`` on and
    sets its coefficient per row: each row equals the run with that coefficient given
    (the same kernel, the same arithmetic: bit for bit)."""
    values = [0.0, 0.5]
    grid = sweep.Grid(theta1_0=[1.0], damping_theta2=values)
    swept = sweep.run(_double(), grid, t_end=1.0, dt=0.01, observe=("final",))
    assert swept.damping_theta2.attrs["units"] == "kg m2 s-1"
    for k, c in enumerate(values):
        one = sweep.run(_double((sweep.Damping(c, on="theta2"),)),
                        sweep.Grid(theta1_0=[1.0]), t_end=1.0, dt=0.01, observe=("final",))
        for name in FINAL:
            np.testing.assert_array_equal(swept[name].values[0, k], one[name].values[0])
    assert swept.theta2_final.values[0, 0] != swept.theta2_final.values[0, 1]


def test_a_torque_on_one_coupled_pendulum_gives_the_static_deflection():
    """Two pendula (m, l) joined by a torsion spring kappa, a torque tau on the first:
    at rest ``m g l sin th1 + kappa (th1 - th2) = tau`` and ``m g l sin th2 =
    kappa (th1 - th2)``. Chosen th2* = 0.1: th1* = th2* + m g l sin(th2*) / kappa and
    tau = m g l (sin th1* + sin th2*) (by hand, exact). Damped at each pivot (the
    generalized forces ``-c omega_i``, decay rate c / (2 m l^2) = 2/s), from rest
    hanging, both settle there: after 40 s the transient is e^-80 of its start, so
    what is left is rounding (1e-9 rad leaves room for it)."""
    m, length, kappa, c = 1.0, 1.0, 2.0, 4.0
    th2 = 0.1
    th1 = th2 + m * G * length * math.sin(th2) / kappa
    tau = m * G * length * (math.sin(th1) + math.sin(th2))
    system = sweep.CoupledPendula(2, mass=m, length=length, gravity=G, coupling=kappa,
                                  kind="torsion",
                                  effects=(sweep.Torque(tau, on="theta1"),
                                           sweep.Damping(c, on="theta1"),
                                           sweep.Damping(c, on="theta2")))
    ds = sweep.run(system, sweep.Points(theta1_0=[0.0]), t_end=40.0, dt=0.01,
                   observe=("final",))
    assert float(ds.theta1_final[0]) == pytest.approx(th1, abs=1e-9)
    assert float(ds.theta2_final[0]) == pytest.approx(th2, abs=1e-9)
    assert abs(float(ds.omega1_final[0])) < 1e-9


def _energy(th1, th2, w1, w2):
    """T + V of the double pendulum (V = 0 hanging at rest), written out here."""
    kinetic = ((M1 + M2) * L1 ** 2 * w1 ** 2 / 2 + M2 * L2 ** 2 * w2 ** 2 / 2
               + M2 * L1 * L2 * w1 * w2 * np.cos(th1 - th2))
    potential = (M1 + M2) * G * L1 * (1 - np.cos(th1)) + M2 * G * L2 * (1 - np.cos(th2))
    return kinetic + potential


def _balance(c: float, dt: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The energy along a saved trajectory (every step) with ``Damping(c, on="theta1")``,
    and ``E(t) - E(0) + c int_0^t omega1^2`` (Simpson) every 0.4 s; and the kernel's
    final energy."""
    ds = sweep.run(_double((sweep.Damping(c, on="theta1"),)),
                   sweep.Points(theta1_0=[2.0], theta2_0=[-1.0], omega2_0=[1.0]),
                   t_end=4.0, dt=dt, save_every=1, observe=("final", "energy"))
    th1, th2, w1, w2 = (ds[name].values[0] for name in ("theta1", "theta2", "omega1",
                                                         "omega2"))
    energy = _energy(th1, th2, w1, w2)
    time, stride = ds.time.values, round(0.4 / dt)  # an even number of Simpson panels
    dissipated = np.array([-c * simpson(w1[:k + 1] ** 2, x=time[:k + 1])
                           for k in range(stride, len(time), stride)])
    return energy, energy[stride::stride] - energy[0] - dissipated, float(ds.energy_final[0])


def test_damping_on_one_coordinate_dissipates_energy_at_minus_c_omega1_squared():
    """With only ``Damping(c, on="theta1")`` the energy falls monotonically at the rate
    ``dE/dt = Q . v = -c omega1^2``: on a saved trajectory (every step), ``E(t) - E(0)``
    equals ``-c`` times Simpson's integral of ``omega1^2``, to RK4's accuracy (the
    residual falls ~16x per halving of dt)."""
    c = 0.3
    energy, coarse, final = _balance(c, 0.002)
    _, fine, _ = _balance(c, 0.001)
    # the kernel's energy observable is the same energy (to rounding of its terms)
    assert final == pytest.approx(energy[-1], abs=1e-12)
    # monotonic: a step never gains energy, beyond RK4's local error (~dt^5 |E^(5)|,
    # 1e-13 here) and rounding
    assert np.max(np.diff(energy)) < 1e-11
    assert energy[-1] < 0.8 * energy[0]  # a third of it dissipated over the run
    # measured: 7e-8 J at dt = 0.002 of an energy of 30 J (RK4's C dt^4 and Simpson's
    # h^4 error), 3e-9 at dt = 0.001; a wrong rate (-c omega2^2, or the mass-proportional
    # -c v.Mv) misses by > 1 J
    assert np.max(np.abs(coarse)) < 2e-7
    # order 4: 16x per halving (21x measured); 10x leaves room for the h^5 terms
    assert np.max(np.abs(fine)) < np.max(np.abs(coarse)) / 10


def test_cuda_kernel_with_effects_agrees_with_the_cpu_kernel():
    """device="cuda" (numba's CUDA simulator on CI) runs the same derived source, drag's
    ``abs`` included. CUDA's sine is not sweep's polynomial, so the results agree to
    rounding (measured 2e-14 over these 200 steps; 1e-10 leaves room, while a missing
    or different force is off by far more than 1e-3)."""
    system = _double((sweep.QuadraticDrag(0.3, on="theta2"), sweep.Torque(0.5, on="theta1"),
                      sweep.Forcing(1.0, 2.0, on="theta2")))
    starts = STARTS + [(-2.5, 2.9, 0.0, 0.0)]
    kwargs = dict(t_end=2.0, dt=0.01, observe=("final", "energy", "lyapunov"))
    cpu = sweep.run(system, _points(starts), **kwargs)
    gpu = sweep.run(system, _points(starts), device="cuda", **kwargs)
    for name in FINAL + ("energy_final", "lyapunov_max"):
        np.testing.assert_allclose(gpu[name].values, cpu[name].values, rtol=0, atol=1e-10)


def test_effects_on_a_declared_systems_coordinate_that_is_not_an_angle():
    """A cart's position x (in m) takes a force in N: ``Torque(f, on="x")`` [N] holds
    the cart's spring at ``kc x = f`` at rest; its units are the coordinate's."""
    from sweep.physics import Coordinate, Parameter, SystemDeclaration

    declaration = SystemDeclaration(
        name="test_effects_cart",
        coordinates=(Coordinate("x", "v", "xc", "vc", units="m", velocity_units="m s-1",
                                angular=False),),
        parameters=(Parameter("stiffness", "stiffness", "kc", "kg s-2", "N/m",
                              "spring constant", minimum=0.0, default=4.0),),
        lagrangian="2*vc**2/2 - kc*xc**2/2")
    system = sweep.DeclaredSystem(declaration, effects=(sweep.Torque(2.0, on="x"),
                                                        sweep.Damping(3.0, on="x")))
    ds = sweep.run(system, sweep.Points(x_0=[0.0]), t_end=30.0, dt=0.01, observe=("final",))
    # decay rate c / (2 m) = 0.75/s: e^-22 after 30 s
    assert float(ds.x_final[0]) == pytest.approx(2.0 / 4.0, abs=1e-8)
    assert ds.attrs["effects"] == "damping_x torque_x"
    assert json.loads(ds.attrs["system"])["effects"][0]["on"] == "x"
    grid = sweep.Grid(x_0=[0.0], damping_x=[1.0])
    assert sweep.run(system, grid, t_end=0.1, dt=0.01).damping_x.attrs["units"] == "kg s-1"


def test_effects_without_on_read_as_before():
    """``Damping(c)`` alone on a system is still the mass-proportional damping (the
    ``damping`` axis), and an effect's repr shows ``on`` only when given."""
    assert repr(sweep.Damping(0.1)) == "Damping(coefficient=0.1)"
    assert repr(sweep.Torque(1.0, on="theta2")) == "Torque(value=1.0, on='theta2')"
    assert sweep.Damping(0.1) != sweep.Damping(0.1, on="theta1")
    assert _double((sweep.Damping(0.1),)).columns(True)[-1] == "damping"
    a = _double((sweep.Damping(0.1, on="theta2"), sweep.Torque(1.0, on="theta1")))
    b = _double((sweep.Torque(1.0, on="theta1"), sweep.Damping(0.1, on="theta2")))
    assert a == b and hash(a) == hash(b)  # canonical order of the effects


def test_sympy_missing_is_said_for_an_effect_on_a_coordinate(monkeypatch):
    from sweep.physics import derive as derive_module

    def no_sympy():
        raise ImportError("deriving a system's equations needs SymPy: pip install sympy")

    monkeypatch.setattr(derive_module, "_sympy", no_sympy)
    monkeypatch.setattr(derive_module, "_folder", lambda: None)  # no disk cache
    derive_module.derive.cache_clear()
    try:
        system = sweep.CoupledPendula(3, effects=(sweep.Torque(0.5, on="theta3"),))
        with pytest.raises(ImportError, match=r"Torque\(value=0.5, on='theta3'\): an "
                                              "effect on one coordinate changes the "
                                              r"equations.*needs SymPy"):
            sweep.run(system, sweep.Grid(theta1_0=[0.1]), t_end=1.0, dt=0.1)
        # without one, the shipped derivation needs no SymPy
        sweep.CoupledPendula(3).derived()
    finally:
        derive_module.derive.cache_clear()


def _vee():
    """A declaration whose abs has a derivative that is not paired with its argument
    (the force -sign(x) of the potential |x|): refused (abs serves a drag)."""
    from sweep.physics import Coordinate, SystemDeclaration

    return SystemDeclaration(
        name="test_effects_vee", parameters=(), lagrangian="vc**2/2 - abs(xc)",
        coordinates=(Coordinate("x", "v", "xc", "vc", units="m", velocity_units="m s-1",
                                angular=False),))


@pytest.mark.parametrize("make, match", [
    (lambda: _double((sweep.Damping(0.1, on="theta3"),)),
     r"acts on 'theta3', which is not a coordinate of DoublePendulum; accepted: on= one "
     "of 'theta1', 'theta2'"),
    (lambda: sweep.Scene(effects=(sweep.Damping(0.1, on="theta"),)),
     "a sweep.Scene has one coordinate, theta, that every effect acts on"),
    (lambda: _double((sweep.Torque(1.0),)), r"without on=.*Torque\(..., on=...\) with on "
                                            "one of 'theta1', 'theta2'"),
    (lambda: _double((sweep.Damping(0.1, on="theta1"), sweep.Damping(0.2, on="theta1"))),
     "Damping on 'theta1' twice"),
    (lambda: _double((sweep.PivotDrive(0.1, 1.0),)), "accepts the effects"),
    (lambda: sweep.Damping(0.1, on=1), r"Damping.on=1 is not accepted"),
    (lambda: sweep.Damping(-0.1, on="theta1"), "Damping.coefficient"),
    (lambda: sweep.Grid(damping_theta1=[-1.0]), r"grid axis 'damping_theta1' has value "
                                                r"-1.0 at index 0; accepted: finite numbers "
                                                r">= 0 \(N m s on an angle\)"),
    (lambda: sweep.run(_double(), sweep.Grid(torque_theta2=[1.0]), t_end=1, dt=0.1),
     r"grid axis 'torque_theta2' needs a sweep.Torque\(value, on='theta2'\) in the "
     "effects of DoublePendulum"),
    (lambda: sweep.run(_double(), sweep.Grid(damping_theta3=[1.0]), t_end=1, dt=0.1),
     "grid axis 'damping_theta3' names 'theta3', which is not a coordinate of "
     "DoublePendulum; accepted: damping_<coordinate> with a coordinate among theta1, "
     "theta2"),
    (lambda: sweep.run(sweep.Scene(), sweep.Grid(damping_theta1=[1.0]), t_end=1, dt=0.1),
     "is a system's, not the single pendulum's"),
    (lambda: sweep.DeclaredSystem(_vee()), r"the derived equations hold sign\(xc\), which "
                                           "the kernels cannot evaluate"),
])
def test_bad_effects_are_refused_before_any_compute(make, match):
    with pytest.raises((ValueError, TypeError), match=match):
        make()


def test_a_run_file_takes_effects_on_coordinates():
    """``[system.<effect>]`` with ``on``, or ``[[system.<effect>]]`` one per coordinate;
    ``[system.damping]`` without ``on`` stays the mass-proportional damping."""
    from sweep.toml_spec import parse_run

    spec = {"system": {"kind": "CoupledPendula", "n": 3,
                       "damping": [{"coefficient": 0.1}, {"coefficient": 0.2, "on": "theta1"}],
                       "torque": {"value": 0.5, "on": "theta3"}},
            "grid": {"theta1_0": [0.1, 0.2], "damping_theta2": [0.0, 0.3]},
            "run": {"t_end": 1.0, "dt": 0.1}}
    system, grid, _ = parse_run(spec)
    assert system == sweep.CoupledPendula(3, effects=(
        sweep.Damping(0.1), sweep.Damping(0.2, on="theta1"), sweep.Torque(0.5, on="theta3")))
    assert grid.dims == ("theta1_0", "damping_theta2")
    spec["system"]["torque"] = {"value": 0.5, "coordinate": "theta3"}
    with pytest.raises(ValueError, match=r"run.toml: \[system\] unknown key 'coordinate' "
                                         r"in \[system.torque\]; accepted: value, on"):
        parse_run(spec, source="run.toml")
