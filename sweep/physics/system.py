"""A system: coordinates, parameters and dynamics, declared once as plain data.

The single pendulum (`sweep.Scene`) has one coordinate, ``theta``; a *system* has
any number: a double pendulum ``theta1, theta2``, a chain of coupled pendula, a swing
network. A `SystemDeclaration` says, once, everything the kernel generator, the grid,
the dataset and the maps need:

- its coordinates (`Coordinate`): names, kernel symbols, units, angular or not;
- its parameters (`sweep.physics.Parameter`, as an effect's): grid axis, kernel symbol,
  units, bounds, default;
- its dynamics, as a **Lagrangian** (a SymPy expression written as a string in the
  coordinates' and velocities' kernel symbols, the parameters' symbols and ``t``) plus
  generalized forces per coordinate (damping at a joint, a drive), or directly as
  **accelerations** (one expression per coordinate).

`derive` turns a declaration into a `DerivedSystem`: plain kernel-source strings for
the accelerations (mass matrix solved in closed form), the energy and, where asked,
the Jacobian of the accelerations. SymPy is imported only there; everything else is
strings, numbers and tuples, so declarations hash, compare and pickle (a kernel spec
carries one; a Dask worker needs no SymPy).

Kernel-source conventions of `DerivedSystem` (what the generator relies on):

- names: position ``<coordinate.symbol>`` (``th1``), velocity
  ``<coordinate.velocity_symbol>`` (``om1``), each parameter's ``symbol``, time ``t``;
- functions: ``vsin``, ``vcos``, ``vsincos`` (returns ``(sin x, cos x)`` from one
  argument reduction), ``vfma(a, b, c)`` (``a * b + c``, one rounding), ``math.sqrt``;
  no other call;
- ``accel_lines``: statements; temporaries are named ``x<k>`` (SymPy's ``cse``); the
  last statements assign ``acc_<symbol>`` for every coordinate, in coordinate order;
- ``energy_lines``: statements ending with ``energy_value = ...`` (kinetic plus
  potential energy, the Lagrangian's units);
- ``jacobian_lines`` (empty when not derived): statements ending with
  ``jac_<a>_<b> = ...``, the derivative of ``acc_<a>`` with respect to state
  variable ``<b>`` (a position or velocity symbol), for every pair.
"""

from __future__ import annotations

from dataclasses import dataclass

from .effect import Parameter

__all__ = ["Coordinate", "DerivedSystem", "SystemDeclaration"]


@dataclass(frozen=True)
class Coordinate:
    """One generalized coordinate of a system.

    Attributes
    ----------
    name : str
        Its name in datasets (``"theta1"``): grid axes ``<name>_0`` and
        ``<velocity>_0``, outputs ``<name>_final``, saved variable ``<name>``.
    velocity : str
        Name of its velocity in datasets (``"omega1"``).
    symbol, velocity_symbol : str
        Kernel variables of the position and the velocity (``"th1"``, ``"om1"``).
    units, velocity_units : str
        UDUNITS strings (``"rad"``, ``"rad s-1"``).
    long_name : str
        What it is (``"angle of the first rod from the downward vertical"``).
    angular : bool
        An angle (winding, flips, sines of it are meaningful; TOML accepts degrees).
    """

    name: str
    velocity: str
    symbol: str
    velocity_symbol: str
    units: str = "rad"
    velocity_units: str = "rad s-1"
    long_name: str = ""
    angular: bool = True


@dataclass(frozen=True)
class DerivedSystem:
    """A system's dynamics as kernel source (see the module docstring's conventions).

    Attributes
    ----------
    accel_lines : tuple of str
    energy_lines : tuple of str
    jacobian_lines : tuple of str
    """

    accel_lines: tuple[str, ...]
    energy_lines: tuple[str, ...]
    jacobian_lines: tuple[str, ...] = ()


@dataclass(frozen=True)
class SystemDeclaration:
    """Everything sweep needs to know about a system, as plain data.

    Attributes
    ----------
    name : str
        Identifier (``"double_pendulum"``).
    coordinates : tuple of Coordinate
    parameters : tuple of sweep.physics.Parameter
        Per-trajectory parameters (grid axes), in table-column order after the initial
        state.
    lagrangian : str, optional
        The Lagrangian as a SymPy-parsable string in the kernel symbols.
    forces : tuple of str, optional
        Generalized force on each coordinate (same symbols; ``"0"`` for none), added to
        the Euler-Lagrange equations' right-hand side.
    accelerations : tuple of str, optional
        Instead of a Lagrangian: each coordinate's acceleration, as a SymPy-parsable
        string.
    potential : str, optional
        With ``accelerations``: the potential energy (kinetic energy is then taken as
        ``sum(v**2) / 2``); None: no energy.
    """

    name: str
    coordinates: tuple[Coordinate, ...]
    parameters: tuple[Parameter, ...]
    lagrangian: str | None = None
    forces: tuple[str, ...] = ()
    accelerations: tuple[str, ...] = ()
    potential: str | None = None
