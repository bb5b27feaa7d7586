"""Deprecated: the 0.1 module path of `sweep.maps.metrics` (basin metrics).

``import sweep.metrics`` and ``from sweep.metrics import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.maps.metrics` itself: every name, public or private, is the same object under
both paths. This file goes in 0.3.

``sweep.metrics`` as an attribute of the package (``import sweep`` then
``sweep.metrics.basin_entropy(...)``, through `sweep.__getattr__`) is
`sweep.maps.metrics` too; it is not deprecated and does not warn.
"""

import sys
import warnings

from .maps import metrics as _new

warnings.warn("the module path sweep.metrics is deprecated and will be removed in 0.3; "
              "import sweep.maps.metrics instead", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _new  # the import statement binds the new module itself
