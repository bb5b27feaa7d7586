"""The blocked fixed-step kernels: trajectories advance in blocks of SIMD lanes (time
loop outside, lane loop inside), and a partial block is padded with copies of the
last trajectory. Whatever the block size, the number of trajectories per call (so the
padding), the thread count, and whether the forcing sine is shared by the block, every
trajectory must get the same bits -- including its observables, saved samples, status
and early stop."""

import re

import numba
import numpy as np
import pytest
from shared_kernels import EVERY, EVERY_ADAPTIVE

import sweep
from sweep import kernels as _kernels
from sweep.kernels import KernelSpec, Status
from sweep.methods import METHODS
from sweep.observables import OBSERVABLES

DT = 0.05
N_STEPS = 600  # 30 s: the forced scene is chaotic, so a last-bit change would show
# Every observable: the blocks sweep.run also picks (16, for 4-127 trajectories) are then
# the kernels of test_naive's and test_methods' runs (tests/shared_kernels.py)
ALL_OBSERVE = EVERY


def _table(n, *, damping=0.5, amplitude=1.2, frequency=2 / 3, phase=0.3):
    """n parameter rows (`sweep.physics.parameter_names` order) with distinct starts;
    row 5 overflows (c = 1e4 is far outside RK4's stability region at this dt)."""
    rng = np.random.default_rng(7)
    column = {name: k for k, name in enumerate(sweep.physics.parameter_names())}
    params = np.empty((n, len(column)))
    params[:, column["theta0"]] = rng.uniform(-np.pi, np.pi, n)
    params[:, column["omega0"]] = rng.uniform(-2.0, 2.0, n)
    params[:, column["damping"]] = damping
    params[:, column["forcing_amplitude"]] = amplitude
    params[:, column["forcing_frequency"]] = frequency
    params[:, column["forcing_phase"]] = phase
    params[:, column["length"]] = 1.0
    params[:, column["gravity"]] = 1.0
    if n > 5:
        params[5, column["damping"]] = 1e4
    return params


def _call(spec, params, *, n_transient=100, save_every=0):
    kernel = _kernels.build(spec)
    n = params.shape[0]
    out = np.full((n, _kernels.n_columns(spec)), -7.0)
    status = np.full(n, 99, dtype=np.int8)
    saved = np.full((n, 2, N_STEPS // save_every + 1), np.nan) if save_every else \
        np.empty((0, 2, 0))
    kernel(params, 0.0, DT, N_STEPS, n_transient, save_every or 1, out, status, saved)
    return out, status, saved


def _one_by_one(spec, params, **kwargs):
    """Each trajectory alone in its call: a block of one real lane and padding."""
    parts = [_call(spec, params[k:k + 1], **kwargs) for k in range(params.shape[0])]
    return tuple(np.concatenate([p[q] for p in parts]) for q in range(3))


def _assert_same(a, b):
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("shared", [False, True])
def test_forced_run_with_every_observable_and_saving_is_the_same_for_any_blocking(shared):
    params = _table(77)  # not a multiple of any block size: the last block is padded
    # (128: one block, larger than the table; the kernel the per-lane check of the other
    # parametrisation uses)
    specs = [KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True, block=block,
                        shared_forcing=shared) for block in (1, 8, 64, 128)]
    reference = _call(specs[0], params, save_every=7)
    out, status, saved = reference
    assert (status[np.arange(77) != 5] == Status.OK).all() and status[5] == Status.NONFINITE
    assert np.isnan(out[5]).all() and np.isfinite(out[np.arange(77) != 5]).all()
    assert np.isnan(saved[5, :, -1]).all()  # samples after the failure are NaN
    for spec in specs[1:]:
        _assert_same(_call(spec, params, save_every=7), reference)
    _assert_same(_one_by_one(specs[1], params, save_every=7), reference)
    # the shared sine is the per-lane sine, evaluated once: the same bits
    per_lane = KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True,
                          shared_forcing=not shared)
    _assert_same(_call(per_lane, params, save_every=7), reference)


def test_frequencies_that_differ_per_trajectory_are_each_honoured():
    params = _table(40)
    params[:, sweep.physics.parameter_names().index("forcing_frequency")] = \
        np.linspace(0.5, 1.5, 40)  # forcing_frequency differs per lane
    # one block of 64 lanes holds the 40 frequencies (the previous test's kernels)
    spec = KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True, block=64)
    _assert_same(_call(spec, params, save_every=7), _one_by_one(spec, params, save_every=7))
    # and one frequency per call, with the shared sine, is the same again
    shared = KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True, block=64,
                        shared_forcing=True)
    _assert_same(_one_by_one(shared, params, save_every=7), _call(spec, params, save_every=7))


@pytest.mark.parametrize("observe,forcing", [(("strobe",), True), (("capture",), False)])
def test_early_stop_is_the_same_for_any_blocking(observe, forcing):
    params = _table(50, amplitude=1.66 if forcing else 0.0, frequency=1.0, damping=0.2)
    params[5, 2] = 0.2
    references = None
    for block in (1, 8, 64):
        spec = KernelSpec("nonlinear", ("damping",) + ("forcing",) * forcing, observe,
                          stop_early=True, block=block,
                          shared_forcing=forcing)
        got = _call(spec, params, n_transient=0)
        if references is None:
            references = got
            # a lane that stops must not disturb its block: alone it gives the same
            _assert_same(_one_by_one(spec, params[:12], n_transient=0),
                         tuple(a[:12] for a in got))
        else:
            _assert_same(got, references)


@pytest.mark.parametrize("method", [m for m, v in METHODS.items() if not v.adaptive])
def test_every_fixed_step_method_is_the_same_for_any_blocking(method):
    conservative = METHODS[method].conservative_only
    params = _table(30, damping=0.0 if conservative else 0.5)
    if conservative:  # no damping at all, not even row 5's overflowing one
        params[5, sweep.physics.parameter_names().index("damping")] = 0.0
    # every observable and the table's one drive frequency shared by the block: 16 lanes
    # (two blocks, the second partial) are test_methods' run of the method, 64 (one
    # block larger than the table) test_engine's run (RK4) and test_effects' kernel
    # (Yoshida4); blocks of 8 are tested above and below
    spec = [KernelSpec("nonlinear", () if conservative else ("damping", "forcing"),
                       ALL_OBSERVE, method=method, block=block,
                       shared_forcing=not conservative) for block in (1, 16, 64)]
    first = _call(spec[0], params)
    for other in spec[1:]:
        _assert_same(first, _call(other, params))


def _adaptive(spec, params, t_transient=5.0):
    """The adaptive kernel over 30 s (chaotic: a last-bit change would show)."""
    n = params.shape[0]
    out = np.full((n, _kernels.n_columns(spec)), -7.0)
    status = np.full(n, 99, dtype=np.int8)
    stats = np.full((n, 2), -1, dtype=np.int64)
    _kernels.build(spec)(params, 0.0, 30.0, 0.1, t_transient, 1e-8, 1e-10, out, status,
                         stats)
    return out, status, stats


def test_adaptive_lanes_are_the_same_for_any_blocking_and_threads():
    """dopri5 in SIMD lanes: each lane accepts or rejects its own step, so lanes drift
    apart in time; whatever the block, the padding (30 rows: partial blocks) and the
    thread count, each trajectory gets the bits and step counts of a block of one.
    Row 5 (c = 1e300) is stiff beyond any step: its step collapses and it is flagged."""
    params = _table(30)
    params[5, sweep.physics.parameter_names().index("damping")] = 1e300  # stable only
    # for h < ~3e-300: the step underflows
    # every observable dopri5 takes, and the table's one drive frequency shared: the
    # block of one is test_methods' run of dopri5
    specs = [KernelSpec("nonlinear", ("damping", "forcing"), EVERY_ADAPTIVE, method="dopri5",
                        block=block, shared_forcing=True) for block in (1, 8, 64)]
    first = _adaptive(specs[0], params)
    assert first[1][5] == Status.STEP_UNDERFLOW and (np.delete(first[1], 5) == 0).all()
    assert (first[2].sum(axis=1) > 0).all()  # every lane tried steps
    for spec in specs[1:]:
        _assert_same(first, _adaptive(spec, params))
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _adaptive(specs[2], _table(300))
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = _adaptive(specs[2], _table(300))
    finally:
        numba.set_num_threads(before)
    _assert_same(one, many)


def test_thread_count_does_not_matter_within_a_call():
    params = _table(300)
    # the saving kernel in blocks of 8 of the forced test above: samples checked too
    spec = KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True, block=8)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = _call(spec, params, save_every=7)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = _call(spec, params, save_every=7)
    finally:
        numba.set_num_threads(before)
    _assert_same(one, many)


def test_adaptive_lanes_with_every_effect_and_observable():
    """The five effects (the pivot's tension reads each lane's own time) and every
    observable dopri5 takes, updated from the start (t_transient = 0): blocks of 1, 16
    and 64 give the same bits; with t_end = t0 nothing is integrated and the start is
    the result."""
    column = {name: k for k, name in enumerate(sweep.physics.parameter_names())}
    params = _table(40)
    params[:, column["torque"]] = 0.3
    params[:, column["drag"]] = 0.2
    params[:, column["pivot_amplitude"]] = 0.05
    params[:, column["pivot_frequency"]] = np.linspace(5.0, 30.0, 40)
    params[:, column["pivot_phase"]] = 0.1
    observe = ("final", "winding", "theta_max", "amplitude", "tension", "energy",
               "top_distance")
    effects = ("damping", "forcing", "torque", "drag", "pivot")
    specs = [KernelSpec("nonlinear", effects, observe, method="dopri5", block=block)
             for block in (1, 16, 64)]
    first = _adaptive(specs[0], params, t_transient=0.0)
    assert (first[1] == 0).sum() >= 39 and np.isfinite(first[0][first[1] == 0]).all()
    for spec in specs[1:]:
        _assert_same(first, _adaptive(spec, params, t_transient=0.0))
    n = params.shape[0]
    out, status = np.full((n, _kernels.n_columns(specs[1])), -7.0), np.full(n, 9, np.int8)
    stats = np.full((n, 2), -1, dtype=np.int64)
    _kernels.build(specs[1])(params, 0.0, 0.0, 0.1, 0.0, 1e-8, 1e-10, out, status, stats)
    assert (stats == 0).all() and (status == 0).all()
    np.testing.assert_array_equal(out[:, :2], params[:, :2])  # final = the start


def test_lane_code_never_writes_a_row_of_out_directly():
    """Padding lanes repeat the last trajectory's row index; only the final copy of
    real lanes may touch ``out`` (snippets write the block's row buffer)."""
    for name, obs in OBSERVABLES.items():
        spec = KernelSpec("nonlinear", ("damping",) + ("forcing",) * obs.requires_forcing, (name,),
                          stop_early=bool(obs.settled))
        text = _kernels.source(spec)
        assert re.findall(r"\bout\[", text) == ["out["], name


def test_every_observable_declares_the_state_it_keeps():
    """A variable assigned in ``init`` lives across steps, so in a blocked kernel it
    must be a per-lane array: it has to be declared in ``state``."""
    assigned = re.compile(r"^\s*([A-Za-z_]\w*)\s*=(?!=)", re.MULTILINE)
    for name, obs in OBSERVABLES.items():
        declared = {var for var, _ in obs.state}
        assert set(assigned.findall(obs.init)) <= declared, name
        for _, dtype in obs.state:
            assert dtype in ("float64", "int64", "bool_"), name


@pytest.mark.parametrize("block", [12, True, 8.0])
def test_block_must_be_a_multiple_of_eight(block):
    """Refused before any compute; True too, which equals 1 (so its spec would share
    the memo of block 1's) but would reach the compiled kernel as a boolean ``BLOCK``."""
    with pytest.raises(ValueError, match=r"block must be 1 or a positive multiple of 8, "
                                         rf"got {block!r}$"):
        KernelSpec("linear", (), ("final",), block=block)


def test_one_compiled_kernel_serves_every_block_size_but_one_lane():
    """The lanes per block are an argument of the compiled function
    (`sweep.kernels.lanes.BIND`), not a constant of its text: every kind of CPU module
    reads the same for 8 and 64 lanes (so a new block size compiles nothing), and one
    lane has its own, scalar text (`sweep.kernels.lanes.scalar_lanes`); a swing
    network's kernel keeps the block a constant."""
    import dataclasses
    import sys

    from sweep.engine_systems import prepare_system
    from sweep.kernels.network import NetworkSpec

    source = sys.modules["sweep.kernels.source"].source
    period = 2 * np.pi / 0.7
    forced = sweep.Scene(effects=(sweep.Damping(0.2), sweep.Forcing(1.2, 0.7)))
    grid = sweep.Grid(theta0=np.linspace(-3, 3, 40), omega0=[0.0, 1.0])
    pendulum = {  # the run's specs: no kernel is compiled here
        "fixed": dict(observe=ALL_OBSERVE, save_every=7),
        "refill": dict(observe=("strobe",), stop_early=True, t_transient=2 * period),
        "adaptive": dict(observe=("final",), method="dopri5")}
    specs = {name: sweep.engine.prepare(forced, grid, t_end=4 * period, dt=period / 100,
                                        **kw)[1] for name, kw in pendulum.items()}
    double = sweep.Grid(theta1_0=np.linspace(-3, 3, 40), theta2_0=[0.0, 1.0])
    for name, kw in {"system": dict(observe=("final",)),
                     "system refill": dict(observe=("flip",), stop_early=True)}.items():
        specs[name] = prepare_system(sweep.DoublePendulum(), double, t_end=1.0, dt=0.01,
                                     **kw)[1]
    specs["network"] = NetworkSpec(((0, 1, 1.0),), (-1.0, 1.0), (0.0, 0.5), ("final",),
                                   block=8)
    assert specs["refill"].refill and specs["system refill"].refill
    for name, spec in specs.items():
        texts = {block: source(dataclasses.replace(spec, block=block)) for block in (1, 8, 64)}
        # a network's block is a constant of its text (sweep.kernels.network says why)
        assert (texts[8] == texts[64]) == (name != "network"), name
        if name in ("fixed", "system"):
            assert texts[1] != texts[8], name  # scalar lanes
    small = KernelSpec("nonlinear", ("damping", "forcing"), ALL_OBSERVE, save=True, block=8)
    large = dataclasses.replace(small, block=64)  # test_forced_run_...'s kernels
    assert _kernels.compiled(_kernels.build(small)) is _kernels.compiled(_kernels.build(large))
    params = _table(77)
    _assert_same(_call(small, params, save_every=7), _call(large, params, save_every=7))
    assert len(_kernels.compiled(_kernels.build(small)).signatures) == 1


def test_one_head_writer_serves_every_kind_of_kernel():
    """Every CPU module's head (``bind`` and the compiled function's signature) comes
    from `sweep.kernels.lanes.blocks_head`: a swing network's with its block a constant
    of the text in place of the line that says the argument is a multiple of 8 (16 for a
    float32 block of 16), none for one lane; an adaptive kernel's with its own
    arguments."""
    import sys

    from sweep.kernels.lanes import ADAPTIVE_ARGUMENTS, blocks_head
    from sweep.kernels.network import NETWORK_ARGUMENTS, NetworkSpec

    def tidy(text):  # a module's text, as sweep.kernels.source writes it
        return "\n".join(line for line in text.splitlines() if line.strip())

    source = sys.modules["sweep.kernels.source"].source
    ends = {blocks_head(16, ", src", constant_block=True): "    BLOCK = 16  # a constant",
            blocks_head(16, ", src"): "    BLOCK = (BLOCK >> 3) << 3  # a multiple of 8",
            blocks_head(16, dtype="float32"): "    BLOCK = (BLOCK >> 4) << 4  # a multiple of 16",
            blocks_head(1): "           BLOCK, b_first, b_stop):"}
    for head, end in ends.items():
        assert head.splitlines()[-1].startswith(end), head
    network = NetworkSpec(((0, 1, 1.0),), (-1.0, 1.0), (0.0, 0.5), ("final",), block=16)
    assert tidy(blocks_head(16, NETWORK_ARGUMENTS, constant_block=True)) in source(network)
    adaptive = KernelSpec("nonlinear", ("damping",), ("final",), method="dopri5", block=16)
    head = blocks_head(16, arguments=ADAPTIVE_ARGUMENTS)
    assert "rtol, atol, out, status, stats," in head and tidy(head) in source(adaptive)
