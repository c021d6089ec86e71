"""The simulation's two states: a step reads the current one and writes the
other, what users see of the current one is read-only, and edits go through
``set_state``."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from pvcloth.errors import InputError


def small(integrator: str = "symplectic_euler") -> pvcloth.Simulation:
    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(6, 6)))
    return pvcloth.Simulation(scene, integrator=integrator)


@pytest.mark.parametrize("integrator", sorted(pvcloth.INTEGRATORS))
def test_a_step_never_writes_the_state_it_starts_from(integrator):
    sim = small(integrator)
    sim.advance(0.05)
    corner = int(sim.pinned_indices[0])
    # A pin on the move needs velocities other than the state's at its row.
    sim.move_pin(corner, sim.positions[corner] + (0.0, 0.01, 0.0))
    start = sim.state
    x, v, t = start.x.copy(), start.v.copy(), start.t
    sim.step()
    assert sim.state is not start
    assert np.array_equal(start.x, x) and np.array_equal(start.v, v) and start.t == t
    assert not np.array_equal(sim.state.x, x)


def test_the_two_states_take_turns():
    sim = small()
    first = sim.state
    sim.step()
    second = sim.state
    sim.step()
    # the first state's memory is current again: no third state was made
    assert np.shares_memory(sim.state.x, first.x) and not np.shares_memory(second.x, first.x)


def test_the_current_state_cannot_be_written_in_place():
    sim = small()
    with pytest.raises(ValueError, match="read-only"):
        sim.state.x[0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        sim.state.v[0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        sim.positions[0] = 0.0


def test_set_state_replaces_what_it_is_given_and_keeps_the_rest():
    sim = small()
    sim.advance(0.05)
    x, t = sim.positions.copy(), sim.time
    v = np.full_like(x, 0.25)
    sim.set_state(velocities=v)
    assert np.array_equal(sim.velocities, v) and np.array_equal(sim.positions, x)
    assert sim.time == t
    v[:] = 9.0  # the simulation holds a copy
    assert (sim.velocities == 0.25).all()
    sim.set_state(time=1.5, steps=7)
    assert (sim.time, sim.steps) == (1.5, 7)


def test_set_state_updates_the_mesh_a_user_holds():
    sim = small()
    mesh = sim.mesh
    moved = sim.positions + (0.0, 0.0, 0.1)
    sim.set_state(positions=moved)
    np.testing.assert_array_equal(mesh.points, moved)


@pytest.mark.parametrize(
    ("keywords", "message"),
    [
        ({"positions": np.zeros((3, 3))}, "positions: expected shape"),
        ({"velocities": np.full((36, 3), np.nan)}, "velocities: every value must be finite"),
        ({"positions": np.full((36, 3), 1e9)}, "positions: each coordinate must be within"),
        ({"velocities": np.full((36, 3), 1e5)}, "velocities: each component must be within"),
        ({"time": -1.0}, "time: expected a finite time"),
        ({"steps": 2.5}, "steps: expected a whole number"),
        ({"positions": "left"}, "positions: expected"),
    ],
)
def test_set_state_refuses_what_no_state_can_be(keywords, message):
    sim = small()
    before = sim.positions.copy()
    with pytest.raises(InputError, match=message):
        sim.set_state(**keywords)
    assert np.array_equal(sim.positions, before)


def test_advance_shows_a_bar_when_asked_and_keeps_the_same_steps(capsys):
    plain, shown = small("rk4"), small("rk4")
    plain.advance(0.1)
    shown.advance(0.1, progress=True)
    assert np.array_equal(plain.positions, shown.positions) and plain.steps == shown.steps
    assert "advancing" in capsys.readouterr().err
    quiet = small("rk4")
    quiet.advance(0.1, progress="auto")  # a tenth of a second: no bar
    assert "advancing" not in capsys.readouterr().err
    with pytest.raises(InputError, match="progress"):
        quiet.advance(0.1, progress="yes")
