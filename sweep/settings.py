"""The settings of a run, checked: time stepping (`validate_settings`, `RunSettings`),
the method, the chunk size and the block of SIMD lanes. Shared by the single pendulum's
engine (`sweep.engine`) and the systems' (`sweep.engine_systems`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _config
from . import methods as _methods
from ._timesteps import transient_steps, whole_steps
from ._validate import check_real
from .kernels.spec import check_device
from .methods import METHODS
from .observables import STROBE_SAMPLES, STROBE_SAMPLES_RANGE

__all__ = ["CUDA_CHUNK", "DEFAULT_ATOL", "DEFAULT_RTOL", "MIN_RTOL", "RunSettings",
           "check_strobe_samples", "default_chunk_size", "validate_method",
           "validate_settings"]

#: Default tolerances of the adaptive methods (per step, RMS norm over theta, omega):
#: about 1e-6 global error on a few periods of the pendulum.
DEFAULT_RTOL = 1e-6
DEFAULT_ATOL = 1e-9

#: Smallest rtol accepted: below ~100 machine epsilons the local error estimate is
#: round-off, and the controller would shrink the step for nothing (SciPy's floor too).
MIN_RTOL = 100 * np.finfo(np.float64).eps

@dataclass(frozen=True)
class RunSettings:
    """Validated time-stepping settings of a run (see `run` for the meaning)."""

    t0: float
    t_end: float
    dt: float
    t_transient: float
    n_steps: int
    n_transient: int
    save_every: int | None
    method: str
    rtol: float | None = None
    atol: float | None = None
    integrator: object = None

    @property
    def adaptive(self) -> bool:
        """True for an embedded pair (per-trajectory step-size control)."""
        return bool(self.integrator is not None and self.integrator.adaptive)


def validate_settings(*, t_end, dt, t0, t_transient, save_every, method, rtol=None,
                      atol=None) -> RunSettings:
    """Check the time-stepping arguments of `run`; return them cleaned.

    ``method`` is a `sweep.methods.METHODS` name or a method object; ``rtol``/``atol``
    belong to adaptive methods only (defaults `DEFAULT_RTOL`, `DEFAULT_ATOL`).

    Raises
    ------
    ValueError, TypeError
        Naming the argument, its value and what is accepted.
    """
    t0 = check_real("t0", t0)
    t_end = check_real("t_end", t_end)
    dt = check_real("dt", dt, minimum=0.0, strict=True, accepted="a finite number > 0 (s)")
    t_transient = check_real("t_transient", t_transient, minimum=0.0,
                             accepted="a finite number >= 0 (s)")
    if not t_end > t0:
        raise ValueError(f"t_end must be > t0 = {t0!r}, got t_end = {t_end!r}")
    if not t_transient < t_end - t0:
        raise ValueError(
            f"t_transient must be < t_end - t0 = {t_end - t0!r} (something must remain "
            f"to observe), got t_transient = {t_transient!r}"
        )
    integrator = validate_method(method)
    if integrator.adaptive:
        if save_every is not None:
            raise ValueError(
                f"save_every = {save_every!r} cannot be used with the adaptive method "
                f"{integrator.name!r}: each trajectory takes its own steps, so there is no "
                "common time axis to sample; accepted: save_every=None, or a fixed-step "
                f"method ({', '.join(repr(n) for n, m in METHODS.items() if not m.adaptive)})"
            )
        rtol = DEFAULT_RTOL if rtol is None else check_real(
            "rtol", rtol, minimum=MIN_RTOL, accepted=f"a finite number >= {MIN_RTOL:.3g} "
            "(100 machine epsilons)")
        atol = DEFAULT_ATOL if atol is None else check_real(
            "atol", atol, minimum=0.0, strict=True, accepted="a finite number > 0 "
            "(rad and rad/s)")
        # adaptive: dt is the first trial step and the largest step; no whole-step rule
        return RunSettings(t0=t0, t_end=t_end, dt=dt, t_transient=t_transient, n_steps=0,
                           n_transient=0, save_every=None, method=integrator.name,
                           rtol=rtol, atol=atol, integrator=integrator)
    for name, value in (("rtol", rtol), ("atol", atol)):
        if value is not None:
            raise ValueError(
                f"{name} = {value!r} applies only to adaptive methods "
                f"({', '.join(repr(n) for n, m in METHODS.items() if m.adaptive)}), but "
                f"method {integrator.name!r} takes fixed steps dt; accepted: {name}=None "
                "with a fixed-step method, or an adaptive method"
            )
    n_steps = whole_steps("t_end - t0", t_end - t0, dt)
    # first step index whose time t0 + n dt is >= t0 + t_transient
    n_transient = transient_steps(t_transient, dt)
    if n_transient >= n_steps:
        raise ValueError(
            f"t_transient = {t_transient!r} leaves no step to observe before t_end - t0 = "
            f"{t_end - t0!r} with dt = {dt!r}; accepted: t_transient <= t_end - t0 - dt"
        )
    if save_every is not None:
        if isinstance(save_every, (bool, np.bool_)) or not isinstance(
            save_every, (int, np.integer)
        ):
            raise TypeError(f"save_every must be None or an int >= 1 (steps), got "
                            f"{save_every!r}")
        if save_every < 1:
            raise ValueError(f"save_every must be None or an int >= 1 (steps), got "
                             f"{save_every!r}")
        save_every = int(save_every)
    return RunSettings(t0=t0, t_end=t_end, dt=dt, t_transient=t_transient, n_steps=n_steps,
                       n_transient=n_transient, save_every=save_every,
                       method=integrator.name, integrator=integrator)


def validate_method(method):
    """The method object for ``method`` (a `METHODS` name or a method object).

    Raises
    ------
    ValueError
        Listing the valid names.
    """
    if isinstance(method, str) and method in METHODS:
        return METHODS[method]
    if isinstance(method, (_methods.ButcherTableau, _methods.SplittingMethod)):
        return method
    raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))} (or a "
                     f"sweep.methods.ButcherTableau or SplittingMethod), got {method!r}")


def default_chunk_size(settings: RunSettings, stop_early: bool = False) -> int:
    """Trajectories per chunk when ``run`` is given none: about `_config.CHUNK_WORK`
    trajectory-steps of work (a second or so), a multiple of `_config.CHUNK_MIN`, at
    most `_config.CHUNK_SIZE`; with ``stop_early`` the cap, `_config.CHUNK_SIZE`. A
    function of the time settings (and ``stop_early``) alone, so a resumed run computes
    the same chunks.

    Why the cap with early stop: its trajectories mostly end long before ``t_end``, so
    a chunk sized by ``t_end`` holds a fraction of a second of work, and every chunk
    ends with its slowest trajectory while the other threads wait. The 1200 x 1200
    forced Wada map with known cells (`sweep.maps.known`) ran its main pass in 3.2 s in
    chunks of 8,192 (the size by ``t_end``: 32,000 steps) and in 2.3-2.6 s in chunks of
    65,536 or more, its threads busy 1.8 and 1.95 of 2 cores (AMD EPYC Zen 5, 2 cores,
    2026-11-28). If nothing stops early a chunk of the cap takes a few seconds."""
    if stop_early:
        return _config.CHUNK_SIZE
    steps = settings.n_steps or math.ceil((settings.t_end - settings.t0) / settings.dt)
    chunks = max(1, _config.CHUNK_WORK // max(steps, 1) // _config.CHUNK_MIN)
    return min(_config.CHUNK_SIZE, chunks * _config.CHUNK_MIN)


def _block(n: int, stop_early: bool) -> int:
    """Trajectories per block of a fixed-step run of ``n`` (see `sweep._config`): one
    each for a handful, 16 for a few dozen, small blocks for small grids and early
    stop, else `_config.BLOCK`."""
    if n < _config.NARROW_BELOW:
        return 1
    if n < _config.TINY_BELOW and not stop_early:
        return _config.TINY_BLOCK
    if stop_early or n < 16 * _config.BLOCK:
        return _config.SMALL_BLOCK
    return _config.BLOCK


#: Default trajectories per chunk on a GPU (2^20: ~8 threads per CUDA core of an
#: H100; the chunk's arrays are a few tens of MB).
CUDA_CHUNK = 2 ** 20


def _check_device(device, integrator) -> None:
    """Refuse an unknown device, an adaptive method on the GPU, and ``"cuda"`` where no
    GPU (or numba's CUDA simulator) is available -- before any compute."""
    check_device(device, integrator)
    if device != "cuda":
        return
    from .kernels.cuda import available

    reason = available()
    if reason is not None:
        raise ValueError(f"device='cuda' cannot run here: {reason}; accepted: "
                         "device='cpu'")


def check_strobe_samples(strobe_samples, names) -> None:
    """Refuse a number of stroboscopic samples out of range, or one given without the
    ``strobe`` observable (it would change nothing).

    Parameters
    ----------
    strobe_samples : int
        Samples the ``strobe`` observable keeps (`STROBE_SAMPLES_RANGE`).
    names : tuple of str
        The observed observables (`sweep.observables.resolve`).

    Raises
    ------
    TypeError
        If ``strobe_samples`` is not an int (a bool is not).
    ValueError
        If it is out of range, or differs from the default without ``strobe``.
    """
    low, high = STROBE_SAMPLES_RANGE
    accepted = f"an int from {low} to {high} (samples, one per forcing period)"
    if isinstance(strobe_samples, (bool, np.bool_)) or not isinstance(
            strobe_samples, (int, np.integer)):
        raise TypeError(f"strobe_samples must be {accepted}, got {strobe_samples!r}")
    if not low <= strobe_samples <= high:
        raise ValueError(f"strobe_samples must be {accepted}, got {strobe_samples!r}")
    if strobe_samples != STROBE_SAMPLES and "strobe" not in names:
        raise ValueError(f"strobe_samples = {strobe_samples!r} is read only by the 'strobe' "
                         "observable, which this run does not observe; accepted: "
                         "observe=(..., 'strobe'), or no strobe_samples")
