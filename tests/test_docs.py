"""The documentation site: built as the README says, warnings as errors, the
gallery's examples run (each asserts its physics), and its pages looked at
in a real browser (headless Chromium) to see that they are not blank.

The build takes minutes (the gallery simulates), so it is a validation test;
its quick twin checks what the build reads without building it.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT

DOCS = ROOT / "docs"
#: The README's build command, minus the install (the test tier has it).
BUILD = "python -m sphinx -W --keep-going -b html docs docs/_build/html"


def test_the_readme_names_the_build_command_this_test_runs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert f"pip install -e '.[docs]' && {BUILD}" in readme


def test_every_page_is_in_a_table_of_contents():
    # Sphinx warns about (and -W fails on) a page no toctree reaches; this is
    # the same check without a build, for the hand-written pages.
    pages = {
        str(path.relative_to(DOCS).with_suffix(""))
        for path in DOCS.rglob("*")
        if path.suffix in (".md", ".rst")
        and not str(path.relative_to(DOCS)).startswith(
            ("_build", "api", "auto_examples", "performance/results", "sg_execution_times")
        )
    }
    listed = {"index"}
    for path in DOCS.rglob("*.md"):
        for block in re.findall(r"```\{toctree\}\n(.*?)```", path.read_text(), flags=re.S):
            for line in block.splitlines():
                line = line.strip()
                if line and not line.startswith(":") and "*" not in line:
                    target = (path.parent / line).resolve().relative_to(DOCS.resolve())
                    listed.add(str(target))
    listed.add("api")  # from index.md
    assert pages <= listed | {"auto_examples/index"}, sorted(pages - listed)


def _screenshot(chromium: str, page: Path, out: Path) -> np.ndarray:
    import imageio.v3 as iio

    subprocess.run(
        [
            chromium,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            f"--screenshot={out}",
            "--window-size=1280,900",
            page.as_uri(),
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return iio.imread(out)


@pytest.mark.validation
@pytest.mark.usefixtures("rendering")
def test_the_site_builds_with_warnings_as_errors_and_its_pages_show(tmp_path):
    out = tmp_path / "html"
    command = [sys.executable, *BUILD.split()[1:]]
    command[command.index("docs/_build/html")] = str(out)
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, (done.stdout[-3000:], done.stderr[-5000:])
    examples = sorted(out.glob("auto_examples/*/plot_*.html"))
    assert len(examples) >= 12
    # every example drew its picture
    assert len(list(out.glob("_images/sphx_glr_plot_*"))) >= len(examples)
    assert (out / "api" / "pvcloth.Simulation.html").exists()
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.skip("chromium not installed (apt-get install chromium): pages not looked at")
    shots = tmp_path / "shots"
    shots.mkdir()
    for name, page in [
        ("front", out / "index.html"),
        ("gallery", out / "auto_examples" / "index.html"),
        ("example", examples[0]),
    ]:
        image = _screenshot(chromium, page, shots / f"{name}.png").astype(float)
        # Not blank: a page of text and pictures has many distinct shades,
        # and a spread of brightness well above a blank page's zero.
        assert image[..., :3].std() > 10, name
        assert len(np.unique(image[..., :3].reshape(-1, 3), axis=0)) > 50, name


def test_the_api_reference_lists_everything_pvcloth_exports():
    import re

    import pvcloth

    page = (ROOT / "docs" / "api.rst").read_text(encoding="utf-8")
    listed = set(re.findall(r"^   (\w+)$", page, re.MULTILINE))
    listed |= set(re.findall(r"``pvcloth\.(\w+)``", page))
    assert set(pvcloth.__all__) - listed == set()
