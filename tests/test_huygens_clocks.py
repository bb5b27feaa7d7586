"""Huygens' two clocks (examples/huygens_clocks.py, a `sweep.DeclaredSystem`): the
derived equations against the same equations written by hand and integrated by SciPy's
DOP853, both synchronized states present and stable, and the map's labels of a few
starts equal to DOP853's."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import sweep

scipy_integrate = pytest.importorskip("scipy.integrate")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "huygens_clocks.py"


def _load():
    spec = importlib.util.spec_from_file_location("huygens_clocks", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


huygens = _load()
V = huygens.VALUES
FREQUENCY = math.sqrt(V["g"] / V["l"])  # rad/s


def rhs(_t, y):
    """The model by hand: the mass matrix [[M + 2m, m l cos th1, m l cos th2],
    [m l cos th1, m l^2, 0], [m l cos th2, 0, m l^2]] times (x'', th1'', th2'') equals
    (m l (w1^2 sin th1 + w2^2 sin th2) - k x - c v,
     -m g l sin th_i - eps (th_i^2 - th_a^2) w_i)."""
    x, t1, t2, v, w1, w2 = y
    M, m, l, g = V["M"], V["m"], V["l"], V["g"]  # noqa: E741 - the rod length
    c1, c2 = math.cos(t1), math.cos(t2)
    matrix = np.array([[M + 2 * m, m * l * c1, m * l * c2], [m * l * c1, m * l * l, 0.0],
                       [m * l * c2, 0.0, m * l * l]])
    forcing = np.array([
        m * l * (w1 * w1 * math.sin(t1) + w2 * w2 * math.sin(t2)) - V["k"] * x - V["c"] * v,
        -m * g * l * math.sin(t1) - V["eps"] * (t1 * t1 - V["theta_a"] ** 2) * w1,
        -m * g * l * math.sin(t2) - V["eps"] * (t2 * t2 - V["theta_a"] ** 2) * w2])
    return [v, w1, w2, *np.linalg.solve(matrix, forcing)]


def dop853(start, t_end, y0=None):
    """The state (x, th1, th2, v, w1, w2) at ``t_end`` from rest at ``start``."""
    y0 = [0.0, *start, 0.0, 0.0, 0.0] if y0 is None else y0
    return scipy_integrate.solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-10,
                                     atol=1e-12).y[:, -1]


def label_of(state):
    _, t1, t2, _, w1, w2 = state
    return int(huygens.phase_label(t1, w1, t2, w2, FREQUENCY))


def test_the_derived_equations_are_the_hand_written_ones():
    starts = [(0.4, -0.1), (-0.3, -0.5)]
    ds = sweep.run(huygens.clocks(), sweep.Points(theta1_0=[s[0] for s in starts],
                                                  theta2_0=[s[1] for s in starts]),
                   t_end=20.0, dt=0.005, observe=("final",), progress=False)
    for i, start in enumerate(starts):
        ref = dop853(start, 20.0)
        got = [float(ds[n].values[i]) for n in ("x_final", "theta1_final", "theta2_final",
                                                "v_final", "omega1_final", "omega2_final")]
        # RK4 at dt = 5 ms over 20 s: measured 3e-8 at most (Zen 5); 1e-6 leaves a
        # factor 30 and is far below the effect of any wrong term (>= 1e-3 over 20 s)
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)


@pytest.mark.parametrize("start, label, amplitude, beam", [
    ((0.2, 0.18), huygens.IN_PHASE, 0.183, True),
    ((0.2, -0.18), huygens.ANTI_PHASE, 0.200, False),
])
def test_both_synchronized_states_exist_and_are_stable(start, label, amplitude, beam):
    """DOP853 from a start near each state: after 300 s the clocks are locked (relative
    phase 0 or pi) at their amplitude; kicked (0.05 rad on one clock) they return."""
    state = dop853(start, 300.0)
    for kicked in (False, True):
        if kicked:
            state = state.copy()
            state[2] += 0.05
            state = dop853(None, 300.0, y0=state)
        samples = scipy_integrate.solve_ivp(rhs, (0.0, 10.0), state, method="DOP853",
                                            rtol=1e-10, atol=1e-12,
                                            t_eval=np.linspace(0, 10, 1001)).y
        t1, t2, x = samples[1], samples[2], samples[0]
        correlation = np.mean(t1 * t2) / math.sqrt(np.mean(t1 * t1) * np.mean(t2 * t2))
        # locked: correlation within 1e-3 of +-1 (measured 1 - 3e-7 after 300 s)
        assert abs(correlation - label) < 1e-3
        assert label_of(state) == label
        # the amplitudes of the two states (measured about 0.183 and 0.200 rad), 8 % apart:
        # so 0.005 tells them apart
        assert np.ptp(t1) / 2 == pytest.approx(amplitude, abs=0.005)
        # in phase the beam swings (0.065 m peak to peak), in anti-phase it rests
        assert (np.ptp(x) > 0.03) if beam else (np.ptp(x) < 1e-4)


def test_the_maps_labels_of_a_few_starts_are_dop853s():
    # starts away from the basin boundary (the map: same-sign starts in phase, except
    # near the axes), both labels among them
    starts = [(0.4, 0.3), (-0.5, -0.2), (0.3, -0.4), (-0.2, 0.5), (0.55, 0.15),
              (-0.1, 0.35)]
    ds = sweep.run(huygens.clocks(), sweep.Points(theta1_0=[s[0] for s in starts],
                                                  theta2_0=[s[1] for s in starts]),
                   t_end=300.0, dt=0.01, observe=("final",), progress=False)
    got = huygens.phase_label(ds.theta1_final.values, ds.omega1_final.values,
                              ds.theta2_final.values, ds.omega2_final.values, FREQUENCY)
    expected = [label_of(dop853(start, 300.0)) for start in starts]
    assert list(got) == expected
    assert set(expected) == {huygens.IN_PHASE, huygens.ANTI_PHASE}


def test_the_example_writes_its_map(tmp_path, capsys):
    assert huygens.main(["--size", "9", "--t-end", "100", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "huygens_clocks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ds = sweep.load(tmp_path / "huygens_clocks.nc")
    assert set(np.unique(ds.sync)) == {huygens.IN_PHASE, huygens.ANTI_PHASE}
    assert "end in phase" in capsys.readouterr().out
