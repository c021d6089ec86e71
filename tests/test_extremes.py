"""The extremes: each case ends in a correct, bounded result or in the
project's own clear error, never a silent NaN."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import small_scene
from pvcloth import DivergenceError, InputError, PvclothError, SceneError, Simulation


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


@pytest.mark.parametrize("n", [64, pytest.param(256, marks=pytest.mark.validation)])
def test_a_large_cloth_steps(n):
    scene = small_scene(n, stiffness=100.0, damping=0.0, dt=1e-5, stability="ignore")
    sim = Simulation(scene)
    for _ in range(5):
        sim.step()
    bounded(sim)
    assert sim.positions.shape == (n * n, 3)


@pytest.mark.parametrize("integrator", sorted(pvcloth.INTEGRATORS))
def test_a_collapsed_cloth_recovers_without_nan(integrator):
    sim = Simulation(
        small_scene(
            5, damping=0.2, air_damping=1.0, integrator=integrator, dt=5e-4, stability="ignore"
        )
    )
    free = ~sim.control.pinned
    x = sim.positions.copy()
    x[free] = x[free].mean(axis=0)  # every free point on one spot
    sim.set_state(positions=x)
    try:
        sim.advance(0.2)
    except DivergenceError as error:  # allowed: the project's clear error
        assert "diverged at t =" in str(error) or "did not converge at t =" in str(error)
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
    with pytest.raises(InputError, match="seconds"):
        sim.advance(-1.0)
    with pytest.raises(InputError, match="finite"):
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


@pytest.mark.filterwarnings("error")  # scipy's "exactly singular" on a NaN system too
@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("integrator", sorted(pvcloth.INTEGRATORS))
@pytest.mark.parametrize("where", ["x", "v"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_state_raises_in_every_backend_and_integrator(bad, where, integrator, backend):
    """No backend calls NaN finite (the compiled update once folded its
    finiteness test away under fast-math)."""
    from pvcloth.physics.kernels import available

    if backend == "numba" and not available():
        pytest.skip("numba not installed")
    scene = small_scene(6, damping=0.1, integrator=integrator, dt=1e-3, stability="substep")
    sim = Simulation(scene, backend=backend)
    # set_state refuses what is not finite, so the test writes it in itself.
    corrupted = getattr(sim.state, where)
    corrupted.flags.writeable = True
    corrupted[7, 0] = bad
    with pytest.raises(DivergenceError):
        sim.advance(0.01)


@pytest.mark.parametrize(
    "call",
    [
        lambda sim: sim.pin(0, [np.nan, 0.0, 0.0]),
        lambda sim: sim.pin(0, [np.inf, 0.0, 0.0]),
        lambda sim: sim.pin(0, [1.0, 2.0]),
        lambda sim: sim.pin(0, "up"),
        lambda sim: sim.move_pin(sim.pinned_indices[0], None),
        lambda sim: sim.pin(("a", 0)),
        lambda sim: sim.pin((1.9, 0)),
        lambda sim: sim.pin(True),
        lambda sim: sim.pin(36),
        lambda sim: sim.pin((6, 0)),
    ],
    ids=[
        "nan",
        "inf",
        "two-coords",
        "text",
        "none",
        "text-index",
        "float-index",
        "bool",
        "36",
        "i=6",
    ],
)
def test_bad_pins_are_refused_naming_the_value(call):
    sim = Simulation(small_scene(6))
    before = (sim.control.pinned.copy(), sim.control.targets.copy())
    with pytest.raises(InputError):
        call(sim)
    np.testing.assert_array_equal(sim.control.pinned, before[0])
    np.testing.assert_array_equal(sim.control.targets, before[1])


def test_a_step_far_below_what_the_run_needs_is_refused_before_it_starts():
    sim = Simulation(small_scene(6), dt=1e-30, stability="ignore")
    with pytest.raises(SceneError, match=r"1e\+30 steps, more than the 1e\+07"):
        sim.advance(1.0)
    assert sim.steps == 0 and sim.time == 0.0
    with pytest.raises(SceneError, match="inf steps"):
        Simulation(small_scene(6)).advance(1e308)


def test_a_cloth_bigger_than_the_memory_is_refused_with_the_numbers():
    from pvcloth.physics.memory import PEAK_BYTES_PER_POINT, available_memory

    have = available_memory()
    if have is None or have > 4096**2 * PEAK_BYTES_PER_POINT:
        pytest.skip("this machine could hold a 4096 x 4096 cloth")
    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(4096, 4096)))
    with pytest.raises(
        SceneError, match=r"cloth.resolution: 4096 x 4096 = 16,777,216 points .* GB"
    ):
        Simulation(scene)


def test_a_cloth_with_no_springs_falls_at_the_automatic_frame_step():
    scene = pvcloth.Scene(
        springs=pvcloth.SpringsSpec(structural=None, shear=None, bending=None),
        pins=pvcloth.PinSpec(corners=()),
    )
    sim = Simulation(scene)
    assert sim.stable_dt() == np.inf and sim.dt == pytest.approx(1 / 60)
    sim.advance(0.5)
    # free fall, with symplectic Euler's first-order error g t dt / 2 = 0.04 m
    fall = sim.model.rest_positions[:, 2] - 0.5 * 9.81 * 0.5**2
    np.testing.assert_allclose(sim.positions[:, 2], fall, atol=0.05)


@pytest.mark.parametrize(
    "content, words",
    [
        (b"name = '\xff\xfe'\n", "not a text file in UTF-8"),
        (b"a = " + b"[" * 5000 + b"]" * 5000, "nested too deeply"),
        (b"[cloth\n", "not valid TOML"),
    ],
    ids=["latin-1", "deep", "broken"],
)
def test_unreadable_scene_files_raise_scene_errors(tmp_path, content, words):
    path = tmp_path / "scene.toml"
    path.write_bytes(content)
    with pytest.raises(SceneError, match=words):
        pvcloth.load_scene(path)


def test_a_path_with_a_nul_character_is_a_scene_error():
    with pytest.raises(SceneError, match="null byte"):
        pvcloth.load_scene("a\x00b.toml")
