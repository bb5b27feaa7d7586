"""The built-in systems' shipped derivations (`sweep.physics.shipped`): each equals a
fresh SymPy derivation, and a built-in needs no SymPy."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

from sweep.physics import derive as derive_module
from sweep.physics import shipped

pytest.importorskip("sympy")


def test_every_shipped_file_is_a_fresh_derivation_and_no_other_file_is_there():
    expected = set()
    for declaration, jacobian in shipped.built_ins():
        path = shipped.path_of(declaration, jacobian)
        expected.add(path.name)
        assert path.is_file(), f"{path.name} ({declaration.name}, jacobian={jacobian}) " \
                               "missing: run python -m sweep.physics.shipped"
        stored = json.loads(path.read_text(encoding="utf-8"))
        fresh = derive_module._derive_now(declaration, jacobian)
        # exact equality: a shipped file must be what this version derives, line by line
        assert stored["derive_version"] == derive_module.DERIVE_VERSION
        assert stored["declaration"] == repr(declaration)
        assert stored["jacobian"] is jacobian
        assert tuple(stored["accel_lines"]) == fresh.accel_lines, path.name
        assert tuple(stored["energy_lines"]) == fresh.energy_lines, path.name
        assert tuple(stored["jacobian_lines"]) == fresh.jacobian_lines, path.name
    assert len(expected) == len(shipped.built_ins()) == 28
    assert {p.name for p in shipped.FOLDER.glob("*")} == expected


def test_a_built_in_derives_without_sympy_and_a_larger_one_says_it_needs_it(tmp_path):
    """In a process where ``import sympy`` fails and with an empty kernel cache, the
    shipped double pendulum and coupled pendula derive (the same lines as here); five
    coupled pendula, not shipped, raise the ImportError that names SymPy."""
    script = textwrap.dedent("""
        import json, sys
        sys.modules["sympy"] = None  # import sympy raises ImportError
        from sweep.physics.derive import derive
        from sweep.physics.systems import coupled_pendula, double_pendulum
        out = {}
        for name, decl in (("double", double_pendulum(damping=True, pivot=True)),
                           ("ring", coupled_pendula(4, "torsion", "ring"))):
            out[name] = list(derive(decl, jacobian=True).accel_lines)
        try:
            derive(coupled_pendula(5))
        except ImportError as error:
            out["error"] = str(error)
        print(json.dumps(out))
    """)
    env = {**os.environ, "SWEEP_CACHE_DIR": str(tmp_path / "cache")}
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=env, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    from sweep.physics.systems import coupled_pendula, double_pendulum
    assert out["double"] == list(derive_module._derive_now(
        double_pendulum(damping=True, pivot=True), True).accel_lines)
    assert out["ring"] == list(derive_module._derive_now(
        coupled_pendula(4, "torsion", "ring"), True).accel_lines)
    assert "SymPy" in out["error"]
    assert not list((tmp_path / "cache").rglob("system_*.json"))  # nothing derived there
