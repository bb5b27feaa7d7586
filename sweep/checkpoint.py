"""Deprecated: the 0.1 module path of `sweep.execution.checkpoint` (per-chunk
checkpoints).

``import sweep.checkpoint`` and ``from sweep.checkpoint import ...`` warn once, with a
DeprecationWarning that points at the importing line, and give the module
`sweep.execution.checkpoint` itself: every name, public or private, is the same object
under both paths. This file goes in 0.3.
"""

from ._moved import forward

forward("sweep.checkpoint", "sweep.execution.checkpoint")
