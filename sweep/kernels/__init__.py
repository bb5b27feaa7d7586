"""Compiled kernels: generated source per (model, effects, observables, method), the
vectorised math they call, and the cache that compiles each at most once per machine.

Reads `sweep.physics`, `sweep.methods` and `sweep.observables`; nothing here imports
the engine, the execution back ends or the maps.
"""

from .generate import (KernelSpec, Status, build, check_method_fits, check_observables_fit,
                       method_of, n_columns, source)

__all__ = ["KernelSpec", "Status", "build", "check_method_fits", "check_observables_fit",
           "method_of", "n_columns", "source"]
