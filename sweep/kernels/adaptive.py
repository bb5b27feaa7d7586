"""The adaptive kernel: an embedded Runge-Kutta pair, each trajectory controlling its own
step (one trajectory per ``prange`` iteration).

Each trajectory advances its own time ``t`` (a sum of accepted steps) and clips its
last step so that it ends at ``t_end`` exactly. A trajectory whose step would have to
shrink below ``16 eps max(|t0|, |t_end|)`` (which only a state on its way to overflow
does) is flagged ``STEP_UNDERFLOW``: a rejected step whose new state is non-finite
shrinks the step, so a blow-up ends there too (its state stays finite).
"""

from __future__ import annotations

from .lanes import indent
from .snippets import snippets
from .spec import KernelSpec, Status, n_columns
from .steppers import at_node, combination, rk_stages
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
    new_state = [f"thn = th + {combination(tableau.b, kt, 'h', None)}",
                 f"omn = om + {combination(tableau.b, ko, 'h', None)}"]
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
    update = snippets(spec, "update", time="t")
    exponent = -1.0 / (tableau.embedded_order + 1)
    nl = chr(10)
    return f'''
@njit(parallel=True, **JIT)
def kernel(params, t0, t_end, dt, t_transient, rtol, atol, out, status, stats):
    TWO_PI = 2.0 * math.pi
    t_obs = t0 + t_transient
    h_min = 16.0 * 2.220446049250313e-16 * max(abs(t0), abs(t_end))
    for i in prange(params.shape[0]):
{indent(nl.join(load_lines(spec)), 2)}
        th = th0
        om = om0
        t = t0
{indent(snippets(spec, "init", time="t"), 2)}
{indent(("if t_transient <= 0.0:" + nl + indent(update, 1)) if update else "", 2)}
        h = dt
{indent(nl.join(f_first + first), 2)}
        accepted = 0
        rejected = 0
        after_reject = False
        ok = True
        while t < t_end:
            last = t + h >= t_end
            if last:
                h = t_end - t
{indent(nl.join(attempt), 3)}
{indent(nl.join(err), 3)}
            sct = atol + rtol * max(abs(th), abs(thn))
            sco = atol + rtol * max(abs(om), abs(omn))
            err = math.sqrt(0.5 * ((et / sct) ** 2 + (eo / sco) ** 2))
            if err <= 1.0 and math.isfinite(thn) and math.isfinite(omn):
                t = t_end if last else t + h
                th = thn
                om = omn
{indent(nl.join(accept_carry), 4)}
                accepted += 1
{indent(("if t >= t_obs:" + nl + indent(update, 1)) if update else "", 4)}
                if err == 0.0:
                    fac = {_FACMAX!r}
                else:
                    fac = min({_FACMAX!r}, max({_FACMIN!r}, {_SAFETY!r} * err ** {exponent!r}))
                if after_reject:
                    fac = min(fac, 1.0)
                after_reject = False
                h = min(h * fac, dt)
            else:
                rejected += 1
                if math.isfinite(err):
                    h = h * max({_FACMIN!r}, {_SAFETY!r} * err ** {exponent!r})
                else:
                    h = h * {_FACMIN!r}
                after_reject = True
                if h < h_min:
                    ok = False
                    break
        stats[i, 0] = accepted
        stats[i, 1] = rejected
{_final_block(spec)}'''


def _final_block(spec: KernelSpec) -> str:
    return f'''\
        if ok:
            status[i] = {int(Status.OK)}
{indent(snippets(spec, "final"), 3) or "            pass"}
        else:
            status[i] = {int(Status.STEP_UNDERFLOW)}
            for col in range({n_columns(spec)}):
                out[i, col] = math.nan
'''
