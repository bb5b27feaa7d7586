"""The physics as kernel source, read from the effect declarations: the acceleration
with only the scene's terms, the energy, the drives' values at stage times, and the
loads of parameters from the table."""

from __future__ import annotations

from ..physics import BASE_PARAMETERS, EffectDeclaration, parameter_names
from .lanes import IDENTIFIER
from .spec import KernelSpec

__all__ = ["accel_call", "accel_jacobian_source", "accel_source", "column_of", "drive_line",
           "drive_nodes", "drive_sine", "energy_source", "float_literal", "load_lines", "symbols",
           "tension_terms"]

def float_literal(x) -> str:
    """``repr(float(x))``: an exact literal of a coefficient."""
    return repr(float(x))


def symbols(spec: KernelSpec) -> dict[str, str]:
    """``{kernel symbol: parameter name}`` of the base parameters and the spec's effects."""
    found = {p.symbol: p.axis for p in BASE_PARAMETERS}
    for effect in spec.effects:
        found.update({p.symbol: p.axis for p in effect.parameters})
    return found


def column_of(spec: KernelSpec, symbol: str) -> int:
    """Column of the parameter table holding kernel variable ``symbol``."""
    return parameter_names().index(symbols(spec)[symbol])


def _accel_args(effect: EffectDeclaration, jacobian: bool = False) -> list[str]:
    """The names its term reads (with ``jacobian``: or its derivatives): its symbols
    (declaration order), then its drive value."""
    texts = [effect.term] + ([effect.jacobian("th"), effect.jacobian("om")] if jacobian
                             else [])
    used = set(IDENTIFIER.findall(" ".join(texts)))
    args = [s for s in effect.symbols if s in used]
    if effect.drive is not None and effect.drive.value in used:
        args.append(effect.drive.value)
    return args


def accel_source(spec: KernelSpec) -> str:
    """``accel(th, om, w0sq, ...)``: theta'' with only the scene's terms: each effect's
    term in canonical order, then gravity fused onto their sum (`_acceleration`)."""
    args = ["th", "om", "w0sq"] + [a for effect in spec.effects for a in _accel_args(effect)]
    f_theta = "vsin(th)" if spec.model == "nonlinear" else "th"
    return (
        "@njit(**JIT)\n"
        f"def accel({', '.join(args)}):\n"
        f"    return {_acceleration(spec, f_theta)}\n"
    )


def _acceleration(spec: KernelSpec, f_theta: str) -> str:
    """theta'' as an expression: the effects' terms in canonical order, then gravity
    fused onto them, ``vfma(-w0sq, f_theta, terms)`` (one rounding, written explicitly:
    the kernels let LLVM fuse nothing itself, `sweep._config.FASTMATH`), with
    ``f_theta`` the source of f(theta)."""
    terms = " ".join(effect.term.replace("FTH", f_theta) for effect in spec.effects)
    return f"vfma(-w0sq, {f_theta}, {terms or '0.0'})"


def accel_jacobian_source(spec: KernelSpec) -> str:
    """``accel_jac(th, om, w0sq, ...)``: theta'' and its derivatives with respect to
    theta and theta' (the tangent dynamics' coefficients), with the sine and cosine of
    theta from one argument reduction (`sweep.kernels.vecmath.sincos`).

    Raises
    ------
    ValueError
        If an effect's term reads a state variable without a declared derivative.
    """
    args = ["th", "om", "w0sq"] + [a for e in spec.effects
                                   for a in _accel_args(e, jacobian=True)]
    nonlinear = spec.model == "nonlinear"
    f_theta, df_theta = ("sin_th", "cos_th") if nonlinear else ("th", "1.0")
    d_theta = ["-w0sq * " + df_theta] + [e.jacobian("th").replace("DFTH", df_theta)
                                        .replace("FTH", f_theta) for e in spec.effects
                                        if e.jacobian("th")]
    d_omega = [e.jacobian("om").replace("DFTH", df_theta).replace("FTH", f_theta)
               for e in spec.effects if e.jacobian("om")]
    d_omega = " ".join(d_omega) if d_omega else "0.0"
    return (
        "@njit(**JIT)\n"
        f"def accel_jac({', '.join(args)}):\n"
        + ("    sin_th, cos_th = vsincos(th)\n" if nonlinear else "")
        + f"    return ({_acceleration(spec, f_theta)}), ({' '.join(d_theta)}), ({d_omega})\n"
    )


def accel_call(spec: KernelSpec, th: str, om: str, values: dict[str, str],
               jacobian: bool = False) -> str:
    """``accel(...)`` (with ``jacobian``: ``accel_jac(...)``) on state ``th, om``;
    ``values`` maps a drive effect's name to the variable holding its drive value at
    this stage."""
    args = [th, om, "w0sq"]
    for effect in spec.effects:
        for arg in _accel_args(effect, jacobian):
            args.append(values.get(effect.name) if effect.drive is not None
                        and arg == effect.drive.value else arg)
    return f"{'accel_jac' if jacobian else 'accel'}({', '.join(args)})"


def energy_source(spec: KernelSpec) -> str:
    """``energy(th, om, w0sq)``: kinetic plus gravitational energy per unit ``m L^2``."""
    potential = "w0sq * (1.0 - vcos(th))" if spec.model == "nonlinear" else \
        "0.5 * w0sq * th * th"
    return (
        "@njit(**JIT)\n"
        "def energy(th, om, w0sq):\n"
        f"    return 0.5 * om * om + {potential}\n"
    )


def tension_terms(spec: KernelSpec, time: str) -> str:
    """The effects' additions to the rod tension ``T/m`` (``TENSION_TERMS``), with
    ``TIME`` the kernel's expression for the time of the state."""
    return "".join(f" {effect.tension}".replace("TIME", time)
                   for effect in spec.effects if effect.tension)


def drive_nodes(spec: KernelSpec, c, *, time: str, step: str | None, scale: str,
                constants: dict[str, str] | None):
    """Each drive's variable per distinct node c_i, and the time it is evaluated at.

    Fixed step (``step`` given): time of node c is ``t0 + step * dt + c * dt`` (c = 0:
    ``t0 + step * dt``; c = 1: ``t0 + (step + 1) * dt``), never accumulated. Adaptive
    (``step`` None): ``time + c * h``.

    Returns
    -------
    names : dict
        ``{effect name: {c: variable}}``; the variable holds the drive's value
        ``amplitude * sin(frequency * time + phase)`` (see `drive_line`).
    nodes : list of (EffectDeclaration, variable, time expression)
    """
    names, nodes = {}, []
    for effect in spec.drives:
        own = names[effect.name] = {}
        for x in sorted(set(c)):
            name = own[x] = f"{effect.drive.value}{len(own)}"
            if step is None:
                at = time if x == 0 else (f"{time} + {scale}" if x == 1 else
                                          f"{time} + {float_literal(x)} * {scale}")
            elif x == 0:
                at = f"t0 + {step} * dt"
            elif x == 1:
                at = f"t0 + ({step} + 1) * dt"
            else:
                line = f"dt * {float_literal(x)}"
                const = next((k for k, v in constants.items() if v.endswith(f"= {line}")),
                             f"cdt{len(constants)}")
                constants[const] = f"{const} = {line}"
                at = f"t0 + {step} * dt + {const}"
            nodes.append((effect, name, at))
    return names, nodes


def drive_sine(effect: EffectDeclaration, at: str) -> str:
    """``sin(frequency * (at) + phase)`` (or ``cos``) of an effect's drive, as source."""
    drive = effect.drive
    return f"v{drive.function}({drive.frequency} * ({at}) + {drive.phase})"


def drive_line(effect: EffectDeclaration, name: str, at: str) -> str:
    """``name = amplitude * sin(frequency * (at) + phase)``: the drive at time ``at``."""
    return f"{name} = {effect.drive.amplitude} * {drive_sine(effect, at)}"


def load_lines(spec: KernelSpec, row: str | None = "i", table: str = "params",
               arguments: str = "") -> list[str]:
    """Per-trajectory loads: initial state, pendulum, the effects' parameters, from
    ``table[row, column]``, or, where ``row`` is None, from the call
    ``table(column, arguments)`` (a GPU thread's parameter, `sweep.kernels.cuda`)."""
    def load(symbol):
        column = column_of(spec, symbol)
        return f"{symbol} = {table}({column}, {arguments})" if row is None else \
            f"{symbol} = {table}[{row}, {column}]"

    lines = [load(p.symbol) for p in BASE_PARAMETERS] + ["w0sq = g / L"]
    for effect in spec.effects:
        lines += [load(s) for s in effect.symbols]
    return lines
