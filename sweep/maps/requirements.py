"""What each map of ``sweep.maps`` needs of a run, known before the run: the command
line refuses a label its run cannot give in one line, before anything is computed, and
names the labels that would work.

For developers
--------------
`NEEDS` holds, per map name, what the run must observe (any one of the names) and
whether the map is for unforced scenes only. ``basins`` of an unforced scene and
``well`` read the wells, which ``sweep boundary`` adds to what is observed
(``capture``), so they need nothing here.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NEEDS", "STOP_EARLY_OBSERVABLES", "file_labels", "label_refusal",
           "working_labels"]

#: Map name -> (observables, any one of which the run needs (empty: none), for forced
#: scenes only: the same; unforced scenes only).
NEEDS = {
    "basins": ((), ("strobe",), False),
    "well": ((), (), True),
    "motion": (("omega_mean", "winding", "final"), ("omega_mean", "winding", "final"),
               False),
    "period": (("strobe",), ("strobe",), False),
    "inverted": (("top_distance",), ("top_distance",), False),
}


#: What a run with ``stop_early`` may observe (the others need the whole run).
STOP_EARLY_OBSERVABLES = ("strobe", "attractor", "capture")


def _missing(name: str, observe, forced: bool,
             stop_early: bool = False) -> tuple[str, ...] | None:
    """The observables ``name`` needs and ``observe`` lacks (any one of them), () for
    a scene it is not for, None when the run gives it."""
    unforced_needs, forced_needs, unforced_only = NEEDS[name]
    if forced and unforced_only:
        return ()
    needs = forced_needs if forced else unforced_needs
    if needs and (not set(needs) & set(observe)
                  or (stop_early and not set(needs) & set(STOP_EARLY_OBSERVABLES))):
        return needs
    return None


def working_labels(observe, forced: bool, stop_early: bool = False) -> list[str]:
    """The map names a run observing ``observe`` (of a forced scene or not, with
    ``stop_early`` or not) gives."""
    return [name for name in NEEDS if _missing(name, observe, forced, stop_early) is None]


def label_refusal(name: str, observe, forced: bool, where: str,
                  stop_early: bool = False) -> str | None:
    """Why the map ``name`` cannot label a run observing ``observe`` of a forced (or
    unforced) scene, as one line naming what would work; None when it can.

    Parameters
    ----------
    name : str
        A key of `NEEDS`.
    observe : iterable of str
        The run's observables (``[run] observe``).
    forced : bool
        Whether the scene has a forcing.
    where : str
        The run's name in the message (a run file's path).
    stop_early : bool, default False
        Whether the run stops early (then it observes only `STOP_EARLY_OBSERVABLES`).
    """
    missing = _missing(name, observe, forced, stop_early)
    if missing is None:
        return None
    others = [f"--label {n}" for n in working_labels(observe, forced, stop_early)
              if n != name]
    alternative = f"; or {' or '.join(others)}, which this run gives" if others else ""
    if missing == ():
        works = " or ".join(others) + " (this run gives it)" if others else \
            '--label basins with observe = ["strobe"] in [run]'
        return (f"--label {name} is for unforced scenes, and the scene of {where} has a "
                f"forcing; accepted: {works}")
    wanted = " or ".join(f'"{n}"' for n in missing)
    scene = " of a forced scene" if name == "basins" else ""
    if stop_early and not set(missing) & set(STOP_EARLY_OBSERVABLES):
        return (f"--label {name}{scene} needs observe = [{wanted}], which needs the whole "
                f"run, and {where} has stop_early = true; accepted: that observable "
                f"without stop_early{alternative}")
    return (f"--label {name}{scene} needs observe = [{wanted}] in [run], which {where} "
            f"does not observe; accepted: that observable{alternative}")


def file_labels(ds, tried: str | None = None) -> list[str]:
    """What labels a run's dataset (a file): the maps of `sweep.maps` that accept it
    (`sweep.toml_spec.REFINE_MAPS`, in that order), then its dimensionless variables
    (units ``1`` or none) of whole numbers (NaN: no label) on the trajectories'
    dimensions, ``status`` aside; ``tried`` left out. What ``sweep fractions`` names
    when a label fails.

    Parameters
    ----------
    ds : xarray.Dataset
        A run's dataset (`sweep.load`).
    tried : str, optional
        The label that failed, not named again.

    Returns
    -------
    list of str
    """
    from .. import maps
    from ..toml_spec import REFINE_MAPS

    working = []
    for name in REFINE_MAPS:
        if name == tried:
            continue
        try:
            getattr(maps, name)(ds)
        except (ValueError, KeyError):
            continue
        working.append(name)
    dims = set(ds["status"].dims) if "status" in ds else None
    for name, variable in ds.data_vars.items():
        values = np.asarray(variable.values)
        if name in (tried, "status") or (dims is not None and set(variable.dims) != dims) \
                or values.dtype.kind not in "biuf" or values.size == 0 \
                or variable.attrs.get("units", "1") != "1":  # a quantity (s, rad), no label
            continue
        finite = values[np.isfinite(values)] if values.dtype.kind == "f" else values
        if finite.size and np.array_equal(finite, np.round(finite)) \
                and str(name) not in working:
            working.append(str(name))
    return working
