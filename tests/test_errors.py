"""Bad input gets a clear error before any compute: it names the parameter, the bad
value and what would be accepted."""

import numpy as np
import pytest

import sweep

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
     r"grid axis 'theta0' has 'a' \(str\) at index 0; accepted: real numbers"),
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
     lambda: _run(grid=dict(theta0=np.linspace(0, 1, 50_000),
                            omega0=np.linspace(0, 1, 50_000)),
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
    # values that would convert silently into numbers nobody meant (issue 15)
    ("bool axis", lambda: sweep.Grid(theta0=[True, False]), ValueError,
     r"grid axis 'theta0' holds booleans .*accepted: real numbers"),
    ("numpy bool axis", lambda: sweep.Grid(omega0=np.array([True, False])), ValueError,
     r"grid axis 'omega0' holds booleans"),
    ("bool scalar axis", lambda: sweep.Grid(damping=True), ValueError,
     r"grid axis 'damping' holds booleans"),
    ("bool among floats", lambda: sweep.Grid(theta0=[0.5, True]), ValueError,
     r"grid axis 'theta0' has True \(bool\) at index 1; accepted: real numbers"),
    ("numpy bool among floats", lambda: sweep.Grid(theta0=[0.5, np.True_]), ValueError,
     r"grid axis 'theta0' has np\.True_ \(bool\) at index 1"),
    ("repeated axis value", lambda: sweep.Grid(theta0=[0.1, 0.2, 0.1]), ValueError,
     r"grid axis 'theta0' has the value 0\.1 more than once \(indices 0, 2\).*accepted: "
     r"distinct values"),
    ("repeated zero, signed", lambda: sweep.Grid(omega0=[0.0, 1.0, -0.0]), ValueError,
     r"grid axis 'omega0' has the value 0\.0 more than once \(indices 0, 2\)"),
    ("repeated values of a range", lambda: sweep.Grid(damping=np.linspace(0.5, 0.5, 3)),
     ValueError, r"grid axis 'damping' has the value 0\.5 more than once \(indices 0, 1, 2\)"),
    ("numeric string in axis", lambda: sweep.Grid(theta0=["1.0", 2.0]), ValueError,
     r"grid axis 'theta0' has '1\.0' \(str\) at index 0; accepted: real numbers"),
    ("numeric strings array", lambda: sweep.Grid(theta0=np.array(["1", "2"])), ValueError,
     r"grid axis 'theta0' has '1' \(str\) at index 0"),
    ("bytes in axis", lambda: sweep.Grid(theta0=[b"1"]), ValueError,
     r"grid axis 'theta0' has b'1' \(bytes\) at index 0"),
    ("None in axis", lambda: sweep.Grid(theta0=[0.0, None]), ValueError,
     r"grid axis 'theta0' has None \(NoneType\) at index 1"),
    ("None axis", lambda: sweep.Grid(theta0=None), ValueError,
     r"grid axis 'theta0' must be a number or a 1-D array of numbers, got None"),
    ("complex axis", lambda: sweep.Grid(theta0=[1 + 0j]), ValueError,
     r"grid axis 'theta0' has \(1\+0j\) \(complex\) at index 0"),
    ("datetime axis", lambda: sweep.Grid(theta0=np.array(["2020-01-01"], "datetime64[D]")),
     ValueError, r"grid axis 'theta0' has datetime\.date\(2020, 1, 1\) \(date\) at index 0"),
    ("masked value in axis", lambda: sweep.Grid(theta0=np.ma.masked_array([1.0, 2.0],
                                                                            [False, True])),
     ValueError, r"grid axis 'theta0' has a masked value at flat index 1"),
    ("int beyond float range", lambda: sweep.Grid(theta0=[10**400]), ValueError,
     r"grid axis 'theta0' has 1000.*\(int\) at index 0, beyond the float range"),
    ("set as axis", lambda: sweep.Grid(theta0={0.1, 0.2}), ValueError,
     r"grid axis 'theta0' must be a number or a 1-D array of numbers, got \{"),
    ("degrees from strings", lambda: sweep.from_degrees(["10"]), ValueError,
     r"from_degrees: values has '10' \(str\) at index 0"),
    ("degrees from booleans", lambda: sweep.from_degrees([True]), ValueError,
     r"from_degrees: values holds booleans"),
    ("numpy bool length", lambda: sweep.Scene(length=np.True_), TypeError,
     r"length must be a finite number > 0 \(m\), got np\.True_ \(bool\)"),
    ("complex gravity", lambda: sweep.Scene(gravity=9.81 + 0j), TypeError,
     r"gravity must be .* got \(9\.81\+0j\) \(complex\)"),
    ("0-d array length", lambda: sweep.Scene(length=np.array(1.0)), TypeError,
     r"length must be .* got array\(1\.\) \(ndarray\)"),
    ("int beyond float range length", lambda: sweep.Scene(length=10**400), ValueError,
     r"length must be a finite number > 0 \(m\), got 1000.* \(beyond the float range\)"),
    ("bool damping", lambda: sweep.Damping(True), TypeError,
     r"Damping\.coefficient must be .* got True \(bool\)"),
    ("string forcing phase", lambda: sweep.Forcing(1.0, 1.0, "0"), TypeError,
     r"Forcing\.phase must be a finite number, got '0' \(str\)"),
    ("model in capitals", lambda: sweep.Scene(model="Linear"), ValueError,
     r"model must be one of 'nonlinear', 'linear', got 'Linear'"),
    ("method in capitals", lambda: _run(method="RK4"), ValueError,
     r"method must be one of .*got 'RK4'"),
    ("bool dt", lambda: _run(dt=True), TypeError, r"dt must be .* got True \(bool\)"),
    ("numpy bool t_end", lambda: _run(t_end=np.True_), TypeError,
     r"t_end must be a finite number, got np\.True_ \(bool\)"),
    ("list dt", lambda: _run(dt=[0.1]), TypeError, r"dt must be .* got \[0\.1\] \(list\)"),
    ("observe as one comma string", lambda: _run(observe="final,winding"), ValueError,
     r"observe = 'final,winding' is one string; accepted: a name or a sequence of names, "
     r"e\.g\. \['final', 'winding'\]"),
    ("observe as a mapping", lambda: _run(observe={"final": True}), ValueError,
     r"observe must be a sequence of names .*got \{'final': True\}"),
    ("bool save_every", lambda: _run(save_every=True), TypeError,
     r"save_every must be None or an int >= 1 \(steps\), got True"),
    ("bool chunk size", lambda: _run(chunk_size=True), ValueError,
     r"chunk_size must be an int >= 1, got True"),
    ("bool estimate_error", lambda: _run(estimate_error=True), ValueError,
     r"estimate_error must be None or an int >= 1 \(trajectories\), got True"),
    ("stop_early as a number", lambda: _run(stop_early=0), TypeError,
     r"stop_early must be True or False, got 0"),
    ("progress as a string", lambda: _run(progress="no"), TypeError,
     r"progress must be True, False or None, got 'no'"),
    ("specialize as a string", lambda: _run(specialize="no"), TypeError,
     r"specialize must be True or False, got 'no'"),
    ("keep_checkpoint as a number", lambda: _run(keep_checkpoint=1), TypeError,
     r"keep_checkpoint must be True or False, got 1"),
    ("resume as a string", lambda: _run(resume="yes"), TypeError,
     r"resume must be True or False, got 'yes'"),
    ("booleans as convergence steps",
     lambda: sweep.accuracy.convergence(sweep.Scene(), [0.1], [0.0], 1.0, "rk4",
                                        [True, 0.1]),
     ValueError, r"dts has True \(bool\) at index 0; accepted: real numbers"),
    ("repeated response frequency",
     lambda: sweep.response.frequency_response(
         sweep.Scene(effects=(sweep.Forcing(1.0, 1.0),)), [0.5, 0.5]),
     ValueError, r"'frequencies' has the value 0\.5 more than once \(indices 0, 1\)"),
]


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


def test_accepted_numbers_mean_what_they_say():
    """Ints, NumPy floats of any width, 0-d arrays and xarray coordinates are numbers:
    accepted as the same float64 values."""
    import xarray as xr

    grid = sweep.Grid(theta0=[1, 2], omega0=np.float32([0.5]), damping=np.array(0.25),
                      length=xr.DataArray([1.0, 2.0]))
    assert grid.axes["theta0"].tolist() == [1.0, 2.0]
    assert grid.axes["omega0"].tolist() == [0.5]  # 0.5 is exact in float32
    assert grid.axes["damping"].tolist() == [0.25]
    assert grid.axes["length"].tolist() == [1.0, 2.0]
    assert sweep.Scene(length=np.float32(2.0), gravity=10).length == 2.0


def test_an_unsorted_axis_keeps_the_order_given():
    """An axis need not be sorted: row i of the dataset is the i-th value given, each
    result equals the run of that value alone (bit-identical: every trajectory is
    computed independently, the same operations in the same order), and ``.sel`` finds
    values by label."""
    values = [0.3, -1.0, 2.0, 0.1]
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=values), t_end=1.0, dt=0.01,
                   observe=("final",), progress=False)
    assert ds.theta0.values.tolist() == values
    for value in values:
        alone = sweep.run(sweep.Scene(), sweep.Grid(theta0=[value]), t_end=1.0, dt=0.01,
                          observe=("final",), progress=False)
        assert ds.theta_final.sel(theta0=value).item() == alone.theta_final.item()
    # sorting the dataset afterwards is the user's choice and works as usual
    assert ds.sortby("theta0").theta0.values.tolist() == sorted(values)
