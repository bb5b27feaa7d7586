"""Deprecated: the 0.1 module path of `sweep.physics.scene` (the Scene).

``import sweep.scene`` and ``from sweep.scene import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.physics.scene` itself: every name it has is the same object under both paths.
This file goes in 0.3. (``Scene``, ``Damping``, ``Forcing`` and the others are
``sweep.Scene``, ... as well. 0.1's ``PARAMETERS`` and ``PARAMETER_INFO`` are gone:
the functions `sweep.physics.scene.parameter_names` and ``parameter_info`` replace
them.)
"""

import sys
import warnings

from .physics import scene as _new

warnings.warn("the module path sweep.scene is deprecated and will be removed in 0.3; "
              "import sweep.physics.scene instead", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _new  # the import statement binds the new module itself
