"""The kernel of a swing network (`sweep.physics.network.SwingNetwork`): blocks of SIMD
lanes as every sweep kernel, with the nodes' state in arrays ``[node, lane]`` and the
coupling summed by a loop over the network's edges, so a step costs time linear in the
edges and the generated code (and its compile time) does not grow with the network.

Kernel contract (`sweep.kernels.source`'s fixed-step contract)::

    kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved)

params : float64[n, 5]            perturbed_node, delta_theta, delta_omega, damping,
                                  coupling (`sweep.physics.network.NETWORK_PARAMETERS`)
out : float64[n, n_outputs(spec)] ``final``: theta_final then omega_final per node;
                                  ``synchrony``: frequency_spread, order_parameter
saved : float64[n, 2 N, n_saved]  every node's theta, then every omega (``save``)

Trajectory ``i`` starts at the synchronous state (every omega 0) with node
``perturbed_node`` moved by ``(delta_theta, delta_omega)``. The edge sums run in a
fixed order (the edges' row-major order), so the results do not depend on blocks,
chunks or threads.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import methods as _methods
from .lanes import blocks_head, indent
from .spec import Status, check_block
from .steppers import fused

__all__ = ["NETWORK_OBSERVABLES", "NetworkSpec", "network_outputs", "network_source"]

NL = "\n"

#: What a network run can observe: ``final`` (every node's phase and frequency at
#: t_end) and ``synchrony`` (``frequency_spread``: max abs(omega_i) at t_end [rad/s], 0 in
#: the synchronous state; ``order_parameter``: Kuramoto's r = |mean exp(i theta)|).
NETWORK_OBSERVABLES = ("final", "synchrony")


@dataclass(frozen=True)
class NetworkSpec:
    """Everything that changes a network kernel's code (plain data: it hashes, pickles
    and keys the kernel cache).

    Attributes
    ----------
    edges : tuple of (int, int, float)
        ``(i, j, A_ij)`` per line, ``i < j``.
    power : tuple of float
        ``P_i`` per node [1/s^2].
    synchronous : tuple of float
        The synchronous state's phases [rad] (the starts are perturbations of it).
    observe : tuple of str
        `NETWORK_OBSERVABLES`, canonical order.
    save : bool
    method : str
        A fixed-step explicit Runge-Kutta method.
    block : int
    """

    edges: tuple
    power: tuple
    synchronous: tuple
    observe: tuple[str, ...]
    save: bool = False
    method: str = "rk4"
    block: int = None
    device: str = "cpu"
    dtype: str = "float64"

    def __post_init__(self) -> None:
        object.__setattr__(self, "block", check_block(self.block))

    @property
    def n_nodes(self) -> int:
        return len(self.power)

    def describe(self) -> str:
        """A one-line description for the generated module's docstring."""
        return (f"swing network of {self.n_nodes} nodes and {len(self.edges)} edges, "
                f"observe={self.observe!r}, save={self.save!r}, method={self.method!r}, "
                f"block={self.block!r}")


def network_outputs(spec: NetworkSpec) -> int:
    """Width of ``out``."""
    return sum(2 * spec.n_nodes if name == "final" else 2 for name in spec.observe)


def _array(values, dtype: str) -> str:
    return f"np.array([{', '.join(repr(v) for v in values)}], dtype=np.{dtype})"


def network_source(spec: NetworkSpec, header: str) -> str:
    """The module text: ``header`` (imports and ``JIT``), the network as constants, the
    accelerations and the kernel."""
    method = _methods.METHODS.get(spec.method)
    if method is None or method.adaptive or method.kind != "explicit":
        raise ValueError(f"a swing network integrates with a fixed-step explicit "
                         f"Runge-Kutta method, got {spec.method!r}")
    from .vecmath import SIN_RANGE

    constants: dict[str, str] = {}
    stages = []
    for s in range(method.stages):
        row = method.a[s][:s]
        kx = [f"k{j + 1}_th[q, j]" for j in range(s)]
        kv = [f"k{j + 1}_om[q, j]" for j in range(s)]
        if s == 0:
            stages.append("accel(th, om, k1_th, k1_om, alpha, coupling)")
            continue
        stages.append(
            "for q in range(N):\n    for j in range(BLOCK):\n"
            f"        ths[q, j] = {fused('th[q, j]', row, kx, 'dt', constants)}\n"
            f"        oms[q, j] = {fused('om[q, j]', row, kv, 'dt', constants)}\n"
            f"accel(ths, oms, k{s + 1}_th, k{s + 1}_om, alpha, coupling)")
    kx = [f"k{j + 1}_th[q, j]" for j in range(method.stages)]
    kv = [f"k{j + 1}_om[q, j]" for j in range(method.stages)]
    stages.append(
        "for q in range(N):\n    for j in range(BLOCK):\n"
        f"        th[q, j] = {fused('th[q, j]', method.b, kx, 'dt', constants)}\n"
        f"        om[q, j] = {fused('om[q, j]', method.b, kv, 'dt', constants)}")
    n = spec.n_nodes
    writes, col = [], 0
    for name in spec.observe:
        if name == "final":
            writes += [f"for q in range(N):\n    out[i, {col} + q] = th[q, j]\n"
                       f"    out[i, {col + n} + q] = om[q, j]"]
            col += 2 * n
        else:
            writes += ["spread = 0.0\nsum_cos = 0.0\nsum_sin = 0.0\nfor q in range(N):\n"
                       "    spread = max(spread, abs(om[q, j]))\n"
                       "    sum_cos += vcos(th[q, j])\n    sum_sin += vsin(th[q, j])",
                       f"out[i, {col}] = spread",
                       f"out[i, {col + 1}] = math.sqrt(sum_cos * sum_cos + sum_sin * sum_sin) "
                       "/ N"]
            col += 2
    width = network_outputs(spec)
    save_first = save_step = ""
    if spec.save:
        save_first = ("for j in range(n_real):\n    for q in range(N):\n"
                      "        saved[base + j, q, 0] = th[q, j]\n"
                      "        saved[base + j, N + q, 0] = om[q, j]")
        save_step = ("if (step + 1) % save_every == 0:\n    k_save = (step + 1) // save_every\n"
                     "    for j in range(n_real):\n        for q in range(N):\n"
                     "            saved[base + j, q, k_save] = th[q, j]\n"
                     "            saved[base + j, N + q, k_save] = om[q, j]")
    failed_samples = ("for k_save in range(saved.shape[2]):\n    for q in range(2 * N):\n"
                      "        if not (math.isfinite(saved[i, q, k_save]) and (q >= N or "
                      f"abs(saved[i, q, k_save]) <= {SIN_RANGE!r})):\n"
                      "            saved[i, q, k_save] = math.nan") if spec.save else "pass"
    stage_arrays = NL.join(f"k{s + 1}_th = np.empty((N, BLOCK))\n"
                           f"k{s + 1}_om = np.empty((N, BLOCK))" for s in range(method.stages))
    edges = spec.edges
    return header + f'''
N = {n}
SRC = {_array([int(e[0]) for e in edges], "int64")}
DST = {_array([int(e[1]) for e in edges], "int64")}
WEIGHT = {_array([float(e[2]) for e in edges], "float64")}
POWER = {_array([float(p) for p in spec.power], "float64")}
SYNC = {_array([float(x) for x in spec.synchronous], "float64")}


@njit(inline="always", **JIT)
def accel(x, v, kx, kv, alpha, coupling):
    """kx = v; kv = P - alpha v + K sum_edges A sin(x_other - x_self), edge by edge."""
    for q in range(N):
        for j in range(BLOCK):
            kx[q, j] = v[q, j]
            kv[q, j] = vfma(-alpha[j], v[q, j], POWER[q])
    for e in range(SRC.shape[0]):
        a = SRC[e]
        c = DST[e]
        w = WEIGHT[e]
        for j in range(BLOCK):
            f = w * coupling[j] * vsin(x[c, j] - x[a, j])
            kv[a, j] += f
            kv[c, j] -= f


{blocks_head(spec.block)}    n = params.shape[0]
{indent(NL.join(constants.values()), 1)}
    th = np.empty((N, BLOCK))
    om = np.empty((N, BLOCK))
    ths = np.empty((N, BLOCK))
    oms = np.empty((N, BLOCK))
{indent(stage_arrays, 1)}
    alpha = np.empty(BLOCK)
    coupling = np.empty(BLOCK)
    for b in range(b_first, b_stop):
        base = b * BLOCK
        n_real = min(BLOCK, n - base)
        for q in range(N):
            for j in range(BLOCK):
                th[q, j] = SYNC[q]
                om[q, j] = 0.0
        for j in range(BLOCK):
            i = min(base + j, n - 1)  # padding lanes repeat the last trajectory
            alpha[j] = params[i, 3]
            coupling[j] = params[i, 4]
            node = int(params[i, 0])
            if node >= 0:
                th[node, j] += params[i, 1]
                om[node, j] += params[i, 2]
{indent(save_first, 2)}
        for step in range(n_steps):
{indent(NL.join(stages), 3)}
{indent(save_step, 3)}
        for j in range(n_real):
            i = base + j
            ok = True
            for q in range(N):
                if not (math.isfinite(th[q, j]) and math.isfinite(om[q, j])):
                    ok = False
            if ok:
                finite = True
                for q in range(N):
                    if not abs(th[q, j]) <= {SIN_RANGE!r}:
                        ok = False
            else:
                finite = False
            if ok:
                status[i] = {int(Status.OK)}
{indent(NL.join(writes), 4)}
            else:
                status[i] = {int(Status.ANGLE_OUT_OF_RANGE)} if finite else {int(Status.NONFINITE)}
                for col in range({width}):
                    out[i, col] = math.nan
{indent(failed_samples, 4)}
'''
