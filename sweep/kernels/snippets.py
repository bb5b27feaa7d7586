"""The observables' snippets pasted into a kernel, and the early-stop test."""

from __future__ import annotations

import re

from ..observables import (
    ATTRACTOR_MATCHES,
    ATTRACTOR_TOL,
    OBSERVABLES,
    STROBE_TOL,
    STROBE_TOL_FLOAT32,
)
from .lanes import indent
from .spec import KernelSpec, Status
from .terms import tension_terms

__all__ = ["failed_samples", "failed_status", "finite_test", "ok_test", "renormalisations",
           "snippets", "stop_source"]


def _counts(code: str, spec: KernelSpec) -> str:
    """``NSTROBE`` -> the spec's number of stroboscopic samples; the attractor
    catalogue's names (``CAT_TH``, ``CAT_OM``, ``CAT_NEXT``, ``CAT_A``, ``N_POINTS``,
    ``ATTRACTOR_TOL``, ``ATTRACTOR_MATCHES``) -> its points as tuples and the
    constants (`sweep.observables`, the ``attractor`` observable)."""
    code = code.replace("NSTROBE", str(spec.strobe_samples))
    if "CAT_" not in code and "ATTRACTOR_" not in code:
        return code
    th, om, following, owner = [], [], [], []
    for a, orbit in enumerate(spec.attractors):
        start = len(th)
        for k, (theta, omega) in enumerate(orbit):
            th.append(repr(float(theta)))
            om.append(repr(float(omega)))
            following.append(str(start + (k + 1) % len(orbit)))
            owner.append(str(a))
    for name, values in (("CAT_TH", th), ("CAT_OM", om), ("CAT_NEXT", following),
                         ("CAT_A", owner)):
        code = re.sub(rf"\b{name}\b", "(" + ", ".join(values) + ",)", code)
    return (code.replace("N_POINTS", str(len(th)))
            .replace("ATTRACTOR_TOL", repr(ATTRACTOR_TOL))
            .replace("ATTRACTOR_MATCHES", str(ATTRACTOR_MATCHES)))


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
