"""All numba: build the sweep kernel for (model, effects, observables, saving).

The kernel is *generated source*: `source` writes a small Python module that
contains only the terms the scene calls for (no ``sin(W t)`` without forcing, no
``c * omega`` without damping, ``sin(theta)`` only for the nonlinear model) and only
the requested observables. The module is written once to the cache folder (named by
the hash of its text) and imported; its functions are compiled with numba's
``cache=True``, so a fresh process loads machine code from disk instead of compiling
again. Built kernels are also memoised in the process (`build`).

Kernel contract (every generated kernel)::

    kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved)

params : float64[n, len(PARAMETERS)]  one row per trajectory, columns PARAMETERS
t0, dt : float64                      time of step n is t0 + n*dt (never accumulated)
n_steps : int64                       steps to take
n_transient : int64                   steady observables accumulate from this step index
save_every : int64                    sampling stride when spec.save (else ignored)
out : float64[n, n_columns]           observables, in `columns(spec)` order
status : int8[n]                      Status code per trajectory
saved : float64[n, 2, n_saved]        theta, omega at steps 0, k, 2k, ... (spec.save)

Iteration ``i`` reads ``params[i]`` and writes only ``out[i]``, ``status[i]``,
``saved[i]``; nothing is allocated inside the time loop; no exception is raised: a
non-finite state sets ``status[i] = NONFINITE``, stops that trajectory, and fills its
outputs with NaN (its saved samples from then on stay NaN).
"""

from __future__ import annotations

import enum
import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
import textwrap
from dataclasses import dataclass
from pathlib import Path

from . import _config
from .observables import OBSERVABLES
from .scene import PARAMETERS

__all__ = ["Status", "KernelSpec", "columns", "source", "build"]


class Status(enum.IntEnum):
    """Per-trajectory outcome stored in the dataset's ``status`` variable."""

    OK = 0
    NONFINITE = 1

    @property
    def message(self) -> str:
        """What the code means, for users."""
        return _STATUS_MESSAGES[self]


_STATUS_MESSAGES = {
    Status.OK: "integrated to t_end",
    Status.NONFINITE: "state became non-finite (overflow or NaN); integration stopped",
}


@dataclass(frozen=True)
class KernelSpec:
    """Everything that changes the compiled code (and nothing that does not).

    Attributes
    ----------
    model : {"nonlinear", "linear"}
    damping, forcing : bool
        Whether the ``-c omega`` and ``A sin(W t + phase)`` terms exist.
    observe : tuple of str
        Observable names in canonical (`OBSERVABLES`) order.
    save : bool
        Whether sampled trajectories are written.
    method : str
        Integrator; only ``"rk4"`` for now.
    """

    model: str
    damping: bool
    forcing: bool
    observe: tuple[str, ...]
    save: bool = False
    method: str = "rk4"


def columns(spec: KernelSpec) -> list[tuple[str, str, str]]:
    """The ``out`` columns of a kernel: ``(name, units, long_name)`` in order."""
    return [v for name in spec.observe for v in OBSERVABLES[name].variables]


# --------------------------------------------------------------------------- source
_COL = {name: k for k, name in enumerate(PARAMETERS)}


def _accel_source(spec: KernelSpec) -> str:
    """``accel(th, om, w0sq[, c][, f])``: theta'' with only the scene's terms."""
    args = ["th", "om", "w0sq"]
    terms = ["-w0sq * " + ("math.sin(th)" if spec.model == "nonlinear" else "th")]
    if spec.damping:
        args.append("c")
        terms.append("- c * om")
    if spec.forcing:
        args.append("f")
        terms.append("+ f")
    return (
        "@njit(inline='always', **JIT)\n"
        f"def accel({', '.join(args)}):\n"
        f"    return {' '.join(terms)}\n"
    )


def _energy_source(spec: KernelSpec) -> str:
    potential = "w0sq * (1.0 - math.cos(th))" if spec.model == "nonlinear" else \
        "0.5 * w0sq * th * th"
    return (
        "@njit(inline='always', **JIT)\n"
        "def energy(th, om, w0sq):\n"
        f"    return 0.5 * om * om + {potential}\n"
    )


def _rk4_step_source(spec: KernelSpec) -> str:
    """One classical RK4 step of (th, om); forcing values fa, fb, fc at t, t+dt/2, t+dt."""
    extra_a = (", c" if spec.damping else "") + (", fa" if spec.forcing else "")
    extra_b = (", c" if spec.damping else "") + (", fb" if spec.forcing else "")
    extra_c = (", c" if spec.damping else "") + (", fc" if spec.forcing else "")
    return textwrap.dedent(f"""\
        k1t = om
        k1o = accel(th, om, w0sq{extra_a})
        k2t = om + half * k1o
        k2o = accel(th + half * k1t, om + half * k1o, w0sq{extra_b})
        k3t = om + half * k2o
        k3o = accel(th + half * k2t, om + half * k2o, w0sq{extra_b})
        k4t = om + dt * k3o
        k4o = accel(th + dt * k3t, om + dt * k3o, w0sq{extra_c})
        th = th + sixth * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
        om = om + sixth * (k1o + 2.0 * k2o + 2.0 * k3o + k4o)
        """)


_STEPPERS = {"rk4": _rk4_step_source}


def _snippets(spec: KernelSpec, part: str) -> str:
    """Concatenate one part (init/update/final) of every observed observable, with
    ``COL`` replaced by the observable's first column."""
    lines, col = [], 0
    for name in spec.observe:
        obs = OBSERVABLES[name]
        code = getattr(obs, part)
        if code:
            lines.append(f"# {name}\n" + code.replace("COL", str(col)))
        col += len(obs.variables)
    return "\n".join(lines)


def _indent(code: str, level: int) -> str:
    return textwrap.indent(code, "    " * level) if code else ""


def source(spec: KernelSpec) -> str:
    """The Python source of the kernel module for ``spec``.

    Parameters
    ----------
    spec : KernelSpec

    Returns
    -------
    str
        A self-contained module defining ``kernel`` (see the module docstring).
    """
    if spec.method not in _STEPPERS:
        raise ValueError(f"method must be one of {', '.join(map(repr, _STEPPERS))}, "
                         f"got {spec.method!r}")
    n_columns = len(columns(spec))
    jit = {"fastmath": _config.FASTMATH, "boundscheck": _config.BOUNDSCHECK,
           "error_model": "numpy", "cache": True}
    uses_energy = any(OBSERVABLES[n].uses_energy for n in spec.observe)
    load = [f"th0 = params[i, {_COL['theta0']}]", f"om0 = params[i, {_COL['omega0']}]",
            f"L = params[i, {_COL['length']}]", f"g = params[i, {_COL['gravity']}]",
            "w0sq = g / L"]
    if spec.damping:
        load.append(f"c = params[i, {_COL['damping']}]")
    if spec.forcing:
        load += [f"A = params[i, {_COL['forcing_amplitude']}]",
                 f"W = params[i, {_COL['forcing_frequency']}]",
                 f"phi = params[i, {_COL['forcing_phase']}]"]
    update = _snippets(spec, "update")
    save_first = "saved[i, 0, 0] = th\nsaved[i, 1, 0] = om" if spec.save else ""
    save_step = textwrap.dedent("""\
        if (step + 1) % save_every == 0:
            j = (step + 1) // save_every
            saved[i, 0, j] = th
            saved[i, 1, j] = om""") if spec.save else ""
    forcing_first = "fa = A * math.sin(W * t0 + phi)" if spec.forcing else ""
    forcing_step = textwrap.dedent("""\
        fb = A * math.sin(W * (t0 + step * dt + half) + phi)
        fc = A * math.sin(W * (t0 + (step + 1) * dt) + phi)""") if spec.forcing else ""
    forcing_carry = "fa = fc" if spec.forcing else ""

    body = f'''\
"""Generated by sweep._kernels for {spec!r}. Do not edit."""
import math
from numba import njit, prange

JIT = {jit!r}


{_accel_source(spec)}

{_energy_source(spec) if uses_energy else ""}

@njit(parallel=True, **JIT)
def kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved):
    TWO_PI = 2.0 * math.pi
    half = 0.5 * dt
    sixth = dt / 6.0
    for i in prange(params.shape[0]):
{_indent(chr(10).join(load), 2)}
        th = th0
        om = om0
{_indent(_snippets(spec, "init"), 2)}
{_indent(("if n_transient <= 0:" + chr(10) + _indent(update, 1)) if update else "", 2)}
{_indent(save_first, 2)}
{_indent(forcing_first, 2)}
        ok = True
        for step in range(n_steps):
{_indent(forcing_step, 3)}
{_indent(_STEPPERS[spec.method](spec), 3)}
{_indent(forcing_carry, 3)}
            if not (math.isfinite(th) and math.isfinite(om)):
                ok = False
                break
{_indent(("if step + 1 >= n_transient:" + chr(10) + _indent(update, 1)) if update else "", 3)}
{_indent(save_step, 3)}
        if ok:
            status[i] = {int(Status.OK)}
{_indent(_snippets(spec, "final"), 3) or "            pass"}
        else:
            status[i] = {int(Status.NONFINITE)}
            for col in range({n_columns}):
                out[i, col] = math.nan
'''
    # drop the blank lines left by absent parts, for a readable module
    return "\n".join(line for line in body.splitlines() if line.strip()) + "\n"


# --------------------------------------------------------------------------- build
def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically unless an identical file is there
    (rewriting would change its mtime and invalidate numba's cache index)."""
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, path)


def _module_dir() -> Path:
    folder = _config.cache_dir() / "kernels"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".write-probe"
        probe.touch()
        probe.unlink()
    except OSError:
        folder = Path(tempfile.gettempdir()) / f"sweep-kernels-{os.getuid()}"
        folder.mkdir(parents=True, exist_ok=True)
    return folder


@functools.lru_cache(maxsize=None)
def build(spec: KernelSpec):
    """Return the compiled kernel for ``spec`` (memoised; disk-cached by numba).

    Parameters
    ----------
    spec : KernelSpec

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The ``kernel`` of the generated module; compiled on first call.
    """
    text = source(spec)
    digest = hashlib.sha1(text.encode()).hexdigest()[:16]
    name = f"sweep_kernel_{digest}"
    path = _module_dir() / f"{name}.py"
    _write_once(path, text)
    module_spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    module_spec.loader.exec_module(module)
    return module.kernel
