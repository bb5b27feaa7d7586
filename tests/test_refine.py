"""Adaptive boundary refinement (`sweep.maps.refine`, issue 27).

The algorithm (`sweep.maps._quadtree.refine_field`) on synthetic label fields with exact
expectations, against a naive recursive implementation of the same rule; then the sweep
wiring against the full run of the same grid.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import ndimage

from sweep.maps._quadtree import refine_field


# ------------------------------------------------------------------ synthetic fields
def field_callback(field: np.ndarray):
    """A callback reading ``field``, that fails if a cell is asked for twice."""
    asked = np.zeros(field.shape, dtype=bool)

    def compute(rows, cols):
        assert rows.dtype == np.int64 and cols.dtype == np.int64
        assert not asked[rows, cols].any(), "a cell was computed twice"
        asked[rows, cols] = True
        return field[rows, cols]

    return compute, asked


def naive(field: np.ndarray, step: int):
    """The rule of sweep.maps._quadtree written plainly: recursion block by block."""
    n0, n1 = field.shape
    out = np.full(field.shape, -999, dtype=np.int64)
    computed = np.zeros(field.shape, dtype=bool)

    def get(r, c):
        out[r, c] = field[r, c]
        computed[r, c] = True

    rows = sorted(set(range(0, n0, step)) | {n0 - 1})
    cols = sorted(set(range(0, n1, step)) | {n1 - 1})
    for r in rows:
        for c in range(n1):
            get(r, c)
    for c in cols:
        for r in range(n0):
            get(r, c)

    def visit(r0, r1, c0, c1):
        if r1 - r0 < 2 or c1 - c0 < 2:
            return
        border = np.concatenate([out[r0, c0:c1 + 1], out[r1, c0:c1 + 1],
                                 out[r0:r1 + 1, c0], out[r0:r1 + 1, c1]])
        if (border == border[0]).all():
            out[r0 + 1:r1, c0 + 1:c1] = border[0]
            return
        rm, cm = (r0 + r1) // 2, (c0 + c1) // 2
        for c in range(c0, c1 + 1):
            get(rm, c)
        for r in range(r0, r1 + 1):
            get(r, cm)
        for a, b in ((r0, rm), (rm, r1)):
            for c, d in ((c0, cm), (cm, c1)):
                visit(a, b, c, d)

    for a, b in itertools.pairwise(rows):
        for c, d in itertools.pairwise(cols):
            visit(a, b, c, d)
    return out, computed


def disks(shape, centres_radii):
    """Label k + 1 inside the k-th disk (later disks on top), 0 outside."""
    r, c = np.indices(shape)
    field = np.zeros(shape, dtype=np.int64)
    for k, (r0, c0, radius) in enumerate(centres_radii):
        field[(r - r0) ** 2 + (c - c0) ** 2 <= radius**2] = k + 1
    return field


def newton_basins(n: int) -> np.ndarray:
    """Basins of Newton's method for z^3 = 1 on [-1.5, 1.5]^2: a fractal boundary."""
    x = np.linspace(-1.5, 1.5, n)
    z = x[None, :] + 1j * x[:, None]
    with np.errstate(all="ignore"):
        for _ in range(40):
            z = z - (z**3 - 1) / (3 * z**2)
    roots = np.exp(2j * np.pi * np.arange(3) / 3)
    return np.argmin(np.abs(z[..., None] - roots), axis=-1).astype(np.int64)


def stripes(shape, width):
    """Diagonal stripes of ``width`` cells, three labels."""
    r, c = np.indices(shape)
    return ((r + 2 * c) // width) % 3


SYNTHETIC = {
    "stripes": (stripes((129, 129), 7), 16),
    "stripes uneven": (stripes((100, 131), 30), 8),
    "disks": (disks((129, 129), [(40, 50, 30), (90, 90, 25), (64, 64, 9)]), 16),
    "checkerboard": ((np.add.outer(np.arange(129) // 9, np.arange(129) // 9) % 2), 16),
    "newton": (newton_basins(129), 16),
    "newton step 4": (newton_basins(129), 4),
    "one row": (stripes((1, 40), 3), 4),
    "tiny": (stripes((2, 3), 1), 2),
}


@pytest.mark.parametrize("name", list(SYNTHETIC))
def test_same_as_the_naive_rule(name):
    """Cell for cell, the vectorised levels do what the plain recursion does."""
    field, step = SYNTHETIC[name]
    compute, asked = field_callback(field)
    got = refine_field(field.shape, compute, step)
    want, want_computed = naive(field, step)
    np.testing.assert_array_equal(got.labels, want)
    np.testing.assert_array_equal(got.computed, want_computed)
    np.testing.assert_array_equal(got.computed, asked)
    assert got.cells_computed == int(asked.sum())
    # the computed cells hold their own labels
    np.testing.assert_array_equal(got.labels[got.computed], field[got.computed])


@pytest.mark.parametrize("name", ["stripes", "stripes uneven", "disks", "checkerboard"])
def test_exact_on_fields_without_islands(name):
    """Every region of these fields reaches a lattice line (stripes and checker squares
    cross every line; the disks are wider than the step): nothing can be missed."""
    field, step = SYNTHETIC[name]
    got = refine_field(field.shape, field_callback(field)[0], step)
    np.testing.assert_array_equal(got.labels, field)
    assert got.cells_computed < field.size


def test_smooth_boundary_costs_little():
    """One disk of radius 40 in 257 x 257: the lattice (2/16 of the cells) and the blocks
    along the circle, whose cells grow like its length, not the area."""
    field = disks((257, 257), [(128, 128, 40)])
    got = refine_field(field.shape, field_callback(field)[0], 16)
    np.testing.assert_array_equal(got.labels, field)
    assert got.cells_computed < 0.25 * field.size
    assert got.cells_per_level[0] == 257**2 - (257 - 17) ** 2  # 17 lines each way


def test_an_island_inside_one_block_is_missed():
    """The documented limit: a disk of radius 3 inside one 16 x 16 block whose whole
    perimeter is 0 is never seen; the map is the field without it, and nothing but the
    lattice is computed."""
    field = disks((65, 65), [(24, 24, 3)])
    got = refine_field(field.shape, field_callback(field)[0], 16)
    np.testing.assert_array_equal(got.labels, np.zeros_like(field))
    assert got.cells_computed == got.cells_per_level[0] == 65**2 - 60**2  # 5 lines each way


def test_wrong_cells_lie_in_islands(rng):
    """The guarantee, where something is missed: Newton's fractal basins with a dust of
    60 small disks (label 3, radius 1 to 4 cells) on top. Every wrong cell is a filled
    one, and each connected set (through edges and corners) of wrong cells is an island:
    all its neighbours carry the one label its block was filled with."""
    field = newton_basins(257)
    centres = rng.integers(0, 257, size=(60, 2))
    dust = disks(field.shape, [(r, c, rad) for (r, c), rad in
                               zip(centres, rng.integers(1, 5, size=60))]) > 0
    field[dust] = 3
    got = refine_field(field.shape, field_callback(field)[0], 32)
    wrong = got.labels != field
    assert wrong.any()  # some disks sit inside uniform blocks: the test has islands
    assert not (wrong & got.computed).any()
    islands, count = ndimage.label(wrong, structure=np.ones((3, 3)))
    for k in range(1, count + 1):
        cells = islands == k
        ring = ndimage.binary_dilation(cells, structure=np.ones((3, 3))) & ~cells
        assert np.unique(got.labels[ring]).size == 1
        assert (field[ring] == got.labels[ring]).all()


def test_bad_arguments():
    field = stripes((9, 9), 2)
    for step in (1, 0, -4):
        with pytest.raises(ValueError, match="step must be an int >= 2"):
            refine_field(field.shape, field_callback(field)[0], step)
    for step in (2.0, "4", True, None):
        with pytest.raises(ValueError, match="step must be an int >= 2"):
            refine_field(field.shape, field_callback(field)[0], step)
    with pytest.raises(ValueError, match="shape must be two ints"):
        refine_field((9, 9, 9), field_callback(field)[0], 4)
    with pytest.raises(ValueError, match="shape"):
        refine_field((0, 9), field_callback(field)[0], 4)
    with pytest.raises(ValueError, match="dtype float64"):
        refine_field((9, 9), lambda r, c: np.zeros(r.size), 4)
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        refine_field((9, 9), lambda r, c: np.zeros(3, dtype=int), 4)


# ------------------------------------------------------------------ sweep wiring
import functools  # noqa: E402

import xarray as xr  # noqa: E402

import sweep  # noqa: E402
from sweep import maps  # noqa: E402

REFINE_ATTRS = ("refine_step", "cells_computed", "cells_total", "cells_per_level",
                "blocks_filled", "pilot_cells")


def without_refinement(refined: xr.DataArray) -> xr.DataArray:
    """The refined map less what refine adds (the mask and the counts)."""
    out = refined.copy().drop_vars("computed")
    out.attrs = {k: v for k, v in refined.attrs.items() if k not in REFINE_ATTRS}
    return out


def check_bookkeeping(refined: xr.DataArray, step: int) -> None:
    mask = refined["computed"]
    assert mask.dtype == bool and mask.dims == refined.dims
    assert int(mask.sum()) == refined.attrs["cells_computed"] \
        == int(refined.attrs["cells_per_level"].sum())
    assert refined.attrs["cells_total"] == refined.size
    assert refined.attrs["refine_step"] == step


DAMPED = sweep.Scene(gravity=9.81, length=1.0, effects=(sweep.Damping(0.25),))
DAMPED_GRID = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 129),
                         omega0=np.linspace(-12.0, 12.0, 129))
DAMPED_RUN = dict(t_end=40.0, dt=0.02, observe=("capture",), stop_early=True,
                  progress=False)


@pytest.fixture(scope="module")
def damped_full():
    return sweep.run(DAMPED, DAMPED_GRID, **DAMPED_RUN)


@pytest.mark.parametrize("label", [maps.well, maps.basins, "well",
                                   functools.partial(maps.basins, rest_position=True)],
                         ids=["well", "basins", "variable", "basins rest_position"])
def test_damped_well_map_is_the_full_runs(damped_full, label):
    """Smooth spiral boundaries, every band wider than the step where it crosses a
    lattice line: 0 differing cells, and the same DataArray (name, dtype, coordinates
    with their attributes, attributes: basins' numbering from the wells of the whole
    map)."""
    refined = maps.refine(DAMPED, DAMPED_GRID, label, step=16, **DAMPED_RUN)
    full = damped_full[label] if isinstance(label, str) else label(damped_full)
    xr.testing.assert_identical(without_refinement(refined), full)
    check_bookkeeping(refined, 16)
    assert refined.attrs["cells_computed"] < 0.6 * refined.size  # 52 % at this size
    assert refined.attrs["pilot_cells"] == 0  # pilots are for forced basins


def test_torque_motion_map_with_singleton_axes():
    """Locked versus running over (torque, damping) from a running start (theta0 and
    omega0 one value each, so the grid is 4-D with two varying axes): the map and its
    dims are the full run's."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.1), sweep.Torque(0.5)))
    grid = sweep.Grid(torque=np.linspace(0.0, 1.2, 97), damping=np.linspace(0.02, 0.5, 97),
                      theta0=[0.0], omega0=[2.0])
    run = dict(t_end=150.0, dt=0.05, t_transient=100.0, observe=("omega_mean",),
               progress=False)
    refined = maps.refine(scene, grid, maps.motion, step=8, **run)
    full = maps.motion(sweep.run(scene, grid, **run))
    xr.testing.assert_identical(without_refinement(refined), full)
    check_bookkeeping(refined, 8)
    assert refined.attrs["cells_computed"] < 0.5 * refined.size


def test_torque_motion_phase_map():
    """Locked and running states coexisting at torque 0.5, damping 0.1 over (theta0,
    omega0): rotation/libration with sense, 0 differing cells (smooth boundaries)."""
    scene = sweep.Scene(gravity=1.0, length=1.0,
                        effects=(sweep.Damping(0.1), sweep.Torque(0.5)))
    grid = sweep.Grid(theta0=np.linspace(-np.pi, np.pi, 129),
                      omega0=np.linspace(-4.0, 4.0, 129))
    run = dict(t_end=150.0, dt=0.05, t_transient=100.0, observe=("omega_mean",),
               progress=False)
    refined = maps.refine(scene, grid, maps.motion, **run)
    full = maps.motion(sweep.run(scene, grid, **run))
    assert set(np.unique(full.values)) >= {0, 1}  # both states present
    xr.testing.assert_identical(without_refinement(refined), full)


FORCED = sweep.Scene(gravity=1.0, length=1.0,
                     effects=(sweep.Damping(0.2), sweep.Forcing(1.66, 1.0, np.pi / 2)))
# conftest's WADA_PILOT: a 21 x 21 pilot of it is the wada_catalogue fixture's run
FORCED_RUN = dict(t_end=320 * 2 * np.pi, dt=2 * np.pi / 100, t_transient=20 * 2 * np.pi,
                  observe=("strobe",), stop_early=True, progress=False)


def forced_grid(n):
    return sweep.Grid(theta0=np.linspace(-np.pi, np.pi, n), omega0=np.linspace(-4.0, 4.0, n))


def assert_islands(refined, full):
    """Only filled cells differ from the full run, each connected set of them an island
    whose neighbours all hold the full run's label, the one its block was filled with."""
    differ = refined.values != full.values
    assert not (differ & refined["computed"].values).any()
    islands, count = ndimage.label(differ, structure=np.ones((3, 3)))
    for k in range(1, count + 1):
        cells = islands == k
        ring = ndimage.binary_dilation(cells, structure=np.ones((3, 3))) & ~cells
        assert np.unique(refined.values[ring]).size == 1
        assert (refined.values[ring] == full.values[ring]).all()


def check_forced(refined, full):
    """The forced map against the full run: computed cells alike (the same
    trajectories, the same catalogue), only filled cells in islands may differ (the
    documented limit), and at most 1e-3 of the cells do (the issue's aim; measured 14
    cells of 25,921 at 161 x 161, 5.4e-4, and 4.4e-4 on the 1200 x 1200 map)."""
    assert_islands(refined, full)
    differ = refined.values != full.values
    assert differ.mean() <= 1e-3
    for key in ("attractor_period", "attractor_turns_per_period"):
        np.testing.assert_array_equal(refined.attrs[key], full.attrs[key])
    # each basin's size is the count of its label, so it is off by the differing cells
    assert np.abs(refined.attrs["attractor_size"] - full.attrs["attractor_size"]).sum() \
        <= 2 * differ.sum()
    for name in ("long_name", "attractor_kind", "unresolved"):
        assert refined.attrs[name] == full.attrs[name]
    assert refined.dims == full.dims and refined.dtype == full.dtype
    xr.testing.assert_identical(refined.drop_vars("computed").coords.to_dataset(),
                                full.coords.to_dataset())


def test_forced_wada_map_with_the_coarse_catalogue(wada_catalogue):
    """The fractal map: refine's pilot catalogue is the full run's (the same 21 x 21
    pilot, conftest's: its catalogue's kernel is compiled once for the suite; a pilot
    of any size is the same code as the default 41), so labels are numbered alike."""
    grid = forced_grid(161)  # thinned to 21 x 21 (every 8th value): the fixture's starts
    refined = maps.refine(FORCED, grid, maps.basins, pilot=21, **FORCED_RUN)
    catalogue = maps.pilot_catalogue(FORCED, grid, 21, **FORCED_RUN)
    for key, value in wada_catalogue.items():  # the fixture's pilot
        np.testing.assert_array_equal(catalogue[key], value, err_msg=key)
    full = maps.basins(sweep.run(FORCED, grid, attractors=catalogue, **FORCED_RUN))
    check_forced(refined, full)
    check_bookkeeping(refined, 16)
    assert refined.attrs["pilot_cells"] == 21 * 21


def test_an_attractor_missing_from_the_catalogue_gets_one_label(wada_catalogue):
    """A catalogue without the libration attractor (so its starts are found by the
    strobe test, level by level): its basin still has one label, the full run's. The
    catalogue is conftest's (FORCED's 21 x 21 pilot), less the same attractor as in
    test_attractor_catalogue.py, so the partial catalogue's kernel is shared."""
    grid = forced_grid(65)
    catalogue = wada_catalogue
    keep = np.flatnonzero(np.asarray(catalogue["period"]) != 1)  # the two rotations
    assert keep.size == len(catalogue["period"]) - 1
    partial = {k: np.asarray(v)[keep] for k, v in catalogue.items()}
    refined = maps.refine(FORCED, grid, maps.basins, attractors=partial, **FORCED_RUN)
    full = maps.basins(sweep.run(FORCED, grid, attractors=partial, **FORCED_RUN))
    assert len(full.attrs["attractor_size"]) == 3
    check_forced(refined, full)
    assert refined.attrs["pilot_cells"] == 0  # attractors given: no pilot


def test_period_map_without_catalogue():
    """A per-trajectory map of a forced scene (no pilot: catalogues are for basins)."""
    grid = forced_grid(33)
    refined = maps.refine(FORCED, grid, maps.period, step=4, **FORCED_RUN)
    full = maps.period(sweep.run(FORCED, grid, **FORCED_RUN))
    assert_islands(refined, full)
    # 6 of 1089 cells measured (0.55 %): a coarse map of a fractal, where single cells
    # inside 3 x 3 blocks whose 8 neighbours agree are filled; 1 % bounds it
    assert (refined.values != full.values).mean() <= 0.01
    assert refined.attrs["pilot_cells"] == 0


@pytest.mark.parametrize("grid, match", [
    (sweep.Grid(theta0=np.linspace(0, 1, 5)), "exactly two axes of more than one value"),
    (sweep.Grid(theta0=[0.0, 1.0], omega0=[0.0, 1.0], damping=[0.1, 0.2]),
     "exactly two axes of more than one value"),
    (sweep.Grid(theta0=[0.0, 1.0], omega0=[0.5]), "exactly two axes of more than one"),
])
def test_grid_not_2d_is_refused_before_compute(no_compute, grid, match):
    with pytest.raises(ValueError, match=match):
        maps.refine(DAMPED, grid, maps.well, **DAMPED_RUN)


@pytest.mark.parametrize("kwargs, match", [
    (dict(label=3), r"label must be a map function or the name of a data variable, got 3"),
    (dict(label=None), "label must be a map function"),
    (dict(label="welll"), r"label = 'welll' is not a variable of this run; accepted: "
                          r"'well', 'capture_time', 'status'"),
    (dict(label=functools.partial(maps.basins, rest=True)), r"label = .*rest"),
    (dict(label=functools.partial(maps.basins, tol=-1.0)), "tol must be"),
    (dict(step=1), "step must be an int >= 2"),
    (dict(step=8.0), "step must be an int >= 2"),
    (dict(step="16"), "step must be an int >= 2"),
    (dict(pilot=1), "pilot must be None or an int >= 2"),
    (dict(checkpoint="somewhere"), "cannot use checkpoint"),
])
def test_bad_arguments_are_refused_before_compute(no_compute, kwargs, match):
    kwargs = {"label": maps.well, **kwargs}
    with pytest.raises(ValueError, match=match):
        maps.refine(DAMPED, DAMPED_GRID, **kwargs, **DAMPED_RUN)


def test_points_and_other_objects_are_refused(no_compute):
    points = sweep.grid.Points(theta0=[0.0, 1.0], omega0=[0.0, 1.0])
    with pytest.raises(ValueError, match="got Points"):
        maps.refine(DAMPED, points, maps.well, **DAMPED_RUN)
    with pytest.raises(ValueError, match=r"scene must be a sweep\.Scene"):
        maps.refine("scene", DAMPED_GRID, maps.well, **DAMPED_RUN)
    with pytest.raises(ValueError, match=r"got DoublePendulum; accepted: a sweep\.Scene "
                       r"\(sweep\.maps\.refine supports the single pendulum only"):
        maps.refine(sweep.DoublePendulum(), DAMPED_GRID, maps.well, **DAMPED_RUN)


def test_run_errors_come_from_the_probe_before_the_lattice(monkeypatch):
    """A label the run cannot give (basins of an unforced run without energy) fails on
    the one-trajectory probe, before the lattice is asked for."""
    import sys
    module = sys.modules["sweep.maps.refine"]  # the attribute sweep.maps.refine is refine
    monkeypatch.setattr(module, "refine_field", None)  # never reached
    with pytest.raises(ValueError, match="energy"):
        maps.refine(DAMPED, DAMPED_GRID, maps.basins, t_end=1.0, dt=0.02,
                    observe=("final",), progress=False)


# ------------------------------------------------------------------ run files and CLI
REFINE_RUN_FILE = """\
[scene]
gravity = 9.81
length = 1.0

[scene.damping]
coefficient = 0.25

[grid]
theta0 = {start = -3.141592653589793, stop = 3.141592653589793, num = 129}
omega0 = {start = -12.0, stop = 12.0, num = 129}

[run]
t_end = 40.0
dt = 0.02
observe = "capture"
stop_early = true
refine = true
"""


def sweep_cli(*argv):
    import contextlib
    import io

    from sweep import cli
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("extra, name", [("", "basins"),
                                         ('refine_label = "well"\nrefine_step = 8\n', "well")])
def test_run_file_with_refine(tmp_path, damped_full, extra, name):
    """``[run] refine = true``: sweep run writes the refined map (labels, the computed
    mask, the counts), which is maps.refine's, read back from the file."""
    path = tmp_path / "run.toml"
    path.write_text(REFINE_RUN_FILE + extra)
    code, out, err = sweep_cli("run", path, "-o", tmp_path / "map.nc", "--no-progress")
    assert code == 0, err
    assert f"refined {name} map (theta0 129 x omega0 129)" in out and "computed" in out
    saved = sweep.load(tmp_path / "map.nc")
    label = getattr(maps, name)
    step = 8 if extra else 16
    want = maps.refine(DAMPED, DAMPED_GRID, label, step=step, **DAMPED_RUN)
    np.testing.assert_array_equal(saved[name].values, want.values)
    np.testing.assert_array_equal(saved["computed"].values, want["computed"].values)
    assert saved[name].attrs["cells_computed"] == want.attrs["cells_computed"]
    np.testing.assert_array_equal(want.values, label(damped_full).values)


@pytest.mark.parametrize("extra, match", [
    ("refine_step = 1\n", "refine_step must be an int >= 2"),
    ("refine = 3\n", "refine"),
])
def test_run_file_refine_errors(tmp_path, extra, match):
    path = tmp_path / "run.toml"
    text = REFINE_RUN_FILE.replace("refine = true\n", "") if "refine =" in extra \
        else REFINE_RUN_FILE
    path.write_text(text + extra)
    code, _out, err = sweep_cli("run", path, "-o", tmp_path / "map.nc")
    assert code != 0 and match in err
    assert not (tmp_path / "map.nc").exists()


def test_refine_keys_need_refine(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text(REFINE_RUN_FILE.replace("refine = true\n", "refine_step = 8\n"))
    code, _out, err = sweep_cli("run", path, "-o", tmp_path / "map.nc")
    assert code != 0 and "refine_step is for refine = true" in err
