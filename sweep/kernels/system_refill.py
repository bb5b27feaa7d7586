"""A system's early-stop kernel with lane refill (`sweep.kernels.system`, ``stop_early``):
a lane whose trajectory has flipped (or reached ``t_end``, or started below the lowest
flipping energy), or settled on a catalogued attractor (``attractor``), writes its
outputs and takes the next waiting trajectory, so no SIMD lane idles while its block's
slowest trajectory finishes.

The single pendulum's refill kernel (`sweep.kernels.refill`) in the systems' terms: one
group of lanes per thread (group ``b`` of ``G`` takes the trajectories ``b, b + G, b +
2 G, ...``, `sweep.kernels.threads`), each lane with its own step index ``ks`` (the
time ``t0 + ks dt`` of a driven pivot, and of the flip's interpolation). A trajectory's
arithmetic is the same operations whatever lane it runs in and whenever it starts (the
step of `sweep.kernels.system._parts`, with the block's step count replaced by the
lane's), so the results are bit-identical to the kernel without refill
(``tests/test_systems_refill.py``) and independent of the threads and of ``BLOCK``.

Why: on the double pendulum's flip-time map (``examples/double_pendulum_flip.py``,
300 x 300 starts at rest, blocks of 64) a third of the starts are below the lowest
flipping energy and the flip times spread over the whole run, so only 29 % of the
lane-steps the block kernel executes belong to a trajectory that is still running
(measured from the map's flip times, AMD EPYC Zen 5, 2026-11-28).
"""

from __future__ import annotations

import re

from .lanes import CATALOGUE_ARGUMENTS, IDENTIFIER, allocate, indent, lane_loop, skip_unless
from .refill import groups_head

__all__ = ["system_refill_kernel"]

NL = "\n"
_STEP = re.compile(r"\bstep\b")  # the block kernel's step count, in the step's times
_K_STATE = re.compile(r"\bk_state\b")  # the block kernel's state index, in the samples'


def system_refill_kernel(spec, parts, finish: str) -> str:
    """The body of ``spec``'s refill kernel (the contract of `sweep.kernels.system`).

    Parameters
    ----------
    spec : sweep.kernels.system.SystemSpec
        With ``stop_early`` (``observe`` one of `sweep.kernels.system.STOPPING`, no
        saving) and ``block > 1``.
    parts : sweep.kernels.system._Parts
        Its per-trajectory pieces.
    finish : str
        The per-trajectory lines writing ``status[i]`` and ``out[i, :]`` (the block
        kernel's, for lane variable ``i``), the stopped state restored where ``done``.

    Returns
    -------
    str
    """
    state, symbols = parts.state, parts.symbols
    load = [f"{x} = params[i, {k}]" for k, x in enumerate(state + symbols)]
    load += parts.hoisted + parts.first + ["ks = 0", "finished = False"]
    if parts.strobe_first:  # an idle lane's copy writes nothing
        load += ["if live:"] + [indent(line, 1) for line in parts.strobe_first]
    body = [_STEP.sub("ks", line) for line in parts.body]
    # the samples of the lane's own step ks (the block kernel's k_state)
    observe = [_K_STATE.sub("ks", line)
               for line in parts.strobe_sample + parts.attractor_sample]
    observe += [f"if {parts.stop_test}:"] + [indent(line, 1) for line in parts.stopped] + [
        "if done or ks >= n_steps:", "    finished = True", "    n_finished += 1"]
    refill = [finish, "if first + taken * n_groups < n:", "    i = first + taken * n_groups",
              "    taken += 1", "else:", "    i = first  # idle: a copy, never written",
              "    live = False", "    n_live -= 1"] + load
    first = ["if first + taken * n_groups < n:", "    i = first + taken * n_groups",
             "    taken += 1", "    live = True", "    n_live += 1", "else:", "    i = first",
             "    live = False"] + load
    lane = dict(parts.lane)
    lane.update({"i": "int64", "ks": "int64", "live": "bool_", "finished": "bool_"})
    later = set(IDENTIFIER.findall(NL.join(body + observe + refill)))
    lane = {name: dtype for name, dtype in lane.items() if name in later or name == "live"}
    invariant = ([f"hoisted_values = np.empty(({parts.n_hoisted}, BLOCK))"]
                 if parts.n_hoisted else [])
    init_loop = lane_loop(NL.join(first), lane, level=2, load=False)
    step_loop = lane_loop(NL.join(body), lane, level=3)  # stores what the step assigns
    head = "    ks = lane_ks[j] + 1\n    lane_ks[j] = ks\n" + skip_unless("live")
    observe_loop = lane_loop(NL.join(observe), {k: v for k, v in lane.items() if k != "ks"},
                             level=3, head=head)
    if "flip" not in spec.observe:  # only sampled observables: see _due
        observe_loop = _due(parts, lane, observe)
    refill_loop = lane_loop(NL.join(refill), lane, level=4, head=skip_unless("finished"))
    more = CATALOGUE_ARGUMENTS if "attractor" in spec.observe else ""
    return groups_head(spec.block, more, spec.dtype) + f'''\
    TWO_PI = 2.0 * math.pi
    n = params.shape[0]
{indent(NL.join(parts.constants.values()), 1)}
    for b in range(g_first, g_stop):
        first = b  # group b's first trajectory
{indent(NL.join(allocate(lane) + invariant), 2)}
        taken = 0  # trajectories first, first + n_groups, ... taken so far
        n_live = 0
        n_finished = 0
        n_done = 0
{init_loop}
        while n_live > 0:
{step_loop}
{observe_loop}
            if n_finished > 0:
{refill_loop}
                n_finished = 0
'''


def _due(parts, lane: dict[str, str], observe: list[str]) -> str:
    """The observe loop of a kernel whose observables act only at their samples (a
    catalogue's ``attractor``, ``strobe``): each lane's step advanced and the lanes due
    at this step (a sample, or the last step) counted, in a loop LLVM vectorises; the
    lane loop of the observables runs only when one is due, as the single pendulum's
    known-cells kernel does (`sweep.kernels.refill`). Most steps sample nothing (one in
    ``2 pi / (nu dt)``), and the observe loop, not vectorised, cost as much as a third
    of a step (measured on the double Kapitza pendulum's map, AMD EPYC Zen 5). The
    same operations at the same steps, so the same bits."""
    nexts = [name for name in ("ca_next", "sb_next") if name in lane]
    due = " or ".join([f"ks == lane_{name}[j]" for name in nexts] + ["ks >= n_steps"])
    count = (f"for j in range(BLOCK):\n    ks = lane_ks[j] + 1\n    lane_ks[j] = ks\n"
             f"    n_due += 1 if {due} else 0")
    loop = lane_loop(NL.join(["ks = lane_ks[j]"] + observe),
                     {k: v for k, v in lane.items() if k != "ks"}, level=1,
                     head=skip_unless("live"))
    return indent(f"n_due = 0\n{count}\nif n_due > 0:\n{loop}", 3)
