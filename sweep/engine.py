"""`run`: validate -> parameter table -> kernel -> chunks -> dataset.

Orchestration only: the physics is in `scene`, the numbers in `_kernels`, the
dataset in `io`.
"""

from __future__ import annotations

import math
import os
import sys
import time
import warnings
from dataclasses import dataclass

import numpy as np

from . import _config, io
from ._kernels import KernelSpec, Status, build, columns
from ._validate import check_real
from .grid import Grid
from .observables import DEFAULT_OBSERVE, resolve
from .scene import Scene

__all__ = ["run", "RunSettings", "METHODS"]

#: Integrators `run` accepts (more arrive with the accuracy work).
METHODS = ("rk4",)

# A time span must be a whole number of steps to within this relative slack:
# (t_end - t0) / dt is computed in floating point, so 300 / 0.01 = 30000.000000000004.
_WHOLE_STEPS_RTOL = 1e-9


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


def _steps(name: str, span: float, dt: float) -> int:
    exact = span / dt
    n = round(exact)
    if abs(exact - n) > _WHOLE_STEPS_RTOL * max(1.0, exact):
        suggestion = span / max(n, 1)
        raise ValueError(
            f"{name} = {span!r} is not a whole number of steps dt = {dt!r} "
            f"({exact:.6g} steps); accepted: a dt that divides it, e.g. dt = {suggestion!r}"
        )
    return n


def _available_memory() -> int:
    """Bytes of memory available to this process (MemAvailable on Linux, else the
    free physical pages)."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:  # pragma: no cover - non-Linux
        pass
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")  # pragma: no cover


def validate_settings(*, t_end, dt, t0, t_transient, save_every, method) -> RunSettings:
    """Check the time-stepping arguments of `run`; return them cleaned.

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
    n_steps = _steps("t_end - t0", t_end - t0, dt)
    # first step index whose time t0 + n dt is >= t0 + t_transient
    n_transient = math.ceil(t_transient / dt - _WHOLE_STEPS_RTOL * max(1.0, t_transient / dt))
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
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))}, "
                         f"got {method!r}")
    return RunSettings(t0=t0, t_end=t_end, dt=dt, t_transient=t_transient, n_steps=n_steps,
                       n_transient=n_transient, save_every=save_every, method=method)


def _progress_printer(enabled: bool, total: int):
    """One aggregated progress line on stderr; a no-op when disabled."""
    if not enabled:
        return lambda done: None
    start = time.perf_counter()

    def report(done: int) -> None:
        elapsed = time.perf_counter() - start
        width = 30
        filled = int(width * done / total)
        sys.stderr.write(f"\rsweep: [{'#' * filled}{'.' * (width - filled)}] "
                         f"{done}/{total} trajectories, {elapsed:.1f} s")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return report


def run(
    scene: Scene,
    grid: Grid,
    *,
    t_end: float,
    dt: float,
    t0: float = 0.0,
    t_transient: float = 0.0,
    observe=DEFAULT_OBSERVE,
    save_every: int | None = None,
    method: str = "rk4",
    progress: bool | None = None,
    chunk_size: int | None = None,
    specialize: bool = True,
):
    """Integrate every trajectory of ``grid`` under ``scene``; return a labelled Dataset.

    Parameters
    ----------
    scene : Scene
        The physics; only its effects are simulated.
    grid : Grid
        Named axes; the run covers their Cartesian product.
    t_end : float
        Final time [s]; ``t_end - t0`` must be a whole number of steps ``dt``.
    dt : float
        Fixed step [s], > 0. Time at step n is ``t0 + n*dt``.
    t0 : float, default 0
        Initial time [s] (matters for the forcing phase).
    t_transient : float, default 0
        Steady observables (``theta_max``, ``amplitude``, ``tension``) accumulate
        only over ``t >= t0 + t_transient`` [s].
    observe : sequence of str, default ("final", "winding")
        Any of ``final`` (theta_final, omega_final), ``winding``, ``theta_max``,
        ``amplitude``, ``tension`` (tension_min, tension_max), ``energy``
        (energy_initial, energy_final). Only these are computed and stored.
    save_every : int, optional
        Also store ``theta`` and ``omega`` at every ``save_every``-th step (a ``time``
        dimension). Refused if it would need more than half the available memory.
    method : {"rk4"}
        Fixed-step integrator.
    progress : bool, optional
        Print one aggregated progress line to stderr; default: when stderr is a tty.
    chunk_size : int, optional
        Trajectories per chunk (progress granularity); results do not depend on it.
    specialize : bool, default True
        False builds the fully general kernel (damping and forcing terms present and
        fed zeros when the scene lacks them): for tests and benchmarks.

    Returns
    -------
    xarray.Dataset
        One dimension per grid axis (grid order), plus ``time`` when ``save_every`` is
        given; the observed variables; ``status`` (int8, CF flags; outputs of a
        non-finite trajectory are NaN); attributes that say how to reproduce the run.

    Raises
    ------
    ValueError, TypeError
        On bad input, before any compute.

    Warns
    -----
    RuntimeWarning
        When some trajectories became non-finite (count given; see ``ds.status``).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a sweep.Scene, got {scene!r}")
    if not isinstance(grid, Grid):
        raise TypeError(f"grid must be a sweep.Grid, got {grid!r}")
    grid.check_against(scene)
    settings = validate_settings(t_end=t_end, dt=dt, t0=t0, t_transient=t_transient,
                                 save_every=save_every, method=method)
    names = resolve(observe)
    if not names and save_every is None:
        raise ValueError("observe is empty and save_every is None -- nothing would be "
                         "computed; accepted: at least one of final, winding, theta_max, "
                         "amplitude, tension, energy, or a save_every")
    if chunk_size is None:
        chunk_size = _config.CHUNK_SIZE
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or chunk_size < 1:
        raise ValueError(f"chunk_size must be an int >= 1, got {chunk_size!r}")

    effects = grid.effects(scene)
    spec = KernelSpec(
        model=scene.model,
        damping=("damping" in effects) or not specialize,
        forcing=("forcing" in effects) or not specialize,
        observe=names,
        save=save_every is not None,
        method=settings.method,
    )
    n = grid.size
    n_columns = len(columns(spec))
    n_saved = settings.n_steps // save_every + 1 if save_every is not None else 0
    needed = n * (n_columns * 8 + 1 + 2 * n_saved * 8)
    available = _available_memory()
    if needed > available // 2:
        raise ValueError(
            f"save_every = {save_every!r} with {n} trajectories needs {needed / 2**30:.2f} GiB "
            f"but only {available / 2**30:.2f} GiB is available; accepted: a larger "
            "save_every, fewer trajectories, or save_every=None"
            if save_every is not None else
            f"a grid of {n} trajectories needs {needed / 2**30:.2f} GiB for its outputs but only "
            f"{available / 2**30:.2f} GiB is available; accepted: a smaller grid"
        )

    kernel = build(spec)
    out = np.empty((n, n_columns), dtype=np.float64)
    status = np.empty(n, dtype=np.int8)
    saved = np.full((n, 2, n_saved), np.nan) if save_every else np.empty((0, 2, 0))
    if progress is None:
        progress = sys.stderr.isatty()
    report = _progress_printer(bool(progress), n)
    for start, stop in grid.chunks(int(chunk_size)):
        table = grid.table(scene, start, stop)
        kernel(table, settings.t0, settings.dt, settings.n_steps, settings.n_transient,
               save_every or 1, out[start:stop], status[start:stop],
               saved[start:stop] if save_every else saved)
        report(stop)

    failed = int(np.count_nonzero(status != Status.OK))
    if failed:
        warnings.warn(
            f"{failed} of {n} trajectories became non-finite; see ds.status",
            RuntimeWarning,
            stacklevel=2,
        )
    return io.to_dataset(scene=scene, grid=grid, settings=settings, spec=spec, out=out,
                         status=status, saved=saved if save_every else None)
