"""The map examples run end to end at a reduced size and say what they should."""

import importlib.util
import pathlib

import matplotlib.image
import numpy as np
import pytest

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _assert_png(path):
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert matplotlib.image.imread(path).ndim == 3


def test_damped_basins(tmp_path, capsys):
    assert _load("damped_basins").main(["--size", "41", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "basins.png")
    assert (tmp_path / "basins.nc").is_file()
    assert "basin fraction per well k" in capsys.readouterr().out


def test_rotation_map(tmp_path, capsys):
    assert _load("rotation_map").main(["--size", "15", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "rotation.png")
    _assert_png(tmp_path / "amplitude.png")
    shares = capsys.readouterr().out
    assert "libration" in shares


def test_frequency_response(tmp_path, capsys):
    assert _load("frequency_response").main(["--points", "31", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "frequency_response.png")
    # the softening resonance shows hysteresis below the natural frequency 1 rad/s
    out = capsys.readouterr().out
    assert "hysteresis window: W in [0.9" in out


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__])


def test_forced_basins(tmp_path, capsys):
    # 21 x 21 starts, 320 periods and a 21 x 21 pilot (the map's own starts): conftest's
    # Wada pilot, so the kernel of its catalogue is the wada_catalogue fixture's
    assert _load("forced_basins").main(["--size", "21", "--periods", "320", "--pilot", "21",
                                        "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "forced_basins.png")
    out = capsys.readouterr().out
    assert "turns/period" in out and "boundary basin entropy" in out


def test_torque_locked_running(tmp_path, capsys):
    assert _load("torque_locked_running").main(["--size", "13", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "torque_locked_running.png")
    out = capsys.readouterr().out
    # a running start runs in more of the (torque, damping) plane than a start at rest
    # (hysteresis): between 4 c / pi and the rest start's threshold only it runs
    shares = [float(line.rsplit(" ", 1)[1]) for line in out.splitlines() if "share" in line]
    assert shares[1] > shares[0]


def test_kapitza(tmp_path, capsys):
    assert _load("kapitza").main(["--size", "9", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "kapitza.png")
    share = float(capsys.readouterr().out.split("share ")[1].split()[0])
    assert 0.2 < share < 0.95  # both sides of Kapitza's threshold are on the map


def test_mathieu_chart(tmp_path, capsys):
    assert _load("mathieu_chart").main(["--size", "11", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "mathieu_chart.png")
    share = float(capsys.readouterr().out.split("share ")[1].split(";")[0])
    assert 0.1 < share < 0.9  # the first tongue and the stable region are both on it


def test_lyapunov_map(tmp_path, capsys):
    example = _load("lyapunov_map")
    assert example.main(["--size", "11", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "lyapunov_map.png")
    assert "chaotic (lambda_max > 0.01 /s)" in capsys.readouterr().out
    # the line's exponents sum to the mean divergence -2 beta (to RK4's O(dt^4), ~1e-6
    # relative at w0 dt = 0.047), and gamma = 1.1 is chaotic (Taylor, fig. 12.12 ff.)
    line = example.taylor([1.05, 1.1])
    total = (line["lyapunov_max"] + line["lyapunov_min"]).values.ravel()
    np.testing.assert_allclose(total, -2 * example.BETA, rtol=1e-5)
    assert line["lyapunov_max"].values.ravel()[1] > 0.02  # measured 0.09 /s


def test_orbit_diagram(tmp_path, capsys):
    example = _load("orbit_diagram")
    assert example.main(["--size", "9", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "orbit_diagram.png")
    assert "periods on the map" in capsys.readouterr().out
    # every forcing frequency of the map has a whole number of steps per period
    steps = 2 * np.pi / (example.frequencies(9) * example.DT)
    np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
    # the benchmark's 400 x 400 map has 400 distinct such frequencies (a finer step;
    # with DT only 189 fit in [0.4, 1.0] rad/s, and asking for more is refused)
    dt = example.time_step(400)
    steps = 2 * np.pi / (example.frequencies(400, dt) * dt)
    assert np.unique(np.round(steps)).size == 400
    np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
    # the transient is a whole number of steps: 500 / dt is off only by rounding (~1e-11
    # steps), far below 1e-6 of a step
    assert (500.0 / dt) == pytest.approx(round(500.0 / dt), abs=1e-6)
    with pytest.raises(ValueError, match="only 189 forcing periods"):
        example.frequencies(400)


def test_continuation(tmp_path, capsys):
    assert _load("continuation").main(["--size", "5", "--out", str(tmp_path)]) == 0
    _assert_png(tmp_path / "continuation.png")
    out = capsys.readouterr().out
    assert "attractor 0 (period 1): A from 0.020" in out


def _forced_run_files():
    """The shipped run files (examples/*.toml) whose scene has a forcing."""
    from sweep.toml_spec import load_run

    return [path for path in sorted(EXAMPLES.glob("*.toml"))
            if getattr(load_run(path, {})[0], "forcing", None) is not None]


def test_the_forced_run_files_are_found():
    assert [p.name for p in _forced_run_files()] == ["forced.toml", "points.toml",
                                                     "wada_map.toml", "wada_sample.toml"]


@pytest.mark.parametrize("path", _forced_run_files(), ids=lambda p: p.name)
def test_each_forced_run_file_fits_the_basins_map(path):
    """A forced scene's own map is its basins, from stroboscopic samples: the step must
    divide the forcing period and the run must hold the samples after the transient.
    The explorer opens a grid run file on that map without falling back to motion (its
    check is sweep.run's own, made before anything is computed; examples/forced.toml's
    dt = 0.01 did not divide 3 pi), and its settings, run at one start with the strobe
    observable, fill every sample and give an attractor label."""
    import warnings

    import sweep
    from sweep import maps
    from sweep.explore.model import Explorer
    from sweep.toml_spec import load_run

    scene, rows, kwargs = load_run(path, {})
    if isinstance(rows, sweep.Grid):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a fallback to the motion map warns
            explorer = Explorer(scene, rows, resolution=8, **kwargs)
        assert explorer.state.quantity == "basins"
    timing = {k: v for k, v in kwargs.items()
              if k in ("t0", "t_end", "dt", "t_transient", "method", "strobe_samples")}
    ds = sweep.run(scene, sweep.Grid(theta0=[0.5], omega0=[0.5]), observe=("strobe",),
                   progress=False, **timing)
    assert np.isfinite(ds.strobe_theta).all() and np.isfinite(ds.strobe_omega).all()
    assert (maps.basins(ds) >= 0).all()
