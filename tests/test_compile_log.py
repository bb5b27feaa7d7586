"""tests/compile_log.py's summary (the SWEEP_COMPILE_LOG plugin's reader): what it
counts from the per-worker logs, on logs written here (nothing is compiled)."""

import json
from pathlib import Path

import compile_log


def _log(path, rows):
    path.write_text("".join(json.dumps(row) + "\n" for row in rows))
    return str(path)


def _compile(test, spec, cpu, function="sweep_kernel_x.blocks", args="(float64,)"):
    return {"test": test, "function": function, "spec": spec, "seconds": 2 * cpu,
            "cpu": cpu, "args": args}


def test_functions_compiled_by_more_than_one_worker_are_counted_with_the_later_copies(
        tmp_path, capsys):
    """A kernel both workers compiled (1.5 s and 1.0 s of CPU: all but its cheapest copy
    is 1.5 s), one each compiled alone, and one compiled twice in one worker (as by a
    test that empties the memo): one function by more than one process, 1.5 s."""
    gw0 = _log(tmp_path / "compile.gw0.jsonl", [
        _compile("a.py::t", "Spec(shared)", 1.5), _compile("a.py::t", "Spec(alone)", 2.0),
        _compile("a.py::u", "Spec(again)", 0.5), _compile("a.py::v", "Spec(again)", 0.5)])
    gw1 = _log(tmp_path / "compile.gw1.jsonl", [
        _compile("b.py::t", "Spec(shared)", 1.0), _compile("b.py::t", "Spec(other)", 3.0),
        _compile("b.py::t", "Spec(shared)", 0.25, function="sweep_kernel_x.accel")])
    rows = [dict(json.loads(line), log=path) for path in (gw0, gw1)
            for line in Path(path).read_text().splitlines()]
    assert compile_log._compiled_by_several(rows) == (1, 1.5)
    compile_log._summary([gw0, gw1])
    assert "1 compiled by more than one process" in capsys.readouterr().out
