"""Live edits go through one path: the scene stays the source of truth, the
model and the integrators' caches follow it, and a checkpoint taken after
any edits resumes the edited run bit for bit."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import InputError, SceneError, WindSpec, build_model
from pvcloth.physics.integrators import get_integrator
from pvcloth.physics.state import State


def _edited(sim: pvcloth.Simulation) -> None:
    """A run of every kind of live edit, with steps between them."""
    sim.advance(0.02)
    sim.scale_stiffness(3.0)
    sim.advance(0.01)
    sim.set_wind(WindSpec(velocity=(2.0, 3.0, 0.0), gust=0.3))
    sim.update({"gravity": [0.0, 0.5, -9.0], "air_damping": 0.2})
    sim.pin(5)
    sim.move_pin(5, [0.1, 0.2, 0.3])
    sim.advance(0.013)
    sim.set_integrator("verlet")
    sim.set_step(sim.dt / 2, "substep")
    sim.unpin(5)
    sim.advance(0.011)  # leaves time owed (not a whole number of steps)


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("last", ["symplectic_euler", "implicit_euler", "fast_mass_spring"])
def test_a_checkpoint_after_live_edits_resumes_bit_for_bit(tmp_path, backend, last):
    sim = pvcloth.Simulation(small_scene(7, damping=0.5), backend=backend)
    _edited(sim)
    sim.set_integrator(last)
    sim.advance(0.01)
    resumed = pvcloth.load_checkpoint(pvcloth.save_checkpoint(sim, tmp_path / "run.npz"))
    assert resumed.scene == sim.scene
    assert (resumed.dt, resumed.owed, resumed.steps) == (sim.dt, sim.owed, sim.steps)
    assert resumed.stiffness_scale == sim.stiffness_scale == 3.0
    for run in (sim, resumed):
        run.advance(0.05)
    assert np.array_equal(sim.positions, resumed.positions)
    assert np.array_equal(sim.velocities, resumed.velocities)


def test_the_scene_is_the_source_of_truth_after_edits():
    # After edits, the live model holds exactly the constants a model built
    # afresh from sim.scene holds: nothing edited in place behind the scene.
    sim = pvcloth.Simulation(small_scene(6, damping=0.5))
    _edited(sim)
    assert sim.scene.springs.structural.stiffness == pytest.approx(300.0)
    assert sim.scene.solver.integrator == "verlet" and sim.requested_dt == sim.scene.solver.dt
    fresh = build_model(sim.scene)
    for mine, theirs in zip(sim.model.springs, fresh.springs, strict=True):
        for a, b in zip(mine.groups, theirs.groups, strict=True):
            assert np.array_equal(a.stiffness, b.stiffness)
            assert np.array_equal(a.damping, b.damping)
    assert np.array_equal(sim.model.gravity.acceleration, [0.0, 0.5, -9.0])
    assert sim.model.air.rate == 0.2 and sim.model.wind.gust == 0.3


def test_a_refused_edit_changes_nothing():
    sim = pvcloth.Simulation(small_scene(6))
    before = (sim.scene, sim.dt, sim.integrator, sim.model.revision)
    with pytest.raises(SceneError, match="solver.dt"):
        sim.set_step(0.5)  # far above the stable step: refused
    with pytest.raises(SceneError, match="stiffness"):
        sim.update({"springs.structural.stiffness": -1.0})
    assert (sim.scene, sim.dt, sim.integrator) == before[:3]
    with pytest.raises(InputError, match="cloth cannot change during a run"):
        sim.update({"cloth.resolution": 9})
    with pytest.raises(InputError, match="family added or removed"):
        sim.update({"springs.bending": None})
    assert (sim.scene, sim.dt, sim.integrator) == before[:3]
    # an integrator that refuses its settings, with a stiffness change beside it
    stiffness = sim.model.spring_table().stiffness.copy()
    with pytest.raises(InputError, match="at least 10 iterations"):
        sim.update(
            {
                "solver.integrator": "fast_bdf2",
                "solver.iterations": 6,
                "springs.structural.stiffness": 50.0,
            }
        )
    assert (sim.scene, sim.dt, sim.integrator) == before[:3]
    np.testing.assert_array_equal(sim.model.spring_table().stiffness, stiffness)


def test_control_derived_arrays_cannot_go_stale():
    sim = pvcloth.Simulation(small_scene(5))
    control = sim.control
    with pytest.raises(ValueError, match="read-only"):
        control.pinned[7] = True  # an edit in place would leave inv_mass stale
    with pytest.raises(ValueError, match="read-only"):
        control.inv_mass[7] = 0.0
    revision = control.revision
    mask = control.pinned.copy()
    mask[7] = True
    control.pinned = mask
    assert control.inv_mass[7] == 0.0 and 7 in control.pinned_index
    assert 7 not in control.movable_index and control.revision > revision
    sim.unpin(7)
    assert control.inv_mass[7] == pytest.approx(1.0 / sim.model.mass[7])
    with pytest.raises(InputError, match="shape"):
        control.pinned = np.zeros(3, bool)


def test_fast_mass_spring_follows_pins_and_stiffness_without_a_stale_factorisation():
    # Liu et al.'s solver caches a factorisation; after a pin and a stiffness
    # change, its step must equal that of a new integrator that never cached.
    sim = pvcloth.Simulation(small_scene(6), integrator="fast_mass_spring", dt=1 / 60)
    sim.advance(1 / 30)
    sim.pin(9)
    sim.scale_stiffness(2.0)
    sim.step()  # the cached integrator steps once
    fresh = get_integrator("fast_mass_spring")
    state = State(sim.state.x.copy(), sim.state.v.copy(), sim.state.t)
    pinned = sim.control.pinned_index
    state.v[pinned] = 0.0  # step() gives pinned points the velocity that holds them
    expected = fresh.step(sim.model, state, sim.control, sim.dt)
    actual = sim.integrator.step(sim.model, state, sim.control, sim.dt)
    assert np.array_equal(expected.x, actual.x)


def test_the_frame_loop_is_shared_and_checked_before_it_starts():
    sim = pvcloth.Simulation(small_scene(5))
    assert [round(sim.time, 6) for _ in sim.frames(3, fps=20)] == [0.0, 0.05, 0.1]
    with pytest.raises(InputError, match="frames"):
        sim.frames(0, 30)
    with pytest.raises(InputError, match="fps"):
        sim.frames(3, 5000)
    with pytest.raises(SceneError, match="steps"):
        sim.frames(10**6, 1)  # 10^9 steps: refused before any step
    assert sim.steps == 100


def test_one_dotted_key_dialect_for_files_sweeps_the_command_line_and_live_edits():
    from pvcloth.studies.sweep import expand, parse_sets

    base = small_scene(5)
    nested = pvcloth.Scene.from_dict(
        {**base.to_dict(), "springs": {**base.to_dict()["springs"], "shear": {"stiffness": 7.0}}}
    )
    dotted = pvcloth.Scene.from_dict({**base.to_dict(), "springs.shear": 7.0})
    assert dotted == nested == base.with_overrides({"springs.shear.stiffness": 7.0})
    [unit] = expand(base, parse_sets(["springs.shear=7.0"]))
    assert unit.scene == dotted
    sim = pvcloth.Simulation(base)
    sim.update({"springs.shear": 7.0})
    assert sim.scene == dotted.with_overrides({"solver.dt": sim.scene.solver.dt})


def test_the_command_line_takes_the_same_keys():
    scene = SCENES / "hanging.toml"
    done = subprocess.run(
        [sys.executable, "-m", "pvcloth", "info", str(scene), "--set", "solver.integrator=rk4",
         "--set", "springs.structural=2000", "--set", "cloth.resolution=6"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "rk4" in done.stdout and "6 x 6" in done.stdout
    bad = subprocess.run(
        [sys.executable, "-m", "pvcloth", "info", str(scene), "--set", "cloth.mas=1"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert bad.returncode == 2 and "did you mean 'mass'" in bad.stderr
    assert "Traceback" not in bad.stderr
