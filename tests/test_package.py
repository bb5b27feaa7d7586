"""Package hygiene: a cheap import, one place for JIT flags, a public surface that exists."""

import pathlib
import re
import subprocess
import sys

import sweep

ROOT = pathlib.Path(sweep.__file__).parent


def test_import_compiles_nothing_and_loads_no_matplotlib():
    code = ("import sys, sweep; "
            "print('numba' in sys.modules, 'matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False"]


def test_jit_flags_live_only_in_config():
    for path in ROOT.rglob("*.py"):
        if path.name == "_config.py":
            continue
        text = path.read_text()
        assert "fastmath=" not in text, path
        assert "boundscheck=" not in text, path


def test_public_names_exist():
    for name in sweep.__all__:
        assert hasattr(sweep, name), name


def test_plot_module_is_reachable_lazily():
    # DESIGN: `import sweep; sweep.plot.map(...)` works, and matplotlib loads only
    # when a figure is drawn
    code = ("import sys, sweep; print(callable(sweep.plot.map)); "
            "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["True", "False"]


def test_no_install_hint_names_the_distribution_sweep():
    # "sweep" on PyPI is SWeeP, an unrelated project that also installs a package named
    # sweep (docs/guide/install.md): pip install sweep, or 'sweep[dask]', would replace
    # this package. The distribution is sweep-pendulum; extras are named by what they hold.
    hint = re.compile(r"pip install\s+(-e\s+)?[\"']?sweep(\[|[\"'\s)]|$)", re.MULTILINE)
    repository = ROOT.parent
    found = []
    for folder in ("sweep", "docs", "examples", ".ci"):
        for path in (repository / folder).rglob("*"):
            if path.suffix in (".py", ".md", ".rst", ".toml", ".sh", "") and path.is_file() \
                    and "_build" not in path.parts:
                found += [f"{path}: {m.group(0)!r}" for m in hint.finditer(path.read_text())]
    assert found == []
