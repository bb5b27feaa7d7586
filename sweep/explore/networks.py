"""The explorer's model for a swing network (`sweep.SwingNetwork`): `NetworkExplorer`,
the systems' explorer (`sweep.explore.systems.SystemExplorer`) with what a network's
runs have in place of a declaration's coordinates.

- a start is a perturbation of one node from the synchronous state: ``perturbed_node``
  (a control), ``delta_theta`` [rad] and ``delta_omega`` [rad/s] (the map's axes by
  default), so a 100-node network is explored one node at a time;
- the quantities are the per-run variables of the network's observables (read from the
  dataset `sweep.diskspace.layout` describes, without computing: ``frequency_spread``,
  ``order_parameter``), and `sweep.maps.synchronized`;
- the controls are the network's damping and coupling (`sweep.physics.network.
  NETWORK_PARAMETERS`: units, bounds); the adjacency and the powers are the network's;
- a click gives every node's phase and frequency over time.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import maps
from ..diskspace import layout as run_layout
from ..grid import Grid
from ..kernels.network import NETWORK_OBSERVABLES
from ..physics.network import NETWORK_PARAMETERS, SwingNetwork
from ..physics.system import System
from .model import Control, Explorer
from .quantities import Quantity
from .systems import SystemExplorer

__all__ = ["NetworkExplorer", "explorer_for", "network_quantities"]

#: Parameters of a network that the controls set (the others are a start's).
CONTROLLED = ("damping", "coupling")

#: A start: the perturbed node and its perturbation from the synchronous state.
START = ("perturbed_node", "delta_theta", "delta_omega")


def _always(network) -> bool:
    return True


def network_quantities(network: SwingNetwork) -> dict[str, Quantity]:
    """Every map of ``network``: the variables of each observable with one value per
    run (per-node variables have a ``node`` dimension and are left out), then
    ``synchronized`` (`sweep.maps.synchronized`: 1 back in the synchronous state)."""
    out: dict[str, Quantity] = {}
    for observable in NETWORK_OBSERVABLES:
        ds = run_layout(network, Grid(delta_theta=[0.0]), t_end=1.0, dt=1.0,
                        observe=(observable,))
        for name, da in ds.data_vars.items():
            if name == "status" or "node" in da.dims:
                continue
            out[f"var:{name}"] = Quantity(
                f"var:{name}", f"{observable}: {name}", (observable,), False, _always,
                lambda ds, name=name: ds[name], False, expression=f'ds["{name}"]')
    out["synchronized"] = Quantity(
        "synchronized", "synchrony: back in the synchronous state", ("synchrony",), False,
        _always, maps.synchronized, True, expression="maps.synchronized(ds)")
    return out


class NetworkExplorer(SystemExplorer):
    """`SystemExplorer` of a `sweep.SwingNetwork` (see the module docstring).

    Parameters
    ----------
    network : sweep.SwingNetwork
    grid : sweep.Grid
        Axes ``delta_theta``, ``delta_omega``, ``damping``; ``perturbed_node`` as one
        value (default 0, the first node).
    **kwargs
        As `SystemExplorer` (default quantity: ``synchronized``).
    """

    takes = SwingNetwork
    trajectory_observe = ("synchrony",)

    def __init__(self, network, grid, **kwargs) -> None:
        if isinstance(grid, Grid) and "perturbed_node" not in grid.axes:
            grid = Grid(**grid.axes, perturbed_node=[0])
        kwargs.setdefault("quantity", "synchronized")
        super().__init__(network, grid, **kwargs)

    @staticmethod
    def _quantities_of(network) -> dict[str, Quantity]:
        return network_quantities(network)

    @staticmethod
    def _start_names(network) -> list[str]:
        return list(START)

    @staticmethod
    def _preferred_axes(network) -> list[str]:
        return ["delta_theta", "delta_omega"]

    @staticmethod
    def _axes_of(network) -> tuple[str, ...]:
        return ("delta_theta", "delta_omega", "damping")

    def series_names(self) -> tuple[list[str], list[str]]:
        n = self.state.scene.n_nodes
        return [f"theta_{k}" for k in range(n)], [f"omega_{k}" for k in range(n)]

    def axis_units(self) -> dict[str, str]:
        return {p.axis: p.units for p in NETWORK_PARAMETERS}

    @staticmethod
    def _default_range(network, name: str) -> tuple[float, float]:
        if name == "delta_theta":
            return (-math.pi, math.pi)
        if name == "delta_omega":  # the scale of the lines' frequency sqrt(K * degree)
            degree = float(network.adjacency.sum(axis=1).max())
            w = math.sqrt(network.coupling * degree)
            return (-2.0 * w, 2.0 * w)
        value = network.parameters().get(name, 1.0)
        return (0.5 * value, 1.5 * value) if value else (0.0, 1.0)

    def parameter_controls(self) -> list[Control]:
        """The network's damping and coupling (units, bound), then the start's values
        not on the map's axes (``perturbed_node``: a node index)."""
        network, shown = self.state.scene, (self.state.view.x, self.state.view.y)
        info = {p.axis: p for p in NETWORK_PARAMETERS}
        values = network.parameters()
        out = []
        for name in CONTROLLED:
            p = info[name]
            bound = f" ({'>' if p.strict else '>='} {p.minimum:g})"
            note = " (on the map's axis)" if name in shown else ""
            out.append(Control(name, f"{name} [{p.unit_text}]", "float", float(values[name]),
                               minimum=p.minimum, strict=p.strict,
                               help=f"{p.long_name}{bound}{note}", group="scene"))
        for name, value in self.state.start:
            if name in shown:
                continue
            p = info[name]
            if name == "perturbed_node":
                out.append(Control(name, "perturbed_node", "int", int(value), minimum=-1,
                                   help=f"{p.long_name}: 0 to {network.n_nodes - 1}",
                                   group="scene"))
            else:
                out.append(Control(name, f"{name} [{p.unit_text}]", "float", float(value),
                                   help=f"{p.long_name} (where it is not an axis)",
                                   group="scene"))
        return out

    @staticmethod
    def _with_parameters(network, values: dict[str, float]):
        for name in values:
            if name not in CONTROLLED:
                raise ValueError(f"{name}: not a parameter of SwingNetwork; accepted: "
                                 f"{', '.join(CONTROLLED)} (and the start's "
                                 f"{', '.join(START)})")
        return dataclasses.replace(network, **values)

    def _series(self, ds, one: dict) -> tuple[dict, dict]:
        positions, velocities = self.series_names()
        theta = np.asarray(ds.theta.isel(one).transpose("node", "time").values)
        omega = np.asarray(ds.omega.isel(one).transpose("node", "time").values)
        series = {**dict(zip(positions, theta, strict=True)),
                  **dict(zip(velocities, omega, strict=True))}
        units = {**{n: "rad" for n in positions}, **{n: "rad s-1" for n in velocities}}
        return series, units

    def _end_label(self, ds, one: dict) -> str:
        return (f"frequency_spread = {float(ds.frequency_spread.isel(one)):.6g} rad/s, "
                f"order_parameter = {float(ds.order_parameter.isel(one)):.6g}")


def explorer_for(target, grid, **kwargs) -> Explorer:
    """`SystemExplorer` for a system with several coordinates, else `Explorer` (the
    single pendulum's `sweep.Scene`)."""
    if isinstance(target, SwingNetwork):
        return NetworkExplorer(target, grid, **kwargs)
    if isinstance(target, System):
        return SystemExplorer(target, grid, **kwargs)
    return Explorer(target, grid, **kwargs)
