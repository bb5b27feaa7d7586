"""Deprecated: the 0.1 module path of `sweep.execution.checkpoint` (per-chunk
checkpoints).

``import sweep.checkpoint`` and ``from sweep.checkpoint import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.execution.checkpoint` itself: every name, public or private, is the same object
under both paths. This file goes in 0.3.
"""

import sys
import warnings

from .execution import checkpoint as _new

warnings.warn("the module path sweep.checkpoint is deprecated and will be removed in 0.3; "
              "import sweep.execution.checkpoint instead", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _new  # the import statement binds the new module itself
