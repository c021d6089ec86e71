"""Sphinx configuration of pvcloth's documentation.

Build it (warnings are errors, as in the test suite):
``python -m sphinx -W --keep-going -b html docs docs/_build/html``
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

# The gallery's examples draw off-screen, and PyVista hands each plot to
# sphinx-gallery's scraper instead of showing it.
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
import pyvista  # noqa: E402

from pvcloth.visual.gl import use_offscreen_gl_if_headless  # noqa: E402

use_offscreen_gl_if_headless()
pyvista.OFF_SCREEN = True
pyvista.BUILDING_GALLERY = True
pyvista.set_plot_theme("document")

import pvcloth  # noqa: E402

project = "pvcloth"
author = "the pvcloth developers"
copyright = "2026, the pvcloth developers"
release = version = pvcloth.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
    "scene_keys",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "sweep/*.csv", "**/README.rst"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]
suppress_warnings = ["myst.domains"]

# The API reference: one page per public name, from its numpydoc docstring.
autosummary_generate = True
autodoc_default_options = {"members": True, "inherited-members": False}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": ["../examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"__init__\.py|_helpers\.py",
    "image_scrapers": ("pyvista", "matplotlib"),
    # An example that raises (its physics assertion failed) fails the build.
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
}

html_theme = "pydata_sphinx_theme"
html_title = "pvcloth"
html_static_path: list[str] = []
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False


# -- the performance pages: every benchmarks/results table, as it is -----------
# Each results file becomes a page (generated here, not committed), so the
# numbers the guide quotes link to the table and the command that made them
# (each names its commit and machine: tests/test_benchmarks.py checks).
RESULTS = HERE.parent / "benchmarks" / "results"
GENERATED = HERE / "performance" / "results"


def _write_results_pages() -> None:
    import shutil
    from collections import Counter

    if GENERATED.exists():
        shutil.rmtree(GENERATED)
    shutil.copytree(RESULTS, GENERATED, ignore=shutil.ignore_patterns("*.md"))
    tables = {table: table.read_text(encoding="utf-8") for table in sorted(RESULTS.glob("*.md"))}
    titles = Counter(text.partition("\n")[0] for text in tables.values())
    for table, text in tables.items():
        title, _, rest = text.partition("\n")
        if titles[title] > 1:  # one benchmark run several ways: the menu tells them apart
            title = f"{title} ({table.stem})"
        page = f"{title}\n\nSource: `benchmarks/results/{table.name}`.\n{rest}"
        (GENERATED / table.name).write_text(page, encoding="utf-8")


_write_results_pages()
