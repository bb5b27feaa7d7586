"""Deprecated: the 0.1 module path of `sweep.maps.response` (frequency responses).

``import sweep.response`` and ``from sweep.response import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.maps.response` itself: every name, public or private, is the same object under
both paths. This file goes in 0.3.

``sweep.response`` as an attribute of the package (``import sweep`` then
``sweep.response.frequency_response(...)``, through `sweep.__getattr__`) is
`sweep.maps.response` too; it is not deprecated and does not warn.
"""

import sys
import warnings

from .maps import response as _new

warnings.warn("the module path sweep.response is deprecated and will be removed in 0.3; "
              "import sweep.maps.response instead", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _new  # the import statement binds the new module itself
