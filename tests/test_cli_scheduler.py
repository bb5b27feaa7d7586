"""``sweep run --scheduler ADDRESS`` and ``[run] scheduler``: the chunks run on a Dask
cluster (a LocalCluster this module starts), bit-identical to a local run, with the
same checkpoint/resume behaviour; without dask, or with no scheduler there, one line."""

import contextlib
import io
import sys

import pytest
import xarray as xr
from dask_clusters import DASHBOARD, port_8787_taken

import sweep
from sweep import cli
from sweep.toml_spec import load_run

from test_resume import Interrupt, chunk_files

distributed = pytest.importorskip("distributed")

TIMEOUT = 60  # s: bound on the cluster's start (runs here take well under 5 s)

RUN_FILE = """\
[scene.damping]
coefficient = 0.3

[grid]
theta0 = {start = -3.0, stop = 3.0, num = 9}
omega0 = [-1.0, 0.0, 1.0, 2.0]

[run]
t_end = 3.0
dt = 0.01
observe = ["final", "winding"]
chunk_size = 5
"""


@pytest.fixture(scope="module")
def scheduler():
    # in-process workers (threads): the cheapest real cluster, reached over TCP; its
    # Scheduler on free ports (tests/dask_clusters.py: 8787 races other workers' clusters)
    with port_8787_taken():
        cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                           dashboard_address=DASHBOARD, scheduler_port=0,
                                           protocol="tcp")
    with cluster:
        yield cluster.scheduler_address


def call(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def _same(a, b):
    a, b = a.copy(), b.copy()
    a.attrs.pop("history", None)
    b.attrs.pop("history", None)
    xr.testing.assert_identical(a, b)


@pytest.fixture
def local(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text(RUN_FILE)
    scene, grid, kwargs = load_run(path)
    return path, sweep.run(scene, grid, **kwargs)


def test_option_and_key_run_on_the_cluster(scheduler, local, tmp_path, monkeypatch):
    run_file, reference = local
    submitted = []
    real = distributed.Client.submit

    def counting(self, *args, **kwargs):
        submitted.append(args[0].__name__)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(distributed.Client, "submit", counting)
    code, _out, err = call("run", run_file, "-o", tmp_path / "a.nc", "--scheduler", scheduler)
    assert code == 0, err
    assert submitted.count("run_chunk_task") == 8  # 36 trajectories in chunks of 5
    _same(sweep.load(tmp_path / "a.nc"), reference)
    keyed = tmp_path / "keyed.toml"
    keyed.write_text(RUN_FILE + f'scheduler = "{scheduler}"\n')
    code, _out, err = call("run", keyed, "-o", tmp_path / "b.nc")
    assert code == 0, err
    assert submitted.count("run_chunk_task") == 16
    _same(sweep.load(tmp_path / "b.nc"), reference)


def test_resume_on_the_cluster(scheduler, local, tmp_path, monkeypatch):
    run_file, reference = local
    out, folder = tmp_path / "out.nc", tmp_path / "ck"
    Interrupt(monkeypatch, 3)  # a local run stopped after 3 of 8 chunks
    code, _, err = call("run", run_file, "-o", out, "--checkpoint", folder)
    monkeypatch.undo()
    assert code == 130 and len(chunk_files(folder)) == 3, err
    code, _, err = call("run", run_file, "-o", out, "--checkpoint", folder, "--resume",
                        "--scheduler", scheduler)
    assert code == 0, err
    assert not folder.exists()
    _same(sweep.load(out), reference)


@pytest.mark.parametrize("label,setup,words", [
    ("dask missing", lambda m: m.setitem(sys.modules, "distributed", None),
     "needs dask.distributed, which is not installed; accepted: pip install "
     "'dask[distributed]' (the extra dask)"),
    ("no scheduler there", lambda m: m.setattr(cli, "CONNECT_TIMEOUT_S", 1),
     "cannot connect to the Dask scheduler at 'tcp://127.0.0.1:9'"),
])
def test_cluster_errors_are_one_line(label, setup, words, local, tmp_path, monkeypatch):
    run_file, _ = local
    setup(monkeypatch)
    code, out, err = call("run", run_file, "-o", tmp_path / "out.nc", "--scheduler",
                          "tcp://127.0.0.1:9")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith("sweep: error: --scheduler tcp://127.0.0.1:9: " if label ==
                          "dask missing" else "sweep: error: ")
    assert words in err and "Traceback" not in err
    assert not (tmp_path / "out.nc").exists()


@pytest.mark.parametrize("value,words", [
    ("8786", "[run] scheduler must be a Dask scheduler address such as 'tcp://HOST:8786', "
             "got 8786"),
    ('""', "[run] scheduler must be a Dask scheduler address"),
    ('"tcp://"', "got 'tcp://'"),
    ("true", "got True"),
])
def test_bad_scheduler_key(value, words, tmp_path):
    path = tmp_path / "run.toml"
    path.write_text(RUN_FILE + f"scheduler = {value}\n")
    code, out, err = call("run", path, "-o", tmp_path / "out.nc")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert words in err, err


def test_python_run_arguments_leave_the_scheduler_out(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text(RUN_FILE + 'scheduler = "tcp://somewhere:8786"\n')
    options = {}
    _, _, kwargs = load_run(path, options)
    assert "scheduler" not in kwargs and options == {"scheduler": "tcp://somewhere:8786"}
    assert "scheduler" not in load_run(path)[2]
