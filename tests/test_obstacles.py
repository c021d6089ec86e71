"""Obstacles: no tunnelling, Coulomb friction, moving obstacles, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from conftest import SCENES, small_scene
from pvcloth import (
    ClothSpec,
    ObstacleSpec,
    PinSpec,
    Scene,
    SceneError,
    Simulation,
    build_model,
)
from pvcloth.info import describe

G = 9.81


def falling_cloth(n, obstacles, *, integrator="symplectic_euler", dt=1e-3, size=1.0):
    """A horizontal cloth of ``n x n`` points 0.5 m above the origin, no pins."""
    scene = small_scene(
        n,
        stiffness=200.0,
        damping=0.2,
        pins=PinSpec(corners=()),
        orientation="horizontal",
        integrator=integrator,
        dt=dt,
        stability="substep",
    )
    cloth = ClothSpec(
        size=(size, size),
        resolution=(n, n),
        mass=0.2,
        orientation="horizontal",
        center=(0.0, 0.0, 0.5),
    )
    return Simulation(scene.replace(cloth=cloth, obstacles=tuple(obstacles)))


def run_checking_every_step(sim, seconds, speed):
    """Throw the cloth down at ``speed`` and step, asserting after every step
    that no point is closer than the thickness to any obstacle's surface and
    that no point's straight path over the step went through an obstacle's
    core (sampled finely, with the obstacles' own signed distance)."""
    v = sim.velocities.copy()
    v[:, 2] = -speed
    sim.set_state(velocities=v)
    steps = round(seconds / sim.dt)
    closest = np.inf
    samples = np.linspace(0.0, 1.0, 129)[:, None, None]
    for _ in range(steps):
        before = sim.positions.copy()
        sim.step()
        path = before + samples * (sim.positions - before)  # (129, N, 3)
        for obstacle in sim.model.obstacles:
            gap = obstacle.distance(sim.positions, sim.time) - obstacle.thickness
            closest = min(closest, gap.min())
            assert gap.min() >= -1e-9, f"a point is inside the {obstacle.name} at t={sim.time}"
            depth = -obstacle.distance(path.reshape(-1, 3), sim.time).min()
            assert depth < 0.25 * core(obstacle), f"a path crossed the {obstacle.name}"
    return closest


def core(obstacle):
    """Half the obstacle's thinnest dimension: how deep its middle is."""
    if obstacle.name == "sphere":
        return obstacle.radius
    return 0.5 * obstacle.size.min()


SPHERE = ObstacleSpec("sphere", center=(0.0, 0.0, 0.0), radius=0.3, thickness=0.01)
THIN_BOX = ObstacleSpec(
    "box",
    center=(0.05, -0.02, 0.0),
    size=(0.6, 0.5, 0.004),
    rotation=(10.0, -5.0, 30.0),
    thickness=0.002,
)


@pytest.mark.parametrize("obstacle", [SPHERE, THIN_BOX], ids=["sphere", "thin-box"])
@pytest.mark.parametrize(
    ("n", "speed", "dt"),
    [(4, 5.0, 1e-3), (4, 60.0, 4e-3), (12, 30.0, 1e-3), (12, 100.0, 2e-3), (24, 10.0, 1e-3)],
)
def test_a_cloth_thrown_down_never_ends_a_step_inside(obstacle, n, speed, dt):
    sim = falling_cloth(n, [obstacle], dt=dt)
    run_checking_every_step(sim, 0.25, speed)


def test_the_path_test_is_what_stops_tunnelling():
    """Checking only where a point ends would let this one through: in one
    step it jumps from 2 cm above a 4 mm slab to 2 cm below it."""
    sim = falling_cloth(4, [ObstacleSpec("box", size=(2, 2, 0.004), thickness=0.0)])
    x = sim.positions.copy()
    x[:, 2] = 0.02
    v = np.broadcast_to((0.0, 0.0, -0.04 / sim.dt), x.shape)  # 4 cm per step
    sim.set_state(x, v)
    sim.step()
    assert (sim.positions[:, 2] >= 0.002 - 1e-12).all()


@pytest.mark.parametrize("integrator", ["explicit_euler", "verlet", "rk4", "implicit_euler"])
def test_every_integrator_keeps_points_outside(integrator):
    dt = 5e-3 if integrator == "implicit_euler" else 5e-4
    sim = falling_cloth(8, [SPHERE, THIN_BOX], integrator=integrator, dt=dt)
    run_checking_every_step(sim, 0.3, 3.0)


def test_a_moving_sphere_pushes_through_a_resting_cloth_without_entering_it():
    path = ((0.0, 0.0, 0.0, -0.5), (0.5, 0.0, 0.0, 1.2))  # up through the cloth at 3.4 m/s
    sphere = ObstacleSpec("sphere", radius=0.2, thickness=0.01, path=path)
    sim = falling_cloth(16, [sphere], dt=5e-4)
    closest = run_checking_every_step(sim, 0.6, 0.0)
    assert closest < 0.01  # it did touch the cloth
    assert sim.positions[:, 2].mean() > 0.6  # and carried it up


def test_friction_on_a_horizontal_box_top_holds_the_cloth_still():
    box = ObstacleSpec("box", center=(0, 0, -0.25), size=(2, 2, 0.5), thickness=0.0, friction=0.3)
    sim = falling_cloth(10, [box])
    x = sim.positions.copy()
    x[:, 2] = 0.0
    sim.set_state(positions=x)
    start = sim.positions.copy()
    sim.advance(0.5)
    np.testing.assert_allclose(sim.positions[:, :2], start[:, :2], atol=1e-9)
    np.testing.assert_allclose(sim.positions[:, 2], 0.0, atol=1e-9)


def cloth_on_slope(kind, degrees, *, static=0.5, kinetic=0.4, dt=5e-4):
    """A 0.3 m cloth resting on a surface tilted by ``degrees`` about x."""
    tilt = Rotation.from_euler("x", degrees, degrees=True)
    common = dict(thickness=0.0, friction=kinetic, static_friction=static)
    if kind == "box":
        obstacle = ObstacleSpec(
            "box", center=(0, 0, 0), size=(3, 3, 0.2), rotation=(degrees, 0, 0), **common
        )
        surface = tilt.apply([0.0, 0.0, 0.1])
    else:
        obstacle = ObstacleSpec("ground", normal=tuple(tilt.apply([0, 0, 1])), **common)
        surface = np.zeros(3)
    sim = falling_cloth(8, [obstacle], dt=dt, size=0.3)
    flat = sim.model.rest_positions - sim.model.rest_positions.mean(axis=0)
    sim.set_state(positions=tilt.apply(flat) + surface)
    downhill = tilt.apply([0.0, -1.0, 0.0])  # the slope falls towards -y tilted
    if downhill[2] > 0:
        downhill = -downhill
    return sim, downhill


@pytest.mark.parametrize("kind", ["box", "ground"])
@pytest.mark.parametrize("degrees", [10.0, 24.0])  # below atan(0.4) and between the angles
def test_shallower_than_the_friction_angle_it_sticks(kind, degrees):
    sim, _ = cloth_on_slope(kind, degrees)
    start = sim.positions.copy()
    sim.advance(0.4)
    np.testing.assert_allclose(sim.positions, start, atol=1e-7)


@pytest.mark.parametrize("kind", ["box", "ground"])
@pytest.mark.parametrize("degrees", [30.0, 45.0])  # steeper than atan(0.5) = 26.6 degrees
def test_steeper_than_the_friction_angle_it_slides_at_the_coulomb_rate(kind, degrees):
    sim, downhill = cloth_on_slope(kind, degrees)
    start = sim.positions.mean(axis=0)
    seconds = 0.4
    sim.advance(seconds)
    moved = (sim.positions.mean(axis=0) - start) @ downhill
    theta = np.radians(degrees)
    expected = 0.5 * G * (np.sin(theta) - 0.4 * np.cos(theta)) * seconds**2
    assert moved == pytest.approx(expected, rel=0.01)


def test_a_scene_without_obstacles_builds_none_and_says_so():
    sim = Simulation(small_scene(5))
    assert sim.model.obstacles == []
    assert "obstacles   none" in describe(sim)
    with_sphere = Simulation(small_scene(5).replace(obstacles=(SPHERE,)))
    assert "sphere r = 0.3 m" in describe(with_sphere)


def test_obstacles_round_trip_through_plain_data():
    scene = small_scene(5).replace(obstacles=(SPHERE, THIN_BOX, ObstacleSpec("ground")))
    assert Scene.from_dict(scene.to_dict()) == scene


@pytest.mark.parametrize(
    ("obstacle", "key", "words"),
    [
        ({"type": "sphere", "radius": -0.2}, "obstacles[0].radius", "at least 0.0001"),
        ({"type": "sphere", "radius": 1e308}, "obstacles[0].radius", "at most 10000"),
        (
            {"type": "sphere", "radius": 0.1, "thickness": 1e308},
            "obstacles[0].thickness",
            "at most 1",
        ),
        ({"type": "ground", "normal": [0, 0, 1e-320]}, "obstacles[0].normal", "nearly) zero"),
        ({"type": "sphere"}, "obstacles[0].radius", "needs a radius"),
        ({"type": "box", "size": [1.0, 0.0, 1.0]}, "obstacles[0].size[1]", "at least 0.0001"),
        ({"type": "box"}, "obstacles[0].size", "needs size"),
        ({"type": "ground", "normal": [0, 0, 0]}, "obstacles[0].normal", "nearly) zero"),
        ({"type": "ground", "normal": [0, float("nan"), 1]}, "obstacles[0].normal[1]", "finite"),
        ({"type": "box", "size": [1, 1, 1], "radius": 1}, "obstacles[0].radius", "not used"),
        ({"type": "cone"}, "obstacles[0].type", "sphere, box, ground"),
        ({"type": "ground", "friction": -0.1}, "obstacles[0].friction", "at least 0"),
        (
            {"type": "ground", "friction": 0.5, "static_friction": 0.2},
            "obstacles[0].static_friction",
            "at least the kinetic",
        ),
        (
            {"type": "ground", "path": [[1.0, 0, 0, 0], [0.5, 0, 0, 1]]},
            "obstacles[0].path[1]",
            "increasing time",
        ),
        ({"type": "sphere", "radius": 1, "centre": [0, 0, 0]}, "obstacles[0].centre", "center"),
    ],
)
def test_bad_obstacles_are_named(obstacle, key, words):
    with pytest.raises(SceneError) as caught:
        Scene.from_dict({"obstacles": [obstacle]})
    assert caught.value.key == key
    assert words in str(caught.value)


@pytest.mark.parametrize(  # the ground in the quick tier, the drapes in validation
    "name",
    [pytest.param(n, marks=pytest.mark.validation) for n in ("drape_sphere", "drape_cube")]
    + ["ground"],
)
def test_bundled_obstacle_scenes_settle_outside_their_obstacles(name):
    sim = Simulation.from_file(SCENES / f"{name}.toml")
    for _ in range(15):
        sim.advance(0.1)
        for obstacle in sim.model.obstacles:
            assert obstacle.distance(sim.positions, sim.time).min() >= obstacle.thickness - 1e-9
    assert np.isfinite(sim.positions).all()
    assert np.abs(sim.velocities).max() < 1.0  # settling, not flying about
    first = sim.model.obstacles[0]  # the one the scene is about: the cloth rests on it
    assert first.distance(sim.positions, sim.time).min() < first.thickness + 1e-3


def test_model_builds_obstacles_only_when_asked():
    assert build_model(small_scene(4)).obstacles == []
    model = build_model(small_scene(4).replace(obstacles=(SPHERE, ObstacleSpec("ground"))))
    assert [o.name for o in model.obstacles] == ["sphere", "ground"]
