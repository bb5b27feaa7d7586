"""`sweep.run` for a system with several coordinates (`sweep.physics.System`): validate
-> parameter table -> kernel (`sweep.kernels.system`) -> chunks -> dataset.

The same path as the single pendulum's below the kernel (chunks, threads, progress,
Dask through `sweep.execution`); `sweep.engine.run` hands a system here.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import xarray as xr

from . import _config
from .catalogue_drives import system_drives
from .catalogue_scene import ATTRIBUTE as SCENE_ATTRIBUTE
from .catalogue_scene import check_scene, grid_value, scene_values
from .execution import RunContext, execute
from .execution.local import allocate
from .execution.progress import progress_bar
from .grid import ParameterRows
from .io import device_attributes, origin_attributes, run_attributes, status_variable
from .kernels import failure_summary, status_counts
from .kernels.network import NETWORK_OBSERVABLES, NetworkSpec, network_arguments
from .kernels.system import STOPPING, SystemSpec
from .observables import STROBE_SAMPLES, variable_attributes
from .physics.network import NETWORK_PARAMETERS, SwingNetwork
from .physics.system import System, system_parameters
from .settings import CUDA_CHUNK, _block, _check_device, default_chunk_size, validate_settings
from .strobe_phase import check_phase, other_drives_attribute, phase_axis
from .system_attractors import catalogue_arguments, catalogue_attributes, check_catalogue
from .system_observables import (
    SYSTEM_OBSERVABLES,
    comments,
    resolve_system_observe,
    variables,
)

__all__ = ["kernel_arguments", "prepare_system", "run_system", "system_dataset",
           "to_network_dataset", "to_system_dataset"]

#: `sweep.run`'s arguments that a system run does not take yet, with the value that
#: means "not used"; any other value is refused before any compute.
_NOT_YET = {"rtol": None, "atol": None, "specialize": True, "estimate_error": None,
            "checkpoint": None, "resume": False}


def _check_not_yet(system: System, given: dict) -> None:
    for name, unused in _NOT_YET.items():
        value = given.get(name, unused)
        if value is not unused and value != unused:
            raise ValueError(f"{name}={value!r} is not available for a system "
                             f"({type(system).__name__}) yet; accepted: {name}={unused!r} "
                             "(the single pendulum's sweep.Scene takes it)")


def _network_observe(observe) -> tuple[str, ...]:
    if isinstance(observe, str):
        observe = (observe,)
    for name in observe:
        if name not in NETWORK_OBSERVABLES:
            raise ValueError(f"unknown observable {name!r} for a SwingNetwork; accepted: "
                             f"{', '.join(map(repr, NETWORK_OBSERVABLES))}")
    return tuple(name for name in NETWORK_OBSERVABLES if name in observe)


def _check_network_grid(network: SwingNetwork, grid: ParameterRows) -> None:
    """Perturbed nodes must be node indices (or -1); the coupling is not an axis (the
    synchronous state depends on it)."""
    axes = grid.axes
    if "coupling" in axes and grid.varies("coupling"):
        raise ValueError("grid axis 'coupling' is not available for a SwingNetwork yet (its "
                         "synchronous state, the starts' origin, depends on it); accepted: "
                         "SwingNetwork(..., coupling=K), one network per coupling")
    nodes = axes.get("perturbed_node")
    if nodes is not None:
        bad = (nodes != np.round(nodes)) | (nodes < -1) | (nodes >= network.n_nodes)
        if bad.any():
            raise ValueError(f"axis 'perturbed_node' has value {float(nodes[bad][0])!r}; "
                             f"accepted: node indices 0 to {network.n_nodes - 1}, or -1 (none)")


def _prepare_network(network, grid, settings, observe, save_every, stop_early,
                     device="cpu"):
    if stop_early:
        raise ValueError("stop_early is not available for a SwingNetwork; accepted: "
                         "stop_early=False")
    _check_network_grid(network, grid)
    names = _network_observe(("synchrony",) if observe is None else observe)
    if not names and save_every is None:
        raise ValueError("observe is empty and save_every is None -- nothing would be "
                         "computed; accepted: final, synchrony, or a save_every")
    coupling = grid.axes.get("coupling", [network.coupling])[0]
    return NetworkSpec(edges=tuple(tuple(e) for e in network.edges.tolist()),
                       power=tuple(network.power.tolist()),
                       synchronous=tuple(network.synchronous_state(coupling).tolist()),
                       observe=names, save=save_every is not None, method=settings.method,
                       block=_block(grid.size, False), device=device)


def system_values(system: System, grid: ParameterRows, drive_axis: str) -> dict:
    """`sweep.catalogue_scene.scene_values` of a system's run (``system`` switched on by
    the grid's axes): its parameters of one value, without its initial state and its
    drive's frequency ``drive_axis`` and phase constant (`sweep.strobe_phase.phase_axis`)."""
    from .system_attractors import initial_axes

    return scene_values(system.parameters(), grid, initial_axes(system),
                        (drive_axis, phase_axis(drive_axis)))


def _check_strobe(system: System, grid: ParameterRows, names, settings):
    """With ``strobe`` (or ``attractor``) observed: the system's drive-frequency
    parameter (it must have one), every frequency on the grid > 0 with a period of whole
    steps; else None."""
    from ._timesteps import check_sampling_period

    if "strobe" not in names and "attractor" not in names:
        return None
    drive = system.drive_frequency_parameter
    sampled = "strobe" if "strobe" in names else "attractor"
    if drive is None:
        raise ValueError(f"observable {sampled!r} samples once per drive period, and "
                         f"this {system.title} has no periodic drive; accepted: a driven "
                         "system, e.g. sweep.DoublePendulum(..., pivot_amplitude=a, "
                         "pivot_frequency=nu), or sweep.DeclaredSystem(..., "
                         "drive_frequency_axis=<its frequency parameter>)")
    frequencies = grid.axes.get(drive.axis, np.array([system.parameters()[drive.axis]]))
    check_sampling_period(sampled, frequencies, settings.dt, axis=drive.axis,
                          period="drive")
    return drive


def prepare_system(system: System, grid: ParameterRows, *, t_end, dt, t0=0.0,
                   t_transient=0.0, observe=None, save_every=None,
                   method="rk4", chunk_size=None, stop_early=False, strobe_samples=None,
                   check_stability=True, device="cpu", dtype="float64", attractors=None,
                   **not_yet):
    """Validate a system run (before any compute); return its settings, kernel spec and
    chunk size (`run_system` takes the checked catalogue from
    `sweep.system_attractors.check_catalogue`).

    Raises
    ------
    ValueError, TypeError
        Naming the argument, its value and what is accepted.
    """
    from ._validate import check_flag, check_positive_int
    from .settings import check_strobe_samples

    if not isinstance(grid, ParameterRows):
        raise TypeError(f"grid must be a sweep.Grid or sweep.Points, got {grid!r}")
    _check_not_yet(system, not_yet)
    grid.check_against(system)
    system = system.switched_on(tuple(grid.axes))
    settings = validate_settings(t_end=t_end, dt=dt, t0=t0, t_transient=t_transient,
                                 save_every=save_every, method=method)
    integrator = settings.integrator
    if integrator.adaptive or integrator.kind != "explicit":
        from .methods import METHODS

        accepted = ", ".join(repr(n) for n, m in METHODS.items()
                             if not m.adaptive and m.kind == "explicit")
        raise ValueError(f"a system integrates with a fixed-step explicit Runge-Kutta "
                         f"method; got method {integrator.name!r}; accepted: {accepted}")
    check_flag("stop_early", stop_early)
    _check_device(device, settings.integrator)
    from .kernels.spec import check_dtype

    check_dtype(dtype, integrator)
    if chunk_size is None:
        chunk_size = default_chunk_size(settings, bool(stop_early)) \
            if device != "cuda" else CUDA_CHUNK
    check_positive_int("chunk_size", chunk_size)
    if isinstance(system, SwingNetwork):
        if dtype != "float64":
            raise ValueError(f"dtype={dtype!r} is not available for a SwingNetwork yet; "
                             "accepted: dtype='float64'")
        if strobe_samples is not None:
            raise ValueError(f"strobe_samples={strobe_samples!r} is not available for a "
                             "SwingNetwork; accepted: strobe_samples=None")
        if attractors is not None:
            raise ValueError("attractors= is not available for a SwingNetwork; accepted: "
                             "attractors=None")
        return settings, _prepare_network(system, grid, settings, observe, save_every,
                                          stop_early, device), int(chunk_size)
    names = resolve_system_observe(("final", "winding") if observe is None else observe)
    if not names and save_every is None:
        raise ValueError("observe is empty and save_every is None -- nothing would be "
                         "computed; accepted: at least one of final, winding, energy, "
                         "flip, lyapunov, strobe, or a save_every")
    strobe_samples = STROBE_SAMPLES if strobe_samples is None else strobe_samples
    check_strobe_samples(strobe_samples, names)
    catalogue = check_catalogue(system, attractors, names, grid)
    drive = _check_strobe(system, grid, names, settings)
    if catalogue is not None:  # rings of another drive phase would never match
        values = system.parameters()
        name = phase_axis(drive.axis)  # a Forcing(on=...)'s phase; a pivot has none
        frequency, phase = (grid_value(grid, axis, values.get(axis, 0.0))
                            for axis in (drive.axis, name or drive.axis))
        check_phase(attractors, len(catalogue["period"]), frequency, settings,
                    drive.axis, phase=phase if name else 0.0,
                    others=system_drives(system, grid, drive.axis))
        check_scene(attractors, system_values(system, grid, drive.axis))
    check_flag("check_stability", check_stability)
    if stop_early and (names not in STOPPING or save_every is not None):
        raise ValueError(
            "stop_early stops a system's trajectory at its first flip (observe=('flip',)) "
            "or once it settled on a catalogued attractor (observe=('attractor',) or "
            "('strobe', 'attractor'), with attractors=), and saves nothing; got "
            f"observe={names!r}, save_every={save_every!r}; accepted: one of those and "
            "save_every=None, or stop_early=False")
    if device == "cuda" and "attractor" in names:
        raise ValueError("observable 'attractor' is not available for a system on the GPU "
                         "yet (the systems' CUDA kernel takes no catalogue); accepted: "
                         "device='cpu'")
    damping = "damping" in grid.effects(system)
    spec = SystemSpec(system=system.declaration_with_effects,
                      derived=system.derived(jacobian="lyapunov" in names), observe=names,
                      damping=damping, save=save_every is not None, method=settings.method,
                      stop_early=bool(stop_early), block=_block(grid.size, bool(stop_early)),
                      flip_energy=system.flip_energy, device=device, dtype=dtype,
                      refill=bool(stop_early) and _config.REFILL,
                      strobe_samples=int(strobe_samples),
                      strobe_frequency=None if drive is None else drive.symbol)
    if dtype != "float64":
        _check_single(system, spec)
    if "energy" in names and not spec.derived.energy_lines:
        raise ValueError(f"observable 'energy' needs the energy of {type(system).__name__}, "
                         "which its declaration does not give; accepted: observe without "
                         "'energy'")
    return settings, spec, int(chunk_size)


def _check_single(system: System, spec: SystemSpec) -> None:
    """Refuse float32 where a system's kernel does not have it yet: on the GPU.
    (Dynamics that read the time run in float32 with their drives' phases in float64,
    `sweep.kernels.phases`; ``lyapunov`` with its tangent vector in float64.)"""
    where = type(system).__name__
    if spec.device != "cpu":
        raise ValueError(f"dtype='float32' for a system ({where}) runs on the CPU only yet; "
                         f"got device={spec.device!r}; accepted: device='cpu', or "
                         "dtype='float64'")


def run_system(system: System, grid: ParameterRows, *, progress=None, client=None,
               **kwargs) -> xr.Dataset:
    """`sweep.run` for a `sweep.physics.System` (see `sweep.run` for the arguments)."""
    from ._validate import check_flag

    check_flag("progress", progress, allow_none=True)
    keep = kwargs.pop("keep_checkpoint", False)
    check_flag("keep_checkpoint", keep)
    settings, spec, chunk_size = prepare_system(system, grid, **kwargs)
    catalogue, extra = kernel_arguments(system, grid, spec, kwargs.get("attractors"))
    system = system.switched_on(tuple(grid.axes))  # as prepare_system: the table's columns
    if client is not None:
        from .execution.dask import check_client

        check_client(client)
    n = grid.size
    arrays = allocate(spec, settings, n)
    todo = list(grid.chunks(chunk_size))
    with progress_bar(progress, n) as bar:
        execute(RunContext(system, grid, spec, settings, extra), todo, arrays,
                lambda start, stop: bar.update(stop - start), client=client)
    failures = failure_summary(status_counts(arrays["status"]), n)
    if failures:
        warnings.warn(failures, RuntimeWarning, stacklevel=3)
    ds = system_dataset(system, grid, settings, spec, arrays)
    ds.attrs.update(catalogue_attributes(catalogue))
    return ds


def kernel_arguments(system: System, grid: ParameterRows, spec,
                     attractors) -> tuple[dict | None, tuple]:
    """The checked catalogue (`sweep.system_attractors.check_catalogue`, None without
    one) and the kernel's arguments after ``saved`` of a checked run (``spec`` from
    `prepare_system`): the catalogue's arrays, a network's arrays, or ``()``; for
    `run_system` and `sweep.engine.warm_up`."""
    if isinstance(spec, NetworkSpec):
        return None, network_arguments(spec)
    catalogue = check_catalogue(system, attractors, spec.observe, grid)
    return catalogue, (() if catalogue is None else catalogue_arguments(system, catalogue))


def system_dataset(system, grid, settings, spec, arrays: dict) -> xr.Dataset:
    """The dataset of a system run from the arrays its kernel wrote
    (`sweep.execution.local.allocate`)."""
    build = to_network_dataset if isinstance(spec, NetworkSpec) else to_system_dataset
    return build(system=system, grid=grid, settings=settings, spec=spec, out=arrays["out"],
                 status=arrays["status"], saved=arrays.get("saved"))


def to_system_dataset(*, system, grid, settings, spec: SystemSpec, out, status,
                      saved=None) -> xr.Dataset:
    """Wrap a system run's flat outputs into a labelled Dataset.

    Parameters
    ----------
    system : sweep.physics.System
    grid : Grid or Points
    settings : sweep.engine.RunSettings
    spec : SystemSpec
    out : ndarray, shape (grid.size, n_outputs(spec)), float64
    status : ndarray, shape (grid.size,), int8
    saved : ndarray, shape (grid.size, 2 m, n_saved), float64, optional
        The m coordinates then the m velocities at the saved steps.
    """
    dims = grid.dims
    info = {p.axis: p for p in system_parameters(spec.system, True)}
    coords = {name: xr.Variable(dim, values, {"units": info[name].units,
                                              "long_name": info[name].long_name})
              for name, dim, values in grid.coordinates()}
    data_vars, col = {}, 0
    coordinates = spec.system.coordinates
    for name in spec.observe:
        width = spec.strobe_samples if SYSTEM_OBSERVABLES[name].sampled else 1
        notes = comments(name, coordinates)
        for variable, units, long_name in variables(name, coordinates, system.energy_units):
            attrs = variable_attributes(variable, units, long_name, notes.get(variable, ""))
            if width == 1:
                data_vars[variable] = xr.Variable(dims, grid.unflatten(out[:, col]), attrs)
            else:  # as the single pendulum's strobe_theta (sweep.io)
                data_vars[variable] = xr.Variable(dims + ("strobe",),
                                                  grid.unflatten(out[:, col:col + width]),
                                                  attrs)
                coords["strobe"] = xr.Variable("strobe", np.arange(1 - width, 1), {
                    "units": "1", "long_name": "drive periods before the last sample"})
            col += width
    data_vars["status"] = status_variable(grid, status)
    if saved is not None:
        coords["time"] = _time(settings, saved.shape[2])
        rows = [(c.name, c.units, f"{c.long_name or c.name}"
                 + (", unwrapped" if c.angular else "")) for c in coordinates] + \
            [(c.velocity, c.velocity_units, c.velocity) for c in coordinates]
        for k, (name, units, long_name) in enumerate(rows):
            data_vars[name] = xr.Variable(dims + ("time",), grid.unflatten(saved[:, k, :]),
                                          {"units": units, "long_name": long_name})
    fixed = {k: v for k, v in system.parameters().items()
             if k not in grid.axes and (k != "damping" or spec.damping)}
    attrs = _attributes(system, grid, settings, spec, fixed)
    attrs.update(system_name=spec.system.name,
                 coordinates_names=" ".join(c.name for c in coordinates),
                 effects=_effects_attribute(system, spec))
    if spec.stop_early:
        attrs["stop_early"] = "at the first flip" if "flip" in spec.observe else \
            "once settled on a catalogued attractor"
    if "strobe" in spec.observe:  # what `sweep.maps.basins` reads of the samples
        attrs[SCENE_ATTRIBUTE] = json.dumps(system_values(
            system, grid, system.drive_frequency_parameter.axis), sort_keys=True)
        # the other drives whose phases a catalogue of it records
        attrs.update(other_drives_attribute(
            system_drives(system, grid, system.drive_frequency_parameter.axis)))
        attrs.update(strobe_samples=spec.strobe_samples,
                     strobe_frequency=system.drive_frequency_parameter.axis,
                     strobe_positions=" ".join(c.name for c in coordinates),
                     strobe_velocities=" ".join(c.velocity for c in coordinates),
                     strobe_angular=" ".join(c.name for c in coordinates if c.angular))
    return xr.Dataset(data_vars, coords, attrs)


def _effects_attribute(system, spec: SystemSpec) -> str:
    """The dataset's ``effects``: ``damping`` (mass-proportional) and ``<effect>_<coordinate>``
    of the effects on one coordinate (``damping_theta1 torque_theta2``), or ``none``."""
    names = ["damping"] if spec.damping else []
    names += [f"{e.declaration.name}_{e.coordinate}" for e in system.effects
              if e.coordinate is not None]
    return " ".join(names) or "none"


def _time(settings, n_saved: int) -> xr.Variable:
    return xr.Variable("time", settings.t0 + np.arange(n_saved) * settings.save_every
                       * settings.dt, {"units": "s", "long_name": "time (t0 + n dt at saved "
                                                                 "steps n)"})


def _attributes(system, grid, settings, spec, fixed: dict) -> dict:
    """The attributes every system dataset has: provenance and how to reproduce it."""
    attrs = {
        **origin_attributes(f"{system.title} parameter sweep"),
        **{name: float(value) for name, value in fixed.items()},
        "system": json.dumps(system.to_dict(), sort_keys=True),
        **grid.provenance(),
        **run_attributes(settings, spec),
        **device_attributes(spec),
    }
    if getattr(spec, "dtype", "float64") != "float64":  # as the single pendulum's
        attrs["dtype"] = spec.dtype
    return attrs


def to_network_dataset(*, system: SwingNetwork, grid, settings, spec: NetworkSpec, out,
                       status, saved=None) -> xr.Dataset:
    """Wrap a swing network run's flat outputs into a labelled Dataset: per-node
    variables have a ``node`` dimension (last before ``time``).

    Parameters
    ----------
    out : ndarray, shape (grid.size, network_outputs(spec)), float64
    saved : ndarray, shape (grid.size, 2 N, n_saved), float64, optional
    """
    dims, n = grid.dims, spec.n_nodes
    info = {p.axis: p for p in NETWORK_PARAMETERS}
    coords = {name: xr.Variable(dim, values, {"units": info[name].units,
                                              "long_name": info[name].long_name})
              for name, dim, values in grid.coordinates()}
    coords["node"] = xr.Variable("node", np.arange(n), {"long_name": "node index"})
    data_vars, col = {}, 0
    for name in spec.observe:
        if name == "final":
            for variable, units, meaning, comment in (
                    ("theta_final", "rad", "node phase at t_end",
                     "unwrapped (not reduced modulo 2 pi)"),
                    ("omega_final", "rad s-1", "node frequency deviation at t_end", "")):
                data_vars[variable] = xr.Variable(
                    dims + ("node",), grid.unflatten(out[:, col:col + n]),
                    variable_attributes(variable, units, meaning, comment))
                col += n
        else:
            data_vars["frequency_spread"] = xr.Variable(
                dims, grid.unflatten(out[:, col]),
                variable_attributes("frequency_spread", "rad s-1", "frequency spread at t_end",
                                    "max |omega_i| over the nodes at t_end: 0 in the "
                                    "synchronous state"))
            data_vars["order_parameter"] = xr.Variable(
                dims, grid.unflatten(out[:, col + 1]),
                variable_attributes("order_parameter", "1", "Kuramoto order parameter at t_end",
                                    "r = |mean over the nodes of exp(i theta_i)| at t_end: "
                                    "1 where every phase is the same"))
            col += 2
    data_vars["status"] = status_variable(grid, status)
    if saved is not None:
        coords["time"] = _time(settings, saved.shape[2])
        data_vars["theta"] = xr.Variable(dims + ("node", "time"),
                                         grid.unflatten(saved[:, :n, :]),
                                         {"units": "rad", "long_name": "phase, unwrapped"})
        data_vars["omega"] = xr.Variable(dims + ("node", "time"),
                                         grid.unflatten(saved[:, n:, :]),
                                         {"units": "rad s-1", "long_name": "frequency deviation"})
    fixed = {k: v for k, v in system.parameters().items()
             if k not in grid.axes and k in ("damping", "coupling")}
    attrs = _attributes(system, grid, settings, spec, fixed)
    attrs.update(system_name="swing_network", n_nodes=n, n_edges=len(spec.edges))
    return xr.Dataset(data_vars, coords, attrs)
