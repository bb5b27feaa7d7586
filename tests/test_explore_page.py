"""The explorer's page without a browser (sweep.explore.app; needs Panel and Bokeh): what
is sent for a picture (one byte per pixel for labels), the colour bar's ticker kept, the
debounce of range changes, a newer zoom dropping an older one's pictures, progressive
steps, and the numbers of the view under the map."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

import sweep

pytest.importorskip("panel")
pytest.importorskip("bokeh")

from sweep.explore import app as explore_app
from sweep.explore import model
from sweep.explore.app import ExplorerApp, wire_image
from sweep.explore.model import Explorer

N = 40  # pixels per axis: small maps; 32 or more for the grid's uncertainty exponent
WINDOW = ((-3.0, -1.0), (3.0, 8.0))  # the demo's wells 0, 1 and 2 meet here


def demo_app(**extra) -> ExplorerApp:
    from sweep.cli import demo_inputs

    scene, grid, kwargs = demo_inputs(N)
    return ExplorerApp(scene, grid, resolution=N, **kwargs, **extra)


def wait_for(predicate, timeout=60.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.02)
    return False


@pytest.fixture
def session():
    """A page without a document: the worker's callbacks draw at once (as in a
    notebook)."""
    page = explore_app._Session(demo_app())
    assert page.requests.idle(60)
    yield page
    page.requests.close()


def _zoom_to(page, window):
    (x0, x1), (y0, y1) = window
    page.map.x_range.update(start=x0, end=x1)
    page.map.y_range.update(start=y0, end=y1)
    page._zoom()


def _final_shown(page, request):
    """The final map of ``request`` is on the page."""
    shown = [r for _, r, event, _ in page.timeline if event == "final"]
    return (page.latest == request and bool(shown) and shown[-1] == request
            and page.source.data["stage"] == ["final"])


def test_a_label_map_is_sent_as_one_byte_per_pixel_and_a_continuous_one_as_float32():
    from sweep.cli import demo_inputs

    scene, grid, kwargs = demo_inputs(N)
    e = Explorer(scene, grid, resolution=N, **kwargs)
    labels = e.compute()
    sent = wire_image(labels)
    assert sent.dtype == np.uint8 and sent.shape == (N, N)
    np.testing.assert_array_equal(sent, labels.image)  # the legend index, exactly
    e.update(quantity="lyapunov_max")
    values = e.compute()
    sent = wire_image(values)
    assert sent.dtype == np.float32
    np.testing.assert_array_equal(sent, values.image.astype(np.float32))


def test_the_page_draws_the_final_map_with_its_stage_and_its_numbers(session):
    _zoom_to(session, WINDOW)
    request = session.latest
    assert wait_for(lambda: _final_shown(session, request)
                    and "Sb" in session.numbers.object)
    data = session.source.data
    assert data["image"][0].dtype == np.uint8
    assert (data["x"][0], data["y"][0]) == (WINDOW[0][0], WINDOW[1][0])
    numbers = session.explorer.numbers(session.result)
    assert session.numbers.object == numbers.markdown()
    assert session.caption.object == session.result.caption  # long name and CF comment
    assert "python" in session.map_python.object  # written after the picture
    events = [event for _, r, event, _ in session.timeline if r == request]
    assert events[0] == "zoom" and events[1] == "submit"
    assert events.index("final") < events.index("numbers")


def test_the_colour_bar_keeps_its_ticker_model(session):
    ticker = session.colorbar.ticker
    assert ticker is session.ticker
    _zoom_to(session, WINDOW)  # other wells: other ticks, in the same model
    request = session.latest
    assert wait_for(lambda: _final_shown(session, request))
    assert session.colorbar.ticker is ticker
    assert list(ticker.ticks) == list(range(len(session.result.legend)))


@pytest.mark.parametrize("low, high, want", [
    (0.0, 1.0, [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]),
    (-3.0, -1.0, [-3.0, -2.5, -2.0, -1.5, -1.0]),
    (0.0, 1e-4, [0.0, 2e-05, 4e-05, 6e-05, 8e-05, 1e-04]),  # no rounding noise
    # narrow against its values: 12 significant digits drew 12345.6 three times
    (12345.6, 12345.6000001, [12345.6, 12345.60000002, 12345.60000004, 12345.60000006,
                              12345.60000008, 12345.6000001]),
    (-9e307, 9e307, [-9e307, 9e307]),  # a span beyond float64: matplotlib raised
    (1e-300, 2e-300, [1e-300, 2e-300]),  # matplotlib's ticks all fell outside: none
])
def test_a_continuous_colour_bar_gets_distinct_round_ticks_inside_its_range(low, high, want):
    got = explore_app._nice_ticks(low, high)
    assert got == want  # exact: each tick is rounded to the digits that tell them apart
    assert len(set(got)) == len(got) and all(low <= v <= high for v in got)


def test_range_changes_wait_for_a_quiet_debounce_before_the_zoom():
    page = explore_app._Session(demo_app())
    try:
        assert page.requests.idle(60)
        timers = []

        class Doc:  # the document's timer, recorded instead of run
            session_context = None

            def add_timeout_callback(self, callback, milliseconds):
                timers.append(milliseconds)
                return object()

        page.doc = Doc()
        before = page.latest
        page._range_changed("start", 0.0, 1.0)
        page._range_changed("end", 0.0, 1.0)  # the same zoom: one timer
        assert timers == [explore_app.DEBOUNCE_MS]
        page._zoom()  # fired while changes are fresh: waits for the rest of the quiet
        assert len(timers) == 2 and 1 <= timers[1] <= explore_app.DEBOUNCE_MS
        assert page.latest == before  # nothing submitted yet
        page.last_change -= explore_app.DEBOUNCE_MS / 1000.0  # quiet since
        page.map.x_range.update(start=WINDOW[0][0], end=WINDOW[0][1])
        page.last_change -= explore_app.DEBOUNCE_MS / 1000.0
        page._zoom()
        assert page.latest == before + 1
    finally:
        page.requests.close()


def test_a_newer_zoom_drops_the_older_ones_pictures(session, monkeypatch):
    monkeypatch.setattr(model, "BAND_MIN", 1)
    monkeypatch.setattr(model, "BAND_SECONDS", 1e-12)  # as a slow map: 8 bands
    monkeypatch.setattr(model, "STEP_SECONDS", 0.0)  # and a step after 1, 2, 4
    monkeypatch.setattr(model, "PREVIEW_AFTER", 0.0)
    entered, release = threading.Event(), threading.Event()
    run = Explorer._run

    def held(state, grid, kwargs):
        if state.view.x_range == WINDOW[0] and grid.shape[0] < N // 4:  # a band, held
            entered.set()
            assert release.wait(30)
        return run(state, grid, kwargs)

    monkeypatch.setattr(Explorer, "_run", staticmethod(held))
    _zoom_to(session, WINDOW)
    first = session.latest
    assert entered.wait(60)  # the first zoom's final map is computing
    newer = ((-1.0, 1.0), (-2.0, 2.0))
    _zoom_to(session, newer)
    second = session.latest
    release.set()
    assert wait_for(lambda: _final_shown(session, second))
    assert session.requests.idle(60)
    assert session.result.state.view.x_range == newer[0]
    first_events = [event for _, r, event, _ in session.timeline if r == first]
    assert "final" not in first_events and "numbers" not in first_events
    assert first_events.count("step") <= 1  # it stopped at its next band
    second_events = [event for _, r, event, _ in session.timeline if r == second]
    assert second_events[-2:] == ["final", "numbers"]
    assert second_events.count("step") == 3  # after 1, 2 and 4 of 8 bands
    # a picture or numbers of the older request still queued for the event loop when
    # the newer one was submitted: dropped
    data, numbers = dict(session.source.data), session.numbers.object
    stale = session.explorer.compute(session.explorer.zoom(*WINDOW))
    session._show(first, stale)
    session._show_numbers(first, stale, session.explorer.numbers(stale))
    assert session.source.data["x"] == data["x"] and session.numbers.object == numbers
    assert session.result.state.view.x_range == newer[0]


def test_numbers_on_request_run_off_the_event_loop_and_show_on_the_page(session):
    assert session.on_request.visible and session.on_request_button.visible
    session.on_request.value = "uncertainty exponent (grid scale)"
    _zoom_to(session, WINDOW)
    request = session.latest
    assert wait_for(lambda: _final_shown(session, request))
    session._request_numbers()
    assert wait_for(lambda: "alpha" in session.on_request_text.object
                    or "too few" in session.on_request_text.object)
    session.explorer.update(quantity="lyapunov_max")
    session._submit()
    request = session.latest
    assert wait_for(lambda: _final_shown(session, request)
                    and session.result.state.quantity == "lyapunov_max")
    session._request_numbers()  # a map of continuous values: nothing to count
    assert "refused" in session.on_request_text.object
    # the panel's text follows the final picture from the worker (not in the same tick)
    assert wait_for(lambda: "continuous" in session.numbers.object)


def test_the_systems_page_sends_float32_values_and_says_they_have_no_numbers():
    from sweep.explore.system_app import SystemExplorerApp

    app = SystemExplorerApp(sweep.DoublePendulum(),
                            sweep.Grid(theta1_0=np.linspace(-3, 3, 16),
                                       theta2_0=np.linspace(-3, 3, 16)),
                            t_end=0.5, dt=0.01, resolution=16)
    page = explore_app._Session.__new__(app.session_class)
    explore_app._Session.__init__(page, app)
    try:
        request = page.latest
        assert wait_for(lambda: _final_shown(page, request))
        assert page.source.data["image"][0].dtype == np.float32  # flip times: values
        assert wait_for(lambda: "continuous" in page.numbers.object)
    finally:
        page.requests.close()


def test_the_app_lists_open_pages_without_keeping_closed_ones_alive():
    import gc

    app = demo_app()
    page = explore_app._Session(app)
    assert app.sessions == [page]
    page.requests.close()
    page.requests._thread.join(30)  # the worker holds the page until it stops
    del page
    gc.collect()
    assert app.sessions == []  # a closed page's maps are freed
