"""The documentation's generated parts cover the code, so that they cannot go stale.

The site (``docs/``, built by ``.ci/run`` with ``python -m sphinx -W --keep-going -b html
docs docs/_build/html``) writes its API reference, its command-line reference and its
table of parameters from the code at build time (``docs/_ext/sweep_docs.py``), and its
gallery runs every script of ``examples/`` (``docs/_ext/sweep_gallery.py``). These tests
check those sources without Sphinx (they need no docs extra): every public name has an
entry, every command its help, every example its gallery arguments and a title, every
guide page a place in the table of contents, and every link of the README a target.
"""

from __future__ import annotations

import ast
import importlib.util
import re
import sys
from pathlib import Path

import pytest

import sweep
import sweep.physics

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _load(name):
    path = DOCS / "_ext" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_docs_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def docs():
    return _load("sweep_docs")


@pytest.fixture(scope="module")
def sources(docs):
    return {str(path): text for path, text in docs.sources().items()}


def _autosummary_entries(page: str) -> set[str]:
    """The names listed under the page's autosummary directive."""
    block = page.split(".. autosummary::", 1)[1]
    return {line.strip() for line in block.splitlines()
            if line.startswith("   ") and not line.strip().startswith(":")} - {""}


def _linked_elsewhere(page: str) -> set[str]:
    return set(re.findall(r"^- ``[\w.]+\.(\w+)``: :obj:`[\w.]+`$", page, re.MULTILINE))


@pytest.mark.parametrize("module_name", ["sweep", "sweep.maps", "sweep.plot",
                                         "sweep.physics", "sweep.methods"])
def test_every_public_name_is_in_the_reference(docs, sources, module_name):
    assert module_name in docs.REQUIRED_MODULES
    page = sources[f"api/{module_name}.rst"]
    module = importlib.import_module(module_name)
    documented = _autosummary_entries(page)
    linked = _linked_elsewhere(page)
    assert documented.isdisjoint(linked)
    assert set(module.__all__) == documented | linked, module_name
    # a name linked to another page is documented there, as the very same object
    for name in linked:
        where = re.search(rf"^- ``{re.escape(module_name)}\.{name}``: :obj:`([\w.]+)`$",
                          page, re.MULTILINE).group(1)
        home, _, attribute = where.rpartition(".")
        assert getattr(importlib.import_module(home), attribute) is getattr(module, name)
        assert attribute in _autosummary_entries(sources[f"api/{home}.rst"])


def test_the_reference_index_lists_every_module_page(docs, sources):
    index = sources["api/index.rst"]
    for name, _, _ in docs.API_MODULES:
        assert f"\n   {name}\n" in index
        assert f"api/{name}.rst" in sources
    assert "\n   cli\n" in index
    assert set(docs.REQUIRED_MODULES) <= {name for name, _, _ in docs.API_MODULES}


def test_the_cli_reference_is_every_commands_help(docs, sources):
    from sweep.cli import build_parser

    helps = docs.cli_help()
    commands = set(docs._subcommands(build_parser()))
    assert {"run", "demo", "plot", "explore"} <= commands
    assert set(helps) == {"sweep"} | {f"sweep {name}" for name in commands}
    page = sources["api/cli.rst"]
    for command, text in helps.items():
        assert text.startswith(f"usage: {command}")
        block = "\n".join(("    " + line).rstrip() for line in text.rstrip().splitlines())
        assert block in page, command


def test_the_parameter_table_is_the_declarations(sources):
    table = sources["guide/_generated/parameter_table.md"]
    assert table == sweep.physics.parameter_table()
    for cls in sweep.physics.EFFECTS.values():
        assert f"| `{cls.__name__}` |" in table
        for parameter in cls.declaration.parameters:
            assert f"`{parameter.axis}`" in table
    # each row keeps the header's 7 columns (a "|" inside a cell is escaped)
    for row in table.splitlines():
        assert len(re.split(r"(?<!\\)\|", row)) == 9, row
    scenes = (DOCS / "guide" / "scenes.md").read_text()
    assert "```{include} _generated/parameter_table.md\n```" in scenes


def test_every_example_runs_in_the_gallery_with_a_title():
    gallery = _load("sweep_gallery")
    scripts = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
    assert scripts and set(scripts) == set(gallery.ARGUMENTS)
    assert set(scripts) >= gallery.PRINTS_ONLY
    for name in scripts:
        source = (ROOT / "examples" / f"{name}.py").read_text()
        tree = ast.parse(source)
        lines = ast.get_docstring(tree, clean=False).splitlines()
        # sphinx-gallery's page title: the docstring's first line, underlined with "="
        assert lines[1] == "=" * len(lines[1]) and len(lines[1]) >= len(lines[0]), name
        # sphinx-gallery runs the script in-process, so it must not raise SystemExit
        assert "raise SystemExit" not in source and "sys.exit(" not in source, name
    assert (ROOT / "examples" / "GALLERY_HEADER.rst").is_file()


def test_every_guide_page_is_in_the_table_of_contents():
    guide = DOCS / "guide"
    index = (guide / "index.md").read_text()
    listed = set(re.findall(r"^(\w+)$", index, re.MULTILINE))
    pages = {p.stem for p in guide.glob("*.md")} - {"index"}
    assert pages == listed
    root = (DOCS / "index.rst").read_text()
    for entry in ("guide/index", "api/index", "gallery/index", "changelog"):
        assert f"   {entry}\n" in root


def test_the_readme_links_resolve_and_the_quick_start_is_two_commands():
    readme = (ROOT / "README.md").read_text()
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme)
    assert len(targets) >= 15
    for target in targets:
        assert not target.startswith("http"), target
        assert (ROOT / target).exists(), target
    quick = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)\n```", quick, re.DOTALL)
    assert commands == ['pip install -e . && sweep demo', 'pip install -e ".[test]" && pytest']


@pytest.mark.parametrize("page", ["guide/systems.md", "guide/extending.md"])
def test_the_guide_names_what_the_expression_parser_accepts(page):
    # The sentence "read from Python's syntax tree ..." lists the functions and constants;
    # the parser's refusal ("accepted: ...") names the same.
    from sweep.physics.derive import FUNCTIONS

    text = (DOCS / page).read_text(encoding="utf-8")
    sentence = text.split("read from Python's syntax tree")[1].split("declared names")[0]
    for name in (*FUNCTIONS, "pi", "t"):
        assert f"`{name}`" in sentence, (page, name)
    with pytest.raises(ValueError) as refused:
        sweep.DeclaredSystem(sweep.physics.SystemDeclaration(
            name="test_accepted_names",
            coordinates=(sweep.physics.Coordinate("theta", "omega", "q", "w"),),
            parameters=(), lagrangian="w**2/2 + tan(q)"))
    message = str(refused.value)
    for name in (*FUNCTIONS, "pi"):
        assert name in message.split("accepted:")[1], name
