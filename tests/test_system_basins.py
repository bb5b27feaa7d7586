"""`sweep.maps.basins` of driven systems with several coordinates, from the
stroboscopic samples of every coordinate (``observe=("strobe",)``), checked against
oracles: two uncoupled forced pendula declared as one system must have the product of
the single pendulum's own basins (computed by `sweep.maps.basins` on `sweep.Scene`), and
a damped double pendulum whose drive has no amplitude must send every start, whatever
its turns, to the one rest state.
"""

import numpy as np
import pytest
from test_system_strobe import _two_forced_pendula

import sweep
from sweep import maps
from sweep.physics import Coordinate, Parameter, SystemDeclaration

#: Damped, forced pendulum (g/L = 1) with two coexisting period-1 librations, a small
#: and a large one (found by a scan of sweep.maps.basins on theta0 in [-pi, pi]).
C, A, W = 0.15, 0.3, 0.75
PERIOD = 2 * np.pi / W
#: 44 transient periods: the slower libration's distance shrinks by ~exp(-c t / 2), to
#: ~1e-12 after 370 s, far inside basins' tol = 1e-3; then 16 samples.
RUN = dict(t_end=60 * PERIOD, dt=PERIOD / 100, t_transient=44 * PERIOD,
           observe=("strobe",), progress=False)
STARTS = np.linspace(-2.5, 2.5, 15)


def test_two_uncoupled_forced_pendula_have_the_product_of_the_pendulums_basins():
    """Each coordinate of the declared system obeys the pendulum's equation alone, so
    the system's attractors are the pairs of the pendulum's and a start (a, b) lies in
    the basin of the pair (label(a), label(b)): the system's labels must be a one-to-one
    function of the pairs of the pendulum's labels, with the pendulum's attractor
    points per coordinate. Exact label agreement: the two kernels' arithmetic differ by
    rounding only (the forcing A cos(W t) written as the declaration's cos, the scene's
    sin(W t + pi/2)), and none of these 15 starts lies within rounding of a basin
    boundary (else the pendulum's run at dt / 2 would disagree too; checked below)."""
    scene = sweep.Scene(gravity=1.0, length=1.0, effects=(
        sweep.Damping(C), sweep.Forcing(A, W, np.pi / 2)))
    single = maps.basins(sweep.run(scene, sweep.Grid(theta0=STARTS, omega0=[0.0]), **RUN))
    label = single.values[:, 0]
    half = maps.basins(sweep.run(scene, sweep.Grid(theta0=STARTS, omega0=[0.0]),
                                 **dict(RUN, dt=PERIOD / 200)))
    np.testing.assert_array_equal(half.values[:, 0], label)  # no start on a boundary
    assert len(single.attrs["attractor_period"]) == 2 and (label >= 0).all()

    system = sweep.DeclaredSystem(_two_forced_pendula(Coordinate, Parameter, SystemDeclaration),
                                  drive_frequency_axis="frequency", friction=C,
                                  amplitude=A, frequency=W)
    both = maps.basins(sweep.run(system, sweep.Grid(p1_0=STARTS, p2_0=STARTS), **RUN))
    assert both.dims == ("p1_0", "p2_0")
    pairs = {}
    for i, a in enumerate(label):
        for j, b in enumerate(label):
            pairs.setdefault((a, b), set()).add(int(both.values[i, j]))
    assert all(len(found) == 1 for found in pairs.values())      # a function of the pair
    image = [found.pop() for found in pairs.values()]
    assert sorted(image) == list(range(4)) == sorted(set(image))  # one-to-one, 4 basins
    for (a, b), system_label in zip(pairs, image):
        for name, k in (("p1", a), ("p2", b)):
            np.testing.assert_allclose(both.attrs[f"attractor_{name}"][system_label],
                                       single.attrs["attractor_theta"][k], atol=1e-6)
        np.testing.assert_allclose(both.attrs["attractor_v2"][system_label],
                                   single.attrs["attractor_omega"][b], atol=1e-6)
    np.testing.assert_array_equal(both.attrs["attractor_period"], [1, 1, 1, 1])
    np.testing.assert_array_equal(both.attrs["attractor_turns_per_period_p1"], np.zeros(4))
    # the sizes: the product of the pendulum's
    sizes = np.bincount(label, minlength=2)
    for (a, b), system_label in zip(pairs, image):
        assert both.attrs["attractor_size"][system_label] == sizes[a] * sizes[b]


def test_a_damped_double_pendulum_without_drive_rests_in_one_basin():
    """A pivot drive of zero amplitude (the undamped equations unchanged), sampled once a
    second: mass-proportional damping c = 0.5 takes every start, after however many
    turns, to rest hanging down, theta = 2 pi k per angle; modulo 2 pi that is one
    attractor, the state (0, 0, 0, 0). Over 64 s of transient a start's distance from
    rest shrinks by ~exp(-c t / 2) ~ 1e-7 (well inside tol = 1e-3: one basin), and the
    catalogued point is within 1e-5 of rest (exp(-0.25 * 64) ~ 1e-7 times speeds of
    ~10 rad/s)."""
    system = sweep.DoublePendulum(pivot_amplitude=0.0, pivot_frequency=2 * np.pi,
                                  effects=(sweep.Damping(0.5),))
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 5), omega2_0=np.linspace(-12, 12, 5))
    ds = sweep.run(system, grid, t_end=80.0, dt=0.01, t_transient=64.0,
                   observe=("winding", "strobe"), progress=False)
    assert (ds.winding_theta2 != 0).any()  # some rested in other wells than they started
    found = maps.basins(ds)
    np.testing.assert_array_equal(found.values, np.zeros((5, 5)))
    assert found.attrs["attractor_size"].tolist() == [25]
    for name in ("theta1", "theta2", "omega1", "omega2"):
        value = found.attrs[f"attractor_{name}"][0]
        assert min(abs(value), 2 * np.pi - abs(value)) < 1e-5


def test_coexisting_attractors_of_the_double_kapitza_pendulum_agree_with_dop853():
    """The damped double pendulum on a pivot driven fast (a = 0.1 m, nu = 60 rad/s,
    c = 0.5/s; the docs' example): three starts that sweep's basins send to three
    different attractors -- the first arm upright, the second arm upright, and a
    period-4 orbit -- are integrated by SciPy's DOP853 on Lagrange's equations written
    out in tests/test_systems.py (rtol = atol = 1e-10) to the same 16 strobe times, and
    `identify_attractors` puts each DOP853 sequence on the attractor of sweep's (the
    period-4 one reached at another phase of its orbit: a cyclic shift). Identity
    within basins' tol = 1e-3 rad and rad/s: after 984 periods (103 s) both have
    converged to ~exp(-0.25 * 103) ~ 1e-11 of the orbit."""
    from scipy.integrate import solve_ivp
    from test_systems import _lagrange

    period = 2 * np.pi / 60.0
    system = sweep.DoublePendulum(pivot_amplitude=0.1, pivot_frequency=60.0,
                                  effects=(sweep.Damping(0.5),))
    starts = [(0.0, np.pi / 10), (1.4137166941154070, -np.pi / 4), (0.0, 3 * np.pi / 4)]
    points = sweep.Points(theta1_0=[s[0] for s in starts], theta2_0=[s[1] for s in starts])
    ds = sweep.run(system, points, t_end=1000 * period, dt=period / 40,
                   t_transient=984 * period, observe=("strobe",), progress=False)
    found = maps.basins(ds)
    assert len(set(found.values.tolist())) == 3 and (found.values >= 0).all()
    assert sorted(found.attrs["attractor_period"].tolist()) == [1, 1, 4]
    # the period map reads the same samples: each start's attractor's period
    np.testing.assert_array_equal(maps.period(ds).values,
                                  found.attrs["attractor_period"][found.values])

    def damped(t, y):  # mass-proportional damping: every acceleration gains - c omega_i
        w1, w2, a1, a2 = _lagrange(t, y, a=0.1, nu=60.0)
        return [w1, w2, a1 - 0.5 * y[2], a2 - 0.5 * y[3]]

    times = (984 + np.arange(16)) * period
    reference = np.stack([solve_ivp(damped, (0, times[-1]), [*s, 0.0, 0.0],
                                    method="DOP853", rtol=1e-10, atol=1e-10,
                                    t_eval=times).y for s in starts])
    position, velocity, angular, *_ = maps.labels.system_strobe_table(ds)
    labels, _ = maps.identify_attractors(np.concatenate([position, reference[:, :2]]),
                                         np.concatenate([velocity, reference[:, 2:]]),
                                         angular=angular)
    np.testing.assert_array_equal(labels[3:], labels[:3])
    assert len(set(labels.tolist())) == 3


def test_identify_attractors_compares_angles_modulo_two_pi_and_other_coordinates_not():
    """Synthetic (n, 2, P) tables, an angle and a length: fixed points at angle 0 and
    2 pi (one attractor) and at length 0 and 2 pi (two), plus a period-2 orbit."""
    samples = 8
    k = np.arange(samples)
    rows = [((0.0, 0.0), (0.0, 0.0)), ((2 * np.pi, 0.0), (0.0, 0.0)),
            ((0.0, 2 * np.pi), (0.0, 0.0))]
    position = np.array([np.repeat(np.array(p)[:, None], samples, axis=1) for p, _ in rows])
    velocity = np.zeros_like(position)
    orbit = np.stack([1.0 + 0.5 * (k % 2), 0.3 * (k % 2)])[None]
    position = np.concatenate([position, orbit, orbit + np.array([[2 * np.pi], [0.0]])])
    velocity = np.concatenate([velocity, np.stack([k % 2, -(k % 2)])[None] * 1.0,
                               np.stack([k % 2, -(k % 2)])[None] * 1.0])
    labels, catalogue = maps.identify_attractors(position, velocity,
                                                 angular=[True, False])
    assert labels[0] == labels[1] != labels[2]
    assert labels[3] == labels[4] not in (labels[0], labels[2])
    np.testing.assert_array_equal(catalogue["period"][labels[[0, 2, 3]]], [1, 1, 2])
    assert catalogue["theta"].shape == (3, 2)
    np.testing.assert_allclose(catalogue["theta"][labels[2]], [0.0, 2 * np.pi])


def test_maps_not_yet_taking_a_systems_samples_say_so():
    system = sweep.DoublePendulum(pivot_amplitude=0.0, pivot_frequency=2 * np.pi)
    ds = sweep.run(system, sweep.Points(theta1_0=[0.1]), t_end=4.0, dt=0.01,
                   observe=("final", "strobe"), strobe_samples=2, progress=False)
    with pytest.raises(ValueError, match="not available for a system's stroboscopic "
                                         r"samples yet; accepted: sweep\.maps\.basins"):
        maps.continuation(ds, "point")
    undriven = sweep.run(sweep.DoublePendulum(), sweep.Points(theta1_0=[0.1]), t_end=4.0,
                         dt=0.01, observe=("final",), progress=False)
    # each map of the samples says what it needs of a system, not the pendulum's
    # strobe_theta and strobe_omega
    for name in ("basins", "period", "attractor_catalogue"):
        with pytest.raises(ValueError, match=rf"sweep\.maps\.{name} needs a system's "
                                             "stroboscopic samples, and this run of "
                                             "double_pendulum has none; accepted"):
            getattr(maps, name)(undriven)
