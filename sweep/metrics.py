"""Deprecated: the 0.1 module path of `sweep.maps.metrics` (basin metrics).

``import sweep.metrics`` and ``from sweep.metrics import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.maps.metrics` itself: every name, public or private, is the same object under
both paths. This file goes in 0.3.

``sweep.metrics`` as an attribute of the package (``import sweep`` then
``sweep.metrics.basin_entropy(...)``, through `sweep.__getattr__`) is
`sweep.maps.metrics` too; it is not deprecated and does not warn.
"""

from ._moved import forward

forward("sweep.metrics", "sweep.maps.metrics")
