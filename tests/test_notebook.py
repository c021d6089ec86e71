"""The example notebooks run top to bottom in a real Jupyter kernel, from a
folder of their own, and each cell shows what it asks for and nothing else:
the HTML reprs, the cloth inline as a picture, the movie embedded, and no
stray plotter picture or widget from ``render``."""

from __future__ import annotations

import base64
import shutil

import imageio.v3 as iio
import numpy as np
import pytest

from conftest import ROOT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOK = ROOT / "examples" / "cloth_in_a_notebook.ipynb"


def _mimetypes(cell) -> list[str]:
    kinds = []
    for output in cell.get("outputs", []):
        if output["output_type"] == "stream":
            kinds.append(f"stream:{output['name']}")
        else:
            kinds.extend(output.get("data", {}))
    return kinds


def _picture(cell, mimetype: str) -> np.ndarray:
    for output in cell["outputs"]:
        if mimetype in output.get("data", {}):
            return iio.imread(base64.b64decode(output["data"][mimetype]))
    raise AssertionError(f"no {mimetype} output")


def _cell(notebook, starts_with: str):
    (cell,) = [
        c for c in notebook.cells if c.cell_type == "code" and c.source.startswith(starts_with)
    ]
    return cell


@pytest.mark.usefixtures("rendering")
def test_the_notebook_runs_and_shows_only_what_it_asks_for(tmp_path):
    shutil.copy(NOTEBOOK, tmp_path)
    notebook = nbformat.read(tmp_path / NOTEBOOK.name, as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": tmp_path}}
    )
    client.execute()  # raises CellExecutionError, with the cell's traceback, if any cell fails

    assert "text/html" in _mimetypes(_cell(notebook, "scene = "))  # Scene._repr_html_
    assert "text/html" in _mimetypes(_cell(notebook, "sim = "))  # Simulation._repr_html_
    plot = _cell(notebook, "sim.plot(")
    pictures = [o for o in plot.outputs if any(k.startswith("image/") for k in o.get("data", {}))]
    assert len(pictures) == 1, _mimetypes(plot)  # one inline picture (PyVista's static backend)
    image = _picture(plot, "image/png")
    assert image.shape[:2] == (400, 480)  # the window_size asked for
    # coloured by stretch: a cloth in many shades of the colormap, not one colour
    assert len(np.unique(image.reshape(-1, image.shape[-1]), axis=0)) > 200
    # render: a progress widget and the stats it returns, no picture of its plotter
    rendered = _mimetypes(_cell(notebook, "stats = pvcloth.render("))
    assert not [kind for kind in rendered if kind.startswith("image/")], rendered
    assert "application/vnd.jupyter.widget-view+json" in rendered  # tqdm.auto's bar
    assert "text/plain" in rendered
    assert "stream:stderr" not in rendered  # no text progress bar, no warning
    assert _mimetypes(_cell(notebook, "from IPython.display import Image")) == [
        "image/gif",
        "text/plain",
    ]
    assert (tmp_path / "curtain.gif").stat().st_size > 10_000
