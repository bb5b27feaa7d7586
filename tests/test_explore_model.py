"""The explorer's model without a browser: state -> grid -> run -> image, history,
cancellation, every map kind, refused input, and the snippets and exports that
reproduce a map (sweep.explore.model; no Panel needed)."""

from __future__ import annotations

import dataclasses
import math
import threading
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

import sweep
from sweep import maps
from sweep.explore import model
from sweep.explore.model import (
    QUANTITIES,
    Cancelled,
    CancelToken,
    Explorer,
    InvalidInput,
    Requests,
    centres,
)
from sweep.physics import Effect, EffectDeclaration, Parameter, register, unregister
from sweep.toml_spec import load_run

N = 24  # pixels per axis: small maps, the code paths are those of 400 x 400
PERIOD = 2 * np.pi  # the forced scene's forcing period (W = 1 rad/s) [s]


def demo():
    """The demo scene of `sweep demo` (damped, unforced) on its phase-plane window."""
    from sweep.cli import demo_inputs

    scene, grid, kwargs = demo_inputs(N)
    return scene, grid, kwargs


def wada():
    """The forced scene of examples/forced_basins.py (three attractors, Wada basins),
    shortened: 60 forcing periods, 20 of them transient, 50 steps per period."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, N), omega0=np.linspace(-4, 4, N))
    return scene, grid, dict(t_end=60 * PERIOD, dt=PERIOD / 50, t_transient=20 * PERIOD)


def torque():
    """A constant torque with damping: locked versus running (examples/torque_...)."""
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Torque(5.0)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, N), omega0=np.linspace(-6, 6, N))
    return scene, grid, dict(t_end=20.0, dt=0.02, t_transient=10.0)


def pivot():
    """Kapitza's pendulum over (pivot_amplitude, pivot_frequency), from near the top."""
    scene = sweep.Scene(effects=(sweep.Damping(0.2), sweep.PivotDrive(0.05, 200.0, 0.0)))
    grid = sweep.Grid(theta0=[np.pi - 0.1], pivot_amplitude=np.linspace(0.01, 0.1, N),
                      pivot_frequency=np.linspace(20.0, 200.0, N))
    return scene, grid, dict(t_end=5.0, dt=0.002, t_transient=4.0)


def explorer(make=demo, **extra):
    scene, grid, kwargs = make()
    return Explorer(scene, grid, resolution=N, **kwargs, **extra)


# ------------------------------------------------------------------ state -> image
def test_state_grid_run_image_is_sweep_run_and_maps():
    e = explorer()
    s = e.state
    assert (s.view.x, s.view.y, s.quantity) == ("theta0", "omega0", "well")
    grid = e.grid()
    assert grid.dims == ("omega0", "theta0") and grid.shape == (N, N)
    # the demo grid's points are the home view's pixel centres
    np.testing.assert_allclose(grid.axes["theta0"], np.linspace(-np.pi, np.pi, N),
                               rtol=0, atol=1e-12)  # centres of (lo - h/2, hi + h/2)
    result = e.compute()
    ds = sweep.run(s.scene, grid, **e.run_kwargs(), progress=False)
    expected = maps.well(ds).values
    assert result.values.shape == (N, N)
    np.testing.assert_array_equal(result.values, expected)
    # discrete map: the image indexes the legend, which names each well
    assert result.legend and all("well" in text for _, text in result.legend
                                 if math.isfinite(_))
    for (row, col) in [(0, 0), (N // 2, N // 2), (N - 1, 3)]:
        value, _text = result.legend[int(result.image[row, col])]
        assert value == expected[row, col]
    assert result.title == "well" and "rest at theta" in result.description


def test_the_caption_shows_the_maps_cf_comment(monkeypatch):
    """A variable whose long name is a short label keeps its full meaning in a CF
    ``comment`` (`sweep.observables.COMMENTS`, as the ``attractor`` variable does): the
    caption below the map shows the long name and then the comment, Markdown's
    characters escaped (``attractors_*`` or ``t_end ... theta_final`` would start an
    emphasis); a map without one shows its long name alone. (The caption showed the
    long name alone, unescaped.)"""
    from sweep import observables

    plain = explorer(quantity="var:theta_final").compute()  # no comment
    assert plain.comment == "" and "_" in plain.description
    assert plain.caption == "*" + plain.description.replace("_", "\\_") + "*"
    result = explorer(quantity="var:winding").compute()
    assert result.description == "wells crossed from t0 to t_end"  # a short label
    assert result.comment == observables.COMMENTS["winding"]
    assert "theta_final" in result.comment and "*" not in result.comment
    assert result.caption == ("*wells crossed from t0 to t\\_end*\n\n"
                              + result.comment.replace("_", "\\_"))
    monkeypatch.setitem(observables.COMMENTS, "winding",
                        "net turns over the run (attributes winding_*); 0: none")
    result = explorer(quantity="var:winding").compute()
    assert result.caption == ("*wells crossed from t0 to t\\_end*\n\nnet turns over the "
                              "run (attributes winding\\_\\*); 0: none")
    # a system's log10 map of a variable keeps the variable's comment
    import xarray as xr

    from sweep.explore.systems import _log10

    ds = xr.Dataset({"t": ("x", [1.0, 10.0], {"units": "s", "long_name": "time",
                                             "comment": "until the first flip"})})
    assert _log10(ds, "t").attrs["comment"] == "until the first flip"


def test_bands_give_the_one_run_map(monkeypatch):
    e = explorer()
    whole = e.compute().values
    monkeypatch.setattr(model, "BAND_MIN", 1)  # 8 bands of 3 rows
    calls = []
    run = Explorer._run

    def counting(state, grid, kwargs):
        calls.append(grid.shape)
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(counting))
    e._cache.clear()
    banded = e.compute()
    assert len(calls) == model.BANDS and all(shape == (N // model.BANDS, N) for shape in calls)
    np.testing.assert_array_equal(banded.values, whole)
    assert banded.ds.sizes == {"omega0": N, "theta0": N}


def test_zoom_recomputes_the_window_at_full_resolution():
    e = explorer()
    home = e.compute()
    e.zoom((0.5, 1.5), (-3.0, -1.0))
    zoomed = e.compute()
    assert zoomed.values.shape == (N, N)  # never a scaled image
    np.testing.assert_allclose(zoomed.x, centres(0.5, 1.5, N), rtol=0, atol=0)
    assert zoomed.x.min() > 0.5 and zoomed.x.max() < 1.5
    assert zoomed.y.min() > -3.0 and zoomed.y.max() < -1.0
    assert not np.array_equal(zoomed.values, home.values)


def test_preview_is_coarse_and_agrees_where_it_samples_the_same_map():
    e = explorer()
    e.update(resolution=40)
    preview = e.compute(preview=True)
    assert preview.preview and preview.values.shape == (10, 10)
    assert preview.ds is None  # previews keep no dataset
    final = e.compute()
    assert not final.preview and final.values.shape == (40, 40)


# ------------------------------------------------------------------ history
def test_history_back_forward_reset():
    e = explorer()
    home = e.state.view
    a = e.zoom((-1.0, 1.0), (-2.0, 2.0)).view
    b = e.zoom((0.0, 1.0), (0.0, 2.0)).view
    assert e.history == [home, a, b] and e.position == 2
    assert e.back().view == a and e.back().view == home
    assert not e.can_go_back() and e.back().view == home  # stays at the first
    assert e.forward().view == a
    c = e.zoom((0.0, 0.5), (0.0, 1.0)).view  # a new view drops the forward branch
    assert e.history == [home, a, c] and not e.can_go_forward()
    assert e.reset().view == home and e.history[-1] == home
    # changing an axis is a new view too
    e.update(x="damping")
    assert e.state.view.x == "damping" and e.history[-1] == e.state.view
    assert e.back().view == home


def test_swapping_axes():
    e = explorer()
    v = e.state.view
    e.update(x="omega0")
    assert (e.state.view.x, e.state.view.y) == ("omega0", "theta0")
    assert (e.state.view.x_range, e.state.view.y_range) == (v.y_range, v.x_range)


# ------------------------------------------------------------------ cancellation
def test_a_cancelled_token_computes_nothing(monkeypatch):
    e = explorer()
    token = CancelToken()
    token.cancel()
    monkeypatch.setattr(Explorer, "_run", staticmethod(lambda *a: pytest.fail("ran")))
    with pytest.raises(Cancelled):
        e.compute(cancel=token)


def test_cancel_lands_between_bands(monkeypatch):
    e = explorer()
    monkeypatch.setattr(model, "BAND_MIN", 1)
    token = CancelToken()
    bands = []
    run = Explorer._run

    def cancel_after_first(state, grid, kwargs):
        bands.append(grid.shape)
        token.cancel()  # a newer request arrives while the first band computes
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(cancel_after_first))
    with pytest.raises(Cancelled):
        e.compute(cancel=token)
    assert len(bands) == 1  # the other 7 bands never ran
    assert e.state not in e._cache  # nothing half-made is kept


def test_requests_newest_wins(monkeypatch):
    e = explorer()
    monkeypatch.setattr(model, "BAND_MIN", 1)
    monkeypatch.setattr(model, "PREVIEW_AFTER", 0.0)  # every preview shown
    started = threading.Event()
    release = threading.Event()
    run = Explorer._run

    def slow(state, grid, kwargs):
        started.set()
        release.wait(10)
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(slow))
    results, cancelled, errors = [], [], []
    requests = Requests(e, lambda r, res: results.append((r, res)),
                        lambda r, exc: errors.append(exc), cancelled.append)
    first = requests.submit(e.state)
    assert started.wait(10)
    second_state = e.zoom((0.0, 1.0), (0.0, 1.0))
    second = requests.submit(second_state)
    release.set()
    assert requests.idle(60)
    requests.close()
    assert not errors
    assert cancelled == [first]
    assert [r for r, _ in results] == [second, second]  # its preview, then its map
    assert [res.preview for _, res in results] == [True, False]
    assert results[-1][1].state == second_state


# ------------------------------------------------------------------ progressive steps
def test_bands_are_interleaved_rows_in_van_der_corput_order(monkeypatch):
    assert Explorer.band_order(8) == [0, 4, 2, 6, 1, 5, 3, 7]
    assert sorted(Explorer.band_order(5)) == list(range(5))
    e = explorer()
    monkeypatch.setattr(model, "BAND_MIN", 1)  # 8 bands of 3 rows
    rows = []
    run = Explorer._run

    def recording(state, grid, kwargs):
        rows.append(np.asarray(grid.axes["omega0"]))
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(recording))
    e.compute()
    ys = centres(*e.state.view.y_range, N)
    for band, got in zip(Explorer.band_order(8), rows, strict=True):
        np.testing.assert_array_equal(got, ys[band::8])  # rows band, band + 8, ...


def test_progressive_steps_show_the_computed_rows_and_end_in_the_one_run_map(monkeypatch):
    e = explorer()
    whole = e.compute().values
    e._cache.clear()
    monkeypatch.setattr(model, "BAND_MIN", 1)  # 8 bands of 3 rows
    monkeypatch.setattr(model, "STEP_SECONDS", 0.0)  # every step shown, however fast
    steps = []
    final = e.compute(on_step=steps.append)
    np.testing.assert_array_equal(final.values, whole)  # steps change nothing computed
    assert final.stage == "final" and final.done == 1.0 and not final.preview
    # after 1, 2 and 4 of the 8 bands: rows every 8, 4 and 2 pixels
    assert [s.stage for s in steps] == ["step"] * 3 and all(s.preview for s in steps)
    assert [s.done for s in steps] == [1 / 8, 2 / 8, 4 / 8]
    for step, stride in zip(steps, (8, 4, 2), strict=True):
        assert step.values.shape == (N, N) and step.image.shape == (N, N)
        np.testing.assert_array_equal(step.y, final.y)
        computed = np.arange(0, N, stride)
        np.testing.assert_array_equal(step.values[computed], whole[computed])
        for row in range(N):  # a missing row repeats its nearest computed row
            nearest = computed[np.argmin(np.abs(computed - row))]
            np.testing.assert_array_equal(step.values[row], whole[nearest])
        for value, text in step.legend:  # the legend names what the step shows
            assert text and (value in step.values or math.isnan(value))


def test_a_slow_map_is_cut_into_bands_a_cheap_one_is_one_run():
    n = 400
    assert Explorer.band_count(n) == model.BANDS  # no measure: the size rule alone
    assert Explorer.band_count(n, per_start=1e-7) == 1  # 16 ms: one run
    slow = 2 * model.BANDS * model.BAND_SECONDS / n**2  # twice what all bands take
    assert Explorer.band_count(n, per_start=slow) == model.BANDS
    middle = Explorer.band_count(n, per_start=3 * model.BAND_SECONDS / n**2)
    assert middle == 3  # three bands of about BAND_SECONDS each


def test_a_cheap_maps_preview_is_not_shown_and_once_measured_not_computed(monkeypatch):
    e = explorer()
    shown, runs = [], []
    run = Explorer._run

    def counting(state, grid, kwargs):
        runs.append(grid.shape)
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(counting))
    side = max(model.RESOLUTION_RANGE[0], N // model.PREVIEW_FACTOR)
    monkeypatch.setattr(model, "PREVIEW_AFTER", math.inf)  # every map counts as cheap
    e.stages(e.state, CancelToken(), shown.append)
    assert [r.stage for r in shown] == ["final"]
    assert runs == [(side, side), (N, N)]  # the preview measured the cost, unseen
    shown.clear()
    runs.clear()
    zoomed = e.zoom((0.0, 1.0), (0.0, 1.0))  # another window of the same settings
    e.stages(zoomed, CancelToken(), shown.append)
    assert [r.stage for r in shown] == ["final"]
    assert runs == [(N, N)]  # the last map's cost says cheap: no preview at all
    runs.clear()
    other_axes = e.update(x="damping")  # another setting: its cost is not known yet
    e.stages(other_axes, CancelToken(), shown.append)
    assert [shape[:2] for shape in runs] == [(side, side), (N, N)]  # and omega0's 1
    e._cache.clear()
    shown.clear()
    monkeypatch.setattr(model, "PREVIEW_AFTER", 0.0)  # every map counts as slow
    e.stages(e.state, CancelToken(), shown.append)
    assert [r.stage for r in shown] == ["preview", "final"]
    assert shown[0].values.shape == (side, side)


def test_a_newer_request_cancels_the_steps_of_an_older_one(monkeypatch):
    e = explorer()
    monkeypatch.setattr(model, "BAND_MIN", 1)
    monkeypatch.setattr(model, "BAND_SECONDS", 1e-12)  # as slow maps: every band
    monkeypatch.setattr(model, "STEP_SECONDS", 0.0)
    monkeypatch.setattr(model, "PREVIEW_AFTER", 0.0)
    first_step, release = threading.Event(), threading.Event()
    results = []

    def on_result(request, result):
        results.append((request, result.stage))
        if request == 1 and result.stage == "step":
            first_step.set()
            assert release.wait(10)  # the newer zoom arrives while the step is shown

    numbers = []
    requests = Requests(e, on_result, on_numbers=lambda r, res, nums: numbers.append(r))
    requests.submit(e.state)
    assert first_step.wait(60)
    second = requests.submit(e.zoom((0.0, 1.0), (0.0, 1.0)))
    release.set()
    assert requests.idle(60)
    requests.close()
    old = [stage for request, stage in results if request == 1]
    assert old == ["preview", "step"]  # nothing of the old request after the cancel
    assert [stage for request, stage in results if request == second][-1] == "final"
    assert numbers == [second]


# ------------------------------------------------------------------ the view's numbers
def test_the_numbers_are_the_metrics_of_the_maps_labels():
    from sweep.explore.numbers import BOX_SIZE
    from sweep.maps.metrics import basin_entropy

    e = explorer()
    e.update(resolution=40)
    e.zoom((-3.0, -1.0), (3.0, 8.0))  # crosses the boundaries of wells 0, 1 and 2
    result = e.compute()
    numbers = e.numbers(result)
    assert e.numbers(result) is numbers  # computed once per result
    ds = sweep.run(e.state.scene, e.grid(), **e.run_kwargs(), progress=False)
    wells = maps.well(ds).values  # NaN: not captured, an outcome of its own
    labels = np.where(np.isfinite(wells), wells, -1).astype(int)
    reference = maps.fractions(labels)
    assert len(numbers.meanings) == reference.sizes["label"] >= 2
    order = [-1] if -1 in labels else []
    by_label = {int(k): i for i, k in enumerate(reference["label"].values)}
    legend_labels = [int(v) if math.isfinite(v) else -1 for v, _ in result.legend]
    for k, label in enumerate(legend_labels):
        i = by_label[label]
        assert numbers.fractions[k] == pytest.approx(float(reference["fraction"][i]),
                                                     rel=1e-15)  # n_j / n both ways
        assert numbers.errors[k] == pytest.approx(float(reference["standard_error"][i]),
                                                  rel=1e-15)
    assert numbers.meanings == tuple(text for _, text in result.legend)
    assert numbers.pixels == labels.size and order is not None
    entropy = basin_entropy(labels, box_size=BOX_SIZE)
    # the same partition of every box; the entropies' sums run in another order of
    # the labels, so they agree to a few ulps, not bit for bit
    assert numbers.sb == pytest.approx(entropy.sb, rel=1e-12)
    assert numbers.sbb == pytest.approx(entropy.sbb, rel=1e-12)
    assert (numbers.n_boxes, numbers.n_boundary_boxes, numbers.fractal) == (
        entropy.n_boxes, entropy.n_boundary_boxes, entropy.fractal_boundary)
    text = numbers.markdown()
    assert f"{numbers.sb:.4f}" in text and f"{numbers.sbb:.4f}" in text
    assert all(meaning in text for meaning in numbers.meanings)


def test_a_map_of_continuous_values_has_no_numbers():
    e = explorer(quantity="lyapunov_max")
    assert e.numbers(e.compute()) is None


def test_on_request_numbers_are_registered_by_name():
    from sweep.explore import numbers

    e = explorer()
    e.update(resolution=40)  # the grid's exponent needs 32 pixels per axis or more
    e.zoom((-3.0, -1.0), (3.0, 8.0))
    result = e.compute()
    text = numbers.ON_REQUEST["uncertainty exponent (grid scale)"](result, e)
    assert "alpha" in text or "too few" in text
    with pytest.raises(TypeError, match="function must be callable"):
        numbers.register_on_request("wada", 3)
    with pytest.raises(TypeError, match="name must be a non-empty string"):
        numbers.register_on_request("", lambda result, explorer: "")
    try:
        numbers.register_on_request("count", lambda result, explorer: f"{result.values.size}")
        assert numbers.ON_REQUEST["count"](result, e) == f"{40 * 40}"
    finally:
        numbers.ON_REQUEST.pop("count", None)


# ------------------------------------------------------------------ every map kind
CASES = [(demo, q) for q in ("well", "motion", "lyapunov_max", "amplitude", "var:theta_final",
                              "var:omega_final", "var:winding", "var:theta_max",
                              "var:omega_mean", "var:energy_final", "var:tension_max",
                              "var:top_distance_max")]
CASES += [(wada, "basins"), (wada, "period"), (wada, "motion"), (torque, "motion"),
          (torque, "amplitude"), (pivot, "inverted")]


@pytest.mark.parametrize("make, quantity", CASES,
                         ids=[f"{m.__name__}-{q}" for m, q in CASES])
def test_every_map_kind(make, quantity):
    e = explorer(make)
    assert quantity in e.quantities()
    e.update(quantity=quantity)
    result = e.compute()
    s = e.state
    assert result.values.shape == (N, N)
    q = QUANTITIES[quantity]
    kwargs = e.run_kwargs()
    if e.uses_pilot():
        assert result.catalogue is not None
        kwargs["attractors"] = maps.pilot_catalogue(s.scene, e.grid(), model.PILOT_POINTS,
                                                    **kwargs)
    ds = sweep.run(s.scene, e.grid(), progress=False, **kwargs)
    expected = q.compute(ds).squeeze().transpose(s.view.y, s.view.x).values
    np.testing.assert_array_equal(result.values, expected)
    if q.discrete:
        assert result.legend and all(text for _, text in result.legend)
        assert np.isfinite(result.image).all()  # every pixel has a legend entry
    else:
        units = QUANTITIES[quantity].compute(ds).attrs.get("units", "1")
        assert units == "1" or "[" in result.title  # the colour bar names the units


def test_forced_basins_name_their_attractors():
    e = explorer(wada)
    result = e.compute()
    assert e.state.quantity == "basins" and e.uses_pilot()
    texts = [text for value, text in result.legend if value >= 0]
    assert texts and all(t.startswith("attractor") and "period" in t for t in texts)


def test_parameter_axes():
    e = explorer(pivot)
    assert (e.state.view.x, e.state.view.y) == ("pivot_amplitude", "pivot_frequency")
    assert dict(e.state.start)["theta0"] == pytest.approx(np.pi - 0.1)
    assert e.state.quantity == "motion" and "inverted" in e.quantities()
    e.update(quantity="inverted")
    grid = e.grid()
    assert grid.dims == ("pivot_frequency", "pivot_amplitude", "theta0", "omega0")
    assert e.compute().values.dtype == bool


# ------------------------------------------------------------------ controls
def test_controls_come_from_the_declarations():
    e = explorer(wada)
    names = [c.name for c in e.parameter_controls()]
    assert names == ["length", "gravity", "damping", "forcing_amplitude",
                     "forcing_frequency", "forcing_phase"]
    damping = e.parameter_controls()[2]
    assert damping.label == "damping c [1/s]" and damping.minimum == 0.0
    assert [c.name for c in e.run_controls()] == ["model", "t_end", "dt", "t_transient",
                                                  "method", "resolution", "route"]
    # the route control is the forced basins map's (over the initial state) alone
    assert [c.name for c in explorer().run_controls()][-1] == "resolution"


def test_an_effect_registered_later_gets_its_controls():
    @dataclass(frozen=True)
    class Spring(Effect):
        stiffness: float
        declaration: ClassVar[EffectDeclaration] = EffectDeclaration(
            name="explore_spring", term="- kappa * th", equation="- kappa theta",
            parameters=(Parameter("spring_kappa", "stiffness", "kappa", "s-2", "1/s^2",
                                  "torsion spring stiffness", minimum=0.0),),
            conservative=True, linear_stiffness="kappa", jacobian_theta="- kappa")

    register(Spring)
    try:
        scene = sweep.Scene(effects=(sweep.Damping(0.3), Spring(2.0)))
        e = Explorer(scene, sweep.Grid(theta0=np.linspace(-1, 1, N),
                                       omega0=np.linspace(-1, 1, N)), t_end=1.0, dt=0.01)
        spring = [c for c in e.parameter_controls() if c.name == "spring_kappa"]
        assert spring and spring[0].label == "spring_kappa kappa [1/s^2]"
        assert "spring_kappa" in e.axes()
        e.update(spring_kappa=3.0)
        assert e.state.scene.effect("explore_spring").stiffness == 3.0
        with pytest.raises(InvalidInput, match="stiffness"):
            e.update(spring_kappa=-1.0)
    finally:
        unregister("explore_spring")


# ------------------------------------------------------------------ invalid input
@pytest.mark.parametrize("change, control, words", [
    ({"damping": -0.5}, "damping", ["coefficient", "-0.5", ">= 0"]),
    ({"gravity": 0.0}, "gravity", ["gravity", "> 0"]),
    ({"dt": 0.03}, "dt", ["whole number of steps"]),
    ({"dt": -1.0}, "dt", ["dt", "-1.0"]),
    ({"t_transient": 50.0}, "t_transient", ["t_transient"]),
    ({"resolution": 3}, "resolution", ["resolution", "8 to 2000", "3"]),
    ({"resolution": 40.5}, "resolution", ["resolution", "40.5"]),
    ({"quantity": "basins"}, "quantity", ["basins", "does not apply", "well"]),
    ({"method": "rk5"}, "method", ["rk5", "rk4"]),
    ({"model": "cubic"}, "model", ["cubic", "nonlinear"]),
    ({"x": "forcing_amplitude"}, "x", ["forcing_amplitude", "theta0"]),
    ({"damping": "0.5"}, "damping", ["number", "'0.5'"]),
    ({"damping": "__import__('os').system('true')"}, "damping", ["number"]),
    ({"damping": True}, "damping", ["number"]),
    ({"theta0": float("nan")}, "theta0", ["theta0"]),
])
def test_refused_input_names_the_control_and_computes_nothing(monkeypatch, change, control,
                                                              words):
    e = explorer()
    before = e.state
    monkeypatch.setattr(Explorer, "_run", staticmethod(lambda *a: pytest.fail("ran")))
    with pytest.raises(InvalidInput) as info:
        e.update(**change)
    assert info.value.control == control
    for word in words:
        assert word in str(info.value), (word, str(info.value))
    assert e.state == before and e.history == [before.view]


def test_refused_windows():
    e = explorer()
    for window in [((1.0, 1.0), (0.0, 1.0)), ((2.0, 1.0), (0.0, 1.0)),
                   ((0.0, math.inf), (0.0, 1.0)), (("a", 1.0), (0.0, 1.0))]:
        with pytest.raises(InvalidInput) as info:
            e.zoom(*window)
        assert info.value.control == "view"
    e.update(x="damping")
    with pytest.raises(InvalidInput, match="damping"):  # c < 0 on the axis
        e.zoom((-1.0, 1.0), e.state.view.y_range)


def test_unknown_run_keyword_is_refused():
    scene, grid, kwargs = demo()
    with pytest.raises(TypeError, match="dtt"):
        Explorer(scene, grid, dtt=0.1, **kwargs)
    with pytest.raises(TypeError, match="t_end"):
        Explorer(scene, grid, dt=0.1)


def test_a_forced_run_file_without_a_strobe_period_opens_on_motion():
    """examples/forced.toml with dt = 0.01 (its step until it was made to fit the basins
    map), which does not divide its forcing period 3 pi: no stroboscopic samples, so no
    basins; the explorer opens on the motion map and says why (it used to refuse to
    start). Asking for basins explicitly is still refused. Nothing is computed: the
    constructor only validates."""
    scene, grid, kwargs = load_run("examples/forced.toml", {})
    kwargs = dict(kwargs, t_end=120.0, dt=0.01)
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, N), omega0=np.linspace(-3, 3, N))
    with pytest.warns(UserWarning, match=r"attractor basins .* not a whole number of "
                                         r"steps .* showing the motion map"):
        e = Explorer(scene, grid, resolution=N, **kwargs)
    assert e.state.quantity == "motion"
    with pytest.raises(InvalidInput, match="not a whole number of steps"):
        Explorer(scene, grid, resolution=N, quantity="basins", **kwargs)


# ------------------------------------------------------------------ reproduction
def test_the_run_file_of_a_driven_map_counts_drive_periods(tmp_path):
    """The download of examples/forced.toml's map gives its times as the file does, in
    drive periods with the seconds in a comment, and reads back as the very same
    floats (`sweep.toml_periods.run_lines`); it wrote t_end = 245.04422698000386.
    Nothing is computed."""
    scene, grid, kwargs = load_run("examples/forced.toml", {})
    e = Explorer(scene, grid, resolution=N, **kwargs)
    text = e.toml_text()
    for line in ("t_end = {periods = 26}  # 245.04422698000386 s",
                 "dt = {per_period = 1000}  # 0.00942477796076938 s",
                 "t_transient = {periods = 10}  # 94.24777960769379 s", "t0 = 0.0"):
        assert f"\n{line}\n" in text, text
    path = tmp_path / "map.toml"
    path.write_text(text)
    _, _, again = load_run(path, {})
    for key in ("t0", "t_end", "dt", "t_transient"):
        assert again[key].hex() == kwargs[key].hex(), key  # the same bits


@pytest.mark.parametrize("make", [demo, wada], ids=["demo", "wada"])
def test_toml_and_python_reproduce_the_map_exactly(make, tmp_path):
    e = explorer(make)
    e.zoom(*[(lo + 0.1 * (hi - lo), hi - 0.3 * (hi - lo)) for lo, hi in
             (e.state.view.x_range, e.state.view.y_range)])
    result = e.compute()
    path = tmp_path / "map.toml"
    path.write_text(e.toml_text())
    options = {}
    scene, grid, kwargs = load_run(path, options)
    if options.get("pilot"):  # what sweep run --pilot does
        kwargs["attractors"] = maps.pilot_catalogue(scene, grid, options["pilot"], **kwargs)
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    q = QUANTITIES[e.state.quantity]
    np.testing.assert_array_equal(q.compute(ds).squeeze().values, result.values)
    namespace = {}
    exec(e.python_snippet(), namespace)  # our own generated text, nothing typed
    np.testing.assert_array_equal(namespace["image"].squeeze().values, result.values)


def test_trajectory_is_the_clicked_pixel_and_reproduces(tmp_path):
    e = explorer(wada)
    result = e.compute()
    traj = e.trajectory(0.31, -1.07, result)
    row, col = e.value_at(result, 0.31, -1.07)
    assert (traj.theta0, traj.omega0) == (result.x[col], result.y[row])
    assert traj.theta[0] == traj.theta0 and traj.omega[0] == traj.omega0
    assert traj.status == "ok" and traj.label.startswith(result.legend[
        int(result.image[row, col])][1])
    assert traj.strobe_theta.size == 40  # one per forcing period after the transient
    assert traj.t[-1] == pytest.approx(e.state.t_end, rel=1e-12)
    path = tmp_path / "trajectory.toml"
    path.write_text(traj.toml)
    scene, grid, kwargs = load_run(path)
    ds = sweep.run(scene, grid, progress=False, **kwargs)
    np.testing.assert_array_equal(ds.theta.values.ravel(), traj.theta)
    namespace = {}
    exec(traj.python.replace("sweep.plot.trajectory(ds)", "pass"), namespace)
    np.testing.assert_array_equal(namespace["ds"].omega.values.ravel(), traj.omega)


# ------------------------------------------------------------------ exports
def test_netcdf_export_has_the_provenance_and_the_map(tmp_path):
    e = explorer(wada)
    result = e.compute()
    path = tmp_path / "export.nc"
    path.write_bytes(e.netcdf_bytes(result))
    ds = sweep.load(path)
    for key in ("sweep_version", "scene", "equation", "t_end", "dt", "observe", "history"):
        assert key in ds.attrs
    assert ds.attrs["explore_quantity"] == "basins"
    np.testing.assert_array_equal(ds[ds.attrs["explore_map"]].values, result.values)
    again = sweep.run(sweep.io.scene_from(ds), sweep.Grid(**{d: ds[d].values for d in
                                                            ds.attrs["grid_axes"].split()}),
                      progress=False, **sweep.io.run_arguments(ds))
    np.testing.assert_array_equal(maps.basins(again).values, result.values)


def test_png_export():
    """The PNG download draws the angle axes in degrees, as the page does (it drew rad)."""
    e = explorer()
    result = e.compute()
    data = e.png_bytes(result)
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    ax = e.png_figure(result).axes[0]
    assert "deg" in ax.get_xlabel() and "deg/s" in ax.get_ylabel(), (ax.get_xlabel(),
                                                                      ax.get_ylabel())


# ------------------------------------------------------------------ command line
@pytest.mark.parametrize("argv, words", [
    (["explore", "--port", "70000"], ["--port", "70000", "0 to 65535"]),
    (["explore", "no-such-run-file.toml"], ["no-such-run-file.toml"]),
    (["explore", "--device", "tpu"], ["--device", "tpu"]),
])
def test_sweep_explore_errors_are_one_line(capsys, argv, words):
    from sweep.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("sweep: error:") or "error:" in err[-1]
    for word in words:
        assert word in err[-1]


def test_sweep_explore_refuses_a_run_file_the_explorer_cannot_use(capsys, tmp_path):
    from sweep.cli import main

    path = tmp_path / "one_axis.toml"
    path.write_text("[grid]\ntheta0 = [0.0, 1.0]\n[run]\nt_end = 1.0\ndt = 0.3\n")
    assert main(["explore", str(path), "--no-browser"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sweep: error:") and "dt" in err[0]


def test_the_view_is_tested_for_fractality_and_below_the_grid_on_request():
    """The forced Wada window: the fractality test of the view's labels is
    `fractality_test`'s own; below the grid's scale, new starts labelled by the
    explorer's catalogue agree with the map's pixels (same label function, same
    catalogue) and the boundary reads fractal and Wada (alpha ~ 0.15 and W3 ~ 0.99 on
    this scene, docs/guide/map_accuracy.md; here a short 60-period run)."""
    from sweep.explore import numbers
    from sweep.maps import metrics

    e = explorer(wada)
    e.update(resolution=64)
    result = e.compute()
    text = numbers.ON_REQUEST["fractality test (Puy et al.)"](result, e)
    # the ball of sweep.maps.describe_boundary: 64 // 40 pixels, at least 3
    expected = metrics.fractality_test(np.asarray(result.image).astype(np.int64), radius=3,
                                       n_balls=1000, rng=0)
    assert f"{expected.sbb:.4f}" in text and ("fractal" if expected.fractal else "smooth") \
        in text
    # new starts at the pixel centres get the labels the map's run gave them: the same
    # run, labelled by the catalogue's index instead of basins' numbering by size
    labels_of = numbers.view_labels_of(result, e)
    grid = e.grid(result.state)
    rows, cols = np.meshgrid(np.arange(0, 64, 9), np.arange(0, 64, 7), indexing="ij")
    starts = np.column_stack([grid.axes["theta0"][cols.ravel()],
                              grid.axes["omega0"][rows.ravel()]])
    fresh = labels_of(starts)
    pixels = np.asarray(result.values)[rows.ravel(), cols.ravel()]
    # one label per catalogue index: the map's basins and the catalogue agree start by
    # start up to their numbering (a bijection between the two)
    pairs = set(zip(fresh.tolist(), pixels.tolist()))
    assert len(pairs) == len({a for a, _ in pairs}) == len({b for _, b in pairs})
    below = numbers.ON_REQUEST["below the grid's scale: sampled exponent, Wada test"](
        result, e)
    alpha = float(below.split("scale: alpha = ")[1].split()[0])
    assert 0.05 < alpha < 0.3  # measured 0.139 +- 0.009 here
    assert "Wada test (grid method, 6 steps" in below and "): Wada (" in below


def test_below_the_grid_is_refused_for_a_systems_explorer():
    from sweep.explore import numbers

    class Bare:  # a SystemExplorer has no quantity_info / uses_pilot of a scene
        pass

    class Result:
        state = None

    with pytest.raises(ValueError, match="pendulum scene only"):
        numbers.view_labels_of(Result(), Bare())


def test_known_cells_background_is_cached_per_catalogue(monkeypatch):
    """`Explorer.known` keeps one background per catalogue (`Explorer.pilot_key`): a
    state with a catalogue of its own (another start) or other run settings (``t0``)
    gets a background of its own, computed with its own catalogue. Stubs stand for the
    pilot and the backgrounds: only the caching is checked."""
    import sweep.maps.known as known_module

    backgrounds = []

    def fake_background(scene, theta, omega, catalogue, fixed=None, **run_kwargs):
        backgrounds.append((catalogue, run_kwargs))
        return object(), 0

    monkeypatch.setattr(maps, "pilot_catalogue", lambda *args, **kwargs: {})
    monkeypatch.setattr(known_module, "background", fake_background)
    scene, _, kwargs = wada()
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 96), omega0=np.linspace(-4, 4, 96))
    e = model.Explorer(scene, grid, resolution=96, **kwargs)
    home = e.state
    first = e.known(home)
    assert e.known(home) is first and len(backgrounds) == 1  # cached
    moved = dataclasses.replace(home, start=tuple((n, v + 0.5) for n, v in home.start))
    assert e.uses_known(moved) and e.catalogue(moved) is not e.catalogue(home)
    assert e.known(moved) is not first and backgrounds[-1][0] is e.catalogue(moved)
    later = dataclasses.replace(home, extra=(("t0", PERIOD),))
    assert e.known(later) is not first and backgrounds[-1][1]["t0"] == PERIOD
    # what the key leaves out cannot reach a background: one pilot quantity, the CPU
    assert [q.name for q in QUANTITIES.values() if q.pilot] == ["basins"]
    assert e.known(dataclasses.replace(home, device="cuda")) is None


def test_forced_basins_stop_on_known_cells_by_default_and_the_exact_route_agrees():
    """The Wada window at the full settings (320 periods, 100 steps each) and 96 x 96
    pixels: by default the map's trajectories stop on the known cells of a background
    of the home window (issue 37; 24 and 48 pixels a side here), and the status says so;
    the exact route (the catalogue alone) gives every start the same label (measured:
    none differs, home window and zoom; at 48 pixels 1 % did, so the explorer takes the
    exact route below `KNOWN_MIN_RESOLUTION`)."""
    scene, _, _ = wada()
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 96), omega0=np.linspace(-4, 4, 96))
    e = model.Explorer(scene, grid, resolution=96, t_end=320 * PERIOD, dt=PERIOD / 100,
                       t_transient=20 * PERIOD)
    assert e.uses_known() and [c.name for c in e.run_controls()][-1] == "route"
    known = e.compute()
    assert known.route.startswith("catalogue + known cells: 9216 starts computed, ")
    stopped = int(known.route.split(", ")[1].split()[0])
    assert 0 < stopped <= 9216 and int(known.ds["stopped_known"].sum()) == stopped
    e.update(route="exact")
    assert not e.state.known_cells and not e.uses_known() and e.known() is None
    exact = e.compute()
    assert exact.route == "catalogue (exact route): 9216 starts computed"
    assert "stopped_known" not in exact.ds
    np.testing.assert_array_equal(known.values, exact.values)
    e.update(route="known cells")
    e.zoom((-1.0, 0.0), (1.0, 2.0))  # stops on the home window's background too
    zoomed = e.compute()
    assert int(zoomed.ds["stopped_known"].sum()) > 0
    e.update(route="exact")
    np.testing.assert_array_equal(zoomed.values, e.compute().values)
    e.update(route="known cells", resolution=48)  # too coarse a background: exact
    assert not e.uses_known()
    assert e.compute().route.endswith("(known cells from 96 pixels per axis): 2304 starts "
                                      "computed")
    with pytest.raises(model.InvalidInput, match="route must be one of known cells, exact"):
        e.update(route="fast")
