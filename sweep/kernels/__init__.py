"""Compiled kernels: source generated from the effects' declarations, the method's data
and the observables' snippets, the vectorised math it calls, and the cache that
compiles each kernel at most once per machine.

Modules, each one concern: `spec` (what a kernel is built for, status codes, fit
checks), `terms` (the physics as source, from `sweep.physics`), `steppers` (one step of
a method, from `sweep.methods`), `snippets` (observables), `lanes` (per-lane code of a
block), `fixed` and `adaptive` (the two kernel bodies), `source` (the module text),
`cache` (build, memo, disk cache), `threads` (a kernel's blocks on threads), `vecmath`
(vectorisable sin/cos, float64 and float32), `precision` (a module made float32),
`cuda` (the same pieces as one CUDA thread per trajectory), `system` and `network` (the
kernels of systems with several coordinates and of swing networks), `rewrite` (a
system's derived source made fast for the lanes: parameter-only work hoisted, sums of
products fused).

Reads `sweep.physics`, `sweep.methods` and `sweep.observables`; nothing here imports
the engine, the execution back ends or the maps.
"""

from .cache import build, compiled
from .snippets import catalogue_argument
from .source import source
from .spec import (
    DEVICES,
    DTYPES,
    KernelSpec,
    Status,
    check_device,
    check_dtype,
    check_method_fits,
    check_observables_fit,
    check_tangent_fits,
    declarations,
    failure_summary,
    method_of,
    n_columns,
    status_counts,
)

__all__ = ["DEVICES", "DTYPES", "KernelSpec", "Status", "build", "catalogue_argument",
           "check_device", "check_dtype", "compiled",
           "check_method_fits",
           "check_observables_fit", "check_tangent_fits", "declarations", "failure_summary",
           "method_of", "n_columns", "source", "status_counts"]
