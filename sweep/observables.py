"""Streaming per-trajectory observables: what each one stores and how it accumulates.

An observable is data: the variables it writes (name, units, long name) and three
snippets of kernel source -- ``init`` (once, with the initial state in ``th, om``),
``update`` (at every step whose time is >= ``t0 + t_transient``, state in ``th, om``)
and ``final`` (once, writing ``out[i, COL + k]`` for its k-th variable). `sweep.kernels`
pastes in only the snippets of the observables a run asks for, so a run that observes
only the final state keeps no running maxima.

Names available to the snippets: ``th, om`` (state, unwrapped angle), ``th0, om0``
(initial state), ``L, g`` (length, gravity), ``w0sq = g/L``, ``W`` (forcing frequency),
``energy(th, om, w0sq)`` (the mechanical energy per unit ``m L^2`` of the scene's
model), ``vsin``/``vcos`` (`sweep.kernels.vecmath`: vectorisable, use them rather than
``math.sin``/``math.cos``), ``k_state`` (step index of the state), ``dt``, ``t0`` and
``TWO_PI``; the text ``TENSION_TERMS`` becomes the rod-tension terms the scene's effects
declare (nothing for damping and forcing). Snippets are per trajectory: ``out[i, ...]`` is
this trajectory's row.

Every variable that lives from one snippet to the next (set in ``init``, read in
``update``, ``settled`` or ``final``) is declared in ``state`` with its dtype: the
kernels (fixed-step, refill and adaptive) integrate trajectories in blocks of SIMD
lanes with the time loop outside the lane loop, so such a variable becomes one array
element per lane.

Memory is O(number of trajectories): one row of ``out`` per trajectory, whatever the
number of steps.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["COMMENTS", "Observable", "OBSERVABLES", "DEFAULT_OBSERVE", "resolve",
           "variable_attributes"]


@dataclass(frozen=True)
class Observable:
    """A streaming per-trajectory reduction.

    Attributes
    ----------
    name : str
        The key users pass in ``observe=``.
    variables : tuple of (name, units, long_name)
        The dataset variables it writes, in order.
    init, update, final : str
        Kernel source snippets (see the module docstring).
    steady : bool
        True if it accumulates only over ``t >= t0 + t_transient``.
    uses_energy : bool
        True if a snippet calls ``energy(th, om, w0sq)``.
    samples : int
        Columns per variable: 1 for a scalar, more for a variable with an extra
        dimension ``sample_dim`` (variable k occupies ``COL + k*samples ...``); the
        default when ``sample_option`` is set.
    sample_option : str or None
        The `sweep.kernels.KernelSpec` field (and `sweep.run` argument) that sets the
        number of samples; the snippets read it as ``NSTROBE``.
    sample_dim : str or None
        Name of that extra dimension.
    requires_forcing : bool
        True if the snippets read the forcing frequency ``W``.
    settled : str
        Optional snippet that sets ``SETTLED`` to True once the observable's answer can
        no longer change; with ``run(..., stop_early=True)`` a trajectory stops when
        every observed observable is settled (only observables that have one may be
        observed then).
    unforced_only : bool
        True if the observable's meaning needs an unforced scene.
    state : tuple of (name, dtype)
        Variables kept per trajectory between snippets (numpy dtype names:
        ``"float64"``, ``"int64"``, ``"bool_"``); every name assigned in ``init``
        (other than loop variables) must be here.
    tangent : bool
        True if it reads the tangent dynamics: the fixed-step explicit kernels then
        integrate two tangent vectors ``(ly_u1, ly_v1)``, ``(ly_u2, ly_v2)`` beside
        the state, with the same method (`sweep.kernels.steppers.rk_stages`), from
        the Jacobian terms the effects declare; set them in ``init``.
    renormalise : str
        Snippet run every ``renormalise_every`` steps from the start (the transient
        included), at the first step of the steady window and at the last step; the
        name ``keep`` is True when the segment since the last run lies in the steady
        window (``t >= t0 + t_transient``).
    renormalise_every : int
        Steps between runs of ``renormalise``.
    finite : str
        An expression that must be True for the trajectory's outputs to count as
        finite (beside the state being finite); a False makes its status
        ``NONFINITE``.
    alternative : bool
        With ``stop_early``, its ``settled`` alone is enough to stop: a trajectory
        stops when every other observed observable is settled *or* any alternative
        one is (``attractor``: a match with a known attractor answers the question
        the ``strobe`` test answers more slowly).
    phase : str
        The state variable that ``update`` keeps as the steps since the steady
        window's start modulo the forcing period's steps, if ``update`` does nothing
        else while it is not 0 (and ``settled`` changes only where it is 0): a kernel
        may then run ``update`` and ``settled`` only at those stroboscopic steps,
        setting it to 0 first (`sweep.kernels.refill` with known cells).
    """

    name: str
    variables: tuple[tuple[str, str, str], ...]
    init: str = ""
    update: str = ""
    final: str = ""
    steady: bool = False
    uses_energy: bool = False
    samples: int = 1
    sample_option: str | None = None
    sample_dim: str | None = None
    requires_forcing: bool = False
    settled: str = ""
    unforced_only: bool = False
    state: tuple[tuple[str, str], ...] = ()
    tangent: bool = False
    renormalise: str = ""
    renormalise_every: int = 0
    finite: str = ""
    alternative: bool = False
    phase: str = ""

    def n_samples(self, spec=None) -> int:
        """Columns per variable for a kernel spec (its ``sample_option`` field), or
        the default without one."""
        if self.sample_option is None or spec is None:
            return self.samples
        return getattr(spec, self.sample_option)

    def n_columns(self, spec=None) -> int:
        """Columns of the kernel's ``out`` array this observable fills."""
        return len(self.variables) * self.n_samples(spec)


#: Stroboscopic samples kept per trajectory by the ``strobe`` observable by default
#: (``sweep.run(..., strobe_samples=N)`` changes it): enough to recognise periods up to
#: STROBE_SAMPLES // 2 forcing periods. The snippets read the count as ``NSTROBE``.
STROBE_SAMPLES = 16

#: Bounds of ``strobe_samples``: two samples are the least that show a period, and
#: 4096 x 2 columns (64 KiB per trajectory) the most a run keeps.
STROBE_SAMPLES_RANGE = (2, 4096)

#: Longest period (forcing periods) the ``strobe`` early-stop test looks for: a longer
#: one is rare and the test costs O(N p) per forcing period.
STROBE_MAX_PERIOD = 8

#: Periodicity tolerance [rad, rad/s] of the strobe observable's early-stop test.
#: Tight on purpose: a start near the stable manifold of an *unstable* periodic orbit
#: repeats it for a while before it leaves, and the chance of repeating it for 16
#: periods shrinks with the tolerance. At 1e-4, 2 of 48,000 starts of the 1200^2
#: forced map stopped on an unstable period-2 orbit; at 1e-8, none, and a stable
#: orbit (contracting geometrically) needs only a few more periods to get there
#: (`benchmarks/forced_basins.py`: about 32 s -> 45 s for the whole map).
STROBE_TOL = 1e-8

#: The same test's tolerance in a ``dtype="float32"`` run, ``(absolute, relative)``:
#: |difference| < 1e-6 + 2**-21 |x| [rad, rad/s]. 1e-8 is below float32's resolution
#: (an angular velocity of 1.8 rad/s is held to 1.2e-7), so with it ``stop_early``
#: would never stop. A converged float32 stroboscopic sequence repeats to about one
#: float32 ulp of the velocity (measured on a forced map: at most 1.4e-7; the angle is
#: float64, see `sweep.kernels.precision`), so this bound, ~14 ulps at 1.8 rad/s, is met
#: soon after convergence while staying 100x tighter than the maps' default tolerance.
#: The relative part covers faster velocities.
STROBE_TOL_FLOAT32 = (1e-6, 2.0**-21)

#: Tolerance [rad, rad/s] of the ``attractor`` observable's match of a stroboscopic
#: point with a catalogued attractor's point (angle modulo 2 pi): the maps' default
#: identity tolerance (`sweep.maps.basins`), so a match is what `maps.basins` would
#: call the same attractor.
ATTRACTOR_TOL = 1e-3

#: Forcing periods running on which a stroboscopic point must match the successive
#: points of one catalogued attractor's orbit before the ``attractor`` observable
#: settles. One match can be a transient passing by; a run of them, each at the orbit's
#: next point, is a trajectory moving with the attractor (and contracting onto it:
#: `benchmarks/forced_basins.py` checks every start of the 1200^2 map against the full
#: run).
ATTRACTOR_MATCHES = 3

#: Forcing periods running on which a trajectory's stroboscopic point must fall in known
#: cells of one label before it stops there (`sweep.run(..., known_cells=...)`,
#: `sweep.maps.refine(..., known_cells=True)`; the kernels' `KernelSpec.known_cells`).
#: Measured on the 1200^2 Wada map and the Baker-Gollub map (docs/guide/refine.md).
KNOWN_HITS = 3

#: Hits running that stop a trajectory in a known cell by how far its label reaches:
#: entry r where every cell within r rows and columns of the map of known cells holds
#: its label (r = 0: the cell alone, `KNOWN_HITS`; the last entry for any larger r;
#: `sweep._known.hits_needed`). Each entry is at most 3 (the kernel keeps it in two
#: bits). Measured on the 1200^2 Wada map (docs/guide/refine.md): with (3, 2, 1) no start
#: is labelled differently from the full run, and the map's trajectories run 16 % fewer
#: periods than with 3 hits everywhere.
KNOWN_HITS_BY_DEPTH = (KNOWN_HITS, 2, 1)

#: Steps between renormalisations of the ``lyapunov`` observable's tangent vectors. A
#: stable RK4 step (|z| <= 2.83) grows a tangent vector by at most ~14 (the stability
#: polynomial's modulus there), so 64 steps stay below 14**64 ~ 1e73, far from
#: overflow (1e308); and a renormalisation (a square root, two logarithms per lane)
#: every 64 steps costs little beside 64 steps of four stages. The result does not
#: depend on it beyond rounding (the product of the step Jacobians is the same).
LYAPUNOV_EVERY = 64

OBSERVABLES: dict[str, Observable] = {
    o.name: o
    for o in (
        Observable(
            name="final",
            variables=(
                ("theta_final", "rad", "angle at t_end, unwrapped (not reduced modulo 2 pi)"),
                ("omega_final", "rad s-1", "angular velocity at t_end"),
            ),
            final="out[i, COL] = th\nout[i, COL + 1] = om",
        ),
        Observable(
            name="winding",
            variables=(
                ("winding", "1", "wells crossed from t0 to t_end"),
            ),
            # the well index k (rest at 2 pi k) of the end minus that of the start. It
            # changes by +-1 exactly where the angle crosses a top, so it is the net count
            # of those crossings, whatever the path between steps; a pendulum that never
            # crosses one (a libration) gets 0, wherever it starts or stops in its well.
            # round() is half to even on every target (llvm.rint on the CPU, libdevice's
            # llrint on CUDA, np.round in the maps), odd (mirror starts give opposite
            # windings) and puts the edges theta0 = +-pi of a [-pi, pi] grid in well 0.
            final="out[i, COL] = round(th / TWO_PI) - round(th0 / TWO_PI)",
        ),
        Observable(
            name="theta_max",
            variables=(("theta_max", "rad", "max |theta| over t >= t0 + t_transient"),),
            init="acc_abs_max = 0.0",
            update="acc_abs_max = max(acc_abs_max, abs(th))",
            final="out[i, COL] = acc_abs_max",
            steady=True,
            state=(("acc_abs_max", "float64"),),
        ),
        Observable(
            name="amplitude",
            variables=(
                ("amplitude", "rad",
                 "half peak-to-peak of theta over t >= t0 + t_transient"),
            ),
            init="acc_th_max = -math.inf\nacc_th_min = math.inf",
            update="acc_th_max = max(acc_th_max, th)\nacc_th_min = min(acc_th_min, th)",
            final="out[i, COL] = 0.5 * (acc_th_max - acc_th_min)",
            steady=True,
            state=(("acc_th_max", "float64"), ("acc_th_min", "float64")),
        ),
        Observable(
            name="omega_mean",
            variables=(
                ("omega_mean", "rad s-1", "mean angular velocity over t >= t0 + t_transient"),
            ),
            init="acc_n_steady = 0\nacc_th_steady = th",
            update=(
                "if acc_n_steady == 0:\n"
                "    acc_th_steady = th\n"
                "acc_n_steady += 1"
            ),
            final="out[i, COL] = (th - acc_th_steady) / ((acc_n_steady - 1) * dt)",
            steady=True,
            state=(("acc_n_steady", "int64"), ("acc_th_steady", "float64")),
        ),
        Observable(
            name="strobe",
            variables=(
                ("strobe_theta", "rad", "angle at the last strobe_samples forcing periods"),
                ("strobe_omega", "rad s-1",
                 "angular velocity at the last strobe_samples forcing periods"),
            ),
            # a ring of the last NSTROBE samples; `final` rotates it oldest-first
            init=(
                "acc_sb_S = round(TWO_PI / (W * dt))\n"
                "acc_sb_k = 0\n"
                "acc_sb_m = 0\n"
                "acc_sb_new = False\n"
                "for acc_sb_q in range(2 * NSTROBE):\n"
                "    out[i, COL + acc_sb_q] = math.nan"
            ),
            update=(
                # acc_sb_k counts steps modulo acc_sb_S (no integer division per step)
                "acc_sb_new = acc_sb_k == 0\n"
                "if acc_sb_new:\n"
                "    acc_sb_col = acc_sb_m % NSTROBE\n"
                "    out[i, COL + acc_sb_col] = th\n"
                "    out[i, COL + NSTROBE + acc_sb_col] = om\n"
                "    acc_sb_m += 1\n"
                "acc_sb_k += 1\n"
                "if acc_sb_k == acc_sb_S:\n"
                "    acc_sb_k = 0"
            ),
            final=(
                # rotate each block left by r = m mod N (three reversals, in place)
                "acc_sb_r = acc_sb_m % NSTROBE\n"
                "if acc_sb_r:\n"
                "    for acc_sb_b in range(2):\n"
                "        acc_sb_o = COL + NSTROBE * acc_sb_b\n"
                "        for acc_sb_j in range(acc_sb_r // 2):\n"
                "            acc_sb_x = acc_sb_o + acc_sb_j\n"
                "            acc_sb_y = acc_sb_o + acc_sb_r - 1 - acc_sb_j\n"
                "            out[i, acc_sb_x], out[i, acc_sb_y] = "
                "out[i, acc_sb_y], out[i, acc_sb_x]\n"
                "        for acc_sb_j in range((NSTROBE - acc_sb_r) // 2):\n"
                "            acc_sb_x = acc_sb_o + acc_sb_r + acc_sb_j\n"
                "            acc_sb_y = acc_sb_o + NSTROBE - 1 - acc_sb_j\n"
                "            out[i, acc_sb_x], out[i, acc_sb_y] = "
                "out[i, acc_sb_y], out[i, acc_sb_x]\n"
                "        for acc_sb_j in range(NSTROBE // 2):\n"
                "            acc_sb_x = acc_sb_o + acc_sb_j\n"
                "            acc_sb_y = acc_sb_o + NSTROBE - 1 - acc_sb_j\n"
                "            out[i, acc_sb_x], out[i, acc_sb_y] = "
                "out[i, acc_sb_y], out[i, acc_sb_x]"
            ),
            # settled: the ring is full and periodic with some p <= min(N/2, STROBE_MAX_PERIOD)
            # within STROBE_TOL (STROBE_TOL_FLOAT32 in a float32 kernel; the kernel
            # generator writes ``STROBE_TOL(x)`` out as the working precision's bound)
            # (far tighter than the maps' default tolerance, so a stopped trajectory is
            # classified as it would be after a full run; see STROBE_TOL)
            settled=(
                "SETTLED = False\n"
                "if acc_sb_new and acc_sb_m >= NSTROBE:\n"
                f"    for acc_sb_p in range(1, min(NSTROBE // 2, {STROBE_MAX_PERIOD}) + 1):\n"
                "        acc_sb_a = (acc_sb_m - 1) % NSTROBE\n"
                "        acc_sb_z = (acc_sb_m - 1 - acc_sb_p) % NSTROBE\n"
                "        acc_sb_turns = round((out[i, COL + acc_sb_a] - out[i, COL + acc_sb_z])"
                " / TWO_PI)\n"
                "        acc_sb_periodic = True\n"
                "        for acc_sb_j in range(NSTROBE - acc_sb_p):\n"
                "            acc_sb_x = (acc_sb_m + acc_sb_j) % NSTROBE\n"
                "            acc_sb_y = (acc_sb_m + acc_sb_j + acc_sb_p) % NSTROBE\n"
                "            if abs(out[i, COL + acc_sb_y] - out[i, COL + acc_sb_x] - TWO_PI * "
                "acc_sb_turns) >= STROBE_TOL(out[i, COL + acc_sb_y]) or abs(out[i, COL + NSTROBE + "
                "acc_sb_y] - out[i, COL + NSTROBE + acc_sb_x]) >= "
                "STROBE_TOL(out[i, COL + NSTROBE + acc_sb_y]):\n"
                "                acc_sb_periodic = False\n"
                "                break\n"
                "        if acc_sb_periodic:\n"
                "            SETTLED = True\n"
                "            break"
            ),
            steady=True,
            samples=STROBE_SAMPLES,
            sample_option="strobe_samples",
            sample_dim="strobe",
            requires_forcing=True,
            state=(("acc_sb_S", "int64"), ("acc_sb_k", "int64"), ("acc_sb_m", "int64"),
                   ("acc_sb_new", "bool_")),
            phase="acc_sb_k",
        ),
        Observable(
            name="attractor",
            variables=(
                ("attractor", "1", "index of the attractor settled on (-1: none)"),
            ),
            # the catalogue is the kernel's argument ``catalogue`` (after ``saved``, or
            # ``stats``; `sweep.kernels.snippets.catalogue_argument`): per point of the
            # orbits, its angle in [0, 2 pi), velocity, the orbit's next point and its
            # attractor; the kernel's text does not depend on it. The scan runs from the
            # last point down, without a break and with `&` (no branch but the loop's),
            # so the first matching point wins, as a forward scan with a break would
            # find it: with the points in memory that loop matched the speed of the
            # constants it replaced (the break cost the catalogue map 1.5-2 % CPU,
            # Zen 5, single thread)
            init=(
                "acc_at_S = round(TWO_PI / (W * dt))\n"
                "acc_at_k = 0\n"
                "acc_at_j = 0\n"
                "acc_at_n = 0"
            ),
            update=(
                "if acc_at_k == 0 and acc_at_n < ATTRACTOR_MATCHES:\n"
                "    acc_at_w = th - TWO_PI * math.floor(th / TWO_PI)\n"
                "    acc_at_q = -1\n"
                "    for acc_at_c in range(catalogue.shape[0] - 1, -1, -1):\n"
                "        acc_at_d = abs(acc_at_w - catalogue[acc_at_c, 0])\n"
                "        if (abs(om - catalogue[acc_at_c, 1]) < ATTRACTOR_TOL) & "
                "(min(acc_at_d, TWO_PI - acc_at_d) < ATTRACTOR_TOL):\n"
                "            acc_at_q = acc_at_c\n"
                "    if acc_at_q < 0:\n"
                "        acc_at_n = 0\n"
                "    elif acc_at_n > 0 and acc_at_q == catalogue[acc_at_j, 2]:\n"
                "        acc_at_n += 1\n"
                "    else:\n"
                "        acc_at_n = 1\n"
                "    acc_at_j = max(acc_at_q, 0)\n"
                "acc_at_k += 1\n"
                "if acc_at_k == acc_at_S:\n"
                "    acc_at_k = 0"
            ),
            final="out[i, COL] = catalogue[acc_at_j, 3] if acc_at_n >= ATTRACTOR_MATCHES else -1",
            settled="SETTLED = acc_at_n >= ATTRACTOR_MATCHES",
            steady=True,
            requires_forcing=True,
            alternative=True,
            state=(("acc_at_S", "int64"), ("acc_at_k", "int64"), ("acc_at_j", "int64"),
                   ("acc_at_n", "int64")),
            phase="acc_at_k",
        ),
        Observable(
            name="capture",
            variables=(
                ("well", "1", "potential well k captured in (rest at theta = 2 pi k)"),
                ("capture_time", "s", "time of capture in a well"),
            ),
            init="acc_cap = False\nacc_well = math.nan\nacc_tcap = math.nan",
            update=(
                "if not acc_cap and energy(th, om, w0sq) < 2.0 * w0sq:\n"
                "    acc_cap = True\n"
                "    acc_well = float(round(th / TWO_PI))\n"
                "    acc_tcap = t0 + k_state * dt"
            ),
            final="out[i, COL] = acc_well\nout[i, COL + 1] = acc_tcap",
            settled="SETTLED = acc_cap",
            steady=True,
            uses_energy=True,
            unforced_only=True,
            state=(("acc_cap", "bool_"), ("acc_well", "float64"), ("acc_tcap", "float64")),
        ),
        Observable(
            name="tension",
            variables=(
                ("tension_min", "m s-2", "min rod tension per unit mass T/m"),
                ("tension_max", "m s-2", "max rod tension per unit mass T/m"),
            ),
            init="acc_T_min = math.inf\nacc_T_max = -math.inf",
            update=(
                "tension = L * om * om + g * vcos(th)TENSION_TERMS\n"
                "acc_T_min = min(acc_T_min, tension)\n"
                "acc_T_max = max(acc_T_max, tension)"
            ),
            final="out[i, COL] = acc_T_min\nout[i, COL + 1] = acc_T_max",
            steady=True,
            state=(("acc_T_min", "float64"), ("acc_T_max", "float64")),
        ),
        Observable(
            name="energy",
            variables=(
                ("energy_initial", "s-2", "mechanical energy per unit m L^2 at t0"),
                ("energy_final", "s-2", "mechanical energy per unit m L^2 at t_end"),
            ),
            init="acc_E0 = energy(th, om, w0sq)",
            final="out[i, COL] = acc_E0\nout[i, COL + 1] = energy(th, om, w0sq)",
            uses_energy=True,
            state=(("acc_E0", "float64"),),
        ),
        Observable(
            name="top_distance",
            variables=(
                ("top_distance_max", "rad", "max distance from the upright position"),
            ),
            init="acc_top = 0.0",
            # theta - pi reduced to [-pi, pi): np.floor keeps it branch-free (vectorised)
            update=("acc_top = max(acc_top, abs(th - math.pi - TWO_PI * "
                    "np.floor((th - math.pi) / TWO_PI + 0.5)))"),
            final="out[i, COL] = acc_top",
            steady=True,
            state=(("acc_top", "float64"),),
        ),
        Observable(
            name="lyapunov",
            variables=(
                ("lyapunov_max", "s-1", "largest Lyapunov exponent"),
                ("lyapunov_min", "s-1", "smallest Lyapunov exponent"),
            ),
            # two tangent vectors from the identity; Gram-Schmidt every
            # LYAPUNOV_EVERY steps: the first vector's growth gives the largest
            # exponent, the area's growth (the determinant) the sum of both
            init=("ly_u1 = 1.0\nly_v1 = 0.0\nly_u2 = 0.0\nly_v2 = 1.0\n"
                  "acc_ly1 = 0.0\nacc_ly2 = 0.0"),
            renormalise=(
                "ly_n1 = math.sqrt(ly_u1 * ly_u1 + ly_v1 * ly_v1)\n"
                "ly_r22 = (ly_u1 * ly_v2 - ly_v1 * ly_u2) / ly_n1\n"
                "if keep:\n"
                "    acc_ly1 += math.log(ly_n1)\n"
                "    acc_ly2 += math.log(abs(ly_r22))\n"
                "ly_u1 = ly_u1 / ly_n1\n"
                "ly_v1 = ly_v1 / ly_n1\n"
                "ly_u2 = -ly_v1\n"
                "ly_v2 = ly_u1"
            ),
            renormalise_every=LYAPUNOV_EVERY,
            # over a finite time the first vector's rate need not be the larger (both
            # tend to -c/2 on an attractor with complex Floquet multipliers): sorted
            final=("ly_window = (n_steps - max(n_transient, 0)) * dt\n"
                   "out[i, COL] = max(acc_ly1, acc_ly2) / ly_window\n"
                   "out[i, COL + 1] = min(acc_ly1, acc_ly2) / ly_window"),
            finite="math.isfinite(acc_ly1) and math.isfinite(acc_ly2)",
            steady=True,
            tangent=True,
            state=(("ly_u1", "float64"), ("ly_v1", "float64"), ("ly_u2", "float64"),
                   ("ly_v2", "float64"), ("acc_ly1", "float64"), ("acc_ly2", "float64")),
        ),
    )
}

#: CF ``comment`` attributes: what a variable means beyond its ``long_name``, which plots
#: (a colour bar's label) and the explorer (under its map) show and so is kept short.
_STEADY = "over t >= t0 + t_transient"
_STROBE = "stroboscopic samples at t0 + n_transient dt + m 2 pi / W, oldest first"
_LYAPUNOV = (f"{_STEADY}; finite-time, of the integrator's step map (two tangent vectors "
             f"from the identity, Gram-Schmidt every {LYAPUNOV_EVERY} steps)")
COMMENTS = {
    "winding": "round(theta_final / 2 pi) - round(theta0 / 2 pi) (half to even): the net "
               "signed number of passes over the top (theta = pi mod 2 pi)",
    "omega_mean": "net angle turned over t >= t0 + t_transient divided by that window's "
                  "duration",
    "strobe_theta": f"{_STROBE}; the angle unwrapped",
    "strobe_omega": _STROBE,
    "attractor": "its index in the run's attractor catalogue (attributes attractors_*); "
                 "settled on: the trajectory's stroboscopic point within ATTRACTOR_TOL of "
                 "the successive points of that attractor's orbit for ATTRACTOR_MATCHES "
                 "forcing periods running; -1: it never was",
    "well": "captured: the energy below the separatrix energy 2 g/L (from t0 + "
            "t_transient on); NaN if never",
    "capture_time": "first time the energy is below the separatrix energy 2 g/L (from t0 "
                    "+ t_transient on); NaN if never",
    "tension_min": f"T/m = L omega^2 + g cos(theta), {_STEADY}",
    "tension_max": f"T/m = L omega^2 + g cos(theta), {_STEADY}",
    "energy_initial": "omega^2/2 + (g/L) V(theta)",
    "energy_final": "omega^2/2 + (g/L) V(theta)",
    "top_distance_max": f"|theta - pi| reduced modulo 2 pi to [0, pi], {_STEADY}",
    "lyapunov_max": _LYAPUNOV,
    "lyapunov_min": _LYAPUNOV,
}


def variable_attributes(name: str, units: str, long_name: str,
                        comment: str | None = None) -> dict[str, str]:
    """The netCDF attributes of an observable's variable ``name``: ``units``,
    ``long_name`` (a short label) and its CF ``comment`` (``comment``, by default the
    variable's entry in `COMMENTS`; none where that is empty)."""
    attrs = {"units": units, "long_name": long_name}
    comment = COMMENTS.get(name, "") if comment is None else comment
    if comment:
        attrs["comment"] = comment
    return attrs


#: What `sweep.run` observes when ``observe`` is not given.
DEFAULT_OBSERVE = ("final", "winding")


def resolve(observe) -> tuple[str, ...]:
    """Validate ``observe`` and return its names in canonical (registry) order.

    Parameters
    ----------
    observe : str or iterable of str
        Observable names, keys of `OBSERVABLES`.

    Raises
    ------
    ValueError
        Naming the unknown observable and listing the accepted ones.
    """
    if isinstance(observe, str):
        if observe not in OBSERVABLES and any(sep in observe for sep in ", ;"):
            raise ValueError(
                f"observe = {observe!r} is one string; accepted: a name or a sequence of "
                f"names, e.g. {observe.replace(',', ' ').replace(';', ' ').split()!r}"
            )
        observe = (observe,)
    if isinstance(observe, (Mapping, bytes)):
        raise ValueError(f"observe must be a sequence of names from {', '.join(OBSERVABLES)}, "
                         f"got {observe!r}")
    try:
        names = tuple(observe)
    except TypeError:
        raise ValueError(
            f"observe must be a sequence of names from {', '.join(OBSERVABLES)}, "
            f"got {observe!r}"
        ) from None
    for name in names:
        if name not in OBSERVABLES:
            raise ValueError(
                f"unknown observable {name!r} in observe; accepted: {', '.join(OBSERVABLES)}"
            )
    return tuple(n for n in OBSERVABLES if n in names)
