"""Self-collision (``[self_collision]``): the cloth never passes through
itself, checked after every step by the brute-force counter of
``tests/intersections.py`` (independent of the code under test); the
closest-point routines against dense sampling; bad input named by key; and
a scene without the table runs none of it."""

from __future__ import annotations

import numpy as np
import pytest
from intersections import count_self_intersections

from conftest import ROOT
from pvcloth import Scene, SceneError, SelfCollisionSpec, Simulation, load_scene
from pvcloth.physics import self_collision

RNG = np.random.default_rng(7)


def test_closest_point_on_a_triangle_is_no_farther_than_any_sampled_point():
    grid = np.linspace(0.0, 1.0, 121)
    u, v = np.meshgrid(grid, grid)
    inside = u + v <= 1.0
    for _ in range(100):
        p, a, b, c = RNG.normal(size=(4, 3))
        weights = self_collision.point_triangle(tuple(p), tuple(a), tuple(b), tuple(c))
        assert min(weights) >= 0.0 and sum(weights) == pytest.approx(1.0)
        found = np.linalg.norm(p - np.dot(weights, [a, b, c]))
        samples = a + u[inside, None] * (b - a) + v[inside, None] * (c - a)
        nearest = np.linalg.norm(samples - p, axis=1).min()
        assert nearest - 1e-3 <= found <= nearest + 1e-12


@pytest.mark.parametrize("parallel", [False, True])
def test_closest_points_of_two_segments_are_no_farther_than_any_sampled_pair(parallel):
    grid = np.linspace(0.0, 1.0, 301)[:, None]
    for _ in range(60):
        p1, q1, p2, q2 = RNG.normal(size=(4, 3))
        if parallel:
            q2 = p2 + (q1 - p1) * RNG.uniform(-2.0, 2.0)
        s, t = self_collision.segment_segment(tuple(p1), tuple(q1), tuple(p2), tuple(q2))
        found = np.linalg.norm(p1 + s * (q1 - p1) - p2 - t * (q2 - p2))
        first, second = p1 + grid * (q1 - p1), p2 + grid * (q2 - p2)
        nearest = np.linalg.norm(first[:, None] - second[None], axis=2).min()
        assert nearest - 1e-2 <= found <= nearest + 1e-12


def test_the_grid_triangles_match_the_counters():
    from intersections import grid_triangles

    ours = {tuple(t) for t in self_collision.grid_triangles((5, 7)).tolist()}
    assert ours == {tuple(t) for t in grid_triangles(7, 5).tolist()} and len(ours) == 48
    edges = self_collision.grid_edges((5, 7))
    from_triangles = {
        tuple(sorted(e))
        for t in grid_triangles(7, 5)
        for e in ((t[0], t[1]), (t[1], t[2]), (t[0], t[2]))
    }
    assert {tuple(sorted(e)) for e in edges} == from_triangles and len(edges) == len(from_triangles)


def _fold(integrator: str, n: int, contact: bool) -> Scene:
    scene = load_scene(ROOT / "data" / "scenes" / "fold.toml").with_resolution(n)
    changes = {"solver.integrator": integrator}
    scene = scene.with_overrides(changes)
    return scene if contact else scene.replace(self_collision=None)


def _worst_after_every_step(sim: Simulation, seconds: float) -> int:
    nx, ny = sim.resolution
    worst = 0
    end = sim.state.t + seconds
    while sim.state.t < end - 1e-9:
        sim.advance(sim.dt)  # one step
        worst = max(worst, count_self_intersections(sim.state.x, (nx, ny)))
    return worst


def test_the_fold_scene_passes_through_itself_without_self_collision():
    # What the tests below guard against really happens in this scene.
    sim = Simulation(_fold("fast_mass_spring", 32, contact=False))
    sim.advance(1.2)
    assert count_self_intersections(sim.state.x, sim.resolution) > 100


def test_the_fold_never_intersects_with_self_collision():
    sim = Simulation(_fold("fast_mass_spring", 32, contact=True))
    assert _worst_after_every_step(sim, 1.2) == 0
    assert sim.model.self_collision.report.contacts > 0  # the halves did meet


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["symplectic_euler", "verlet", "implicit_euler"])
def test_the_fold_never_intersects_with_other_integrators(integrator):
    # From the folded cloth (halves in contact), each integrator at its own
    # step, checked after every step.
    sim = Simulation(_fold("fast_mass_spring", 32, contact=True))
    sim.advance(0.9)
    sim.update({"solver.integrator": integrator, "solver.dt": None})
    assert count_self_intersections(sim.state.x, sim.resolution) == 0
    seconds = 0.3 if integrator == "implicit_euler" else 0.015
    assert _worst_after_every_step(sim, seconds) == 0
    assert sim.model.self_collision.report.contacts > 0


def test_without_the_table_no_self_collision_code_runs(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("self-collision ran in a scene without it")

    monkeypatch.setattr(self_collision.SelfCollision, "resolve", refuse)
    sim = Simulation(Scene.from_dict({"cloth": {"resolution": [8, 8]}}))
    sim.advance(0.05)
    assert sim.model.self_collision is None
    assert dict(sim.scene.summary())["self-contact"] == "off"


def test_the_scene_file_turns_it_on_with_its_thickness():
    scene = load_scene(ROOT / "data" / "scenes" / "fold.toml")
    sim = Simulation(scene)
    gap = (1.6 / 31) * (0.6 / 31) / np.hypot(1.6 / 31, 0.6 / 31)
    assert sim.model.self_collision.thickness == pytest.approx(0.3 * gap)
    assert "friction 0.3" in dict(scene.summary())["self-contact"]


@pytest.mark.parametrize(
    "table, key, words",
    [
        ({"thickness": 0.0}, "self_collision.thickness", "greater than 0"),
        ({"thickness": -0.01}, "self_collision.thickness", "greater than 0"),
        ({"thickness": 0.05}, "self_collision.thickness", "at most 0.0177 m here"),
        ({"thickness": "thin"}, "self_collision.thickness", "expected a number"),
        ({"friction": -0.1}, "self_collision.friction", "at least 0"),
        ({"friction": 12}, "self_collision.friction", "at most 5"),
        ({"thick": 0.01}, "self_collision.thick", ""),
    ],
)
def test_bad_input_names_the_key(table, key, words):
    with pytest.raises(SceneError) as caught:
        Scene.from_dict({"cloth": {"resolution": [21, 21]}, "self_collision": table})
    assert caught.value.key == key
    assert words in str(caught.value)


def test_a_direct_spec_is_checked_against_the_grid_too():
    with pytest.raises(SceneError, match="self_collision.thickness"):
        Scene(self_collision=SelfCollisionSpec(thickness=0.5))
