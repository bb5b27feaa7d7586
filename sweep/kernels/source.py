"""The source of a kernel module: header, physics functions and the kernel body.

Kernel contract (every fixed-step kernel: explicit Runge-Kutta and symplectic)::

    kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved)

params : float64[n, n_parameters]     one row per trajectory, columns
                                      `sweep.physics.parameter_names`
t0, dt : float64                      time of step n is t0 + n*dt (never accumulated)
n_steps : int64                       steps to take
n_transient : int64                   steady observables accumulate from this step index
save_every : int64                    sampling stride when spec.save (else ignored)
out : float64[n, n_columns(spec)]     observables, in observe order
status : int8[n]                      Status code per trajectory
saved : float64[n, 2, n_saved]        theta, omega at steps 0, k, 2k, ... (spec.save)

With the ``attractor`` observable a kernel takes the attractor catalogue after
``saved`` (an adaptive kernel: after ``stats``): ``catalogue`` (float[n_points, 4] in
the spec's dtype, `sweep.kernels.snippets.catalogue_argument`), so one kernel serves
every catalogue. With `KernelSpec.known_cells` a fixed-step kernel takes two arguments
more, after those: ``known`` (int32[n0, n1]) and ``known_axes`` (float64[5]); see
`sweep.kernels.snippets.known_source`.

Adaptive kernels (embedded pairs, per-trajectory step-size control)::

    kernel(params, t0, t_end, dt, t_transient, rtol, atol, out, status, stats)

dt : float64                          first trial step and largest step [s]
t_transient : float64                 steady observables update at accepted steps
                                      whose time is >= t0 + t_transient
rtol, atol : float64                  error per step <= atol + rtol * |y| (RMS norm)
stats : int64[n, 2]                   accepted and rejected steps per trajectory

Trajectory ``i`` reads ``params[i]`` and writes only ``out[i]``, ``status[i]``,
``saved[i]`` (``stats[i]``); nothing is allocated inside the time loop; no exception is
raised: a trajectory whose state became non-finite gets ``status[i] = NONFINITE`` and
NaN outputs (its saved samples from the failure on are NaN).
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from .. import _config
from ..observables import OBSERVABLES
from . import vectors
from .adaptive import adaptive_kernel
from .cuda import cuda_kernel, device_functions
from .fixed import fixed_kernel
from .network import NetworkSpec, network_cuda_source, network_source
from .phases import float64_phases
from .precision import (
    HEADER,
    clock,
    float64_symbols,
    single,
    single_drive_values,
    single_loads,
)
from .refill import refill_kernel
from .spec import (
    KernelSpec,
    check_device,
    check_dtype,
    check_method_fits,
    check_observables_fit,
    check_tangent_fits,
    method_of,
    tangent,
)
from .system import SystemSpec, drive_phases, system_source
from .terms import accel_jacobian_source, accel_source, energy_source

__all__ = ["source", "system_module"]

# The kernels inline sweep.kernels.vecmath; its text is part of every kernel's source hash.
_VECMATH_DIGEST = hashlib.sha1(
    (Path(__file__).parent / "vecmath.py").read_bytes()).hexdigest()[:16]


_VECMATH_IMPORT = ("from sweep.kernels.vecmath import cos as vcos, fma as vfma, sin as vsin, "
                   "sincos as vsincos")
#: A system's kernels pair the sine and cosine of one argument from one reduction
#: (`sweep.kernels.vecmath.sincos_quadrant`; the accelerations and the tangent dynamics
#: read the same statements, so the pairing keeps them on one trajectory).
_SYSTEM_VECMATH_IMPORT = _VECMATH_IMPORT.replace("sincos as vsincos",
                                                 "sincos_quadrant as vsincos")
#: Whether a system's CPU kernels compile with LLVM's machine instruction scheduler
#: (`sweep.kernels.vectors._llvm_options` says why not), but for those with the tangent
#: dynamics (``lyapunov``), which keep it, as the single pendulum's kernels and the
#: swing networks' do (a 100-node network ran at the same speed either way, within the
#: noise, AMD EPYC Zen 5). Set to True to compare: the results are the same bits.
SYSTEM_SCHEDULER = False


def source(spec: KernelSpec) -> str:
    """The Python source of the kernel module for ``spec``.

    Parameters
    ----------
    spec : KernelSpec

    Returns
    -------
    str
        A self-contained module defining ``kernel`` (see the module docstring).

    Raises
    ------
    ValueError
        For an unknown method, a symplectic method with damping or forcing, or an
        adaptive method with saving.
    """
    if isinstance(spec, SystemSpec):
        return system_module(spec)
    if isinstance(spec, NetworkSpec):
        if spec.device == "cuda":
            return _tidy(network_cuda_source(spec, _cuda_header(spec)))
        return _tidy(network_source(spec, _cpu_header(spec, _jit_options()))) + \
            _compile_with(False)
    method = method_of(spec)
    check_method_fits(method, spec.effects, where="the kernel spec")
    if method.adaptive and spec.save:
        raise ValueError(f"method {method.name!r} is adaptive: its steps are not on a fixed "
                         "grid, so it cannot save every k-th step; accepted: save=False")
    if spec.known_cells and method.adaptive:
        raise ValueError(f"known_cells stops trajectories at stroboscopic times on the "
                         f"fixed step grid; method {method.name!r} is adaptive; accepted: "
                         "a fixed-step method, or known_cells=False")
    check_tangent_fits(method, spec.effects, spec.observe)
    check_observables_fit(method, spec.observe)
    check_dtype(spec.dtype, method)
    jit = _jit_options()
    uses_energy = any(OBSERVABLES[n].uses_energy for n in spec.observe)
    physics = (accel_jacobian_source(spec) if tangent(spec) else accel_source(spec)) + \
        "\n\n" + (energy_source(spec) if uses_energy else "")
    if spec.device == "cuda":
        check_device(spec.device, method)
        return _precision(spec, f'''\
"""Generated by sweep.kernels for {spec.describe()}. Do not edit."""
import math
import warnings
import numpy as np
from numba import cuda
from sweep.grid import GridRows


{device_functions(physics, spec.dtype)}
{cuda_kernel(spec, method)}
''')
    body = (adaptive_kernel if method.adaptive else refill_kernel if spec.refill
            else fixed_kernel)(spec, method)
    return _precision(spec, _cpu_header(spec, jit) + physics + "\n" + body) + \
        _compile_with(spec.dtype == "float32")


def _jit_options() -> str:
    """The ``JIT`` options of a generated module, as source (`sweep._config.FASTMATH`
    written in a fixed order, so the text and its hash are stable)."""
    fastmath = _config.FASTMATH
    if not isinstance(fastmath, bool):  # a set, written in a fixed order (stable hash)
        fastmath = "{" + ", ".join(repr(flag) for flag in sorted(fastmath)) + "}" \
            if fastmath else "False"
    return (f"{{'fastmath': {fastmath}, 'boundscheck': {_config.BOUNDSCHECK!r}, "
            "'error_model': 'numpy', 'cache': True}")


def _cuda_header(spec) -> str:
    """A system's or network's CUDA module: docstring and imports."""
    return f'''\
"""Generated by sweep.kernels for {spec.describe()}, device='cuda'. Do not edit."""
import math
import warnings
import numpy as np
from numba import cuda
from sweep.grid import GridRows


'''


def _cpu_header(spec, jit: str) -> str:
    """A CPU kernel module's docstring, imports and ``JIT`` options."""
    return f'''\
"""Generated by sweep.kernels for {spec.describe()}. Do not edit."""
# sweep.kernels.vecmath {_VECMATH_DIGEST} (numba's cache does not track inlined imports)
import math
import numpy as np
from numba import get_num_threads, njit
from sweep.kernels.threads import run_blocks
{_VECMATH_IMPORT}
from sweep.kernels.vectors import compile_with

JIT = {jit}


'''


def _compile_with(single: bool, scheduler: bool = True) -> str:
    """The module's last line: every dispatcher above compiles with the configured SIMD
    width and alignment (`sweep.kernels.vectors`), and without LLVM's machine
    instruction scheduler where ``scheduler`` is False (`SYSTEM_SCHEDULER`)."""
    width = vectors.resolved(_config.vector_width())
    return f"compile_with(globals(), {width}, {_config.LANE_ALIGNMENT}, " \
        f"{single and _config.SINGLE_BY_NARROWEST}" \
        + ("" if scheduler else ", scheduler=False") + ")\n"


def system_module(spec: SystemSpec) -> str:
    """The module text of a system's kernel (`sweep.kernels.system`), float64, on the CPU
    or (``device="cuda"``) one GPU thread per trajectory."""
    if spec.device == "cuda":
        return _tidy(system_source(spec, _cuda_header(spec)))
    header = _cpu_header(spec, _jit_options()).replace(_VECMATH_IMPORT,
                                                       _SYSTEM_VECMATH_IMPORT, 1)
    text = system_source(spec, header)
    if spec.dtype == "float32":
        text = _system_single(spec, text)
    # the tangent dynamics' loop ran slower without the scheduler: 124 against 143 M
    # trajectory-steps/s on the double pendulum (AMD EPYC Zen 5, 2 threads)
    scheduler = SYSTEM_SCHEDULER or "lyapunov" in spec.observe
    return _tidy(text) + _compile_with(spec.dtype == "float32", scheduler)


_HOISTED = re.compile(r"(hoisted_values = np\.empty\(\(\d+, BLOCK\))\)")
#: a drive period's steps, of ``strobe`` (``sb_S``) and ``attractor`` (``ca_S``): both
#: from the float64 step, so that they sample the same steps
_STROBE_PERIOD = re.compile(r"((?:sb|ca)_S = round\(TWO_PI / \(\w+) \* dt\)\)")
#: the tangent vector's first value and the exponent's sum: float64 lanes (`_system_single`)
_TANGENT_START = re.compile(r"^(\s*(?:ly_\w+|acc_ly) = )F\(([^()]*)\)$", re.MULTILINE)
_FLIP_TIME = re.compile(r"^(\s*at_\w+ = t0 \+ \(.*\)) \* dt$", re.MULTILINE)


def _single_module(text: str, vecmath_import: str, keep) -> str:
    """A generated CPU module's first float32 steps (`sweep.kernels.precision`): the
    float32 sine imported in place of ``vecmath_import``, ``F = np.float32``, every
    float literal and every parameter load but those of ``keep`` as float32."""
    text = text.replace(vecmath_import, HEADER, 1).replace(
        "import numpy as np\n", "import numpy as np\nF = np.float32\n", 1)
    return single_loads(single(text), keep)


def _system_single(spec: SystemSpec, text: str) -> str:
    """A system's CPU module in float32 (`sweep.kernels.precision`, as the single
    pendulum's): float literals and parameter loads as float32, the float32 sine, the
    step in float32 on a float64 clock; the angles, ``2 pi``, the flip's thresholds
    and times, the observables' accumulators and the drives' phases
    (`sweep.kernels.phases`) stay float64."""
    angles = {c.symbol for c in spec.system.coordinates if c.angular}
    phases = drive_phases(spec)
    text = clock(_single_module(text, _SYSTEM_VECMATH_IMPORT, angles | phases.parameters))
    text = text.replace("F(math.pi)", "math.pi").replace("TWO_PI = F(2.0) * math.pi",
                                                         "TWO_PI = 2.0 * math.pi")
    text = _HOISTED.sub(r"\1, dtype=np.float32)", text)
    # lyapunov: the tangent vector and the exponent's sum stay float64 (its stages read
    # the float32 Jacobian, widened exactly); their first values as float64 literals
    text = _TANGENT_START.sub(r"\1\2", text)
    text = float64_phases(text, phases)  # a no-op where no function reads the time
    # the times on the float64 clock: a strobe period's steps, the energy at t_end
    text = _STROBE_PERIOD.sub(r"\1 * dt_clock))", text).replace(
        "t0 + n_steps * dt)", "t0 + n_steps * dt_clock)")
    return _FLIP_TIME.sub(r"\1 * dt_clock", text)


def _precision(spec: KernelSpec, text: str) -> str:
    """The module in the spec's working precision: float64 as generated; float32 with
    its literals and sine in float32 (`sweep.kernels.precision`)."""
    if spec.dtype == "float64":
        return _tidy(text)
    text = clock(single_drive_values(_single_module(
        text, _VECMATH_IMPORT, float64_symbols(spec.model, spec.effects))))
    # 2 pi for the observables (turns of the float64 angle): kept float64
    text = text.replace("TWO_PI = F(2.0) * F(math.pi)", "TWO_PI = 2.0 * math.pi")
    return _tidy(text)


def _tidy(text: str) -> str:
    """Drop the blank lines left by absent parts, for a readable module."""
    return "\n".join(line for line in text.splitlines() if line.strip()) + "\n"
