"""The swing equation of a power grid: a network of damped, driven pendula.

Each node ``i`` (a generator or a consumer) has a phase ``theta_i`` in the frame that
rotates at the grid frequency and obeys

    theta_i'' = P_i - alpha theta_i' + K sum_j A_ij sin(theta_j - theta_i)

with ``P_i`` its power (> 0 generator, < 0 consumer; they balance, ``sum P_i = 0``),
``alpha`` the damping, ``K`` the coupling and ``A`` the weighted adjacency matrix of its
lines (symmetric, >= 0). It is the system for which *basin stability* was introduced
(Menck, Heitzig, Marwan, Kurths, Nat. Phys. 9, 89 (2013); Menck et al., Nat. Commun. 5,
3969 (2014)): the fraction of perturbations of one node's ``(theta, omega)`` after
which the grid returns to its synchronous state.

A network is data (the adjacency as a matrix, an edge list or a ``networkx`` graph);
its kernel loops over its edges (`sweep.kernels.network`), so a step costs time
linear in the edges; on the CPU the kernel takes the network as arguments, so it is
compiled once for every network (4 nodes or 100, any lines and powers). The grid perturbs
one node at a time from the synchronous state: axes ``perturbed_node`` (its index),
``delta_theta`` [rad] and ``delta_omega`` [rad/s], besides ``damping`` and ``coupling``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._validate import check_real
from .effect import Parameter
from .system import System, register_system

__all__ = ["NETWORK_PARAMETERS", "SwingNetwork"]

#: The per-trajectory parameters of a swing network run, in table-column order.
NETWORK_PARAMETERS = (
    Parameter("perturbed_node", "perturbed_node", "node", "1", "node index",
              "index of the perturbed node (-1: none)", minimum=-1.0, default=-1.0),
    Parameter("delta_theta", "delta_theta", "dth", "rad", "rad",
              "perturbation of the node's phase from the synchronous state", default=0.0,
              angle=True),
    Parameter("delta_omega", "delta_omega", "dom", "rad s-1", "rad/s",
              "perturbation of the node's frequency from the synchronous state",
              default=0.0),
    Parameter("damping", "damping", "alpha", "s-1", "1/s", "damping alpha of every node",
              minimum=0.0),
    Parameter("coupling", "coupling", "K", "s-2", "1/s^2",
              "coupling K of the lines (times their weights A_ij)", minimum=0.0, strict=True),
)

_AXES = {p.axis: p for p in NETWORK_PARAMETERS}


def _adjacency(adjacency, n_nodes: int | None) -> np.ndarray:
    """The adjacency as a float64 square matrix, from a matrix, an edge list
    ``[(i, j), ...]`` or ``[(i, j, weight), ...]``, or a networkx graph."""
    if hasattr(adjacency, "nodes") and hasattr(adjacency, "edges"):  # a networkx graph
        nodes = list(adjacency.nodes)
        index = {node: k for k, node in enumerate(nodes)}
        matrix = np.zeros((len(nodes), len(nodes)))
        for a, b, data in adjacency.edges(data=True):
            weight = data.get("weight", 1.0)
            matrix[index[a], index[b]] = matrix[index[b], index[a]] = weight
        return matrix
    array = np.asarray(adjacency, dtype=object)
    square = array.ndim == 2 and array.shape[0] == array.shape[1]
    if square and (array.shape[1] not in (2, 3) or _zero_diagonal(array)):
        # a 2 x 2 or 3 x 3 array could be an edge list too: a matrix has a zero
        # diagonal, an edge list's "diagonal" would name a line from a node to itself
        try:
            return np.array(adjacency, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"adjacency must hold real numbers, got {adjacency!r}") from None
    if array.ndim == 2 and array.shape[1] in (2, 3) and array.shape[0] >= 1:  # edge list
        try:
            edges = np.array(adjacency, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"an edge list holds (i, j) or (i, j, weight) of numbers, got "
                             f"{adjacency!r}") from None
        ends = edges[:, :2]
        if not np.all(np.isfinite(ends)) or not np.all(ends == np.round(ends)) \
                or np.any(ends < 0):
            raise ValueError("an edge list names its nodes by indices 0, 1, ...; got "
                             f"{adjacency!r}")
        loops = ends[:, 0] == ends[:, 1]
        if loops.any():
            raise ValueError(f"an edge joins two different nodes; got the edge "
                             f"{tuple(edges[loops][0])!r} from node to itself")
        n = int(ends.max()) + 1 if n_nodes is None else n_nodes
        matrix = np.zeros((n, n))
        for row in edges:
            a, b = int(row[0]), int(row[1])
            weight = row[2] if len(row) == 3 else 1.0
            matrix[a, b] = matrix[b, a] = weight
        return matrix
    raise ValueError(f"adjacency must be a square matrix, an edge list [(i, j), ...] or "
                     f"[(i, j, weight), ...], or a networkx graph; got an array of shape "
                     f"{array.shape}")


def _zero_diagonal(array) -> bool:
    """Whether a square array of numbers has zeros on its diagonal."""
    try:
        return bool(np.all(np.diag(np.array(array, dtype=np.float64)) == 0))
    except (TypeError, ValueError):
        return False


@register_system
@dataclass(frozen=True, eq=False)
class SwingNetwork(System):
    """A power grid's swing equation: damped, driven pendula coupled along lines.

    Parameters
    ----------
    adjacency : array_like or networkx.Graph
        The lines: a square symmetric matrix of weights ``A_ij >= 0`` (zero diagonal),
        an edge list ``[(i, j), ...]`` or ``[(i, j, weight), ...]`` (nodes 0, 1, ...),
        or a ``networkx`` graph (edge attribute ``weight``, default 1; nodes in the
        graph's order).
    power : float or array_like, shape (n_nodes,)
        ``P_i`` [1/s^2]: > 0 generators, < 0 consumers. A scalar: that power for every
        node, which only balances as 0. Must sum to 0 (within 1e-9 of the sum of the abs(P_i)): the
        frame rotates at the grid frequency.
    damping : float, default 0.1
        ``alpha`` [1/s], >= 0, every node.
    coupling : float, default 8.0
        ``K`` [1/s^2], > 0.

    Examples
    --------
    A ring of 4 nodes, two generators and two consumers:

    >>> import sweep
    >>> grid = sweep.SwingNetwork([(0, 1), (1, 2), (2, 3), (3, 0)],
    ...                           power=[1, -1, 1, -1], damping=0.1, coupling=8.0)
    >>> grid.n_nodes, grid.n_edges
    (4, 4)
    """

    adjacency: object
    power: object = 0.0
    damping: float = 0.1
    coupling: float = 8.0
    effects: tuple = field(default=())

    def __post_init__(self) -> None:
        matrix = _adjacency(self.adjacency, None)
        n = matrix.shape[0]
        if matrix.ndim != 2 or n != matrix.shape[1]:
            raise ValueError(f"adjacency must be square, got shape {matrix.shape}")
        if n < 2:
            raise ValueError(f"a SwingNetwork needs at least 2 nodes, got {n}")
        if not np.all(np.isfinite(matrix)):
            raise ValueError("adjacency must be finite; accepted: weights >= 0")
        if np.any(matrix < 0):
            k = np.argwhere(matrix < 0)[0]
            raise ValueError(f"adjacency has a negative weight {matrix[k[0], k[1]]!r} at "
                             f"({k[0]}, {k[1]}); accepted: weights >= 0")
        if not np.array_equal(matrix, matrix.T):
            raise ValueError("adjacency must be symmetric (a line couples both its ends "
                             "alike); accepted: A_ij == A_ji")
        if np.any(np.diag(matrix) != 0):
            raise ValueError("adjacency must have a zero diagonal (a node has no line to "
                             "itself)")
        power = np.asarray(self.power, dtype=np.float64)
        if power.ndim == 0:
            power = np.full(n, float(power))
        if power.shape != (n,) or not np.all(np.isfinite(power)):
            raise ValueError(f"power must be a finite number or {n} finite numbers (one per "
                             f"node), got {self.power!r}")
        if abs(power.sum()) > 1e-9 * max(np.abs(power).sum(), 1.0):
            raise ValueError(f"power must sum to 0 (generators balance consumers, so the "
                             f"frame rotates at the grid frequency), got sum "
                             f"{float(power.sum())!r}; accepted: powers whose sum is 0")
        matrix.flags.writeable = False
        power.flags.writeable = False
        object.__setattr__(self, "adjacency", matrix)
        object.__setattr__(self, "power", power)
        object.__setattr__(self, "damping", check_real(
            "damping", self.damping, minimum=0.0, accepted="a finite number >= 0 (1/s)"))
        object.__setattr__(self, "coupling", check_real(
            "coupling", self.coupling, minimum=0.0, strict=True,
            accepted="a finite number > 0 (1/s^2)"))
        if self.effects:
            raise TypeError("SwingNetwork takes no effects (its damping, powers and coupling "
                            f"are its own arguments); got {self.effects!r}")

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return self.adjacency.shape[0]

    @property
    def edges(self) -> np.ndarray:
        """``(i, j, weight)`` of each line, ``i < j``, in row-major order; shape
        (n_edges, 3)."""
        i, j = np.nonzero(np.triu(self.adjacency, 1))
        return np.column_stack([i, j, self.adjacency[i, j]])

    @property
    def n_edges(self) -> int:
        """Number of lines."""
        return len(self.edges)

    def __eq__(self, other) -> bool:
        return isinstance(other, SwingNetwork) and self.key() == other.key()

    def __hash__(self) -> int:
        return hash(self.key())

    def key(self) -> tuple:
        """Hashable content: what the kernel is built from."""
        return (self.adjacency.tobytes(), self.adjacency.shape, self.power.tobytes(),
                self.damping, self.coupling)

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:
        """The parameter of a swing network run whose grid axis is ``name``."""
        return _AXES.get(name)

    def columns(self, damping: bool = True) -> tuple[str, ...]:
        """The parameter table's columns (every run of a network has all of them)."""
        return tuple(_AXES)

    def accepted_axes(self) -> tuple[str, ...]:
        """Every grid axis of a network run (`columns`: it takes no effects)."""
        return self.columns()

    def switched_on(self, axes) -> SwingNetwork:
        """Itself: no axis switches a term on (it takes no effects)."""
        return self

    def axis_hint(self, name: str) -> None:
        """None: a network takes no effects on its nodes (the grid's message lists its
        axes)."""
        return None

    def parameters(self) -> dict[str, float]:
        """Values of every table column except the perturbation (none by default)."""
        return {"perturbed_node": -1.0, "delta_theta": 0.0, "delta_omega": 0.0,
                "damping": self.damping, "coupling": self.coupling}

    def synchronous_state(self, coupling: float | None = None) -> np.ndarray:
        """The phases ``theta*`` [rad] of the synchronous state (every ``omega = 0``):
        the solution of ``P_i + K sum_j A_ij sin(theta_j - theta_i) = 0`` with mean
        phase 0 that Newton's method reaches from all phases 0, the stable one for
        the loads of a working grid (every line's ``|theta_j - theta_i| < pi/2``).

        Raises
        ------
        ValueError
            When Newton's method finds none: the coupling cannot carry the powers.
        """
        coupling = self.coupling if coupling is None else coupling
        a, power, n = self.adjacency, self.power, self.n_nodes
        theta = np.zeros(n)
        for _ in range(100):
            diff = theta[None, :] - theta[:, None]
            residual = power + coupling * (a * np.sin(diff)).sum(axis=1)
            if np.max(np.abs(residual)) < 1e-13 * max(1.0, np.abs(power).max()):
                break
            jac = coupling * a * np.cos(diff)
            jac[np.diag_indices(n)] = -jac.sum(axis=1)
            # the phases are defined up to a common shift: fix the mean with an extra row
            step = np.linalg.lstsq(np.vstack([jac, np.ones(n)]),
                                   -np.concatenate([residual, [0.0]]), rcond=None)[0]
            theta = theta + step
        else:
            raise ValueError(
                f"SwingNetwork has no synchronous state that Newton's method reaches: the "
                f"coupling K = {float(coupling)!r} cannot carry the powers (max |P| = "
                f"{float(np.abs(power).max())!r}); accepted: a larger coupling or smaller "
                "powers")
        diff = theta[None, :] - theta[:, None]
        if np.any(np.abs(diff[a > 0]) >= math.pi / 2):
            raise ValueError(
                f"SwingNetwork's synchronous state found has a line with a phase "
                f"difference >= pi/2 (unstable); the coupling K = {coupling!r} is too weak "
                "for the powers; accepted: a larger coupling or smaller powers")
        return theta - theta.mean()

    def to_dict(self) -> dict:
        """A JSON-able description (dataset attribute ``system``)."""
        return {"system": "SwingNetwork", "adjacency": self.adjacency.tolist(),
                "power": self.power.tolist(), "damping": self.damping,
                "coupling": self.coupling}
