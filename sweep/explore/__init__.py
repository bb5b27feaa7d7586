"""Explore maps in the browser: ``sweep.explore(scene, grid, **run_kwargs)`` and
``sweep explore [RUN.toml]``.

`sweep.explore.model` is the app's model in plain Python (state, validation, history,
cancellable computation, snippets, exports; no Panel import); `sweep.explore.numbers`
the numbers of a view (fractions, basin entropy, and the on-request ones registered by
name); `sweep.explore.app` is the Panel/Bokeh page (the optional extra ``explore``:
``pip install -e ".[explore]"``).
Importing this package imports neither Panel nor Bokeh; `explore` does.

The module itself is callable, ``sweep.explore(scene, grid, ...)`` being
``sweep.explore.explore(scene, grid, ...)``: the package and the function share the name
``sweep.explore``.
"""

from __future__ import annotations

import sys
import types

__all__ = ["explore"]


def explore(scene, grid, **run_kwargs):
    """An interactive explorer of ``scene``'s maps over ``grid``, recomputed on zoom.

    Parameters
    ----------
    scene : sweep.Scene, sweep.DoublePendulum, sweep.CoupledPendula or sweep.SwingNetwork
        The single pendulum, or a system with several coordinates
        (`sweep.explore.systems.SystemExplorer`: its observables' variables as maps,
        its declaration's parameters as controls, every coordinate over time on a click;
        a network's starts are one node's perturbation, `sweep.explore.networks`).
    grid : sweep.Grid
        Its first two axes with more than one value are the map's x and y (for example
        ``theta0`` [rad] and ``omega0`` [rad/s], or a system's ``theta1_0`` and
        ``theta2_0``); their ranges are the home view (the resolution, pixels per axis,
        is ``resolution``, default 400 for a Scene and 200 for a system, not their
        length).
    **run_kwargs
        `sweep.run` arguments: ``t_end`` and ``dt`` [s] (required), ``t_transient``
        [s], ``method``, ``device``, ``t0``, ``dtype``, ``strobe_samples``, ...; and
        ``quantity`` (a key of `sweep.explore.model.QUANTITIES`, default: basins for a
        forced scene, the final well for damping alone, else motion; for a system a key
        of `sweep.explore.systems.system_quantities`, default ``log10:flip_time``, and
        for a driven system also ``basins`` and ``period``) and ``resolution``.
        ``observe``, ``stop_early`` and ``attractors`` are set per map and ignored.

    Returns
    -------
    sweep.explore.app.ExplorerApp
        (`sweep.explore.system_app.SystemExplorerApp` for a system,
        `~sweep.explore.system_app.NetworkExplorerApp` for a network)
        Displays in a Jupyter notebook (after ``import panel; panel.extension()``, as
        every Panel object); ``.show()`` opens it in a browser from a local
        server, ``.servable()`` marks it for ``panel serve``, ``.serve(port=...)``
        starts a server (listening once it returns, the warm-up following on a
        background thread; `sweep.explore.app.AddressUnavailable`, an OSError, when
        the address or the port cannot be bound).

    Raises
    ------
    ImportError
        Without Panel and Bokeh (``pip install -e ".[explore]"``).
    sweep.explore.model.InvalidInput
        A ValueError naming the setting sweep's validators refuse.
    """
    from ..physics.network import SwingNetwork
    from ..physics.system import System

    if isinstance(scene, SwingNetwork):
        from .system_app import NetworkExplorerApp

        return NetworkExplorerApp(scene, grid, **run_kwargs)
    if isinstance(scene, System):
        from .system_app import SystemExplorerApp

        return SystemExplorerApp(scene, grid, **run_kwargs)
    from .app import ExplorerApp

    return ExplorerApp(scene, grid, **run_kwargs)


class _CallableModule(types.ModuleType):
    """``sweep.explore`` is this package; calling it calls `explore`."""

    def __call__(self, *args, **kwargs):
        return explore(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
