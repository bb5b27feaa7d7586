"""What a kernel is built for (`KernelSpec`), what it reports per trajectory (`Status`),
and the checks that a method and observables fit a scene."""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from .. import _config
from .. import methods as _methods
from ..observables import OBSERVABLES, STROBE_SAMPLES
from ..physics import EFFECTS, EffectDeclaration

__all__ = ["DEVICES", "DTYPES", "KernelSpec", "Status", "check_block", "check_device",
           "check_dtype",
           "check_method_fits",
           "check_observables_fit",
           "check_tangent_fits", "declarations", "describe_block", "failure_summary",
           "method_of", "n_columns",
           "status_counts", "tangent"]


#: Where kernels run (`KernelSpec.device`).
DEVICES = ("cpu", "cuda")

#: The working precisions of the fixed-step kernels (`KernelSpec.dtype`).
DTYPES = ("float64", "float32")


class Status(enum.IntEnum):
    """Per-trajectory outcome stored in the dataset's ``status`` variable."""

    OK = 0
    NONFINITE = 1
    STEP_UNDERFLOW = 2
    ANGLE_OUT_OF_RANGE = 3

    @property
    def message(self) -> str:
        """What the code means, for users."""
        return _STATUS_MESSAGES[self]


_STATUS_MESSAGES = {
    Status.OK: "integrated to t_end",
    Status.NONFINITE: "state became non-finite (overflow or NaN); integration stopped",
    Status.STEP_UNDERFLOW: "the adaptive step shrank below 16 eps |t| (the solution blows "
                           "up, or is too stiff for the tolerances); integration stopped",
    Status.ANGLE_OUT_OF_RANGE: "the angle ended beyond the range where the kernel's sine is "
                               "accurate (|theta| <= 1e12 rad, 1e8 in float32: "
                               "KernelSpec.angle_limit); outputs are NaN",
}


def status_counts(status) -> dict[int, int]:
    """``{code: trajectories}`` of a `Status` array (any shape)."""
    import numpy as np

    status = np.asarray(status).reshape(-1)
    ok = status == Status.OK  # nearly every trajectory: sort only the others
    counts = {int(Status.OK): int(np.count_nonzero(ok))} if ok.any() else {}
    codes, others = np.unique(status[~ok], return_counts=True)
    counts.update({int(c): int(k) for c, k in zip(codes, others)})
    return dict(sorted(counts.items()))


def failure_summary(counts: dict[int, int], total: int) -> str | None:
    """``"3 of 12 trajectories became non-finite; see ds.status"`` (or ``"... failed (2
    nonfinite, 1 step_underflow) ..."`` when the kinds differ); None if none failed.

    Parameters
    ----------
    counts : dict
        Trajectories per `Status` code (`status_counts`).
    total : int
        Trajectories of the run.
    """
    failed = {Status(c): k for c, k in counts.items() if c != Status.OK and k}
    if not failed:
        return None
    n = sum(failed.values())
    if set(failed) == {Status.NONFINITE}:
        return f"{n} of {total} trajectories became non-finite; see ds.status"
    kinds = ", ".join(f"{k} {s.name.lower()}" for s, k in sorted(failed.items()))
    return f"{n} of {total} trajectories failed ({kinds}); see ds.status"


def declarations(effects) -> tuple[EffectDeclaration, ...]:
    """Effect declarations in canonical order from names, effect classes or
    instances, or declarations (registered ones in registration order, then the rest).

    Raises
    ------
    ValueError
        On an unknown effect name.
    """
    found = []
    for effect in effects:
        if isinstance(effect, str):
            if effect not in EFFECTS:
                raise ValueError(f"unknown effect {effect!r}; accepted: "
                                 f"{', '.join(map(repr, EFFECTS))}")
            effect = EFFECTS[effect].declaration
        elif not isinstance(effect, EffectDeclaration):
            effect = effect.declaration
        if effect not in found:
            found.append(effect)
    order = [cls.declaration for cls in EFFECTS.values()]
    return tuple(sorted(found, key=lambda d: order.index(d) if d in order else len(order)))


@dataclass(frozen=True)
class KernelSpec:
    """Everything that changes the compiled code (and nothing that does not).

    Attributes
    ----------
    model : {"nonlinear", "linear"}
    effects : tuple of EffectDeclaration
        The effects whose terms exist, in canonical order; given as names (``"damping"``),
        effect classes or declarations.
    observe : tuple of str
        Observable names in canonical (`OBSERVABLES`) order. With ``attractor`` the
        kernel takes the attractor catalogue as an argument, ``catalogue``
        (`sweep.kernels.snippets.catalogue_argument`): one kernel for every catalogue.
    save : bool
        Whether sampled trajectories are written.
    method : str or sweep.methods.ButcherTableau or sweep.methods.SplittingMethod
        Integrator: a `sweep.methods.METHODS` name or a method object. A registry
        object is stored as its name, so ``method=RK4`` and ``method="rk4"`` share one
        kernel; an unknown name is refused by `sweep.kernels.source`.
    stop_early : bool
        Stop each trajectory as soon as every observed observable says its answer is
        settled (only observables with a ``settled`` snippet; see `sweep.observables`).
    shared_forcing : bool
        True when the frequency and phase of every drive (an effect's harmonic signal,
        such as the forcing's ``sin(W t + phase)``) are the same for every trajectory
        of a call: the fixed-step kernel then evaluates each drive's sine once per step
        for a whole block instead of once per lane (the same arithmetic, so the same
        results; a test checks it). False (the default) is right for any parameter
        table; `sweep.run` sets it when its grid has no drive frequency or phase axis.
    refill : bool
        With ``stop_early``: a lane whose trajectory has settled takes the next waiting
        one (`sweep.kernels.refill`), so no lane idles until its block's slowest
        trajectory is done. Lanes are then at different steps, so a shared drive's
        sines come from a table over the steps, computed once per call (``n_steps`` x 8
        bytes per sine; `sweep.run` shares them only up to
        `sweep._config.SINE_TABLE_STEPS`), and other drives' sines are per lane.
        Bit-identical to ``refill=False`` (a test checks it).
    strobe_samples : int
        Stroboscopic samples the ``strobe`` observable keeps per trajectory (its
        ring's length; `sweep.observables.STROBE_SAMPLES` by default).
    device : {"cpu", "cuda"}
        Where the kernel runs: the CPU's SIMD lanes and threads, or an NVIDIA GPU with
        one CUDA thread per trajectory (`sweep.kernels.cuda`; fixed-step methods only,
        no refill or shared drive sines there).
    dtype : {"float64", "float32"}
        Working precision of the state, the parameters and the step's arithmetic
        (`sweep.kernels.precision`; float32 for fixed-step methods only). The clock
        ``t0 + n dt`` is formed in float64 and rounded once; observables accumulate
        and report in float64.
    block : int
        Trajectories per block of the fixed-step, refill and adaptive kernels (SIMD
        lanes; a multiple of 8, or 1 for a few trajectories, each alone). Results do not
        depend on it (a test checks it); `_config.BLOCK` by default.
    known_cells : bool
        With ``stop_early`` and the ``attractor`` observable: the kernel takes two more
        arguments, ``known`` (int32[n0, n1], per cell of a map over theta0 x omega0
        ``4 L + h``: the index ``L`` of the catalogued attractor its start settles on
        and the hits ``h`` (1..3) that stop a trajectory there, -1 unknown;
        `sweep._known.known_arguments`) and ``known_axes`` (float64[5],
        `sweep.kernels.snippets.known_source`), and stops a trajectory whose
        stroboscopic points (times ``t0 + m 2 pi / W``, m >= 1) fall in known cells of
        one label as many periods running as the last cell's ``h``, writing that label
        as its ``attractor`` (fixed-step float64 CPU kernels only).
    """

    model: str
    effects: tuple
    observe: tuple[str, ...]
    save: bool = False
    method: object = "rk4"
    stop_early: bool = False
    shared_forcing: bool = False
    block: int = None
    refill: bool = False
    device: str = "cpu"
    strobe_samples: int = STROBE_SAMPLES
    dtype: str = "float64"
    known_cells: bool = False

    def __post_init__(self) -> None:
        check_device(self.device)
        check_dtype(self.dtype)
        if self.known_cells and not (self.stop_early and "attractor" in self.observe
                                     and self.device == "cpu" and self.dtype == "float64"):
            raise ValueError("known_cells needs stop_early, the 'attractor' observable, "
                             "device='cpu' and dtype='float64'; accepted: all four, or "
                             "known_cells=False")
        if self.device == "cuda":  # one thread per trajectory: no lanes to refill or share
            object.__setattr__(self, "refill", False)
            object.__setattr__(self, "shared_forcing", False)
            object.__setattr__(self, "block", 1)  # one kernel whatever the grid's size
        method = self.method
        if not isinstance(method, str) and \
                _methods.METHODS.get(getattr(method, "name", None)) == method:
            object.__setattr__(self, "method", method.name)
        object.__setattr__(self, "effects", declarations(self.effects))
        # refill has no per-step save (early stop refuses saving anyway)
        object.__setattr__(self, "refill", bool(self.refill and self.stop_early
                                                and not self.save))
        object.__setattr__(self, "shared_forcing", bool(self.shared_forcing and self.drives))
        object.__setattr__(self, "block", check_block(self.block))

    @property
    def names(self) -> tuple[str, ...]:
        """Names of its effects, in canonical order."""
        return tuple(effect.name for effect in self.effects)

    @property
    def drives(self) -> tuple[EffectDeclaration, ...]:
        """Its effects that have a harmonic drive."""
        return tuple(effect for effect in self.effects if effect.drive is not None)

    @property
    def angle_limit(self) -> float | None:
        """Largest ``|theta|`` [rad] the kernel's sine of the angle is guaranteed for
        (`sweep.kernels.vecmath.SIN_RANGE`, or ``SIN32_RANGE`` in float32; the same on
        the GPU, so a status never depends on the device); None when the kernel takes no
        sine or cosine of the angle (the linear model without ``tension``)."""
        if self.model == "linear" and "tension" not in self.observe:
            return None
        from .vecmath import SIN32_RANGE, SIN_RANGE  # numba: not at `import sweep`

        return SIN_RANGE if self.dtype == "float64" else SIN32_RANGE

    def describe(self) -> str:
        """A one-line description for the generated module's docstring."""
        return (f"model={self.model!r}, effects={self.names!r}, observe={self.observe!r}, "
                f"save={self.save!r}, method={self.method!r}, stop_early={self.stop_early!r}, "
                f"shared_forcing={self.shared_forcing!r}, {describe_block(self.block)}, "
                f"refill={self.refill!r}, device={self.device!r}, "
                f"strobe_samples={self.strobe_samples!r}"
                + (f", dtype={self.dtype!r}" if self.dtype != "float64" else "")
                + (", known_cells=True" if self.known_cells else ""))


def describe_block(block: int) -> str:
    """The block in a generated module's docstring: a CPU module's text is the same for
    every block size but one lane (`sweep.kernels.lanes.BIND`), so it names no other."""
    return "block=1" if block == 1 else "block=BLOCK (bind)"


def check_block(block) -> int:
    """``block`` (trajectories per block of SIMD lanes), `_config.BLOCK` for None.

    Raises
    ------
    ValueError
        Unless it is 1 or a positive multiple of 8.
    """
    block = _config.BLOCK if block is None else block
    # not a bool: True == 1, but it would reach the compiled kernel as a boolean BLOCK
    # (`sweep.kernels.lanes.BIND`), which numba cannot type
    if isinstance(block, bool) or not isinstance(block, int) or \
            not (block == 1 or (block >= 8 and block % 8 == 0)):
        raise ValueError(f"block must be 1 or a positive multiple of 8, got {block!r}")
    return block


def n_columns(spec: KernelSpec) -> int:
    """Width of ``out``: every column of every observed observable, in observe order
    (an observable with samples > 1 fills ``samples`` columns per variable), then with
    ``known_cells`` one column ``stopped_known`` (1 where the trajectory stopped on
    known cells, else 0)."""
    return sum(OBSERVABLES[name].n_columns(spec) for name in spec.observe) + \
        (1 if spec.known_cells else 0)  # stopped_known, after the observables


def _check_option(name: str, value, accepted: tuple[str, ...], default: str, method) -> None:
    """Refuse a ``name`` not in ``accepted`` and, given the method, an adaptive method
    with any value but ``default`` (those kernels are fixed-step only)."""
    if not isinstance(value, str) or value not in accepted:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, accepted))}, got "
                         f"{value!r}")
    if value != default and method is not None and method.adaptive:
        fixed = ", ".join(repr(n) for n, m in _methods.METHODS.items() if not m.adaptive)
        raise ValueError(f"{name}={value!r} runs fixed-step methods; method "
                         f"{method.name!r} is adaptive; accepted: one of {fixed}, or "
                         f"{name}={default!r}")


def check_device(device, method=None) -> None:
    """Refuse an unknown device and, given the method, an adaptive method on the GPU
    (its kernel is fixed-step only).

    Raises
    ------
    ValueError
        Naming the device or method and what is accepted.
    """
    _check_option("device", device, DEVICES, "cpu", method)


def check_dtype(dtype, method=None) -> None:
    """Refuse an unknown working precision and, given the method, float32 with an
    adaptive method (its error control is written for float64's rounding).

    Raises
    ------
    ValueError
        Naming the dtype or method and what is accepted.
    """
    _check_option("dtype", dtype, DTYPES, "float64", method)


def tangent(spec: KernelSpec) -> bool:
    """True if an observed observable needs the tangent dynamics (``lyapunov``): only
    then are the Jacobian terms generated."""
    return any(OBSERVABLES[name].tangent for name in spec.observe)


def check_tangent_fits(method, effects, observe) -> None:
    """Refuse tangent dynamics (``lyapunov``) where they are not generated: adaptive
    and symplectic methods, and effects without a declared Jacobian.

    Raises
    ------
    ValueError
        Naming the observable, the method or effect, and what is accepted.
    """
    names = [n for n in observe if OBSERVABLES[n].tangent]
    if not names:
        return
    name = names[0]
    if method.adaptive or method.kind != "explicit":
        accepted = ", ".join(repr(n) for n, m in _methods.METHODS.items()
                             if not m.adaptive and m.kind == "explicit")
        what = "adaptive" if method.adaptive else "symplectic"
        raise ValueError(
            f"observable {name!r} integrates the tangent dynamics with a fixed-step "
            f"explicit Runge-Kutta method; method {method.name!r} is {what}; accepted: "
            f"{accepted}")
    for effect in declarations(effects):
        missing = effect.jacobian_missing()
        if missing:
            raise ValueError(
                f"observable {name!r} needs the Jacobian of every effect's term, but effect "
                f"{effect.name!r} declares no derivative of {effect.term!r} with respect to "
                f"{' and '.join(missing)}; accepted: a scene without {effect.name!r}, or its "
                "declaration with jacobian_theta/jacobian_omega")


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
STEP_GRID_NAMES = re.compile(r"\b(dt|step|k_state|n_steps|n_transient|save_every)\b")


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
        if any(STEP_GRID_NAMES.search(getattr(obs, part)) for part in
               ("init", "update", "final")):
            fixed = ", ".join(repr(n) for n, m in _methods.METHODS.items() if not m.adaptive)
            raise ValueError(
                f"observable {name!r} is defined on the fixed step grid (t0 + n dt), which "
                f"the adaptive method {method.name!r} does not have; accepted: a fixed-step "
                f"method ({fixed}), or observe without {name!r}"
            )


def _enumerate(names: list[str]) -> str:
    """``a, b and c``."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def check_method_fits(method, effects, *, where: str = "the scene") -> None:
    """Refuse a method that does not fit the scene's effects (a symplectic method with a
    non-conservative effect such as damping or forcing), naming the method, the effects
    and what is accepted.

    Parameters
    ----------
    method : method object
    effects : iterable of effect names, classes or declarations

    Raises
    ------
    ValueError
    """
    if not method.conservative_only:
        return
    offending = [effect.name for effect in declarations(effects) if not effect.conservative]
    if offending:
        dissipative = [name for name, cls in EFFECTS.items()
                       if not cls.declaration.conservative]
        others = ", ".join(repr(n) for n, m in _methods.METHODS.items()
                           if not m.conservative_only)
        raise ValueError(
            f"method {method.name!r} is symplectic and integrates only conservative scenes "
            f"(no {', no '.join(dissipative)}), but {where} has {' and '.join(offending)}; "
            f"accepted: a scene (and grid) without {_enumerate(dissipative)}, or one of "
            f"{others}"
        )
