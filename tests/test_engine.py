"""Engine behaviour: specialisation, invariance to how the work is cut, per-trajectory
failure, the time convention, and the shape of the returned dataset."""

import itertools
import os
import subprocess
import sys
import textwrap
import warnings

import numba
import numpy as np
import pytest
from shared_kernels import EVERY

import sweep
from sweep import kernels as _kernels
from sweep.kernels import KernelSpec, Status

ALL_OBSERVE = EVERY  # the kernels of test_naive's runs (tests/shared_kernels.py)


def _scene(model, damping, forcing):
    effects = []
    if damping:
        effects.append(sweep.Damping(0.3))
    if forcing:
        effects.append(sweep.Forcing(amplitude=1.1, frequency=0.9, phase=0.4))
    return sweep.Scene(model=model, effects=tuple(effects))


COMBINATIONS = list(itertools.product(("nonlinear", "linear"), (False, True), (False, True)))


@pytest.fixture(scope="module")
def small_grid():
    return sweep.Grid(theta0=np.linspace(-3.0, 3.0, 5), omega0=np.linspace(-6.0, 6.0, 4))


# --------------------------------------------------------------------- specialisation
@pytest.mark.parametrize("model,damping,forcing", COMBINATIONS)
def test_specialised_kernel_equals_general_kernel_fed_zeros(model, damping, forcing,
                                                            small_grid):
    scene = _scene(model, damping, forcing)
    kwargs = dict(t_end=5.0, dt=0.01, t_transient=1.0, observe=ALL_OBSERVE)
    special = sweep.run(scene, small_grid, **kwargs)
    general = sweep.run(scene, small_grid, specialize=False, **kwargs)
    assert general.attrs["effects"] == " ".join(sweep.physics.EFFECTS)  # every term, fed zeros
    for name in special.data_vars:
        # Adding the general path's absent terms (- 0.0 * omega, + 0.0 * sin(...)) is
        # exact in IEEE arithmetic, and the kernels fuse only the multiply-adds they
        # write (vfma, in the same places in both; sweep._config.FASTMATH lets LLVM fuse
        # nothing else): the same bits. (Until 2026-11-25 LLVM chose which products to
        # fuse, and a term fewer could change its choice: up to 2.2e-13 here.)
        np.testing.assert_array_equal(special[name].values, general[name].values,
                                      err_msg=name)


def test_each_effect_set_gets_its_own_kernel_without_absent_terms():
    specs = [KernelSpec(m, ("damping",) * d + ("forcing",) * f, ("final",))
             for m, d, f in COMBINATIONS]
    kernels = [_kernels.build(s) for s in specs]
    assert len({id(k) for k in kernels}) == len(specs)  # one compiled kernel per effect set
    assert _kernels.build(specs[0]) is kernels[0]  # memoised
    for spec in specs:
        text = _kernels.source(spec)
        assert ("vsin(th)" in text) == (spec.model == "nonlinear")
        assert ("vsin(W" in text) == ("forcing" in spec.names)
        assert ("c * om" in text) == ("damping" in spec.names)
        # only the requested observables are accumulated
        assert "acc_" not in text and "tension" not in text


def test_compiled_kernels_have_the_scene_terms_only_and_vectorised_lanes(tmp_path):
    """The machine code, not just the source: no sine at all in the linear unforced
    kernel; in the nonlinear one, sweep.kernels.vecmath's inlined polynomial sine (its
    argument-reduction constant 1/pi), no call to libm's sin, and SIMD vectors.

    numba cannot inspect code loaded from its disk cache, so this compiles afresh in a
    subprocess with an empty cache folder.
    """
    script = textwrap.dedent("""
        import re, struct, sweep
        from sweep import kernels as _kernels
        from sweep.kernels import vecmath as _vecmath
        inv_pi = "0x" + struct.pack(">d", _vecmath.INV_PI).hex().upper()
        for model in ("linear", "nonlinear"):
            sweep.run(sweep.Scene(model=model), sweep.Grid(theta0=[0.1 * k for k in range(1, 11)]),
                      t_end=1.0, dt=0.1, observe=("final",))
            # the spec sweep.run compiled (a ten-trajectory grid runs in a block of 16)
            kernel = _kernels.build(_kernels.KernelSpec(model, (), ("final",),
                                                        block=sweep.engine._block(10, False)))
            ir = "".join(_kernels.compiled(kernel).inspect_llvm().values())
            assert ir, "not compiled in this process"
            print(model, re.search(r"@(llvm\\.sin\\.[fv]|sin)\\(", ir) is not None,
                  inv_pi in ir, re.search(r"<\\d+ x double>", ir) is not None)
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, check=True)
    assert result.stdout.split() == ["linear", "False", "False", "True",
                                     "nonlinear", "False", "True", "True"]


def test_grid_damping_axis_switches_damping_on():
    scene = sweep.Scene()
    # every observable (tests/shared_kernels.py): test_points' kernel of this scene
    ds = sweep.run(scene, sweep.Grid(damping=[0.0, 2.0], theta0=[1.0]), t_end=5.0, dt=0.01,
                   observe=EVERY)
    assert ds.attrs["effects"] == "damping"
    energy_lost = ds.energy_initial - ds.energy_final
    # undamped RK4 at dt = 0.01 conserves energy to ~1e-9; c = 2 dissipates most of it
    assert abs(float(energy_lost.sel(damping=0.0).item())) < 1e-7
    assert float(energy_lost.sel(damping=2.0).item()) > 0.9 * float(ds.energy_initial[0, 0])


def test_unknown_method_lists_choices():
    with pytest.raises(ValueError,
                       match=r"method must be one of 'euler', 'heun', 'rk4', .*, got 'euler2'"):
        _kernels.source(KernelSpec("linear", (), ("final",), method="euler2"))


# --------------------------------------------------------------------- invariance
@pytest.fixture(scope="module")
def chaotic_setup():
    scene = sweep.Scene(effects=(sweep.Damping(0.5), sweep.Forcing(1.2, 2 / 3)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 13), omega0=np.linspace(-2, 2, 11),
                      forcing_amplitude=[1.2, 1.5])
    kwargs = dict(t_end=30.0, dt=0.01, t_transient=10.0, observe=ALL_OBSERVE)
    return scene, grid, kwargs


def test_results_do_not_depend_on_chunk_size(chaotic_setup):
    scene, grid, kwargs = chaotic_setup
    whole = sweep.run(scene, grid, **kwargs)
    for chunk_size in (1, 7, 100):
        cut = sweep.run(scene, grid, chunk_size=chunk_size, **kwargs)
        # bit-identical: each trajectory runs the same instructions whatever the chunk
        assert cut.drop_attrs().identical(whole.drop_attrs())


def test_results_do_not_depend_on_thread_count(chaotic_setup):
    scene, grid, kwargs = chaotic_setup
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = sweep.run(scene, grid, **kwargs)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = sweep.run(scene, grid, **kwargs)
    finally:
        numba.set_num_threads(before)
    assert one.drop_attrs().identical(many.drop_attrs())


def test_grid_sweep_equals_each_point_alone(chaotic_setup):
    scene, grid, kwargs = chaotic_setup
    whole = sweep.run(scene, grid, **kwargs)
    for i, j, k in [(0, 0, 0), (6, 7, 1), (12, 10, 1)]:
        point = whole.isel(theta0=[i], omega0=[j], forcing_amplitude=[k])
        alone = sweep.run(scene, sweep.Grid(theta0=point.theta0.values,
                                            omega0=point.omega0.values,
                                            forcing_amplitude=point.forcing_amplitude.values),
                          **kwargs)
        assert alone.drop_attrs().identical(point.drop_attrs())


# --------------------------------------------------------------------- failure
def test_overflowing_trajectories_are_flagged_and_neighbours_untouched():
    # RK4 is unstable for c * dt > 2.785 (real-axis limit), so c = 1e4, dt = 0.01
    # grows by ~|R(-100)| = 3.8e6 per step and overflows within a few dozen steps.
    scene = sweep.Scene(effects=(sweep.Damping(0.1),))
    theta0 = np.linspace(-1.0, 1.0, 4)  # no 0: the rest state stays exactly at rest
    clean = sweep.run(scene, sweep.Grid(theta0=theta0, damping=[0.1, 0.2]), t_end=2.0,
                      dt=0.01, observe=ALL_OBSERVE)
    with pytest.warns(RuntimeWarning, match=r"^4 of 12 trajectories became non-finite"):
        mixed = sweep.run(scene, sweep.Grid(theta0=theta0, damping=[0.1, 1e4, 0.2]),
                          t_end=2.0, dt=0.01, observe=ALL_OBSERVE,
                          check_stability=False)  # unstable on purpose
    bad = mixed.sel(damping=1e4)
    assert (bad.status == Status.NONFINITE).all()
    for name in ("theta_final", "omega_final", "winding", "amplitude", "energy_final"):
        assert np.isnan(bad[name]).all(), name  # never silently kept as a number
    good = mixed.sel(damping=[0.1, 0.2])
    assert (good.status == Status.OK).all()
    assert good.drop_attrs().identical(clean.drop_attrs())


def test_saved_samples_after_failure_are_nan():
    scene = sweep.Scene(effects=(sweep.Damping(1e4),))
    with pytest.warns(RuntimeWarning):
        ds = sweep.run(scene, sweep.Grid(theta0=[1.0]), t_end=1.0, dt=0.01,
                       observe=ALL_OBSERVE, save_every=10,  # (test_oracles' kernel)
                       check_stability=False)  # unstable on purpose
    theta = ds.theta.values[0]
    assert theta[0] == 1.0 and np.isnan(theta[-1])
    assert np.isnan(theta[np.argmax(np.isnan(theta)):]).all()


def test_no_warning_when_all_ok(small_grid):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sweep.run(sweep.Scene(), small_grid, t_end=1.0, dt=0.01)


# --------------------------------------------------------------------- time
def test_time_is_t0_plus_n_dt_not_an_accumulated_sum():
    """A shift of t0 is the same as a shift of the forcing phase.

    If time were accumulated (t += dt), after 1e5 steps from t0 = 1e4 it would carry
    ~1e5 rounding errors of size ulp(1e4) ~ 2e-12 each, far from the closed form below.
    """
    amplitude, frequency, t0 = 0.8, 1.3, 1.0e4
    kwargs = dict(dt=0.01, observe=ALL_OBSERVE, save_every=10_000)  # test_oracles' kernel
    shifted = sweep.run(sweep.Scene(effects=(sweep.Forcing(amplitude, frequency, 0.2),)),
                        sweep.Grid(theta0=[0.3]), t0=t0, t_end=t0 + 1000.0, **kwargs)
    phase = (0.2 + frequency * t0) % (2 * np.pi)
    origin = sweep.run(sweep.Scene(effects=(sweep.Forcing(amplitude, frequency, phase),)),
                       sweep.Grid(theta0=[0.3]), t0=0.0, t_end=1000.0, **kwargs)
    np.testing.assert_allclose(shifted.time.values - t0, origin.time.values, rtol=0,
                               atol=1e-9)  # times t0 + n dt: exact up to ulp(1e4)
    # The forcing phase at step n differs by at most ulp(W t) ~ 2e-12 rad between the
    # runs (W * (t0 + n dt) vs W * n dt + W t0 mod 2 pi); over 1e5 steps on this chaotic
    # scene such differences stay far below 1e-6 rad (measured growth is modest here:
    # no damping, small forcing, libration).
    np.testing.assert_allclose(shifted.theta_final, origin.theta_final, rtol=0, atol=1e-6)


def test_transient_boundary_and_steps():
    ds = sweep.run(sweep.Scene(), sweep.Grid(theta0=[0.5]), t_end=300.0, dt=0.01,
                   t_transient=200.0, observe=EVERY)  # a kernel other tests compile
    assert ds.attrs["n_steps"] == 30_000
    # small-amplitude libration from rest keeps its amplitude: |theta| <= theta0
    assert abs(float(ds.amplitude[0]) - 0.5) < 1e-6


# --------------------------------------------------------------------- dataset
def test_dataset_layout_units_and_provenance(small_grid):
    scene = sweep.Scene(effects=(sweep.Damping(0.2),))
    ds = sweep.run(scene, small_grid, t_end=2.0, dt=0.01, observe=("final", "tension"),
                   save_every=50)
    assert tuple(ds.theta_final.dims) == ("theta0", "omega0")
    assert tuple(ds.theta.dims) == ("theta0", "omega0", "time")
    assert set(ds.data_vars) == {"theta_final", "omega_final", "tension_min", "tension_max",
                                 "status", "theta", "omega"}
    np.testing.assert_allclose(ds.time, [0.0, 0.5, 1.0, 1.5, 2.0])
    assert ds.theta0.attrs["units"] == "rad" and ds.omega0.attrs["units"] == "rad s-1"
    assert "long_name" in ds.theta0.attrs
    assert ds.status.attrs["flag_meanings"] == "ok nonfinite step_underflow angle_out_of_range"
    np.testing.assert_array_equal(ds.status.attrs["flag_values"], [0, 1, 2, 3])
    assert ds.attrs["effects"] == "damping" and ds.attrs["damping"] == 0.2
    assert "forcing_amplitude" not in ds.attrs  # no forcing was simulated
    # a file alone says how it was made: rebuild and rerun
    grid = sweep.Grid(**{d: ds[d].values for d in ds.attrs["grid_axes"].split()})
    again = sweep.run(sweep.io.scene_from(ds), grid, **sweep.io.run_arguments(ds))
    assert again.drop_attrs().identical(ds.drop_attrs())
    # saved samples agree with the final state
    np.testing.assert_array_equal(ds.theta.isel(time=-1), ds.theta_final)


def test_winding_counts_the_wells_crossed():
    """winding = round(theta_final / 2 pi) - round(theta0 / 2 pi): the demo's damped
    pendulum (c = 0.3 1/s, g/L = 9.81 1/s^2) started 0.01 rad either side of the
    bottom of wells -1, 0 and 2 at 7.5 rad/s goes over the top once and is captured in
    the next well, so every start counts 1 (-1 for the mirror starts). The old
    definition, trunc((theta_final - theta0) / 2 pi), counted 0 from +0.01 (net angle
    2 pi - 0.01) and 1 from -0.01: the cut along theta0 = 0 of the demo's map."""
    bottoms = 2 * np.pi * np.array([-1, 0, 2])
    theta0 = np.concatenate([bottoms - 0.01, bottoms + 0.01])
    ds = sweep.run(sweep.Scene(effects=(sweep.Damping(0.3),)),
                   sweep.Grid(theta0=theta0, omega0=[7.5, -7.5]), t_end=40.0, dt=0.01,
                   observe=("final", "winding", "energy"))
    assert (ds.energy_final < 2 * 9.81).all()  # captured: below the separatrix energy
    k = np.round(theta0 / (2 * np.pi))[:, None] + np.array([1, -1])  # the next well
    np.testing.assert_array_equal(np.round(ds.theta_final / (2 * np.pi)), k)
    np.testing.assert_array_equal(ds.winding, np.broadcast_to([1, -1], ds.winding.shape))
    # at rest near the bottom of a well, or near its top: a libration crosses no top
    starts = (bottoms[:, None] + [0.3, -3.0, 3.0]).ravel()
    rest = sweep.run(sweep.Scene(), sweep.Grid(theta0=starts), t_end=10.0, dt=0.01,
                     observe=("final", "winding"))
    np.testing.assert_array_equal(rest.winding, 0)
    # fast, undamped: many wells crossed, the sense of rotation, and the end's well
    fast = sweep.run(sweep.Scene(), sweep.Grid(omega0=[-10.0, 0.0, 10.0]), t_end=10.0,
                     dt=0.001, observe=("final", "winding"))
    np.testing.assert_array_equal(fast.winding, np.round(fast.theta_final / (2 * np.pi)))
    assert fast.winding[0] < -5 and fast.winding[1] == 0 and fast.winding[2] > 5


def test_fresh_process_loads_the_kernel_from_the_disk_cache(tmp_path):
    script = textwrap.dedent("""
        import sweep
        from sweep import kernels as _kernels
        sweep.run(sweep.Scene(effects=(sweep.Damping(0.1),)), sweep.Grid(theta0=[0.1]),
                  t_end=1.0, dt=0.1, observe=("final", "energy"))
        # the spec sweep.run built: a one-trajectory grid runs one trajectory per block
        kernel = _kernels.build(_kernels.KernelSpec("nonlinear", ("damping",),
                                                    ("final", "energy"), block=1))
        stats = _kernels.compiled(kernel).stats
        print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
    """)
    env = dict(os.environ, SWEEP_CACHE_DIR=str(tmp_path))
    runs = [subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                           text=True, check=True).stdout.split() for _ in range(2)]
    assert runs[0] == ["0", "1"]  # first process compiles...
    assert runs[1] == ["1", "0"]  # ...the second loads machine code from disk


def test_warm_up_compiles_the_kernel_the_run_then_uses():
    scene = sweep.Scene(effects=(sweep.Damping(0.3),))
    grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 3000))  # > 16 blocks: large blocks
    kwargs = dict(t_end=1.0, dt=0.01, observe=("final", "theta_max"))
    spec = sweep.engine.warm_up(scene, grid, **kwargs)
    assert spec.block == sweep._config.BLOCK and spec.observe == ("final", "theta_max")
    kernel = _kernels.compiled(_kernels.build(spec))
    assert len(kernel.signatures) == 1  # compiled (or loaded) for the run's types
    misses = _kernels.build.cache_info().misses
    sweep.run(scene, grid, **kwargs)
    assert _kernels.build.cache_info().misses == misses  # the run's spec: memo hit
    assert len(kernel.signatures) == 1  # and nothing new compiled
    with pytest.raises(ValueError, match=r"t_end must be > t0"):
        sweep.engine.warm_up(scene, grid, t_end=-1.0, dt=0.01)  # validated like run


def test_after_warm_up_the_first_run_imports_nothing():
    """warm_up pays the process's one-time costs too: xarray imports Dask (where it is
    installed) on its first Dataset, 0.29 s, which a benchmark timing the first run of
    a process counted as integration (issue 29's "bimodal" rate). In a fresh process:
    after warm_up, the run imports no module."""
    script = textwrap.dedent("""
        import sys, numpy as np, sweep
        scene = sweep.Scene(effects=(sweep.Damping(0.3),))
        grid = sweep.Grid(theta0=np.linspace(-1.0, 1.0, 3000))
        kwargs = dict(t_end=1.0, dt=0.01, observe=("final", "theta_max"))
        sweep.engine.warm_up(scene, grid, **kwargs)
        before = set(sys.modules)
        sweep.run(scene, grid, progress=False, **kwargs)
        print(sorted(set(sys.modules) - before))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_grid_table_and_its_description_against_meshgrid():
    """`Grid.table` (any slice) is the C-order meshgrid of the axes over the scene's
    row, and `Grid.rows` / `GridRows.from_table` describe the same rows: rebuilding
    each row from the description the way a GPU thread does gives the table exactly."""
    from sweep.grid import GridRows
    from sweep.physics import parameter_names

    grid = sweep.Grid(theta0=np.linspace(-1, 1, 7), omega0=[1.0, 2.0, 3.0],
                      damping=[0.1, 0.2])
    scene = sweep.Scene(gravity=3.0, effects=(sweep.Damping(0.3),))
    names = parameter_names()
    mesh = np.meshgrid(*grid.axes.values(), indexing="ij")

    def rebuilt(rows):
        table = np.tile(rows.template, (len(rows), 1))
        for i in range(len(rows)):
            for a, column in enumerate(rows.columns):
                k = (rows.start + i) // rows.strides[a] % rows.sizes[a]
                table[i, column] = rows.values[rows.offsets[a] + k]
        return table

    for start, stop in ((0, 42), (5, 37), (41, 42), (9, 9)):
        table = grid.table(scene, start, stop)
        assert table.shape == (stop - start, len(names)) and table.flags.c_contiguous
        for name, values in zip(grid.axes, mesh):
            np.testing.assert_array_equal(table[:, names.index(name)],
                                          values.ravel()[start:stop])
        assert (table[:, names.index("gravity")] == 3.0).all()
        np.testing.assert_array_equal(rebuilt(grid.rows(scene, start, stop)), table)
        np.testing.assert_array_equal(rebuilt(GridRows.from_table(table)), table)
