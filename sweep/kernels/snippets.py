"""The observables' snippets pasted into a kernel, and the early-stop test."""

from __future__ import annotations

import re

import numpy as np

from ..observables import (
    ATTRACTOR_MATCHES,
    ATTRACTOR_TOL,
    OBSERVABLES,
    STROBE_TOL,
    STROBE_TOL_FLOAT32,
)
from .lanes import KNOWN_ARGUMENTS, indent
from .spec import KernelSpec, Status
from .terms import tension_terms

__all__ = ["CATALOGUE_ARGUMENT", "KNOWN_STATE", "KNOWN_STOPPED", "catalogue_argument",
           "failed_samples", "failed_status", "finite_test",
           "kernel_arguments", "known_final", "known_head", "known_init", "known_source", "ok_test",
           "renormalisations", "snippets", "stop_source"]

#: The known-cells stop's count of hits once the trajectory stopped on known cells
#: (`known_source`; read by `known_final`): no count of hits reaches it.
KNOWN_STOPPED = 1 << 30

#: Per-trajectory state of the known-cells stop (`known_source`), name -> dtype.
KNOWN_STATE = {"acc_kn_S": "int64", "acc_kn_next": "int64", "acc_kn_n": "int64",
               "acc_kn_L": "int64"}


def _counts(code: str, spec: KernelSpec) -> str:
    """``NSTROBE`` -> the spec's number of stroboscopic samples; ``ATTRACTOR_TOL``,
    ``ATTRACTOR_MATCHES`` -> the constants of the ``attractor`` observable
    (`sweep.observables`), whose catalogue is the kernel's argument ``catalogue``
    (`catalogue_argument`), not part of its text."""
    code = code.replace("NSTROBE", str(spec.strobe_samples))
    if "ATTRACTOR_" not in code:
        return code
    return (code.replace("ATTRACTOR_TOL", repr(ATTRACTOR_TOL))
            .replace("ATTRACTOR_MATCHES", str(ATTRACTOR_MATCHES)))


#: The kernel argument of the ``attractor`` observable's catalogue (`catalogue_argument`).
CATALOGUE_ARGUMENT = ", catalogue"


def kernel_arguments(spec: KernelSpec) -> str:
    """The arguments a single pendulum's kernel takes after ``saved`` (an adaptive
    kernel: after ``stats``), as source (``""`` or starting with ``", "``): the
    ``attractor`` observable's ``catalogue`` (`catalogue_argument`), then with
    `KernelSpec.known_cells` ``known`` and ``known_axes``."""
    return (CATALOGUE_ARGUMENT if "attractor" in spec.observe else "") + \
        (KNOWN_ARGUMENTS if spec.known_cells else "")


def catalogue_argument(orbits, dtype: str = "float64") -> np.ndarray:
    """The kernel's ``catalogue`` argument (the ``attractor`` observable's) from an
    attractor catalogue's orbits.

    Parameters
    ----------
    orbits : sequence of sequence of (float, float)
        Per attractor, its orbit's stroboscopic points ``(theta mod 2 pi [rad], omega
        [rad/s])`` in the order the orbit visits them (`sweep.engine.attractor_orbits`).
    dtype : {"float64", "float32"}
        The kernel's working precision (`KernelSpec.dtype`): a float32 kernel compares
        its state with the points rounded to float32.

    Returns
    -------
    numpy.ndarray
        C-contiguous, of ``dtype``, shape ``(n_points, 4)``: per point of the orbits, one
        after the other, its angle [rad], its velocity [rad/s], the row of its orbit's
        next point and the index of its attractor (both whole numbers).

    Raises
    ------
    ValueError
        For no orbit, an orbit without a point, or a point that is not finite.
    """
    rows = []
    for a, orbit in enumerate(orbits):
        orbit = [(float(theta), float(omega)) for theta, omega in orbit]
        if not orbit:
            rows = []
            break
        start = len(rows)
        rows += [(theta, omega, start + (k + 1) % len(orbit), a)
                 for k, (theta, omega) in enumerate(orbit)]
    table = np.array(rows, dtype=np.float64).reshape(-1, 4)
    if not len(table) or not np.isfinite(table).all():
        raise ValueError(f"the 'attractor' observable's catalogue must hold at least one "
                         f"orbit, each with at least one point, every point finite; got "
                         f"{orbits!r}")
    return np.ascontiguousarray(table, dtype=dtype)


_TOLERANCE = re.compile(r"STROBE_TOL\(([^()]*)\)")


def _tolerances(code: str, spec: KernelSpec) -> str:
    """``STROBE_TOL(x)`` -> the strobe test's bound on a difference next to ``x`` in the
    spec's working precision: ``STROBE_TOL`` in float64 (absolute), ``a + r * abs(x)``
    in float32 (`sweep.observables.STROBE_TOL_FLOAT32`)."""
    if spec.dtype == "float64":
        return _TOLERANCE.sub(repr(STROBE_TOL), code)
    absolute, relative = STROBE_TOL_FLOAT32
    return _TOLERANCE.sub(lambda m: f"({absolute!r} + {relative!r} * abs({m.group(1)}))",
                          code)


def snippets(spec: KernelSpec, part: str, time: str = "(t0 + k_state * dt)") -> str:
    """Concatenate one part (init/update/final) of every observed observable, with
    ``COL`` replaced by the observable's first column and ``TENSION_TERMS`` by the
    effects' rod-tension terms (``time``: the kernel's expression for the time of the
    state, for terms that depend on it)."""
    lines, col = [], 0
    extra = tension_terms(spec, time)
    for name in spec.observe:
        obs = OBSERVABLES[name]
        code = getattr(obs, part)
        if code:
            code = _counts(code.replace("COL", str(col)), spec).replace("TENSION_TERMS",
                                                                          extra)
            lines.append(f"# {name}\n" + code)
        col += obs.n_columns(spec)
    return "\n".join(lines)


def stop_source(spec: KernelSpec, action: str = "break") -> str:
    """Early stop (spec.stop_early): each observable's ``settled`` snippet sets its own
    flag; ``action`` runs when all flags are set, or any flag of an ``alternative``
    observable."""
    if not spec.stop_early:
        return ""
    lines, flags, alternatives, col = [], [], [], 0
    for name in spec.observe:
        obs = OBSERVABLES[name]
        if not obs.settled:
            raise ValueError(f"observable {name!r} has no settled test, so a trajectory "
                             "cannot stop early; accepted with stop_early: "
                             + ", ".join(n for n, o in OBSERVABLES.items() if o.settled))
        flag = f"settled_{len(flags) + len(alternatives)}"
        (alternatives if obs.alternative else flags).append(flag)
        lines.append(f"# {name} settled?\n"
                     + _counts(_tolerances(obs.settled, spec).replace("COL", str(col)),
                               spec).replace("SETTLED", flag))
        col += obs.n_columns(spec)
    test = " and ".join(flags)
    if alternatives:
        test = " or ".join(([f"({test})"] if flags else []) + alternatives)
    lines.append(f"if {test}:\n" + indent(action, 1))
    return "\n".join(lines)


def renormalisations(spec: KernelSpec) -> list[tuple[str, str]]:
    """``(head, snippet)`` of each observed observable with a ``renormalise`` snippet
    (see `sweep.observables.Observable`): ``head`` is the test after a step (state at
    step ``k_state``) that runs it -- every ``renormalise_every`` steps, at the start
    of the steady window and at the last step -- and sets ``keep``; the kernel puts the
    snippet under it (in a lane loop, or as it is for one thread)."""
    found = []
    for name in spec.observe:
        obs = OBSERVABLES[name]
        if obs.renormalise:
            head = (f"if k_state % {obs.renormalise_every} == 0 or k_state == n_transient "
                    "or k_state == n_steps:\n    keep = k_state > n_transient")
            found.append((head, f"# {name}\n" + obs.renormalise))
    return found


def ok_test(spec: KernelSpec) -> str:
    """The condition for a trajectory to end ``OK``: `finite_test`, and the final angle
    within `KernelSpec.angle_limit` (where the kernel takes its sine)."""
    limit = spec.angle_limit
    return finite_test(spec) + (f" and abs(th) <= {limit!r}" if limit is not None else "")


def failed_status(spec: KernelSpec) -> str:
    """The status code of a trajectory that failed `ok_test`, as an expression:
    ``ANGLE_OUT_OF_RANGE`` if it is finite, else ``NONFINITE``."""
    if spec.angle_limit is None:
        return str(int(Status.NONFINITE))
    return (f"{int(Status.ANGLE_OUT_OF_RANGE)} if {finite_test(spec)} "
            f"else {int(Status.NONFINITE)}")


def failed_samples(spec: KernelSpec) -> str:
    """Source that sets NaN in the sampled trajectory ``saved[i]`` of a failed
    trajectory where a sample is non-finite or its angle is beyond the limit (the
    samples before are kept: they were computed with accurate sines)."""
    limit = spec.angle_limit
    beyond = f"\n    if not abs(saved[i, 0, k_save]) <= {limit!r}:\n" \
             "        saved[i, 0, k_save] = math.nan\n" \
             "        saved[i, 1, k_save] = math.nan" if limit is not None else ""
    return ("for k_save in range(saved.shape[2]):\n"
            "    for q in range(2):\n"
            "        if not math.isfinite(saved[i, q, k_save]):\n"
            "            saved[i, q, k_save] = math.nan" + beyond)


def finite_test(spec: KernelSpec) -> str:
    """The condition for a trajectory's outputs to be finite: the state, and what each
    observed observable adds (its ``finite`` expression)."""
    tests = ["math.isfinite(th)", "math.isfinite(om)"]
    tests += [OBSERVABLES[name].finite for name in spec.observe if OBSERVABLES[name].finite]
    return " and ".join(tests)


def known_init() -> str:
    """The known-cells stop's state at the start (`known_source`)."""
    return ("acc_kn_S = round(TWO_PI / (W * dt))\n"
            "acc_kn_next = acc_kn_S\n"
            "acc_kn_n = 0\n"
            "acc_kn_L = -1")


def known_head(step: str, skip: str) -> str:
    """The head of a lane loop of observables in a known-cells kernel: the lane is
    skipped -- before its variables are loaded -- when ``skip`` holds (the condition
    under which the kernel skipped it without known cells: a step in the transient)
    unless its step ``step`` is its next stroboscopic time ``acc_kn_next``."""
    return (f"    if {step} != lane_acc_kn_next[j] and {skip}:\n"
            "        continue\n")


def known_source(action: str) -> str:
    """The known-cells stop (`KernelSpec.known_cells`), per trajectory, after every
    step (state ``th, om`` at step ``k_state``) whatever the transient (`known_head`):
    at each stroboscopic time ``t0 + m 2 pi / W`` (m >= 1; step ``acc_kn_next``)
    the point is snapped to the nearest cell of the map ``known`` (its angle first
    wrapped by whole turns into the map's rows); a cell holding ``4 L + h`` (label
    ``L >= 0``, hits ``h`` in 1..3: `sweep._known.known_arguments`) is a hit, and a
    run of hits of one label as long as the current cell's ``h`` runs ``action`` (once:
    only while the trajectory is not ``done``) and sets the count to `KNOWN_STOPPED`.

    ``known_axes`` holds, in cell units: ``[theta of row 0, rows per rad, omega of
    column 0, columns per rad/s, rows per 2 pi turn (> 0)]``. A point beyond the map
    (or non-finite) is no hit.
    """
    return f"""# known cells (its state read and written in its lane arrays: loaded
# only at a stroboscopic time)
if k_state == lane_acc_kn_next[j]:
    lane_acc_kn_next[j] += lane_acc_kn_S[j]
    if not done:
        acc_kn_x = (th - known_axes[0]) * known_axes[1]
        acc_kn_x -= known_axes[4] * math.floor((acc_kn_x + 0.5) / known_axes[4])
        acc_kn_y = (om - known_axes[2]) * known_axes[3]
        acc_kn_c = -1
        if acc_kn_x >= -0.5 and acc_kn_x < known.shape[0] - 0.5 and acc_kn_y >= -0.5 \\
                and acc_kn_y < known.shape[1] - 0.5:
            acc_kn_c = known[int(math.floor(acc_kn_x + 0.5)),
                             int(math.floor(acc_kn_y + 0.5))]
        if acc_kn_c < 0:
            lane_acc_kn_n[j] = 0
        else:
            if lane_acc_kn_n[j] > 0 and (acc_kn_c >> 2) == lane_acc_kn_L[j]:
                lane_acc_kn_n[j] += 1
            else:
                lane_acc_kn_n[j] = 1
                lane_acc_kn_L[j] = acc_kn_c >> 2
            if lane_acc_kn_n[j] >= (acc_kn_c & 3):
                lane_acc_kn_n[j] = {KNOWN_STOPPED}
{indent(action, 4)}"""


def known_final(spec: KernelSpec) -> str:
    """Per trajectory at the end: ``stopped_known`` (the column after the observables)
    and, for a trajectory stopped on known cells, its label as ``attractor``."""
    col, attractor = 0, None
    for name in spec.observe:
        if name == "attractor":
            attractor = col
        col += OBSERVABLES[name].n_columns(spec)
    return (f"out[i, {col}] = 1.0 if acc_kn_n == {KNOWN_STOPPED} else 0.0\n"
            f"if acc_kn_n == {KNOWN_STOPPED}:\n"
            f"    out[i, {attractor}] = acc_kn_L")
