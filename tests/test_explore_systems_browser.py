"""The double pendulum's explorer page in a real browser (Debian's chromium through
Selenium, as tests/test_explore_browser.py, whose fixtures and page scripts it uses):
the flip-time map, a click's every coordinate over time, a parameter change."""

from __future__ import annotations

import numpy as np
import pytest
from test_explore_browser import (  # the browser fixture and the page scripts
    _FRAME,
    _LEGENDS,
    _MAP,
    _TEXTS,
    _click,
    _missing,
    _wait,
    check_degree_axes,
    check_layout,
    driver,  # noqa: F401 - a fixture
)

import sweep

N = 200  # pixels per axis (the map's frame is N screen pixels wide)

#: The trajectory figure: its data source's columns, the first values and its lines.
_SERIES = """
const t = Bokeh.documents[0].get_model_by_name('trajectory');
if (!t) return null;
const src = t.renderers[0].data_source;
const n = src.data.t ? src.data.t.length : 0;
return {names: Object.keys(src.data), n: n, lines: t.renderers.length,
        theta1: n ? src.data.theta1[0] : null, theta2: n ? src.data.theta2[0] : null};
"""


@pytest.fixture(scope="module")
def system_app():
    try:
        from sweep.explore.system_app import SystemExplorerApp
    except ImportError as exc:
        _missing(f"Panel/Bokeh are not importable ({exc})")
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, N), theta2_0=np.linspace(-3, 3, N))
    app = SystemExplorerApp(sweep.DoublePendulum(), grid, t_end=3.0, dt=0.01, resolution=N)
    app.serve(port=0)
    yield app
    app.stop()


def test_double_pendulum_in_a_real_browser(system_app, driver):  # noqa: F811 - the fixture
    driver.get(system_app.url)
    home = _wait(driver, _MAP, lambda s: s["n"] == N * N and "flip" in s["title"], 60)

    frame = driver.execute_script(_FRAME)
    (x0, x1), (y0, y1) = frame["xr"], frame["yr"]
    fx, fy = 0.3, 0.6  # fractions of the frame from its left and its top
    _click(driver, (int(frame["left"] + fx * frame["width"]),
                    int(frame["top"] + fy * frame["height"])))
    traj = _wait(driver, _SERIES, lambda t: t["n"] > 0)
    assert {"t", "theta1", "theta2", "omega1", "omega2"} <= set(traj["names"])
    assert traj["lines"] == 4  # every coordinate and velocity over time
    pixel = (x1 - x0) / N, (y1 - y0) / N
    # snapped to the pixel centre; the click lands within ~1 screen pixel of the target
    assert abs(traj["theta1"] - (x0 + fx * (x1 - x0))) <= 2 * pixel[0]
    assert abs(traj["theta2"] - (y1 - fy * (y1 - y0))) <= 2 * pixel[1]
    info = [text for text in driver.execute_script(_TEXTS, "omega2_0") if "status" in text]
    assert len(info) == 1 and "ok" in info[0]  # the info pane: every start value, status
    # with units, and the angles in degrees too (the map's axes' units)
    assert f"theta1_0 = {traj['theta1']:.6g} rad ({np.degrees(traj['theta1']):.4g} deg)" \
        in info[0]
    assert "omega2_0 = 0 rad/s (0 deg/s)" in info[0]
    # the log10 flip time is a value with its name and units, not a label
    # (the pane's text is its escaped HTML: "&lt;strong&gt;value&lt;/strong&gt; ...")
    assert "value&lt;/strong&gt; log10_flip_time = " in info[0]
    assert "label" not in info[0]
    check_layout(driver, "flip_time")  # fits 1400 px; the bar's title; no warning
    check_degree_axes(driver, ("theta1_0 [deg]", "theta2_0 [deg]"))  # as `sweep plot`
    legends = driver.execute_script(_LEGENDS)  # above the curves, never over them
    assert [g["labels"] for g in legends["phase"]["legends"]] == [
        ["(theta1, omega1)", "(theta2, omega2)"]]
    for name in ("trajectory", "phase"):
        assert not any(g["overlap"] for g in legends[name]["legends"]), legends

    set_value = ("for (const m of Bokeh.documents[0].all_models) {"
                 " if (m.title === arguments[0]) { m.value = arguments[1]; return true; } }"
                 "return false;")
    assert driver.execute_script(set_value, "mass2 [kg]", 3.0)
    changed = _wait(driver, _MAP, lambda s: s["n"] == N * N and s["sum"] != home["sum"])
    assert changed["weighted"] != home["weighted"]


#: The page's colour mapper and colour bar: the palette and the legend's labels.
_COLOURS = """
const m = Bokeh.documents[0].get_model_by_name('map');
const bar = m.right.find(r => r.color_mapper);
if (!bar) return null;
const o = bar.major_label_overrides;  // a Map in BokehJS 3, keyed by tick
const entries = o instanceof Map ? Array.from(o.entries()) : Object.entries(o);
entries.sort((a, b) => Number(a[0]) - Number(b[0]));
return {palette: Array.from(bar.color_mapper.palette), labels: entries.map(e => e[1])};
"""


def test_a_driven_double_pendulums_basins_in_a_real_browser(driver, tmp_path):  # noqa: F811
    """The basins map of tests/test_explore_systems.py's driven double pendulum (44 x 44
    pixels, by the catalogue route: its pilot, preview and map share the 64-lane
    kernels of that test's catalogue route and of tests/test_system_attractors.py):
    categorical colours, "unresolved" in black, the route and the attractors counted on
    the status line."""
    try:
        from sweep.explore.system_app import SystemExplorerApp
    except ImportError as exc:
        _missing(f"Panel/Bokeh are not importable ({exc})")
    from test_explore_systems import DRIVEN, DRIVEN_RUN

    n = 44
    grid = sweep.Grid(theta1_0=np.linspace(-3, 3, n), theta2_0=np.linspace(-3, 3, n))
    app = SystemExplorerApp(DRIVEN, grid, quantity="basins", resolution=n, **DRIVEN_RUN)
    app.serve(port=0)
    try:
        driver.get(app.url)
        _wait(driver, _MAP, lambda s: s["n"] == n * n and s["stage"] == "final"
              and "basins" in s["title"], 90)
        status = _wait(driver, _TEXTS, lambda texts: len(texts) == 1, 30, "attractors;")[0]
        assert f"of {n * n} starts unresolved" in status
        assert "(pilot catalogue included); catalogue route (21 x 21 pilot, " in status
        assert f"of {n * n} starts stopped on the catalogue; " in status
        colours = driver.execute_script(_COLOURS)
        assert colours["labels"][0] == "unresolved" and colours["palette"][0] == "#000000"
        assert all(label.startswith("attractor ") for label in colours["labels"][1:])
        assert "#000000" not in colours["palette"][1:]
        driver.save_screenshot(str(tmp_path / "driven-basins.png"))
        check_layout(driver, "basins")
    finally:
        app.stop()
