"""All numba: build the sweep kernel for (model, effects, observables, saving, method).

The kernel is *generated source*: `source` writes a small Python module that
contains only the terms the scene calls for (no ``sin(W t)`` without forcing, no
``c * omega`` without damping, ``sin(theta)`` only for the nonlinear model) and only
the requested observables. The module is written once to the cache folder (named by
the hash of its text) and imported; its functions are compiled with numba's
``cache=True``, so a fresh process loads machine code from disk instead of compiling
again. Built kernels are also memoised in the process (`build`).

The step is generated from the method's *data* (`sweep.methods`): an explicit
Runge-Kutta step from its Butcher tableau (RK4 included: the generated code performs
exactly the operations of the classical hand-written step, ``th + (dt/6) * (k1 + 2 k2
+ 2 k3 + k4)`` etc., so there is no separate fast path), a kick-drift sequence from a
splitting method's coefficients, and an adaptive loop from an embedded pair.

Kernel contract (every fixed-step kernel: explicit Runge-Kutta and symplectic)::

    kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved)

params : float64[n, len(PARAMETERS)]  one row per trajectory, columns PARAMETERS
t0, dt : float64                      time of step n is t0 + n*dt (never accumulated)
n_steps : int64                       steps to take
n_transient : int64                   steady observables accumulate from this step index
save_every : int64                    sampling stride when spec.save (else ignored)
out : float64[n, n_columns(spec)]     observables, in observe order
status : int8[n]                      Status code per trajectory
saved : float64[n, 2, n_saved]        theta, omega at steps 0, k, 2k, ... (spec.save)

Adaptive kernels (embedded pairs, per-trajectory step-size control)::

    kernel(params, t0, t_end, dt, t_transient, rtol, atol, out, status, stats)

dt : float64                          first trial step and largest step [s]
t_transient : float64                 steady observables update at accepted steps
                                      whose time is >= t0 + t_transient
rtol, atol : float64                  error per step <= atol + rtol * |y| (RMS norm)
stats : int64[n, 2]                   accepted and rejected steps per trajectory

Each trajectory advances its own time ``t`` (a sum of accepted steps) and clips its
last step so that it ends at ``t_end`` exactly.

Trajectory ``i`` reads ``params[i]`` and writes only ``out[i]``, ``status[i]``,
``saved[i]`` (``stats[i]``); nothing is allocated inside the time loop; no exception is
raised: a trajectory whose state became non-finite gets ``status[i] = NONFINITE`` and
NaN outputs (its saved samples from the failure on are NaN). An adaptive trajectory
whose step would have to shrink below ``16 eps max(|t0|, |t_end|)`` (which only a state
on its way to overflow does) is flagged the same way.

Fixed-step kernels run trajectories in blocks of ``spec.block`` SIMD lanes, time loop
outside and lane loop inside (see `_fixed_kernel`); every sine is
`sweep.kernels.vecmath.sin`, which LLVM vectorises, and the JIT flags of `sweep._config`
let it fuse multiply-adds. Results do not depend on the block size, the number of
trajectories per call, chunks or threads (``tests/test_blocks.py``). Adaptive kernels
keep one trajectory per iteration (each controls its own step).
"""

from __future__ import annotations

import enum
import functools
import hashlib
import importlib.util
import os
import re
import sys
import tempfile
import textwrap
from dataclasses import dataclass
from fractions import Fraction
from math import lcm
from pathlib import Path

from .. import _config
from .. import methods as _methods
from ..observables import OBSERVABLES
from ..physics import PARAMETERS

__all__ = ["Status", "KernelSpec", "n_columns", "source", "build"]


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
    Status.NONFINITE: "state became non-finite (overflow or NaN), or an adaptive step "
                      "underflowed; integration stopped",
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
    method : str or sweep.methods.ButcherTableau or sweep.methods.SplittingMethod
        Integrator: a `sweep.methods.METHODS` name or a method object. A registry
        object is stored as its name, so ``method=RK4`` and ``method="rk4"`` share one
        kernel; an unknown name is refused by `source`.
    stop_early : bool
        Stop each trajectory as soon as every observed observable says its answer is
        settled (only observables with a ``settled`` snippet; see `sweep.observables`).
    shared_forcing : bool
        True when the forcing frequency and phase are the same for every trajectory
        of a call: the fixed-step kernel then evaluates ``sin(W t + phase)`` once per
        step for a whole block instead of once per lane (the same arithmetic, so the
        same results; a test checks it). False (the default) is right for any
        parameter table; `sweep.run` sets it when its grid has no frequency or phase
        axis.
    block : int
        Trajectories per block of the fixed-step kernel (SIMD lanes; a multiple of 8).
        Results do not depend on it (a test checks it); `_config.BLOCK` by default.
    """

    model: str
    damping: bool
    forcing: bool
    observe: tuple[str, ...]
    save: bool = False
    method: object = "rk4"
    stop_early: bool = False
    shared_forcing: bool = False
    block: int = None

    def __post_init__(self) -> None:
        method = self.method
        if not isinstance(method, str) and \
                _methods.METHODS.get(getattr(method, "name", None)) == method:
            object.__setattr__(self, "method", method.name)
        object.__setattr__(self, "shared_forcing", bool(self.shared_forcing and self.forcing))
        block = _config.BLOCK if self.block is None else self.block
        if not isinstance(block, int) or block < 8 or block % 8:
            raise ValueError(f"block must be a positive multiple of 8, got {block!r}")
        object.__setattr__(self, "block", block)


def n_columns(spec: KernelSpec) -> int:
    """Width of ``out``: every column of every observed observable, in observe order
    (an observable with samples > 1 fills ``samples`` columns per variable)."""
    return sum(OBSERVABLES[name].n_columns for name in spec.observe)


# --------------------------------------------------------------------------- source
_COL = {name: k for k, name in enumerate(PARAMETERS)}
# The kernels inline sweep.kernels.vecmath; its text is part of every kernel's source hash.
_VECMATH_DIGEST = hashlib.sha1(
    (Path(__file__).parent / "vecmath.py").read_bytes()).hexdigest()[:16]


def _accel_source(spec: KernelSpec) -> str:
    """``accel(th, om, w0sq[, c][, f])``: theta'' with only the scene's terms."""
    args = ["th", "om", "w0sq"]
    terms = ["-w0sq * " + ("vsin(th)" if spec.model == "nonlinear" else "th")]
    if spec.damping:
        args.append("c")
        terms.append("- c * om")
    if spec.forcing:
        args.append("f")
        terms.append("+ f")
    return (
        "@njit(**JIT)\n"
        f"def accel({', '.join(args)}):\n"
        f"    return {' '.join(terms)}\n"
    )


def _energy_source(spec: KernelSpec) -> str:
    potential = "w0sq * (1.0 - vcos(th))" if spec.model == "nonlinear" else \
        "0.5 * w0sq * th * th"
    return (
        "@njit(**JIT)\n"
        "def energy(th, om, w0sq):\n"
        f"    return 0.5 * om * om + {potential}\n"
    )


def _accel_call(spec: KernelSpec, th: str, om: str, f: str | None) -> str:
    """``accel(...)`` with only the arguments the scene's terms take."""
    args = [th, om, "w0sq"]
    if spec.damping:
        args.append("c")
    if spec.forcing:
        args.append(f)
    return f"accel({', '.join(args)})"


def _float(x) -> str:
    return repr(float(x))


# Rows whose exact (Fraction) coefficients share a denominator up to this size are
# written as (dt / D) * (n1 k1 + n2 k2 + ...), with small integers n: for RK4 that is
# exactly the classical hand-written step, operation for operation.
_MAX_COMMON_DENOMINATOR = 1000


def _combination(coeffs, names, scale: str, constants: dict[str, str] | None):
    """Source of ``scale * sum(coeffs[j] * names[j])`` over the non-zero coefficients,
    or None when they are all zero.

    With ``constants`` (a dict filled with preamble lines), exact rows with a small
    common denominator D become ``dt_D * (n1 * x1 + ...)`` with ``dt_D = dt / D``
    computed once per kernel call; otherwise ``scale * (c1 * x1 + ...)`` with the
    coefficients as float literals.
    """
    terms = [(x, name) for x, name in zip(coeffs, names) if x != 0]
    if not terms:
        return None
    exact = all(isinstance(x, Fraction) for x, _ in terms)
    if constants is not None and exact:
        denominator = lcm(*(x.denominator for x, _ in terms))
        if denominator <= _MAX_COMMON_DENOMINATOR:
            if denominator == 1:
                factor = scale
            else:
                factor = f"{scale}_{denominator}"
                constants[factor] = f"{factor} = {scale} / {float(denominator)!r}"
            parts = []
            for x, name in terms:
                n = int(x * denominator)
                sign = "-" if n < 0 else "+"
                body = name if abs(n) == 1 else f"{float(abs(n))!r} * {name}"
                parts.append((sign, body))
            text = ("-" if parts[0][0] == "-" else "") + parts[0][1]
            for sign, body in parts[1:]:
                text += f" {sign} {body}"
            return f"{factor} * {text}" if len(parts) == 1 else f"{factor} * ({text})"
    text = ""
    for x, name in terms:
        body = f"{_float(abs(x))} * {name}"
        text += (("-" if x < 0 else "") + body) if not text else \
            (f" - {body}" if x < 0 else f" + {body}")
    return f"{scale} * ({text})"


def _forcing_times(spec: KernelSpec, c, *, time: str, step: str | None, scale: str,
                   constants: dict[str, str] | None):
    """Forcing variable per distinct node c_i, and the time at which each is evaluated.

    Fixed step (``step`` given): time of node c is ``t0 + step * dt + c * dt`` (c = 0:
    ``t0 + step * dt``; c = 1: ``t0 + (step + 1) * dt``), never accumulated. Adaptive
    (``step`` None): ``time + c * h``.
    Returns ({c: variable}, [(variable, time expression)]); the variable holds
    ``A * sin(W * time + phi)`` (see `_forcing_line`).
    """
    if not spec.forcing:
        return {}, []
    names, nodes = {}, []
    for x in sorted(set(c)):
        name = f"f{len(names)}"
        names[x] = name
        if step is None:
            at = time if x == 0 else (f"{time} + {scale}" if x == 1 else
                                      f"{time} + {_float(x)} * {scale}")
        elif x == 0:
            at = f"t0 + {step} * dt"
        elif x == 1:
            at = f"t0 + ({step} + 1) * dt"
        else:
            const = f"cdt{len(names) - 1}"
            constants[const] = f"{const} = dt * {_float(x)}"
            at = f"t0 + {step} * dt + {const}"
        nodes.append((name, at))
    return names, nodes


def _forcing_line(name: str, at: str) -> str:
    """``name = A * sin(W * (at) + phi)``: the forcing term at time ``at``."""
    return f"{name} = A * vsin(W * ({at}) + phi)"


def _rk_stages(spec: KernelSpec, tableau, scale: str, constants, forcing: dict) -> list[str]:
    """Stage lines k_it, k_io (k_it = omega at stage i, since theta' = omega)."""
    lines = []
    for i in range(tableau.stages):
        row = tableau.a[i][:i]
        kt = [f"k{j + 1}t" for j in range(i)]
        ko = [f"k{j + 1}o" for j in range(i)]
        dth = _combination(row, kt, scale, constants)
        dom = _combination(row, ko, scale, constants)
        lines.append(f"k{i + 1}t = " + (f"om + {dom}" if dom else "om"))
        lines.append(f"k{i + 1}o = " + _accel_call(
            spec, f"th + {dth}" if dth else "th", f"k{i + 1}t", forcing.get(tableau.c[i])))
    return lines


def _explicit_stepper(spec: KernelSpec, tableau) -> dict[str, list]:
    """One fixed step of an explicit Runge-Kutta method, from its tableau.

    Returns the parts `_fixed_kernel` assembles: ``preamble`` (constants, once per
    call), ``forcing_init`` and ``forcing_step`` ((variable, time) pairs evaluated
    before the first step and at the start of every step), ``forcing_carry``
    ((destination, source) pairs copied at the end of every step), ``before`` (lane
    lines before the first step), ``step`` (lane lines of one step) and ``carried``
    (lane variables that live from one step to the next besides th, om).
    """
    constants: dict[str, str] = {}
    c = tableau.c
    carry = spec.forcing and 0 in c and 1 in c  # f(t_{n+1}) is the next step's f(t_n)
    forcing, nodes = _forcing_times(spec, c, time="", step="step", scale="dt",
                                    constants=constants)
    init, pairs = [], []
    if carry:
        first = forcing[Fraction(0)]
        nodes = [(name, at) for name, at in nodes if name != first]  # from the last step
        init.append((first, "t0"))
        pairs.append((first, forcing[Fraction(1)]))
    step = _rk_stages(spec, tableau, "dt", constants, forcing)
    kt = [f"k{j + 1}t" for j in range(tableau.stages)]
    ko = [f"k{j + 1}o" for j in range(tableau.stages)]
    step.append(f"th = th + {_combination(tableau.b, kt, 'dt', constants)}")
    step.append(f"om = om + {_combination(tableau.b, ko, 'dt', constants)}")
    return {"preamble": list(constants.values()), "forcing_init": init,
            "forcing_step": nodes, "forcing_carry": pairs, "before": [], "step": step,
            "carried": []}


def _symplectic_stepper(spec: KernelSpec, method) -> dict[str, list[str]]:
    """One kick-drift step; the force is re-evaluated only after a drift moved theta."""
    if spec.damping or spec.forcing:  # `source` refuses these first; a guard
        raise ValueError(f"method {method.name!r} needs a conservative scene")
    constants, step, stale = {}, [], False
    force = f"acc = {_accel_call(spec, 'th', 'om', None)}"

    def scaled(kind, x):
        if x == 1:
            return "dt"
        line = f"dt * {_float(x)}"
        for name, known in constants.items():
            if known.endswith(f" = {line}"):
                return name
        name = f"{kind}{len(constants)}"
        constants[name] = f"{name} = {line}"
        return name

    for kick, drift in zip(method.kick, method.drift):
        if kick != 0:
            if stale:
                step.append(force)
                stale = False
            step.append(f"om = om + {scaled('kick', kick)} * acc")
        if drift != 0:
            step.append(f"th = th + {scaled('drift', drift)} * om")
            stale = True
    if stale:
        step.append(force)
    return {"preamble": list(constants.values()), "forcing_init": [], "forcing_step": [],
            "forcing_carry": [], "before": [force], "step": step, "carried": ["acc"]}


#: How each kind of fixed-step method becomes kernel source (keyed by ``method.kind``).
_STEPPERS = {"explicit": _explicit_stepper, "symplectic": _symplectic_stepper}


def method_of(spec: KernelSpec):
    """The method object of ``spec`` (registry name resolved)."""
    if isinstance(spec.method, str):
        if spec.method not in _methods.METHODS:
            raise ValueError(f"method must be one of "
                             f"{', '.join(map(repr, _methods.METHODS))}, got {spec.method!r}")
        return _methods.METHODS[spec.method]
    return _methods.resolve(spec.method)


# Names of the fixed-step kernel that an observable snippet may rely on (the step grid);
# an adaptive kernel has no such grid, so observables using them are refused there.
_STEP_GRID_NAMES = re.compile(r"\b(dt|step|k_state|n_steps|n_transient|save_every)\b")


def check_observables_fit(method, observe) -> None:
    """Refuse observables that sample the fixed step grid under an adaptive method.

    Raises
    ------
    ValueError
        Naming the observable, the method and what is accepted.
    """
    if not method.adaptive:
        return
    for name in observe:
        obs = OBSERVABLES[name]
        if any(_STEP_GRID_NAMES.search(getattr(obs, part)) for part in
               ("init", "update", "final")):
            fixed = ", ".join(repr(n) for n, m in _methods.METHODS.items() if not m.adaptive)
            raise ValueError(
                f"observable {name!r} is defined on the fixed step grid (t0 + n dt), which "
                f"the adaptive method {method.name!r} does not have; accepted: a fixed-step "
                f"method ({fixed}), or observe without {name!r}"
            )


def check_method_fits(method, *, damping: bool, forcing: bool, where: str = "the scene"):
    """Refuse a method that does not fit the scene (a symplectic method with damping or
    forcing), naming the method, the effect and what is accepted.

    Raises
    ------
    ValueError
    """
    if not method.conservative_only:
        return
    effects = [name for name, on in (("damping", damping), ("forcing", forcing)) if on]
    if effects:
        others = ", ".join(repr(n) for n, m in _methods.METHODS.items()
                           if not m.conservative_only)
        raise ValueError(
            f"method {method.name!r} is symplectic and integrates only conservative scenes "
            f"(no damping, no forcing), but {where} has {' and '.join(effects)}; accepted: "
            f"a scene (and grid) without damping and forcing, or one of {others}"
        )


def _snippets(spec: KernelSpec, part: str) -> str:
    """Concatenate one part (init/update/final) of every observed observable, with
    ``COL`` replaced by the observable's first column."""
    lines, col = [], 0
    for name in spec.observe:
        obs = OBSERVABLES[name]
        code = getattr(obs, part)
        if code:
            lines.append(f"# {name}\n" + code.replace("COL", str(col)))
        col += obs.n_columns
    return "\n".join(lines)


def _stop_source(spec: KernelSpec, action: str = "break") -> str:
    """Early stop (spec.stop_early): each observable's ``settled`` snippet sets its own
    flag; ``action`` runs when all flags are set."""
    if not spec.stop_early:
        return ""
    lines, flags, col = [], [], 0
    for name in spec.observe:
        obs = OBSERVABLES[name]
        if not obs.settled:
            raise ValueError(f"observable {name!r} has no settled test, so a trajectory "
                             "cannot stop early; accepted with stop_early: "
                             + ", ".join(n for n, o in OBSERVABLES.items() if o.settled))
        flag = f"settled_{len(flags)}"
        flags.append(flag)
        lines.append(f"# {name} settled?\n"
                     + obs.settled.replace("COL", str(col)).replace("SETTLED", flag))
        col += obs.n_columns
    lines.append(f"if {' and '.join(flags)}:\n" + _indent(action, 1))
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

    Raises
    ------
    ValueError
        For an unknown method, a symplectic method with damping or forcing, or an
        adaptive method with saving.
    """
    method = method_of(spec)
    check_method_fits(method, damping=spec.damping, forcing=spec.forcing,
                      where="the kernel spec")
    if method.adaptive and spec.save:
        raise ValueError(f"method {method.name!r} is adaptive: its steps are not on a fixed "
                         "grid, so it cannot save every k-th step; accepted: save=False")
    check_observables_fit(method, spec.observe)
    fastmath = _config.FASTMATH
    if not isinstance(fastmath, bool):  # a set, written in a fixed order (stable hash)
        fastmath = "{" + ", ".join(repr(flag) for flag in sorted(fastmath)) + "}"
    jit = (f"{{'fastmath': {fastmath}, 'boundscheck': {_config.BOUNDSCHECK!r}, "
           "'error_model': 'numpy', 'cache': True}")
    uses_energy = any(OBSERVABLES[n].uses_energy for n in spec.observe)
    body = (_adaptive_kernel if method.adaptive else _fixed_kernel)(spec, method)
    header = f'''\
"""Generated by sweep.kernels for {spec!r}. Do not edit."""
# sweep.kernels.vecmath {_VECMATH_DIGEST} (numba's cache does not track inlined imports)
import math
import numpy as np
from numba import njit, prange
from sweep.kernels.vecmath import cos as vcos, sin as vsin

JIT = {jit}


{_accel_source(spec)}

{_energy_source(spec) if uses_energy else ""}
'''
    text = header + body
    # drop the blank lines left by absent parts, for a readable module
    return "\n".join(line for line in text.splitlines() if line.strip()) + "\n"


def _load_lines(spec: KernelSpec) -> list[str]:
    load = [f"th0 = params[i, {_COL['theta0']}]", f"om0 = params[i, {_COL['omega0']}]",
            f"L = params[i, {_COL['length']}]", f"g = params[i, {_COL['gravity']}]",
            "w0sq = g / L"]
    if spec.damping:
        load.append(f"c = params[i, {_COL['damping']}]")
    if spec.forcing:
        load += [f"A = params[i, {_COL['forcing_amplitude']}]",
                 f"W = params[i, {_COL['forcing_frequency']}]",
                 f"phi = params[i, {_COL['forcing_phase']}]"]
    return load


def _final_block(spec: KernelSpec) -> str:
    return f'''\
        if ok:
            status[i] = {int(Status.OK)}
{_indent(_snippets(spec, "final"), 3) or "            pass"}
        else:
            status[i] = {int(Status.NONFINITE)}
            for col in range({n_columns(spec)}):
                out[i, col] = math.nan
'''


# Kernel variables holding a parameter, and the parameter's column.
_PARAMETER_OF = {"th0": "theta0", "om0": "omega0", "L": "length", "g": "gravity",
                 "c": "damping", "A": "forcing_amplitude", "W": "forcing_frequency",
                 "phi": "forcing_phase"}
_IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")
_ASSIGNED = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:[-+*/]?=)(?!=)", re.MULTILINE)


def _lane_snippet(code: str) -> str:
    """A per-trajectory snippet inside a block: ``out[i, ...]`` becomes the block's
    row buffer ``obuf[j, ...]`` (padding lanes then write nowhere shared)."""
    return code.replace("out[i,", "obuf[j,")


def _lane_loop(body: str, lane: dict[str, str], *, level: int, head: str = "",
               stores: list[str] | None = None, count: str = "BLOCK",
               load: bool = True) -> str:
    """``for j in range(count):`` around ``body``: loads each lane variable the body
    reads from its array ``lane_<name>[j]`` first (unless ``load`` is False) and
    stores back those it assigns (or ``stores``)."""
    used = set(_IDENTIFIER.findall(body)) if load else set()
    loads = [f"{name} = lane_{name}[j]" for name in lane if name in used]
    if stores is None:
        stores = [name for name in lane if name in set(_ASSIGNED.findall(body))]
    lines = loads + [body] + [f"lane_{name}[j] = {name}" for name in stores]
    return _indent(f"for j in range({count}):\n{head}" + _indent("\n".join(lines), 1),
                   level)


def _fixed_kernel(spec: KernelSpec, method) -> str:
    """Kernel body of a fixed-step method (time at step n is t0 + n dt).

    Trajectories go in blocks of ``spec.block`` SIMD lanes (one ``prange`` iteration
    per block); the time loop is outside and the lane loop inside, so the lane loop
    is straight-line arithmetic that LLVM vectorises (``vsin`` is branch-free). A
    partial last block is padded with copies of the last trajectory, so every lane
    runs the same code whatever the number of trajectories, blocks, chunks or threads:
    the results do not depend on how the work is cut. Per-lane state lives in small
    arrays ``lane_<name>``; observables write a per-block row buffer ``obuf``.

    Non-finite states are detected once, at the end (or when a trajectory stops
    early): a NaN never becomes finite again in this arithmetic (an infinite angle
    or velocity turns into NaN within a step), so the status is the same as with a
    test after every step, and samples saved after the failure are set to NaN.
    """
    parts = _STEPPERS[method.kind](spec, method)
    nl = "\n"
    # Every parameter is a lane variable (read per lane: no slower, and a product
    # such as A * sin(...) is then never hoisted out of the lane loop, which would
    # change where LLVM contracts it into an FMA, and the last bits of the result),
    # except W and phi when the forcing sine is shared by the block.
    shared_sine = spec.shared_forcing
    per_lane = ["L", "g", "w0sq"] + (["c"] if spec.damping else []) + \
        (["A"] if spec.forcing else []) + (["W", "phi"] if spec.forcing and not shared_sine
                                          else [])
    shared = ["W", "phi"] if shared_sine else []
    # lane variables (name -> dtype): state, per-lane parameters, carried values,
    # observable state, early-stop bookkeeping
    lane = {"th": "float64", "om": "float64", "th0": "float64", "om0": "float64"}
    lane.update({p: "float64" for p in per_lane})
    lane.update({name: "float64" for name in parts["carried"]})
    for name in spec.observe:
        lane.update(dict(OBSERVABLES[name].state))
    if spec.stop_early:
        lane.update({"done": "bool_", "th_stop": "float64", "om_stop": "float64"})

    def load(p, row):
        return f"{p} = g / L" if p == "w0sq" else f"{p} = params[{row}, {_COL[_PARAMETER_OF[p]]}]"

    # forcing: the sines sin(W t + phi) once per block and step when W and phi are
    # shared, else per lane in a loop of their own; either way the step loop reads
    # them as plain values s<f> and forms f = A * s<f> itself, so LLVM fuses the same
    # products into FMAs and both forms give the same bits (a test checks it)
    f_names = [name for name, _ in parts["forcing_init"] + parts["forcing_step"]]
    sines = {"init": [f"s{name} = vsin(W * ({at}) + phi)" for name, at in parts["forcing_init"]],
             "step": [f"s{name} = vsin(W * ({at}) + phi)" for name, at in parts["forcing_step"]],
             "carry": [f"s{dst} = s{src}" for dst, src in parts["forcing_carry"]]}
    block_init, block_step, block_after = (sines["init"], sines["step"], sines["carry"]) \
        if shared_sine else ([], [], [])
    lane_init = [] if shared_sine else sines["init"]
    lane_step = [f"{name} = A * s{name}" for name in f_names]
    if not shared_sine:
        lane.update({f"s{name}": "float64" for name in f_names})
    update = _lane_snippet(_snippets(spec, "update"))
    init = _lane_snippet(_snippets(spec, "init"))
    final = _lane_snippet(_snippets(spec, "final"))
    width = n_columns(spec)

    # --- once per lane: parameters, initial state, observables' init
    first = [f"i = min(base + j, n - 1)  # padding lanes repeat the last trajectory",
             load("th0", "i"), load("om0", "i")] + [load(p, "i") for p in per_lane] + \
        ["th = th0", "om = om0", init]
    if update:
        first += ["if n_transient <= 0:", _indent(update, 1)]
    if spec.save:
        first += ["if base + j < n:", "    saved[base + j, 0, 0] = th",
                  "    saved[base + j, 1, 0] = om"]
    first += parts["before"] + lane_init
    if spec.stop_early:
        first += ["done = False", "th_stop = th", "om_stop = om"]

    # --- one step of every lane: straight-line arithmetic, vectorised
    step_body = lane_step + parts["step"]
    step_stores = ["th", "om"] + parts["carried"]

    # --- observables' update (steady window) and the early-stop test, per lane
    observe_block = observe_body = observe_head = ""
    if update:
        observe_body = update
        if spec.stop_early:
            observe_head = "    if lane_done[j]:\n        continue\n"
            observe_body += nl + _lane_snippet(_stop_source(
                spec, action="done = True\nth_stop = th\nom_stop = om\nn_done += 1"))
        observe_block = "if step + 1 >= n_transient:\n{loop}"  # lane loop: below
        if spec.stop_early:
            observe_block += "\n    if n_done == BLOCK:\n        break"
    save_block = textwrap.dedent("""\
        if (step + 1) % save_every == 0:
            k_save = (step + 1) // save_every
            for j in range(n_real):
                saved[base + j, 0, k_save] = lane_th[j]
                saved[base + j, 1, k_save] = lane_om[j]""") if spec.save else ""

    # --- per real lane: status, observables' final values, copy out
    fail_saved = textwrap.dedent("""\
        for k_save in range(saved.shape[2]):
            for q in range(2):
                if not math.isfinite(saved[i, q, k_save]):
                    saved[i, q, k_save] = math.nan""") if spec.save else ""
    stop_state = "if done:\n    th = th_stop\n    om = om_stop\n" if spec.stop_early else ""
    finish = f"""i = base + j
{stop_state}if math.isfinite(th) and math.isfinite(om):
    status[i] = {int(Status.OK)}
{_indent(final, 1) or "    pass"}
else:
    status[i] = {int(Status.NONFINITE)}
    for col in range({width}):
        obuf[j, col] = math.nan
{_indent(fail_saved, 1)}
for col in range({width}):
    out[i, col] = obuf[j, col]"""
    # lane arrays only for what the loops after the first one read
    later = set(_IDENTIFIER.findall(nl.join(step_body + sines["step"] + sines["carry"] +
                                            [observe_head, observe_body, finish])))
    lane = {name: dtype for name, dtype in lane.items() if name in later}
    init_loop = _lane_loop(nl.join(first), lane, level=2, load=False)
    step_loop = _lane_loop(nl.join(step_body), lane, level=3,
                           stores=[name for name in lane if name in step_stores])
    if not shared_sine and sines["step"]:
        step_loop = _lane_loop(nl.join(sines["step"]), lane, level=3) + nl + step_loop
    if not shared_sine and sines["carry"]:
        step_loop += nl + _lane_loop(nl.join(sines["carry"]), lane, level=3)
    if observe_block:
        observe_block = observe_block.format(loop=_lane_loop(observe_body, lane, level=1,
                                                             head=observe_head))
    finish_loop = _lane_loop(finish, lane, level=2, stores=[], count="n_real")

    allocate = [f"lane_{name} = np.empty(BLOCK, dtype=np.{dtype})"
                for name, dtype in lane.items()]
    return f'''
BLOCK = {spec.block}


@njit(parallel=True, **JIT)
def kernel(params, t0, dt, n_steps, n_transient, save_every, out, status, saved):
    TWO_PI = 2.0 * math.pi
    n = params.shape[0]
{_indent(nl.join(parts["preamble"]), 1)}
    for b in prange((n + BLOCK - 1) // BLOCK):
        base = b * BLOCK
        n_real = min(BLOCK, n - base)
{_indent(nl.join(load(p, "base") for p in shared), 2)}
{_indent(nl.join(allocate), 2)}
        obuf = np.empty((BLOCK, {width}))
        k_state = 0
        n_done = 0
{init_loop}
{_indent(nl.join(block_init), 2)}
        for step in range(n_steps):
{_indent(nl.join(block_step), 3)}
{step_loop}
{_indent(nl.join(block_after), 3)}
            k_state = step + 1
{_indent(observe_block, 3)}
{_indent(save_block, 3)}
{finish_loop}
'''


# Step-size control of the adaptive kernels ([HNW] II.4, as in DOPRI5 and SciPy's RK45):
# h_new = h * min(FACMAX, max(FACMIN, SAFETY * err^(-1/(q+1)))), q the embedded order;
# no growth right after a rejection.
_SAFETY = 0.9
_FACMIN = 0.2
_FACMAX = 10.0


def _adaptive_kernel(spec: KernelSpec, tableau) -> str:
    """Kernel body of an embedded pair: each trajectory controls its own step."""
    s = tableau.stages
    forcing, nodes = _forcing_times(spec, tableau.c, time="t", step=None, scale="h",
                                    constants=None)
    f_lines = [_forcing_line(name, at) for name, at in nodes]
    stages = _rk_stages(spec, tableau, "h", None, forcing)
    kt = [f"k{j + 1}t" for j in range(s)]
    ko = [f"k{j + 1}o" for j in range(s)]
    new_state = [f"thn = th + {_combination(tableau.b, kt, 'h', None)}",
                 f"omn = om + {_combination(tableau.b, ko, 'h', None)}"]
    if tableau.fsal:
        # the last stage is evaluated at the new state: it is the next step's first
        stages = stages[2:-2]
        last = [f"k{s}t = omn",
                f"k{s}o = " + _accel_call(spec, "thn", "omn", forcing.get(tableau.c[-1]))]
        first = ["k1t = om", "k1o = " + _accel_call(spec, "th", "om", forcing.get(0))]
        f_first = [line for line in f_lines if line.startswith(f"{forcing.get(0)} =")]
        f_lines = [line for line in f_lines if line not in f_first]
        attempt = f_lines + stages + new_state + last
        accept_carry = [f"k1t = k{s}t", f"k1o = k{s}o"]
    else:
        first, f_first, accept_carry = [], [], []
        attempt = f_lines + _rk_stages(spec, tableau, "h", None, forcing) + new_state
    err = [f"et = {_combination(tableau.error_weights, kt, 'h', None)}",
           f"eo = {_combination(tableau.error_weights, ko, 'h', None)}"]
    update = _snippets(spec, "update")
    exponent = -1.0 / (tableau.embedded_order + 1)
    nl = chr(10)
    return f'''
@njit(parallel=True, **JIT)
def kernel(params, t0, t_end, dt, t_transient, rtol, atol, out, status, stats):
    TWO_PI = 2.0 * math.pi
    t_obs = t0 + t_transient
    h_min = 16.0 * 2.220446049250313e-16 * max(abs(t0), abs(t_end))
    for i in prange(params.shape[0]):
{_indent(nl.join(_load_lines(spec)), 2)}
        th = th0
        om = om0
{_indent(_snippets(spec, "init"), 2)}
{_indent(("if t_transient <= 0.0:" + nl + _indent(update, 1)) if update else "", 2)}
        t = t0
        h = dt
{_indent(nl.join(f_first + first), 2)}
        accepted = 0
        rejected = 0
        after_reject = False
        ok = True
        while t < t_end:
            last = t + h >= t_end
            if last:
                h = t_end - t
{_indent(nl.join(attempt), 3)}
{_indent(nl.join(err), 3)}
            sct = atol + rtol * max(abs(th), abs(thn))
            sco = atol + rtol * max(abs(om), abs(omn))
            err = math.sqrt(0.5 * ((et / sct) ** 2 + (eo / sco) ** 2))
            if err <= 1.0 and math.isfinite(thn) and math.isfinite(omn):
                t = t_end if last else t + h
                th = thn
                om = omn
{_indent(nl.join(accept_carry), 4)}
                accepted += 1
{_indent(("if t >= t_obs:" + nl + _indent(update, 1)) if update else "", 4)}
                if err == 0.0:
                    fac = {_FACMAX!r}
                else:
                    fac = min({_FACMAX!r}, max({_FACMIN!r}, {_SAFETY!r} * err ** {exponent!r}))
                if after_reject:
                    fac = min(fac, 1.0)
                after_reject = False
                h = min(h * fac, dt)
            else:
                rejected += 1
                if math.isfinite(err):
                    h = h * max({_FACMIN!r}, {_SAFETY!r} * err ** {exponent!r})
                else:
                    h = h * {_FACMIN!r}
                after_reject = True
                if h < h_min:
                    ok = False
                    break
        stats[i, 0] = accepted
        stats[i, 1] = rejected
{_final_block(spec)}'''


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
