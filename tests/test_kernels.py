"""The compiled kernels against the NumPy reference: same results to round-off."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import INTEGRATORS, ObstacleSpec, SceneError, Simulation, WindSpec
from pvcloth.kernels import available, resolve_backend

pytestmark = pytest.mark.skipif(not available(), reason="numba not installed")


def twin(scene, **options):
    """The same simulation on both backends."""
    return (
        Simulation(scene, backend="numba", **options),
        Simulation(scene, backend="numpy", **options),
    )


@pytest.mark.parametrize("n", [2, 3, 7, 16, 70])  # 70 rows: the threaded kernels
def test_forces_agree_to_round_off(n):
    scene = small_scene(
        n, damping=0.3, air_damping=0.4, orientation="horizontal", stability="ignore"
    )
    compiled, reference = twin(scene)
    rng = np.random.default_rng(n)
    x = compiled.model.rest_positions + 0.05 * rng.standard_normal((n * n, 3))
    v = rng.standard_normal((n * n, 3))
    f_compiled = compiled.model.compute_forces(x, v)
    f_reference = reference.model.compute_forces(x, v)
    scale = np.abs(f_reference).max()
    np.testing.assert_allclose(f_compiled, f_reference, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_every_integrator_gives_the_same_run(integrator):
    dt = 1 / 120 if integrator == "implicit_euler" else None
    scene = pvcloth.load_scene(SCENES / "hanging.toml").with_resolution(20)
    compiled, reference = twin(scene, integrator=integrator, dt=dt, stability="substep")
    for sim in (compiled, reference):
        sim.advance(0.2)
    np.testing.assert_allclose(compiled.positions, reference.positions, rtol=0, atol=1e-9)
    assert compiled.model.compiled and not reference.model.compiled


def test_wind_obstacles_and_a_stiffness_change_reach_both_paths_alike():
    scene = pvcloth.load_scene(SCENES / "flag.toml").with_resolution(24, 16)
    scene = scene.replace(obstacles=(ObstacleSpec("sphere", center=(0.6, 0.3, 1.5), radius=0.2),))
    compiled, reference = twin(scene)
    for sim in (compiled, reference):
        sim.advance(0.2)
        sim.scale_stiffness(3.0)  # the compiled path holds copies: they must follow
        sim.set_wind(WindSpec(velocity=(2.0, 4.0, 0.0)))
        sim.advance(0.2)
    np.testing.assert_allclose(compiled.positions, reference.positions, rtol=0, atol=1e-9)


def test_backend_choice_and_errors(monkeypatch):
    assert resolve_backend("auto") == "numba"
    assert resolve_backend("numpy") == "numpy"
    monkeypatch.setenv("PVCLOTH_BACKEND", "numpy")
    assert not Simulation(small_scene(4)).model.compiled
    with pytest.raises(SceneError, match="numba, numpy"):
        resolve_backend("cuda")


def test_serial_and_threaded_builds_keep_separate_disk_caches(tmp_path):
    """numba keys its cache by function name and signature, not by flags: the
    threaded build must not be served the serial one's code (it was, when a
    small cloth ran first, and big cloths then ran on one core)."""
    import os
    import subprocess
    import sys

    run = (
        "import sys, pvcloth; n = int(sys.argv[1]);"
        "pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(n, n)))).step()"
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    for n in (8, 80):  # serial first, then a grid big enough for the threaded build
        subprocess.run([sys.executable, "-c", run, str(n)], env=env, check=True, timeout=300)
    indexes = {p.name.split("-")[0] for p in tmp_path.rglob("*.nbi")}
    for kernel in ("_spring_forces", "_kick_drift", "_body_forces"):
        assert f"kernels.{kernel}" in indexes and f"kernels.{kernel}_threaded" in indexes, indexes
