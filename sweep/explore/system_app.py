"""The explorer's page for a system with several coordinates: the single pendulum's page
(`sweep.explore.app`) with the system's model (`sweep.explore.systems.SystemExplorer`),
its axes' units on the map, and a clicked start's every coordinate and velocity over
time (``name="trajectory"``) and each coordinate's phase portrait (``name="phase"``).
"""

from __future__ import annotations

import math

from bokeh.models import ColumnDataSource
from bokeh.palettes import Category10_10

from .app import ExplorerApp, _fit, _legend_above, _Session
from .networks import NetworkExplorer
from .systems import SystemExplorer, SystemTrajectory

__all__ = ["NetworkExplorerApp", "SystemExplorerApp"]


class _SystemSession(_Session):
    """One browser session of a system's explorer."""

    controls_heading = "System"

    def _build(self) -> None:
        super()._build()
        positions, velocities = self.explorer.series_names()
        names = positions + velocities
        self.series_source = ColumnDataSource({"t": [], **{n: [] for n in names}})
        for fig in (self.trajectory, self.phase):
            fig.renderers = []
            for legend in fig.legend:
                legend.items = []
        position_units, velocity_units = self._units()
        self.trajectory.yaxis.axis_label = (f"coordinates [{position_units}], "
                                            f"velocities [{velocity_units}]")
        for k, name in enumerate(names):
            self.trajectory.line("t", name, source=self.series_source, legend_label=name,
                                 color=Category10_10[k % 10],
                                 line_dash="solid" if k < len(positions) else "dashed")
        if not self.phase.legend:  # an unforced system: the curves' legend above them too
            _legend_above(self.phase, [])
        self.phase.xaxis.axis_label = f"coordinate [{position_units}]"
        self.phase.yaxis.axis_label = f"velocity [{velocity_units}]"
        for k, (position, velocity) in enumerate(zip(positions, velocities, strict=True)):
            self.phase.line(position, velocity, source=self.series_source,
                            legend_label=f"({position}, {velocity})",
                            color=Category10_10[k % 10])

    def _units(self) -> tuple[str, str]:
        """The coordinates' units and the velocities' (each distinct one, in order)."""
        from ..plot import units_text

        scene = self.explorer.state.scene
        coordinates = getattr(getattr(scene, "declaration", None), "coordinates", None)
        if not coordinates:  # a network: its nodes' phases
            return "rad", "rad/s"
        return tuple(", ".join(dict.fromkeys(units_text(getattr(c, key))
                                             for c in coordinates))
                     for key in ("units", "velocity_units"))

    def _axis_text(self, name: str) -> str:
        from ..plot import units_text

        return f"{name} [{units_text(self.explorer.axis_units().get(name, '1'))}]"

    def _start_text(self, name: str, value: float) -> str:
        """``name = value units``, and in degrees too for an angle axis (the map's:
        `sweep.plot.degree_units`)."""
        from ..plot import degree_units, units_text

        units = units_text(self.explorer.axis_units().get(name, "1"))
        shown = f"{name} = {value:.6g}" + (f" {units}" if units else "")
        degrees = degree_units(name, units)
        if degrees is not None:
            shown += f" ({math.degrees(value):.4g} {degrees})"
        return shown

    def show_trajectory(self, traj: SystemTrajectory) -> None:
        v = self.explorer.state.view
        self.clicked.data = {"x": [traj.point[v.x]], "y": [traj.point[v.y]]}
        self.series_source.data = {"t": traj.t, **traj.series}
        positions, velocities = self.explorer.series_names()
        _fit(self.trajectory, [traj.t], list(traj.series.values()))
        _fit(self.phase, [traj.series[n] for n in positions],
             [traj.series[n] for n in velocities])
        # the clicked axes' values with their units (an angle's in degrees too, as the
        # map's axes show it), one a line: two do not fit the panel's width on one
        where = ",\n".join(self._start_text(k, val) for k, val in traj.point.items())
        self.trajectory.title.text = f"trajectory from {where}"
        start = ", ".join(self._start_text(k, val) for k, val in traj.start.items())
        # a continuous map's clicked value is a value, not a label (`SystemExplorer.label_at`)
        heading = "value" if self.result is not None and not self.result.legend else "label"
        self.info.object = (f"**start** {start}  \n**status** {traj.status}  \n"
                            f"**{heading}** {traj.label}")
        self.traj_python.object = f"```python\n{traj.python}```"
        self.traj_toml.object = f"```toml\n{traj.toml}```"


class SystemExplorerApp(ExplorerApp):
    """`ExplorerApp` of a `sweep.DoublePendulum` or `sweep.CoupledPendula` (see
    `sweep.explore`)."""

    explorer_class = SystemExplorer
    session_class = _SystemSession


class NetworkExplorerApp(ExplorerApp):
    """`ExplorerApp` of a `sweep.SwingNetwork` (see `sweep.explore`)."""

    explorer_class = NetworkExplorer
    session_class = _SystemSession
