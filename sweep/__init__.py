"""sweep: JIT-compiled parameter sweeps of pendulum dynamics.

Importing ``sweep`` compiles nothing and loads no matplotlib.
"""

from ._version import __version__ as __version__
from .engine import run as run
from .grid import Grid as Grid
from .grid import Points as Points
from .grid import from_degrees as from_degrees
from .grid import sample as sample
from .io import load as load
from .io import save as save
from .kernels import Status as Status
from .physics import CoupledPendula as CoupledPendula
from .physics import Damping as Damping
from .physics import DeclaredSystem as DeclaredSystem
from .physics import DoublePendulum as DoublePendulum
from .physics import Forcing as Forcing
from .physics import PivotDrive as PivotDrive
from .physics import QuadraticDrag as QuadraticDrag
from .physics import Scene as Scene
from .physics import SwingNetwork as SwingNetwork
from .physics import Torque as Torque

#: Submodules imported on first use, so that ``import sweep`` stays cheap (no
#: matplotlib): ``sweep.plot``, ``sweep.maps``, ... ``sweep.metrics`` and
#: ``sweep.response`` are the modules of the same name in `sweep.maps`: as attributes
#: they are kept and do not warn. Their 0.1 module paths (``import sweep.metrics``,
#: ``from sweep.response import ...``), like those of ``sweep.scene`` and
#: ``sweep.checkpoint``, are deprecated shims (sweep/metrics.py, ...) that warn once
#: and give the same module object as the attribute.
_LAZY_MODULES = {"plot": "plot", "io": "io", "cli": "cli", "maps": "maps",
                 "metrics": "maps.metrics", "response": "maps.response",
                 "methods": "methods", "accuracy": "accuracy",
                 # the browser explorer (extra "explore"); the module is callable:
                 # sweep.explore(scene, grid, ...) is sweep.explore.explore(...)
                 "explore": "explore"}

#: Functions imported on first use, like the modules above: name -> (module, name).
_LAZY_FUNCTIONS = {"map_accuracy": ("map_precision", "map_accuracy")}


def __getattr__(name):
    """Import submodules such as `sweep.plot` on first use."""
    if name in _LAZY_MODULES:
        import importlib

        return importlib.import_module(f".{_LAZY_MODULES[name]}", __name__)
    if name in _LAZY_FUNCTIONS:
        import importlib

        module, attribute = _LAZY_FUNCTIONS[name]
        return getattr(importlib.import_module(f".{module}", __name__), attribute)
    raise AttributeError(f"module 'sweep' has no attribute {name!r}")


__all__ = [
    "CoupledPendula",
    "Damping",
    "DeclaredSystem",
    "DoublePendulum",
    "Forcing",
    "Grid",
    "PivotDrive",
    "Points",
    "QuadraticDrag",
    "Scene",
    "Status",
    "SwingNetwork",
    "Torque",
    "__version__",
    "explore",
    "from_degrees",
    "load",
    "map_accuracy",
    "run",
    "sample",
    "save",
]
