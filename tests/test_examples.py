"""The gallery (``examples/``, built by sphinx-gallery): every example is in
its format, in one of its sections, and asserts its physics; and every
example runs as a plain script, off-screen, from a folder that is not the
repository's (a user's working directory is anywhere), its assertions
holding."""

from __future__ import annotations

import ast
import re
import subprocess
import sys

import pytest

from conftest import ROOT

GALLERY = ROOT / "examples"
SECTIONS = (
    "01_basics",
    "02_wind_and_obstacles",
    "03_self_collision",
    "04_seeing_the_physics",
    "05_speed_and_accuracy",
    "06_export_and_checkpoints",
)
EXAMPLES = sorted(GALLERY.rglob("plot_*.py"))
#: The quickest example (about 2 s as a script): the quick tier's twin of
#: the validation test that runs them all.
QUICKEST = GALLERY / "04_seeing_the_physics" / "plot_energy_budget.py"


def _title(text: str) -> str | None:
    """The RST title a text starts with (a line, then ``=`` at least as long), or ``None``."""
    lines = text.strip().splitlines()
    if len(lines) >= 2 and lines[0].strip() and re.fullmatch(r"=+", lines[1].strip()):
        return lines[0].strip() if len(lines[1].strip()) >= len(lines[0].strip()) else None
    return None


def _run(script, tmp_path) -> None:
    """Run ``script`` as a user would, from ``tmp_path``: a failed assertion
    fails the test (its traceback is in the test's captured output)."""
    subprocess.run([sys.executable, str(script)], cwd=tmp_path, check=True, timeout=300)


def test_the_gallery_has_its_sections_each_with_a_title():
    assert _title((GALLERY / "README.rst").read_text(encoding="utf-8")) == "Gallery"
    for section in SECTIONS:
        readme = (GALLERY / section / "README.rst").read_text(encoding="utf-8")
        lines = readme.strip().splitlines()
        # A subsection's title: a line underlined with "-" at least as long.
        assert re.fullmatch(r"-+", lines[1]) and len(lines[1]) >= len(lines[0]), section
        folder = GALLERY / section
        assert len(list(folder.glob("plot_*.py"))) >= 2, f"{section} needs two examples"
    assert len(EXAMPLES) >= 12


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_each_example_is_a_gallery_lesson_that_asserts_its_physics(script):
    assert script.parent.name in SECTIONS and script.parent.parent == GALLERY
    text = script.read_text(encoding="utf-8")
    tree = ast.parse(text)
    docstring = ast.get_docstring(tree, clean=False)
    assert docstring and _title(docstring), f"{script.name}: no 'Title\\n=====' docstring"
    assert "\n# %%\n" in text, f"{script.name}: no '# %%' cells"
    # An assert statement, not the word in a comment.
    assert any(isinstance(node, ast.Assert) for node in ast.walk(tree)), script.name
    # sphinx-gallery runs an example without __file__ (and in its own
    # folder), so an example that needs it breaks only in the docs build.
    assert "__file__" not in text, script.name


def test_the_gallery_holds_only_examples_and_their_helpers():
    # sphinx-gallery lists every .py of examples/; conf.py leaves out the
    # ones named *_helpers.py (modules the examples and tests import), and
    # runs those named plot_*.py.
    for path in GALLERY.rglob("*.py"):
        assert path.name.startswith("plot_") or path.name.endswith("_helpers.py"), path


@pytest.mark.usefixtures("rendering")
def test_the_quickest_example_runs_as_a_script(tmp_path):
    assert QUICKEST in EXAMPLES
    _run(QUICKEST, tmp_path)


@pytest.mark.validation
@pytest.mark.usefixtures("rendering")
@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_runs_as_a_script_and_its_physics_holds(script, tmp_path):
    _run(script, tmp_path)
