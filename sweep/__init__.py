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
