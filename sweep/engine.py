"""`run`: validate -> parameter table -> kernel -> chunks -> dataset.

Orchestration only: the physics is in `sweep.physics`, the numbers in `sweep.kernels`, the
dataset in `io`.
"""

from __future__ import annotations

import inspect
import math
import os
import warnings

import numpy as np

from . import _config, io
from . import methods as _methods
from . import stability as _stability
from ._known import check_known_cells, known_arguments, no_known_arguments
from ._timesteps import check_sampling_period
from ._validate import check_flag, check_positive_int
from ._version import __version__
from .catalogue_drives import pendulum_drives
from .catalogue_scene import attributes as scene_attributes
from .catalogue_scene import check_scene, grid_value, pendulum_values
from .execution import RunContext, execute
from .execution.local import allocate as _allocate
from .execution.local import integrate as _integrate
from .execution.progress import progress_bar
from .grid import Grid, ParameterRows
from .kernels import (
    KernelSpec,
    build,
    catalogue_argument,
    check_dtype,
    check_method_fits,
    check_observables_fit,
    check_tangent_fits,
    declarations,
    failure_summary,
    n_columns,
    status_counts,
)
from .methods import METHODS
from .observables import DEFAULT_OBSERVE, OBSERVABLES, STROBE_SAMPLES, resolve
from .physics import EFFECTS, Scene
from .physics.system import System
from .settings import (  # re-exported: sweep.engine.RunSettings, validate_settings, ...
    CUDA_CHUNK,
    DEFAULT_ATOL,  # noqa: F401
    DEFAULT_RTOL,  # noqa: F401
    MIN_RTOL,  # noqa: F401
    RunSettings,
    _block,
    _check_device,
    check_strobe_samples,
    default_chunk_size,
    validate_method,  # noqa: F401
    validate_settings,
)
from .strobe_phase import attributes as drive_attributes
from .strobe_phase import check_phase
from .system_attractors import catalogue_parts, check_rings

__all__ = ["run", "prepare", "warm_up", "estimate_error", "default_chunk_size", "RunSettings",
           "METHODS"]

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


def _check_stop_early(names, scene: Scene, grid: Grid, stop_early, save_every) -> None:
    """Observables that need an unforced scene, and what early stopping allows."""
    others = sorted(grid.effects(scene) - {"damping"})
    for name in names:
        if OBSERVABLES[name].unforced_only and scene.forcing is not None:
            raise ValueError(f"observable {name!r} is for unforced scenes (a forced pendulum "
                             "can leave a well); accepted: a Scene without Forcing, or "
                             "observe 'strobe' for forced basins")
        if OBSERVABLES[name].unforced_only and others:
            raise ValueError(f"observable {name!r} needs a pendulum with at most damping (its "
                             f"well criterion is the pendulum's energy), but the run has "
                             f"{' and '.join(others)}; accepted: a Scene with no effect but "
                             "Damping, or observe 'omega_mean'/'final' instead")
    if not isinstance(stop_early, (bool, np.bool_)):
        raise TypeError(f"stop_early must be True or False, got {stop_early!r}")
    if not stop_early:
        return
    stoppable = [n for n, o in OBSERVABLES.items() if o.settled]
    for name in names:
        if not OBSERVABLES[name].settled:
            raise ValueError(f"stop_early=True: observable {name!r} needs the whole run; "
                             f"accepted with stop_early: {', '.join(stoppable)}")
    if save_every is not None:
        raise ValueError("stop_early=True cannot save trajectories (they would end at "
                         "different times); accepted: save_every=None")


def _check_stroboscopic(names, scene: Scene, grid: Grid, settings) -> None:
    """Observables that sample once per forcing period need forcing, W > 0, and a
    period that is a whole number of steps (so every sample is at the same phase)."""
    for name in names:
        if not OBSERVABLES[name].requires_forcing:
            continue
        if scene.forcing is None:
            raise ValueError(f"observable {name!r} samples once per forcing period and "
                             "needs a forcing in the scene; accepted: a Scene with "
                             "sweep.Forcing(amplitude, frequency, phase)")
        frequencies = grid.axes.get("forcing_frequency",
                                    np.array([scene.forcing.frequency]))
        check_sampling_period(name, frequencies, settings.dt)


def _extremes(values: dict[str, np.ndarray]) -> list[dict[str, float]]:
    """Every corner of the box spanned by the min and max of each parameter."""
    corners = [{}]
    for name, array in values.items():
        ends = sorted({float(array.min()), float(array.max())})
        corners = [dict(corner, **{name: end}) for corner in corners for end in ends]
    return corners


def _energy_speed_bound(scene: Scene, grid: Grid, p: dict) -> float:
    """A bound on ``|theta'|`` from the starts' energy [rad/s]: exact for a pendulum
    without forces (torque, forcing and a moving pivot can exceed it)."""
    def largest(name, default):
        return float(np.max(np.abs(grid.axes.get(name, [default]))))

    w2 = largest("gravity", p["gravity"]) / float(np.min(grid.axes.get("length",
                                                                       [p["length"]])))
    omega0, theta0 = largest("omega0", 0.0), largest("theta0", 0.0)
    # sqrt(omega0^2 + potential) as a hypotenuse: no overflow for huge starts (a
    # start of 1e300 rad/s gives a bound of 1e300, not an OverflowError)
    reach = 2.0 * math.sqrt(w2) if scene.model == "nonlinear" else math.sqrt(w2) * theta0
    return math.hypot(omega0, reach)


def _speed_bound(scene: Scene, grid: Grid, effects, corner: dict, energy: float) -> float:
    """A bound on ``|theta'|`` over the run at one corner of the parameter ranges
    [rad/s] (see `EffectDeclaration`'s ``speed_bound``): the energy bound, or a
    speed-capping effect's terminal speed under every force the effects declare."""
    values = [{q.symbol: corner[q.axis] for q in effect.parameters} |
              {"L": corner["length"], "g": corner["gravity"]} for effect in effects]
    forces = [f for effect, known in zip(effects, values)
              if (f := effect.bound("force_bound", known)) is not None]
    force_max = abs(corner["gravity"] / corner["length"]) + sum(forces)
    caps = [c for effect, known in zip(effects, values)
            if (c := effect.bound("speed_bound", known | {"force_max": force_max}))
            is not None and math.isfinite(c)]
    if not caps or scene.model != "nonlinear":
        return energy
    omega0 = float(np.max(np.abs(grid.axes.get("omega0", [0.0]))))
    terminal = max(omega0, min(caps))
    return terminal if any(f > 0 for f in forces) else min(energy, terminal)


def _check_stable_step(scene: Scene, grid: Grid, settings, effects) -> None:
    """Refuse a fixed step beyond the method's linear stability limit (see
    `sweep.stability`). The linearisation at the bottom is ``theta'' + C theta' + K
    theta``, ``K = g/L`` plus each effect's declared ``linear_stiffness`` (its largest
    value) and ``C`` the sum of their ``linear_damping``; both are checked at every
    corner of the grid's parameter ranges (exact for the declared terms, which are
    monotone in each parameter). ``omega_max`` in a declaration is `_speed_bound` at
    that corner. Then each drive's largest frequency on the grid must be resolved by
    ``dt`` (`sweep.stability.check_drive`)."""
    p = scene.parameters()
    names = ["gravity", "length"] + [a for effect in effects for a in effect.axes]
    values = {name: np.asarray(grid.axes.get(name, [p[name]]), dtype=np.float64)
              for name in names}
    energy = _energy_speed_bound(scene, grid, p)
    dampings, stiffnesses = set(), set()
    for corner in _extremes(values):
        c, k = 0.0, corner["gravity"] / corner["length"]
        omega_max = _speed_bound(scene, grid, effects, corner, energy)
        for effect in effects:
            known = {q.symbol: corner[q.axis] for q in effect.parameters}
            dc, dk = effect.linearisation(dict(known, L=corner["length"], g=corner["gravity"],
                                               omega_max=omega_max))
            c, k = c + dc, k + dk
        dampings.add(c)
        stiffnesses.add(k)
    _stability.check(settings.integrator, settings.dt, sorted({min(dampings), max(dampings)}),
                     sorted({min(stiffnesses), max(stiffnesses)}))
    drives = [_drive_axes(effect)[0] for effect in effects if effect.drive is not None]
    _stability.check_drive(settings.integrator, settings.dt,
                           [(axis, float(np.max(np.abs(values[axis])))) for axis in drives])


def _drive_axes(effect) -> tuple[str, str]:
    """Grid axes of a drive's frequency and phase."""
    axis = {p.symbol: p.axis for p in effect.parameters}
    return axis[effect.drive.frequency], axis[effect.drive.phase]


def _prepare(scene, grid, *, t_end, dt, t0, t_transient, observe, save_every, method,
             rtol, atol, chunk_size, specialize, check_stability, estimate_error,
             stop_early, device="cpu", strobe_samples=STROBE_SAMPLES, dtype="float64",
             attractors=None, known_cells=None, checkpoint=None):
    """Validate the arguments of `run` (before any compute); return the time
    settings, the kernel spec and the chunk size. Raises ValueError/TypeError."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a sweep.Scene, got {scene!r}")
    if not isinstance(grid, ParameterRows):
        raise TypeError(f"grid must be a sweep.Grid or sweep.Points, got {grid!r}")
    grid.check_against(scene)
    settings = validate_settings(t_end=t_end, dt=dt, t0=t0, t_transient=t_transient,
                                 save_every=save_every, method=method, rtol=rtol, atol=atol)
    names = resolve(observe)
    orbits = attractor_orbits(attractors)
    if orbits:
        check_one_scene(grid)
        names = resolve(names + ("attractor",))
    elif "attractor" in names:
        raise ValueError("observable 'attractor' matches the run against an attractor "
                         "catalogue; accepted: attractors=sweep.maps.attractor_catalogue("
                         "pilot_run), or observe without 'attractor'")
    if not names and save_every is None:
        raise ValueError("observe is empty and save_every is None -- nothing would be "
                         "computed; accepted: at least one of final, winding, theta_max, "
                         "amplitude, tension, energy, or a save_every")
    check_strobe_samples(strobe_samples, names)
    if estimate_error is not None:
        check_positive_int("estimate_error", estimate_error,
                           "None or an int >= 1 (trajectories)")
    if chunk_size is None:  # a GPU needs ~10^5-10^6 threads in flight to be busy
        chunk_size = default_chunk_size(settings, bool(stop_early)) \
            if device != "cuda" else CUDA_CHUNK
    check_positive_int("chunk_size", chunk_size)

    integrator = settings.integrator
    _check_device(device, integrator)
    if device == "cpu":
        _config.vector_width()  # a bad SWEEP_VECTOR_WIDTH is refused before any compute
    check_dtype(dtype, integrator)
    effects = declarations(grid.effects(scene))
    check_method_fits(integrator, effects)
    check_tangent_fits(integrator, effects, names)
    check_observables_fit(integrator, names)
    _check_stroboscopic(names, scene, grid, settings)
    if orbits:  # the attractors of another scene: -1 everywhere
        check_scene(attractors, pendulum_values(scene, grid))
    if orbits and scene.forcing is not None:  # rings of another drive phase: -1 everywhere
        frequency, phase = forcing_drive(scene, grid)
        check_phase(attractors, len(orbits), frequency, settings, "forcing_frequency",
                    phase=phase, others=pendulum_drives(scene, grid))
    _check_stop_early(names, scene, grid, stop_early, save_every)
    if known_cells is not None:
        check_known_cells(known_cells, attractors=len(orbits), stop_early=stop_early,
                          method=integrator, checkpoint=checkpoint)
        if device != "cpu" or dtype != "float64":
            raise ValueError(f"known_cells runs on the CPU in float64; got device="
                             f"{device!r}, dtype={dtype!r}; accepted: device='cpu', "
                             "dtype='float64', or known_cells=None")
    if not isinstance(check_stability, (bool, np.bool_)):
        raise TypeError(f"check_stability must be True or False, got {check_stability!r}")
    check_flag("specialize", specialize)
    if check_stability:
        _check_stable_step(scene, grid, settings, effects)
    if not specialize:  # every registered effect the method can integrate, fed zeros
        effects = tuple(cls.declaration for cls in EFFECTS.values()
                        if cls.declaration.conservative or not integrator.conservative_only)
        check_tangent_fits(integrator, effects, names)
    refill = bool(stop_early) and _config.REFILL
    spec = KernelSpec(
        model=scene.model,
        effects=effects,
        observe=names,
        save=save_every is not None,
        stop_early=bool(stop_early),
        method=integrator,
        block=(1 if grid.size < _config.ADAPTIVE_NARROW_BELOW else _config.ADAPTIVE_BLOCK)
        if integrator.adaptive else _block(grid.size, stop_early),
        # a settled trajectory's lane takes the next waiting one (no idle lanes)
        refill=refill,
        # one sine per drive and step for a whole block when no trajectory differs in it
        shared_forcing=not any(grid.varies(name) for effect in effects if effect.drive is not None
                               for name in _drive_axes(effect))
        and not (refill and settings.n_steps > _config.SINE_TABLE_STEPS),
        device=device,
        strobe_samples=int(strobe_samples),
        dtype=dtype,
        known_cells=known_cells is not None,
    )
    _check_angle_range(grid, spec)
    return settings, spec, int(chunk_size)


def _check_angle_range(grid: Grid, spec: KernelSpec) -> None:
    """Refuse starts beyond the range where the kernel's sine of the angle is accurate
    (`KernelSpec.angle_limit`); a trajectory that leaves it during the run is flagged
    ``ANGLE_OUT_OF_RANGE`` by the kernel instead."""
    limit = spec.angle_limit
    theta0 = np.asarray(grid.axes.get("theta0", [0.0]), dtype=np.float64)
    if limit is None or theta0.size == 0 or np.max(np.abs(theta0)) <= limit:
        return
    index = int(np.argmax(np.abs(theta0)))
    raise ValueError(
        f"theta0 = {float(theta0[index])!r} rad (index {index}) is beyond the range where "
        f"the kernel's sine is accurate ({spec.dtype}); accepted: |theta0| <= {limit:g} "
        "rad (in the nonlinear model theta0 % (2 * np.pi) gives the same motion)")


#: The grid axes an attractor catalogue may be used across: initial conditions only.
#: Every other parameter changes the attractors themselves, and a catalogue holds the
#: attractors of one scene.
def forcing_drive(scene, grid) -> tuple[float, float]:
    """The forcing's frequency W [rad/s] and phase constant phi [rad] of a run of
    ``scene`` (with a forcing) over ``grid`` (varying the initial state only: a run with
    a catalogue, `check_one_scene`): the grid's value of ``forcing_frequency`` and
    ``forcing_phase``, else the scene's (`sweep.catalogue_scene.grid_value`; what a
    catalogue's drive phase is checked against, `sweep.strobe_phase`)."""
    return tuple(grid_value(grid, name, value)
                 for name, value in (("forcing_frequency", scene.forcing.frequency),
                                     ("forcing_phase", scene.forcing.phase)))


INITIAL_AXES = ("theta0", "omega0")


def check_one_scene(grid: ParameterRows) -> None:
    """Refuse a grid (or points) that varies anything but the initial conditions (for an
    attractor catalogue, which holds one scene's attractors). A `Points` column varies
    when it holds more than one distinct value.

    Raises
    ------
    ValueError
        Naming the varied axes and what is accepted.
    """
    varied = [name for name in grid.axes if name not in INITIAL_AXES and grid.varies(name)]
    if varied:
        raise ValueError(f"an attractor catalogue holds the attractors of one scene, but the "
                         f"grid varies {', '.join(varied)}; accepted: a grid that varies only "
                         f"{' and '.join(INITIAL_AXES)}")


def attractor_orbits(attractors) -> tuple:
    """The orbits of an attractor catalogue (for the kernel's ``catalogue`` argument,
    `sweep.kernels.catalogue_argument`) from a catalogue of stroboscopic rings
    (`sweep.maps.attractor_catalogue`): per attractor, the last ``period`` points of its
    ring, ``(theta mod 2 pi, omega)``; ``()`` for None.

    Raises
    ------
    ValueError
        Naming what is wrong with the catalogue and what is accepted.
    """
    if attractors is None:
        return ()
    accepted = ("accepted: a catalogue from sweep.maps.attractor_catalogue(run), a mapping "
                "with 'theta', 'omega' (m x P stroboscopic rings, finite) and 'period' "
                "(m ints, 1 <= period <= P / 2: a ring shows its orbit twice)")
    theta, omega, period = catalogue_parts(attractors, accepted)
    check_rings(theta, omega, period, accepted, ndim=2)
    return tuple(tuple((float(np.mod(t, 2 * np.pi)), float(w))
                       for t, w in zip(theta[a, -p:], omega[a, -p:]))
                 for a, p in enumerate(int(q) for q in period))


def _catalogue_attrs(attractors) -> dict:
    """The catalogue's rings as dataset attributes (for `sweep.maps.basins`)."""
    if attractors is None:
        return {}
    theta = np.asarray(attractors["theta"], dtype=np.float64)
    return {"attractors_theta": theta.ravel(),
            "attractors_omega": np.asarray(attractors["omega"], dtype=np.float64).ravel(),
            "attractors_period": np.asarray(attractors["period"], dtype=np.int64),
            "attractors_samples": int(theta.shape[1]),
            **drive_attributes(attractors, theta.shape[0]), **scene_attributes(attractors)}


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
    method="rk4",
    rtol: float | None = None,
    atol: float | None = None,
    progress: bool | None = None,
    chunk_size: int | None = None,
    specialize: bool = True,
    check_stability: bool = True,
    estimate_error: int | None = None,
    checkpoint=None,
    resume: bool = False,
    keep_checkpoint: bool = False,
    stop_early: bool = False,
    client=None,
    device: str = "cpu",
    strobe_samples: int = STROBE_SAMPLES,
    dtype: str = "float64",
    attractors=None,
    known_cells=None,
):
    """Integrate every trajectory of ``grid`` under ``scene``; return a labelled Dataset.

    Parameters
    ----------
    scene : Scene or System
        The physics; only its effects are simulated. A system with several coordinates
        (`sweep.DoublePendulum`) runs its own kernel (`sweep.engine_systems`): fixed-step
        explicit Runge-Kutta methods, observables ``final``, ``winding``, ``energy``,
        ``flip``, ``lyapunov`` and, for a driven system, ``strobe`` (once per period of
        its drive, `sweep.physics.System.drive_frequency_parameter`;
        `sweep.system_observables`), ``save_every``, ``stop_early`` at the first flip,
        Dask; the other options are refused for it, before any compute.
    grid : Grid
        Named axes; the run covers their Cartesian product.
    t_end : float
        Final time [s]; ``t_end - t0`` must be a whole number of steps ``dt`` (fixed-step
        methods).
    dt : float
        Fixed step [s], > 0. Time at step n is ``t0 + n*dt``. For an adaptive method:
        the first trial step and the largest step any trajectory takes.
    t0 : float, default 0
        Initial time [s] (matters for the forcing phase).
    t_transient : float, default 0
        Steady observables (``theta_max``, ``amplitude``, ``tension``) accumulate
        only over ``t >= t0 + t_transient`` [s].
    observe : sequence of str, default ("final", "winding")
        Any of ``final`` (theta_final, omega_final), ``winding``, ``theta_max``,
        ``amplitude``, ``tension`` (tension_min, tension_max), ``energy``
        (energy_initial, energy_final), ``lyapunov`` (lyapunov_max, lyapunov_min [1/s],
        fixed-step Runge-Kutta methods), and the others of `sweep.observables`. Only
        these are computed and stored.
    save_every : int, optional
        Also store ``theta`` and ``omega`` at every ``save_every``-th step (a ``time``
        dimension). Refused if it would need more than half the available memory, and
        with an adaptive method (no common time axis).
    method : str or method object, default "rk4"
        A `sweep.methods.METHODS` name or object. Fixed step: ``"euler"`` (order 1),
        ``"heun"`` (2), ``"rk4"`` (4), ``"rk38"`` (4); symplectic, for scenes without
        damping and forcing only: ``"verlet"`` (2), ``"yoshida4"`` (4); adaptive:
        ``"dopri5"`` (5(4), each trajectory controls its own step).
    rtol, atol : float, optional
        Adaptive methods only (an error otherwise): each accepted step has an error
        estimate ``<= atol + rtol * |y|`` in the RMS norm over (theta, omega) [rad,
        rad/s]. Defaults 1e-6 and 1e-9. Steady observables update at accepted steps;
        the last step is clipped so every trajectory ends at ``t_end`` exactly. The
        dataset gains ``steps_accepted`` and ``steps_rejected`` per trajectory.
    progress : bool, optional
        Show a progress bar (`tqdm`: trajectories done, rate, time left; a widget in
        Jupyter) on stderr. Default: when stderr is a terminal or in a notebook, and
        never when the environment variable ``CI`` is set (true).
    chunk_size : int, optional
        Trajectories per chunk (the unit of progress, checkpoints and Dask tasks);
        results do not depend on it. Default `default_chunk_size`: about a second of
        work per chunk, at most 65,536 trajectories.
    specialize : bool, default True
        False builds the fully general kernel (damping and forcing terms present and
        fed zeros when the scene lacks them): for tests and benchmarks.
    check_stability : bool, default True
        Refuse a fixed ``dt`` beyond the method's linear stability limit for the scene
        and grid (`sweep.stability`: the pendulum linearised at the bottom, eigenvalues
        ``-c/2 +- sqrt(c^2/4 - g/L)`` at the extremes of the damping and ``g/L`` axes;
        RK4: ``dt |lambda| <= 2.785`` on the real axis, ``<= 2.828`` on the imaginary
        axis; Verlet ``w dt < 2``). It covers the scene's linear stiffness, not the
        nonlinear pendulum's physical instability near the top nor the accuracy of fast
        rotation. Adaptive methods are never checked for stability. It also refuses a
        ``dt`` that does not resolve a drive (`sweep.stability.check_drive`: the largest
        forcing or pivot frequency ``W`` on the grid must have ``W dt`` within the
        method's 1 % limit on a sinusoid; RK4: ``W dt <= 1.70``, 3.7 steps per period;
        DOPRI5's largest step: 3.24). False integrates anyway: unstable trajectories then
        grow, overflow and are flagged non-finite (for tests).
    stop_early : bool, default False
        Stop each trajectory as soon as its answer is settled: for ``capture`` (the
        well of an unforced pendulum, final once its energy is below the separatrix)
        and ``strobe`` (the stroboscopic samples are periodic, the attractor found).
        Only observables with such a test may be observed; the saving is the point
        (measured in the user guide's Maps page, docs/guide/maps.md, "Simulate only
        what the question needs").
    estimate_error : int, optional
        Opt-in accuracy estimate: re-run this many random trajectories with half the
        step (or 100x tighter tolerances) and attach the estimated global error of the
        final state to the attributes (``error_estimate_max``, ``error_estimate_rms``
        [rad]); see `estimate_error`.
    checkpoint : str or Path, optional
        A folder (created if missing) where each finished chunk is written atomically,
        so that an interrupted run can be resumed (see `sweep.execution.checkpoint`). Without
        ``resume`` the folder must not hold a checkpoint already.
    resume : bool, default False
        Load the chunks already in ``checkpoint`` instead of computing them; the
        result is bit-identical to an uninterrupted run. Refused (ValueError naming
        each difference) if the checkpoint belongs to another scene, grid, settings,
        chunk size or sweep version; an absent checkpoint starts from scratch.
    keep_checkpoint : bool, default False
        Keep the checkpoint files after the chunks are all done (default: remove
        them, and the folder if that leaves it empty).
    client : dask.distributed.Client, optional
        Run each chunk as a task on this Dask cluster (`sweep.distributed`; needs the
        ``dask`` extra) and gather the chunks as they finish; the dataset is
        bit-identical to a local run. A lost worker's chunks are rerun elsewhere;
        ``chunk_size`` is the task size. Works with ``checkpoint``/``resume``.
    strobe_samples : int, default 16
        Stroboscopic samples the ``strobe`` observable keeps per trajectory (the last
        ones, one per forcing period, or per drive period for a system): 16 recognise
        periods up to 8; hundreds draw an
        orbit diagram (`sweep.plot.orbit_diagram`). Between 2 and 4096; only with
        ``strobe`` observed. With ``stop_early`` a trajectory stops only once all N
        samples are taken and repeat with a period up to min(N // 2, 8), so a large N
        stops late.
    device : {"cpu", "cuda"}, default "cpu"
        ``"cuda"``: run on an NVIDIA GPU, one CUDA thread per trajectory, from the same
        generated pieces (`sweep.kernels.cuda`; needs the ``cuda`` extra and a GPU,
        refused before any compute otherwise). Every fixed-step method and observable
        the CPU kernels support; chunks are copied to the GPU and back, so memory
        stays O(chunk_size); results agree with the CPU's to rounding (the GPU's
        sine is not `sweep.kernels.vecmath`'s).
    dtype : {"float64", "float32"}, default "float64"
        Working precision of the state and the step's arithmetic (fixed-step methods;
        `sweep.kernels.precision`). ``"float32"`` runs more trajectories per SIMD
        register and per GPU clock, at the cost of float32 rounding: about 6e-8
        relative per step, which grows over a run (see the user guide's section on
        float32, docs/guide/integrators.md, "Single precision": its speed, and where
        basin labels and Lyapunov exponents change and where they do not). The
        nonlinear pendulum's angle, the drives' frequencies and phases, the clock, the
        observables' accumulators and the outputs stay float64; the state steps by
        ``float32(dt)``.
    attractors : mapping, optional
        An attractor catalogue of the scene (`sweep.maps.attractor_catalogue` of a
        pilot run, e.g. a coarse grid with ``stop_early``): adds the ``attractor``
        observable, which records the catalogued attractor a trajectory is seen to
        settle on (its stroboscopic point within `sweep.observables.ATTRACTOR_TOL` of
        the attractor orbit's successive points for `ATTRACTOR_MATCHES` periods
        running). With ``stop_early`` that match alone stops the trajectory, long
        before the ``strobe`` test's 1e-8 periodicity could; `sweep.maps.basins` labels
        such a trajectory by the catalogued attractor. Attractors not in the catalogue
        are still found by the ``strobe`` test. The catalogue is stored in the
        dataset's attributes (``attractors_*``). Its rings must have been sampled at
        this run's drive phase ``W t + phi`` (``drive_phase`` and ``drive_frequency``,
        which `sweep.maps.attractor_catalogue` records: the same frequency, and e.g.
        the same ``forcing_phase`` phi with the pilot's ``t0 + t_transient`` and this
        run's a whole number of forcing periods apart; `sweep.strobe_phase`), and at
        one of the phases its rings met of each other drive (a `PivotDrive`:
        ``other_drive_phases``), else the run is refused; a catalogue without them is
        not checked. A run of another
        scene than the catalogue's ``scene`` (its pilot's parameters of one value,
        `sweep.catalogue_scene`) is refused too.
    known_cells : xarray.DataArray, optional
        With ``attractors`` and ``stop_early`` (fixed-step methods on the CPU, float64):
        a map over ``theta0`` and ``omega0`` (each evenly spaced) of the catalogued
        attractor each cell's start settles on (its index in ``attractors``), -1 where
        unknown, e.g. labels known from a coarser map. A trajectory whose stroboscopic
        points (times ``t0 + m 2 pi / W``, m >= 1, from the start on, whatever
        ``t_transient``) fall in cells of one label `sweep.observables.KNOWN_HITS`
        periods running, fewer where the last cell's label reaches its neighbours in
        the map (`sweep.observables.KNOWN_HITS_BY_DEPTH`; the angle taken modulo 2 pi
        onto the map's rows; a point beyond the map is no hit), stops there and is
        labelled with it (``attractor``).
        The map is read, never written, during the run, so the result does not depend
        on threads, blocks, chunks or Dask. The dataset gains ``stopped_known`` (1
        where a trajectory stopped on known cells) and the attribute
        ``cells_stopped_known``. Which cells to mark known sets the accuracy (see
        `sweep.maps.refine` with ``known_cells=True`` and the maps guide).

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
        When some trajectories failed (counts by kind: non-finite, step underflow;
        see ``ds.status``).
    """
    if isinstance(scene, System):  # several coordinates: sweep.engine_systems
        from .engine_systems import run_system

        return run_system(
            scene, grid, t_end=t_end, dt=dt, t0=t0, t_transient=t_transient,
            observe=None if observe is DEFAULT_OBSERVE else observe,
            save_every=save_every, method=method, rtol=rtol, atol=atol, progress=progress,
            chunk_size=chunk_size, specialize=specialize, check_stability=check_stability,
            estimate_error=estimate_error, checkpoint=checkpoint, resume=resume,
            keep_checkpoint=keep_checkpoint, stop_early=stop_early, client=client,
            device=device, strobe_samples=None if strobe_samples == STROBE_SAMPLES
            else strobe_samples, dtype=dtype, attractors=attractors) \
            if known_cells is None else _refuse_known_cells(scene)
    check_flag("progress", progress, allow_none=True)
    check_flag("keep_checkpoint", keep_checkpoint)
    settings, spec, chunk_size = _prepare(
        scene, grid, t_end=t_end, dt=dt, t0=t0, t_transient=t_transient, observe=observe,
        save_every=save_every, method=method, rtol=rtol, atol=atol, chunk_size=chunk_size,
        specialize=specialize, check_stability=check_stability,
        estimate_error=estimate_error, stop_early=stop_early, device=device,
        strobe_samples=strobe_samples, dtype=dtype, attractors=attractors,
        known_cells=known_cells, checkpoint=checkpoint)
    n = grid.size
    _check_memory(n, spec, settings)
    if client is not None:
        from .execution.dask import check_client

        check_client(client)
    catalogue = _catalogue(spec, attractors)
    store = _open_checkpoint(checkpoint, resume, scene=scene, grid=grid, settings=settings,
                             spec=spec, chunk_size=int(chunk_size),
                             **({} if catalogue is None else {"catalogue": catalogue}))
    # every per-trajectory array the kernel writes (out, status, [saved], [stats]); a
    # checkpoint stores and restores these, a distributed task returns its rows of them
    persisted = _allocate(spec, settings, n)
    todo = [(start, stop) for start, stop in grid.chunks(int(chunk_size))
            if store is None or not store.restore(start, stop, persisted)]
    resumed = n - sum(stop - start for start, stop in todo)
    with progress_bar(progress, n, initial=resumed) as bar:

        def finished(start, stop):
            if store is not None:
                store.store(start, stop, persisted)
            bar.update(stop - start)

        execute(RunContext(scene, grid, spec, settings,
                           (() if catalogue is None else (catalogue,))
                           + (known_arguments(known_cells) if spec.known_cells else ())),
                todo, persisted, finished, client=client)
    if store is not None and not keep_checkpoint:
        store.remove()
    if store is not None:  # one writer per checkpoint: let the next run have it
        store.release()

    out, status = persisted["out"], persisted["status"]
    failures = failure_summary(status_counts(status), n)
    if failures:
        warnings.warn(failures, RuntimeWarning, stacklevel=2)
    ds = io.to_dataset(scene=scene, grid=grid, settings=settings, spec=spec, out=out,
                       status=status, saved=persisted.get("saved"))
    ds.attrs.update(_catalogue_attrs(attractors))
    if spec.known_cells:
        ds.attrs["cells_stopped_known"] = int(np.nansum(ds["stopped_known"].values))
    if settings.adaptive:
        _add_step_statistics(ds, grid, settings, persisted["stats"])
    if estimate_error is not None:
        ds.attrs.update(_estimate(scene, grid, sample=estimate_error, t_end=t_end, dt=dt,
                                  t0=t0, t_transient=t_transient, method=method, rtol=rtol,
                                  atol=atol, dtype=dtype))
    return ds


def _catalogue(spec: KernelSpec, attractors) -> np.ndarray | None:
    """The kernel's ``catalogue`` argument for a spec with the ``attractor`` observable
    (`sweep.kernels.snippets.catalogue_argument` of the checked ``attractors``), else
    None: the catalogue is data the kernel reads, not part of its text, so every
    catalogue runs the same compiled kernel."""
    if "attractor" not in spec.observe:
        return None
    return catalogue_argument(attractor_orbits(attractors), spec.dtype)


def _refuse_known_cells(system: System):
    raise ValueError(f"known_cells is for the pendulum's forced basins; {system!r} is a "
                     "system with several coordinates; accepted: known_cells=None")


def prepare(scene: Scene, grid: Grid, **run_kwargs):
    """Validate ``run(scene, grid, **run_kwargs)`` in full, as `run` does, computing
    nothing.

    Returns
    -------
    settings : RunSettings
    spec : sweep.kernels.KernelSpec
        The kernel the run would use.
    chunk_size : int
    """
    if isinstance(scene, System):  # several coordinates: sweep.engine_systems
        from .engine_systems import prepare_system

        return prepare_system(scene, grid, **{k: v for k, v in run_kwargs.items()
                                              if k not in ("progress", "client",
                                                           "keep_checkpoint")})
    bound = inspect.signature(run).bind(scene, grid, **run_kwargs)
    bound.apply_defaults()
    wanted = inspect.signature(_prepare).parameters
    return _prepare(**{name: value for name, value in bound.arguments.items()
                       if name in wanted})


def warm_up(scene: Scene, grid: Grid, **kwargs) -> KernelSpec:
    """Compile (or load from the disk cache) the kernel that ``run(scene, grid,
    **kwargs)`` would use, integrating nothing: to time a run apart from compilation
    and from the process's other one-time costs.

    The kernel depends on the grid (its size sets the block of SIMD lanes, its axes
    whether the forcing sine is shared), so a smaller stand-in grid may compile
    another kernel; this takes the run's own grid and arguments. It also makes an
    (empty) xarray Dataset: xarray imports Dask on its first Dataset where Dask is
    installed, 0.29 s once per process (measured on a 2-core AMD EPYC), which a
    benchmark timing the first run of a process would otherwise count as integration
    (a 0.6 s run then measures 30 % slower: the "bimodal" rate of issue 29).

    Parameters
    ----------
    scene, grid, **kwargs
        As for `run` (validated the same way, before anything is compiled); a system
        with several coordinates or a swing network too.

    Returns
    -------
    sweep.kernels.KernelSpec
        What was compiled (a system's `sweep.kernels.system.SystemSpec`, a network's
        `sweep.kernels.network.NetworkSpec`).
    """
    settings, spec, _ = prepare(scene, grid, **kwargs)
    if isinstance(scene, System):  # a system's or network's arguments after saved
        from .engine_systems import kernel_arguments

        extra = kernel_arguments(scene, grid, spec, kwargs.get("attractors"))[1]
        scene = scene.switched_on(tuple(grid.axes))  # as run_system: the table's columns
    else:
        catalogue = _catalogue(spec, kwargs.get("attractors"))
        extra = (() if catalogue is None else (catalogue,)) \
            + (no_known_arguments() if spec.known_cells else ())
    _integrate(build(spec), grid.table(scene, 0, 0), settings,
               _allocate(spec, settings, 0),  # no trajectories: compiles, runs nothing
               extra)
    io.warm_up()
    return spec


def _check_memory(n: int, spec, settings) -> None:
    """Refuse outputs (and saved samples) that would need more than half the available
    memory, before anything is allocated."""
    save_every = settings.save_every
    width = n_columns(spec)
    n_saved = settings.n_steps // save_every + 1 if save_every is not None else 0
    needed = n * (width * 8 + 1 + 2 * n_saved * 8)
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


def _open_checkpoint(checkpoint, resume, **run):
    """The run's `sweep.execution.checkpoint.Checkpoint`, or None without ``checkpoint``."""
    if not isinstance(resume, (bool, np.bool_)):
        raise TypeError(f"resume must be True or False, got {resume!r}")
    if checkpoint is None:
        if resume:
            raise ValueError("resume=True needs checkpoint= (the folder of the interrupted "
                             "run's checkpoint); accepted: a checkpoint folder, or "
                             "resume=False")
        return None
    if not isinstance(checkpoint, (str, os.PathLike)) or not str(checkpoint):
        raise TypeError(f"checkpoint must be None or a folder path (str or Path), got "
                        f"{checkpoint!r}")
    from .execution import checkpoint as _checkpoint

    fp = _checkpoint.fingerprint(version=__version__, **run)
    return _checkpoint.open_checkpoint(checkpoint, fp, resume=bool(resume))


def _add_step_statistics(ds, grid, settings, stats) -> None:
    """Adaptive runs: tolerances and per-trajectory step counts (cost maps)."""
    for k, (name, meaning) in enumerate((("steps_accepted", "accepted"),
                                         ("steps_rejected", "rejected"))):
        ds[name] = (grid.dims, grid.unflatten(stats[:, k]),
                    {"units": "1", "long_name": f"number of {meaning} adaptive steps"})
    ds.attrs.pop("n_steps", None)
    ds.attrs["rtol"] = settings.rtol
    ds.attrs["atol"] = settings.atol
    ds.attrs["step_control"] = (
        "per-trajectory embedded error control: error estimate <= atol + rtol |y| (RMS "
        "over theta, omega); dt is the first trial and the largest step"
    )


def estimate_error(scene: Scene, grid: Grid, *, sample: int = 32, seed: int = 0,
                   **run_kwargs) -> dict:
    """Estimate the global error of a run from a random sample of its trajectories.

    Each sampled trajectory is integrated again with half the step (fixed-step methods;
    the difference times ``2^p / (2^p - 1)`` is Richardson's estimate of the error of
    the run's step, p the method's order) or with tolerances 100 times tighter (the
    adaptive method: the difference estimates the error of the run's tolerances).

    Parameters
    ----------
    scene, grid
        As given to `sweep.run`.
    sample : int, default 32
        Trajectories re-run (at most the grid size); chosen uniformly without
        replacement with ``numpy.random.default_rng(seed)``.
    seed : int, default 0
    **run_kwargs
        The run's keyword arguments (``t_end``, ``dt``, ``method``, ...).

    Returns
    -------
    dict
        Attributes for the dataset: ``error_estimate_max`` and ``error_estimate_rms``
        [rad] of the per-trajectory state error max(|d theta|, |d omega| / omega_n) at
        ``t_end`` (failed trajectories left out), ``error_estimate_sample`` and
        ``error_estimate_method``. For chaotic trajectories the estimate is large:
        that is the honest answer about their final state.
    """
    check_positive_int("estimate_error", sample, "None or an int >= 1 (trajectories)")
    method = _methods.resolve(run_kwargs.get("method", "rk4"))
    rng = np.random.default_rng(seed)
    picks = rng.choice(grid.size, size=min(int(sample), grid.size), replace=False)
    base = {k: v for k, v in run_kwargs.items()
            if k in ("t_end", "dt", "t0", "t_transient", "method", "rtol", "atol", "dtype")}
    base.update(observe=("final",), progress=False)
    fine = dict(base, dtype="float64")  # a float32 run's rounding is part of its error
    if method.adaptive:
        fine["rtol"] = (run_kwargs.get("rtol") or 1e-6) / 100
        fine["atol"] = (run_kwargs.get("atol") or 1e-9) / 100
        factor, how = 1.0, "re-run with rtol and atol / 100; difference of final states"
    else:
        fine["dt"] = run_kwargs["dt"] / 2
        factor = 2.0**method.order / (2.0**method.order - 1)
        how = (f"Richardson: re-run with dt/2, difference x 2^{method.order}/"
               f"(2^{method.order} - 1)")
    if base.get("dtype", "float64") != "float64":
        how += "; the re-run in float64, so the estimate includes the float32 rounding"
    errors = []
    axes = grid.axes
    for flat in np.sort(picks):
        index = np.unravel_index(flat, grid.shape)
        point = Grid(**{name: [values[i]] for (name, values), i in zip(axes.items(), index)})
        with warnings.catch_warnings():  # the run itself already reported failures
            warnings.simplefilter("ignore", RuntimeWarning)
            coarse_ds = run(scene, point, **base)
            fine_ds = run(scene, point, **fine)
        # the state error max(|d theta|, |d omega| / omega_n) [rad] at t_end
        err = factor * np.maximum(
            np.abs(coarse_ds.theta_final.values - fine_ds.theta_final.values),
            np.abs(coarse_ds.omega_final.values - fine_ds.omega_final.values)
            / scene.natural_frequency)
        errors.append(float(err.ravel()[0]))
    errors = np.array(errors)
    errors = errors[np.isfinite(errors)]
    return {
        "error_estimate_max": float(errors.max()) if errors.size else float("nan"),
        "error_estimate_rms": float(np.sqrt(np.mean(errors**2))) if errors.size
        else float("nan"),
        "error_estimate_sample": len(picks),
        "error_estimate_method": how,
    }


_estimate = estimate_error  # `run`'s argument of the same name hides the function
