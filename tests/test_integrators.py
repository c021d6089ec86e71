"""One matrix of checks over every integrator (as Warp's cloth tests do), and
the numerical behaviour each promises: convergence order, step limits,
stability of implicit Euler on stiff and light cloths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_physics import two_body

from conftest import small_scene
from pvcloth import INTEGRATORS, Control, PinSpec, Simulation, State, get_integrator
from pvcloth.physics.integrators.base import largest_stable_step

ALL = sorted(INTEGRATORS)
EXPLICIT = [name for name in ALL if name != "implicit_euler"]


@pytest.mark.parametrize("integrator", ALL)
def test_pins_stay_and_nothing_explodes(integrator):
    scene = small_scene(8, stiffness=100.0, damping=0.2, air_damping=0.5, integrator=integrator)
    sim = Simulation(scene)
    sim.dt = 0.5 * min(Simulation(scene, integrator="symplectic_euler").stable_dt(), 1e-3)
    sim.advance(0.3)
    pinned = sim.model.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    assert np.isfinite(sim.positions).all()
    assert np.abs(sim.positions - sim.model.rest_positions).max() < 1.0


@pytest.mark.parametrize("integrator", ALL)
def test_free_fall(integrator):
    scene = small_scene(
        4, pins=PinSpec(corners=()), integrator=integrator, dt=1e-3, stability="ignore"
    )
    sim = Simulation(scene)
    sim.advance(0.5)
    drop = sim.model.rest_positions[:, 2] - sim.positions[:, 2]
    exact = 0.5 * 9.81 * 0.5**2
    if integrator in ("bdf2", "fast_bdf2"):  # exact but for the start-up (test_bdf2.py)
        np.testing.assert_allclose(drop, exact + 0.75 * 9.81 * 1e-3**2, rtol=1e-9)
    elif INTEGRATORS[integrator].order >= 2:
        np.testing.assert_allclose(drop, exact, rtol=1e-10)  # exact for constant a
    else:
        np.testing.assert_allclose(drop, exact, atol=9.81 * 0.5 * 1e-3)  # O(h): g t h
    np.testing.assert_allclose(sim.positions[:, :2], sim.model.rest_positions[:, :2], atol=1e-12)


@pytest.mark.parametrize("integrator", ALL)
def test_a_moving_pin_is_honoured(integrator):
    sim = Simulation(small_scene(6, damping=0.2, air_damping=1.0, dt=5e-4, integrator=integrator))
    corner = sim.point_index((5, 5))
    goal = sim.positions[corner] + np.array([0.2, -0.1, 0.1])
    sim.move_pin(corner, goal)
    sim.advance(0.1)
    np.testing.assert_array_equal(sim.positions[corner], goal)
    assert np.isfinite(sim.positions).all()


def oscillator_error(integrator, steps, duration=0.5):
    """Error of one integrator on two bodies and a spring, against the exact
    solution: the separation is ``L0 + A cos(omega t)`` along the axis.

    The methods that iterate run 50 iterations: the order is their time
    discretisation's. At their default 10 the solver's error can dominate:
    on two bodies the plain local/global iteration contracts far faster than
    the 0.95 Chebyshev assumes, and ``fast_bdf2``'s error stops falling with
    the step (see :class:`~pvcloth.physics.integrators.fast_mass_spring.FastMassSpring`)."""
    model, k = two_body()
    mu = 1.0 * 0.5 / 1.5
    omega = math.sqrt(k / mu)
    x = model.rest_positions.copy()
    x[1, 0] += 0.1
    state = State(x, np.zeros_like(x))
    iterations = 50 if INTEGRATORS[integrator].iterative else None
    method, control = get_integrator(integrator, iterations), Control.from_model(model)
    dt = duration / steps
    for _ in range(steps):
        state = method.step(model, state, control, dt)
    separation = state.x[1, 0] - state.x[0, 0]
    return abs(separation - (1.0 + 0.1 * math.cos(omega * duration)))


@pytest.mark.parametrize("integrator", ALL)
def test_convergence_order(integrator):
    steps = np.array([100, 200, 400, 800])
    errors = np.array([oscillator_error(integrator, int(n)) for n in steps])
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope == pytest.approx(INTEGRATORS[integrator].order, abs=0.25)


@pytest.mark.parametrize(
    ("integrator", "limit"),
    [
        ("symplectic_euler", 2.0),
        ("verlet", 2.0),
        ("rk4", 2 * math.sqrt(2)),
        ("explicit_euler", 0.0),
        ("implicit_euler", math.inf),
    ],
)
def test_undamped_step_limits_match_theory(integrator, limit):
    omega = 250.0
    assert largest_stable_step(INTEGRATORS[integrator], omega, 0.0) * omega == pytest.approx(
        limit, rel=1e-6
    )


def test_damped_limits_match_closed_forms():
    omega, alpha = 1000.0, 100.0
    symplectic = 2 * (math.sqrt(alpha**2 + omega**2) - alpha) / omega**2  # Jury conditions
    explicit = 2 * alpha / omega**2  # |1 + h lambda| = 1
    assert largest_stable_step(INTEGRATORS["symplectic_euler"], omega, alpha) == pytest.approx(
        symplectic, rel=1e-6
    )
    assert largest_stable_step(INTEGRATORS["explicit_euler"], omega, alpha) == pytest.approx(
        explicit, rel=1e-6
    )


@pytest.mark.parametrize("integrator", ["symplectic_euler", "verlet", "rk4"])
def test_stable_step_estimate_is_sharp_on_a_cloth(integrator):
    scene = small_scene(
        8,
        stiffness=400.0,
        damping=0.2,
        pins=PinSpec(corners=()),
        gravity=(0, 0, 0),
        integrator=integrator,
    )
    limit = Simulation(scene).stable_dt()
    kick = 1e-6 * np.random.default_rng(2).standard_normal((64, 3))
    outcomes = []
    for factor in (0.95, 1.05):
        sim = Simulation(scene, dt=factor * limit, stability="ignore")
        sim.set_state(positions=sim.positions + kick)
        try:
            sim.advance(3000 * sim.dt)
            outcomes.append("stable")
        except Exception:
            outcomes.append("diverged")
    assert outcomes == ["stable", "diverged"]


@pytest.mark.parametrize(("stiffness", "mass"), [(1e6, 1e-6 * 256), (1e6, 1.0), (1e2, 1e-6 * 256)])
def test_implicit_euler_is_bounded_at_a_frame_step(stiffness, mass):
    """Stiff springs and 1e-6 kg points at dt = 1/30 s: explicit methods
    would need steps far below a microsecond here."""
    scene = small_scene(
        16,
        stiffness=stiffness,
        damping=0.0,
        mass=mass,
        integrator="implicit_euler",
        dt=1 / 30,
        orientation="horizontal",
    )
    sim = Simulation(scene)
    sim.advance(1.0)
    assert np.isfinite(sim.positions).all()
    pinned = sim.model.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    # it hangs below its pins, no further than its own diagonal plus stretch
    reach = np.linalg.norm(sim.positions - sim.positions[pinned][0], axis=1).max()
    assert reach < 1.6
    if stiffness >= 1e6 and mass < 1e-3:  # explicit methods could only crawl here
        explicit = Simulation(scene, integrator="symplectic_euler", stability="ignore")
        assert explicit.stable_dt() < 1e-3 / 30


def test_substep_policy_splits_the_step_evenly():
    scene = small_scene(8, stiffness=400.0, damping=0.1, dt=1 / 60, stability="substep")
    sim = Simulation(scene)
    limit = sim.stable_dt()
    assert sim.dt <= 0.5 * limit
    assert (1 / 60) / sim.dt == pytest.approx(round((1 / 60) / sim.dt), abs=1e-9)
    sim.advance(1 / 60)
    assert sim.time == pytest.approx(1 / 60)


def test_switching_integrator_keeps_the_step_asked_for():
    sim = Simulation(small_scene(8, damping=0.1, dt=1e-3), dt=2e-4)
    sim.set_integrator("verlet")
    assert sim.integrator.name == "verlet" and sim.dt == 2e-4  # not the scene's 1e-3
    sim.set_integrator("implicit_euler")
    assert sim.dt == 2e-4


def test_fast_mass_spring_rests_where_the_explicit_solver_rests():
    """Liu et al.'s local/global iterations solve backward Euler, whose fixed
    point is the static equilibrium: both integrators settle to the same cloth."""
    scene = small_scene(9, stiffness=200.0, air_damping=8.0, orientation="horizontal")
    scene = scene.replace(
        springs=scene.springs.__class__(
            *(
                s.__class__(s.stiffness, 0.0)
                for s in (scene.springs.structural, scene.springs.shear, scene.springs.bending)
            )
        )
    )
    explicit = Simulation(scene, integrator="symplectic_euler", dt=1e-3)
    liu = Simulation(scene, integrator="fast_mass_spring", dt=1 / 60)
    # With few iterations per step the cloth creeps to rest (the method's
    # numerical damping); more iterations per step get there in time.
    liu.integrator.iterations = 200
    for sim in (explicit, liu):
        sim.advance(16.0)
    assert np.abs(liu.velocities).max() < 1e-4
    np.testing.assert_allclose(liu.positions, explicit.positions, atol=1e-4)


def test_fast_mass_spring_is_stable_at_a_frame_step_on_a_very_stiff_cloth():
    scene = small_scene(12, stiffness=1e6, mass=1e-3, dt=1 / 30, integrator="fast_mass_spring")
    sim = Simulation(scene)
    assert sim.stable_dt() == math.inf
    sim.advance(1.0)
    assert np.isfinite(sim.positions).all()
    pinned = sim.model.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    # stiff springs keep their rest length: the 1 m cloth hangs from z = 1.5 m
    # without stretching more than a percent
    assert sim.positions[:, 2].min() > 0.49


def test_the_stable_step_estimate_is_the_same_every_time():
    # ARPACK's random start vector made repeated estimates differ by enough
    # to change the automatic step's substep count for the same state.
    sim = Simulation(small_scene(24, stiffness=400.0, damping=0.1, stability="substep"))
    sim.advance(0.05)
    assert len({sim.stable_dt() for _ in range(6)}) == 1
    assert len({sim.automatic_dt() for _ in range(6)}) == 1
