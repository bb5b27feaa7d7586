"""Bad run files through the ``sweep run`` command (in-process, `sweep.cli.main`).

Each case: exit status 2, nothing on stdout, exactly one ``sweep: error:`` line on
stderr that names the offending parameter, no traceback, no output file created, and
an output file that already exists left byte-identical.
"""

import contextlib
import io
from pathlib import Path

import pytest

# the valid run file of test_cli, which each case below breaks in one place
from test_cli import RUN_FILE as GOOD

from sweep import cli


def _edit(old, new):
    assert old in GOOD, old
    return GOOD.replace(old, new)


# label -> (run-file text, or a callable folder -> path of the run file; words the one
# stderr line must contain: the parameter it names)
CASES = {
    "malformed TOML": ("[grid\ntheta0 = 1\n", "not valid TOML"),
    "not TOML at all": ("\x00\x01 binary", "not valid TOML"),
    "unknown table": (GOOD + "\n[plot]\ncmap = 'x'\n", "plot"),
    "unknown [run] key": (_edit("dt =", "step ="), "step"),
    "unknown [scene] key": (_edit("gravity =", "gravty ="), "gravty"),
    "unknown grid axis": (_edit("omega0 =", "omega =") , "omega"),
    "unknown effect key": (_edit("coefficient", "coef"), "coef"),
    "string gravity": (_edit("gravity = 9.81", 'gravity = "9.81"'), "gravity"),
    "nan length": (_edit("length = 1.0", "length = nan"), "length"),
    "inf dt": (_edit("dt = 0.05", "dt = inf"), "dt"),
    "negative length": (_edit("length = 1.0", "length = -1.0"), "length"),
    "zero gravity": (_edit("gravity = 9.81", "gravity = 0.0"), "gravity"),
    "negative damping": (_edit("coefficient = 0.3", "coefficient = -0.3"), "coefficient"),
    "unknown model": (_edit('model = "nonlinear"', 'model = "quadratic"'), "model"),
    "empty axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = []"), "omega0"),
    "2-D axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = [[1.0, 2.0], [3.0, 4.0]]"),
                 "omega0"),
    "nan in axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = [0.0, nan]"), "omega0"),
    "string axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", 'omega0 = "fast"'), "omega0"),
    "bad units": (_edit('units = "deg"', 'units = "grad"'), "units"),
    "zero-point range": (_edit("num = 5", "num = 0"), "num"),
    "missing t_end": (_edit("t_end = 2.0\n", ""), "t_end"),
    "t_end equals t0": (_edit("t_end = 2.0", "t_end = 2.0\nt0 = 2.0"), "t_end"),
    "t_end before t0": (_edit("t_end = 2.0", "t_end = -1.0"), "t_end"),
    "zero dt": (_edit("dt = 0.05", "dt = 0.0"), "dt"),
    "dt not dividing the span": (_edit("dt = 0.05", "dt = 0.3"), "dt"),
    "t_transient too long": (_edit("dt = 0.05", "dt = 0.05\nt_transient = 5.0"),
                             "t_transient"),
    "unknown observable": (_edit('"energy"]', '"energie"]'), "energie"),
    "observe not a list": (_edit('observe = ["final", "winding", "energy"]', "observe = 3"),
                           "observe"),
    "unknown method": (_edit("dt = 0.05", 'dt = 0.05\nmethod = "rk5"'), "method"),
    "symplectic with damping": (_edit("dt = 0.05", 'dt = 0.05\nmethod = "verlet"'),
                                "verlet"),
    "float save_every": (_edit("dt = 0.05", "dt = 0.05\nsave_every = 2.5"), "save_every"),
    "unstable step (stiff damping)": (_edit("coefficient = 0.3", "coefficient = 200.0"),
                                      "stability limit"),
    # values that would convert silently into something nobody meant (issue 15)
    "boolean axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = [true, false]"), "omega0"),
    "boolean axis value": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = true"), "omega0"),
    "boolean in axis values": (_edit("omega0 = [-1.0, 0.0, 1.0]",
                                     "omega0 = {values = [0.0, true]}"),
                               "omega0"),
    "repeated axis value": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = [0.0, 1.0, 0.0]"),
                            "omega0' has the value 0.0 more than once (indices 0, 2)"),
    "range with repeated values": (_edit("start = -180, stop = 180, num = 5",
                                         "start = 1, stop = 1, num = 3"),
                                   "theta0' has the value 0.017453292519943295 more than once"),
    "numeric string in axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", 'omega0 = ["1.0", 2.0]'),
                               "omega0"),
    "date as axis": (_edit("omega0 = [-1.0, 0.0, 1.0]", "omega0 = 1979-05-27"), "omega0"),
    "boolean range start": (_edit("start = -180", "start = true"), "theta0.start"),
    "float num": (_edit("num = 5", "num = 5.0"), "num"),
    "boolean units": (_edit('units = "deg"', "units = true"), "units"),
    "units in capitals": (_edit('units = "deg"', 'units = "DEG"'), "units"),
    "boolean gravity": (_edit("gravity = 9.81", "gravity = true"), "gravity"),
    "boolean damping coefficient": (_edit("coefficient = 0.3", "coefficient = false"),
                                    "coefficient"),
    "model in capitals": (_edit('model = "nonlinear"', 'model = "Nonlinear"'), "model"),
    "boolean t_end": (_edit("t_end = 2.0", "t_end = true"), "t_end"),
    "string dt": (_edit("dt = 0.05", 'dt = "0.05"'), "dt"),
    "date t0": (_edit("dt = 0.05", "dt = 0.05\nt0 = 1979-05-27"), "t0"),
    "method in capitals": (_edit("dt = 0.05", 'dt = 0.05\nmethod = "RK4"'), "method"),
    "observe as one comma string": (
        _edit('observe = ["final", "winding", "energy"]', 'observe = "final, winding"'),
        "observe"),
    "boolean in observe": (_edit('observe = ["final", "winding", "energy"]',
                                 'observe = ["final", true]'), "observe"),
    "boolean save_every": (_edit("dt = 0.05", "dt = 0.05\nsave_every = true"), "save_every"),
    "boolean chunk_size": (_edit("dt = 0.05", "dt = 0.05\nchunk_size = true"), "chunk_size"),
    "stop_early as a number": (_edit("dt = 0.05", "dt = 0.05\nstop_early = 1"),
                               "stop_early"),
    "check_stability as a string": (_edit("dt = 0.05", 'dt = 0.05\ncheck_stability = "no"'),
                                    "check_stability"),
    "boolean estimate_error": (_edit("dt = 0.05", "dt = 0.05\nestimate_error = true"),
                               "estimate_error"),
    "run file is a folder": (lambda d: _folder(d), "run.toml"),
    "missing run file": (lambda d: d / "missing.toml", "missing.toml"),
}


def _folder(folder: Path) -> Path:
    # chmod 000 does not stop root from reading, so unreadability is a directory
    path = folder / "run.toml"
    path.mkdir()
    return path


def _call(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def _run_file(folder: Path, spec) -> Path:
    if callable(spec):
        return spec(folder)
    path = folder / "run.toml"
    path.write_text(spec, encoding="utf-8")
    return path


def test_the_good_file_runs(tmp_path):
    path = _run_file(tmp_path, GOOD)
    code, _, err = _call("run", path, "-o", tmp_path / "out.nc")
    assert code == 0, err
    assert (tmp_path / "out.nc").is_file()


def test_battery_is_large_enough():
    assert len(CASES) >= 15


@pytest.mark.parametrize("existing", [False, True], ids=["no output", "output exists"])
@pytest.mark.parametrize("label", list(CASES))
def test_bad_run_file_gives_one_line_status_2_and_touches_no_file(label, existing, tmp_path):
    spec, words = CASES[label]
    path = _run_file(tmp_path, spec)
    output = tmp_path / "out.nc"
    previous = b"previous results, not to be damaged\n"
    if existing:
        output.write_bytes(previous)
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = _call("run", path, "-o", output)
    assert code == 2, err
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("sweep: error: "), err
    assert words in err, err
    assert "Traceback" not in err
    if existing:
        assert output.read_bytes() == previous
    else:
        assert not output.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no stray files


def test_output_in_a_missing_folder_is_refused(tmp_path):
    path = _run_file(tmp_path, GOOD)
    output = tmp_path / "nowhere" / "out.nc"
    code, out, err = _call("run", path, "-o", output)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "nowhere" in err
    assert not output.parent.exists()


# Each error of an axis written as a table names the table the run file wrote:
# [points.theta0] (or [points] theta0.start) for a table of points, never [grid.theta0].
# label -> (the keys of theta0's table, as TOML, and the start of the error)
_AXIS_TABLE_ERRORS = {
    "values and a range": ({"start": "-180", "stop": "180", "num": "3",
                            "values": "[0.0, 1.0, 2.0]"},
                           "[{table}.theta0] gives both 'values' and 'start'"),
    "values not a list": ({"values": "3"},
                          "[{table}.theta0] values must be a list of numbers"),
    "range without num": ({"start": "-180", "stop": "180"},
                          "[{table}.theta0] missing key 'num'"),
    "zero num": ({"start": "-180", "stop": "180", "num": "0"},
                 "[{table}.theta0] num must be an integer >= 1, got 0"),
    "boolean start": ({"start": "true", "stop": "180", "num": "3"},
                      "[{table}] theta0.start must be a number, got True"),
    "bad units": ({"start": "-180", "stop": "180", "num": "3", "units": '"grad"'},
                  "[{table}.theta0] units must be one of 'rad', 'deg', got 'grad'"),
    "boolean in values": ({"values": "[0.0, true, 1.0]"},
                          "[{table}] theta0.values[1] must be a number, got True"),
    "unknown key": ({"values": "[0.0]", "step": "1"},
                    "unknown key 'step' in [{table}.theta0]"),
}


def _axis_table_file(table: str, keys: dict, inline: bool) -> str:
    """A run file whose [grid] or [points] gives theta0 as a table: inline
    (``theta0 = {...}``) or as the sub-table ``[TABLE.theta0]``."""
    if inline:
        axis, sub = f"theta0 = {{{', '.join(f'{k} = {v}' for k, v in keys.items())}}}\n", ""
    else:
        axis, sub = "", f"[{table}.theta0]\n" + "".join(f"{k} = {v}\n" for k, v in keys.items())
    return (f"[scene.damping]\ncoefficient = 0.3\n\n[{table}]\n{axis}"
            f"omega0 = [-1.0, 0.0, 1.0]\n{sub}\n[run]\nt_end = 2.0\ndt = 0.05\n")


@pytest.mark.parametrize("inline", [True, False], ids=["inline", "sub-table"])
@pytest.mark.parametrize("table", ["grid", "points"])
@pytest.mark.parametrize("label", list(_AXIS_TABLE_ERRORS))
def test_an_axis_table_error_names_the_table_the_file_wrote(label, table, inline, tmp_path,
                                                            no_compute):
    keys, words = _AXIS_TABLE_ERRORS[label]
    path = _run_file(tmp_path, _axis_table_file(table, keys, inline))
    code, out, err = _call("run", path, "-o", tmp_path / "out.nc")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith(f"sweep: error: {path}: ") and words.format(table=table) in err, err
    if table == "points":
        assert "grid" not in err, err


# ------------------------------------------------------------- the parser's errors
# label -> (argv after the run file's "run FILE" or the whole argv, words the one line
# must contain, words it must not contain)
_PARSER_ERRORS = {
    # a misspelled option is named, before the -o it leaves missing, with the nearest one
    "misspelled option": (["run", "{run}", "--outptu", "{out}"],
                          ["sweep run: unrecognized option --outptu; did you mean --output?"],
                          ["required"]),
    "unknown option, no near one": (["run", "{run}", "-o", "{out}", "--zzz"],
                                    ["unrecognized option --zzz (accepted: the options "
                                     "sweep run --help lists)"], ["did you mean"]),
    "invalid device": (["run", "{run}", "-o", "{out}", "--device", "gpu"],
                       ["--device", "'gpu'", "'cpu', 'cuda'"], []),
    "invalid dtype": (["run", "{run}", "-o", "{out}", "--dtype", "float16"],
                      ["--dtype", "'float16'", "'float64', 'float32'"], []),
    "missing output": (["run", "{run}"], ["sweep run: the following arguments are "
                                          "required: -o/--output"], []),
    "size not an integer": (["demo", "--size", "1e3", "-o", "{out}"],
                            ["--size", "'1e3'", "accepted: an integer"], []),
    "misspelled command": (["rnu", "{run}"], ["'rnu'", "did you mean run?"], []),
    # an extra positional: the command named, with what it takes
    "second run file": (["run", "{run}", "{run}", "-o", "{out}"],
                        ["sweep run: unrecognized arguments: ", "accepted: one RUN.toml "
                         "and the options sweep run --help lists"], []),
    "argument to demo": (["demo", "extra"],
                         ["sweep demo: unrecognized arguments: extra; accepted: no "
                          "argument but the options sweep demo --help lists"], []),
    # an abbreviation of several options is ambiguous, not unknown: argparse's words
    "ambiguous abbreviation": (["run", "{run}", "-o", "{out}", "--no"],
                               ["sweep run: ambiguous option: --no could match",
                                "--no-space-check", "--no-progress"],
                               ["unrecognized", "did you mean"]),
    "ambiguous abbreviation, required missing": (["run", "{run}", "--p"],
                                                 ["ambiguous option: --p could match",
                                                  "--pilot", "--progress"],
                                                 ["unrecognized", "--help"]),
    "no command": ([], ["required: COMMAND; accepted: run, demo, plot"], []),
}


@pytest.mark.parametrize("label", list(_PARSER_ERRORS))
def test_the_parsers_errors_are_one_line_naming_the_option(label, tmp_path, no_compute):
    argv, words, absent = _PARSER_ERRORS[label]
    run, out = _run_file(tmp_path, GOOD), tmp_path / "out.nc"
    code, stdout, err = _call(*(a.format(run=run, out=out) for a in argv))
    assert (code, stdout) == (2, ""), err
    assert err.count("\n") == 1 and err.startswith("sweep: error: "), err
    assert "usage:" not in err and "sweep run: error" not in err, err
    for word in words:
        assert word in err, err
    for word in absent:
        assert word not in err, err
    assert not out.exists()


def test_help_is_still_argparses(capsys):
    with pytest.raises(SystemExit) as info:  # argparse's --help exits; main returns it
        cli.build_parser().parse_args(["run", "--help"])
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith("usage: sweep run [-h] -o OUT.nc")
    code, out, err = _call("run", "--help")
    assert (code, err) == (0, "") and out.startswith("usage: sweep run [-h] -o OUT.nc")


# ------------------------------------------------------------- the output path
@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_an_unwritable_output_folder_is_named_not_taken_for_a_full_disk(tmp_path,
                                                                         no_compute):
    # root writes whatever the mode bits say (os.access agrees), so the folder is /proc,
    # where nobody creates a file
    code, out, err = _call("run", _run_file(tmp_path, GOOD), "-o", "/proc/out.nc")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith("sweep: error: output path '/proc/out.nc': folder '/proc' is not "
                          "writable"), err
    assert "disk space" not in err


def test_an_output_under_a_file_is_named(tmp_path, no_compute):
    (tmp_path / "notes").write_text("mine")
    code, out, err = _call("run", _run_file(tmp_path, GOOD), "-o", tmp_path / "notes" / "o.nc")
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert f"'{tmp_path / 'notes'}' is a file, not a folder" in err, err


@pytest.mark.parametrize("name", ["out.csv", "out", "out.nc.tmp"])
@pytest.mark.parametrize("command", ["run", "map-accuracy"])
def test_a_netcdf_output_must_end_in_nc(command, name, tmp_path, no_compute):
    extra = ["--ladder", "dt=0.1,0.05"] if command == "map-accuracy" else []
    output = tmp_path / name
    code, out, err = _call(command, _run_file(tmp_path, GOOD), "-o", output, *extra)
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    assert err.startswith(f"sweep: error: -o '{output}': the file is netCDF"), err
    assert err.rstrip().endswith("accepted: a file name ending in .nc"), err
    assert not output.exists()


# ------------------------------------------------------------- the pilot
FORCED = _edit("[grid]", "[scene.forcing]\namplitude = 1.66\nfrequency = 1.0\n\n[grid]") \
    .replace("t_end = 2.0\ndt = 0.05", "t_end = { periods = 4 }\ndt = { per_period = 20 }")


@pytest.mark.parametrize("observe, argv, words", [
    ('["final"]', [], ["pilot = 5 finds the attractors of a forced map from the "
                       "stroboscopic points", "observe is ['final']",
                       'accepted: observe = ["strobe"] with stop_early = true']),
    ('["final"]', ["--pilot", "7"], ["pilot = 7 finds the attractors", "['final']"]),
    ('["strobe", "final"]', [], ["pilot = 5: the pilot runs 5 x 5 starts with stop_early "
                                 "= true, and that run is refused", "'final'"]),
])
def test_a_pilot_without_strobe_is_refused_naming_the_pilot(observe, argv, words, tmp_path,
                                                             no_compute):
    text = FORCED.replace('observe = ["final", "winding", "energy"]',
                          f"observe = {observe}\npilot = 5")
    assert "pilot = 5" in text
    output = tmp_path / "out.nc"
    code, out, err = _call("run", _run_file(tmp_path, text), "-o", output, *argv)
    assert (code, out) == (2, "") and err.count("\n") == 1, err
    for word in words:
        assert word in err, err
    assert not output.exists()
