"""Bad input gets a clear error before any compute: it names the parameter, the bad
value and what would be accepted."""

import numpy as np
import pytest

import sweep
from sweep import engine

GOOD_GRID = dict(theta0=[0.1, 0.2])
GOOD_RUN = dict(t_end=1.0, dt=0.1)


def _run(scene=None, grid=None, **kwargs):
    return sweep.run(scene or sweep.Scene(), sweep.Grid(**(grid or GOOD_GRID)),
                     **{**GOOD_RUN, **kwargs})


# (label, callable, exception, regex the message must match)
CASES = [
    # scene
    ("zero length", lambda: sweep.Scene(length=0.0), ValueError,
     r"length must be a finite number > 0 \(m\), got 0\.0"),
    ("negative length", lambda: sweep.Scene(length=-1.0), ValueError,
     r"length must be a finite number > 0 \(m\), got -1\.0"),
    ("nan gravity", lambda: sweep.Scene(gravity=float("nan")), ValueError,
     r"gravity must be a finite number > 0 \(m/s\^2\), got nan"),
    ("zero gravity", lambda: sweep.Scene(gravity=0), ValueError, r"gravity .* got 0\.0"),
    ("string length", lambda: sweep.Scene(length="1"), TypeError,
     r"length must be a finite number > 0 \(m\), got '1' \(str\)"),
    ("bool gravity", lambda: sweep.Scene(gravity=True), TypeError, r"gravity .* got True"),
    ("unknown model", lambda: sweep.Scene(model="quadratic"), ValueError,
     r"model must be one of 'nonlinear', 'linear', got 'quadratic'"),
    ("not an effect", lambda: sweep.Scene(effects=("damping",)), TypeError,
     r"effects: 'damping' is not an effect; accepted: sweep\.Damping"),
    ("effect twice", lambda: sweep.Scene(effects=(sweep.Damping(1), sweep.Damping(2))),
     ValueError, r"effects: Damping given twice; accepted: at most one of each"),
    ("negative damping", lambda: sweep.Damping(-0.1), ValueError,
     r"Damping\.coefficient must be a finite number >= 0 \(1/s\), got -0\.1"),
    ("inf forcing amplitude", lambda: sweep.Forcing(float("inf"), 1.0), ValueError,
     r"Forcing\.amplitude must be a finite number, got inf"),
    ("negative forcing frequency", lambda: sweep.Forcing(1.0, -2.0), ValueError,
     r"Forcing\.frequency must be a finite number >= 0 \(rad/s\), got -2\.0"),
    ("scene from dict, unknown key", lambda: sweep.Scene.from_dict({"lenght": 1}),
     ValueError, r"scene: unknown key\(s\) 'lenght'; accepted: gravity, length"),
    # grid
    ("no axes", lambda: sweep.Grid(), ValueError, r"Grid needs at least one axis; accepted"),
    ("unknown axis", lambda: sweep.Grid(gama=[1.0]), ValueError,
     r"unknown grid axis 'gama'; accepted axis names: theta0, omega0, length, gravity, damping"),
    ("empty axis", lambda: sweep.Grid(theta0=[]), ValueError,
     r"grid axis 'theta0' is empty; accepted: at least one value"),
    ("nan in axis", lambda: sweep.Grid(omega0=[0.0, np.nan]), ValueError,
     r"grid axis 'omega0' has non-finite value nan at index 1; accepted: finite"),
    ("inf in axis", lambda: sweep.Grid(theta0=[np.inf]), ValueError,
     r"grid axis 'theta0' has non-finite value inf at index 0"),
    ("2-D axis", lambda: sweep.Grid(theta0=np.zeros((2, 3))), ValueError,
     r"grid axis 'theta0' must be 1-D, got an array of shape \(2, 3\)"),
    ("string axis", lambda: sweep.Grid(theta0="0 to 1"), ValueError,
     r"grid axis 'theta0' must be a 1-D array of numbers, got '0 to 1'"),
    ("non-numeric axis", lambda: sweep.Grid(theta0=["a", "b"]), ValueError,
     r"grid axis 'theta0' must be a 1-D array of numbers"),
    ("zero length axis", lambda: sweep.Grid(length=[1.0, 0.0]), ValueError,
     r"grid axis 'length' has value 0\.0 at index 1; accepted: finite numbers > 0 \(m\)"),
    ("negative damping axis", lambda: sweep.Grid(damping=[-1.0]), ValueError,
     r"grid axis 'damping' has value -1\.0 at index 0; accepted: finite numbers >= 0"),
    ("forcing axis without forcing", lambda: _run(grid=dict(forcing_amplitude=[1.0])),
     ValueError, r"grid axis 'forcing_amplitude' needs a forcing in the scene"),
    # run
    ("zero dt", lambda: _run(dt=0.0), ValueError,
     r"dt must be a finite number > 0 \(s\), got 0\.0"),
    ("negative dt", lambda: _run(dt=-0.1), ValueError, r"dt must be .* got -0\.1"),
    ("nan dt", lambda: _run(dt=float("nan")), ValueError, r"dt must be .* got nan"),
    ("string dt", lambda: _run(dt="0.1"), TypeError, r"dt must be .* got '0\.1' \(str\)"),
    ("t_end before t0", lambda: _run(t0=2.0), ValueError,
     r"t_end must be > t0 = 2\.0, got t_end = 1\.0"),
    ("t_end equals t0", lambda: _run(t0=1.0), ValueError, r"t_end must be > t0 = 1\.0"),
    ("inf t_end", lambda: _run(t_end=float("inf")), ValueError, r"t_end must be .* got inf"),
    ("transient too long", lambda: _run(t_transient=1.0), ValueError,
     r"t_transient must be < t_end - t0 = 1\.0 .* got t_transient = 1\.0"),
    ("transient leaves no step", lambda: _run(t_transient=0.99), ValueError,
     r"t_transient = 0\.99 leaves no step to observe before t_end - t0 = 1\.0"),
    ("negative transient", lambda: _run(t_transient=-1.0), ValueError,
     r"t_transient must be a finite number >= 0 \(s\), got -1\.0"),
    ("span not whole steps", lambda: _run(dt=0.3), ValueError,
     r"t_end - t0 = 1\.0 is not a whole number of steps dt = 0\.3 .*accepted: a dt that"),
    ("unknown observable", lambda: _run(observe=("final", "energie")), ValueError,
     r"unknown observable 'energie' in observe; accepted: final, winding, theta_max"),
    ("observe not a sequence", lambda: _run(observe=3), ValueError,
     r"observe must be a sequence of names"),
    ("nothing observed", lambda: _run(observe=()), ValueError,
     r"observe is empty and save_every is None -- nothing would be computed"),
    ("zero save_every", lambda: _run(save_every=0), ValueError,
     r"save_every must be None or an int >= 1 \(steps\), got 0"),
    ("float save_every", lambda: _run(save_every=2.5), TypeError,
     r"save_every must be None or an int >= 1 \(steps\), got 2\.5"),
    ("save_every exhausting memory",
     lambda: _run(grid=dict(theta0=np.zeros(50_000), omega0=np.zeros(50_000)),
                  t_end=10.0, dt=0.1, save_every=1),
     ValueError, r"save_every = 1 with 2500000000 trajectories needs .* GiB but only"),
    ("unknown method", lambda: _run(method="rk5"), ValueError,
     r"method must be one of 'euler', 'heun', 'rk4', .*, got 'rk5'"),
    ("bad chunk size", lambda: _run(chunk_size=0), ValueError,
     r"chunk_size must be an int >= 1, got 0"),
    ("scene not a Scene", lambda: sweep.run({"length": 1}, sweep.Grid(theta0=[0.0]),
                                            **GOOD_RUN), TypeError,
     r"scene must be a sweep\.Scene"),
    # stability guard (sweep.stability): RK4 needs dt |lambda| <= 2.785 on the real axis
    ("stiff damping beyond RK4's limit",
     lambda: _run(scene=sweep.Scene(effects=(sweep.Damping(100.0),)), t_end=1.0, dt=0.05),
     ValueError, (r"dt = 0\.05 exceeds RK4's stability limit 0\.0279 s for this scene "
                  r"\(damping c = 100 1/s, g/L = 9\.81 1/s\^2: eigenvalue -99\.9\); "
                  r"accepted: dt <= 0\.0278")),
    ("stiff damping axis beyond RK4's limit",
     lambda: _run(grid=dict(theta0=[0.1], damping=[0.0, 1e3]), t_end=1.0, dt=0.01),
     ValueError, r"dt = 0\.01 exceeds RK4's stability limit 0\.00279 s .*damping c = 1000"),
    ("fast oscillation beyond RK4's imaginary-axis limit",
     lambda: _run(scene=sweep.Scene(length=0.01), t_end=1.0, dt=0.1), ValueError,
     (r"dt = 0\.1 exceeds RK4's stability limit 0\.0903 s .*undamped, g/L = 981 1/s\^2: "
      r"eigenvalue \+-31\.32i\); accepted: dt <= 0\.0903")),
    ("short length axis beyond Verlet's limit",
     lambda: _run(grid=dict(theta0=[0.1], length=[1.0, 1e-3]), t_end=1.0, dt=0.1,
                  method="verlet"), ValueError,
     r"dt = 0\.1 exceeds Verlet's stability limit 0\.0202 s"),
    ("Euler on a damped scene beyond its disk",
     lambda: _run(scene=sweep.Scene(effects=(sweep.Damping(0.1),)), t_end=1.0, dt=0.05,
                  method="euler"), ValueError,
     r"dt = 0\.05 exceeds Euler's stability limit 0\.0102 s .*eigenvalue -0\.05 \+-3\.132i"),
    ("check_stability not a bool", lambda: _run(check_stability="no"), TypeError,
     r"check_stability must be True or False, got 'no'"),
    ("grid not a Grid", lambda: sweep.run(sweep.Scene(), {"theta0": [0.0]}, **GOOD_RUN),
     TypeError, r"grid must be a sweep\.Grid"),
]


@pytest.fixture
def no_compute(monkeypatch):
    """Fail loudly if a kernel is built or run: every error comes before compute."""

    def forbidden(*args, **kwargs):
        raise AssertionError("compute started before the input was validated")

    monkeypatch.setattr(engine, "build", forbidden)


@pytest.mark.parametrize("label,call,exception,message", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_refused_clearly_before_compute(label, call, exception, message,
                                                     no_compute):
    with pytest.raises(exception, match=message):
        call()


def test_battery_is_large_enough():
    assert len(CASES) >= 30


def test_degrees_helper_and_a_scalar_axis():
    grid = sweep.Grid(theta0=sweep.from_degrees([-10.0, 180.0]), omega0=3.0)
    np.testing.assert_allclose(grid.axes["theta0"], [-np.pi / 18, np.pi], rtol=1e-15)
    assert grid.shape == (2, 1)
