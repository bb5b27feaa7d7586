"""Deprecated: the 0.1 module path of `sweep.maps.response` (frequency responses).

``import sweep.response`` and ``from sweep.response import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.maps.response` itself: every name, public or private, is the same object under
both paths. This file goes in 0.3.

``sweep.response`` as an attribute of the package (``import sweep`` then
``sweep.response.frequency_response(...)``, through `sweep.__getattr__`) is
`sweep.maps.response` too; it is not deprecated and does not warn.
"""

from ._moved import forward

forward("sweep.response", "sweep.maps.response")
