"""The fixed-step kernel: trajectories in blocks of SIMD lanes (time at step n is
``t0 + n dt``).

Trajectories go in blocks of ``spec.block`` SIMD lanes; the compiled function
``blocks`` integrates a range of blocks, one after the other, and the module's ``kernel``
spreads the blocks over threads (`sweep.kernels.threads`). The time loop is outside and
the lane loop inside, so the lane loop is straight-line arithmetic that LLVM vectorises
(``vsin`` is branch-free). A partial last block is padded with copies of the last
trajectory, so every lane runs the same code whatever the number of trajectories,
blocks, chunks or threads: the results do not depend on how the work is cut. Per-lane
state lives in small arrays ``lane_<name>`` (plain variables in a kernel of one lane per
block, `sweep.kernels.lanes.scalar_lanes`); observables write a per-block row buffer
``obuf``.

Non-finite states are detected once, at the end (or when a trajectory stops early): a
NaN never becomes finite again in this arithmetic (an infinite angle or velocity turns
into NaN within a step), so the status is the same as with a test after every step,
and samples saved after the failure are set to NaN.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field

from ..observables import OBSERVABLES
from .lanes import IDENTIFIER, allocate, blocks_head, indent, lane_loop, lane_snippet, scalar_lanes
from .precision import float64_symbols
from .snippets import (
    KNOWN_STATE,
    failed_samples,
    failed_status,
    kernel_arguments,
    known_final,
    known_head,
    known_init,
    known_source,
    ok_test,
    renormalisations,
    snippets,
    stop_source,
)
from .spec import KernelSpec, Status, n_columns
from .steppers import STEPPERS
from .terms import column_of, drive_sine

__all__ = ["fixed_kernel"]

NL = "\n"


@dataclass
class _Drives:
    """The drives' sines, as block lines (shared by the block) or lane lines."""

    init: list[str] = field(default_factory=list)   # before the first step
    step: list[str] = field(default_factory=list)   # at the start of every step
    carry: list[str] = field(default_factory=list)  # at the end of every step
    values: list[str] = field(default_factory=list)  # lane lines: value = amplitude * sine
    names: list[str] = field(default_factory=list)  # sine variables


def _drives(parts: dict) -> _Drives:
    """The sines ``s<value> = sin(W t + phi)`` of every drive node, and the lane lines
    that form the values ``<value> = A * s<value>``.

    Either way (block or lane) the step loop reads them as plain values and forms the
    product itself, with the same operations, so both forms give the same bits (a test
    checks it).
    """
    drives = _Drives()
    for key, triples in (("init", parts["drive_init"]), ("step", parts["drive_step"])):
        getattr(drives, key).extend(f"s{name} = {drive_sine(effect, at)}"
                                    for effect, name, at in triples)
    drives.carry = [f"s{dst} = s{src}" for dst, src in parts["drive_carry"]]
    for effect, name, _ in parts["drive_init"] + parts["drive_step"]:
        drives.values.append(f"{name} = {effect.drive.amplitude} * s{name}")
        drives.names.append(f"s{name}")
    return drives


def _parameters(spec: KernelSpec) -> tuple[list[str], list[str]]:
    """Kernel symbols read per lane and per block.

    Every parameter is read per lane (no slower, and the lane loop's arithmetic is
    then the same whatever the block shares), except each drive's frequency and phase
    when the drive sines are shared by the block.
    """
    per_lane, shared = ["L", "g", "w0sq"], []
    for effect in spec.effects:
        block_level = (effect.drive.frequency, effect.drive.phase) \
            if spec.shared_forcing and effect.drive is not None else ()
        for symbol in effect.symbols:
            (shared if symbol in block_level else per_lane).append(symbol)
    return per_lane, shared


def _load(spec: KernelSpec, symbol: str, row: str) -> str:
    return "w0sq = g / L" if symbol == "w0sq" else \
        f"{symbol} = params[{row}, {column_of(spec, symbol)}]"


def _first_lines(spec: KernelSpec, parts: dict, per_lane: list[str], lane_sines: list[str],
                 update: str, index: str = "i = min(base + j, n - 1)  # padding lanes "
                                            "repeat the last trajectory") -> list[str]:
    """Once per lane: trajectory ``i`` (from the line ``index``): parameters, initial
    state, observables' init, first save."""
    first = ([index] if index else []) + [_load(spec, "th0", "i"), _load(spec, "om0", "i")] + \
        [_load(spec, p, "i") for p in per_lane] + \
        ["th = th0", "om = om0", lane_snippet(snippets(spec, "init"))] + \
        ([known_init()] if spec.known_cells else [])
    if update:
        first += ["if n_transient <= 0:", indent(update, 1)]
    if spec.save:
        first += ["if base + j < n:", "    saved[base + j, 0, 0] = th",
                  "    saved[base + j, 1, 0] = om"]
    first += parts["before"] + lane_sines
    if spec.stop_early:
        first += ["done = False", "th_stop = th", "om_stop = om"]
    return first


def _observe_parts(spec: KernelSpec, update: str) -> tuple[str, str, str]:
    """Observables' update (steady window) and the early-stop test, per lane: the block
    template, the lane-loop head and the lane-loop body."""
    if not update:
        return "", "", ""
    body, head = update, ""
    action = "done = True\nth_stop = th\nom_stop = om\nn_done += 1"
    if spec.stop_early:
        head = "    if lane_done[j]:\n        continue\n"
        body += NL + lane_snippet(stop_source(spec, action=action))
    block = "if step + 1 >= n_transient:\n{loop}"
    if spec.known_cells:  # the known-cells stop runs from the first step on
        head += known_head("k_state", "k_state < n_transient")
        body = "if k_state >= n_transient:\n" + indent(body, 1) + NL + known_source(action)
        block = "if True:\n{loop}"
    if spec.stop_early:
        block += "\n    if n_done == BLOCK:\n        break"
    return block, head, body


_SAVE_BLOCK = textwrap.dedent("""\
    if (step + 1) % save_every == 0:
        k_save = (step + 1) // save_every
        for j in range(n_real):
            saved[base + j, 0, k_save] = lane_th[j]
            saved[base + j, 1, k_save] = lane_om[j]""")

def _finish(spec: KernelSpec, index: str = "i = base + j\n", frozen: bool | None = None) -> str:
    """Per real lane: status, observables' final values, copy to ``out`` (row ``i``, set
    by the line ``index``); ``frozen``: a settled lane's state was kept in th_stop,
    om_stop (default: with early stop)."""
    width = n_columns(spec)
    final = lane_snippet(snippets(spec, "final") +
                         (NL + known_final(spec) if spec.known_cells else ""))
    frozen = spec.stop_early if frozen is None else frozen
    stop_state = "if done:\n    th = th_stop\n    om = om_stop\n" if frozen else ""
    return f"""{index}{stop_state}if {ok_test(spec)}:
    status[i] = {int(Status.OK)}
{indent(final, 1) or "    pass"}
else:
    status[i] = {failed_status(spec)}
    for col in range({width}):
        obuf[j, col] = math.nan
{indent(failed_samples(spec) if spec.save else "", 1)}
for col in range({width}):
    out[i, col] = obuf[j, col]"""


def _lane_dtypes(spec: KernelSpec, parts: dict, per_lane: list[str],
                 lane_sines: list[str]) -> dict[str, str]:
    """Every lane variable (name -> dtype): state, per-lane parameters, carried values,
    per-lane drive sines (in the spec's working precision), observable state (as the
    observables declare it), early-stop bookkeeping."""
    real = spec.dtype  # the working precision
    keep = float64_symbols(spec.model, spec.effects) if real != "float64" else set()
    angle = "float64" if "th0" in keep else real  # sweep.kernels.precision
    lane = {"th": angle, "om": real, "th0": angle, "om0": real}
    lane.update({p: "float64" if p in keep else real for p in per_lane})
    lane.update({name: real for name in parts["carried"]})
    for name in spec.observe:
        lane.update(dict(OBSERVABLES[name].state))
    if spec.stop_early:
        lane.update({"done": "bool_", "th_stop": angle, "om_stop": real})
    if spec.known_cells:
        lane.update(KNOWN_STATE)
    lane.update({name: real for name in lane_sines})
    return lane


def fixed_kernel(spec: KernelSpec, method) -> str:
    """Kernel body of a fixed-step method (see the module docstring)."""
    parts = STEPPERS[method.kind](spec, method)
    per_lane, shared = _parameters(spec)
    drives = _drives(parts)
    shared_sine = spec.shared_forcing
    block_init, block_step, block_after = (drives.init, drives.step, drives.carry) \
        if shared_sine else ([], [], [])
    update = lane_snippet(snippets(spec, "update"))
    first = _first_lines(spec, parts, per_lane, [] if shared_sine else drives.init, update)
    step_body = drives.values + parts["step"]
    step_stores = ["th", "om"] + parts["carried"]
    observe_block, observe_head, observe_body = _observe_parts(spec, update)
    finish = _finish(spec)
    lane = _lane_dtypes(spec, parts, per_lane, [] if shared_sine else drives.names)
    renormalise = renormalisations(spec)
    # lane arrays only for what the loops after the first one read
    later = set(IDENTIFIER.findall(NL.join(step_body + drives.step + drives.carry +
                                           [observe_head, observe_body, finish] +
                                           [code for _, code in renormalise])))
    if spec.known_cells:  # read as lane arrays (`known_source`)
        later |= set(KNOWN_STATE)
    lane = {name: dtype for name, dtype in lane.items() if name in later}
    init_loop = lane_loop(NL.join(first), lane, level=2, load=False)
    step_loop = lane_loop(NL.join(step_body), lane, level=3,
                          stores=[name for name in lane if name in step_stores])
    if not shared_sine and drives.step:
        step_loop = lane_loop(NL.join(drives.step), lane, level=3) + NL + step_loop
    if not shared_sine and drives.carry:
        step_loop += NL + lane_loop(NL.join(drives.carry), lane, level=3)
    if observe_block:
        observe_block = observe_block.format(loop=lane_loop(observe_body, lane, level=1,
                                                            head=observe_head))
    renormalise_blocks = NL.join(head + NL + lane_loop(code, lane, level=1)
                                 for head, code in renormalise)
    finish_loop = lane_loop(finish, lane, level=2, stores=[], count="n_real")
    kernel = blocks_head(spec.block, kernel_arguments(spec), spec.dtype) + f'''\
    TWO_PI = 2.0 * math.pi
    n = params.shape[0]
{indent(NL.join(parts["preamble"]), 1)}
    for b in range(b_first, b_stop):
        base = b * BLOCK
        n_real = min(BLOCK, n - base)
{indent(NL.join(_load(spec, p, "base") for p in shared), 2)}
{indent(NL.join(allocate(lane)), 2)}
        obuf = np.empty((BLOCK, {n_columns(spec)}))
        k_state = 0
        n_done = 0
{init_loop}
{indent(NL.join(block_init), 2)}
        for step in range(n_steps):
{indent(NL.join(block_step), 3)}
{step_loop}
{indent(NL.join(block_after), 3)}
            k_state = step + 1
{indent(renormalise_blocks, 3)}
{indent(observe_block, 3)}
{indent(_SAVE_BLOCK if spec.save else "", 3)}
{finish_loop}
'''
    # a known-cells kernel keeps its one-lane loop (its head's skip is no plain flag)
    return scalar_lanes(kernel, lane) if spec.block == 1 and not spec.known_cells \
        else kernel
