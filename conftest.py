"""Shared helpers: small scenes and analytic reference systems."""

from __future__ import annotations

import os
from pathlib import Path

if os.environ.get("PYTEST_XDIST_WORKER"):
    # Several test processes share the cores: threads inside each would only
    # fight (numba reads this when first imported, below).
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
if not os.environ.get("DISPLAY"):
    # Plotters the tests and docstring examples make themselves get VTK's
    # EGL window, as pvcloth's own do (pvcloth.visual.view.use_offscreen_gl_if_headless).
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np
import pytest

import pvcloth
from pvcloth import ClothSpec, PinSpec, Scene, SolverSpec, SpringSpec, SpringsSpec

ROOT = Path(__file__).resolve().parent
SCENES = ROOT / "data" / "scenes"


def small_scene(
    n: int = 8,
    *,
    stiffness: float = 100.0,
    damping: float = 0.0,
    air_damping: float = 0.0,
    gravity=(0.0, 0.0, -9.81),
    pins: PinSpec | None = None,
    orientation: str = "vertical",
    integrator: str = "symplectic_euler",
    dt: float = 1e-3,
    mass: float = 0.2,
    stability: str = "refuse",
) -> Scene:
    """A 1 m square cloth of ``n x n`` points with all three spring families."""
    return Scene(
        name=f"small{n}",
        cloth=ClothSpec(size=(1.0, 1.0), resolution=(n, n), mass=mass, orientation=orientation),
        springs=SpringsSpec(
            structural=SpringSpec(stiffness, damping),
            shear=SpringSpec(stiffness / 10, damping / 10),
            bending=SpringSpec(stiffness / 100, damping / 100),
        ),
        pins=PinSpec() if pins is None else pins,
        solver=SolverSpec(integrator=integrator, dt=dt, stability=stability),
        gravity=gravity,
        air_damping=air_damping,
    )


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


@pytest.fixture
def scenes_dir() -> Path:
    return SCENES


def free_cloth(n=5, **kwargs) -> pvcloth.Simulation:
    """A cloth with no pins and no gravity."""
    scene = small_scene(n, pins=PinSpec(corners=()), gravity=(0, 0, 0), **kwargs)
    return pvcloth.Simulation(scene)


_PROBE = (
    "import pvcloth.visual.view as view, pyvista as pv; view.use_offscreen_gl_if_headless();"
    "pl = pv.Plotter(off_screen=True, window_size=(64, 64));"
    "pl.add_mesh(pv.Sphere()); assert pl.screenshot(return_img=True).shape == (64, 64, 3)"
)


@pytest.fixture(scope="session")
def rendering():
    """Skip (or, under CI, fail) when VTK cannot render off-screen. The probe
    runs in a subprocess because a machine without GL segfaults VTK."""
    import os
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120
    )
    if result.returncode != 0:
        message = (
            f"off-screen rendering unavailable (exit {result.returncode}); install "
            f"libegl1 libgl1-mesa-dri (see README): {result.stderr[-300:]}"
        )
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)


@pytest.fixture(autouse=True)
def _docstring_examples_in_a_fresh_folder(request, monkeypatch):
    """Docstring examples (collected by ``--doctest-modules``) write their
    files into a temporary folder and draw off-screen."""
    from _pytest.doctest import DoctestItem

    if isinstance(request.node, DoctestItem):
        monkeypatch.chdir(request.getfixturevalue("tmp_path"))
        import pyvista

        monkeypatch.setattr(pyvista, "OFF_SCREEN", True)
