"""Sphinx configuration of sweep's documentation.

Build (offline; warnings are errors), from the repository root::

    pip install -e ".[docs]"
    python -m sphinx -W --keep-going -b html docs docs/_build/html

then open ``docs/_build/html/index.html``. Nothing is fetched at build time: no
intersphinx, no remote images, and the theme's assets ship with it.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import sweep_docs  # noqa: E402

import sweep  # noqa: E402

# The API reference, the command-line reference and the table of parameters are written
# from the code before Sphinx reads any source (see docs/_ext/sweep_docs.py).
sweep_docs.generate(DOCS)

project = "sweep"
author = "the sweep developers"
copyright = "the sweep developers"
release = sweep.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build", "guide/_generated", "**/_generated"]
# The docstrings' References sections are bibliographies (numpydoc renames their labels
# per docstring), and seed_cases.py's sources are footnotes its code comments cite: an
# entry cited nowhere in the rendered text is not an error here.
suppress_warnings = ["ref.citation", "ref.footnote"]

# -- API reference: autodoc + autosummary + numpydoc --------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"          # the numpydoc sections give the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False  # the class template lists the members itself
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- Markdown pages (the user guide, the changelog) ----------------------------------
myst_heading_anchors = 3
myst_enable_extensions = ["deflist"]

# -- The gallery: every script in examples/, run at a small size ---------------------
# The examples are ordinary scripts (`python examples/NAME.py --size N --out DIR`); the
# gallery runs each one with the arguments below (docs/_ext/sweep_gallery.py) and shows
# the PNG files it writes.
sphinx_gallery_conf = {
    "examples_dirs": ["../examples"],
    "gallery_dirs": ["gallery"],
    "filename_pattern": r"\.py$",            # run every example, not only plot_*.py
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "FileNameSortKey",
    "reset_argv": "sweep_gallery.reset_argv",
    "image_scrapers": ("matplotlib", "sweep_gallery.png_scraper"),
    "capture_repr": (),
    "show_memory": False,
    "download_all_examples": False,
    "remove_config_comments": True,
}

# -- HTML ------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"sweep {release}"
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version", "theme-version"],
}
html_show_sourcelink = False


# -- Constants ---------------------------------------------------------------------------
def _constant_docstring(app, what, name, obj, options, lines):
    """A module constant without a docstring of its own (``NO_PERIOD = -1``, ``METHODS``)
    would show its type's docstring ("int([x]) -> integer"): show its value instead."""
    import inspect

    own = inspect.getdoc(type(obj))
    if what not in ("data", "attribute") or not own or "\n".join(lines).strip() != own.strip():
        return
    text = repr(obj)
    lines[:] = ([f"The constant ``{text}``."] if len(text) <= 60 else
                [f"A ``{type(obj).__name__}``; the module's description says what it holds."])


def setup(app):
    app.connect("autodoc-process-docstring", _constant_docstring, priority=100)
