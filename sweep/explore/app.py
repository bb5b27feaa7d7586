"""The explorer's page: Panel widgets around two Bokeh figures, the map (``name="map"``)
and the clicked trajectory (``name="trajectory"``, with the phase portrait ``"phase"``).

Each browser session gets its own `sweep.explore.model.Explorer` (its own history); the
sessions of one app share the cache of final maps (the start-up warm-up's map appears at
once) and one compute lock. Zoom, wheel and pan change the map's ranges; `DEBOUNCE_MS`
after the last change the visible window is submitted (`sweep.explore.model.Requests`),
computed on a worker thread (never on the server's event loop), and drawn back through
the document's ``add_next_tick_callback`` (the one thread-safe entry into a Bokeh
document): the preview first, progressive steps of a slow map, then the final map, and
under it the view's numbers (`sweep.explore.numbers`). A stale result (an older request)
is dropped.

What travels to the page is small: a discrete map is sent as one byte per pixel (its
index into the legend, coloured by the page's colour mapper), a continuous one as
float32; the colour bar's ticker is one model updated in place (a new model would make
Bokeh walk the document's whole model graph, ~50 ms per picture); the map's Python and
run file are written after the final map is on its way.
"""

from __future__ import annotations

import errno
import math
import socket
import sys
import threading
import time
import urllib.parse
import warnings
import weakref
from collections import OrderedDict, deque
from functools import partial

import numpy as np

from .model import Explorer, InvalidInput, MapResult, Requests, Trajectory
from .numbers import ON_REQUEST

try:
    import panel as pn
    from bokeh.events import Tap
    from bokeh.models import (
        ColorBar,
        ColumnDataSource,
        CustomJSTicker,
        CustomJSTickFormatter,
        FixedTicker,
        Legend,
        LegendItem,
        LinearColorMapper,
        Range1d,
        Title,
    )
    from bokeh.palettes import Category10_10, Category20_20, Viridis256
    from bokeh.plotting import figure
    from panel.io import hold
except ImportError as exc:  # pragma: no cover - the extra is missing
    raise ImportError(f"sweep.explore needs Panel and Bokeh ({exc}); install them with: "
                      "pip install -e \".[explore]\" (or pip install 'panel>=1.4' "
                      "'bokeh>=3.4')") from None

__all__ = ["AddressUnavailable", "ExplorerApp", "free_port"]

#: Milliseconds without a range change before the window is recomputed: the four ends
#: of one zoom arrive within a millisecond, a wheel or a pan sends a change per frame
#: (~16 ms), and a newer request cancels an older one anyway (150 ms until 2026-11-27:
#: most of the time a damped window took to reach the page).
DEBOUNCE_MS = 25

#: Events kept in a session's `timeline` (for `benchmarks/explore.py`).
TIMELINE_SIZE = 256

#: Sessions an app keeps a weak reference to (`ExplorerApp.sessions`).
SESSIONS_KEPT = 8

#: Width of the trajectory panels beside the map [px]: with the controls and the map
#: (its colour bar's longest names included) the page fits a 1400 px wide window
#: with 20 px to spare (460 until 2026-11-28: 1455 px, a horizontal scroll bar).
SIDE_WIDTH = 380

#: Width of a character of the colour bar's title [px] (12 px sans-serif; a little
#: more than the mean, so that the room kept for it is never short).
TITLE_CHAR_PX = 7

#: Colours of discrete maps.
_MOTION_COLOURS = {-1.0: "#2166ac", 0.0: "#f0f0f0", 1.0: "#b2182b"}
_NAN_COLOUR = "#404040"


#: Seconds `ExplorerApp.serve` waits for its server thread to listen (binding is
#: immediate; this bounds a server that neither listens nor fails).
LISTEN_TIMEOUT = 60.0

#: How often a page opened during the warm-up asks whether it ended [ms].
WARM_POLL_MS = 50

#: What the page says while the app warms up (`ExplorerApp.warm_up`).
WARMING_TEXT = ("**starting**: compiling the kernels and computing the first view "
                "(once per server; seconds)…")


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody listens on at ``host`` now (the OS's choice)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


class AddressUnavailable(OSError):
    """The explorer's server cannot listen on ``host``, ``port``.

    Parameters
    ----------
    host : str
        The address it tried to bind.
    port : int
        The TCP port it tried to bind.
    reason : OSError
        The operating system's error (``[Errno 98] Address already in use``, ...).
    way_out : str, default "port=0 picks a free port"
        The advice at the end of the message (the command line names ``--port 0``).
    """

    def __init__(self, host: str, port: int, reason: OSError,
                 way_out: str = "port=0 picks a free port") -> None:
        self.host, self.port, self.reason, self.way_out = host, port, reason, way_out
        why = {errno.EADDRINUSE: " (another program listens there)",
               errno.EACCES: " (ports below 1024 need privileges)",
               errno.EADDRNOTAVAIL: f" ({host} is not an address of this machine)"}
        hint = why.get(getattr(reason, "errno", None), "")
        if isinstance(reason, socket.gaierror):
            hint = f" ({host} is not an address or a host name this machine resolves)"
        where = f"port {port}" if port else "port 0 (a free port)"
        super().__init__(f"cannot listen on address {host}, {where}: {reason}{hint}; "
                         f"{way_out}")
        self.errno = getattr(reason, "errno", None)

    def __reduce__(self):
        return type(self), (self.host, self.port, self.reason, self.way_out)


def _labelled(cls, text: str, **kwargs):
    """A Panel widget titled ``text`` (``label=`` where Panel has it, 1.9+; ``name=`` in
    older versions, where it is the same thing)."""
    key = "label" if "label" in cls.param and cls is not pn.widgets.FileDownload else "name"
    return cls(**{key: text}, **kwargs)


def _axis_label(name: str) -> str:
    from ..physics import parameters

    for p in parameters():
        if p.axis == name:
            return f"{name} [{p.unit_text}]"
    return name


def degrees_label(label: str, name: str) -> tuple[str, float]:
    """The map's axis label of axis ``name`` and the factor from its values to the
    numbers its ticks show: an angle axis (`sweep.plot.angle_axis`: theta0, omega0, a
    system's theta1_0, ...) labelled in rad or rad/s is shown in deg or deg/s (factor
    180/pi), as ``sweep plot`` draws it; any other is left as it is (factor 1).

    Parameters
    ----------
    label : str
        ``"name [units]"`` in the units the explorer computes in.
    name : str
        The axis.
    """
    from ..plot import degree_units

    head, _, units = label.partition(" [")
    shown = degree_units(name, units)
    if shown is not None:
        return f"{head} [{shown}", 180.0 / math.pi
    return label, 1.0


#: Ticks of the map's axes, on round numbers of what they show (``scale`` times the
#: value: degrees on an angle axis, the value itself on the others): 1, 2, 2.5, 5 times
#: a power of ten, and on degrees 15, 30, 45, 90 and their multiples of ten. JavaScript
#: (`bokeh.models.CustomJSTicker`); ``minor`` says which ticks it returns.
_TICKS_JS = """
const lo = Math.min(cb_data.start, cb_data.end) * scale;
const hi = Math.max(cb_data.start, cb_data.end) * scale;
const span = hi - lo;
if (!(span > 0) || !Number.isFinite(span)) return [];
const raw = span / 6;
const mag = Math.pow(10, Math.floor(Math.log10(raw)));
const steps = scale !== 1 && mag >= 10 ? [1, 1.5, 3, 4.5, 9, 10] : [1, 2, 2.5, 5, 10];
let step = 10 * mag;
for (const m of steps) { if (m * mag >= raw) { step = m * mag; break; } }
if (minor) step /= 5;
const out = [];
for (let k = Math.ceil(lo / step); k * step <= hi && out.length < 1000; k++)
  out.push(k * step / scale);
return out;
"""

#: The tick texts of the map's axes: ``scale`` times the tick, to 10 digits (no
#: rounding noise such as 45.00000000000001), with a minus sign as Bokeh draws it.
_TICK_TEXT_JS = """
const v = Number((tick * scale).toPrecision(10)) || 0;
return String(v).replace("-", "\u2212");
"""


def _nice_ticks(low: float, high: float, count: int = 6) -> list[float]:
    """About ``count`` round tick values in [low, high] for a continuous colour bar
    (matplotlib's `~matplotlib.ticker.MaxNLocator`: steps of 1, 2, 2.5, 5 times a power
    of ten)."""
    from matplotlib.ticker import MaxNLocator

    span = high - low
    try:
        values = MaxNLocator(nbins=count, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high)
    except (ValueError, OverflowError):  # a span beyond float64 (-1e308 to 1e308)
        values = np.array([])
    inside = [float(v) for v in values
              if np.isfinite(v) and low - 1e-9 * span <= v <= high + 1e-9 * span]
    if len(inside) < 2:  # matplotlib widens a range of values below ~1e-288 to +-1e-13
        return [float(low), float(high)]
    # the digits that tell the ticks apart, and 3 more: no rounding noise on the page
    # (2.5000000000000005e-05), and no ticks merged where the range is narrow against
    # its values (12345.6 to 12345.6000001: 12 digits drew 12345.6 three times)
    ratio = max(abs(low), abs(high)) / (inside[1] - inside[0])
    digits = min(15, 3 + max(0, math.ceil(math.log10(ratio))))
    return [float(f"{v:.{digits}g}") for v in inside]


def _tick_text(value: float) -> str:
    """A colour-bar tick's text: the shortest that reads back as ``value`` (``20``, not
    ``20.0``; ``2.5e-05``)."""
    text = repr(float(value) + 0.0)  # + 0.0: no "-0"
    return text[:-2] if text.endswith(".0") else text


def _palette(result: MapResult) -> list[str]:
    """One colour per legend entry (NaN's entry dark grey)."""
    colours = []
    cycle = Category10_10 if len(result.legend) <= 10 else Category20_20
    for k, (value, _) in enumerate(result.legend):
        if not math.isfinite(value):
            colours.append(_NAN_COLOUR)
        elif result.state.quantity == "motion" and value in _MOTION_COLOURS:
            colours.append(_MOTION_COLOURS[value])
        elif result.state.quantity in ("basins", "period") and value < 0:
            colours.append("#000000")
        elif result.state.quantity == "inverted":
            colours.append("#1a9850" if value else "#f0f0f0")
        else:
            colours.append(cycle[k % len(cycle)])
    return colours


def wire_image(result: MapResult) -> np.ndarray:
    """What the page receives of ``result``'s picture: a discrete map's legend index as
    uint8 (uint16 beyond 256 entries), a continuous map as float32 (NaN kept)."""
    if result.legend:
        dtype = np.uint8 if len(result.legend) <= 256 else np.uint16
        return np.ascontiguousarray(result.image, dtype=dtype)
    return np.ascontiguousarray(result.image, dtype=np.float32)


def _fit(fig, xs, ys, padding: float = 0.05) -> None:
    """Set ``fig``'s ranges (and what its reset tool returns to) to the finite values of
    the arrays ``xs`` and ``ys``, widened by ``padding`` of their span on each side (a
    single value: +-1 around it; none: 0 to 1).

    The trajectory panels use fixed ranges set here, not Bokeh's data ranges: a data
    range over no data (before the first click) has NaN ends, and BokehJS warned
    "could not set initial ranges" in the browser's console on every redraw."""
    for rng, arrays in ((fig.x_range, xs), (fig.y_range, ys)):
        values = np.concatenate([np.ravel(np.asarray(a, dtype=np.float64)) for a in arrays]
                                or [np.empty(0)])
        values = values[np.isfinite(values)]
        low, high = (float(values.min()), float(values.max())) if values.size else (0.0, 1.0)
        if high > low:
            low, high = low - padding * (high - low), high + padding * (high - low)
        else:
            low, high = low - 1.0, high + 1.0
        rng.update(start=low, end=high, reset_start=low, reset_end=high)


def _legend_above(fig, items) -> Legend:
    """A horizontal legend of ``items`` (label, renderers) above ``fig``'s plotting area
    (between the title and the frame: it never covers a curve); a click hides a curve."""
    legend = Legend(items=[LegendItem(label=label, renderers=renderers)
                           for label, renderers in items],
                    orientation="horizontal", location="top_left", click_policy="hide",
                    margin=0, padding=4, spacing=12, label_text_font_size="11px",
                    border_line_alpha=0, background_fill_alpha=0)
    fig.add_layout(legend, "above")
    return legend


class _Session:
    """One browser session: widgets, figures and the explorer behind them."""

    #: The heading of the model's own controls (a system's page: "System").
    controls_heading = "Scene"

    def __init__(self, app: ExplorerApp) -> None:
        self.app = app
        self.explorer = app.explorer_class(app.scene, app.grid, cache=app.cache, **app.kwargs)
        self.doc = pn.state.curdoc
        self.latest = 0
        self.result: MapResult | None = None
        self.pending_zoom = None
        self.last_change = 0.0
        #: ``(time.perf_counter(), request, event, seconds)`` of the page's recent
        #: stages: "zoom" (the debounced window taken), "submit", "preview"/"step"/
        #: "final" (each drawn, just after it was handed to the document; ``seconds``:
        #: its computation, a final map's with the preview computed before it),
        #: "numbers"; ``seconds`` is None where there is none.
        self.timeline: deque = deque(maxlen=TIMELINE_SIZE)
        self.numbers_request = 0
        self._build()
        self.requests = Requests(self.explorer, self._from_worker(self._show),
                                 self._from_worker(self._failed),
                                 on_numbers=self._from_worker(self._show_numbers))
        app._sessions.append(weakref.ref(self))
        if self.doc is not None and hasattr(self.doc, "on_session_destroyed"):
            self.doc.on_session_destroyed(lambda context: self.requests.close())
        self._warm_poll = None
        if self._served():
            # a served page asks for its first map once the browser is connected
            # (`pn.state.onload`): a map that came back before (the home view from the
            # cache, in 0.1 s) changed a document the browser had not pulled yet and
            # never reached it (the page showed the status but no picture), and a
            # callback from the warm-up thread scheduled while the server was still
            # attaching the document was lost now and then ("starting" forever)
            if app.warming:
                self.status.object = WARMING_TEXT  # the first map follows from the cache
            pn.state.onload(self._loaded)
        elif app.call_when_warm(self._from_worker(self._first_submit)):
            self.status.object = WARMING_TEXT  # a notebook: no event loop of its own
        else:
            self._submit()

    def _served(self) -> bool:
        """Whether this page is a served Bokeh document (with an event loop)."""
        return self.doc is not None and getattr(self.doc, "session_context", None) is not None

    def _loaded(self) -> None:
        """The browser is connected: the first request now, or, while the app warms up,
        a check on this page's event loop every `WARM_POLL_MS` until it has."""
        if self.app.warming:
            self.status.object = WARMING_TEXT
            self._warm_poll = self.doc.add_periodic_callback(self._poll_warm, WARM_POLL_MS)
        else:
            self._first_submit()

    def _poll_warm(self) -> None:
        """On the page's event loop, every `WARM_POLL_MS`: once the app's warm-up has
        ended, stop polling and make the first request."""
        if self.app.warming or self._warm_poll is None:
            return
        self.doc.remove_periodic_callback(self._warm_poll)
        self._warm_poll = None
        self._first_submit()

    def _first_submit(self) -> None:
        """The first request, once the app's warm-up ended (unless a control was changed
        meanwhile, which submitted already)."""
        if self.latest == 0:
            self._submit()

    # -- threads ------------------------------------------------------------------
    def _from_worker(self, callback):
        """``callback`` run on the document's event loop (from the worker thread)."""
        def schedule(*args):
            doc = self.doc
            if doc is not None and getattr(doc, "session_context", None) is not None:
                doc.add_next_tick_callback(partial(callback, *args))
            else:  # a notebook: Panel syncs the models itself
                callback(*args)
        return schedule

    # -- layout -------------------------------------------------------------------
    def _build(self) -> None:
        e = self.explorer
        s = e.state
        v = s.view
        self.mapper = LinearColorMapper(palette=Viridis256, nan_color=_NAN_COLOUR)
        # no image until the first map arrives (a blank frame, not a placeholder colour);
        # "stage" says which picture it is ("preview", "step", "final")
        self.source = ColumnDataSource({"image": [], "x": [], "y": [], "dw": [], "dh": [],
                                        "stage": []})
        # the colour bar's only ticker, its ticks updated in place: BokehJS (3.9) does not
        # redraw a colour bar whose ticker is swapped for another model, so a page that
        # opened on a continuous map kept its ticks between the categories (-0.5, 0.5,
        # 1.5) beside their names
        self.ticker = FixedTicker(ticks=[])
        n = s.resolution
        self.map = figure(name="map", frame_width=n, frame_height=n,
                          x_range=Range1d(*v.x_range), y_range=Range1d(*v.y_range),
                          tools="box_zoom,wheel_zoom,pan,tap,reset", active_scroll="wheel_zoom",
                          active_drag="box_zoom", toolbar_location="above",
                          title="")
        self.map.image(image="image", x="x", y="y", dw="dw", dh="dh", source=self.source,
                       color_mapper=self.mapper)
        # ticks in the units the axes show (degrees on an angle axis: `degrees_label`);
        # one ticker and formatter per axis, their ``scale`` changed with the axis
        for axis in (self.map.xaxis[0], self.map.yaxis[0]):
            axis.ticker = CustomJSTicker(args={"scale": 1.0, "minor": False},
                                         major_code=_TICKS_JS,
                                         minor_code=_TICKS_JS.replace("if (minor)",
                                                                      "if (true)"))
            axis.formatter = CustomJSTickFormatter(args={"scale": 1.0}, code=_TICK_TEXT_JS)
        self._label_axes()
        self.clicked = ColumnDataSource({"x": [], "y": []})
        self.map.scatter("x", "y", source=self.clicked, size=12, marker="x", line_width=3,
                         color="white")
        self.colorbar = ColorBar(color_mapper=self.mapper, width=16, ticker=self.ticker,
                                 major_label_text_font_size="11px")
        self.map.add_layout(self.colorbar, "right")
        # the colour bar's title, horizontal above the bar: BokehJS (3.9) draws a
        # vertical colour bar's own title rotated in a strip on its left, where a short
        # one sat under the bar's foot ("basins") and a long one was cut; ``offset``
        # from the frame's left edge puts it over the bar
        self.colour_title = Title(name="colour_title", text="", align="left",
                                  offset=n + self.colorbar.padding,
                                  text_font_size="12px", text_font_style="normal",
                                  standoff=0)
        self.map.add_layout(self.colour_title, "above")
        for r in (self.map.x_range, self.map.y_range):
            r.on_change("start", self._range_changed)
            r.on_change("end", self._range_changed)
        self.map.on_event(Tap, self._tapped)

        self.traj_source = ColumnDataSource({"t": [], "theta": [], "omega": []})
        self.strobe_source = ColumnDataSource({"theta": [], "omega": []})
        # fixed ranges, fitted to each trajectory (`_fit`): no data range over no data
        self.trajectory = figure(name="trajectory", width=SIDE_WIDTH, height=260,
                                 x_range=Range1d(0, 1), y_range=Range1d(0, 1),
                                 x_axis_label="t [s]", y_axis_label="theta [rad], omega [rad/s]",
                                 title="trajectory: click a start on the map",
                                 tools="box_zoom,wheel_zoom,pan,reset,save",
                                 toolbar_location="above")
        # a start's coordinates in the title: 12 px, over the frame's whole width
        self.trajectory.title.text_font_size = "12px"
        lines = [self.trajectory.line("t", name, source=self.traj_source, color=colour)
                 for name, colour in (("theta", "#1f77b4"), ("omega", "#ff7f0e"))]
        _legend_above(self.trajectory, [("theta [rad]", lines[:1]),
                                        ("omega [rad/s]", lines[1:])])
        self.phase = figure(name="phase", width=SIDE_WIDTH, height=280,
                            x_range=Range1d(0, 1), y_range=Range1d(0, 1),
                            x_axis_label="theta [rad]",
                            y_axis_label="omega [rad/s]", title="phase portrait",
                            tools="box_zoom,wheel_zoom,pan,reset,save",
                            toolbar_location="above")
        path = self.phase.line("theta", "omega", source=self.traj_source, color="#1f77b4")
        # stroboscopic points only where the scene is forced (a legend entry of an
        # unforced scene's always-empty set would only hide the curve)
        self.strobe = self.strobe_item = None
        if getattr(self.explorer.state.scene, "forcing", None) is not None:  # a system: none
            self.strobe = self.phase.scatter("theta", "omega", source=self.strobe_source,
                                             size=6, color="#d62728", name="strobe")
            legend = _legend_above(self.phase, [("trajectory", [path]),
                                                ("stroboscopic points", [self.strobe])])
            self.strobe_item = legend.items[1]

        # controls from the declarations
        self.errors: dict[str, pn.pane.Alert] = {}
        self.widgets: dict[str, object] = {}
        self.quantity = _labelled(pn.widgets.Select, "quantity", options=self._quantity_options(),
                                          value=s.quantity, width=260)
        self.x_axis = _labelled(pn.widgets.Select, "x axis", options=list(e.axes()), value=v.x,
                                        width=125)
        self.y_axis = _labelled(pn.widgets.Select, "y axis", options=list(e.axes()), value=v.y,
                                        width=125)
        for name, widget in (("quantity", self.quantity), ("x", self.x_axis),
                             ("y", self.y_axis)):
            self._bind(name, widget)
        scene_controls = [self._control(c) for c in e.parameter_controls()]
        run_controls = [self._control(c) for c in e.run_controls()]
        self.back = _labelled(pn.widgets.Button, "◀ back", width=80, disabled=True)
        self.forward = _labelled(pn.widgets.Button, "forward ▶", width=80, disabled=True)
        self.reset = _labelled(pn.widgets.Button, "reset", width=80)
        self.back.on_click(lambda event: self._history(self.explorer.back))
        self.forward.on_click(lambda event: self._history(self.explorer.forward))
        self.reset.on_click(lambda event: self._history(self.explorer.reset))
        self.view_error = self._alert()
        self.status = pn.pane.Markdown("starting…", width=560, name="status")
        self.caption = pn.pane.Markdown("", width=560)
        self.info = pn.pane.Markdown("**Click a start on the map** to see its trajectory.",
                                     width=SIDE_WIDTH, name="info")
        self.numbers = pn.pane.Markdown("", width=560, name="numbers")
        self.on_request = _labelled(pn.widgets.Select, "on request",
                                    options=list(ON_REQUEST), width=300,
                                    visible=bool(ON_REQUEST))
        self.on_request_button = _labelled(pn.widgets.Button, "compute for this view",
                                           width=170, visible=bool(ON_REQUEST))
        self.on_request_button.on_click(lambda event: self._request_numbers())
        self.on_request_text = pn.pane.Markdown("", width=560, name="on_request")
        self.map_python = pn.pane.Markdown("", width=560)
        self.map_toml = pn.pane.Markdown("", width=560)
        self.traj_python = pn.pane.Markdown("(click a start)", width=560)
        self.traj_toml = pn.pane.Markdown("(click a start)", width=560)
        downloads = pn.Row(
            pn.widgets.FileDownload(callback=self._netcdf, filename="sweep-explore.nc",
                                    label="netCDF", width=100),
            pn.widgets.FileDownload(callback=self._png, filename="sweep-explore.png",
                                    label="PNG", width=90),
            pn.widgets.FileDownload(callback=self._toml_file, filename="sweep-explore.toml",
                                    label="run file", width=100))
        controls = pn.Column(
            pn.pane.Markdown("### Map"), self.quantity, pn.Row(self.x_axis, self.y_axis),
            pn.pane.Markdown(f"### {self.controls_heading}"), *scene_controls,
            pn.pane.Markdown("### Run"), *run_controls, width=290, scroll=True, height=900)
        main = pn.Column(
            pn.Row(self.back, self.forward, self.reset, downloads), self.view_error,
            self.status, pn.pane.Bokeh(self.map), self.caption,
            pn.pane.Markdown("#### Numbers of this view"), self.numbers,
            pn.Row(self.on_request, self.on_request_button), self.on_request_text)
        side = pn.Column(pn.pane.Bokeh(self.trajectory), pn.pane.Bokeh(self.phase), self.info)
        code = pn.Tabs(("map: Python", self.map_python), ("map: TOML", self.map_toml),
                       ("trajectory: Python", self.traj_python),
                       ("trajectory: TOML", self.traj_toml), width=1000)
        self.layout = pn.Column(
            pn.pane.Markdown("## sweep explore: maps recomputed on every zoom"),
            pn.Row(controls, main, side), code)

    def _quantity_options(self) -> dict:
        return {label: name for name, label in self.explorer.quantities().items()}

    def _alert(self):
        return pn.pane.Alert("", alert_type="danger", visible=False, width=260,
                             margin=(0, 5))

    def _control(self, control):
        if control.kind == "choice":
            widget = _labelled(pn.widgets.Select, control.label, options=list(control.choices),
                                       value=control.value, width=260)
        elif control.kind == "int":
            widget = _labelled(pn.widgets.IntInput, control.label, value=int(control.value),
                                         width=260)
        else:
            widget = _labelled(pn.widgets.FloatInput, control.label, value=float(control.value),
                                           width=260)
        widget.description = control.help
        self.widgets[control.name] = widget
        self._bind(control.name, widget)
        return pn.Column(widget, self.errors[control.name], margin=0)

    def _bind(self, name: str, widget) -> None:
        self.errors.setdefault(name, self._alert())
        widget.param.watch(partial(self._changed, name), "value")

    # -- events -------------------------------------------------------------------
    def _changed(self, name: str, event) -> None:
        """A control changed: validate through the model; show the refusal beside the
        control, or compute."""
        value = event.new
        alert = self.errors[name]
        try:
            if value is None:
                raise InvalidInput(name, f"{name} must be a number, got nothing")
            before = self.explorer.state.view
            self.explorer.update(**{name: value})
        except InvalidInput as exc:
            alert.object = f"{exc}"
            alert.visible = True
            return
        alert.visible = False
        alert.object = ""
        for other in self.errors.values():  # an earlier refusal is moot now
            other.visible = False
        if self.explorer.state.view != before:
            self._apply_view()
        self._submit()

    def _range_changed(self, attr, old, new) -> None:
        self.last_change = time.perf_counter()
        if self.pending_zoom is None and self.doc is not None:
            self.pending_zoom = self.doc.add_timeout_callback(self._zoom, DEBOUNCE_MS)

    def _zoom(self) -> None:
        self.pending_zoom = None
        quiet = (time.perf_counter() - self.last_change) * 1000.0
        if quiet < DEBOUNCE_MS and self.doc is not None:  # still moving: wait for the rest
            self.pending_zoom = self.doc.add_timeout_callback(
                self._zoom, max(1, math.ceil(DEBOUNCE_MS - quiet)))
            return
        self.timeline.append((time.perf_counter(), self.latest + 1, "zoom", None))
        xr_, yr = self.map.x_range, self.map.y_range
        window = ((float(xr_.start), float(xr_.end)), (float(yr.start), float(yr.end)))
        v = self.explorer.state.view
        if np.allclose(window, (v.x_range, v.y_range), rtol=1e-12, atol=0.0):
            return  # our own change (history), or nothing new
        if self._move_view(lambda: self.explorer.zoom(*window)):
            self._submit()

    def _history(self, move) -> None:
        if self._move_view(move):
            self._apply_view()
            self._submit()

    def _move_view(self, move) -> bool:
        """Run ``move`` (a change of view); show its refusal above the map, or clear it.
        True when the view moved."""
        try:
            move()
        except InvalidInput as exc:
            self.view_error.object = f"{exc}"
            self.view_error.visible = True
            return False
        self.view_error.visible = False
        return True

    def _apply_view(self) -> None:
        """Put the explorer's view on the figure (ranges, labels, axis selectors)."""
        v = self.explorer.state.view
        self.map.x_range.update(start=v.x_range[0], end=v.x_range[1])
        self.map.y_range.update(start=v.y_range[0], end=v.y_range[1])
        self._label_axes()
        for widget, value in ((self.x_axis, v.x), (self.y_axis, v.y)):
            if widget.value != value:
                with widget.param.discard_events(widget):
                    widget.value = value

    def _axis_text(self, name: str) -> str:
        """Axis ``name``'s label in the units the explorer computes in."""
        return _axis_label(name)

    def _label_axes(self) -> None:
        """The map's axis labels and tick units for the view's axes (`degrees_label`)."""
        v = self.explorer.state.view
        for axis, name in ((self.map.xaxis[0], v.x), (self.map.yaxis[0], v.y)):
            label, scale = degrees_label(self._axis_text(name), name)
            axis.axis_label = label
            if axis.ticker.args["scale"] != scale:
                axis.ticker.args = {"scale": scale, "minor": False}
                axis.formatter.args = {"scale": scale}

    def _submit(self) -> None:
        e = self.explorer
        self.back.disabled = not e.can_go_back()
        self.forward.disabled = not e.can_go_forward()
        self.latest = self.requests.submit(e.state)
        self.timeline.append((time.perf_counter(), self.latest, "submit", None))
        s = e.state
        self.status.object = (f"computing {e.quantity_info(s.quantity).label} at "
                              f"{s.resolution} x {s.resolution}…")
        self.numbers.object = "*computing with the map…*"
        self.on_request_text.object = ""

    def _show_code(self, request: int, state) -> None:
        """The Python and the run file of ``state``'s map (after its picture: they wait
        for no one)."""
        if request != self.latest:
            return
        e = self.explorer
        self.map_python.object = f"```python\n{e.python_snippet(state)}```"
        self.map_toml.object = f"```toml\n{e.toml_text(state)}```"

    def _show(self, request: int, result: MapResult) -> None:
        """Draw a result (on the event loop); results of older requests are dropped."""
        if request != self.latest:
            return
        self.result = result
        s = result.state
        x0, x1 = s.view.x_range
        y0, y1 = s.view.y_range
        with hold(self.doc):  # one message for the picture, its colours and its text
            self.source.data = {"image": [wire_image(result)], "x": [x0], "y": [y0],
                                "dw": [x1 - x0], "dh": [y1 - y0], "stage": [result.stage]}
            self._colours(result)
            ny, nx = result.image.shape
            word = {"preview": "preview", "step": "step"}.get(result.stage, "map")
            more = ""
            if result.stage != "final":
                more = (f" ({result.done:.0%} of the starts); computing "
                        f"{s.resolution} x {s.resolution}…")
            pilot = " (pilot catalogue included)" if result.catalogue is not None else ""
            route = f"; {result.route}" if result.route and result.stage == "final" else ""
            found = f"; {result.summary}" if result.summary and result.stage == "final" \
                else ""
            self.status.object = (f"**{word}** {nx} x {ny} in {result.seconds:.2f} s"
                                  f"{pilot}{route}{found}{more}")
            self.caption.object = result.caption
            self.map.title.text = f"{self.explorer.quantity_info(s.quantity).label}"
        seconds = result.seconds + (result.preview_seconds if result.stage == "final" else 0)
        self.timeline.append((time.perf_counter(), request, result.stage, seconds))
        if result.stage == "final":
            if self.doc is not None and getattr(self.doc, "session_context", None):
                self.doc.add_next_tick_callback(partial(self._show_code, request, s))
            else:
                self._show_code(request, s)

    def _colours(self, result: MapResult) -> None:
        """The colour mapper and the colour bar of ``result`` (changed only where they
        differ: an unchanged property sends nothing)."""
        if result.legend:
            palette = _palette(result)
            if list(self.mapper.palette) != palette:
                self.mapper.palette = palette
            self.mapper.update(low=-0.5, high=len(palette) - 0.5)
            step = max(1, math.ceil(len(palette) / 16))
            ticks = list(range(0, len(palette), step))
            self.ticker.ticks = ticks
            self.colorbar.update(major_label_overrides={
                k: result.legend[k][1] for k in ticks})
        else:
            finite = result.image[np.isfinite(result.image)]
            low, high = (float(finite.min()), float(finite.max())) if finite.size else (0, 1)
            if high <= low:
                high = low + 1.0
            if list(self.mapper.palette) != list(Viridis256):
                self.mapper.palette = Viridis256
            self.mapper.update(low=low, high=high)
            ticks = _nice_ticks(low, high)
            self.ticker.ticks = ticks
            # each tick's own text, not no overrides: BokehJS (3.9) kept drawing a label
            # map's names ("attractor 0" at 0) once the overrides were emptied
            self.colorbar.update(major_label_overrides={t: _tick_text(t) for t in ticks})
        if self.colour_title.text != result.title:
            self.colour_title.text = result.title
            # room for it right of the frame, where the bar's labels are narrower (a
            # continuous map's numbers): ~7 px a character at 12 px
            self.map.min_border_right = (self.colorbar.padding
                                         + TITLE_CHAR_PX * len(result.title) + 5)

    def _show_numbers(self, request: int, result: MapResult, numbers) -> None:
        """The numbers of the final map under it (None: a map of continuous values)."""
        if request != self.latest:
            return
        self.numbers.object = (numbers.markdown() if numbers is not None else
                               "*a map of continuous values: no labels to count*")
        self.timeline.append((time.perf_counter(), request, "numbers", None))

    def _request_numbers(self) -> None:
        """Run the selected on-request number for the view's final map on a thread of
        its own (it may run new trajectories: seconds); shown unless the view changed."""
        name = self.on_request.value
        result, request = self.result, self.latest
        if name not in ON_REQUEST:
            self.on_request_text.object = f"**refused**: {name!r} is not offered"
            return
        if result is None or result.stage != "final" or not result.legend:
            self.on_request_text.object = ("**refused**: wait for the final map of a "
                                           "discrete quantity")
            return
        self.on_request_text.object = f"computing {name}…"
        function, explorer = ON_REQUEST[name], self.explorer
        self.numbers_request += 1
        ticket = self.numbers_request
        report = self._from_worker(self._show_requested)

        def work():
            try:
                text = function(result, explorer)
            except Exception as exc:  # noqa: BLE001 - shown on the page
                text = f"**{name} failed**: {' '.join(str(exc).split())}"
            report(request, ticket, text)

        threading.Thread(target=work, name="sweep-explore-on-request", daemon=True).start()

    def _show_requested(self, request: int, ticket: int, text: str) -> None:
        if request == self.latest and ticket == self.numbers_request:
            self.on_request_text.object = text

    def _failed(self, request: int, exc: Exception) -> None:
        if request != self.latest:
            return
        self.status.object = f"**error**: {' '.join(str(exc).split())}"

    def _tapped(self, event) -> None:
        """A click on the map: the trajectory of the nearest pixel's start."""
        try:
            traj = self.explorer.trajectory(event.x, event.y, self.result)
        except InvalidInput as exc:
            self.info.object = f"**refused**: {exc}"
            return
        except ValueError as exc:
            self.info.object = f"**refused**: {' '.join(str(exc).split())}"
            return
        self.show_trajectory(traj)

    def show_trajectory(self, traj: Trajectory) -> None:
        v = self.explorer.state.view
        self.clicked.data = {"x": [traj.point[v.x]], "y": [traj.point[v.y]]}
        self.traj_source.data = {"t": traj.t, "theta": traj.theta, "omega": traj.omega}
        self.strobe_source.data = {"theta": traj.strobe_theta, "omega": traj.strobe_omega}
        _fit(self.trajectory, [traj.t], [traj.theta, traj.omega])
        _fit(self.phase, [traj.theta, traj.strobe_theta], [traj.omega, traj.strobe_omega])
        strobed = traj.strobe_theta.size > 0
        if self.strobe is not None:  # a forced scene: its entry only with points to show
            self.strobe.visible = strobed
            self.strobe_item.visible = strobed
        where = ", ".join(f"{k} = {val:.6g}" for k, val in traj.point.items())
        self.trajectory.title.text = f"trajectory from {where}"
        lines = [f"**start** theta0 = {traj.theta0:.6g} rad "
                 f"({math.degrees(traj.theta0):.4g} deg), omega0 = {traj.omega0:.6g} rad/s "
                 f"({math.degrees(traj.omega0):.4g} deg/s)",
                 f"**status** {traj.status}", f"**label** {traj.label}"]
        if self.strobe is not None:
            lines.append(f"**stroboscopic points** {traj.strobe_theta.size}"
                         + ("" if strobed else " (dt does not divide the forcing period, or "
                            "the forcing frequency is an axis)"))
        self.info.object = "  \n".join(lines)
        self.traj_python.object = f"```python\n{traj.python}```"
        self.traj_toml.object = f"```toml\n{traj.toml}```"

    # -- downloads (bytes made here; the browser chooses where to save) ----------------
    def _final(self) -> MapResult:
        result = self.result
        if result is None or result.stage != "final" or result.state != self.explorer.state:
            result = self.explorer.compute(self.explorer.state)
        return result

    def _netcdf(self):
        import io

        return io.BytesIO(self.explorer.netcdf_bytes(self._final()))

    def _png(self):
        import io

        return io.BytesIO(self.explorer.png_bytes(self._final()))

    def _toml_file(self):
        import io

        return io.BytesIO(self.explorer.toml_text().encode())


class _ServerThread(threading.Thread):
    """A Panel server on its own thread and event loop.

    `listen` starts the thread and returns once the server's socket listens and its
    event loop runs (so a client that connects is answered), or raises what binding
    raised; no traceback is printed from the thread and nothing is left running.

    Parameters
    ----------
    make : callable
        ``make(loop)`` builds the server (binding its socket) on the Tornado ``loop``;
        called on this thread.
    """

    def __init__(self, make) -> None:
        super().__init__(name="sweep-explore-server", daemon=True)
        self._make = make
        self._ready = threading.Event()
        self.error: BaseException | None = None
        self.server = None
        self.loop = None

    def listen(self, timeout: float = LISTEN_TIMEOUT):
        """Start; return the server once it listens, or raise the error of binding."""
        self.start()
        if not self._ready.wait(timeout):
            self.stop()
            raise TimeoutError(f"the explorer's server did not start listening within "
                               f"{timeout:g} s")
        if self.error is not None:
            self.join()
            raise self.error
        return self.server

    def run(self) -> None:
        from tornado.ioloop import IOLoop

        loop = IOLoop(make_current=False)
        try:
            server = self._make(loop)
            server.start()
        except BaseException as exc:  # noqa: BLE001 - raised again by listen, in the caller
            self.error = exc
            loop.close(all_fds=True)
            self._ready.set()
            return
        self.server, self.loop = server, loop
        loop.add_callback(self._ready.set)  # once the loop runs: clients are answered
        try:
            loop.start()
        finally:
            server.stop()
            loop.close(all_fds=True)

    def stop(self, timeout: float = 10.0) -> None:
        """Stop serving (cancel the loop's tasks, close the socket); wait up to
        ``timeout`` seconds for the thread."""
        loop = self.loop
        if loop is not None and self.is_alive():
            loop.add_callback(self._shutdown)
        if self.is_alive() and threading.current_thread() is not self:
            self.join(timeout)

    async def _shutdown(self) -> None:
        import asyncio

        current = asyncio.current_task()
        tasks = [t for t in asyncio.all_tasks() if t is not current]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        self.loop.stop()


class ExplorerApp:
    """The explorer of a scene's maps, served by Panel (see `sweep.explore`).

    Parameters
    ----------
    scene, grid, **run_kwargs
        As `sweep.explore.model.Explorer` (``quantity``, ``resolution`` included);
        validated now.
    """

    #: The model and the page of each session (`sweep.explore.system_app`: systems').
    explorer_class = Explorer
    session_class = _Session

    def __init__(self, scene, grid, **run_kwargs) -> None:
        self.scene, self.grid, self.kwargs = scene, grid, dict(run_kwargs)
        self.cache: OrderedDict = OrderedDict()
        # validates
        self.template = self.explorer_class(scene, grid, cache=self.cache, **run_kwargs)
        self.warm_seconds: float | None = None
        self.server = None
        self.url: str | None = None
        self._warm_lock = threading.Lock()
        self._warming = 0  # warm-ups running now
        self._after_warm: list = []
        self._sessions: deque = deque(maxlen=SESSIONS_KEPT)  # weak references

    @property
    def sessions(self) -> list:
        """The pages open now (of the last `SESSIONS_KEPT` opened), newest last: weak
        references, so a closed page's maps are not kept alive (for benchmarks)."""
        return [s for s in (ref() for ref in self._sessions) if s is not None]

    # -- warm-up ----------------------------------------------------------------------
    def warm_up(self) -> float:
        """Compute the home view's preview, map and one trajectory (compiling, or loading
        from the disk cache, every kernel the first zoom and click need); the map is kept
        for the first page. Returns the seconds it took.

        Pages opened meanwhile say so (`WARMING_TEXT`) and start computing when it ends
        (the first map is then in the shared cache).
        """
        with self._warm_lock:
            self._warming += 1
        try:
            begin = time.perf_counter()
            e = self.template
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                e.compute(preview=True)
                result = e.compute()
                e.trajectory(float(result.x[len(result.x) // 2]),
                             float(result.y[len(result.y) // 2]), result)
            self.warm_seconds = time.perf_counter() - begin
        finally:
            with self._warm_lock:
                self._warming -= 1
                waiting = [] if self._warming else self._after_warm
                if not self._warming:
                    self._after_warm = []
            for callback in waiting:
                try:
                    callback()
                except Exception:  # noqa: BLE001 - a page closed meanwhile
                    continue
        return self.warm_seconds

    @property
    def warming(self) -> bool:
        """True while `warm_up` runs."""
        return self._warming > 0

    def call_when_warm(self, callback) -> bool:
        """Call ``callback()`` when the running `warm_up` ends (on its thread) and return
        True; return False, calling nothing, when no warm-up runs."""
        with self._warm_lock:
            if not self._warming:
                return False
            self._after_warm.append(callback)
            return True

    # -- Panel ------------------------------------------------------------------------
    def session(self):
        """A new page (its own explorer and history): what each browser session gets."""
        return self.session_class(self).layout

    def panel(self):
        """The page as a Panel layout (for notebooks and templates)."""
        return self.session()

    def _repr_mimebundle_(self, include=None, exclude=None):
        return self.panel()._repr_mimebundle_(include, exclude)

    def servable(self, title: str = "sweep explore"):
        """Mark a new page for ``panel serve`` (returns it)."""
        return self.panel().servable(title=title)

    def serve(self, *, port: int = 0, host: str = "127.0.0.1", show: bool = False,
              threaded: bool = True, warm: bool = True, quiet: bool = True):
        """Start a server for this app: bind first, then warm up.

        Parameters
        ----------
        port : int, default 0
            TCP port; 0: a free one.
        host : str, default "127.0.0.1"
            The address to bind; websocket connections are accepted only from pages
            served at ``host:port`` (and ``localhost:port`` for 127.0.0.1).
        show : bool, default False
            Open a browser tab.
        threaded : bool, default True
            Run the server in a thread and return once it listens; False blocks until
            stopped (Ctrl-C).
        warm : bool, default True
            `warm_up` on a background thread once the server listens: a page opened
            meanwhile says it is warming up, then shows the map at once.
        quiet : bool, default True
            Do not print Panel's "Launching server" line.

        Returns
        -------
        The server (``.stop()``), listening; its URL is `url`.

        Raises
        ------
        AddressUnavailable
            An OSError: the socket cannot be bound (the port is in use, a privileged
            port, an address not of this machine); nothing is left running.
        """
        if self.server is not None:
            raise RuntimeError(f"this app already serves {self.url}; stop() it first")
        for attempt in range(5):
            chosen = port
            try:
                chosen = port or free_port(host)
                thread = _ServerThread(partial(self._make_server, port=chosen, host=host,
                                               show=show, quiet=quiet))
                thread.listen()
                break
            except OSError as exc:
                # port 0: another program took the free port first; take another
                if not port and exc.errno == errno.EADDRINUSE and attempt < 4:
                    continue
                raise AddressUnavailable(host, chosen, exc) from None
        self.server = thread
        self.url = f"http://{host if ':' not in host else f'[{host}]'}:{chosen}/"
        if warm and self.warm_seconds is None:
            threading.Thread(target=self._warm_in_background, name="sweep-explore-warm-up",
                             daemon=True).start()
        if not threaded:
            try:
                while thread.is_alive():
                    thread.join(0.5)
            except KeyboardInterrupt:
                pass
            finally:
                self.stop()
        return thread

    def _warm_in_background(self) -> None:
        try:
            self.warm_up()
        except Exception as exc:  # noqa: BLE001 - the page computes again and shows it
            warnings.warn(f"explore: warm-up failed: {exc}", RuntimeWarning, stacklevel=1)

    def _make_server(self, loop, *, port: int, host: str, show: bool, quiet: bool):
        """Panel's server for this app on ``loop`` (binds; not started)."""
        origins = [f"{host}:{port}"]
        if host in ("127.0.0.1", "localhost"):
            origins = [f"127.0.0.1:{port}", f"localhost:{port}"]
        elif host in ("0.0.0.0", "::", ""):  # every interface: this machine's own names
            names = {socket.gethostname(), socket.getfqdn(), "127.0.0.1", "localhost"}
            try:
                names.update(socket.gethostbyname_ex(socket.gethostname())[2])
            except OSError:
                pass
            origins = [f"{name}:{port}" for name in sorted(names)]
        return pn.serve({"/": self.session}, port=port, address=host,
                        websocket_origin=origins, show=show, threaded=False, loop=loop,
                        title="sweep explore", verbose=not quiet, start=False)

    def show(self, **kwargs):
        """Serve and open a browser tab (`serve` with ``show=True``)."""
        return self.serve(show=True, **kwargs)

    def stop(self) -> None:
        """Stop the server `serve` started (its port is free again)."""
        if self.server is not None:
            self.server.stop()
            self.server = None


def _way_out(exc: AddressUnavailable, port: int) -> str:
    """The end of ``sweep explore``'s one line when it cannot listen: the option to
    change. An address that is not this machine's (or no address at all) is the
    host's fault, whatever the port; a busy or privileged port is the port's, and
    ``--port 0`` is the way out unless it was given."""
    if isinstance(exc.reason, socket.gaierror) or exc.errno == errno.EADDRNOTAVAIL:
        return ("accepted: --host an address of this machine (127.0.0.1, the default; "
                "0.0.0.0 for all of its addresses)")
    if port:
        return "--port 0 picks a free port"
    return ("accepted: another --host, or run again (--port 0: other programs took the "
            "free ports it picked first)")


def main_serve(app: ExplorerApp, *, port: int, host: str, open_browser: bool,
               stop: threading.Event | None = None) -> int:
    """``sweep explore``: bind, print the URL, warm up (saying so), serve until Ctrl-C.

    Parameters
    ----------
    app : ExplorerApp
    port : int
        TCP port (0: a free one).
    host : str
        The address to bind.
    open_browser : bool
        Open a browser tab on the page (at once; it shows the warm-up).
    stop : threading.Event, optional
        Stops serving once set (besides Ctrl-C).

    Returns
    -------
    int
        0 once stopped.

    Raises
    ------
    AddressUnavailable
        The address or the port cannot be bound; the message says what to change
        (`_way_out`: ``--host`` or ``--port``).
    """
    try:
        app.serve(port=port, host=host, show=open_browser, threaded=True, warm=False)
    except AddressUnavailable as exc:
        raise AddressUnavailable(exc.host, exc.port, exc.reason,
                                 way_out=_way_out(exc, port)) from None
    if host not in ("127.0.0.1", "localhost", "::1"):  # once it listens: the port is known
        print(f"sweep: warning: --host {host}: anyone who can reach port "
              f"{urllib.parse.urlsplit(app.url).port} on this address can use this "
              "machine's cores through the explorer", file=sys.stderr)
    stop = stop or threading.Event()
    try:
        print(f"sweep explore: serving {app.url} (Ctrl-C stops)", flush=True)
        print("sweep explore: compiling the kernels and computing the first view "
              "(the page shows this too)…", file=sys.stderr, flush=True)
        seconds = app.warm_up()
        print(f"sweep explore: first view ready in {seconds:.1f} s", file=sys.stderr,
              flush=True)
        while not stop.wait(0.5):
            if app.server is None or not app.server.is_alive():
                raise OSError(f"the explorer's server at {app.url} stopped unexpectedly")
    except KeyboardInterrupt:
        pass
    finally:
        app.stop()
    return 0
