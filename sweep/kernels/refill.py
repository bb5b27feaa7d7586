"""The early-stop kernel with lane refill: a lane whose trajectory has settled (or reached
``t_end``) writes its outputs and takes the next waiting trajectory, so no SIMD lane
idles while its block's slowest trajectory finishes.

There is one group per thread (group ``b`` of ``G``, `sweep.kernels.threads`); it takes
the trajectories ``b, b + G, b + 2 G, ...`` in turn, so every group draws on the whole
chunk and the threads finish together whatever the order of slow and fast starts. A
group advances ``BLOCK`` lanes at a time; each lane keeps its own step index
``lane_ks[j]`` (time ``t0 + k dt``), so the drives' sines are per lane (or read from a
table over the steps when every trajectory has the same drive). A trajectory's
arithmetic is the same operations whatever lane it runs in and whenever it starts, so
the results are bit-identical to the kernel without refill (``tests/test_refill.py``)
and independent of the number of threads and of ``BLOCK``. When the group's queue is
empty the lanes that finish go idle (they keep stepping a copy of a valid trajectory,
whose results are never written) until the last one is done.
"""

from __future__ import annotations

import re

from ..observables import OBSERVABLES
from .fixed import NL, _drives, _finish, _first_lines, _lane_dtypes, _load, _parameters
from .lanes import (
    IDENTIFIER,
    allocate,
    blocks_head,
    indent,
    lane_loop,
    lane_snippet,
    skip_unless,
)
from .snippets import (
    KNOWN_STATE,
    kernel_arguments,
    known_head,
    known_source,
    snippets,
    stop_source,
)
from .spec import KernelSpec, n_columns
from .steppers import STEPPERS

__all__ = ["groups_head", "refill_kernel"]

_STEP = re.compile(r"\bstep\b")  # the fixed kernel's block step, in a drive's expression


def _sine_table(spec: KernelSpec, drives, shared: list[str]) -> tuple[str, list[str]]:
    """The code that tabulates the drives' sines over the steps (before the groups;
    "" without shared drives) and the lane lines that read them at step ``ks``."""
    if not shared:
        return "", [_STEP.sub("ks", line) for line in drives.step]
    names = [line.split("=")[0].strip() for line in drives.step]
    # an idle lane's step never passes n_steps - 1 while another lane is live; the
    # bound keeps every read inside the table anyway
    lines = [f"{name} = tab_{name}[min(ks, n_steps - 1)]" for name in names]
    table = NL.join(
        [f"tab_{name} = np.empty(max(n_steps, 1), dtype=np.{spec.dtype})"
         for name in names] +
        ["for step in range(n_steps if n > 0 else 0):"] +
        [f"    {_load(spec, p, '0')}" for p in shared] +
        [f"    {line}" for line in drives.step] +
        [f"    tab_{name}[step] = {name}" for name in names])
    return table, lines


#: A refill kernel's Python ``kernel`` (`groups_head`): one group of lanes per thread.
_GROUPS = '''"""One group of lanes per thread, but no more groups than n // BLOCK (one
group when n < BLOCK), each group on a thread of its own
(`sweep.kernels.threads`)."""
if n_steps < 1:  # every lane steps before its first stop test
    raise ValueError(f"n_steps must be >= 1 for a refill kernel, got {{n_steps!r}}")
n = params.shape[0]
n_groups = min(max(n // BLOCK, 1), n, get_num_threads())
run_blocks(grouped, n_groups, params, t0, dt, n_steps, n_transient, save_every,
           out, status, saved{extra}, BLOCK, n_groups)'''


def groups_head(block: int, extra: str = "", dtype: str = "float64") -> str:
    """The head of a refill kernel module's body (`sweep.kernels.lanes.blocks_head`):
    its Python ``kernel`` runs one group of ``BLOCK`` lanes per thread
    (`sweep.kernels.threads.run_blocks`) and its compiled ``grouped`` takes the number
    of groups and each thread's range of them; shared by the single pendulum's and the
    systems' refill kernels.

    Parameters
    ----------
    block : int
        Lanes per group (`sweep.kernels.lanes.block_multiple`).
    extra : str
        The kernel's arguments after ``saved``, as source.
    dtype : {"float64", "float32"}
        The kernel's working precision.

    Returns
    -------
    str
        Module source up to the compiled function's first line.
    """
    return blocks_head(block, extra, dtype, compiled="grouped",
                       trailing="n_groups, g_first, g_stop",
                       wrapper=_GROUPS.format(extra=extra))


#: A known-cells kernel whose observables act at stroboscopic steps only (`_sampled`):
#: each lane's step advanced and the live lanes due at this step (a known-cells test, a
#: stroboscopic step of the steady window, the last step) counted, in a loop LLVM
#: vectorises; the lane loop of the observables runs only when one is due.
_DUE = """n_due = 0
for j in range(BLOCK):
    ks = lane_ks[j] + 1
    lane_ks[j] = ks
    n_due += lane_live[j] & ((ks == lane_acc_kn_next[j]) | (ks == lane_acc_ob_next[j])
                             | (ks >= n_steps))
if n_due > 0:"""


def _sampled(spec: KernelSpec) -> bool:
    """Whether the kernel runs the observables' update and stop test only at the
    steady window's stroboscopic steps (``acc_ob_next``): with known cells, when every
    observed observable declares its `sweep.observables.Observable.phase` (it acts
    only there). A lane then skips the other steps of its steady window as it skips
    its transient's (the known-cells kernel visits it at its stroboscopic steps
    anyway); the results are the same bits."""
    return spec.known_cells and all(OBSERVABLES[name].phase for name in spec.observe)


def refill_kernel(spec: KernelSpec, method) -> str:
    """Kernel body of a fixed-step method with early stop and lane refill (see the
    module docstring); same contract as `sweep.kernels.fixed`.

    Every step runs four lane loops: the drives' sines at each lane's own step, the
    method's step (the same straight-line code as the fixed kernel's, vectorised), the
    sines' carry, and the observables (only lanes past the transient load their
    state). A lane that finishes is only flagged there; a fifth loop, entered only in a
    step where some lane finished, writes its outputs and loads the next trajectory.
    """
    parts = STEPPERS[method.kind](spec, method)
    per_lane, shared = _parameters(spec)
    drives = _drives(parts)
    update = lane_snippet(snippets(spec, "update"))
    # loading trajectory i into lane j: parameters, state, observables, first sines
    load = ["k_state = 0"] + _first_lines(spec, parts, per_lane, drives.init, update,
                                          index="") + ["ks = 0"]
    if _sampled(spec):  # the first stroboscopic step after the start's own update
        load += ["acc_ob_next = n_transient if n_transient > 0 else acc_kn_S"]
    # the drives' sines at this lane's own step: the same expressions as the fixed
    # kernel's at its block step (so the same bits), per lane, or read from a table
    # over the steps when every trajectory has the same drive frequency and phase
    table, sines = _sine_table(spec, drives, shared)
    step_body = drives.values + parts["step"]
    settle = lane_snippet(stop_source(spec, action="done = True"))
    # the lane's step count was advanced in the loop's head
    known = lane_snippet(known_source("done = True")) if spec.known_cells else ""
    if _sampled(spec):  # the observables only at the steady window's stroboscopic steps
        phases = NL.join(f"{OBSERVABLES[name].phase} = 0" for name in spec.observe)
        steady = f"""if k_state == lane_acc_ob_next[j]:
    lane_acc_ob_next[j] += lane_acc_kn_S[j]
{indent(phases, 1)}"""
    else:
        steady = "if k_state >= n_transient:"
    observe = f"""k_state = ks
{steady}
{indent(update, 1)}
{indent(settle, 1)}
{known}
if done or k_state >= n_steps:
    lane_finished[j] = True
    n_finished += 1"""
    finish = _finish(spec, index="", frozen=False)  # a lane finishes as it settles
    refill = f"""{finish}
if first + taken * n_groups < n:
    i = first + taken * n_groups
    taken += 1
else:
    i = first  # idle: a copy of a valid trajectory, never written
    live = False
    n_live -= 1
{NL.join(load)}
finished = False"""
    lane = _lane_dtypes(spec, parts, per_lane, drives.names)
    lane.update({"i": "int64", "ks": "int64", "live": "bool_", "finished": "bool_"})
    if spec.known_cells:
        lane.update(KNOWN_STATE)
    if _sampled(spec):
        lane["acc_ob_next"] = "int64"
    later = set(IDENTIFIER.findall(NL.join(step_body + sines + drives.carry +
                                           [observe, refill])))
    lane = {name: dtype for name, dtype in lane.items() if name in later or name == "live"}
    first = ["if first + taken * n_groups < n:", "    i = first + taken * n_groups",
             "    taken += 1", "    live = True",
             "    n_live += 1", "else:", "    i = first", "    live = False"] + load + \
        ["finished = False"]
    init_loop = lane_loop(NL.join(first), lane, level=2, load=False)
    sine_loop = lane_loop(NL.join(sines), lane, level=3) if sines else ""
    step_loop = lane_loop(NL.join(step_body), lane, level=3,
                          stores=[name for name in lane if name in ["th", "om"] +
                                  parts["carried"]])
    carry_loop = lane_loop(NL.join(drives.carry), lane, level=3) if drives.carry else ""
    counted = {name: dtype for name, dtype in lane.items() if name != "ks"}
    # the known-cells stop runs from the first step on, the observables after the
    # transient
    head = "    ks = lane_ks[j] + 1\n    lane_ks[j] = ks\n"
    if _sampled(spec):  # the steps advanced, and lanes due counted, a vector at a time
        head = "    ks = lane_ks[j]\n    if not lane_live[j]:\n        continue\n" + \
            known_head("ks", "ks != lane_acc_ob_next[j] and ks < n_steps")
    elif spec.known_cells:
        head += "    if not lane_live[j]:\n        continue\n" + \
            known_head("ks", "ks < n_transient and ks < n_steps")
    else:
        head += "    if not lane_live[j] or (ks < n_transient and ks < n_steps):\n" \
                "        continue\n"
    observe_loop = lane_loop(observe, counted, level=3, head=head)
    if _sampled(spec):
        observe_loop = indent(_DUE, 3) + NL + indent(observe_loop, 1)
    refill_loop = lane_loop(refill, lane, level=4,
                            head=skip_unless("finished"))
    return groups_head(spec.block, kernel_arguments(spec), spec.dtype) + f'''\
    TWO_PI = 2.0 * math.pi
    n = params.shape[0]
{indent(NL.join(parts["preamble"]), 1)}
{indent(table, 1)}
    for b in range(g_first, g_stop):
        first = b  # group b's first trajectory
{indent(NL.join(_load(spec, p, "first") for p in shared), 2)}
{indent(NL.join(allocate(lane)), 2)}
        obuf = np.empty((BLOCK, {n_columns(spec)}))
        taken = 0  # trajectories first, first + n_groups, ... taken so far
        n_live = 0
        n_finished = 0
{init_loop}
        while n_live > 0:
{sine_loop}
{step_loop}
{carry_loop}
{observe_loop}
            if n_finished > 0:
{refill_loop}
                n_finished = 0
'''
