"""A system of the user's own: any `SystemDeclaration` (a Lagrangian with generalized
forces, or accelerations), run by `sweep.run` like the built-in systems.

The built-ins (`sweep.DoublePendulum`, `sweep.CoupledPendula`) are classes with a field
per parameter; `DeclaredSystem` takes the declaration itself and the parameters' values
as keywords. Its grid axes (``<coordinate>_0``, ``<velocity>_0``, the parameters' axes)
are known to `sweep.Grid`, `sweep.Points` and `sweep.sample` once a `DeclaredSystem` of
that declaration exists in the process (create the system before its grid).
"""

from __future__ import annotations

import dataclasses
import json
import math

from .effect import Parameter
from .system import (
    DerivedSystem,
    System,
    SystemDeclaration,
    register_system,
    system_parameters,
)

__all__ = ["DeclaredSystem"]

#: Declarations of the DeclaredSystems made in this process, by name: their axes.
_DECLARED: dict[str, SystemDeclaration] = {}


@register_system
class DeclaredSystem(System):
    """A system declared by the user: coordinates, parameters and a Lagrangian (or
    accelerations), with the parameters' values.

    Parameters
    ----------
    declaration : sweep.physics.SystemDeclaration
        Checked and derived at once (`sweep.physics.derive.derive`: SymPy, extra
        ``systems``, unless derived before on this machine): a bad declaration raises
        here, before any grid or compile.
    effects : tuple, default ()
        `sweep.Damping(c)`: every acceleration gains ``- c v_i`` (c in 1/s). With
        ``on="<coordinate>"``, `sweep.Damping`, `sweep.Torque`, `sweep.Forcing` and
        `sweep.QuadraticDrag` are a
        generalized force on that coordinate (`sweep.physics.coordinate_effects`).
    drive_frequency_axis : str, optional
        The axis name of the parameter that is the angular frequency ``nu`` [rad/s] of a
        periodic drive the dynamics contain (a term in ``t`` of period ``2 pi / nu``):
        the ``strobe`` observable then samples the state once per that period. None
        (default): no periodic drive declared, and ``strobe`` is refused.
    **values : float
        A value for each of the declaration's parameters, by its axis name, in the
        parameter's units; a parameter left out takes its ``default`` (an error if it
        has none).

    Raises
    ------
    ValueError
        A bad declaration; a value missing, unknown or outside the parameter's
        accepted range; another declaration already registered under the same name.
    TypeError
        If ``declaration`` is not a `SystemDeclaration`.

    Notes
    -----
    Every coordinate is integrated; ``winding`` and ``flip`` read the angular ones
    (`sweep.physics.Coordinate.angular`). ``energy`` is the Lagrangian's Jacobi function
    (kinetic plus potential energy for a time-independent one), in the declaration's
    units (``energy_units``, default "J"). A run file declares one with ``[system]
    kind = "DeclaredSystem"`` (`sweep.toml_declared`); `sweep.explore` takes it. The
    dataset's reload (`sweep.io.scene_from`) does not.

    Examples
    --------
    A pendulum on a cart held by a spring, the cart's position ``x`` not an angle:

    >>> import sweep
    >>> from sweep.physics import Coordinate, Parameter, SystemDeclaration
    >>> cart = SystemDeclaration(
    ...     name="pendulum_on_cart",
    ...     coordinates=(Coordinate("theta", "omega", "q", "w"),
    ...                  Coordinate("x", "v", "xc", "vc", units="m", velocity_units="m s-1",
    ...                             angular=False)),
    ...     parameters=(Parameter("stiffness", "stiffness", "kc", "kg s-2", "N/m",
    ...                           "spring constant", minimum=0.0, default=10.0),),
    ...     lagrangian="(2*vc**2 + 2*vc*w*cos(q) + w**2)/2 - kc*xc**2/2 + 9.81*cos(q)")
    >>> system = sweep.DeclaredSystem(cart, stiffness=5.0)       # doctest: +SKIP
    """

    def __init__(self, declaration: SystemDeclaration, effects=(), *,
                 drive_frequency_axis: str | None = None, **values) -> None:
        if not isinstance(declaration, SystemDeclaration):
            raise TypeError(f"DeclaredSystem takes a sweep.physics.SystemDeclaration, got "
                            f"{type(declaration).__name__}")
        from .derive import derive

        derive(declaration)  # refuses a bad declaration now, before any grid or compile
        known = _DECLARED.get(declaration.name)
        if known is not None and known != declaration:
            raise ValueError(f"DeclaredSystem: another declaration named "
                             f"{declaration.name!r} exists in this process; accepted: a "
                             "distinct name per declaration (their grid axes differ)")
        axes = [p.axis for p in declaration.parameters]
        unknown = sorted(set(values) - set(axes))
        if unknown:
            raise ValueError(f"DeclaredSystem {declaration.name!r}: unknown parameter "
                             f"{unknown[0]!r}; accepted: {', '.join(axes) or 'none'}")
        object.__setattr__(self, "_declaration", declaration)
        for p in declaration.parameters:
            value = values.get(p.axis, p.default)
            if value is None:
                raise ValueError(f"DeclaredSystem {declaration.name!r}: parameter "
                                 f"{p.axis!r} has no default and was not given; accepted: "
                                 f"{p.accepted()}")
            object.__setattr__(self, p.axis, value)
        if drive_frequency_axis is not None and drive_frequency_axis not in axes:
            raise ValueError(f"DeclaredSystem {declaration.name!r}: drive_frequency_axis = "
                             f"{drive_frequency_axis!r} names no parameter; accepted: None "
                             f"or one of {', '.join(map(repr, axes)) or 'none'}")
        object.__setattr__(self, "_drive", drive_frequency_axis)
        object.__setattr__(self, "effects", effects)
        self._check_parameters()
        _DECLARED[declaration.name] = declaration

    def __setattr__(self, name, value):
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")

    def _values(self) -> tuple:
        return tuple(getattr(self, p.axis) for p in self._declaration.parameters)

    def __eq__(self, other) -> bool:
        return (type(other) is DeclaredSystem and other._declaration == self._declaration
                and other._values() == self._values() and other.effects == self.effects
                and other._drive == self._drive)

    def __hash__(self) -> int:
        return hash((self._declaration, self._values(), self.effects, self._drive))

    def __repr__(self) -> str:
        values = ", ".join(f"{p.axis}={getattr(self, p.axis)!r}"
                           for p in self._declaration.parameters)
        effects = f", effects={self.effects!r}" if self.effects else ""
        drive = f", drive_frequency_axis={self._drive!r}" if self._drive else ""
        return (f"DeclaredSystem({self._declaration.name!r}"
                f"{', ' + values if values else ''}{effects}{drive})")

    def __reduce__(self):  # pickling (Dask): the declaration, the values, the effects
        return (_rebuild, (self._declaration, self.effects,
                           {p.axis: getattr(self, p.axis)
                            for p in self._declaration.parameters}, self._drive))

    @property
    def drive_frequency_parameter(self) -> Parameter | None:
        """The parameter named by ``drive_frequency_axis``, else the frequency of a
        forcing on one coordinate (`System.drive_frequency_parameter`), or None."""
        if self._drive is None:
            return super().drive_frequency_parameter
        return {p.axis: p for p in self._declaration.parameters}.get(self._drive)

    def derived(self, jacobian: bool = False) -> DerivedSystem:
        """Its equations as kernel source, its effects on coordinates included
        (`sweep.physics.derive.derive_system`)."""
        from .derive import derive_system

        return derive_system(self, jacobian)

    @property
    def declaration(self) -> SystemDeclaration:
        """The declaration it was made with."""
        return self._declaration

    @property
    def title(self) -> str:
        """What a dataset's title calls it: the declaration's name."""
        return self._declaration.name

    @classmethod
    def axis_parameter(cls, name: str) -> Parameter | None:
        """The parameter whose axis is ``name`` in any declaration a DeclaredSystem was
        made with in this process, or None."""
        for declaration in _DECLARED.values():
            found = {p.axis: p for p in system_parameters(declaration, True)}.get(name)
            if found is not None:
                return found
        return None

    def _with_effects(self, effects: tuple) -> DeclaredSystem:
        """This system with ``effects`` instead of its own (its drive kept)."""
        return _rebuild(self._declaration, tuple(effects),
                        {p.axis: getattr(self, p.axis) for p in self._declaration.parameters},
                        self._drive)

    def to_dict(self) -> dict:
        """A JSON-able description (dataset attribute ``system``), with the declaration."""
        spec = super().to_dict()
        spec["declaration"] = json.loads(json.dumps(dataclasses.asdict(self._declaration),
                                                    default=_plain))
        if self._drive is not None:
            spec["drive_frequency_axis"] = self._drive
        return spec


def _plain(value):
    """JSON for what `dataclasses.asdict` leaves (non-finite floats as strings)."""
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)
    return str(value)


def _rebuild(declaration, effects, values, drive=None) -> DeclaredSystem:
    return DeclaredSystem(declaration, effects=effects, drive_frequency_axis=drive, **values)
