"""`sweep.DeclaredSystem`: a system of the user's own declaration, run like the
built-ins, against SciPy's DOP853 and against the built-in double pendulum."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import sweep
from sweep.physics import Coordinate, Parameter, SystemDeclaration
from sweep.physics.systems import double_pendulum

GRAVITY = 9.81  # m/s^2


def cart_declaration(name: str = "test_pendulum_on_cart") -> SystemDeclaration:
    """A unit pendulum (m = l = 1) hanging from a cart of mass 1 held by a spring of
    stiffness ``kc``: T = (2 v^2 + 2 v w cos q + w^2) / 2, V = kc x^2 / 2 - g cos q.
    The cart's position is not an angle."""
    return SystemDeclaration(
        name=name,
        coordinates=(Coordinate("theta", "omega", "q", "w", long_name="pendulum angle"),
                     Coordinate("x", "v", "xc", "vc", units="m", velocity_units="m s-1",
                                long_name="cart position", angular=False)),
        parameters=(Parameter("stiffness", "stiffness", "kc", "kg s-2", "N/m",
                              "the cart's spring constant", minimum=0.0, default=10.0),),
        lagrangian=f"(2*vc**2 + 2*vc*w*cos(q) + w**2)/2 - kc*xc**2/2 + {GRAVITY}*cos(q)")


def cart_rhs(stiffness: float):
    """The same equations by hand: w' + v' cos q = -g sin q and
    2 v' + w' cos q = w^2 sin q - k x, solved for (w', v')."""
    def rhs(_t, y):
        q, x, w, v = y
        c, s = np.cos(q), np.sin(q)
        b1, b2 = -GRAVITY * s, w * w * s - stiffness * x
        det = 2.0 - c * c
        return [w, v, (2.0 * b1 - c * b2) / det, (b2 - c * b1) / det]
    return rhs


def test_a_declared_cart_pendulum_follows_scipy_dop853():
    from scipy.integrate import solve_ivp

    system = sweep.DeclaredSystem(cart_declaration(), stiffness=5.0)
    grid = sweep.Grid(theta_0=np.array([-2.5, 0.3, 1.0]), x_0=np.array([0.0, 0.2]),
                      omega_0=np.array([0.5]), v_0=np.array([-0.3]))
    ds = sweep.run(system, grid, t_end=5.0, dt=1e-3, observe=("final", "energy"),
                   progress=False)
    assert ds.attrs["title"] == "test_pendulum_on_cart parameter sweep"
    assert ds.x_final.attrs["units"] == "m" and "winding" not in ds
    for i, theta0 in enumerate(grid.axes["theta_0"]):
        for j, x0 in enumerate(grid.axes["x_0"]):
            ref = solve_ivp(cart_rhs(5.0), (0.0, 5.0), [theta0, x0, 0.5, -0.3],
                            method="DOP853", rtol=1e-12, atol=1e-12).y[:, -1]
            got = [float(ds[name].values[i, j, 0, 0])
                   for name in ("theta_final", "x_final", "omega_final", "v_final")]
            # RK4 at dt = 1e-3 over 5 s: global error ~ t dt^4 |y^(5)| ~ 1e-10 here
            # (measured 9e-11 at most, Zen 5); 1e-8 leaves two decades of margin and is
            # still far below the effect of any wrong term in the equations (>= 1e-3)
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-8)
    # no damping, no time dependence: the energy T + V is conserved (RK4's relative
    # drift over 5000 steps of 1e-3 measured 2e-11; 1e-9 leaves margin)
    np.testing.assert_allclose(ds.energy_final, ds.energy_initial, rtol=1e-9)


def test_the_double_pendulum_declared_by_the_user_is_the_built_in_bit_for_bit():
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 5), theta2_0=np.linspace(-2.0, 2.0, 4))
    kwargs = {"t_end": 2.0, "dt": 0.01, "observe": ("final", "winding"), "progress": False}
    built_in = sweep.run(sweep.DoublePendulum(mass2=2.0), grid, **kwargs)
    declared = sweep.run(sweep.DeclaredSystem(double_pendulum(), mass2=2.0), grid, **kwargs)
    for name in built_in.data_vars:
        np.testing.assert_array_equal(declared[name].values, built_in[name].values)


def test_a_declared_system_takes_damping_and_pickles():
    system = sweep.DeclaredSystem(cart_declaration(), effects=(sweep.Damping(0.5),))
    assert system.stiffness == 10.0 and system.damping == 0.5  # the default, the effect
    copy = pickle.loads(pickle.dumps(system))
    assert copy == system and hash(copy) == hash(system) and copy is not system
    assert "stiffness=10.0" in repr(system)
    with pytest.raises(AttributeError):
        system.stiffness = 1.0
    assert system.to_dict()["declaration"]["name"] == "test_pendulum_on_cart"


def test_bad_declared_systems_are_refused_before_any_grid_or_compile():
    with pytest.raises(TypeError, match="SystemDeclaration"):
        sweep.DeclaredSystem("pendulum")
    with pytest.raises(ValueError, match=r"unknown parameter 'stifness'.*accepted: stiffness"):
        sweep.DeclaredSystem(cart_declaration(), stifness=1.0)
    with pytest.raises(ValueError, match=r"stiffness.*-1"):
        sweep.DeclaredSystem(cart_declaration(), stiffness=-1.0)
    bare = cart_declaration("test_cart_without_default")
    bare = SystemDeclaration(bare.name, bare.coordinates,
                             (Parameter("stiffness", "stiffness", "kc", "kg s-2", "N/m",
                                        "spring constant", minimum=0.0),), bare.lagrangian)
    with pytest.raises(ValueError, match="no default and was not given"):
        sweep.DeclaredSystem(bare)
    other = SystemDeclaration("test_pendulum_on_cart", cart_declaration().coordinates,
                              cart_declaration().parameters,
                              lagrangian="(2*vc**2 + w**2)/2 - kc*xc**2/2 + cos(q)")
    sweep.DeclaredSystem(cart_declaration())
    with pytest.raises(ValueError, match="another declaration named"):
        sweep.DeclaredSystem(other)
    unknown = SystemDeclaration("test_cart_unknown", cart_declaration().coordinates,
                                cart_declaration().parameters,
                                lagrangian="(2*vc**2 + w**2)/2 - kc*xc**2/2 + mystery*cos(q)")
    with pytest.raises(ValueError, match="mystery"):
        sweep.DeclaredSystem(unknown)


def test_the_explorer_takes_a_declared_system():
    from sweep.explore.systems import SystemExplorer

    grid = sweep.Grid(theta_0=np.linspace(-3, 3, 4), omega_0=np.linspace(-3, 3, 4))
    e = SystemExplorer(sweep.DeclaredSystem(cart_declaration()), grid, resolution=8,
                       t_end=0.1, dt=0.01)  # tests/test_explore_declared.py: its maps
    assert (e.state.view.x, e.state.view.y) == ("theta_0", "omega_0")
    assert [c.name for c in e.parameter_controls()] == ["stiffness", "damping", "x_0", "v_0"]
