"""The built-in systems of more than one coordinate, as declarations.

Each function returns a `sweep.physics.system.SystemDeclaration` (plain data: a
Lagrangian as a string, its parameters, its coordinates); `sweep.physics.derive.derive`
turns it into kernel source. Angles are in radians from the downward vertical, times in
seconds, and every parameter is in SI units. Kernel symbols avoid
`sweep.physics.effect.RESERVED_SYMBOLS` (``g`` and ``L`` are the single pendulum's).
"""

from __future__ import annotations

from .effect import Parameter
from .system import Coordinate, SystemDeclaration

__all__ = ["COUPLINGS", "TOPOLOGIES", "coupled_pendula", "double_pendulum"]

COUPLINGS = ("spring", "torsion")
TOPOLOGIES = ("chain", "ring")

_GRAVITY = Parameter("gravity", "gravity", "grav", "m s-2", "m/s^2",
                     "gravitational acceleration", minimum=0.0, strict=True, default=9.81)


def _angle(k: int, what: str) -> Coordinate:
    return Coordinate(f"theta{k}", f"omega{k}", f"th{k}", f"om{k}", long_name=what)


def double_pendulum(damping: bool = False, pivot: bool = False) -> SystemDeclaration:
    """A double pendulum: two point masses on massless rigid rods in a vertical plane.

    The first rod (length ``l1``) hangs from a fixed pivot and carries the mass ``m1``;
    the second (``l2``) hangs from ``m1`` and carries ``m2``. Coordinates: ``theta1``
    and ``theta2`` [rad], the angles of the first and of the second rod from the
    downward vertical (both *absolute*: ``theta2`` is not measured from the first rod),
    with velocities ``omega1``, ``omega2`` [rad/s].

    Parameters
    ----------
    damping : bool
        Add viscous damping at the two joints: a torque ``-c1 omega1`` at the pivot and
        ``-c2 (omega2 - omega1)`` at the middle joint (on the second rod; the first feels
        the opposite), so that the generalized forces are
        ``Q1 = -c1 omega1 + c2 (omega2 - omega1)`` and ``Q2 = -c2 (omega2 - omega1)``
        and the energy falls as ``dE/dt = -c1 omega1^2 - c2 (omega2 - omega1)^2``.
    pivot : bool
        Drive the pivot vertically, ``y_p(t) = a cos(nu t)`` (up): parameters
        ``pivot_amplitude`` a [m] and ``pivot_frequency`` nu [rad/s] (both >= 0,
        default 0). The Lagrangian gains ``y_p'(t) [(m1 + m2) l1 sin(theta1) omega1 +
        m2 l2 sin(theta2) omega2]`` (the terms of ``T`` and ``V`` that depend on time
        alone change no motion and are left out), so that gravity is effectively
        ``g + y_p''(t)`` (Kapitza's pendulum, doubled). The energy is then the
        Lagrangian's Jacobi function, not conserved.

    Returns
    -------
    SystemDeclaration
        ``name="double_pendulum"``; parameters (grid axis, kernel symbol, units,
        default): ``mass1`` m1 [kg] 1, ``mass2`` m2 [kg] 1, ``length1`` l1 [m] 1,
        ``length2`` l2 [m] 1, ``gravity`` grav [m s-2] 9.81, all > 0; with damping also
        ``damping1`` c1 and ``damping2`` c2 [kg m2 s-1, i.e. N m s], >= 0, default 0.

    Notes
    -----
    With the bobs at ``(l1 sin theta1, -l1 cos theta1)`` and ``(l1 sin theta1 +
    l2 sin theta2, -l1 cos theta1 - l2 cos theta2)``::

        T = (m1 + m2) l1^2 omega1^2 / 2 + m2 l2^2 omega2^2 / 2
            + m2 l1 l2 omega1 omega2 cos(theta1 - theta2)
        V = (m1 + m2) grav l1 (1 - cos theta1) + m2 grav l2 (1 - cos theta2)
        L = T - V

    (V is zero hanging at rest, so the energy ``T + V`` [J] is too.) The equations of
    motion, from ``L`` and the joint torques::

        (m1 + m2) l1 theta1'' + m2 l2 cos(theta1 - theta2) theta2''
            = -m2 l2 omega2^2 sin(theta1 - theta2) - (m1 + m2) grav sin theta1 + Q1 / l1
        l2 theta2'' + l1 cos(theta1 - theta2) theta1''
            = l1 omega1^2 sin(theta1 - theta2) - grav sin theta2 + Q2 / (m2 l2)

    The mass matrix' determinant is ``m2 l1^2 l2^2 (m1 + m2 sin^2(theta1 - theta2))``,
    positive for positive masses and lengths.
    """
    positive = {"minimum": 0.0, "strict": True, "default": 1.0}
    parameters = [
        Parameter("mass1", "mass1", "m1", "kg", "kg", "mass of the first bob", **positive),
        Parameter("mass2", "mass2", "m2", "kg", "kg", "mass of the second bob", **positive),
        Parameter("length1", "length1", "l1", "m", "m", "length of the first rod",
                  **positive),
        Parameter("length2", "length2", "l2", "m", "m", "length of the second rod",
                  **positive),
        _GRAVITY,
    ]
    kinetic = ("(m1 + m2)*l1**2*om1**2/2 + m2*l2**2*om2**2/2"
               " + m2*l1*l2*om1*om2*cos(th1 - th2)")
    potential = "(m1 + m2)*grav*l1*(1 - cos(th1)) + m2*grav*l2*(1 - cos(th2))"
    forces = ()
    if damping:
        joint = {"units": "kg m2 s-1", "unit_text": "N m s", "minimum": 0.0, "default": 0.0}
        parameters += [
            Parameter("damping1", "damping1", "c1", long_name="viscous damping coefficient "
                      "of the pivot joint", **joint),
            Parameter("damping2", "damping2", "c2", long_name="viscous damping coefficient "
                      "of the middle joint", **joint),
        ]
        forces = ("-c1*om1 + c2*(om2 - om1)", "-c2*(om2 - om1)")
    drive = ""
    if pivot:
        parameters += [
            Parameter("pivot_amplitude", "pivot_amplitude", "pa", "m", "m",
                      "amplitude a of the pivot's vertical motion a cos(nu t)", minimum=0.0,
                      default=0.0),
            Parameter("pivot_frequency", "pivot_frequency", "pnu", "rad s-1", "rad/s",
                      "angular frequency nu of the pivot's vertical motion", minimum=0.0,
                      default=0.0),
        ]
        drive = (" + (-pa*pnu*sin(pnu*t))*((m1 + m2)*l1*sin(th1)*om1"
                 " + m2*l2*sin(th2)*om2)")
    return SystemDeclaration(
        name="double_pendulum",
        coordinates=(_angle(1, "angle of the first rod from the downward vertical"),
                     _angle(2, "angle of the second rod from the downward vertical")),
        parameters=tuple(parameters),
        lagrangian=f"{kinetic}{drive} - ({potential})",
        forces=forces,
    )


def coupled_pendula(n: int, coupling: str = "spring", topology: str = "chain",
                    damping: bool = False) -> SystemDeclaration:
    """``n`` identical pendula hanging side by side, neighbours coupled by springs.

    Pendulum i (a point mass ``m`` on a massless rod of length ``l``, from its own fixed
    pivot) has the angle ``theta<i>`` [rad] from the downward vertical and velocity
    ``omega<i>`` [rad/s], i = 1..n. Neighbours are i and i + 1 (``"chain"``), and also n
    and 1 (``"ring"``).

    Parameters
    ----------
    n : int
        Number of pendula: at least 2 for a chain, 3 for a ring.
    coupling : {"spring", "torsion"}
        ``"spring"``: a linear spring of stiffness ``k`` [N/m] between neighbouring bobs,
        acting along the horizontal: its extension is the difference of the bobs'
        horizontal displacements, potential ``k/2 (l sin theta_i - l sin theta_j)^2``
        (the usual model of pendula joined by a weak spring at the bobs: it equals a
        straight spring of natural length the pivots' spacing to first order in the
        angles, and needs no spacing parameter). ``"torsion"``: a torsion spring of
        stiffness ``kappa`` [N m/rad] between neighbouring rods, potential
        ``kappa/2 (theta_i - theta_j)^2``.
    topology : {"chain", "ring"}
    damping : bool
        Viscous damping at every pivot: a torque ``-c omega_i`` [N m], ``c`` in N m s.

    Returns
    -------
    SystemDeclaration
        ``name="coupled_pendula_<n>_<coupling>_<topology>"``; parameters (grid axis,
        kernel symbol, units, default): ``mass`` m [kg] 1 (> 0), ``length`` l [m] 1
        (> 0), ``gravity`` grav [m s-2] 9.81 (> 0), ``coupling`` ks [kg s-2, N/m] for a
        spring or kappa [kg m2 s-2, N m/rad] for torsion, default 1, >= 0; with damping
        ``damping`` cd [kg m2 s-1, N m s] default 0, >= 0.

    Raises
    ------
    ValueError
        For an ``n``, ``coupling`` or ``topology`` that is not accepted.

    Notes
    -----
    ::

        L = sum_i [m l^2 omega_i^2 / 2 - m grav l (1 - cos theta_i)] - sum_(i,j) U_ij
        U_ij = ks/2 l^2 (sin theta_i - sin theta_j)^2      (spring)
        U_ij = kappa/2 (theta_i - theta_j)^2               (torsion)

    over neighbouring pairs (i, j). Linearised at rest, two pendula have the normal modes
    ``omega^2 = grav/l`` (in phase) and ``grav/l + 2 ks/m`` (spring) or
    ``grav/l + 2 kappa/(m l^2)`` (torsion) in anti-phase.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ValueError(f"coupled_pendula: n={n!r} is not accepted; accepted: an integer "
                         ">= 2 (>= 3 for a ring)")
    if coupling not in COUPLINGS:
        raise ValueError(f"coupled_pendula: coupling={coupling!r} is not accepted; "
                         f"accepted: {', '.join(map(repr, COUPLINGS))}")
    if topology not in TOPOLOGIES:
        raise ValueError(f"coupled_pendula: topology={topology!r} is not accepted; "
                         f"accepted: {', '.join(map(repr, TOPOLOGIES))}")
    if topology == "ring" and n < 3:
        raise ValueError(f"coupled_pendula: n={n} is not accepted for a ring (pendula 1 "
                         "and 2 would be coupled twice); accepted: n >= 3, or "
                         "topology='chain'")
    positive = {"minimum": 0.0, "strict": True, "default": 1.0}
    if coupling == "spring":
        stiffness = Parameter("coupling", "coupling", "ks", "kg s-2", "N/m",
                              "stiffness of the springs between neighbouring bobs",
                              minimum=0.0, default=1.0)
        term = "ks/2*l**2*(sin(th{i}) - sin(th{j}))**2"
    else:
        stiffness = Parameter("coupling", "coupling", "kappa", "kg m2 s-2", "N m/rad",
                              "stiffness of the torsion springs between neighbouring rods",
                              minimum=0.0, default=1.0)
        term = "kappa/2*(th{i} - th{j})**2"
    parameters = [
        Parameter("mass", "mass", "m", "kg", "kg", "mass of each bob", **positive),
        Parameter("length", "length", "l", "m", "m", "length of each rod", **positive),
        _GRAVITY,
        stiffness,
    ]
    pairs = [(i, i + 1) for i in range(1, n)] + ([(n, 1)] if topology == "ring" else [])
    pendula = " + ".join(f"m*l**2*om{i}**2/2 - m*grav*l*(1 - cos(th{i}))"
                         for i in range(1, n + 1))
    springs = " + ".join(term.format(i=i, j=j) for i, j in pairs)
    forces = ()
    if damping:
        parameters.append(Parameter("damping", "damping", "cd", "kg m2 s-1", "N m s",
                                    "viscous damping coefficient of each pivot",
                                    minimum=0.0, default=0.0))
        forces = tuple(f"-cd*om{i}" for i in range(1, n + 1))
    return SystemDeclaration(
        name=f"coupled_pendula_{n}_{coupling}_{topology}",
        coordinates=tuple(_angle(i, f"angle of pendulum {i} from the downward vertical")
                          for i in range(1, n + 1)),
        parameters=tuple(parameters),
        lagrangian=f"{pendula} - ({springs})",
        forces=forces,
    )
