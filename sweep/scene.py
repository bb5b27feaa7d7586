"""Deprecated: the 0.1 module path of `sweep.physics.scene` (the Scene).

``import sweep.scene`` and ``from sweep.scene import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.physics.scene` itself: every name it has is the same object under both paths.
This file goes in 0.3. (``Scene``, ``Damping``, ``Forcing`` and the others are
``sweep.Scene``, ... as well. 0.1's ``PARAMETERS`` and ``PARAMETER_INFO`` are gone:
the functions `sweep.physics.scene.parameter_names` and ``parameter_info`` replace
them.)
"""

from ._moved import forward

forward("sweep.scene", "sweep.physics.scene")
