"""The kernel of a swing network (`sweep.physics.network.SwingNetwork`): blocks of SIMD
lanes as every sweep kernel, with the nodes' state in arrays ``[node, lane]`` and the
coupling summed by a loop over the network's edges, so a step costs time linear in the
edges and the generated code (and its compile time) does not grow with the network.

Kernel contract (`sweep.kernels.source`'s fixed-step contract)::

    kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved,
           src, dst, weight, power, sync)

params : float64[n, 5]            perturbed_node, delta_theta, delta_omega, damping,
                                  coupling (`sweep.physics.network.NETWORK_PARAMETERS`)
out : float64[n, n_outputs(spec)] ``final``: theta_final then omega_final per node;
                                  ``synchrony``: frequency_spread, order_parameter
saved : float64[n, 2 N, n_saved]  every node's theta, then every omega (``save``)
src, dst : int64[E]               the edges' nodes, ``src < dst`` (`network_arguments`)
weight : float64[E]               their weights A_ij
power : float64[N]                every node's P_i [1/s^2]
sync : float64[N]                 the synchronous state's phases [rad]

Trajectory ``i`` starts at the synchronous state (every omega 0) with node
``perturbed_node`` moved by ``(delta_theta, delta_omega)``. The edge sums run in a
fixed order (the edges' row-major order), so the results do not depend on blocks,
chunks or threads.

The network is data, not code: the CPU kernel's source (`network_source`) depends only
on the observables, saving, method, block and precision, so every network of a study
(another topology, a repaired line, other powers) runs the kernel compiled once
(`NetworkSpec.code`). The GPU kernel (`network_cuda_source`) holds the network as
constants of its module.

The block is a constant of the CPU kernel's text, where the other kernels take it as an
argument (`sweep.kernels.lanes.BIND`): each edge's update is a loop over the block's
lanes, which a constant count unrolls into whole vectors. With the block an argument
(known to be a multiple of 8) an edge cost 0.87-0.98 ns per trajectory-step against
0.87-0.91 (100 nodes, 100 to 400 edges, 1936 starts, AMD EPYC Zen 5, side by side).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .. import methods as _methods
from .lanes import blocks_head, indent
from .spec import Status, check_block
from .steppers import fused

__all__ = ["NETWORK_ARGUMENTS", "NETWORK_OBSERVABLES", "NetworkSpec", "network_arguments",
           "network_cuda_source", "network_outputs", "network_source"]

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
        if self.device == "cuda":  # one thread per trajectory: no lanes
            object.__setattr__(self, "block", 1)
        object.__setattr__(self, "block", check_block(self.block))

    @property
    def n_nodes(self) -> int:
        return len(self.power)

    @property
    def code(self) -> NetworkSpec:
        """What keys the CPU kernel (`sweep.kernels.build`): this spec without the
        network, which the kernel takes as arguments (`network_arguments`); itself on
        the GPU, whose kernel holds the network as constants."""
        if self.device != "cpu":
            return self
        return dataclasses.replace(self, edges=(), power=(), synchronous=())

    def describe(self) -> str:
        """A one-line description for the generated module's docstring."""
        size = (f" of {self.n_nodes} nodes and {len(self.edges)} edges"
                if self.device != "cpu" else "")
        return (f"swing network{size}, "
                f"observe={self.observe!r}, save={self.save!r}, method={self.method!r}, "
                f"block={self.block!r}"
                + (f", device={self.device!r}" if self.device != "cpu" else ""))


#: The CPU kernel's arguments after ``saved`` (the module docstring).
NETWORK_ARGUMENTS = ", src, dst, weight, power, sync"


def network_arguments(spec: NetworkSpec) -> tuple[np.ndarray, ...]:
    """The network as the CPU kernel's arguments ``(src, dst, weight, power, sync)``
    (`NETWORK_ARGUMENTS`); ``()`` on the GPU."""
    if spec.device != "cpu":
        return ()
    edges = spec.edges
    return (np.array([int(e[0]) for e in edges], dtype=np.int64),
            np.array([int(e[1]) for e in edges], dtype=np.int64),
            np.array([float(e[2]) for e in edges], dtype=np.float64),
            np.array(spec.power, dtype=np.float64),
            np.array(spec.synchronous, dtype=np.float64))


def network_outputs(spec: NetworkSpec) -> int:
    """Width of ``out``."""
    return sum(2 * spec.n_nodes if name == "final" else 2 for name in spec.observe)


def _array(values, dtype: str) -> str:
    return f"np.array([{', '.join(repr(v) for v in values)}], dtype=np.{dtype})"


def _method(spec: NetworkSpec):
    method = _methods.METHODS.get(spec.method)
    if method is None or method.adaptive or method.kind != "explicit":
        raise ValueError(f"a swing network integrates with a fixed-step explicit "
                         f"Runge-Kutta method, got {spec.method!r}")
    return method


def _stages(method, constants: dict[str, str], *, lanes: bool) -> list[str]:
    """One step of every node: the stages' states, ``accel`` and the update, over
    ``[q, j]`` (node, lane) on the CPU or ``[q]`` in a GPU thread (``lanes=False``)."""
    at = "[q, j]" if lanes else "[q]"
    over = "for q in range(N):\n" + ("    for j in range(BLOCK):\n        " if lanes
                                      else "    ")
    pad = "        " if lanes else "    "
    # the CPU kernel's network is its arguments, the GPU's its module's constants
    given = "alpha, coupling" + (", src, dst, weight, power, BLOCK" if lanes else "")
    stages = []
    for s in range(method.stages):
        row = method.a[s][:s]
        kx = [f"k{j + 1}_th{at}" for j in range(s)]
        kv = [f"k{j + 1}_om{at}" for j in range(s)]
        if s == 0:
            stages.append(f"accel(th, om, k1_th, k1_om, {given})")
            continue
        stages.append(
            f"{over}ths{at} = {fused(f'th{at}', row, kx, 'dt', constants)}\n"
            f"{pad}oms{at} = {fused(f'om{at}', row, kv, 'dt', constants)}\n"
            f"accel(ths, oms, k{s + 1}_th, k{s + 1}_om, {given})")
    kx = [f"k{j + 1}_th{at}" for j in range(method.stages)]
    kv = [f"k{j + 1}_om{at}" for j in range(method.stages)]
    stages.append(
        f"{over}th{at} = {fused(f'th{at}', method.b, kx, 'dt', constants)}\n"
        f"{pad}om{at} = {fused(f'om{at}', method.b, kv, 'dt', constants)}")
    return stages


def _writes(spec: NetworkSpec, at: str) -> list[str]:
    """The observables' writes into ``out[i]`` from ``th{at}``, ``om{at}`` (columns
    in terms of the node count ``N``, so that the text does not depend on it)."""
    writes, col = [], "0"
    for name in spec.observe:
        if name == "final":
            writes += [f"for q in range(N):\n    out[i, {col} + q] = th{at}\n"
                       f"    out[i, {col} + N + q] = om{at}"]
            col = "2 * N"
        else:
            writes += ["spread = 0.0\nsum_cos = 0.0\nsum_sin = 0.0\nfor q in range(N):\n"
                       f"    spread = max(spread, abs(om{at}))\n"
                       f"    sum_cos += vcos(th{at})\n    sum_sin += vsin(th{at})",
                       f"out[i, {col}] = spread",
                       f"out[i, {col} + 1] = math.sqrt(sum_cos * sum_cos + sum_sin * sum_sin) "
                       "/ N"]
    return writes


def network_source(spec: NetworkSpec, header: str) -> str:
    """The module text: ``header`` (imports and ``JIT``), the accelerations and the
    kernel, which takes the network as arguments (the module docstring)."""
    method = _method(spec)
    from .vecmath import SIN_RANGE

    constants: dict[str, str] = {}
    stages = _stages(method, constants, lanes=True)
    writes = _writes(spec, "[q, j]")
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
    return header + f'''

@njit(inline="always", **JIT)
def accel(x, v, kx, kv, alpha, coupling, src, dst, weight, power, BLOCK):
    """kx = v; kv = P - alpha v + K sum_edges A sin(x_other - x_self), edge by edge, in
    the BLOCK lanes (inlined: BLOCK is the kernel's constant)."""
    for q in range(power.shape[0]):
        for j in range(BLOCK):
            kx[q, j] = v[q, j]
            kv[q, j] = vfma(-alpha[j], v[q, j], power[q])
    for e in range(src.shape[0]):
        a = src[e]
        c = dst[e]
        w = weight[e]
        for j in range(BLOCK):
            f = w * coupling[j] * vsin(x[c, j] - x[a, j])
            kv[a, j] += f
            kv[c, j] -= f


{blocks_head(spec.block, NETWORK_ARGUMENTS, constant_block=True)}    n = params.shape[0]
    N = power.shape[0]
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
                th[q, j] = sync[q]
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
                for col in range(out.shape[1]):
                    out[i, col] = math.nan
{indent(failed_samples, 4)}
'''


def network_cuda_source(spec: NetworkSpec, header: str) -> str:
    """The module text for ``device="cuda"``: one GPU thread per trajectory (the
    contract of `sweep.kernels.cuda`), its nodes' state in thread-local arrays, the same
    stages, edge loop and observables as the CPU lanes (`_stages`, `_writes`) with
    CUDA's sine (so the CPU's results to rounding, not bit for bit)."""
    from .cuda import cuda_module, device_functions
    from .vecmath import SIN_RANGE

    method = _method(spec)
    constants: dict[str, str] = {}
    stages = _stages(method, constants, lanes=False)
    arrays = ["th", "om", "ths", "oms"] + [f"k{s + 1}_{x}" for s in range(method.stages)
                                           for x in ("th", "om")]
    loads = [f"{name} = _param({k}, params, flat, columns, strides, sizes, offsets, values)"
             for k, name in enumerate(("node_value", "delta_theta", "delta_omega", "alpha",
                                       "coupling"))]
    save_first = save_step = []
    if spec.save:
        save_first = ["for q in range(N):", "    saved[i, q, 0] = th[q]",
                      "    saved[i, N + q, 0] = om[q]"]
        save_step = ["if (step + 1) % save_every == 0:",
                     "    for q in range(N):",
                     "        saved[i, q, (step + 1) // save_every] = th[q]",
                     "        saved[i, N + q, (step + 1) // save_every] = om[q]"]
    width = network_outputs(spec)
    finish = ["ok = True", "finite = True", "for q in range(N):",
              "    if not (math.isfinite(th[q]) and math.isfinite(om[q])):",
              "        finite = False", f"    if not abs(th[q]) <= {SIN_RANGE!r}:",
              "        ok = False", "ok = ok and finite", "if ok:",
              f"    status[i] = {int(Status.OK)}", indent(NL.join(_writes(spec, "[q]")), 1),
              "else:",
              f"    status[i] = {int(Status.ANGLE_OUT_OF_RANGE)} if finite else "
              f"{int(Status.NONFINITE)}",
              f"    for col in range({width}):", "        out[i, col] = math.nan"]
    if spec.save:
        finish += ["    for k_save in range(saved.shape[2]):", "        for q in range(2 * N):",
                   "            if not (math.isfinite(saved[i, q, k_save]) and (q >= N or "
                   f"abs(saved[i, q, k_save]) <= {SIN_RANGE!r})):",
                   "                saved[i, q, k_save] = math.nan"]
    body = NL.join(
        ["i = cuda.grid(1)", "if i >= out.shape[0]:", "    return", "flat = first + i"]
        + loads + list(constants.values())
        + [f"{name} = cuda.local.array(N, np.float64)" for name in arrays]
        + ["for q in range(N):", "    th[q] = SYNC[q]", "    om[q] = 0.0",
           "node = int(node_value)", "if node >= 0:", "    th[node] += delta_theta",
           "    om[node] += delta_omega"] + save_first
        + ["for step in range(n_steps):", indent(NL.join(stages + save_step), 1)] + finish)
    edges = spec.edges
    return header + device_functions("") + f'''
N = {spec.n_nodes}
SRC = {_array([int(e[0]) for e in edges], "int64")}
DST = {_array([int(e[1]) for e in edges], "int64")}
WEIGHT = {_array([float(e[2]) for e in edges], "float64")}
POWER = {_array([float(p) for p in spec.power], "float64")}
SYNC = {_array([float(x) for x in spec.synchronous], "float64")}


@cuda.jit(device=True)
def accel(x, v, kx, kv, alpha, coupling):
    """kx = v; kv = P - alpha v + K sum_edges A sin(x_other - x_self), edge by edge."""
    for q in range(N):
        kx[q] = v[q]
        kv[q] = vfma(-alpha, v[q], POWER[q])
    for e in range(SRC.shape[0]):
        a = SRC[e]
        c = DST[e]
        w = WEIGHT[e]
        f = w * coupling * vsin(x[c] - x[a])
        kv[a] += f
        kv[c] -= f
''' + cuda_module(body)
