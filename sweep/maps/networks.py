"""Maps of swing networks (`sweep.SwingNetwork`): which perturbations the grid
survives, and single-node basin stability.

Menck, Heitzig, Marwan, Kurths, Nat. Phys. 9, 89 (2013) define a node's *basin
stability* as the probability that the grid returns to its synchronous state after a
random perturbation of that node's ``(theta, omega)``; Menck, Heitzig, Kurths, Kurths,
Nat. Commun. 5, 3969 (2014) found it low at "dead ends" (nodes hanging off the grid by
one line). `basin_stability` estimates it per node from sampled perturbations, with
binomial standard errors (`sweep.maps.fractions`).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._validate import check_count, check_real

__all__ = ["SYNC_TOLERANCE", "basin_stability", "synchronized"]

#: Largest final frequency deviation max abs(omega_i) [rad/s] of a trajectory counted as
#: back in the synchronous state. A desynchronised node keeps rotating at about
#: P_i / alpha (10 rad/s for P = 1, alpha = 0.1), and a returning one decays as
#: exp(-alpha t / 2): 0.1 separates them once t_end is several 2 / alpha.
SYNC_TOLERANCE = 0.1


def synchronized(ds: xr.Dataset, tolerance: float = SYNC_TOLERANCE) -> xr.DataArray:
    """1 where the network ended synchronous (``frequency_spread <= tolerance``), 0
    where it did not, -1 where the trajectory failed (``status`` not ok).

    Parameters
    ----------
    ds : xarray.Dataset
        A `sweep.run` of a `sweep.SwingNetwork` that observed ``synchrony``.
    tolerance : float
        [rad/s], > 0 (`SYNC_TOLERANCE`).
    """
    tolerance = check_real("tolerance", tolerance, minimum=0.0, strict=True,
                           accepted="a finite number > 0 (rad/s)")
    if "frequency_spread" not in ds:
        raise ValueError("synchronized needs a run of a SwingNetwork that observed "
                         "'synchrony' (variable frequency_spread); accepted: "
                         "sweep.run(network, grid, observe=('synchrony',), ...)")
    labels = xr.where(ds.frequency_spread <= tolerance, 1, 0).astype(np.int8)
    labels = labels.where(ds.status == 0, -1).astype(np.int8)
    labels.attrs = {"long_name": "back in the synchronous state",
                    "comment": f"frequency_spread (max |omega_i| at t_end) <= {tolerance:g} "
                               "rad/s; -1 where the trajectory failed",
                    "flag_values": np.array([-1, 0, 1], dtype=np.int8),
                    "flag_meanings": "unresolved desynchronised synchronised",
                    "unresolved": -1}
    return labels.rename("synchronized")


def basin_stability(network, n: int, *, seed: int, t_end: float = 200.0, dt: float = 0.01,
                    delta_theta=(-math.pi, math.pi), delta_omega=(-15.0, 15.0),
                    tolerance: float = SYNC_TOLERANCE, nodes=None,
                    progress: bool | None = None) -> xr.Dataset:
    """Single-node basin stability of every node (or of ``nodes``): the fraction of
    ``n`` random perturbations of the node's phase and frequency, drawn uniformly in
    the box ``delta_theta`` x ``delta_omega``, after which the grid is back in its
    synchronous state at ``t_end``.

    Parameters
    ----------
    network : sweep.SwingNetwork
    n : int
        Perturbations per node (>= 1): the standard error is about 0.5 / sqrt(n).
    seed : int
        Seed of the perturbations (>= 0): node k draws with seed ``seed + k``, so a
        node's estimate does not depend on which other nodes are asked for.
    t_end, dt : float
        Integration time and step [s] (`sweep.run`).
    delta_theta, delta_omega : (float, float)
        The box of perturbations [rad], [rad/s].
    tolerance : float
        Synchronous at t_end if max abs(omega_i) <= tolerance [rad/s] (`synchronized`).
    nodes : sequence of int, optional
        The nodes to perturb; default all.
    progress : bool, optional
        As in `sweep.run`.

    Returns
    -------
    xarray.Dataset
        Over dimension ``node``: ``basin_stability`` (fraction, 1) and
        ``standard_error`` (binomial, sqrt(p (1 - p) / n): exact for these independent
        uniform draws); ``failed`` counts trajectories that failed (not counted in n).
    """
    from ..engine import run
    from ..grid import Points, sample
    from ..physics.network import SwingNetwork

    if not isinstance(network, SwingNetwork):
        raise TypeError(f"basin_stability takes a sweep.SwingNetwork, got {network!r}")
    n = check_count("n", n, accepted="an int >= 1 (perturbations per node)")
    nodes = np.arange(network.n_nodes) if nodes is None else np.asarray(nodes)
    if nodes.ndim != 1 or not np.all((nodes >= 0) & (nodes < network.n_nodes)) or \
            not np.all(nodes == np.round(nodes)):
        raise ValueError(f"nodes must be node indices 0 to {network.n_nodes - 1}, got "
                         f"{nodes!r}")
    columns = {"perturbed_node": [], "delta_theta": [], "delta_omega": []}
    for node in nodes.astype(int):
        points = sample(n, seed=seed + int(node), method="random",
                        delta_theta=delta_theta, delta_omega=delta_omega)
        columns["perturbed_node"].append(np.full(n, float(node)))
        columns["delta_theta"].append(points.axes["delta_theta"])
        columns["delta_omega"].append(points.axes["delta_omega"])
    points = Points(**{k: np.concatenate(v) for k, v in columns.items()})
    ds = run(network, points, t_end=t_end, dt=dt, observe=("synchrony",), progress=progress)
    labels = synchronized(ds, tolerance).values.reshape(len(nodes), n)
    ok = labels >= 0
    counted = ok.sum(axis=1)
    p = np.where(counted > 0, (labels == 1).sum(axis=1) / np.maximum(counted, 1), np.nan)
    error = np.sqrt(p * (1 - p) / np.maximum(counted, 1))
    coords = {"node": nodes.astype(int)}
    degree = (network.adjacency[nodes.astype(int)] > 0).sum(axis=1)
    return xr.Dataset(
        {"basin_stability": ("node", p, {
            "units": "1", "long_name": "single-node basin stability",
            "comment": "fraction p of the node's perturbations after which the grid is "
                       "synchronous again (sweep.maps.synchronized); NaN where every "
                       "trajectory failed"}),
         "standard_error": ("node", error, {
             "units": "1", "long_name": "standard error of the basin stability",
             "comment": "binomial: sqrt(p (1 - p) / n), n the trajectories that did not "
                        "fail"}),
         "failed": ("node", (~ok).sum(axis=1), {"long_name": "failed trajectories"}),
         "degree": ("node", degree, {"long_name": "number of lines of the node"})},
        coords, {"perturbations_per_node": n, "seed": seed, "t_end": t_end, "dt": dt,
                 "delta_theta": list(np.asarray(delta_theta, dtype=float)),
                 "delta_omega": list(np.asarray(delta_omega, dtype=float)),
                 "tolerance": tolerance})
