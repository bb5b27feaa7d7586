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
    # fractions: the known shares, summing to one with the unresolved ones
    np.testing.assert_allclose(fractions["fraction"].sel(attractor=label_of["A"]),
                               np.array(share_a) / n_starts)
    np.testing.assert_allclose(fractions["fraction"].sum("attractor") + fractions.unresolved,
                               1.0)
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
    np.testing.assert_allclose(fractions.unresolved, 1 / n_starts)
    np.testing.assert_allclose(fractions["fraction"].sum("attractor") + fractions.unresolved,
                               1.0)


def test_set_distance_respects_the_wrap_and_the_cyclic_order():
    a = np.array([[0.01, 0.0], [3.0, 1.0]])
    b = np.array([[3.0, 1.0], [TWO_PI - 0.01, 0.0]])  # same set, other order, wrapped
    assert set_distance(a, b) == pytest.approx(0.02)
    assert set_distance(a, a[:1]) == pytest.approx(np.hypot(3.0 - 0.01, 1.0))


# ------------------------------------------------------------------ a real pendulum
def test_real_pendulum_bistability_appears_and_vanishes():
    """The damped driven pendulum below resonance (g/L = 1, c = 0.1, W = 0.8; a
    softening spring) is bistable over a window of forcing amplitudes (about 0.16 to
    0.24, scanned with sweep): a small oscillation, the only one at low amplitude, and
    a large one born at a saddle-node; past the window's top the small one vanishes in
    another. The continuation keeps the small one's label until it vanishes and gives
    the large one a label of its own, kept after; SciPy's DOP853 from the same starts
    finds one, two and one attractors at the three amplitudes probed."""
    amplitudes = np.array([0.1, 0.2, 0.3])
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.1), sweep.Forcing(0.1, 0.8)))
    period = TWO_PI / 0.8
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 5), omega0=[-1.0, 1.0],
                      forcing_amplitude=amplitudes)
    ds = sweep.run(scene, grid, t_end=200 * period, dt=period / 100,
                   t_transient=184 * period, observe=("strobe",), progress=False)
    labels, fractions = maps.continuation(ds, along="forcing_amplitude")
    present = (fractions["fraction"] > 0).values  # (amplitude, attractor)
    counts = present.sum(axis=1).tolist()

    def reference(amplitude):
        found = []
        for th0 in np.linspace(-3.0, 3.0, 5):
            for om0 in (-1.0, 1.0):
                sol = solve_ivp(lambda t, y: [y[1], -np.sin(y[0]) - 0.1 * y[1]
                                              + amplitude * np.sin(0.8 * t)],
                                (0, 200 * period), [th0, om0], method="DOP853",
                                rtol=1e-9, atol=1e-9, t_eval=[199 * period, 200 * period])
                point = (np.mod(sol.y[0, -1], TWO_PI), sol.y[1, -1])
                if not any(np.hypot(*np.subtract(point, f)) < 1e-3 for f in found):
                    found.append(point)
        return len(found)

    assert counts == [1, 2, 1]
    assert [reference(a) for a in amplitudes] == counts
    small = int(labels.sel(forcing_amplitude=0.1).values.ravel()[0])
    assert present[:, small].tolist() == [True, True, False]  # vanishes, label retired
    large = 1 - small
    assert present[:, large].tolist() == [False, True, True]  # born, then kept
    assert fractions.sizes["attractor"] == 2
    assert fractions.period.values.tolist() == [1, 1]


# ------------------------------------------------------------------ bad input and plot
def _tiny():
    rows = [[_orbit([(0.1, 0.0)], 0)] * 2 for _ in range(2)]
    return _dataset(rows, [1.0, 1.1], 2)


def test_bad_input_names_what_is_accepted():
    ds = _tiny()
    with pytest.raises(ValueError, match="along = 'damping' is not a grid axis of this "
                                         "dataset; accepted: 'theta0', 'forcing_amplitude'"):
        maps.continuation(ds, along="damping")
    with pytest.raises(ValueError, match="observe=\\('strobe',\\)"):
        maps.continuation(ds.drop_vars("strobe_omega"), along="theta0")
    with pytest.raises(ValueError, match="has 1 value; accepted: an axis with at least two"):
        maps.continuation(ds.isel(forcing_amplitude=[0]), along="forcing_amplitude")
    with pytest.raises(ValueError, match="threshold must be a number > 0"):
        maps.continuation(ds, along="theta0", threshold=0.0)


def test_stacked_fractions_plot():
    n_starts, amplitudes = 6, [1.0, 1.1, 1.2]
    rows = [[_orbit(*_drifting(k)["A" if s < 4 else "C"]) for s in range(n_starts)]
            for k in range(3)]
    _, fractions = maps.continuation(_dataset(rows, amplitudes, n_starts),
                                     along="forcing_amplitude")
    fig = sweep.plot.basin_fractions(fractions)
    ax = fig.axes[0]
    assert len(ax.collections) == 3  # two attractors and the unresolved share
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["attractor 0 (period 1)", "attractor 1 (period 1)", "unresolved"]
    assert "forcing amplitude" in ax.get_xlabel()
