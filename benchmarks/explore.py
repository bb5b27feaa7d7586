"""Latency of the browser explorer (issue 26): from a zoom to the final map.

Measured through the app's own model API (`sweep.explore.model`: a zoom is a
`Requests.submit` of the new window; the preview and the final map arrive on the worker
thread) and through a real browser (chromium via Selenium: the figure's ranges are set in
the page, and the clock stops when the page has painted the recomputed final image):

- damped wells (the demo scene of ``sweep demo``) and forced basins (the Wada scene of
  examples/forced_basins.py, pilot catalogue included), 400 x 400 windows, warm kernels;
- in the browser, the browser's own share (the time to the painted final picture less
  the computation) and its parts: debounce, the event loop, serialisation, transfer and
  paint (`browser_latencies`);
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
        with self.lock:  # the first of each stage (preview, step, final)
            self.events.setdefault(request, {}).setdefault(result.stage, time.perf_counter())
            if result.stage == "final":
                self.done.set()

    def error(self, request, exc) -> None:
        print(f"request {request} failed: {exc}", file=sys.stderr)
        self.done.set()


def zoom_latencies(explorer: Explorer, count: int, seed: int = 0) -> dict:
    """Submit ``count`` zooms one after another (each waits for its final map); the
    latencies from the submit to the preview (when one is shown), the first progressive
    step (a slow map's) and the final map [s]."""
    timer = Timer()
    requests = Requests(explorer, timer.result, timer.error)
    previews, steps, finals = [], [], []
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
            if "step" in got:
                steps.append(got["step"] - begin)
            finals.append(got["final"] - begin)
    finally:
        requests.close()
    return (summary(previews, "preview") | summary(steps, "first_step")
            | summary(finals, "final"))


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


#: In the page: the map's source, and a hook that records each picture's arrival (its
#: stage) and, for the final one, the second animation frame after it (painted).
_HOOK = """
if (!window.Bokeh || !Bokeh.documents.length) return false;
const m = Bokeh.documents[0].get_model_by_name('map');
if (!m) return false;
const src = m.renderers[0].data_source;
if (!src.data.stage || src.data.stage[0] !== 'final') return false;
if (window.__sweep_hooked) return true;
window.__sweep_hooked = true;
window.__sweep_events = [];
const now = () => performance.timeOrigin + performance.now();
src.properties.data.change.connect(() => {
  const stage = src.data.stage[0];
  window.__sweep_events.push([stage, now()]);
  if (stage === 'final')
    requestAnimationFrame(() => requestAnimationFrame(
      () => window.__sweep_events.push(['painted', now()])));
});
return true;
"""

#: Set the figure's ranges (what box zoom, wheel and pan do) and return the page's clock.
_ZOOM = """
window.__sweep_events = [];
const m = Bokeh.documents[0].get_model_by_name('map');
const t0 = performance.timeOrigin + performance.now();
m.x_range.setv({start: arguments[0], end: arguments[1]});
m.y_range.setv({start: arguments[2], end: arguments[3]});
return t0;
"""

#: The parts of a zoom's wait in the browser, in order (see `browser_latencies`).
PARTS = ("debounce", "before_submit", "server_wait", "transfer", "paint")


def browser_latencies(make, size: int, count: int) -> dict | None:
    """Zooms through the figure's ranges in chromium, timed in the page (its clock: the
    ranges set, each picture's arrival, the final one painted) and on the server (the
    session's `timeline`: the debounced zoom, the submit, each picture handed to the
    document and its computation), on one clock (the system's, in ms).

    Returns medians and maxima of: the preview and the final map on the page and painted
    [s]; the computation (the final map's, with its preview) [s]; the browser's share
    (painted minus the computation) and its parts: ``debounce`` (ranges set -> the
    window taken), ``before_submit`` (-> handed to the worker), ``server_wait`` (->
    the final picture handed to the document, less the computation: waiting for the
    event loop, the colour mapping and the serialisation), ``transfer`` (-> the data
    in the page) and ``paint`` (-> two animation frames later).
    """
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
    rows = []
    try:
        driver.get(app.url)
        _until(lambda: driver.execute_script(_HOOK), 180)
        session = app.sessions[-1]
        # the server's perf_counter on the system clock [s]
        offset = time.time() - time.perf_counter()
        for (x0, x1), (y0, y1) in windows(app.template, count, seed=2):
            session.timeline.clear()
            t0 = driver.execute_script(_ZOOM, x0, x1, y0, y1) / 1000.0
            events = _until(lambda: _painted(driver), 300)
            page = {}
            for stage, t in events:
                page.setdefault(stage, t / 1000.0 - t0)
            server = {}
            for t, _, event, seconds in list(session.timeline):
                server.setdefault(event, (t + offset - t0, seconds))
            compute = server["final"][1]
            row = {"preview": page.get("preview"), "final": page["final"],
                   "painted": page["painted"], "steps": sum(e == "step" for e, _ in events),
                   "compute": compute, "debounce": server["zoom"][0],
                   "before_submit": server["submit"][0] - server["zoom"][0],
                   "server_wait": server["final"][0] - server["submit"][0] - compute,
                   "transfer": page["final"] - server["final"][0],
                   "paint": page["painted"] - page["final"]}
            row["browser_share"] = row["painted"] - compute
            rows.append(row)
    finally:
        driver.quit()
        app.stop()
    out = {}
    for key in ("preview", "final", "painted", "compute", "browser_share", *PARTS):
        out |= summary([r[key] for r in rows if r[key] is not None], f"browser_{key}")
    out["browser_steps_median"] = statistics.median(r["steps"] for r in rows)
    out["browser_zooms"] = rows
    return out


def _painted(driver):
    events = driver.execute_script("return window.__sweep_events || []")
    return events if any(stage == "painted" for stage, _ in events) else None


def _until(probe, timeout, step=0.01):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = probe()
        if value:
            return value
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


def _ms(e: dict, key: str) -> str:
    if f"{key}_median_s" not in e:
        return ""
    return f"{1000 * e[f'{key}_median_s']:.0f} ({1000 * e[f'{key}_max_s']:.0f})"


def markdown(result: dict) -> str:
    n = result["size"]
    lines = [f"# Explorer latency ({n} x {n} windows)", "",
             f"Machine: {result['machine']}; sweep {result['sweep']}; {result['date']}.", "",
             "From a zoom (a new window submitted) to the map, warm kernels; through the "
             "model API (`sweep.explore.model.Requests`) and through chromium (the "
             "figure's ranges set in the page, until the page has painted the final "
             "image). Medians (max) over the zooms; `python benchmarks/explore.py`.", "",
             "| scene | warm-up at start-up | first zoom | preview | final map | "
             "preview, in the browser | final map, painted in the browser |",
             "|---|---|---|---|---|---|---|"]
    for name, e in result["scenes"].items():
        b = e.get("browser") or {}
        browser = (f"{b['browser_painted_median_s']:.2f} s ({b['browser_painted_max_s']:.2f})"
                   if b else "not measured")
        shown = (f"{b['browser_preview_median_s']:.2f} s ({b['browser_preview_max_s']:.2f})"
                 if "browser_preview_median_s" in b else "not shown")
        preview = (f"{e['preview_median_s']:.2f} s ({e['preview_max_s']:.2f})"
                   if "preview_median_s" in e else "not shown")
        if "first_step_median_s" in e:
            preview += (f"; first step {e['first_step_median_s']:.2f} s "
                        f"({e['first_step_max_s']:.2f})")
        lines.append(f"| {name} | {e['warm_up_s']:.2f} s | {e['first_zoom_final_s']:.2f} s | "
                     f"{preview} | {e['final_median_s']:.2f} s ({e['final_max_s']:.2f}) | "
                     f"{shown if b else ''} | {browser} |")
    lines += ["", "Where a zoom's time goes in the browser, milliseconds, medians (max): the "
              "computation (the final map and the preview computed before it) and the "
              "browser's share (painted minus computation), made of the debounce (ranges "
              "set -> window taken), the event loop before the submit, the server's wait "
              "(-> final picture handed to the document, less the computation: event loop, "
              "colour mapping, serialisation), the transfer (-> data in the page) and the "
              "paint (-> two animation frames later).", "",
              "| scene | painted | computation | browser's share | debounce | before submit "
              "| server wait | transfer | paint | steps shown |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for name, e in result["scenes"].items():
        b = e.get("browser") or {}
        if not b:
            continue
        cells = [_ms(b, f"browser_{k}") for k in ("painted", "compute", "browser_share",
                                                  *PARTS)]
        lines.append(f"| {name} | " + " | ".join(cells)
                     + f" | {b['browser_steps_median']:g} |")
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
