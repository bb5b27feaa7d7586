"""The 0.1 module paths that moved (`sweep.metrics`, `sweep.response`, `sweep.scene`,
`sweep.checkpoint`): each old path is a shim that calls `forward`. Removed in 0.3."""

from __future__ import annotations

import importlib
import sys
import warnings

__all__ = ["forward"]


def forward(old: str, new: str) -> None:
    """Warn that module path ``old`` moved to ``new`` (a DeprecationWarning pointing at
    the line that imports ``old``) and put the module ``new`` in its place in
    `sys.modules`, so that the import statement binds the new module itself: every name,
    public or private, is the same object under both paths.

    Parameters
    ----------
    old, new : str
        Dotted module paths (``"sweep.metrics"``, ``"sweep.maps.metrics"``).
    """
    module = importlib.import_module(new)
    # stacklevel: 1 here, 2 the shim's body, 3 the importer's line (the import
    # machinery's frames in between are skipped by Python for importlib's own code)
    warnings.warn(f"the module path {old} is deprecated and will be removed in 0.3; "
                  f"import {new} instead", DeprecationWarning, stacklevel=3)
    sys.modules[old] = module
