"""Latency of the browser explorer (issue 26): from a zoom to the final map.

Measured through the app's own model API (`sweep.explore.model`: a zoom is a
`Requests.submit` of the new window; the preview and the final map arrive on the worker
thread) and through a real browser (chromium via Selenium: the figure's ranges are set in
the page, and the clock stops when the page holds the recomputed 400 x 400 image):

- damped wells (the demo scene of ``sweep demo``) and forced basins (the Wada scene of
  examples/forced_basins.py, pilot catalogue included), 400 x 400 windows, warm kernels;
- the first map after start-up (the warm-up: compile or load the kernels from the disk
  cache, then the home view's preview, map and one trajectory);
- the server's RSS over 200 zooms (memory must stay flat).

Usage::

    python benchmarks/explore.py [--size 400] [--zooms 10] [--rss-zooms 200]
                                 [--no-browser] [--no-forced] [--out benchmarks/results]

Writes explore.json and explore.md in ``--out``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import shutil
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np

import sweep
from sweep.cli import demo_inputs
from sweep.explore.model import Explorer, Requests, rss_bytes

from _machine import machine

HERE = Path(__file__).resolve().parent
PERIOD = 2 * np.pi  # the forced scene's forcing period [s] (W = 1 rad/s)


def damped(size: int):
    """The demo scene (c = 0.3 1/s) over its phase-plane window: the final well."""
    scene, grid, kwargs = demo_inputs(size)
    return scene, grid, kwargs


def forced(size: int):
    """examples/forced_basins.py: c = 0.2, A = 1.66, W = 1, cos forcing; at most 300
    periods (20 transient) with early stop, 100 steps per period; basins."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, size),
                      omega0=np.linspace(-4.0, 4.0, size))
    return scene, grid, dict(t_end=300 * PERIOD, dt=PERIOD / 100, t_transient=20 * PERIOD)


def windows(explorer: Explorer, count: int, seed: int = 0):
    """``count`` zoom windows inside the home view: random centres, 5 to 50 % of it."""
    rng = np.random.default_rng(seed)
    h = explorer.home
    out = []
    for _ in range(count):
        box = []
        for lo, hi in (h.x_range, h.y_range):
            width = (hi - lo) * rng.uniform(0.05, 0.5)
            start = rng.uniform(lo, hi - width)
            box.append((start, start + width))
        out.append(tuple(box))
    return out


class Timer:
    """Collects the preview and final arrival times of each request."""

    def __init__(self) -> None:
        self.events: dict[int, dict] = {}
        self.done = threading.Event()
        self.lock = threading.Lock()

    def result(self, request, result) -> None:
        with self.lock:
            key = "preview" if result.preview else "final"
            self.events.setdefault(request, {})[key] = time.perf_counter()
            if not result.preview:
                self.done.set()

    def error(self, request, exc) -> None:
        print(f"request {request} failed: {exc}", file=sys.stderr)
        self.done.set()


def zoom_latencies(explorer: Explorer, count: int, seed: int = 0) -> dict:
    """Submit ``count`` zooms one after another (each waits for its final map); the
    preview and final latencies from the submit [s]."""
    timer = Timer()
    requests = Requests(explorer, timer.result, timer.error)
    previews, finals = [], []
    try:
        for window in windows(explorer, count, seed):
            state = explorer.zoom(*window)
            timer.done.clear()
            begin = time.perf_counter()
            request = requests.submit(state)
            timer.done.wait(600)
            got = timer.events.get(request, {})
            if "preview" in got:
                previews.append(got["preview"] - begin)
            finals.append(got["final"] - begin)
    finally:
        requests.close()
    return summary(previews, "preview") | summary(finals, "final")


def summary(values, name) -> dict:
    if not values:
        return {}
    return {f"{name}_median_s": statistics.median(values), f"{name}_max_s": max(values),
            f"{name}_min_s": min(values), f"{name}_n": len(values)}


def first_map(make, size: int) -> dict:
    """The start-up warm-up, then the first zoom: (seconds, seconds)."""
    scene, grid, kwargs = make(size)
    begin = time.perf_counter()
    explorer = Explorer(scene, grid, resolution=size, **kwargs)
    result = explorer.compute(preview=True)
    result = explorer.compute()
    explorer.trajectory(float(result.x[size // 2]), float(result.y[size // 2]), result)
    warm = time.perf_counter() - begin
    first = zoom_latencies(explorer, 1, seed=3)  # a window the timed zooms do not repeat
    return {"warm_up_s": warm, "first_zoom_final_s": first["final_median_s"]}, explorer


def rss_over_zooms(explorer: Explorer, count: int) -> dict:
    """RSS of this process (the server's model) every 10 zooms over ``count`` zooms."""
    timer = Timer()
    requests = Requests(explorer, timer.result, timer.error)
    samples = [rss_bytes()]
    try:
        for k, window in enumerate(windows(explorer, count, seed=1)):
            timer.done.clear()
            requests.submit(explorer.zoom(*window))
            timer.done.wait(600)
            if (k + 1) % 10 == 0:
                samples.append(rss_bytes())
    finally:
        requests.close()
    mib = [s / 2**20 for s in samples]
    return {"zooms": count, "rss_mib": mib, "rss_first_mib": mib[0], "rss_last_mib": mib[-1],
            "rss_after_10_mib": mib[1] if len(mib) > 1 else mib[0],
            "rss_max_mib": max(mib)}


_MAP = """
if (!window.Bokeh || !Bokeh.documents.length) return null;
const m = Bokeh.documents[0].get_model_by_name('map');
if (!m) return null;
const src = m.renderers[0].data_source;
const img = src.data.image[0];
return {n: img.length, x: src.data.x[0], dw: src.data.dw[0], y: src.data.y[0],
        dh: src.data.dh[0]};
"""


def browser_latencies(make, size: int, count: int) -> dict | None:
    """Zooms through the figure's ranges in chromium; seconds until the page holds the
    recomputed final image (its glyph covers the new window at full resolution)."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.options import Options
        from selenium.webdriver.chrome.service import Service

        from sweep.explore.app import ExplorerApp
    except ImportError as exc:
        print(f"browser latency skipped: {exc}", file=sys.stderr)
        return None
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    driver_path = shutil.which("chromedriver")
    if not browser or not driver_path:
        print("browser latency skipped: chromium/chromedriver not found", file=sys.stderr)
        return None
    scene, grid, kwargs = make(size)
    app = ExplorerApp(scene, grid, resolution=size, **kwargs)
    app.serve(port=0)
    options = Options()
    options.binary_location = browser
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1500,1250"):
        options.add_argument(argument)
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    latencies = []
    try:
        driver.get(app.url)
        _until(driver, lambda s: s["n"] == size * size, 120)
        for (x0, x1), (y0, y1) in windows(app.template, count, seed=2):
            begin = time.perf_counter()
            driver.execute_script(
                "const m = Bokeh.documents[0].get_model_by_name('map');"
                "m.x_range.setv({start: arguments[0], end: arguments[1]});"
                "m.y_range.setv({start: arguments[2], end: arguments[3]});", x0, x1, y0, y1)
            _until(driver, lambda s, x0=x0, x1=x1, y0=y0: s["n"] == size * size
                   and np.isclose(s["x"], x0)
                   and np.isclose(s["x"] + s["dw"], x1) and np.isclose(s["y"], y0), 120,
                   step=0.01)
            latencies.append(time.perf_counter() - begin)
    finally:
        driver.quit()
        app.stop()
    return summary(latencies, "browser_final")


def _until(driver, predicate, timeout, step=0.05):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        state = driver.execute_script(_MAP)
        if state is not None and predicate(state):
            return state
        time.sleep(step)
    raise TimeoutError("the page did not show the map in time")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=400, help="pixels per axis")
    parser.add_argument("--zooms", type=int, default=10, help="zooms timed per scene")
    parser.add_argument("--rss-zooms", type=int, default=200,
                        help="zooms over which the RSS is sampled")
    parser.add_argument("--no-browser", action="store_true", help="skip the browser timing")
    parser.add_argument("--no-forced", action="store_true", help="skip the forced scene")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)

    result = {"machine": machine(), "date": datetime.date.today().isoformat(),
              "sweep": sweep.__version__, "size": args.size, "scenes": {}}
    scenes = {"damped wells": damped} | ({} if args.no_forced else {"forced basins": forced})
    for name, make in scenes.items():
        start, explorer = first_map(make, args.size)
        entry = dict(start)
        entry.update(zoom_latencies(explorer, args.zooms))
        if name == "damped wells":
            entry["rss"] = rss_over_zooms(explorer, args.rss_zooms)
        if not args.no_browser:
            entry["browser"] = browser_latencies(make, args.size, max(2, args.zooms // 2))
        result["scenes"][name] = entry
        print(name, json.dumps(entry, indent=1, default=float), flush=True)
    (args.out / "explore.json").write_text(json.dumps(result, indent=2, default=float) + "\n")
    (args.out / "explore.md").write_text(markdown(result))
    print(f"wrote {args.out / 'explore.json'} and {args.out / 'explore.md'}")
    return 0


def markdown(result: dict) -> str:
    n = result["size"]
    lines = [f"# Explorer latency ({n} x {n} windows)", "",
             f"Machine: {result['machine']}; sweep {result['sweep']}; {result['date']}.", "",
             "From a zoom (a new window submitted) to the map, warm kernels; through the "
             "model API (`sweep.explore.model.Requests`) and through chromium (the "
             "figure's ranges set in the page, until the page holds the recomputed image). "
             "Medians (max) over the zooms; `python benchmarks/explore.py`.", "",
             "| scene | warm-up at start-up | first zoom | preview | final map | "
             "final map, in the browser |", "|---|---|---|---|---|---|"]
    for name, e in result["scenes"].items():
        b = e.get("browser") or {}
        browser = (f"{b['browser_final_median_s']:.2f} s ({b['browser_final_max_s']:.2f})"
                   if b else "not measured")
        preview = (f"{e['preview_median_s']:.2f} s ({e['preview_max_s']:.2f})"
                   if "preview_median_s" in e else "")
        lines.append(f"| {name} | {e['warm_up_s']:.2f} s | {e['first_zoom_final_s']:.2f} s | "
                     f"{preview} | {e['final_median_s']:.2f} s ({e['final_max_s']:.2f}) | "
                     f"{browser} |")
    rss = result["scenes"].get("damped wells", {}).get("rss")
    if rss:
        lines += ["", f"Server RSS over {rss['zooms']} zooms of damped wells (every 10 zooms): "
                  f"{rss['rss_first_mib']:.0f} MiB before, {rss['rss_after_10_mib']:.0f} MiB "
                  f"after 10, {rss['rss_last_mib']:.0f} MiB after {rss['zooms']} (max "
                  f"{rss['rss_max_mib']:.0f} MiB).", "",
                  "RSS samples [MiB]: " + ", ".join(f"{v:.0f}" for v in rss["rss_mib"])]
    lines += ["", "The warm-up (what `sweep explore` does before it prints its URL) "
              "compiles the kernels, or loads them from sweep's disk cache, and computes "
              "the home view's preview, map and one trajectory; the first page shows that "
              "map at once."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
