"""The attractor catalogue of a driven system with several coordinates (``sweep.run(
system, grid, observe=("attractor",), attractors=catalogue)``): checked against the
system, turned into the kernel's arrays (`sweep.kernels.system.CATALOGUE_ARGUMENTS`)
and kept in the dataset's attributes.

A catalogue is what `sweep.maps.attractor_catalogue` makes of a system's run observing
``strobe`` (a pilot: a coarse grid of the map to come): per attractor the stroboscopic
ring of one trajectory on it, every coordinate and velocity, and its period. The kernel
takes its orbits' points as data, so one compiled kernel serves every catalogue.
"""

from __future__ import annotations

import numpy as np

from .catalogue_scene import FIELD as SCENE_FIELD
from .catalogue_scene import attributes as scene_attributes
from .strobe_phase import FIELDS, LEGACY_FIELD, OTHER_FIELD
from .strobe_phase import attributes as drive_attributes

__all__ = ["catalogue_arguments", "catalogue_attributes", "catalogue_parts", "check_catalogue",
           "check_rings", "coordinate_rows", "initial_axes"]


def catalogue_parts(attractors, accepted: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A catalogue's ``theta``, ``omega`` (float64) and ``period`` as arrays, for the
    single pendulum's checks (`sweep.engine.attractor_orbits`) and a system's; anything
    that is not such a mapping is refused, naming it and ``accepted``."""
    try:
        theta = np.asarray(attractors["theta"], dtype=np.float64)
        omega = np.asarray(attractors["omega"], dtype=np.float64)
        period = np.asarray(attractors["period"])
    except (KeyError, TypeError, ValueError, IndexError):
        raise ValueError(f"attractors must be an attractor catalogue, got {attractors!r}; "
                         f"{accepted}") from None
    return theta, omega, period


def check_rings(theta: np.ndarray, omega: np.ndarray, period: np.ndarray, accepted: str,
                ndim: int | None = None) -> None:
    """Refuse rings that cannot be a catalogue's: ``theta`` and ``omega`` of one shape
    (``ndim`` dimensions where given), samples last, at least one attractor, finite, and
    ``period`` one int per attractor with ``1 <= period <= samples / 2``."""
    if (ndim is not None and theta.ndim != ndim) or theta.shape != omega.shape \
            or period.shape != theta.shape[:1] or theta.shape[0] == 0 \
            or not np.all(np.isfinite(theta)) or not np.all(np.isfinite(omega)) \
            or not np.issubdtype(period.dtype, np.integer) or np.any(period < 1) \
            or np.any(2 * period > theta.shape[-1]):
        raise ValueError(f"attractors: rings of shape {theta.shape} and {omega.shape}, "
                         f"periods {period.tolist()!r}; {accepted}")


def coordinate_rows(names, attractors: int) -> np.ndarray:
    """A catalogue's ``coordinates``: the coordinates' ``names`` (m) as one row per
    attractor, an ndarray (``attractors``, m) of str, so that selecting attractors,
    ``{key: value[keep] for key, value in catalogue.items()}``, keeps the names of the
    kept ones (a tuple of names would be indexed by ``keep`` as if it were attractors)."""
    names = np.asarray([str(name) for name in names], dtype=str)
    return np.tile(names, (int(attractors), 1))


def _check_coordinates(given, k: int, expected: tuple[str, ...], title: str,
                       accepted: str) -> None:
    """Refuse a catalogue's ``coordinates`` that are not ``expected``: one row of names
    per attractor (k rows, `coordinate_rows`), or one row of names for all of them (a
    catalogue built by hand)."""
    rows = np.asarray(given, dtype=object)
    if rows.ndim == 1:
        rows = rows[np.newaxis]
    elif rows.ndim != 2 or rows.shape[0] != k:
        raise ValueError(f"attractors: coordinates of shape {np.shape(given)} for {k} "
                         f"attractors; accepted: the names {expected!r}, once or once per "
                         f"attractor ({k} x {len(expected)}, as "
                         "sweep.maps.attractor_catalogue gives them, every array of the "
                         "catalogue selected alike); " + accepted)
    for row in rows:
        if tuple(str(name) for name in row) != expected:
            raise ValueError(f"attractors: a catalogue of coordinates "
                             f"{tuple(str(name) for name in row)!r}, but {title} has "
                             f"{expected!r}; {accepted}")


def initial_axes(system) -> tuple[str, ...]:
    """The grid axes of ``system``'s initial state (``theta1_0``, ..., ``omega2_0``):
    the only axes a catalogue, the attractors of one system, may be used across."""
    coordinates = system.declaration.coordinates
    return tuple(f"{c.name}_0" for c in coordinates) + \
        tuple(f"{c.velocity}_0" for c in coordinates)


def check_catalogue(system, attractors, names, grid) -> dict | None:
    """The catalogue ``attractors`` as float64 rings checked against ``system``, or None
    without one; refuses what cannot be run, before any compute.

    Parameters
    ----------
    system : sweep.physics.System
    attractors : mapping or None
        ``theta``, ``omega``: (k, m, P) rings of the m coordinates and their velocities
        [their units; angles unwrapped], ``period``: (k,) ints (1 <= period <= P / 2);
        optionally ``coordinates``: the m coordinates' names, which must be the system's,
        once per attractor ((k, m) strings, `coordinate_rows`, as
        `sweep.maps.attractor_catalogue` gives them) or once for all (m), and
        ``drive_phase`` [rad] and ``drive_frequency`` [rad/s] (k values each: the
        drive phase ``W t + phi`` and frequency the rings were sampled at,
        `sweep.strobe_phase`; an older catalogue's ``strobe_phase`` instead),
        ``other_drive_phases`` (its other drives' phases, `sweep.strobe_phase`), and
        ``scene``, the pilot system's parameters of one value (`sweep.catalogue_scene`).
    names : tuple of str
        The run's observables.
    grid : Grid or Points

    Returns
    -------
    dict or None
        ``theta``, ``omega`` (k, m, P) float64, ``period`` (k,) int64, and the
        catalogue's ``drive_phase`` (or ``strobe_phase``), ``drive_frequency``,
        ``other_drive_phases`` and ``scene`` where it has them.

    Raises
    ------
    ValueError
        For a catalogue on a system without a periodic drive, with ``attractor`` not
        observed (or observed without a catalogue), of points of another dimension or
        other coordinates, not finite, with a bad period, or across a grid that varies
        anything but the initial state.
    """
    coordinates = system.declaration.coordinates
    m = len(coordinates)
    if attractors is None:
        if "attractor" in names:
            raise ValueError("observable 'attractor' matches the run against an attractor "
                             "catalogue; accepted: attractors=sweep.maps.attractor_catalogue("
                             "pilot_run) (a run of this system observing 'strobe'), or "
                             "observe without 'attractor'")
        return None
    if system.drive_frequency_parameter is None:
        raise ValueError(f"attractors: a catalogue holds the periodic orbits of a driven "
                         f"system, sampled once per drive period, and this {system.title} "
                         "has no periodic drive; accepted: attractors=None, or a driven "
                         "system (sweep.DoublePendulum(..., pivot_amplitude=a, "
                         "pivot_frequency=nu), a sweep.Forcing(on=...), a "
                         "sweep.DeclaredSystem(..., drive_frequency_axis=...))")
    if "attractor" not in names:
        raise ValueError("attractors= is given but observe has no 'attractor'; accepted: "
                         "observe=('attractor',) (or with 'strobe'), or attractors=None")
    accepted = (f"accepted: a catalogue from sweep.maps.attractor_catalogue(run) of a run "
                f"of this system, a mapping with 'theta', 'omega' (k x {m} x P rings of its "
                f"{m} coordinates and of their velocities, finite) and 'period' (k ints, "
                "1 <= period <= P / 2: a ring shows its orbit twice)")
    theta, omega, period = catalogue_parts(attractors, accepted)
    given = attractors.get("coordinates") if hasattr(attractors, "get") else None
    expected = tuple(c.name for c in coordinates)
    if theta.ndim != 3 or theta.shape[1] != m:
        raise ValueError(f"attractors: points of {theta.shape[1] if theta.ndim == 3 else 1} "
                         f"coordinates (rings of shape {theta.shape}), but {system.title} "
                         f"has {m} ({', '.join(expected)}); {accepted}")
    check_rings(theta, omega, period, accepted)
    if given is not None:
        _check_coordinates(given, theta.shape[0], expected, system.title, accepted)
    varied = [name for name in grid.axes
              if name not in initial_axes(system) and grid.varies(name)]
    if varied:
        raise ValueError(f"an attractor catalogue holds the attractors of one system, but "
                         f"the grid varies {', '.join(varied)}; accepted: a grid that varies "
                         f"only the initial state ({', '.join(initial_axes(system))})")
    return {"theta": theta, "omega": omega, "period": period.astype(np.int64),
            **{name: attractors[name] for name in (*FIELDS, LEGACY_FIELD, OTHER_FIELD,
                                                   SCENE_FIELD)
               if name in attractors}}


def catalogue_arguments(system, catalogue: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernel's ``cat_points`` (N, 2 m), ``cat_next`` (N,) and ``cat_owner`` (N,)
    (`sweep.kernels.system`): per attractor, the last ``period`` points of its ring,
    angles wrapped to [0, 2 pi), each followed by the next point of its orbit."""
    angular = np.array([c.angular for c in system.declaration.coordinates])
    points, following, owner = [], [], []
    for a, p in enumerate(int(q) for q in catalogue["period"]):
        start = len(points)
        for k in range(catalogue["theta"].shape[2] - p, catalogue["theta"].shape[2]):
            position = catalogue["theta"][a, :, k]
            position = np.where(angular, np.mod(position, 2 * np.pi), position)
            points.append(np.concatenate([position, catalogue["omega"][a, :, k]]))
            following.append(start + (len(points) - start) % p)
            owner.append(a)
    return (np.ascontiguousarray(points, dtype=np.float64),
            np.asarray(following, dtype=np.int64), np.asarray(owner, dtype=np.int64))


def catalogue_attributes(catalogue: dict | None) -> dict:
    """The catalogue as dataset attributes (flat, netCDF-friendly): ``attractors_theta``
    and ``attractors_omega`` (k m P values, C order), ``attractors_period``,
    ``attractors_samples`` (P) and ``attractors_coordinates`` (m), and its drive
    (``attractors_drive_phase``, ``attractors_drive_frequency``,
    ``attractors_other_drive_phases``) and scene
    (``attractors_scene``) where it has them."""
    if catalogue is None:
        return {}
    k, m, samples = catalogue["theta"].shape
    return {"attractors_theta": catalogue["theta"].ravel(),
            "attractors_omega": catalogue["omega"].ravel(),
            "attractors_period": catalogue["period"],
            "attractors_samples": int(samples), "attractors_coordinates": int(m),
            **drive_attributes(catalogue, k), **scene_attributes(catalogue)}
