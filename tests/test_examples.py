"""Every example script runs off-screen and writes its picture, from a folder
that is not the repository's (a user's working directory is anywhere)."""

from __future__ import annotations

import subprocess
import sys

import imageio.v3 as iio
import pytest

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples").glob("*.py"))


@pytest.mark.usefixtures("rendering")
@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_writes_its_picture(script, tmp_path):
    suffix = ".gif" if "gif" in script.read_text().split("Run:")[1].splitlines()[0] else ".png"
    output = tmp_path / f"{script.stem}{suffix}"
    subprocess.run(
        [sys.executable, str(script), str(output)],
        cwd=tmp_path,
        check=True,
        capture_output=True,
        timeout=300,
    )
    image = iio.imread(output)
    assert image.size > 0
