"""The adaptive kernel: an embedded Runge-Kutta pair, each trajectory controlling its own
step, trajectories in blocks of SIMD lanes.

A block's lanes try a step together (straight-line arithmetic, vectorised by LLVM like
the fixed-step kernels, each lane with its own time ``t`` and step ``h``); then each
lane, one after the other, accepts or rejects its own attempt and sets its next step,
and a lane whose trajectory is done writes its results and goes idle (it keeps trying
steps whose results are never used) until the block's last lane is done. A lane's
arithmetic is the same operations whatever the block, so the results do not depend on
the block or the thread count, bit for bit (``tests/test_blocks.py``). Against the
one-trajectory kernel of sweep 0.1 the step counts are the same and the states agree to
rounding (sweep 0.1 let LLVM choose which products to fuse into FMAs; the kernels now
fuse only those they write, ``vfma``; ``tests/test_effects.py``).

A block costs BLOCK times the most step attempts of its trajectories
(`sweep._config.ADAPTIVE_BLOCK`). Measured by ``benchmarks/work_precision.py`` (its
last table): 4.4-5.1x the speed of one trajectory per block (with libm's power, the
faster scalar choice) at the same tolerance, 3.8-4.1x on an uneven grid; 5.4-6.2x
against one trajectory per block with the previous sine (whose longer latency slowed
the one-at-a-time kernel more than the lanes; docs/guide/integrators.md).
The controller's factor ``err ** -0.2`` is computed with the lanes, vectorised
(`sweep.kernels.vecmath.inverse_fifth_root`: a guess from the float's bits and Newton
steps, no libm call); what is left scalar is a finished lane's write-out.

Each trajectory advances its own time ``t`` (a sum of accepted steps) and clips its
last step so that it ends at ``t_end`` exactly. A trajectory whose step would have to
shrink below ``16 eps max(|t0|, |t_end|)`` (which only a state on its way to overflow
does) is flagged ``STEP_UNDERFLOW``: a rejected step whose new state is non-finite
shrinks the step, so a blow-up ends there too (its state stays finite).
"""

from __future__ import annotations

from .. import _config
from ..observables import OBSERVABLES
from .lanes import (
    ADAPTIVE_ARGUMENTS,
    IDENTIFIER,
    allocate,
    blocks_head,
    indent,
    lane_loop,
    lane_snippet,
    skip_unless,
)
from .snippets import kernel_arguments, snippets
from .spec import KernelSpec, Status, n_columns
from .steppers import at_node, combination, fused, rk_stages
from .terms import accel_call, drive_line, drive_nodes, load_lines

__all__ = ["adaptive_kernel"]

# Step-size control of the adaptive kernels ([HNW] II.4, as in DOPRI5 and SciPy's RK45):
# h_new = h * min(FACMAX, max(FACMIN, SAFETY * err^(-1/(q+1)))), q the embedded order;
# no growth right after a rejection.
_SAFETY = 0.9
_FACMIN = 0.2
_FACMAX = 10.0


def adaptive_kernel(spec: KernelSpec, tableau) -> str:
    """Kernel body of an embedded pair: each trajectory controls its own step."""
    s = tableau.stages
    drives, nodes = drive_nodes(spec, tableau.c, time="t", step=None, scale="h",
                                constants=None)
    f_lines = [drive_line(effect, name, at) for effect, name, at in nodes]
    stages = rk_stages(spec, tableau, "h", None, drives)
    kt = [f"k{j + 1}t" for j in range(s)]
    ko = [f"k{j + 1}o" for j in range(s)]
    new_state = [f"thn = {fused('th', tableau.b, kt, 'h', None)}",
                 f"omn = {fused('om', tableau.b, ko, 'h', None)}"]
    if tableau.fsal:
        # the last stage is evaluated at the new state: it is the next step's first
        stages = stages[2:-2]
        last = [f"k{s}t = omn",
                f"k{s}o = " + accel_call(spec, "thn", "omn", at_node(drives, tableau.c[-1]))]
        first = ["k1t = om", "k1o = " + accel_call(spec, "th", "om", at_node(drives, 0))]
        at_start = set(at_node(drives, 0).values())
        f_first = [drive_line(e, name, at) for e, name, at in nodes if name in at_start]
        f_lines = [drive_line(e, name, at) for e, name, at in nodes if name not in at_start]
        attempt = f_lines + stages + new_state + last
        accept_carry = [f"k1t = k{s}t", f"k1o = k{s}o"]
    else:
        first, f_first, accept_carry = [], [], []
        attempt = f_lines + rk_stages(spec, tableau, "h", None, drives) + new_state
    err = [f"et = {combination(tableau.error_weights, kt, 'h', None)}",
           f"eo = {combination(tableau.error_weights, ko, 'h', None)}"]
    update = lane_snippet(snippets(spec, "update", time="t"))
    exponent = -1.0 / (tableau.embedded_order + 1)
    nl = chr(10)
    init = ["i = min(base + j, n - 1)  # padding lanes repeat the last trajectory"] + \
        load_lines(spec, "i") + [
        "th = th0", "om = om0", "t = t0", lane_snippet(snippets(spec, "init", time="t")),
        ("if t_transient <= 0.0:" + nl + indent(update, 1)) if update else "",
        "h = dt"] + f_first + first + [
        "accepted = 0", "rejected = 0", "after_reject = False", "ok = True",
        "active = j < n_real and t < t_end", "thn = th", "omn = om", "err = 0.0",
        "last = False"] + [f"k{s}t = 0.0", f"k{s}o = 0.0"] * bool(first) + [
        # nothing to integrate (t0 >= t_end): the start is the result, as one
        # trajectory at a time would give
        "if j < n_real and not active:", indent(_finish(spec), 1)]
    # the controller's factor err^exponent: for a 5th-order pair computed with the
    # lanes (vectorised, no libm: vecmath.inverse_fifth_root), else libm's power in the
    # lane-by-lane control below
    vectorised = exponent == -0.2 and _config.VECTOR_CONTROLLER
    power = "fac_new" if vectorised else f"err ** {exponent!r}"
    try_step = ["last = t + h >= t_end", "if last:", "    h = t_end - t"] + attempt + err + [
        "sct = atol + rtol * max(abs(th), abs(thn))",
        "sco = atol + rtol * max(abs(om), abs(omn))",
        "err = math.sqrt(0.5 * ((et / sct) ** 2 + (eo / sco) ** 2))"] + \
        ["fac_new = vroot5(err)"] * vectorised
    # accept or reject. With libm's power (not vectorisable) lane by lane, skipping
    # idle lanes: a branch per lane costs less than selects over all lanes (measured).
    # With the vectorised power, over all lanes as selects (an idle lane's results are
    # written already, so what it computes is never read), then lane by lane only the
    # test for a lane that is done, which writes its results and goes idle.
    decide = f"""if err <= 1.0 and math.isfinite(thn) and math.isfinite(omn):
    t = t_end if last else t + h
    th = thn
    om = omn
{indent(nl.join(accept_carry), 1)}
    accepted += 1
{indent(("if t >= t_obs:" + nl + indent(update, 1)) if update else "", 1)}
    if err == 0.0:
        fac = {_FACMAX!r}
    else:
        fac = min({_FACMAX!r}, max({_FACMIN!r}, {_SAFETY!r} * {power}))
    if after_reject:
        fac = min(fac, 1.0)
    after_reject = False
    h = min(h * fac, dt)
else:
    rejected += 1
    if math.isfinite(err):
        h = h * max({_FACMIN!r}, {_SAFETY!r} * {power})
    else:
        h = h * {_FACMIN!r}
    after_reject = True
    if h < h_min:
        ok = False"""
    done = f"""if not ok or t >= t_end:
    active = False
    n_active -= 1
{indent(_finish(spec), 1)}"""
    control = decide + nl + done
    # per-lane variables (name -> dtype): those the loops after the first one read
    lane = {name: "float64" for name in ["th", "om", "t", "h", "thn", "omn", "err",
                                          "fac_new"]}
    lane.update({line.split("=")[0].strip(): "float64" for line in load_lines(spec)})
    lane.update({name: "float64" for name in (first and
                                              ["k1t", "k1o", f"k{s}t", f"k{s}o"])})
    for name in spec.observe:
        lane.update(dict(OBSERVABLES[name].state))
    lane.update({"accepted": "int64", "rejected": "int64", "after_reject": "bool_",
                 "ok": "bool_", "active": "bool_", "last": "bool_"})
    later = set(IDENTIFIER.findall(nl.join(try_step + [control])))
    lane = {name: dtype for name, dtype in lane.items() if name in later}
    init_loop = lane_loop(nl.join(init), lane, level=2, load=False)
    try_loop = lane_loop(nl.join(try_step), lane, level=3,
                         stores=[name for name in lane if name in
                                 {"h", "last", "thn", "omn", "err", "fac_new", f"k{s}t",
                                  f"k{s}o"}])
    if vectorised:
        control_loop = lane_loop(decide, lane, level=3) + nl + lane_loop(
            done, lane, level=3, head=skip_unless("active"), stores=["active"])
    else:
        control_loop = lane_loop(control, lane, level=3, head=skip_unless("active"))
    extra = kernel_arguments(spec)  # the attractor observable's catalogue
    return """
from sweep.kernels.vecmath import inverse_fifth_root as vroot5
""" + blocks_head(spec.block, extra, spec.dtype, arguments=ADAPTIVE_ARGUMENTS) + f'''\
    TWO_PI = 2.0 * math.pi
    t_obs = t0 + t_transient
    h_min = 16.0 * 2.220446049250313e-16 * max(abs(t0), abs(t_end))
    n = params.shape[0]
    for b in range(b_first, b_stop):
        base = b * BLOCK
        n_real = min(BLOCK, n - base)
{indent(nl.join(allocate(lane)), 2)}
        obuf = np.empty((BLOCK, {n_columns(spec)}))
{init_loop}
        n_active = 0
        for j in range(n_real):
            n_active += lane_active[j]
        while n_active > 0:
{try_loop}
{control_loop}
'''


def _finish(spec: KernelSpec) -> str:
    """A lane's trajectory is done (or its step underflowed): statistics, status,
    observables' final values, copy to ``out``."""
    width = n_columns(spec)
    limit = spec.angle_limit  # an accepted state is finite: only its angle's range
    in_range = f" and abs(th) <= {limit!r}" if limit is not None else ""
    failed = f"{int(Status.STEP_UNDERFLOW)}" if limit is None else \
        f"{int(Status.ANGLE_OUT_OF_RANGE)} if ok else {int(Status.STEP_UNDERFLOW)}"
    return f"""i = base + j
stats[i, 0] = accepted
stats[i, 1] = rejected
if ok{in_range}:
    status[i] = {int(Status.OK)}
{indent(lane_snippet(snippets(spec, "final")), 1) or "    pass"}
else:
    status[i] = {failed}
    for col in range({width}):
        obuf[j, col] = math.nan
for col in range({width}):
    out[i, col] = obuf[j, col]"""
