"""The explorer in a real browser: Debian's chromium and chromium-driver, driven by
Selenium, against a server on a free port.

Under CI (``CI=true``) a missing browser, driver, Selenium or Panel fails the run (`.ci/run`
installs them); elsewhere these tests skip with a message. The README's screenshot is
taken here: with ``SWEEP_README_SCREENSHOT=1`` the last screenshot is also copied to
docs/images/explorer.png.
"""

from __future__ import annotations

import os
import shutil
import threading
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
IN_CI = os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no", "off")


def _missing(reason: str):
    if IN_CI:
        pytest.fail(f"CI=true but {reason}: .ci/run installs chromium and chromium-driver "
                    "(apt) and the test extra (selenium, panel)", pytrace=False)
    pytest.skip(f"{reason}: install chromium and chromium-driver (apt) and "
                "pip install -e '.[test]' to run the browser tests")


def _binaries():
    browser = next((p for p in (shutil.which("chromium"), shutil.which("chromium-browser"),
                                shutil.which("google-chrome")) if p), None)
    driver = shutil.which("chromedriver")
    return browser, driver


@pytest.fixture(scope="module")
def app():
    try:
        from sweep.explore.app import ExplorerApp
    except ImportError as exc:
        _missing(f"Panel/Bokeh are not importable ({exc})")
    from sweep.cli import demo_inputs

    scene, grid, kwargs = demo_inputs(400)  # the demo scene; 400 x 400: screen resolution
    explorer = ExplorerApp(scene, grid, **kwargs)
    explorer.serve(port=0)  # warms up, then serves on a free port of 127.0.0.1
    yield explorer
    explorer.stop()


#: The browser window [px]: a laptop's (the page must fit its width).
WINDOW = (1400, 1000)


def console_warnings(driver) -> list[str]:
    """BokehJS's warnings in the browser's console since the last call (the log is
    drained as it is read); "could not set initial ranges" was logged ~30 times per page
    when the trajectory panels had data ranges over no data."""
    return [entry["message"].split(" ", 2)[-1] for entry in driver.get_log("browser")
            if "[bokeh" in entry["message"] and entry["level"] in ("WARNING", "SEVERE")]


#: The page's width against the window's: what it scrolls over, what it shows (the
#: window less a vertical scroll bar) and the window.
_WIDTH = """
const e = document.documentElement;
return {scroll: e.scrollWidth, client: e.clientWidth, inner: window.innerWidth};
"""

#: The map's colour-bar title as drawn: its text, where the text starts and ends on the
#: canvas (its width measured in its font), the bar's left edge, the canvas width, and
#: the ColorBar's own (rotated) title, which must be empty.
_COLOUR_TITLE = """
const m = Bokeh.documents[0].get_model_by_name('map');
const view = Bokeh.index.find_one(m);
const title = m.above.find((r) => r.name === 'colour_title');
const bar = m.right.find((r) => r.color_mapper !== undefined);
if (!title || !bar) return null;
const ctx = document.createElement('canvas').getContext('2d');
ctx.font = `${title.text_font_style} ${title.text_font_size} ${title.text_font}`;
const left = view.frame.bbox.left + title.offset;
return {text: title.text, left: left, right: left + ctx.measureText(title.text).width,
        bar_left: view.views.find_one(bar).bbox.left + bar.padding,
        canvas: view.canvas_view.bbox.width, bar_title: bar.title || ""};
"""


def check_layout(driver, title_word: str) -> None:
    """The page fits the window's width (no horizontal scroll bar), the colour bar's
    title (containing ``title_word``) is horizontal above the bar and inside the canvas,
    and BokehJS logged no warning."""
    width = driver.execute_script(_WIDTH)
    assert width["inner"] == WINDOW[0] and width["scroll"] <= width["client"], width
    drawn = _wait(driver, _COLOUR_TITLE, lambda t: title_word in t["text"])
    assert drawn["bar_title"] == "", drawn  # no rotated title beside the bar
    # over the bar (to the pixel: both are placed from the frame's right edge and the
    # bar's padding) and wholly on the canvas
    assert abs(drawn["left"] - drawn["bar_left"]) <= 1 and drawn["right"] <= drawn["canvas"], \
        drawn
    assert console_warnings(driver) == []


def _fresh_driver():
    """A new headless chromium (its own process and empty cache)."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.options import Options
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _missing("selenium is not installed")
    browser, chromedriver = _binaries()
    if browser is None or chromedriver is None:
        _missing("chromium or chromedriver not found on PATH")
    options = Options()
    options.binary_location = browser
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", f"--window-size={WINDOW[0]},{WINDOW[1]}",
                     "--force-device-scale-factor=1"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})  # `console_warnings`
    return webdriver.Chrome(service=Service(chromedriver), options=options)


@pytest.fixture(scope="module")
def driver():
    d = _fresh_driver()
    yield d
    d.quit()


#: The map's image data as the page holds it: shape, a checksum that changes with any
#: value, the glyph's window (x, y, dw, dh) and the figure's ranges.
_MAP = """
if (!window.Bokeh || !Bokeh.documents.length) return null;
const doc = Bokeh.documents[0];
const m = doc.get_model_by_name('map');
if (!m) return null;
const src = m.renderers[0].data_source;
const img = src.data.image[0];
if (!img || img.length === undefined) return null;
let sum = 0, weighted = 0;
for (let i = 0; i < img.length; i++) {
  const v = Number.isFinite(img[i]) ? img[i] : -7; sum += v; weighted += v * (i % 9973);
}
const shape = img.shape ? Array.from(img.shape) : [img.length];
return {n: img.length, shape: shape, sum: sum, weighted: weighted,
        x: src.data.x[0], y: src.data.y[0], dw: src.data.dw[0], dh: src.data.dh[0],
        xr: [m.x_range.start, m.x_range.end], yr: [m.y_range.start, m.y_range.end],
        title: m.title.text, stage: src.data.stage[0]};
"""

#: Viewport coordinates of the map's frame (the plotting area).
_FRAME = """
const m = Bokeh.documents[0].get_model_by_name('map');
const view = Bokeh.index.find_one(m);
const canvas = view.canvas_view.el.getBoundingClientRect();
const b = view.frame.bbox;
return {left: canvas.left + b.left, top: canvas.top + b.top, width: b.width,
        height: b.height, xr: [m.x_range.start, m.x_range.end],
        yr: [m.y_range.start, m.y_range.end]};
"""

_TRAJECTORY = """
const t = Bokeh.documents[0].get_model_by_name('trajectory');
if (!t) return null;
const src = t.renderers[0].data_source;
const theta = src.data.theta, omega = src.data.omega;
if (!theta || !theta.length) return {title: t.title.text, n: 0};
return {title: t.title.text, n: theta.length, theta0: theta[0], omega0: omega[0]};
"""

#: Each trajectory panel's legends: their labels, and whether a visible one overlaps the
#: plotting area (the frame, where the curves are), in canvas pixels.
_LEGENDS = """
const out = {};
for (const name of ['trajectory', 'phase']) {
  const fig = Bokeh.documents[0].get_model_by_name(name);
  const view = Bokeh.index.find_one(fig);
  const frame = view.frame.bbox;
  const legends = [];
  for (const r of [...fig.above, ...fig.below, ...fig.left, ...fig.right, ...fig.center]) {
    if (r.items === undefined) continue;  // a Legend has items
    const lv = view.views.find_one(r);
    const b = lv.bbox;
    const labels = r.items.filter((item) => item.visible).map((item) => item.label.value);
    const overlap = b.width > 0 && b.left < frame.right && frame.left < b.right &&
                    b.top < frame.bottom && frame.top < b.bottom;
    legends.push({labels: labels, overlap: overlap,
                  box: [b.left, b.top, b.width, b.height]});
  }
  out[name] = {legends: legends, frame: [frame.left, frame.top, frame.width, frame.height]};
}
return out;
"""

#: The map's colour bar as drawn: the tick values its axis view placed (not only the
#: model's ticker: BokehJS 3.9 kept drawing a colour bar's first ticker after the model
#: was given another), the texts drawn there (it also kept a label map's names once the
#: overrides were emptied), the model's ticks and the colour mapper's range.
_COLOUR_BAR = """
const m = Bokeh.documents[0].get_model_by_name('map');
const view = Bokeh.index.find_one(m);
for (const r of m.right) {
  if (r.color_mapper === undefined) continue;  // a ColorBar has a colour mapper
  const axis = view.views.find_one(r)._axis_view;
  const o = r.major_label_overrides;  // a Map, or a plain object when empty
  const labels = o instanceof Map ? Array.from(o.values()) : Object.values(o || {});
  if (!axis || !axis.tick_coords) return null;
  const drawn = Array.from(axis.tick_coords.major[axis.dimension]);
  const boxes = axis.compute_labels(drawn);  // the texts the axis draws at them
  return {drawn: drawn, texts: Array.from(boxes.items || boxes).map((box) => box.text),
          ticks: Array.from(r.ticker.ticks || []), low: r.color_mapper.low,
          high: r.color_mapper.high, labels: labels};
}
return null;
"""

#: The map's axes as drawn: each one's label, its ticks (in the values the explorer
#: computes with: rad on an angle axis) and the texts drawn at them.
_AXES = """
const m = Bokeh.documents[0].get_model_by_name('map');
const view = Bokeh.index.find_one(m);
const out = [];
for (const axis of [m.below[0], m.left[0]]) {
  const av = view.views.find_one(axis);
  if (!av || !av.tick_coords) return null;
  const drawn = Array.from(av.tick_coords.major[av.dimension]);
  const boxes = av.compute_labels(drawn);
  out.push({label: axis.axis_label, ticks: drawn,
            texts: Array.from(boxes.items || boxes).map((box) => box.text)});
}
return out;
"""


def _number(text: str) -> float:
    return float(text.replace("\u2212", "-"))  # Bokeh's minus sign


def check_degree_axes(driver, labels) -> None:
    """The map's angle axes are labelled ``labels`` (in deg, deg/s), as ``sweep plot``
    draws them, with ticks on round degrees: the texts
    drawn are the ticks (in rad) in degrees, multiples of 15 deg where they are 15 deg
    apart or more."""
    axes = _wait(driver, _AXES, lambda a: all(len(x["ticks"]) >= 3 for x in a))
    assert [a["label"] for a in axes] == list(labels), axes
    for axis in axes:
        degrees = [_number(text) for text in axis["texts"]]
        # the texts are 10 significant digits of the tick in degrees
        assert degrees == pytest.approx(np.degrees(axis["ticks"]), rel=1e-9, abs=1e-9), axis
        step = degrees[1] - degrees[0]
        if step >= 15:
            assert all(d % 15 == 0 for d in degrees), axis


#: Every text shown by a Panel Markdown/Alert model containing a word.
_TEXTS = """
const word = arguments[0];
const out = [];
for (const m of Bokeh.documents[0].all_models) {
  const text = m.text;
  if (typeof text === 'string' && text.includes(word) && m.visible !== false) out.push(text);
}
return out;
"""


def _wait(driver, script, until, timeout=30.0, *args):
    end = time.monotonic() + timeout
    value = None
    while time.monotonic() < end:
        value = driver.execute_script(script, *args)
        if value is not None and until(value):
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s; last value: {value!r}")


def _drag(driver, start, stop):
    """A real mouse drag between two viewport points (the active tool: box-zoom)."""
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver)
    pointer = actions.pointer_action
    pointer.move_to_location(*start).pointer_down()
    for k in range(1, 6):
        pointer.move_to_location(start[0] + (stop[0] - start[0]) * k // 5,
                                 start[1] + (stop[1] - start[1]) * k // 5)
    pointer.pointer_up()
    actions.perform()


def _click(driver, point):
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver)
    actions.pointer_action.move_to_location(*point).click()
    actions.perform()


def _recomputed_for(state, window):
    """The final image (not the preview, nor a progressive step) covers ``window``
    exactly (its glyph's x, y, dw, dh) at 400 x 400."""
    (x0, x1), (y0, y1) = window
    return (state["n"] == 400 * 400 and state["stage"] == "final"
            and np.isclose(state["x"], x0, rtol=1e-9, atol=1e-12)
            and np.isclose(state["x"] + state["dw"], x1, rtol=1e-9, atol=1e-12)
            and np.isclose(state["y"], y0, rtol=1e-9, atol=1e-12)
            and np.isclose(state["y"] + state["dh"], y1, rtol=1e-9, atol=1e-12))


def test_explorer_in_a_real_browser(app, driver, tmp_path):
    driver.get(app.url)
    home = _wait(driver, _MAP, lambda s: s["n"] == 400 * 400 and s["stage"] == "final"
                 and "well" in s["title"], 60)
    driver.save_screenshot(str(tmp_path / "1-home.png"))
    assert home["shape"] == [400, 400]
    check_layout(driver, "well")  # fits 1400 px; the bar's title above it; no warning
    check_degree_axes(driver, ("theta0 [deg]", "omega0 [deg/s]"))
    # the numbers of the view under the map: each well's share, Sb, Sbb and the verdict
    numbers = _wait(driver, _TEXTS, lambda texts: len(texts) == 1, 30, "Sbb")[0]
    assert "share of the view" in numbers and "well 0" in numbers
    assert "on a boundary" in numbers
    # a map of labels: the colour bar names each well at its colour, and draws no other
    # tick (the values between two labels, -0.5 or 0.5, mean nothing)
    bar = _wait(driver, _COLOUR_BAR, lambda b: len(b["ticks"]) > 1)
    assert bar["drawn"] == bar["ticks"] == list(range(len(bar["ticks"]))), bar
    assert all("well" in label for label in bar["labels"]), bar
    assert bar["texts"] == bar["labels"], bar

    # box-zoom: a real mouse drag over the middle of the frame
    frame = driver.execute_script(_FRAME)
    left, top, w, h = frame["left"], frame["top"], frame["width"], frame["height"]
    _drag(driver, (int(left + 0.55 * w), int(top + 0.30 * h)),
          (int(left + 0.80 * w), int(top + 0.55 * h)))
    zoomed = _wait(driver, _MAP, lambda s: s["xr"] != home["xr"] and
                   _recomputed_for(s, (s["xr"], s["yr"])) and s["sum"] != home["sum"])
    # the window is the dragged box (in data units), and the data were recomputed for it:
    # the same 400 x 400 pixels, other values (a scaled image keeps its data and window)
    assert home["xr"][0] < zoomed["xr"][0] < zoomed["xr"][1] < home["xr"][1]
    assert zoomed["dw"] < 0.5 * home["dw"]
    assert zoomed["weighted"] != home["weighted"]
    driver.save_screenshot(str(tmp_path / "2-box-zoom.png"))

    # through the figure's ranges (what wheel zoom and pan change)
    window = ((-3.0, -1.0), (3.0, 8.0))  # crosses the boundaries of wells 0, 1 and 2
    driver.execute_script(
        "const m = Bokeh.documents[0].get_model_by_name('map');"
        "m.x_range.setv({start: arguments[0], end: arguments[1]});"
        "m.y_range.setv({start: arguments[2], end: arguments[3]});",
        window[0][0], window[0][1], window[1][0], window[1][1])
    ranged = _wait(driver, _MAP, lambda s: _recomputed_for(s, window) and
                   s["sum"] != zoomed["sum"])
    assert ranged["shape"] == [400, 400]
    check_degree_axes(driver, ("theta0 [deg]", "omega0 [deg/s]"))  # round degrees in any window
    driver.save_screenshot(str(tmp_path / "3-ranges.png"))

    # click a pixel: the trajectory panel shows that start
    frame = driver.execute_script(_FRAME)
    fx, fy = 0.3, 0.6  # fractions of the frame from its left and its top
    _click(driver, (int(frame["left"] + fx * frame["width"]),
                    int(frame["top"] + fy * frame["height"])))
    traj = _wait(driver, _TRAJECTORY, lambda t: t["n"] > 0)
    x = window[0][0] + fx * (window[0][1] - window[0][0])
    y = window[1][1] - fy * (window[1][1] - window[1][0])
    pixel = (window[0][1] - window[0][0]) / 400, (window[1][1] - window[1][0]) / 400
    # snapped to the pixel centre; the click lands within ~1 screen pixel of the target
    assert abs(traj["theta0"] - x) <= 2 * pixel[0]
    assert abs(traj["omega0"] - y) <= 2 * pixel[1]
    assert f"theta0 = {traj['theta0']:.6g}" in traj["title"]
    info = driver.execute_script(_TEXTS, "status&lt;/strong&gt;")  # Markdown as HTML
    assert len(info) == 1 and "ok" in info[0] and "well" in info[0]
    assert f"{traj['theta0']:.6g}" in info[0] and f"{traj['omega0']:.6g}" in info[0]
    # and in degrees, the map's axes' units
    assert f"({np.degrees(traj['theta0']):.4g} deg)" in info[0]
    assert f"({np.degrees(traj['omega0']):.4g} deg/s)" in info[0]
    assert "stroboscopic" not in info[0]  # an unforced scene has none
    driver.save_screenshot(str(tmp_path / "4-trajectory.png"))
    # the panels' ranges fit the curves (they were 0 to 1 before the click)
    ranges = driver.execute_script(
        "const t = Bokeh.documents[0].get_model_by_name('trajectory');"
        "return [t.x_range.start, t.x_range.end];")
    # t from 0 to the demo's t_end = 40 s, widened by 5 % each side (rel: rounding only)
    assert ranges == pytest.approx([-0.05 * 40.0, 1.05 * 40.0], rel=1e-9), ranges
    assert console_warnings(driver) == []
    # the legends as drawn: beside the curves, never over them; no stroboscopic entry
    legends = driver.execute_script(_LEGENDS)
    assert [g["labels"] for g in legends["trajectory"]["legends"]] == [
        ["theta [rad]", "omega [rad/s]"]]
    assert not legends["phase"]["legends"]  # one curve: nothing to tell apart
    for name in ("trajectory", "phase"):
        assert not any(g["overlap"] for g in legends[name]["legends"]), legends

    # change a parameter: the map changes
    set_value = ("for (const m of Bokeh.documents[0].all_models) {"
                 " if (m.title === arguments[0]) { m.value = arguments[1]; return true; } }"
                 "return false;")
    assert driver.execute_script(set_value, "damping c [1/s]", 0.08)
    damped = _wait(driver, _MAP, lambda s: _recomputed_for(s, window) and
                   s["sum"] != ranged["sum"])
    assert damped["weighted"] != ranged["weighted"]
    driver.save_screenshot(str(tmp_path / "5-parameter.png"))

    # a value the validators refuse: its message beside the control, nothing computed
    assert driver.execute_script(set_value, "damping c [1/s]", -1.0)
    messages = _wait(driver, _TEXTS, lambda texts: len(texts) > 0, 10, "coefficient must be")
    assert "-1.0" in messages[0]
    time.sleep(0.5)
    assert driver.execute_script(_MAP)["sum"] == damped["sum"]
    driver.save_screenshot(str(tmp_path / "6-refused.png"))
    assert driver.execute_script(set_value, "damping c [1/s]", 0.08)  # back to valid

    # a map of values, then labels again: the colour bar's ticks follow, as drawn
    options = driver.execute_script(
        "for (const m of Bokeh.documents[0].all_models)"
        " if (m.title === 'quantity') return [m.value, m.options.map((o) => o[0])];")
    home_quantity, keys = options
    assert "var:theta_final" in keys
    assert driver.execute_script(set_value, "quantity", "var:theta_final")
    _wait(driver, _MAP, lambda s: s["stage"] == "final" and "theta_final" in s["title"])
    bar = _wait(driver, _COLOUR_BAR,  # the values' own texts, no well's name
                lambda b: b["labels"] and not any("well" in x for x in b["labels"]))
    assert len(bar["drawn"]) >= 3 and bar["drawn"] == bar["ticks"], bar
    span = bar["high"] - bar["low"]
    assert all(bar["low"] - 1e-9 * span <= t <= bar["high"] + 1e-9 * span
               for t in bar["drawn"]), bar  # round values inside the colour range
    assert not any("well" in text for text in bar["texts"]), bar  # numbers, not names
    assert [float(text) for text in bar["texts"]] == bar["drawn"], bar
    driver.save_screenshot(str(tmp_path / "7-values.png"))
    check_layout(driver, "theta_final [rad]")  # a longer title than the bar's numbers
    assert driver.execute_script(set_value, "quantity", home_quantity)
    _wait(driver, _MAP, lambda s: s["stage"] == "final" and "well" in s["title"])
    bar = _wait(driver, _COLOUR_BAR,
                lambda b: b["labels"] and all("well" in x for x in b["labels"]))
    assert bar["drawn"] == bar["ticks"] == list(range(len(bar["ticks"]))), bar

    # an axis that is not an angle: its own units and values, no conversion
    assert driver.execute_script(set_value, "x axis", "damping")
    axes = _wait(driver, _AXES, lambda a: a[0]["label"] == "damping [1/s]"
                 and len(a[0]["ticks"]) >= 3)
    assert [_number(text) for text in axes[0]["texts"]] == pytest.approx(
        axes[0]["ticks"], rel=1e-9, abs=1e-12)  # 10 significant digits of each tick
    assert axes[1]["label"] == "omega0 [deg/s]"

    for shot in sorted(tmp_path.glob("*.png")):
        assert shot.stat().st_size > 20_000, shot  # a rendered page, not a blank one
    if os.environ.get("SWEEP_README_SCREENSHOT"):
        shutil.copy(tmp_path / "4-trajectory.png", ROOT / "docs" / "images" / "explorer.png")


def test_websocket_origins_are_limited_to_the_served_address(app):
    from tornado.httpclient import HTTPClientError, HTTPRequest
    from tornado.ioloop import IOLoop
    from tornado.websocket import websocket_connect

    url = app.url.replace("http://", "ws://") + "ws"

    async def status(origin):
        try:
            connection = await websocket_connect(HTTPRequest(url, headers={"Origin": origin}))
        except HTTPClientError as exc:
            return exc.code
        connection.close()
        return 101

    foreign = IOLoop().run_sync(lambda: status("http://evil.example:80"))
    assert foreign == 403
    port = app.url.rstrip("/").rsplit(":", 1)[1]
    own = IOLoop().run_sync(lambda: status(f"http://127.0.0.1:{port}"))
    assert own != 403  # let past the origin check (the session token is checked next)


def _held_warm_up_app():
    """A 64 x 64 demo app whose warm-up waits in its first computation for ``release``
    (``entered`` set once it waits there)."""
    from sweep.cli import demo_inputs
    from sweep.explore import app as explore_app

    scene, grid, kwargs = demo_inputs(64)
    app = explore_app.ExplorerApp(scene, grid, resolution=64, **kwargs)
    entered, release = threading.Event(), threading.Event()
    compute = app.template.compute

    def held(*args, **kw):
        entered.set()
        assert release.wait(60)
        return compute(*args, **kw)

    app.template.compute = held
    return app, entered, release


def test_a_page_opened_during_the_warm_up_shows_the_map_once_it_ends(driver):
    """A page that connects while the server warms up says so, and draws the home map
    as soon as the warm-up ends: once connected it waits on its own event loop
    (`_Session._loaded`, `_poll_warm`),
    not for a callback from the warm-up thread into a document the server may still be
    attaching (which was lost now and then: "starting" forever)."""
    app, entered, release = _held_warm_up_app()
    app.serve(port=0)
    try:
        assert entered.wait(30) and app.warming
        driver.get(app.url)
        loaded = "if (!window.Bokeh || !Bokeh.documents.length) return null;\n" + _TEXTS
        status = _wait(driver, loaded, lambda texts: len(texts) == 1, 30, "starting")[0]
        assert "compiling the kernels" in status
        assert driver.execute_script(_MAP) is None  # nothing computed yet
        release.set()
        shown = _wait(driver, _MAP, lambda s: s["n"] == 64 * 64 and s["stage"] == "final",
                      60)
        assert "well" in shown["title"] and not app.warming
    finally:
        release.set()
        app.stop()


def test_a_map_ready_before_the_browser_connects_still_reaches_the_page():
    """The warm-up ends just after the server made the page's document and before the
    browser has connected to it, so the first map is ready (from the cache, in
    milliseconds) before the page can show it; the page asks for it once the browser is
    connected (`pn.state.onload`) and must show it. This covers that path; the lost
    picture it guards against (status and numbers shown, no image) was reproduced only
    by ``benchmarks/explore.py``'s forced scene in a fresh browser (3 of 3 runs before
    the change, 0 of 3 after), not by this smaller case."""
    app, entered, release = _held_warm_up_app()
    class ReleasedOnCreation(app.session_class):
        def __init__(self, owner):
            super().__init__(owner)  # on the server, during the page's HTTP request
            release.set()
            end = time.monotonic() + 30
            while owner.warming and time.monotonic() < end:
                time.sleep(0.01)

    app.session_class = ReleasedOnCreation
    app.serve(port=0)
    fresh = _fresh_driver()
    try:
        assert entered.wait(30)
        fresh.get(app.url)
        shown = _wait(fresh, _MAP, lambda s: s["n"] == 64 * 64 and s["stage"] == "final",
                      30)
        assert "well" in shown["title"]
    finally:
        fresh.quit()
        release.set()
        app.stop()
