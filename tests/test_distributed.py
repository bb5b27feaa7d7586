"""`sweep.run(..., client=...)` on a Dask LocalCluster of two worker processes.

Oracle: a local run of the same grid (the kernel is deterministic per trajectory and
independent of chunking), so every comparison is bit-identical (`assert_identical`),
except the ``history`` attribute (a timestamp).
"""

import concurrent.futures
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr
from dask_clusters import DASHBOARD, PORT_TAKEN_ERROR, port_8787_taken
from shared_kernels import EVERY, EVERY_ADAPTIVE

import sweep
from sweep import Status
from sweep.distributed import run_to_netcdf

distributed = pytest.importorskip("distributed")

TIMEOUT = 60  # s: bound on every wait below (runs here take well under 5 s)

FORCED = sweep.Scene(effects=(sweep.Damping(0.3), sweep.Forcing(1.2, 2 / 3, 0.0)))
#: The observables of the runs below: one set, so that they share a kernel (each observe
#: set is a kernel of its own, compiled for seconds) with each other and with the tests
#: of the same scene's effects and grid size (test_naive, test_engine, test_blocks:
#: tests/shared_kernels.py); which are observed is not what these tests are about.
FORCED_OBSERVE = EVERY


@pytest.fixture(scope="module")
def client():
    # two processes, one Dask thread each; one numba thread each (this CI machine has
    # two cores: more threads would only oversubscribe them); the Scheduler on a free
    # port, not 8787, which another pytest-xdist worker's cluster may be taking
    # (tests/dask_clusters.py: started while 8787 is held, a cluster asking for it fails)
    with port_8787_taken():
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                           dashboard_address=DASHBOARD,
                                           env={"NUMBA_NUM_THREADS": "1"})
    with cluster, distributed.Client(cluster) as c:
        c.wait_for_workers(2, timeout=TIMEOUT)
        yield c


def _same(local, remote):
    local, remote = local.copy(), remote.copy()
    local.attrs.pop("history", None)
    remote.attrs.pop("history", None)
    xr.testing.assert_identical(local, remote)


def _both(client, scene, grid, **kw):
    return sweep.run(scene, grid, **kw), sweep.run(scene, grid, client=client, **kw)


def test_forced_scene_with_several_observables_is_identical(client):
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 23), omega0=np.linspace(-2, 2, 17),
                      forcing_amplitude=[1.2, 1.5])
    local, remote = _both(client, FORCED, grid, t_end=3 * np.pi, dt=np.pi / 300,
                          t_transient=np.pi, observe=FORCED_OBSERVE,
                          chunk_size=97)  # a ragged last chunk
    _same(local, remote)
    assert (remote.status == Status.OK).all()


def test_save_every_is_identical(client):
    grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 9), omega0=[0.0, 0.5, 1.0])
    local, remote = _both(client, FORCED, grid, t_end=2.0, dt=0.01, save_every=7,
                          observe=FORCED_OBSERVE, chunk_size=5)
    assert "time" in remote.dims
    _same(local, remote)


def test_adaptive_method_step_counts_are_identical(client):
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 15), omega0=[0.0, 2.0])
    local, remote = _both(client, FORCED, grid, t_end=5.0, dt=0.1, method="dopri5",
                          observe=EVERY_ADAPTIVE, chunk_size=8)
    assert (remote.steps_accepted > 0).all()
    _same(local, remote)


def test_nonfinite_trajectories_are_flagged_as_locally(client):
    # c = 1e4 with dt = 0.01 is far outside RK4's stability region: those overflow
    scene = sweep.Scene(effects=(sweep.Damping(0.1),))
    grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 4), damping=[0.1, 1e4, 0.2])
    kw = dict(t_end=2.0, dt=0.01, observe=FORCED_OBSERVE, check_stability=False,
              chunk_size=3)
    with pytest.warns(RuntimeWarning, match=r"^4 of 12 trajectories became non-finite"):
        local = sweep.run(scene, grid, **kw)
    with pytest.warns(RuntimeWarning, match=r"^4 of 12 trajectories became non-finite"):
        remote = sweep.run(scene, grid, client=client, **kw)
    _same(local, remote)
    assert (remote.sel(damping=1e4).status == Status.NONFINITE).all()
    assert np.isnan(remote.sel(damping=1e4).theta_final).all()
    assert (remote.sel(damping=[0.1, 0.2]).status == Status.OK).all()


def _worker_kernel_state(spec):
    """On a worker: memo hits/misses of `build`, and numba's disk-cache statistics of
    the kernel for ``spec`` (compiled signatures count as misses)."""
    from sweep.kernels import build, compiled

    info = build.cache_info()
    stats = compiled(build(spec)).stats
    return {"hits": info.hits, "misses": info.misses,
            "disk_loaded": sum(stats.cache_hits.values()),
            "compiled": sum(stats.cache_misses.values())}



def test_systems_on_the_cluster_are_identical(client):
    """A double pendulum (chaotic starts, where one differing ulp grows visibly over
    5 s) and a swing network with saved samples, chunked over the two worker
    processes, give the local run's bits (their kernels are the ones
    tests/test_vector_width.py and tests/test_networks.py compile)."""
    grid = sweep.Grid(theta1_0=np.linspace(-3.0, 3.0, 8), theta2_0=np.linspace(-2.5, 2.5, 8))
    local, remote = _both(client, sweep.DoublePendulum(), grid, t_end=5.0, dt=0.005,
                          observe=("final",), chunk_size=16)
    _same(local, remote)
    network = sweep.SwingNetwork([(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (1, 3)],
                                 power=[2.0, -1.0, 0.5, -0.5, -1.0], coupling=8.0)
    grid = sweep.Grid(perturbed_node=[0, 2, 4], delta_theta=np.linspace(-3, 3, 7),
                      delta_omega=np.linspace(-6, 6, 9))
    local, remote = _both(client, network, grid, t_end=3.0, dt=0.01,
                          observe=("final", "synchrony"), save_every=50, chunk_size=40)
    _same(local, remote)

def test_basins_by_a_catalogue_on_the_cluster_are_identical(client):
    """A driven double pendulum's basins by an attractor catalogue, stopped early, chunked
    over the two worker processes (the catalogue travels with each chunk as kernel data;
    a stopped lane takes the next start of its own chunk), give the local run's bits:
    the labels, the stop status and the catalogue kept in the attributes. The system,
    grid, run and pilot are tests/test_system_attractors.py's, so both kernels (the
    pilot's strobe run and the route's) are the ones it compiles."""
    from test_system_attractors import GRID, RUN, SYSTEM

    run = {k: v for k, v in RUN.items() if k != "progress"}
    catalogue = sweep.maps.pilot_catalogue(SYSTEM, GRID, 12, **run)
    kw = dict(RUN, observe=("attractor",), attractors=catalogue, stop_early=True,
              chunk_size=40, t_transient=0.0)
    local = sweep.run(SYSTEM, GRID, **kw)
    with distributed.get_task_stream(client) as stream:
        remote = sweep.run(SYSTEM, GRID, client=client, **kw)
    _same(local, remote)
    # the 144 starts ran as 4 chunks of at most 40 on the workers, not locally
    assert sum("sweep-chunk" in str(r["key"]) for r in stream.data) == 4
    assert (local["attractor"].values >= 0).all()  # every start stopped on a label
    assert local.attrs["stop_early"] == "once settled on a catalogued attractor"


def test_kernel_is_not_recompiled_per_task(client):
    # a spec no other test uses; the local run puts its machine code in numba's disk cache
    scene = sweep.Scene(model="linear", effects=(sweep.Damping(0.2),))
    grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 40), omega0=np.linspace(-1, 1, 30))
    kw = dict(t_end=10.0, dt=0.001, observe=("theta_max", "energy"), chunk_size=60)
    local = sweep.run(scene, grid, **kw)
    before = client.run(sweep.kernels.build.cache_info)
    with distributed.get_task_stream(client) as stream:
        remote = sweep.run(scene, grid, client=client, **kw)
    _same(local, remote)

    spec = sweep.kernels.KernelSpec(model="linear", effects=("damping",),
                                     observe=("theta_max", "energy"),
                                     block=sweep._config.SMALL_BLOCK)  # 1200 starts: small
    state = client.run(_worker_kernel_state, spec)
    tasks = {}
    for record in stream.data:
        if "sweep-chunk" in str(record["key"]):
            compute = next(s for s in record["startstops"] if s["action"] == "compute")
            tasks.setdefault(record["worker"], []).append(
                (compute["start"], compute["stop"] - compute["start"]))
    assert sum(len(v) for v in tasks.values()) == grid.size // 60
    for worker, durations in tasks.items():
        durations.sort()
        n = len(durations)
        # one build per worker process (the kernel is loaded there once), then memo hits
        assert state[worker]["misses"] - before[worker].misses <= 1
        assert state[worker]["hits"] - before[worker].hits >= n - 1
        # and numba loaded it from the disk cache: nothing was compiled on the worker
        assert state[worker]["compiled"] == 0 and state[worker]["disk_loaded"] >= 1
        first = durations[0][1]
        later = statistics.median(d for _, d in durations[1:])
        print(f"{worker}: {n} tasks, first {first * 1e3:.1f} ms, "
              f"median of the others {later * 1e3:.1f} ms")
        # a compile of this kernel takes seconds; a chunk of 60 x 10^4 steps, ~10 ms
        assert later < 0.5


def test_checkpoint_with_a_client_resumes_identically(client, tmp_path):
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 12), omega0=[0.0, 1.0])
    kw = dict(t_end=4.0, dt=0.01, observe=FORCED_OBSERVE, chunk_size=5)
    local = sweep.run(FORCED, grid, **kw)
    folder = tmp_path / "ckpt"
    first = sweep.run(FORCED, grid, client=client, checkpoint=folder, keep_checkpoint=True,
                      **kw)
    assert len(list(folder.glob("chunk-*.npz"))) == 5  # each chunk stored as it arrived
    for path in sorted(folder.glob("chunk-*.npz"))[:2]:
        path.unlink()  # as if the run had been killed before these arrived
    again = sweep.run(FORCED, grid, client=client, checkpoint=folder, resume=True, **kw)
    _same(local, first)
    _same(local, again)
    assert not folder.exists()


def test_bad_client_is_refused_before_any_compute():
    grid = sweep.Grid(theta0=[0.1])
    with pytest.raises(TypeError, match=r"client must be None or a dask\.distributed\.Client"):
        sweep.run(FORCED, grid, t_end=1.0, dt=0.01, client="tcp://127.0.0.1:8786")


def test_import_sweep_does_not_import_dask():
    code = "import sys, sweep; print('dask' in sys.modules, 'distributed' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=TIMEOUT)
    assert out.stdout.split() == ["False", "False"]


def test_streamed_to_netcdf_on_the_cluster_is_identical(client, tmp_path):
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 13), omega0=np.linspace(-2, 2, 9),
                      forcing_amplitude=[1.2, 1.5])
    kw = dict(t_end=30 * np.pi, dt=np.pi / 100, t_transient=3 * np.pi,
              observe=("final", "winding", "amplitude", "strobe"))  # strobe: 2nd dim
    local = sweep.run(FORCED, grid, **kw)
    path = run_to_netcdf(tmp_path / "big.nc", FORCED, grid, client=client, rows_per_task=2,
                         **kw)  # 7 blocks, written as they arrive
    _same(local, sweep.load(path))
    assert [p.name for p in tmp_path.iterdir()] == ["big.nc"]  # no temporary file left


def test_streamed_locally_flags_nonfinite_and_validates_first(tmp_path):
    scene = sweep.Scene(effects=(sweep.Damping(0.1),))
    grid = sweep.Grid(damping=[0.1, 1e4, 0.2], theta0=np.linspace(-1.0, 1.0, 4))
    kw = dict(t_end=2.0, dt=0.01, observe=FORCED_OBSERVE,
              check_stability=False)  # test_nonfinite_trajectories_...'s kernel
    with pytest.warns(RuntimeWarning, match=r"^4 of 12 trajectories became non-finite"):
        local = sweep.run(scene, grid, **kw)
    with pytest.warns(RuntimeWarning, match=r"^4 of 12 trajectories became non-finite"):
        path = run_to_netcdf(tmp_path / "out.nc", scene, grid, rows_per_task=1, **kw)
    _same(local, sweep.load(path))
    # the whole grid is validated before any block runs: nothing is written
    with pytest.raises(ValueError, match=r"exceeds RK4.s stability limit"):
        run_to_netcdf(tmp_path / "no.nc", scene, grid, t_end=2.0, dt=0.01)
    with pytest.raises(ValueError, match="does not take checkpoint="):
        run_to_netcdf(tmp_path / "no.nc", scene, grid, t_end=2.0, dt=0.01,
                      checkpoint=tmp_path / "c")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.nc"]


async def _die():
    os._exit(1)  # the worker process ends at once, mid-task (no cleanup)


def test_a_worker_killed_mid_run_still_gives_the_full_identical_result(client):
    # last in the file: it kills a worker (the nanny restarts it; waited for below)
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 60), omega0=np.linspace(-2, 2, 20))
    kw = dict(t_end=2000.0, dt=0.01, observe=FORCED_OBSERVE,
              chunk_size=30)  # 40 chunks of ~50 ms each
    local = sweep.run(FORCED, grid, **kw)
    pids = client.run(os.getpid)
    victim = min(pids)

    def busy_on_victim():
        return [key for key in client.processing(workers=[victim]).get(victim, ())
                if "sweep-chunk" in str(key)]

    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        began = time.monotonic()
        running = pool.submit(sweep.run, FORCED, grid, client=client, **kw)
        deadline = began + TIMEOUT
        while not busy_on_victim():
            assert time.monotonic() < deadline and not running.done(), "never started"
            time.sleep(0.05)
        time.sleep(0.3)  # a few chunks into the run
        lost = busy_on_victim()
        assert lost and not running.done()
        killed_at = time.monotonic() - began
        client.run(_die, workers=[victim], wait=False)
        remote = running.result(timeout=TIMEOUT)
        print(f"killed {victim} (processing {lost}) {killed_at:.2f} s "
              "into the run, "
              f"which then took {time.monotonic() - began:.2f} s")
    _same(local, remote)
    client.wait_for_workers(2, timeout=TIMEOUT)
    deadline = time.monotonic() + TIMEOUT
    while pids[victim] in client.run(os.getpid).values():  # the old process is gone
        assert time.monotonic() < deadline, "the worker was not killed"
        time.sleep(0.1)


def test_cluster_benchmark_runs_at_a_small_size(tmp_path):
    """The script's LocalCluster takes a free port: with 8787 held here and the
    Scheduler's warning about it an error in the script, it still starts."""
    script = os.path.join(os.path.dirname(__file__), "..", "benchmarks", "cluster.py")
    env = dict(os.environ, PYTHONWARNINGS=PORT_TAKEN_ERROR)
    with port_8787_taken():
        subprocess.run([sys.executable, script, "--size", "16", "--steps", "50",
                        "--chunk-sizes", "64,16", "--out", str(tmp_path)],
                       check=True, capture_output=True, timeout=120, env=env)
    table = (tmp_path / "cluster.md").read_text()
    assert "| Dask, chunk_size = 16 | 8 |" in table and "| NO |" not in table
    assert (tmp_path / "cluster.json").is_file()


def test_cuda_device_on_the_cluster_is_identical(client):
    """device="cuda" through Dask: each worker launches the chunk on its GPU (here
    numba's CUDA simulator, inherited from conftest's environment); the gathered dataset
    is the local GPU run's, bit for bit."""
    pytest.importorskip("numba.cuda")
    grid = sweep.Grid(theta0=np.linspace(-3.0, 3.0, 5), omega0=[0.0, 1.0])
    local, remote = _both(client, FORCED, grid, t_end=1.0, dt=0.02, device="cuda",
                          observe=("final", "amplitude"), chunk_size=4)
    _same(local, remote)
    assert remote.attrs["device"] == "cuda"
