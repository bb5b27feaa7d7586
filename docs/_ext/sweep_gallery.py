"""How the gallery runs the examples: their arguments, and their figures.

Each example is a script with ``--out FOLDER`` (and ``--size`` or the like where it is
large). sphinx-gallery executes it in-process; :func:`reset_argv` gives it a small size
and a fresh output folder under ``docs/_build/gallery-output/``, and
:func:`png_scraper` puts the PNG files it wrote into the page (the examples save their
figures with ``sweep.plot.save_figure``, which closes them, so matplotlib's own scraper
finds none).
"""

from __future__ import annotations

import ast
import shutil
from pathlib import Path

OUTPUT = Path(__file__).resolve().parents[1] / "_build" / "gallery-output"

#: Arguments per example: sizes chosen so that the whole gallery builds in a few minutes
#: on 2 cores. An example missing here runs at its defaults (tests/test_docs.py checks
#: that every example of examples/ is listed).
ARGUMENTS = {
    "basin_stability": ["--samples", "2048"],
    "continuation": ["--size", "11"],
    "damped_basins": ["--size", "161"],
    "double_pendulum_flip": ["--size", "121", "--t-max", "30"],
    "forced_basins": ["--size", "61", "--periods", "100", "--pilot", "21"],
    "frequency_response": ["--points", "41"],
    "huygens_clocks": ["--size", "61"],
    "kapitza": ["--size", "41"],
    "lyapunov_map": ["--size", "41"],
    "mathieu_chart": ["--size", "61"],
    "orbit_diagram": ["--size", "41"],
    "rotation_map": ["--size", "61"],
    "seed_cases": [],
    "swing_basin_stability": ["--samples", "40"],
    "torque_locked_running": ["--size", "61"],
}

#: Examples that print their results and write no file (no ``--out``).
PRINTS_ONLY = {"basin_stability"}

_shown: dict[Path, set[Path]] = {}


def _output(src_file) -> Path:
    return OUTPUT / Path(src_file).stem


def reset_argv(gallery_conf, script_vars) -> list[str]:
    """The example's command-line arguments in the gallery.

    Also gives the script the ``__doc__`` and ``__file__`` it has when run as a script
    (sphinx-gallery sets neither; the examples' parsers take their description from the
    docstring, and ``seed_cases.py`` finds its default folder from ``__file__``).
    """
    src = Path(script_vars["src_file"])
    script_vars["example_globals"].update(
        __doc__=ast.get_docstring(ast.parse(src.read_text()), clean=False) or "",
        __file__=str(src))
    out = _output(script_vars["src_file"])
    shutil.rmtree(out, ignore_errors=True)
    _shown[out] = set()
    name = Path(script_vars["src_file"]).stem
    return [*ARGUMENTS.get(name, []), *([] if name in PRINTS_ONLY else ["--out", str(out)])]


def png_scraper(block, block_vars, gallery_conf) -> str:
    """The PNG files the example wrote since the last code block, as reST images."""
    from sphinx_gallery.scrapers import figure_rst

    out = _output(block_vars["src_file"])
    shown = _shown.setdefault(out, set())
    new = sorted(p for p in out.rglob("*.png") if p not in shown) if out.is_dir() else []
    images = []
    for png, target in zip(new, block_vars["image_path_iterator"]):
        shutil.copyfile(png, target)
        shown.add(png)
        images.append(target)
    return figure_rst(images, gallery_conf["src_dir"])
