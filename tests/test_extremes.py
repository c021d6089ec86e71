"""The extremes: each case ends in a correct, bounded result or in the
project's own clear error, never a silent NaN."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import small_scene
from pvcloth import DivergenceError, PvclothError, SceneError, Simulation


def bounded(sim, size=1.0):
    assert np.isfinite(sim.positions).all() and np.isfinite(sim.velocities).all()
    pinned = sim.control.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.control.targets[pinned])
    # nothing further from a pin than the cloth's diagonal, stretched 50 %
    if pinned.any():
        reach = np.linalg.norm(sim.positions[:, None] - sim.positions[pinned][None], axis=2)
        assert reach.min(axis=1).max() < 1.5 * np.sqrt(2) * size


@pytest.mark.parametrize("n", [2, 3])
@pytest.mark.parametrize("integrator", sorted(pvcloth.INTEGRATORS))
def test_tiny_cloths(n, integrator):
    scene = small_scene(
        n, damping=0.1, air_damping=0.5, integrator=integrator, dt=1e-3, stability="substep"
    )
    sim = Simulation(scene)
    sim.advance(0.5)
    bounded(sim)


def test_very_stiff_cloth_is_refused_or_substepped_not_exploded():
    scene = small_scene(8, stiffness=1e6, damping=1.0, dt=1e-3)
    with pytest.raises(SceneError, match="above the largest stable step"):
        Simulation(scene)
    sim = Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    sim.advance(0.5)
    bounded(sim)


def test_a_very_light_cloth_runs_implicitly_at_a_frame_step():
    scene = small_scene(8, mass=1e-5, damping=0.1, air_damping=0.5, dt=1 / 60)
    with pytest.raises(SceneError, match="implicit_euler"):  # explicit: refused, with advice
        Simulation(scene)
    sim = Simulation(scene, integrator="implicit_euler")
    sim.advance(0.5)
    bounded(sim)


def test_a_very_heavy_cloth_substeps():
    scene = small_scene(8, mass=1e3, damping=0.1, air_damping=0.5, dt=1 / 60, stability="substep")
    sim = Simulation(scene)
    sim.advance(0.3)
    bounded(sim, size=50.0)  # 1000 kg on 100 N/m springs stretches far


@pytest.mark.slow
def test_a_256_by_256_cloth_steps():
    scene = small_scene(256, stiffness=100.0, damping=0.0, dt=1e-5, stability="ignore")
    sim = Simulation(scene)
    for _ in range(5):
        sim.step()
    bounded(sim)
    assert sim.positions.shape == (256 * 256, 3)


@pytest.mark.parametrize("integrator", sorted(pvcloth.INTEGRATORS))
def test_a_collapsed_cloth_recovers_without_nan(integrator):
    sim = Simulation(
        small_scene(
            5, damping=0.2, air_damping=1.0, integrator=integrator, dt=5e-4, stability="ignore"
        )
    )
    free = ~sim.control.pinned
    sim.state.x[free] = sim.state.x[free].mean(axis=0)  # every free point on one spot
    try:
        sim.advance(0.2)
    except DivergenceError as error:  # allowed: the project's clear error
        assert "diverged at t =" in str(error)
    else:
        assert np.isfinite(sim.positions).all()


def test_a_huge_step_is_refused_then_caught_if_forced():
    scene = small_scene(8, stiffness=500.0, dt=5.0)
    with pytest.raises(SceneError, match="solver.dt"):
        Simulation(scene)
    sim = Simulation(scene, stability="ignore")
    with pytest.raises(DivergenceError, match="try dt ="):
        sim.advance(50.0)
    assert np.isfinite(sim.positions).all()


def test_zero_duration_advance_changes_nothing():
    sim = Simulation(small_scene(5))
    before = sim.positions.copy()
    sim.advance(0.0)
    assert sim.steps == 0 and sim.time == 0.0
    np.testing.assert_array_equal(sim.positions, before)
    with pytest.raises(SceneError, match="seconds"):
        sim.advance(-1.0)
    with pytest.raises(SceneError, match="finite"):
        sim.advance(float("nan"))


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler"])
def test_a_pin_dragged_very_fast(integrator):
    """A corner yanked 2 m in one frame: the pin moves in a straight line over
    the frame's substeps; the cloth follows or the run stops clearly."""
    sim = Simulation(small_scene(8, damping=0.2, air_damping=1.0, dt=5e-4, integrator=integrator))
    corner = sim.point_index((7, 7))
    goal = sim.positions[corner] + np.array([2.0, 0.0, 0.0])
    sim.move_pin(corner, goal)
    try:
        sim.advance(1 / 60)  # 120 m/s
        sim.advance(0.3)
    except PvclothError as error:
        assert "diverged" in str(error) or "failed" in str(error)
        return
    np.testing.assert_array_equal(sim.positions[corner], goal)
    assert np.isfinite(sim.positions).all()
