"""Swing networks (`sweep.SwingNetwork`) against oracles: two nodes with P2 = -P1 are
exactly one pendulum with torque for their relative angle, the synchronous state solves
the power-flow equations, and single-node basin stability behaves as Menck et al.
found (dead ends are less stable), with standard errors."""

import math

import numpy as np
import pytest

import sweep

P, K, ALPHA = 1.0, 4.0, 0.3


def _two_nodes_against_the_pendulum(power, coupling, damping):
    """theta1'' = -P - a theta1' + K sin(theta2 - theta1), theta2'' = P - a theta2' +
    K sin(theta1 - theta2): delta = theta2 - theta1 obeys delta'' = 2P - a delta' -
    2K sin(delta), the single pendulum with g/L = 2K, damping a and torque 2P. The
    synchronous state has sin(delta*) = P / K. Perturbing node 1 by (d_theta, d_omega)
    starts delta at (delta* + d_theta, d_omega); the network's locked/running map must
    be the pendulum's, cell by cell, and delta must follow the pendulum's angle."""
    network = sweep.SwingNetwork([(0, 1)], power=[-power, power], damping=damping,
                                 coupling=coupling)
    delta_star = math.asin(power / coupling)
    np.testing.assert_allclose(np.diff(network.synchronous_state()), delta_star, rtol=1e-14)
    d_theta = np.linspace(-np.pi, np.pi, 41)
    d_omega = np.linspace(-8.0, 8.0, 41)
    ds = sweep.run(network, sweep.Grid(perturbed_node=[1], delta_theta=d_theta,
                                       delta_omega=d_omega),
                   t_end=100.0, dt=0.01, observe=("final", "synchrony"))
    scene = sweep.Scene(gravity=2 * coupling, length=1.0,
                        effects=(sweep.Damping(damping), sweep.Torque(2 * power)))
    pendulum = sweep.run(scene, sweep.Grid(theta0=delta_star + d_theta, omega0=d_omega),
                         t_end=100.0, dt=0.01, observe=("final",))
    # locked: the relative frequency has decayed (e^{-a t / 2} <= 4e-6 of its start at
    # t = 100 for the a >= 0.25 used here); running: it circulates at about 2P / a >= 6
    # rad/s. 0.1 is between.
    locked_network = sweep.maps.synchronized(ds).values[0] == 1
    locked_pendulum = np.abs(pendulum.omega_final.values) <= 0.1
    assert 0.2 < locked_pendulum.mean() < 0.8  # both kinds of cell are on the map
    np.testing.assert_array_equal(locked_network, locked_pendulum)
    delta = (ds.theta_final.sel(node=1) - ds.theta_final.sel(node=0)).values[0]
    # the same motion by two different sums of rounding errors over 10^4 steps of a
    # damped (non-chaotic) flow: ~1e-11 rad measured; 1e-8 leaves room and still
    # rejects any error in a term (a wrong factor 2 moves delta by order 1)
    np.testing.assert_allclose(delta, pendulum.theta_final.values, rtol=0, atol=1e-8)


def test_two_nodes_are_one_pendulum_with_torque_cell_by_cell():
    _two_nodes_against_the_pendulum(P, K, ALPHA)


def test_every_network_runs_the_kernel_compiled_once():
    """The network is the CPU kernel's data, not its code: networks of 2 and 12 nodes
    have the same kernel text, and a second network (other power, coupling and
    damping) runs the kernel built for the first (a memo hit: nothing is generated or
    compiled) and still gives its own pendulum's map cell by cell."""
    from sweep.engine_systems import prepare_system
    from sweep.kernels import cache, source

    grid = sweep.Grid(perturbed_node=[1], delta_theta=np.linspace(-3, 3, 41),
                      delta_omega=np.linspace(-8, 8, 41))
    ring = sweep.SwingNetwork([(k, (k + 1) % 12) for k in range(12)],
                              power=[1.0, -1.0] * 6, coupling=5.0)
    specs = [prepare_system(network, grid, t_end=1.0, dt=0.01,
                            observe=("final", "synchrony"))[1]
             for network in (sweep.SwingNetwork([(0, 1)], power=[-P, P]), ring)]
    assert specs[0] != specs[1] and specs[0].code == specs[1].code
    assert source(specs[0].code) == source(specs[1].code)
    _two_nodes_against_the_pendulum(P, K, ALPHA)
    built = cache._build.cache_info()
    _two_nodes_against_the_pendulum(0.8, 3.0, 0.25)
    assert cache._build.cache_info().misses == built.misses


def test_synchronous_state_solves_the_power_flow_equations():
    rng = np.random.default_rng(3)
    n = 12
    edges = [(k, int(rng.integers(0, k))) for k in range(1, n)] + [(0, 5), (2, 9), (4, 11)]
    power = rng.uniform(-1, 1, n)
    power -= power.mean()
    network = sweep.SwingNetwork(edges, power=power, coupling=6.0)
    theta = network.synchronous_state()
    a = network.adjacency
    residual = power + 6.0 * (a * np.sin(theta[None, :] - theta[:, None])).sum(axis=1)
    assert np.max(np.abs(residual)) < 1e-12  # Newton's stopping rule: 1e-13 x max |P|
    assert abs(theta.mean()) < 1e-15


def test_adjacency_forms_give_the_same_network_and_bits():
    nx = pytest.importorskip("networkx")
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)]
    matrix = np.zeros((4, 4))
    for i, j in edges:
        matrix[i, j] = matrix[j, i] = 1.0
    graph = nx.Graph(edges)
    graph = nx.relabel_nodes(graph, {k: k for k in range(4)})
    graph = nx.Graph()
    graph.add_nodes_from(range(4))
    graph.add_edges_from(edges)
    power = [1.0, -1.0, 1.0, -1.0]
    networks = [sweep.SwingNetwork(form, power=power) for form in (edges, matrix, graph)]
    assert networks[0] == networks[1] == networks[2]
    grid = sweep.Grid(perturbed_node=[0, 3], delta_theta=np.linspace(-2, 2, 5))
    runs = [sweep.run(net, grid, t_end=2.0, dt=0.01, observe=("final",)) for net in networks]
    for ds in runs[1:]:
        np.testing.assert_array_equal(ds.theta_final.values, runs[0].theta_final.values)


def test_bits_do_not_depend_on_chunks_or_threads_and_samples_are_consistent():
    import numba

    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (1, 3)],
                                 power=[2.0, -1.0, 0.5, -0.5, -1.0], coupling=8.0)
    grid = sweep.Grid(perturbed_node=[0, 2, 4], delta_theta=np.linspace(-3, 3, 7),
                      delta_omega=np.linspace(-6, 6, 9))
    kwargs = dict(t_end=3.0, dt=0.01, observe=("final", "synchrony"), save_every=50)
    whole = sweep.run(network, grid, **kwargs)
    chunked = sweep.run(network, grid, chunk_size=10, **kwargs)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        serial = sweep.run(network, grid, **kwargs)
    finally:
        numba.set_num_threads(threads)
    for name in ("theta_final", "omega_final", "frequency_spread", "order_parameter", "theta"):
        np.testing.assert_array_equal(chunked[name].values, whole[name].values)
        np.testing.assert_array_equal(serial[name].values, whole[name].values)
    assert whole.theta.dims == ("perturbed_node", "delta_theta", "delta_omega", "node", "time")
    np.testing.assert_array_equal(whole.theta.values[..., -1], whole.theta_final.values)
    start = whole.theta.isel(time=0).sel(perturbed_node=2).values
    sync = network.synchronous_state()
    np.testing.assert_array_equal(start[:, 0, [0, 1, 3, 4]],
                                  np.broadcast_to(sync[[0, 1, 3, 4]], (7, 4)))
    np.testing.assert_array_equal(start[:, 0, 2], sync[2] + np.linspace(-3, 3, 7))


def test_cuda_kernel_agrees_with_the_cpu_kernel():
    """device="cuda" (numba's CUDA simulator on CI; SWEEP_REAL_CUDA=1 on a GPU): one
    thread per trajectory, its nodes in thread-local arrays, the same stages and edge
    loop as the CPU lanes. CUDA's sine is not sweep's polynomial (both within an ulp or
    two of the true one), so the results agree to rounding: over these 150 steps of
    returning and desynchronising perturbations the CPU and the simulator differ by
    ~1e-15 measured; 1e-10 leaves room, while a wrong term, stage or edge is of order
    1e-3 or more. A perturbation that overflows is flagged on both."""
    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (1, 3)],
                                 power=[2.0, -1.0, 0.5, -0.5, -1.0], damping=0.2,
                                 coupling=3.0)
    grid = sweep.Grid(perturbed_node=[0, 3], delta_theta=[-2.5, 0.3, 3.0],
                      delta_omega=[-8.0, 0.5, 1e300])
    kwargs = dict(t_end=1.5, dt=0.01, observe=("final", "synchrony"), save_every=50,
                  progress=False)
    with pytest.warns(RuntimeWarning, match="6 of 18 trajectories"):
        cpu = sweep.run(network, grid, **kwargs)
    with pytest.warns(RuntimeWarning, match="6 of 18 trajectories"):
        gpu = sweep.run(network, grid, device="cuda", **kwargs)
    assert gpu.attrs["device"] == "cuda"
    ok = int(sweep.kernels.Status.OK)
    # the overflowing column fails on both (as non-finite on the CPU, whose polynomial
    # sine gives no sine past 7e15; out of range where the sine is libm's)
    assert (cpu.status.values[..., 2] != ok).all() and (gpu.status.values[..., 2] != ok).all()
    np.testing.assert_array_equal(gpu.status.values[..., :2], cpu.status.values[..., :2])
    for name in ("theta_final", "omega_final", "frequency_spread", "order_parameter",
                 "theta", "omega"):
        good = dict(delta_omega=slice(0, 2))
        np.testing.assert_allclose(gpu[name].isel(good).values, cpu[name].isel(good).values,
                                   rtol=0, atol=1e-10)
        if "time" not in gpu[name].dims:  # a failed trajectory's outputs are NaN
            assert np.isnan(gpu[name].isel(delta_omega=2).values).all()
    desynchronised = cpu.frequency_spread.values[..., :2] > 0.5
    assert desynchronised.any() and not desynchronised.all()


def test_small_perturbations_return_and_the_order_parameter_is_kuramotos():
    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 0)], power=[1.0, -0.5, -0.5],
                                 damping=0.5, coupling=5.0)
    ds = sweep.run(network, sweep.Grid(perturbed_node=[0, 1, 2], delta_theta=[0.05]),
                   t_end=60.0, dt=0.01, observe=("final", "synchrony"))
    assert (sweep.maps.synchronized(ds) == 1).all()
    theta = ds.theta_final.values
    r = np.abs(np.exp(1j * theta).mean(axis=-1))
    # the kernel's vectorised sine and cosine are within 2^-52 of numpy's: a few ulps
    np.testing.assert_allclose(ds.order_parameter.values, r, rtol=0, atol=1e-14)


def test_dead_ends_undermine_basin_stability_and_repairing_them_restores_it():
    """Menck, Heitzig, Kurths, Schellnhuber, Nat. Commun. 5, 3969 (2014): in grids of
    generators (P = 1) and consumers (P = -1) with alpha = 0.1 and K = 8, tree-like
    appendices (dead ends, dead trees) strongly diminish single-node basin stability,
    and repairing them with a few lines restores it. Nitzbon et al., New J. Phys. 19,
    033029 (2017) locate the loss at the trees' roots and inner nodes. A ring of six
    with a dead end at node 0 (leaf 6) and a dead tree at node 1 (inner node 7, leaves
    8 and 9), against the same grid with three lines added that close the trees into
    the ring: the root 0 and the inner node 7 must gain by more than 3 combined
    standard errors (measured here: 0.445 -> 0.63 and 0.40 -> 0.63 with 200
    perturbations each, standard errors ~0.035)."""
    edges = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0), (0, 6), (1, 7), (7, 8), (7, 9)]
    power = [1, -1, 1, -1, 1, -1, -1, 1, -1, 1]
    runs = {}
    for name, lines in (("dead", edges), ("repaired", edges + [(6, 5), (8, 2), (9, 3)])):
        network = sweep.SwingNetwork(lines, power=power, damping=0.1, coupling=8.0)
        # |omega| <= 30 rad/s with dt = 0.005: omega dt <= 0.15 rad per step, resolved
        runs[name] = sweep.maps.basin_stability(network, 200, seed=7, t_end=200.0, dt=0.005,
                                                delta_omega=(-30.0, 30.0), nodes=[0, 7])
    dead, repaired = runs["dead"], runs["repaired"]
    for name in ("basin_stability", "standard_error"):  # a short label, then its meaning
        assert len(dead[name].long_name) <= 40 and "p (1 - p)" not in dead[name].long_name
    assert "synchronous again" in dead.basin_stability.comment
    assert "sqrt(p (1 - p) / n)" in dead.standard_error.comment
    assert (dead.failed == 0).all() and (repaired.failed == 0).all()
    gain = repaired.basin_stability - dead.basin_stability
    error = np.hypot(repaired.standard_error, dead.standard_error)
    assert (gain > 3 * error).all(), (dead.basin_stability.values,
                                      repaired.basin_stability.values)


@pytest.mark.parametrize("make, match", [
    (lambda: sweep.SwingNetwork(np.ones((2, 4))), "square matrix, an edge list"),
    (lambda: sweep.SwingNetwork([(0, 1), (1, 1)], power=[1, -1]), "two different nodes"),
    (lambda: sweep.SwingNetwork([[0, 1], [1, 0]], power=[1, -1], damping=-1.0), "damping"),
    (lambda: sweep.SwingNetwork([[0, -1], [-1, 0]], power=[1, -1]), "negative weight"),
    (lambda: sweep.SwingNetwork([[0, 1], [2, 0]], power=[1, -1]), "symmetric"),
    (lambda: sweep.SwingNetwork([(0, 1)], power=[1, 1]), "must sum to 0"),
    (lambda: sweep.SwingNetwork([(0, 1)], power=[1, -1, 0]), "one per node"),
    (lambda: sweep.SwingNetwork([(0, 1)], power=[1, -1], coupling=0.0), "coupling"),
    (lambda: sweep.SwingNetwork([(0, 1)], power=[5, -5], coupling=1.0).synchronous_state(),
     "cannot carry the powers"),
    (lambda: sweep.run(sweep.SwingNetwork([(0, 1)], power=[1, -1]),
                       sweep.Grid(perturbed_node=[2]), t_end=1, dt=0.1),
     "perturbed_node' has value 2.0"),
    (lambda: sweep.run(sweep.SwingNetwork([(0, 1)], power=[1, -1]),
                       sweep.Grid(coupling=[1.0, 2.0]), t_end=1, dt=0.1), "coupling"),
    (lambda: sweep.run(sweep.SwingNetwork([(0, 1)], power=[1, -1]),
                       sweep.Grid(theta1_0=[1.0]), t_end=1, dt=0.1),
     "names no coordinate or parameter of SwingNetwork"),
    (lambda: sweep.run(sweep.SwingNetwork([(0, 1)], power=[1, -1]),
                       sweep.Grid(perturbed_node=[0]), t_end=1, dt=0.1, dtype="float32"),
     "dtype='float32' is not available for a SwingNetwork"),
    (lambda: sweep.run(sweep.SwingNetwork([(0, 1)], power=[1, -1]),
                       sweep.Grid(perturbed_node=[0]), t_end=1, dt=0.1, observe=("flip",)),
     "unknown observable 'flip' for a SwingNetwork"),
])
def test_bad_networks_are_refused_before_any_compute(make, match):
    with pytest.raises((ValueError, TypeError), match=match):
        make()


def test_refusals_print_plain_numbers():
    """A refusal shows the number the user would type (``1.0``), not NumPy's repr
    (``np.float64(1.0)``, NumPy 2's)."""
    with pytest.raises(ValueError) as refused:
        sweep.SwingNetwork([(0, 1)], power=[1.0, 0.0])
    assert "got sum 1.0;" in str(refused.value) and "np." not in str(refused.value)
