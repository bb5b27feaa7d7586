"""The explorer's server: it binds before it says where it serves, refuses a busy port in
one line (the API with `AddressUnavailable`), serves the page while the kernels warm up,
and the trajectory panel's legends (sweep.explore.app; needs Panel and Bokeh)."""

from __future__ import annotations

import dataclasses
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import sweep

pytest.importorskip("panel")
pytest.importorskip("bokeh")

from bokeh.models import Legend

from sweep.explore import app as explore_app
from sweep.explore.app import AddressUnavailable, ExplorerApp, main_serve

ROOT = Path(__file__).resolve().parent.parent
N = 16  # pixels per axis: small maps (the server does not depend on their size)
PERIOD = 2 * np.pi  # the forced scene's forcing period (W = 1 rad/s) [s]

#: A damped scene on a small window, short runs: the run file of the child processes.
RUN_FILE = """\
[scene]
gravity = 9.81
length = 1.0

[scene.damping]
coefficient = 0.3

[grid]
theta0 = {start = -3.0, stop = 3.0, num = 16}
omega0 = {start = -4.0, stop = 4.0, num = 16}

[run]
t_end = 2.0
dt = 0.05
"""


def damped_app(**extra) -> ExplorerApp:
    scene = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.3),))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, N), omega0=np.linspace(-4, 4, N))
    return ExplorerApp(scene, grid, t_end=2.0, dt=0.05, resolution=N, **extra)


def forced_app() -> ExplorerApp:
    """A forced scene, 10 forcing periods of 50 steps (the strobe needs dt | period)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, N), omega0=np.linspace(-4, 4, N))
    return ExplorerApp(scene, grid, t_end=10 * PERIOD, dt=PERIOD / 50,
                       t_transient=5 * PERIOD, resolution=N, quantity="motion")


@pytest.fixture
def busy_port():
    """A port this test listens on (bound and listening: what another server does)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield s.getsockname()[1]


def _get(url: str, timeout: float = 10.0) -> tuple[int, bytes]:
    with urllib.request.urlopen(url, timeout=timeout) as response:
        return response.status, response.read()


def _refused(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
    except ConnectionRefusedError:
        return True
    return False


def _server_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "sweep-explore-server"]


def _child_env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(
        os.pathsep)
    env.pop("CI", None)  # no CI-only behaviour in the child
    return env


# ------------------------------------------------------------------- a busy port
def test_a_busy_port_is_one_line_and_a_nonzero_exit_in_a_real_process(busy_port, tmp_path):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    result = subprocess.run(
        [sys.executable, "-m", "sweep", "explore", str(run_file), "--no-browser", "--port",
         str(busy_port)], capture_output=True, text=True, timeout=120, env=_child_env(),
        check=False)
    assert result.returncode == 2, result
    assert result.stdout == ""  # no URL: nothing serves it
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    line = lines[0]
    assert line.startswith("sweep: error: ") and "Traceback" not in result.stderr
    for words in ("127.0.0.1", str(busy_port), "Address already in use", "--port 0"):
        assert words in line, line


def test_a_busy_port_raises_address_unavailable_and_leaves_nothing_running(busy_port):
    app = damped_app()
    with pytest.raises(AddressUnavailable) as info:
        app.serve(port=busy_port, warm=False)
    exc = info.value
    assert isinstance(exc, OSError)
    assert (exc.host, exc.port) == ("127.0.0.1", busy_port)
    assert exc.errno == exc.reason.errno and exc.errno is not None
    for words in ("127.0.0.1", str(busy_port), "Address already in use", "port=0"):
        assert words in str(exc)
    assert app.server is None and not _server_threads()


def test_a_host_of_another_machine_is_refused_in_one_line(capsys):
    from sweep.cli import main

    # 192.0.2.1: TEST-NET-1 (RFC 5737), never an address of this machine
    assert main(["explore", "--no-browser", "--port", "0", "--host", "192.0.2.1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("sweep: error: cannot listen on address 192.0.2.1")
    assert "not an address of this machine" in err[-1] and not _server_threads()


# ------------------------------------------------------------------- the happy path
def test_the_printed_url_answers_at_once_in_a_real_process(tmp_path):
    run_file = tmp_path / "run.toml"
    run_file.write_text(RUN_FILE)
    child = subprocess.Popen(
        [sys.executable, "-m", "sweep", "explore", str(run_file), "--no-browser", "--port",
         "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_child_env())
    lines: queue.Queue = queue.Queue()
    for stream, name in ((child.stdout, "out"), (child.stderr, "err")):
        threading.Thread(target=lambda s=stream, n=name: [lines.put((n, line)) for line in s],
                         daemon=True).start()
    seen = []
    try:
        url = None
        end = time.monotonic() + 120  # import, compile (cold cache) and warm-up, bounded
        while url is None and time.monotonic() < end:
            try:
                stream, line = lines.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
            seen.append((stream, line))
            if stream == "out" and "serving http://" in line:
                url = line.split("serving ", 1)[1].split()[0]
        assert url is not None, seen
        # the line is printed once the socket listens and its loop runs: connect now
        status, page = _get(url)
        assert status == 200 and b"sweep explore" in page
        ready = False
        while not ready and time.monotonic() < end:
            try:
                stream, line = lines.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
            seen.append((stream, line))
            ready = "first view ready in" in line
        assert ready, seen
        # the terminal says what it waits for before it waits, and the time after
        said = [k for k, (_, line) in enumerate(seen) if "compiling the kernels" in line]
        assert said and said[0] < len(seen) - 1  # the "ready" line is the last one seen
        child.send_signal(signal.SIGINT)
        assert child.wait(timeout=30) == 0
    finally:
        if child.poll() is None:
            child.kill()
            child.wait(timeout=10)
    assert not any("Traceback" in line for _, line in seen), seen


def test_serve_listens_before_it_returns_and_stop_frees_the_port():
    app = damped_app()
    app.serve(port=0, warm=False)
    try:
        port = int(app.url.rstrip("/").rsplit(":", 1)[1])
        status, _ = _get(app.url)
        assert status == 200
        with pytest.raises(RuntimeError, match="already serves"):
            app.serve(port=0, warm=False)
    finally:
        app.stop()
    assert app.server is None and not _server_threads()
    assert _refused(port)


# ------------------------------------------------------------------- the warm-up
def test_the_page_is_served_while_the_first_view_warms_up(monkeypatch, capsys):
    app = damped_app()
    entered, release = threading.Event(), threading.Event()
    compute = app.template.compute

    def held(*args, **kwargs):  # the warm-up's first computation waits for the test
        entered.set()
        assert release.wait(60)
        return compute(*args, **kwargs)

    monkeypatch.setattr(app.template, "compute", held)
    stop = threading.Event()
    codes = []
    server = threading.Thread(target=lambda: codes.append(main_serve(
        app, port=0, host="127.0.0.1", open_browser=False, stop=stop)), daemon=True)
    server.start()
    out = err = ""
    try:
        assert entered.wait(30)
        end = time.monotonic() + 20  # the URL comes before the warm-up ends
        while "serving http://" not in out and time.monotonic() < end:
            time.sleep(0.05)
            captured = capsys.readouterr()
            out, err = out + captured.out, err + captured.err
        assert "serving http://" in out, (out, err)
        assert not release.is_set()
        assert "compiling the kernels and computing the first view" in err
        assert "first view ready" not in err
        status, page = _get(app.url)  # answered during the warm-up
        assert status == 200 and b"sweep explore" in page
        assert app.warming

        # a page opened now says it is warming up, and computes nothing yet
        session = explore_app._Session(app)
        assert session.status.object == explore_app.WARMING_TEXT
        assert session.latest == 0
        release.set()
        end = time.monotonic() + 60
        while session.result is None and time.monotonic() < end:
            time.sleep(0.05)
        assert session.result is not None and not session.result.preview  # from the cache
        assert session.result is app.cache[session.explorer.state]
        session.requests.close()
        while "first view ready in" not in err and time.monotonic() < end:
            time.sleep(0.05)
            err += capsys.readouterr().err
        assert "first view ready in" in err
    finally:
        release.set()
        stop.set()
        server.join(30)
    assert codes == [0] and not _server_threads()


def test_serve_warms_up_in_the_background():
    app = damped_app()
    app.serve(port=0)  # warm=True: returns once listening, the warm-up follows
    try:
        end = time.monotonic() + 60
        while app.warm_seconds is None and time.monotonic() < end:
            time.sleep(0.05)
        assert app.warm_seconds is not None and not app.warming
        assert len(app.cache) == 1  # the home view's final map
    finally:
        app.stop()


# ------------------------------------------------------------------- the legends
def _legend_labels(fig) -> list[str]:
    return [str(getattr(item.label, "value", item.label))
            for legend in fig.select(type=Legend) for item in legend.items]


def _session(app):
    session = explore_app._Session(app)
    session.requests.close()  # the legends only: no map needed
    return session


def test_unforced_phase_portrait_has_no_stroboscopic_entry_and_legends_sit_outside():
    session = _session(damped_app())
    assert not any("strobo" in label for label in _legend_labels(session.phase))
    assert not session.phase.select(name="strobe")
    assert _legend_labels(session.trajectory) == ["theta [rad]", "omega [rad/s]"]
    for fig in (session.trajectory, session.phase):  # never over the curves
        assert not any(isinstance(r, Legend) for r in fig.center)
    assert any(isinstance(r, Legend) for r in session.trajectory.above)
    traj = session.explorer.trajectory(0.5, 0.5)
    session.show_trajectory(traj)
    assert "stroboscopic" not in session.info.object


def test_forced_phase_portrait_shows_stroboscopic_points_only_when_there_are_some():
    session = _session(forced_app())
    assert _legend_labels(session.phase) == ["trajectory", "stroboscopic points"]
    assert not any(isinstance(r, Legend) for r in session.phase.center)
    traj = session.explorer.trajectory(0.5, 0.5)
    assert traj.strobe_theta.size > 0
    session.show_trajectory(traj)
    assert session.strobe.visible and session.strobe_item.visible
    assert f"**stroboscopic points** {traj.strobe_theta.size}" in session.info.object
    empty = dataclasses.replace(traj, strobe_theta=np.empty(0), strobe_omega=np.empty(0))
    session.show_trajectory(empty)
    assert not session.strobe.visible and not session.strobe_item.visible
