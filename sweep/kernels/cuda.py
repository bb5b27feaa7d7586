"""The fixed-step kernel for an NVIDIA GPU (``device="cuda"``): one CUDA thread per
trajectory, from the same generated pieces as the CPU kernels.

The method's step (`sweep.kernels.steppers`: the same lines the CPU lanes run), the
effects' terms (`sweep.kernels.terms`, as device functions), the drives and the
observables' snippets are pasted into a ``numba.cuda`` kernel in which thread ``i``
integrates trajectory ``i`` from its row of the parameter table to ``t_end`` (or, with
early stop, until its observables are settled: that thread leaves the loop while the
others of its warp go on). There is no second hand-written physics.

The generated module defines ``kernel`` with the CPU kernels' contract (see
`sweep.kernels.source`): a Python function that copies the chunk's parameter rows to
the GPU, launches the CUDA kernel and copies the outputs back, so memory stays
O(chunk) on both sides, and checkpoints, Dask and progress work as on the CPU.

On the GPU, ``vsin``/``vcos`` are CUDA's ``sin``/``cos`` (libdevice, correctly rounded
to within an ulp or two), not `sweep.kernels.vecmath`'s polynomials, so results agree
with the CPU kernels to rounding, not bit for bit.

`numba.cuda` is imported only by the generated module and by `available`: ``import
sweep`` never needs CUDA. Without a GPU, `numba.cuda`'s simulator
(``NUMBA_ENABLE_CUDASIM=1``) runs the same kernels in Python threads, which is how the
test suite checks them.
"""

from __future__ import annotations

import re

from .fixed import NL, _drives
from .lanes import indent
from .snippets import (
    failed_samples,
    failed_status,
    kernel_arguments,
    ok_test,
    renormalisations,
    snippets,
    stop_source,
)
from .spec import KernelSpec, Status, n_columns
from .steppers import STEPPERS
from .terms import load_lines

__all__ = ["THREADS_PER_BLOCK", "available", "cuda_kernel", "cuda_module", "device_functions"]

#: CUDA threads per block: a multiple of the warp (32); 128 keeps several blocks per
#: multiprocessor with the kernels' register use.
THREADS_PER_BLOCK = 128


def available() -> str | None:
    """None if a CUDA device can run the kernels (or numba's CUDA simulator is on),
    else the reason, for the error message."""
    try:
        from numba import cuda
    except Exception as exc:  # noqa: BLE001  # pragma: no cover - numba without its CUDA target
        return f"numba's CUDA target cannot be imported ({exc})"
    try:
        if cuda.is_available():
            return None
    except Exception as exc:  # noqa: BLE001  # pragma: no cover - broken driver or toolkit
        return f"numba.cuda could not reach a GPU ({exc})"
    return ("no CUDA GPU was found (numba.cuda.is_available() is False: no NVIDIA GPU, "
            "driver or CUDA toolkit; the extra cuda installs numba's CUDA target: pip "
            "install -e \".[cuda]\" in a checkout, or pip install 'numba-cuda[cu12]>=0.20' "
            "'numpy<2.5')")


_DEVICE_MATH = '''\
@cuda.jit(device=True)
def vsin(x):
    return math.sin(x)


@cuda.jit(device=True)
def vcos(x):
    return math.cos(x)


@cuda.jit(device=True)
def vsincos(x):
    return math.sin(x), math.cos(x)
'''


_DEVICE_MATH32 = '''\
from sweep.kernels.vecmath import P1, P2, TWO_OVER_PI


@cuda.jit(device=True)
def _reduce(x):
    # x - k pi/2 in float64 (x is float64: the angle or a drive's phase), rounded once
    # to float32 and shifted by k quadrants: the CPU's sin32 reduction
    k = math.floor(x * TWO_OVER_PI + 0.5)
    return F((x - k * P1) - k * P2), int(k) & 3


@cuda.jit(device=True)
def _quadrant(s, c, q):
    if q == 0:
        return s, c
    if q == 1:
        return c, -s
    if q == 2:
        return -s, -c
    return -c, s


@cuda.jit(device=True)
def vsin(x):
    r, q = _reduce(x)
    return _quadrant(math.sin(r), math.cos(r), q)[0]


@cuda.jit(device=True)
def vcos(x):
    r, q = _reduce(x)
    return _quadrant(math.sin(r), math.cos(r), q)[1]


@cuda.jit(device=True)
def vsincos(x):
    r, q = _reduce(x)
    return _quadrant(math.sin(r), math.cos(r), q)
'''


# the CPU kernels' explicit fused multiply-add, in both precisions. NVVM fuses a * b + c
# into one FMA by default when all three share a type; the float32 kernel's angle steps
# (float32 factors, float64 angle) round the product to float32 first, where the CPU's
# fma widens it and forms it exactly (not measured on a GPU since: none was lent)
_DEVICE_FMA = '''

@cuda.jit(device=True)
def vfma(a, b, c):
    return a * b + c
'''


def device_functions(text: str, dtype: str = "float64") -> str:
    """CPU physics functions (``@njit(**JIT)``) as CUDA device functions, after the
    device's ``vsin``, ``vcos``, ``vsincos`` and ``vfma``: CUDA's ``sin``/``cos`` in float64; in
    float32 CUDA's ``sinf``/``cosf`` of the argument reduced in float64 (as
    `sweep.kernels.vecmath.sin32` does; see `sweep.kernels.precision`)."""
    math = _DEVICE_MATH if dtype == "float64" else _DEVICE_MATH32
    device = text.replace("@njit(**JIT)", "@cuda.jit(device=True)")
    return math + _DEVICE_FMA + "\n\n" + device


# one parameter of the thread's row of the table, from the chunk's description (see
# `sweep.grid.GridRows`): the scene's value, or the value of the axis that sets it
_PARAMETER = '''

@cuda.jit(device=True)
def _param(column, params, flat, columns, strides, sizes, offsets, values):
    for axis in range(columns.shape[0]):
        if columns[axis] == column:
            return values[offsets[axis] + (flat // strides[axis]) % sizes[axis]]
    return params[column]
'''

#: The module's ``kernel``: the CPU kernels' contract around the CUDA ``_thread``
#: (``{arguments}``: the arguments after ``saved``; ``{on_device}``: them on the GPU).
_LAUNCHER = '''\
def kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved{arguments}):
    """Run one GPU thread per trajectory and copy the outputs back (the CPU kernels'
    contract). ``params``: the chunk's rows described (`sweep.grid.GridRows`: a few
    hundred bytes go to the GPU, and each thread reads its own parameters from it, see
    ``_param``) or a table."""
    n = params.shape[0]
    if n == 0:
        return
    rows = params if isinstance(params, GridRows) else GridRows.from_table(params)
    d_out = cuda.device_array(out.shape, dtype=out.dtype)
    d_status = cuda.device_array(status.shape, dtype=status.dtype)
    d_saved = cuda.to_device(np.ascontiguousarray(saved))
    with warnings.catch_warnings():  # a small grid is a legitimate run, not a mistake
        warnings.filterwarnings("ignore", ".*Grid size .* under-utilization")
        _thread[(n + THREADS - 1) // THREADS, THREADS](
            cuda.to_device(rows.template), t0, dt, n_steps, n_transient, save_every, d_out,
            d_status, d_saved{on_device}, rows.start, cuda.to_device(rows.columns),
            cuda.to_device(rows.strides), cuda.to_device(rows.sizes),
            cuda.to_device(rows.offsets), cuda.to_device(rows.values))
    out[...] = d_out.copy_to_host()
    status[...] = d_status.copy_to_host()
    if saved.size:
        saved[...] = d_saved.copy_to_host()
'''

_NP_FLOOR = re.compile(r"\bnp\.floor\(")


def _device(code: str) -> str:
    """A CPU snippet for a CUDA thread: ``np.floor`` becomes ``math.floor``."""
    return _NP_FLOOR.sub("math.floor(", code)


def cuda_kernel(spec: KernelSpec, method) -> str:
    """Module body for ``spec`` on a CUDA device: the ``_thread`` kernel and the
    ``kernel`` launcher with the CPU contract (see the module docstring)."""
    parts = STEPPERS[method.kind](spec, method)
    drives = _drives(parts)
    width = n_columns(spec)
    update = snippets(spec, "update")
    stop = stop_source(spec, action="break")
    loop = drives.step + drives.values + parts["step"] + drives.carry + ["k_state = step + 1"]
    for head, code in renormalisations(spec):
        loop += [head, indent(code, 1)]
    if update or stop:
        loop += ["if step + 1 >= n_transient:", indent(update, 1) or "    pass"]
        if stop:
            loop += [indent(stop, 1)]
    if spec.save:
        loop += ["if (step + 1) % save_every == 0:",
                 "    saved[i, 0, (step + 1) // save_every] = th",
                 "    saved[i, 1, (step + 1) // save_every] = om"]
    first = load_lines(spec, row=None, table="_param",
                       arguments="params, flat, columns, strides, sizes, offsets, values"
                       ) + ["th = th0", "om = om0", snippets(spec, "init")]
    if update:
        first += ["if n_transient <= 0:", indent(update, 1)]
    if spec.save:
        first += ["saved[i, 0, 0] = th", "saved[i, 1, 0] = om"]
    first += parts["before"] + drives.init
    finish = [f"if {ok_test(spec)}:", f"    status[i] = {int(Status.OK)}",
              indent(snippets(spec, "final"), 1), "else:",
              f"    status[i] = {failed_status(spec)}", f"    for col in range({width}):",
              "        out[i, col] = math.nan"]
    if spec.save:
        finish += [indent(failed_samples(spec), 1)]
    body = NL.join(["i = cuda.grid(1)", "if i >= out.shape[0]:", "    return",
                    "flat = first + i", "TWO_PI = 2.0 * math.pi", "k_state = 0"]
                   + parts["preamble"] + first
                   + ["for step in range(n_steps):", indent(NL.join(loop), 1)] + finish)
    return cuda_module(body, kernel_arguments(spec))



def cuda_module(thread_body: str, arguments: str = "") -> str:
    """A CUDA kernel module's body from a thread's code: ``_param``, the ``_thread``
    kernel (``thread_body``, indented once, reading its parameters with ``_param``) and
    the ``kernel`` launcher with the CPU contract (``arguments``: the arrays it takes
    after ``saved``, as source, ``""`` or starting with ``", "``, copied to the GPU for
    the thread, e.g. `sweep.kernels.snippets.kernel_arguments`); shared by the systems'
    kernels (`sweep.kernels.system`)."""
    names = [name.strip() for name in arguments.split(",") if name.strip()]
    on_device = "".join(f", cuda.to_device(np.ascontiguousarray({name}))" for name in names)
    return f'''
THREADS = {THREADS_PER_BLOCK}


{_PARAMETER}

@cuda.jit
def _thread(params, t0, dt, n_steps, n_transient, save_every, out, status, saved{arguments}, first,
            columns, strides, sizes, offsets, values):
{indent(_device(thread_body), 1)}


{_LAUNCHER.format(arguments=arguments, on_device=on_device)}'''
