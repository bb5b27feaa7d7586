"""sweep: JIT-compiled parameter sweeps of pendulum dynamics.

Importing ``sweep`` compiles nothing and loads no matplotlib.
"""

__version__ = "0.1.0"

from .engine import run as run
from .grid import Grid as Grid
from .grid import from_degrees as from_degrees
from .io import load as load
from .io import save as save
from ._kernels import Status as Status
from .scene import Damping as Damping
from .scene import Forcing as Forcing
from .scene import Scene as Scene

_LAZY_MODULES = ("plot", "io", "cli", "maps", "metrics", "methods", "accuracy")


def __getattr__(name):
    """Import submodules such as `sweep.plot` on first use, so that ``import sweep``
    stays cheap (no matplotlib)."""
    if name in _LAZY_MODULES:
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'sweep' has no attribute {name!r}")


__all__ = [
    "Damping",
    "Forcing",
    "Grid",
    "Scene",
    "Status",
    "__version__",
    "from_degrees",
    "load",
    "run",
    "save",
]
