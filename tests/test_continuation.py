"""`sweep.maps.continuation` on synthetic stroboscopic data with known attractors, and on
a real damped driven pendulum whose attractors appear and vanish (checked with SciPy's
DOP853)."""

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp

import sweep
from sweep import maps
from sweep.maps.continuation import set_distance

TWO_PI = 2 * np.pi
SAMPLES = 16


def _orbit(points, turns, n=SAMPLES, shift=0):
    """Strobe rows of a period-p orbit through ``points`` [(theta, omega)], advancing
    ``turns`` full turns per forcing period, starting at point ``shift``."""
    p = len(points)
    theta = np.empty(n)
    omega = np.empty(n)
    for j in range(n):
        th, om = points[(j + shift) % p]
        theta[j] = th + TWO_PI * turns * j
        omega[j] = om
    return theta, omega


def _dataset(rows, amplitudes, n_starts):
    """A dataset like sweep.run(..., observe=("strobe",)) over (theta0, forcing_amplitude)
    from ``rows[k][s]``: the (theta, omega) strobe rows of start s at amplitude k."""
    theta = np.empty((n_starts, len(amplitudes), SAMPLES))
    omega = np.empty_like(theta)
    for k in range(len(amplitudes)):
        for s in range(n_starts):
            theta[s, k], omega[s, k] = rows[k][s]
    coords = {"theta0": ("theta0", np.linspace(-3, 3, n_starts), {"units": "rad"}),
              "forcing_amplitude": ("forcing_amplitude", np.asarray(amplitudes),
                                    {"units": "rad s-2", "long_name": "forcing amplitude"}),
              "strobe": np.arange(1 - SAMPLES, 1)}
    dims = ("theta0", "forcing_amplitude", "strobe")
    return xr.Dataset({"strobe_theta": (dims, theta), "strobe_omega": (dims, omega)}, coords)


def _drifting(k):
    """Three attractors at step k, drifting by 0.01 per step: A period 1 near the 0/2 pi
    wrap, B period 2 (samples cyclically shifted per start), C a rotation."""
    a = [(TWO_PI - 0.005 + 0.01 * k, 0.5 + 0.01 * k)]  # crosses 2 pi at k = 1
    b = [(1.0 + 0.01 * k, -0.3), (3.0, 0.2 - 0.01 * k)]
    c = [(2.0, 2.0 + 0.01 * k)]
    return {"A": (a, 0), "B": (b, 0), "C": (c, 1)}


def test_labels_follow_drifting_attractors_whatever_their_size_order():
    """Basin sizes change along the axis so that the size order (which
    identify_attractors labels by) swaps A and B at step 3: the continued labels follow
    the attractors, not the sizes; B's starts hold shifted copies of its orbit."""
    n_starts, amplitudes = 20, np.linspace(1.0, 1.5, 6)
    share_a = [10, 9, 8, 5, 4, 3]  # B gets 20 - 3 - share_a: grows past A at step 3
    truth = np.empty((n_starts, len(amplitudes)), dtype=object)
    rows = []
    for k in range(len(amplitudes)):
        attractors = _drifting(k)
        row = []
        for s in range(n_starts):
            name = "A" if s < share_a[k] else ("C" if s >= n_starts - 3 else "B")
            points, turns = attractors[name]
            row.append(_orbit(points, turns, shift=s % len(points)))
            truth[s, k] = name
        rows.append(row)
    ds = _dataset(rows, amplitudes, n_starts)
    labels, fractions = maps.continuation(ds, along="forcing_amplitude")
    assert labels.dims == ("theta0", "forcing_amplitude")
    # one label per attractor along the whole axis, and a different one for each
    mapping = {}
    for (s, k), name in np.ndenumerate(truth):
        mapping.setdefault(name, set()).add(int(labels.values[s, k]))
    assert all(len(v) == 1 for v in mapping.values())
    assert len({next(iter(v)) for v in mapping.values()}) == 3
    label_of = {name: next(iter(v)) for name, v in mapping.items()}
    assert label_of["A"] == 0  # the largest at the first value
    # fractions: the known shares of each attractor, summing to one with the unresolved
    # ones (none here); counts over 20 starts, so equal up to rounding: atol 1e-12
    known = {"A": np.array(share_a) / n_starts, "C": np.full(6, 3 / n_starts)}
    known["B"] = 1 - known["A"] - known["C"]
    for name, share in known.items():
        np.testing.assert_allclose(fractions["fraction"].sel(attractor=label_of[name]),
                                   share, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(fractions.unresolved, 0.0)
    np.testing.assert_allclose(fractions["fraction"].sum("attractor") + fractions.unresolved,
                               1.0, rtol=0, atol=1e-12)
    assert fractions["period"].sel(attractor=label_of["B"]) == 2
    assert fractions["turns_per_period"].sel(attractor=label_of["C"]) == 1


def test_a_vanishing_attractor_retires_its_label_and_a_new_one_gets_a_fresh_label():
    """B exists for the first three values only (its starts then go to A: a saddle-node
    on the data); D appears at the fifth value close to where B was. B's label is never
    reused; D gets a new one; unresolved starts (NaN rows) are counted apart."""
    n_starts, amplitudes = 12, np.linspace(1.0, 1.6, 7)
    rows = []
    for k in range(len(amplitudes)):
        attractors = _drifting(k)
        row = []
        for s in range(n_starts):
            if s == 0:
                row.append((np.full(SAMPLES, np.nan), np.full(SAMPLES, np.nan)))
            elif s < 6 or (k >= 3 and s < 9):
                row.append(_orbit(*attractors["A"]))
            elif s < 9:
                row.append(_orbit(*attractors["B"]))
            elif k >= 4:
                row.append(_orbit([(1.05, -0.25), (3.1, 0.15)], 0))  # D, period 2
            else:
                row.append(_orbit(*attractors["C"]))
        rows.append(row)
    ds = _dataset(rows, amplitudes, n_starts)
    labels, fractions = maps.continuation(ds, along="forcing_amplitude")
    b = int(labels.values[7, 0])
    assert (labels.values[7, :3] == b).all() and (labels.values[7, 3:] != b).all()
    d = int(labels.values[10, 4])
    assert d not in (int(labels.values[1, 0]), b, int(labels.values[10, 0]))
    assert d == labels.max()  # the newest label
    assert float(fractions.last.sel(attractor=b)) == amplitudes[2]
    assert float(fractions.first.sel(attractor=d)) == amplitudes[4]
    np.testing.assert_array_equal(fractions["fraction"].sel(attractor=b).values[3:], 0.0)
    assert (labels.values[0] == maps.UNRESOLVED).all()
    # shares of 12 starts, equal up to rounding: atol 1e-12
    np.testing.assert_allclose(fractions.unresolved, 1 / n_starts, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fractions["fraction"].sum("attractor") + fractions.unresolved,
                               1.0, rtol=0, atol=1e-12)


def test_a_period_doubling_keeps_the_label_and_records_the_period_per_value():
    """P is a period-1 oscillation at (1.0, 0.2) for the first three values, then a
    period-2 orbit whose two points split away from it by 0.02 per step (a period
    doubling: the sets stay 0.02 apart per step); R is a rotation. P keeps its label
    across the doubling; attractor_period says 1, 1, 1, 2, 2 and period its first."""
    n_starts, amplitudes = 8, np.linspace(1.0, 1.4, 5)
    rows = []
    for k in range(len(amplitudes)):
        split = 0.02 * max(k - 2, 0)
        p_points = ([(1.0, 0.2)] if split == 0 else
                    [(1.0 + split, 0.2 - split), (1.0 - split, 0.2 + split)])
        rows.append([_orbit(p_points, 0, shift=s) if s < 5 else _orbit([(2.0, 2.0)], 1)
                     for s in range(n_starts)])
    labels, fractions = maps.continuation(_dataset(rows, amplitudes, n_starts),
                                          along="forcing_amplitude")
    np.testing.assert_array_equal(labels.values[:5], 0)  # the larger basin at the start
    np.testing.assert_array_equal(labels.values[5:], 1)
    np.testing.assert_array_equal(fractions.attractor_period.sel(attractor=0),
                                  [1, 1, 1, 2, 2])
    np.testing.assert_array_equal(fractions.attractor_period.sel(attractor=1), 1)
    assert int(fractions.period.sel(attractor=0)) == 1
    np.testing.assert_allclose(fractions["fraction"].sel(attractor=0), 5 / 8, rtol=0,
                               atol=1e-12)  # 5 of 8 starts: exact up to rounding


def test_a_threshold_keeps_a_far_newcomer_from_inheriting_a_vanished_label():
    """B (period 1 at (1.0, -0.3)) vanishes at the fourth value as D (period 1 at
    (4.0, 1.5), 3.3 away) appears. With no threshold (Attractors.jl's default) D
    inherits B's label, the only unmatched one; with threshold = 0.5 (above the 0.01
    drift per step, below 3.3) B's label retires and D gets a fresh one. A vanished
    label never comes back even where B reappears at the last value."""
    n_starts, amplitudes = 6, np.linspace(1.0, 1.5, 6)
    rows = []
    for k in range(len(amplitudes)):
        b = [(1.0 + 0.01 * k, -0.3)] if k < 3 or k == 5 else [(4.0, 1.5)]
        rows.append([_orbit([(5.0, 0.5 + 0.01 * k)], 0) if s < 4 else _orbit(b, 0)
                     for s in range(n_starts)])
    ds = _dataset(rows, amplitudes, n_starts)
    labels, _ = maps.continuation(ds, along="forcing_amplitude")
    np.testing.assert_array_equal(labels.values[4], 1)  # matched whatever the distance
    labels, fractions = maps.continuation(ds, along="forcing_amplitude", threshold=0.5)
    np.testing.assert_array_equal(labels.values[:4], 0)
    np.testing.assert_array_equal(labels.values[4], [1, 1, 1, 2, 2, 3])
    assert fractions.attrs["threshold"] == 0.5
    np.testing.assert_array_equal(fractions.first, amplitudes[[0, 0, 3, 5]])
    np.testing.assert_array_equal(fractions.last, amplitudes[[5, 2, 4, 5]])


def test_continuing_down_the_axis_groups_the_starts_alike():
    """The same synthetic attractors continued along the reversed axis: the partition
    of the starts into continued attractors is the same (labels renamed), and each
    attractor's fractions are the forward ones reversed."""
    n_starts, amplitudes = 12, np.linspace(1.0, 1.5, 6)
    rows = [[_orbit(*_drifting(k)["A" if s < 4 + k else ("B" if s < 10 else "C")],
                    shift=s) for s in range(n_starts)] for k in range(len(amplitudes))]
    ds = _dataset(rows, amplitudes, n_starts)
    forward, f_fractions = maps.continuation(ds, along="forcing_amplitude")
    backward, b_fractions = maps.continuation(ds.isel(forcing_amplitude=slice(None, None, -1)),
                                              along="forcing_amplitude")
    backward = backward.sel(forcing_amplitude=forward.forcing_amplitude)
    pairs = set(zip(forward.values.ravel().tolist(), backward.values.ravel().tolist()))
    assert len(pairs) == 3 and len({f for f, _ in pairs}) == 3  # a bijection of labels
    for f, b in pairs:
        np.testing.assert_array_equal(
            f_fractions["fraction"].sel(attractor=f).values,
            b_fractions["fraction"].sel(attractor=b).values[::-1])


def test_a_failed_trajectory_is_unresolved_even_with_periodic_samples():
    """A start whose status says it failed (1: non-finite state) is unresolved even
    though its stored samples (taken before it failed) repeat, and is counted in
    ``unresolved``, not in an attractor's basin; status 0 elsewhere changes nothing."""
    n_starts, amplitudes = 4, [1.0, 1.1]
    rows = [[_orbit([(0.5, 0.1)], 0) for _ in range(n_starts)] for _ in amplitudes]
    ds = _dataset(rows, amplitudes, n_starts)
    status = np.zeros((n_starts, 2), dtype=np.int8)
    status[1, 1] = 1
    ds["status"] = (("theta0", "forcing_amplitude"), status)
    labels, fractions = maps.continuation(ds, along="forcing_amplitude")
    np.testing.assert_array_equal(labels.values, [[0, 0], [0, -1], [0, 0], [0, 0]])
    np.testing.assert_array_equal(fractions.unresolved, [0.0, 0.25])  # 1 of 4: exact
    np.testing.assert_array_equal(fractions["fraction"].sel(attractor=0), [1.0, 0.75])


def test_set_distance_respects_the_wrap_and_the_cyclic_order():
    a = np.array([[0.01, 0.0], [3.0, 1.0]])
    b = np.array([[3.0, 1.0], [TWO_PI - 0.01, 0.0]])  # same set, other order, wrapped
    # closed forms; rel 1e-12: only the rounding of 2 pi - 0.01 and of hypot
    assert set_distance(a, b) == pytest.approx(0.02, rel=1e-12)
    assert set_distance(a, a[:1]) == pytest.approx(np.hypot(3.0 - 0.01, 1.0), rel=1e-12)
    # a rotating orbit's unwrapped angle: 4 pi + 0.3 is 0.3
    assert set_distance(np.array([[4 * np.pi + 0.3, 2.0]]),
                        np.array([[0.3, 2.0]])) == pytest.approx(0.0, abs=1e-12)


# ------------------------------------------------------------------ a real pendulum
# The damped driven pendulum below resonance: theta'' = -sin(theta) - C theta' + A sin(W t),
# a softening spring, bistable over a window of forcing amplitudes A (a large oscillation
# born at one saddle-node, the small one dying at another; both located below with DOP853).
DAMPING, FREQUENCY = 0.1, 0.8
PERIOD = TWO_PI / FREQUENCY


def _dop853_strobe_point(y0, amplitude, periods):
    """(theta, omega) after ``periods`` forcing periods from ``y0`` at t = 0, by SciPy's
    DOP853 at rtol = atol = 1e-10 (the reference, independent of sweep)."""
    sol = solve_ivp(lambda t, y: [y[1], -np.sin(y[0]) - DAMPING * y[1]
                                  + amplitude * np.sin(FREQUENCY * t)],
                    (0.0, periods * PERIOD), y0, method="DOP853", rtol=1e-10, atol=1e-10)
    return sol.y[:, -1]


def _dop853_branch(y0, ladder, periods=60):
    """Natural-parameter continuation of one periodic attractor with DOP853: settle
    from ``y0`` at ``ladder[0]``, then at each next amplitude from the last point. The
    branch ends where the point jumps by more than 0.5 (rad, rad/s) in one 0.01 step:
    on this branch consecutive points move by at most 0.25 (measured), a jump to the
    other attractor is over 1.7. 60 periods settle to 1e-10 (decay exp(-C t / 2) over
    471 s, slower only right at a fold). Returns {amplitude: (theta mod 2 pi, omega)}."""
    points, y = {}, np.asarray(y0, dtype=float)
    for amplitude in ladder:
        new = _dop853_strobe_point(y, amplitude, periods)
        d_theta = np.angle(np.exp(1j * (new[0] - y[0])))
        if points and np.hypot(d_theta, new[1] - y[1]) > 0.5:
            break
        y = new
        points[round(float(amplitude), 2)] = (np.mod(y[0], TWO_PI), y[1])
    return points


def test_real_saddle_nodes_label_stops_where_dop853_loses_the_branch():
    """A run over 20 x 20 starts x 6 amplitudes. DOP853 continues the small
    oscillation up from A = 0.10 and the large one down from A = 0.27 in steps of 0.01:
    the small one dies between 0.25 and 0.26, the large one is born between 0.14 and
    0.15. The continuation must give the small one label 0 exactly at the amplitudes
    where DOP853 still has it (the label stops at 0.23, never reused), the large one a
    fresh label 1 from 0.17 on, each label's stroboscopic point on its DOP853 branch,
    and, at the bistable A = 0.20, the label DOP853 reaches from sampled starts."""
    amplitudes = np.array([0.10, 0.13, 0.17, 0.20, 0.23, 0.27])
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(DAMPING), sweep.Forcing(0.1, FREQUENCY)))
    theta0 = np.linspace(-np.pi, np.pi, 20, endpoint=False)
    omega0 = np.linspace(-2.0, 2.0, 20)
    grid = sweep.Grid(theta0=theta0, omega0=omega0, forcing_amplitude=amplitudes)
    ds = sweep.run(scene, grid, t_end=200 * PERIOD, dt=PERIOD / 100,
                   t_transient=184 * PERIOD, observe=("strobe",), progress=False)
    labels, fractions = maps.continuation(ds, along="forcing_amplitude")

    ladder = np.round(np.arange(0.10, 0.2701, 0.01), 2)
    small = _dop853_branch([0.0, 0.0], ladder)
    large = _dop853_branch([0.0, 2.0], ladder[::-1])  # the only attractor at 0.27
    assert max(small) == 0.25 and min(large) == 0.15  # the folds, as scanned
    assert fractions.sizes["attractor"] == 2
    present = fractions["fraction"].values > 0  # (amplitude, attractor)
    np.testing.assert_array_equal(present[:, 0], [a in small for a in amplitudes])
    np.testing.assert_array_equal(present[:, 1], [a in large for a in amplitudes])
    assert float(fractions.last[0]) == 0.23 and float(fractions.first[1]) == 0.17
    np.testing.assert_array_equal(fractions.period, [1, 1])
    np.testing.assert_array_equal(fractions.turns_per_period, [0, 0])
    # each label on its own branch: sweep's stroboscopic point (RK4, dt = T/100) and
    # DOP853's agree to 1.2e-6 measured (RK4's O(dt^4) orbit error); 1e-4 leaves margin and
    # is still 10^4 times smaller than the gap between the two branches (2.0 at 0.20)
    for label, branch in ((0, small), (1, large)):
        for k, amplitude in enumerate(amplitudes):
            if amplitude in branch:
                theta, omega = branch[amplitude]
                got = fractions.isel(forcing_amplitude=k, attractor=label)
                assert set_distance(np.array([[float(got.attractor_theta),
                                               float(got.attractor_omega)]]),
                                    np.array([[theta, omega]])) < 1e-4
    # per start at the bistable 0.20: the label sweep gives is the branch DOP853 reaches
    # after the same 200 periods (nearest branch point; the two are 2.0 apart)
    at = labels.sel(forcing_amplitude=0.20)
    reached = set()
    for i, j in [(0, 0), (3, 15), (7, 9), (10, 10), (12, 4), (16, 19)]:
        point = _dop853_strobe_point([theta0[i], omega0[j]], 0.20, 200)
        d = [set_distance(np.array([point]), np.array([branch[0.20]]))
             for branch in (small, large)]
        reached.add(int(np.argmin(d)))
        assert min(d) < 1e-4  # settled on one of them (same bound as above)
        assert int(at.sel(theta0=theta0[i], omega0=omega0[j])) == int(np.argmin(d))
    assert reached == {0, 1}  # the sampled starts reach both attractors
    np.testing.assert_allclose(fractions["fraction"].sum("attractor") + fractions.unresolved,
                               1.0, rtol=0, atol=1e-12)  # shares of 400 starts: exact


# ------------------------------------------------------------------ bad input and plot
def _tiny():
    rows = [[_orbit([(0.1, 0.0)], 0)] * 2 for _ in range(2)]
    return _dataset(rows, [1.0, 1.1], 2)


AXES = "accepted: 'theta0', 'forcing_amplitude'"


@pytest.mark.parametrize("along, options, message", [
    ("damping", {}, f"along = 'damping' is not a grid axis of this dataset; {AXES}"),
    ("forcing_frequency", {}, "along = 'forcing_frequency' is not a grid axis of this "
                              f"dataset \\(it is held fixed in this run: a dataset "
                              f"attribute\\); {AXES}"),
    ("strobe", {}, "along = 'strobe' is not a grid axis of this dataset \\(it is the "
                   f"dimension of the stroboscopic samples\\); {AXES}"),
    ("strobe_theta", {}, "along = 'strobe_theta' is not a grid axis of this dataset "
                         f"\\(it is a data variable\\); {AXES}"),
    ("time", {}, "along = 'time' is not a grid axis of this dataset \\(it is a "
                 f"coordinate but not a dimension of the grid\\); {AXES}"),
    (None, {}, "along must be the name of a grid axis \\(a str\\), got None"),
    ("theta0", {"max_period": 0}, "max_period must be an int >= 1 \\(forcing periods\\), "
                                  "got 0"),
    ("theta0", {"max_period": 2.0}, "max_period must be an int >= 1"),
    ("theta0", {"max_period": True}, "max_period must be an int >= 1"),
    ("theta0", {"tol": float("nan")}, "tol must be a finite number > 0 \\(rad and "
                                      "rad/s\\), got nan"),
    ("theta0", {"tol": -1e-3}, "tol must be a finite number > 0"),
    ("theta0", {"threshold": 0.0}, "threshold must be a number > 0 \\(rad, rad/s; inf for "
                                   "no threshold\\), got 0.0"),
    ("theta0", {"threshold": "far"}, "threshold must be a number > 0"),
])
def test_bad_options_name_the_value_and_what_is_accepted(along, options, message):
    ds = _tiny().assign_coords(time=12.5)  # a scalar coordinate, not a grid dim
    ds.attrs["forcing_frequency"] = 0.8
    with pytest.raises(ValueError, match=message):
        maps.continuation(ds, along=along, **options)


def test_a_run_without_strobe_samples_is_refused_saying_observe_strobe():
    ds = _tiny()
    without = xr.Dataset({"final_theta": ds.strobe_theta.isel(strobe=-1, drop=True)})
    for bad in (without, ds.drop_vars("strobe_omega"), ds.strobe_theta):
        with pytest.raises(ValueError, match=r"continuation needs stroboscopic samples "
                                             r".*observe=\('strobe',\)"):
            maps.continuation(bad, along="forcing_amplitude")


def test_an_axis_of_one_value_is_refused():
    with pytest.raises(ValueError, match="along = 'forcing_amplitude' has 1 value; "
                                         "accepted: an axis with at least two values"):
        maps.continuation(_tiny().isel(forcing_amplitude=[0]), along="forcing_amplitude")


def test_stacked_fractions_plot():
    """One stacked area per attractor and one for the unresolved share (a NaN start),
    coloured by label (tab10) and grey, the legend naming each with its period(s):
    attractor 0 doubles its period at the third value; the areas' top edge is 1."""
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt

    n_starts, amplitudes = 6, [1.0, 1.1, 1.2]
    rows = []
    for k in range(3):
        doubled = [(1.0, 0.2)] if k < 2 else [(1.02, 0.18), (0.98, 0.22)]
        rows.append([(np.full(SAMPLES, np.nan),) * 2 if s == 5 else
                     _orbit(doubled, 0) if s < 3 else _orbit(*_drifting(k)["C"])
                     for s in range(n_starts)])
    _, fractions = maps.continuation(_dataset(rows, amplitudes, n_starts),
                                     along="forcing_amplitude")
    fig = sweep.plot.basin_fractions(fractions)
    ax = fig.axes[0]
    assert len(ax.collections) == 3  # two attractors and the unresolved share
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["attractor 0 (periods 1, 2)", "attractor 1 (period 1)", "unresolved"]
    colours = [mcolors.to_hex(c.get_facecolor()[0]) for c in ax.collections]
    tab10 = plt.get_cmap("tab10")
    assert colours == [mcolors.to_hex(tab10(0)), mcolors.to_hex(tab10(1)), "#bdbdbd"]
    top = ax.collections[-1].get_paths()[0].vertices[:, 1].max()
    assert top == pytest.approx(1.0, abs=1e-12)  # 3/6 + 2/6 + 1/6, up to rounding
    assert "forcing amplitude" in ax.get_xlabel()
    plt.close(fig)
