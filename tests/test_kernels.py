"""The compiled kernels against the NumPy reference: same results to round-off."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import INTEGRATORS, InputError, ObstacleSpec, Simulation, WindSpec
from pvcloth.physics.kernels import available, resolve_backend

pytestmark = pytest.mark.skipif(not available(), reason="numba not installed")


def twin(scene, **options):
    """The same simulation on both backends."""
    return (
        Simulation(scene, backend="numba", **options),
        Simulation(scene, backend="numpy", **options),
    )


def forces_on_both(scene, seed: int) -> float:
    """Both backends' forces on a randomly displaced, moving cloth agree to
    round-off (1e-12 of the largest); returns that largest force (N)."""
    compiled, reference = twin(scene)
    rng = np.random.default_rng(seed)
    x = compiled.model.rest_positions
    x = x + 0.05 * rng.standard_normal(x.shape)
    v = rng.standard_normal(x.shape)
    f_compiled = compiled.model.compute_forces(x, v)
    f_reference = reference.model.compute_forces(x, v)
    scale = float(np.abs(f_reference).max())
    np.testing.assert_allclose(f_compiled, f_reference, rtol=0, atol=1e-12 * scale)
    return scale


@pytest.mark.parametrize("n", [2, 3, 7, 16, 70])  # 70 rows: the threaded kernels
def test_forces_agree_to_round_off(n):
    scene = small_scene(
        n, damping=0.3, air_damping=0.4, orientation="horizontal", stability="ignore"
    )
    forces_on_both(scene, seed=n)


@pytest.mark.parametrize("lift", [0.0, 0.7])
@pytest.mark.parametrize("shape", [(2, 2), (3, 5), (70, 66)])  # 70 rows: threaded
def test_the_wind_agrees_to_round_off(shape, lift):
    """The compiled wind against ``Wind.accumulate`` on a crumpled, moving
    cloth: every triangle at its own angle to the air, some edge-on."""
    ny, nx = shape
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(resolution=(nx, ny), orientation="vertical"),
        springs=pvcloth.SpringsSpec(None, None, None),
        gravity=(0.0, 0.0, 0.0),
        wind=WindSpec(velocity=(3.0, -1.0, 0.5), drag=1.1, lift=lift),
    )
    scale = forces_on_both(scene, seed=ny)
    assert scale > 1e-6  # the wind is felt (gravity is off, there are no springs)


@pytest.mark.parametrize("integrator", sorted(INTEGRATORS))
def test_every_integrator_gives_the_same_run(integrator):
    dt = 1 / 120 if integrator in ("implicit_euler", "backward_euler", "bdf2") else None
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
    with pytest.raises(InputError, match="numba, numpy"):
        resolve_backend("cuda")


# A 256x256 step on the threaded build, timed as process CPU over wall time,
# then the same step from the same state on the serial build. Printed: the
# best CPU/wall of three tries (another process may take a core for a while)
# and the largest position difference.
BIG_STEP = """
import sys, time
import numpy as np
import pvcloth
from pvcloth.physics import kernels

scene = pvcloth.load_scene(sys.argv[1]).with_resolution(int(sys.argv[2]))
sim = pvcloth.Simulation(scene, dt=1e-5, stability="ignore")  # cpu_speed.py's run
for _ in range(5):
    sim.step()
best = 0.0
for _ in range(3):
    cpu, wall = time.process_time(), time.perf_counter()
    for _ in range(30):
        sim.step()
    best = max(best, (time.process_time() - cpu) / (time.perf_counter() - wall))
start = sim.state.copy()
sim.step()
threaded = sim.state.x.copy()
sim.set_state(start.x, start.v, start.t, steps=sim.steps - 1)
kernels.THREADED_ROWS = 10**9  # every kernel serial from here
sim.step()
print(best, np.abs(sim.state.x - threaded).max(), kernels.threading_layer())
"""


@pytest.mark.serial  # cpu over wall time: another test on the second core would halve it
@pytest.mark.parametrize("first", [8, 96])
def test_a_big_step_runs_threaded_whatever_cloth_filled_the_cache_first(tmp_path, first):
    """numba keys its cache by function name and signature, not by flags: the
    threaded build was served the serial one's code when a small cloth had
    filled a fresh cache first, and big cloths then ran on one core. From a
    fresh cache filled by a small or by a big cloth, a 256x256 step must use
    both cores and give the serial build's result to round-off."""
    import os
    import subprocess
    import sys

    if (os.cpu_count() or 1) < 2:
        pytest.skip("needs two cores")
    if os.environ.get("PYTEST_XDIST_WORKER"):
        pytest.skip("another test process holds a core: cpu/wall cannot reach 2 here")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_NUM_THREADS", None)  # pytest-xdist's conftest sets one thread
    fill = (
        "import sys, pvcloth; n = int(sys.argv[1]);"
        "pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(n, n)))).step()"
    )
    subprocess.run([sys.executable, "-c", fill, str(first)], env=env, check=True, timeout=300)
    out = subprocess.run(
        [sys.executable, "-c", BIG_STEP, str(SCENES / "hanging.toml"), "256"],
        env=env,
        check=True,
        timeout=300,
        capture_output=True,
        text=True,
    ).stdout.split()
    cpu_per_wall, difference, layer = float(out[0]), float(out[1]), out[2]
    assert cpu_per_wall >= 1.4, f"256x256 step ran at cpu/wall {cpu_per_wall:.2f} ({layer})"
    assert difference <= 1e-12
    indexes = {p.name.split("-")[0] for p in tmp_path.rglob("*.nbi")}
    for kernel in ("_spring_forces", "_kick_drift", "_body_forces"):
        assert f"kernels.{kernel}" in indexes and f"kernels.{kernel}_threaded" in indexes, indexes


def test_openmp_is_the_threading_layer_chosen():
    """numba's default order would pick TBB wherever libtbb is installed."""
    import os
    import subprocess
    import sys

    if importable_layers()[0] != "omp":
        pytest.skip("numba's OpenMP layer cannot load here")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_THREADING")}
    env.pop("NUMBA_NUM_THREADS", None)
    run = (
        "import pvcloth; from pvcloth.physics import kernels;"
        "pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(80, 80)))).step();"
        "print(kernels.threading_layer())"
    )
    out = subprocess.run([sys.executable, "-c", run], env=env, capture_output=True, text=True)
    assert out.stdout.split() == ["omp"], out.stderr


def importable_layers() -> list[str]:
    """numba's threading layers that load on this machine, pvcloth's order."""
    import importlib

    from pvcloth.physics.kernels import THREADING_LAYERS

    pools = {"omp": "omppool", "tbb": "tbbpool", "workqueue": "workqueue"}
    layers = []
    for layer in THREADING_LAYERS:
        try:
            importlib.import_module(f"numba.np.ufunc.{pools[layer]}")
        except ImportError:
            continue
        layers.append(layer)
    return layers


# 50 frames of a 64x64 cloth; printed: the layer, the median wall time of
# frames 3-12 and of frames 41-50, and the resident memory after each block.
MANY_FRAMES = """
import sys, time
import numpy as np
import pvcloth
from pvcloth.physics import kernels

scene = pvcloth.load_scene(sys.argv[1]).with_resolution(64)
sim = pvcloth.Simulation(scene, stability="substep")

def resident():
    return int(open("/proc/self/statm").read().split()[1]) * 4096

times, memory = [], []
for frame in range(50):
    start = time.perf_counter()
    sim.advance(1 / 60)
    times.append(time.perf_counter() - start)
    memory.append(resident())
print(kernels.threading_layer(), np.median(times[2:12]), np.median(times[40:]),
      memory[11], memory[-1])
"""


@pytest.mark.serial  # frame times early and late: a neighbour's burst would fall on one
@pytest.mark.parametrize("layer", ["omp", "workqueue"])
def test_frames_do_not_slow_down_or_grow_memory_on_the_layers_pvcloth_picks(layer):
    """Under TBB the threaded build slows from 154 to 465 ms per frame over
    50 frames while its memory grows, so pvcloth never picks TBB (it comes
    after the workqueue, which always loads; see THREADING_LAYERS). On the
    layers it picks, where numba can load them, 50 frames at 64x64: the
    last ten cost at most half as much again as the first ten (a threefold
    slowdown is what it guards against; 20 % failed twice in a row on a
    shared 2-core machine, 83 to 103 ms, and passed on the reruns) and
    memory grows by under 20 %."""
    import os
    import subprocess
    import sys

    if layer not in importable_layers():
        pytest.skip(f"numba's {layer} layer cannot load here")
    env = dict(os.environ, NUMBA_THREADING_LAYER=layer)
    env.pop("NUMBA_NUM_THREADS", None)
    for _attempt in range(2):  # a busy neighbour can slow one block of frames
        out = subprocess.run(
            [sys.executable, "-c", MANY_FRAMES, str(SCENES / "hanging.toml")],
            env=env,
            check=True,
            timeout=600,
            capture_output=True,
            text=True,
        ).stdout.split()
        used, early, late = out[0], float(out[1]), float(out[2])
        early_memory, late_memory = int(out[3]), int(out[4])
        assert used == layer
        assert late_memory <= 1.2 * early_memory
        if late <= 1.5 * early:
            return
    raise AssertionError(f"{layer}: frames went from {early * 1e3:.1f} to {late * 1e3:.1f} ms")


def test_the_compiled_local_step_of_liu_et_al_sums_what_numpy_sums(rng):
    from pvcloth.physics.kernels import spring_projection, spring_projection_numpy

    sim = Simulation(small_scene(9))
    table = sim.model.spring_table()
    x = sim.model.rest_positions + 0.05 * rng.standard_normal(sim.model.rest_positions.shape)
    x[7] = x[8]  # a spring of zero length: no direction, no pull (not NaN)
    weight = rng.random(table.count)
    compiled, reference = np.empty_like(x), np.empty_like(x)
    spring_projection(x, table.a, table.b, table.rest, weight, compiled)
    spring_projection_numpy(x, table.a, table.b, table.rest, weight, reference)
    assert np.isfinite(compiled).all()
    np.testing.assert_allclose(compiled, reference, rtol=1e-12, atol=1e-14)
    # each spring's pull is equal and opposite at its ends: nothing net
    np.testing.assert_allclose(compiled.sum(axis=0), 0.0, atol=1e-12)
