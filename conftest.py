"""Shared helpers: small scenes and analytic reference systems."""

from __future__ import annotations

import os
from pathlib import Path

# One numba cache for the whole run: pytest-xdist's processes and every
# subprocess a test starts (they inherit the environment) load the kernels
# the first one compiled instead of compiling them again.
os.environ.setdefault("NUMBA_CACHE_DIR", str(Path(__file__).resolve().parent / ".cache" / "numba"))
if os.environ.get("PYTEST_XDIST_WORKER"):
    # Several test processes share the cores: threads inside each would only
    # fight (numba reads this when first imported, below).
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
if not os.environ.get("DISPLAY"):
    # Plotters the tests and docstring examples make themselves get VTK's
    # EGL window, as pvcloth's own do (pvcloth.visual.gl.use_offscreen_gl_if_headless).
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
    "import pvcloth.visual.gl as gl, pyvista as pv; gl.use_offscreen_gl_if_headless();"
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


# -- tiers ----------------------------------------------------------------------
#
# A test is quick unless marked ``validation``, ``serial`` or ``exhaustive``
# (pyproject.toml declares them; the README's development section says which
# command runs which). Quick tests get pytest-timeout's limit from
# pyproject.toml; the marked tiers get theirs here, unless a test sets its own.

#: Per-test time limit (s) of each marked tier; 0 is none.
TIME_LIMITS = {"exhaustive": 0, "validation": 900, "serial": 300}
#: Where an exhaustive run records itself, with the commit it ran on.
EXHAUSTIVE_RECORD = ROOT / "benchmarks" / "results" / "exhaustive.md"


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.get_closest_marker("timeout") is not None:
            continue
        for tier, limit in TIME_LIMITS.items():
            if item.get_closest_marker(tier) is not None:
                item.add_marker(pytest.mark.timeout(limit))
                break


def pytest_sessionstart(session):
    import time

    session.config._pvcloth_started = time.time()


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """After ``python -m pytest -m exhaustive`` (and only then), record the
    run in ``benchmarks/results/exhaustive.md``: commit, machine, outcome
    counts, wall time and the slowest tests. A run that only collects
    (``--collect-only``) ran nothing and leaves the record alone."""
    if (config.option.markexpr or "").strip() != "exhaustive" or hasattr(config, "workerinput"):
        return
    if config.option.collectonly:
        return
    import platform
    import subprocess
    import time

    def git(*args: str) -> str:
        done = subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True)
        return done.stdout.strip() if done.returncode == 0 else ""

    commit = git("rev-parse", "HEAD") or "unknown"
    if git("status", "--porcelain", "--untracked-files=no"):
        commit += " with uncommitted changes"
    stats = terminalreporter.stats
    counts = {k: len(stats.get(k, [])) for k in ("passed", "failed", "error", "xfailed", "skipped")}
    seconds = time.time() - config._pvcloth_started
    reports = [r for r in stats.get("passed", []) + stats.get("failed", []) if r.when == "call"]
    slowest = sorted(reports, key=lambda r: r.duration, reverse=True)[:15]
    failed = [r.nodeid for r in stats.get("failed", []) + stats.get("error", [])]
    lines = [
        "# The exhaustive tier's last run",
        "",
        f"`python -m pytest {' '.join(config.invocation_params.args)}` on commit {commit}, "
        f"{time.strftime('%Y-%m-%d', time.gmtime())}, {platform.system()} "
        f"{platform.machine()} with {os.cpu_count()} cores, Python {platform.python_version()}: "
        f"{seconds / 60:.1f} minutes, exit status {int(exitstatus)}.",
        "",
        "| outcome | tests |",
        "|---|---|",
        *(f"| {k} | {v} |" for k, v in counts.items()),
        "",
        "Failed: " + (", ".join(f"`{n}`" for n in failed) if failed else "none."),
        "",
        "Slowest:",
        "",
        "| seconds | test |",
        "|---|---|",
        *(f"| {r.duration:.0f} | `{r.nodeid}` |" for r in slowest),
    ]
    partial = EXHAUSTIVE_RECORD.with_suffix(".md.partial")
    partial.write_text("\n".join(lines) + "\n", encoding="utf-8")
    partial.replace(EXHAUSTIVE_RECORD)  # a killed run leaves the last record whole
    terminalreporter.write_line(f"recorded in {EXHAUSTIVE_RECORD.relative_to(ROOT)}")
