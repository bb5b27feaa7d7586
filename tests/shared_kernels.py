"""Observable sets that many tests share, so that they share compiled kernels.

Every distinct `sweep.kernels.KernelSpec` (model, effects, observables, method, block,
saving, dtype, ...) is a kernel numba compiles, about a second each from an empty cache;
a cold run of the suite is mostly that. A test whose subject is not *which* observables
are computed runs one of these sets, so that the tests of the same scene and grid size
compile one kernel between them (memoised in a worker process, loaded from numba's disk
cache by the others). ``SWEEP_COMPILE_LOG`` (tests/compile_log.py) shows what each test
compiles.

Adding observables never changes a trajectory (only ``stop_early`` reads them), so a
test that runs more of them than it checks checks the same thing.

`sweep.run` picks the block from the number of trajectories (`sweep.engine._block`):
one lane for fewer than 4, 16 lanes up to 127, 64 up to 2047, 128 above; tests that
share a kernel also share that size class.
"""

import numpy as np

import sweep

#: Every observable of a fixed-step run without a forcing period to sample: the set of
#: tests/test_naive.py (each one against the pure-Python reference), and of the tests
#: that need "all of them" or any set at all (test_engine, test_oracles,
#: test_physics_effects, test_methods, test_blocks).
EVERY = ("final", "winding", "theta_max", "amplitude", "omega_mean", "tension", "energy",
         "top_distance")

#: Every observable the adaptive dopri5 takes (`omega_mean` needs a fixed step).
EVERY_ADAPTIVE = ("final", "winding", "theta_max", "amplitude", "tension", "energy",
                  "top_distance")


#: The forced Wada map (c = 0.2, A = 1.66, W = 1, cos forcing, g/L = 1; three attractors),
#: its 21 x 21 pilot and the strict early stop: tests/test_attractor_catalogue.py's SCENE,
#: _grid(21) and EARLY (its test_pilot_catalogue_thins_the_map_and_finds_its_attractors
#: checks that its own pilot gives these bits).
WADA_SCENE = sweep.Scene(gravity=1.0, length=1.0, effects=(
    sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
WADA_PILOT = dict(t_end=320 * 2 * np.pi, dt=2 * np.pi / 100, t_transient=20 * 2 * np.pi,
                  observe=("strobe",), stop_early=True, progress=False)

#: The Wada scene and `WADA_PILOT`'s settings as a run file over an n x n grid of
#: theta0 in [-pi, pi] and omega0 in [-4, 4] (``{n}``), with ``{extra}`` lines of
#: ``[run]`` (``pilot = 21``: the ``wada_catalogue`` fixture's pilot, so its kernels).
WADA_RUN_FILE = """
[scene]
gravity = 1.0
length = 1.0
[scene.damping]
coefficient = 0.2
[scene.forcing]
amplitude = 1.66
frequency = 1.0
phase = 1.5707963267948966
[grid]
theta0 = {{ start = -3.141592653589793, stop = 3.141592653589793, num = {n} }}
omega0 = {{ start = -4.0, stop = 4.0, num = {n} }}
[run]
t_end = 2010.6192982974676
dt = 0.06283185307179587
t_transient = 125.66370614359172
observe = ["strobe"]
stop_early = true
{extra}
"""
