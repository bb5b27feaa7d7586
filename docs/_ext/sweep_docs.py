"""Pages of the documentation that are written from the code at build time.

``docs/conf.py`` calls :func:`generate` before Sphinx reads any source, so that

- the API reference (``docs/api/``) lists every name in the ``__all__`` of the modules
  in :data:`API_MODULES`, through autosummary stubs that autodoc fills from the
  (numpydoc) docstrings: nothing in it is copied by hand;
- the command-line reference (``docs/api/cli.rst``) is the help text of
  ``sweep.cli.build_parser()``, the parser ``sweep`` itself runs, for ``sweep --help`` and
  each command's ``--help``;
- the table of effects and parameters (``docs/guide/_generated/parameter_table.md``) is
  ``sweep.physics.parameter_table()``, written from the effects' declarations.

Everything written here is ignored by git (``docs/.gitignore``). ``tests/test_docs.py``
checks these sources without Sphinx: every public name, every command and the table.
This module imports no Sphinx, so that the test can import it without the docs extra.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import shutil
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]

#: (module, page title, one line on what it holds): the modules whose ``__all__`` the
#: reference lists, in the order of the reference's table of contents.
API_MODULES = (
    ("sweep", "sweep: scenes, grids, runs, files",
     "The names most code needs, importable from the package itself."),
    ("sweep.maps", "sweep.maps: labelled maps of a run",
     "Pure functions ``Dataset -> DataArray`` (they never re-run the integrator), the "
     "attractor catalogue, continuation, fractions and adaptive refinement."),
    ("sweep.plot", "sweep.plot: figures",
     "Maps, basins, orbit diagrams, trajectories and work-precision diagrams "
     "(matplotlib, imported only here)."),
    ("sweep.physics", "sweep.physics: effects and their declarations",
     "The scene, the effects, and what an effect declares (its parameters, its term, "
     "its Jacobian); see :doc:`../guide/extending`."),
    ("sweep.methods", "sweep.methods: integrators as data",
     "Butcher tableaux and splitting methods, validated on construction."),
    ("sweep.maps.metrics", "sweep.maps.metrics: basin metrics",
     "Basin fractions, basin entropy, the uncertainty exponent and the box-counting "
     "dimension of any integer label array."),
    ("sweep.maps.response", "sweep.maps.response: frequency responses",
     "Up and down frequency sweeps by continuation."),
    ("sweep.accuracy", "sweep.accuracy: exact references and work-precision",
     "Exact solutions (Jacobi elliptic functions, closed forms), observed orders and "
     "work-precision datasets."),
    ("sweep.map_precision", "sweep.map_precision: a map's work-precision",
     "The labels of a map's starts under a ladder of settings against its most accurate "
     "run, and what each setting costs (``sweep.map_accuracy``)."),
    ("sweep.io", "sweep.io: files and provenance",
     "netCDF files and the attributes that reproduce a run."),
    ("sweep.distributed", "sweep.distributed: grids larger than memory",
     "Runs on a Dask cluster written to netCDF block by block."),
)

#: The modules every public name of which must appear (the issue's list).
REQUIRED_MODULES = ("sweep", "sweep.maps", "sweep.plot", "sweep.physics", "sweep.methods")

#: Width of the command-line help in the reference (argparse reads $COLUMNS).
HELP_COLUMNS = 90


def public_names(module_name: str) -> list[str]:
    """The names in ``module.__all__``, in its order."""
    return list(importlib.import_module(module_name).__all__)


def _underline(title: str, char: str = "=") -> str:
    return f"{title}\n{char * len(title)}\n"


def documented_elsewhere(module_name: str) -> dict[str, str]:
    """``{name: where}`` for the names of ``module_name.__all__`` that are the very objects
    an earlier module of :data:`API_MODULES` documents (``sweep.physics.Damping`` is
    ``sweep.Damping``): autodoc would describe one object twice, so the later page links
    to the earlier one."""
    module = importlib.import_module(module_name)
    seen = {}
    for earlier, _, _ in API_MODULES:
        if earlier == module_name:
            break
        other = importlib.import_module(earlier)
        for name in other.__all__:
            obj = getattr(other, name)
            if isinstance(obj, type) or callable(obj):
                seen.setdefault(id(obj), f"{earlier}.{name}")
    found = {}
    for name in module.__all__:
        obj = getattr(module, name)
        if (isinstance(obj, type) or callable(obj)) and id(obj) in seen:
            found[name] = seen[id(obj)]
    return found


def api_page(module_name: str, title: str, summary: str) -> str:
    """The reST page of one module: its docstring and an autosummary of its ``__all__``
    (names documented on an earlier page are linked to it)."""
    elsewhere = documented_elsewhere(module_name)
    lines = [
        f".. This page is written by docs/_ext/sweep_docs.py from {module_name}.__all__;",
        "   edit the module, not this file.",
        "",
        _underline(title),
        summary,
        "",
        f".. automodule:: {module_name}",
        "   :no-members:",
        "",
        f".. currentmodule:: {module_name}",
        "",
        ".. autosummary::",
        "   :toctree: stubs",
        "",
    ]
    lines += [f"   {name}" for name in public_names(module_name) if name not in elsewhere]
    if elsewhere:
        lines += ["", f"Also in ``{module_name}``, the same objects as documented under:", ""]
        lines += [f"- ``{module_name}.{name}``: :obj:`{where}`"
                  for name, where in elsewhere.items()]
    return "\n".join(lines) + "\n"


def api_index() -> str:
    """The reference's front page: one entry per module, then the command line."""
    pages = "\n".join(f"   {name}" for name, _, _ in API_MODULES)
    return f"""\
.. This page is written by docs/_ext/sweep_docs.py; edit that file, not this one.

{_underline("API reference")}
Generated from the docstrings (numpydoc) of every name in the ``__all__`` of the modules
below, and from the ``sweep`` command's own argument parser. The user guide explains
how the pieces fit; this reference says what each one accepts and returns.

.. toctree::
   :maxdepth: 1

{pages}
   cli
"""


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:                      # argparse keeps them nowhere else
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


@contextlib.contextmanager
def _columns(width: int):
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)
    try:
        yield
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def cli_help() -> dict[str, str]:
    """``{"sweep": top-level help, "sweep run": its help, ...}`` from the real parser."""
    from sweep.cli import build_parser

    with _columns(HELP_COLUMNS):
        parser = build_parser()
        helps = {"sweep": parser.format_help()}
        for name, sub in _subcommands(parser).items():
            helps[f"sweep {name}"] = sub.format_help()
    return helps


def cli_page() -> str:
    """The reST page of the command line: each command's ``--help``, verbatim."""
    parts = [
        ".. This page is written by docs/_ext/sweep_docs.py from sweep.cli.build_parser().",
        "",
        _underline("Command line: sweep"),
        "The help of the ``sweep`` command and of each of its commands, as ``--help`` prints "
        "it (taken from ``sweep.cli.build_parser()`` when the site is built). The user "
        "guide's :doc:`../guide/cli` shows them at work.",
        "",
    ]
    for command, text in cli_help().items():
        flag = f"``{command} --help``"
        parts += [_underline(command, "-"), flag + "::", ""]
        parts += [("    " + line).rstrip() for line in text.rstrip("\n").splitlines()]
        parts.append("")
    return "\n".join(parts) + "\n"


def parameter_table() -> str:
    """The table of effects and parameters (Markdown), from the declarations."""
    import sweep.physics

    return sweep.physics.parameter_table()


def sources() -> dict[Path, str]:
    """Every generated file (path relative to ``docs/``) and its text."""
    files = {Path("api/index.rst"): api_index(), Path("api/cli.rst"): cli_page()}
    for name, title, summary in API_MODULES:
        files[Path("api") / f"{name}.rst"] = api_page(name, title, summary)
    files[Path("guide/_generated/parameter_table.md")] = parameter_table()
    return files


def generate(docs: Path = DOCS) -> list[Path]:
    """Write :func:`sources` under ``docs``; files whose text is unchanged are left alone
    (so Sphinx does not re-read them)."""
    # autosummary writes a stub per listed name into api/stubs and never removes one:
    # start from none, so that a name dropped from an __all__ leaves no page behind
    stubs = docs / "api" / "stubs"
    if stubs.is_dir():
        shutil.rmtree(stubs)
    written = []
    for relative, text in sources().items():
        path = docs / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)
            written.append(path)
    return written
