"""Physics against answers known in advance: an oscillator's period, energy
behaviour, momentum, rest, and the equilibrium of a hanging cloth."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

import pvcloth
from conftest import free_cloth, small_scene
from pvcloth import Control, DivergenceError, PinSpec, Simulation, State, get_integrator
from pvcloth.physics.model import Model
from pvcloth.physics.springs import Springs

# -- two particles and one spring ---------------------------------------------


def two_body(m1=1.0, m2=0.5, k=100.0):
    rest = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]])  # (ny=1, nx=2, 3)
    springs = Springs.build("structural", rest, k, 0.0, (1.0, 1.0))
    model = Model(
        (1, 2), rest.reshape(2, 3).copy(), np.array([m1, m2]), np.zeros(2, bool), [springs]
    )
    return model, springs.groups[0].stiffness.item()


def spring_period(integrator, dt, periods=5):
    model, k = two_body()
    control = Control.from_model(model)
    x = model.rest_positions.copy()
    x[1, 0] += 0.1  # stretch by 10 cm
    state = State(x, np.zeros_like(x))
    method = get_integrator(integrator)
    mu = 1.0 * 0.5 / 1.5
    exact = 2 * np.pi * np.sqrt(mu / k)
    times, stretch = [], []
    while state.t < periods * exact:
        state = method.step(model, state, control, dt)
        times.append(state.t)
        stretch.append(np.linalg.norm(state.x[1] - state.x[0]) - 1.0)
    s, t = np.array(stretch), np.array(times)
    # upward zero crossings, linearly interpolated
    up = np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0))
    crossings = t[up] - s[up] * (t[up + 1] - t[up]) / (s[up + 1] - s[up])
    return np.mean(np.diff(crossings)), exact


def test_two_body_period_matches_reduced_mass_formula():
    measured, exact = spring_period("symplectic_euler", dt=1e-4)
    assert measured == pytest.approx(exact, rel=0.005)


# -- energy ---------------------------------------------------------------------


def energy_history(integrator, steps, rng):
    sim = free_cloth(5, integrator=integrator, stability="ignore")
    # a tenth of symplectic Euler's limit (undamped explicit Euler has none)
    sim.dt = 0.1 * free_cloth(5).stable_dt()
    sim.set_state(positions=sim.positions + 0.02 * rng.standard_normal(sim.positions.shape))
    energies = np.empty(steps)
    for n in range(steps):
        sim.step()
        energies[n] = sim.energy()["total"]
    return energies


@pytest.mark.parametrize("integrator", ["symplectic_euler", "verlet"])
def test_symplectic_methods_keep_energy_in_a_band(integrator, rng):
    energies = energy_history(integrator, 10_000, rng)
    e0 = energies[:200].mean()
    # Symplectic Euler's energy error is O(h omega): about +-10 % at a tenth
    # of its limit, oscillating, never accumulating.
    assert np.ptp(energies) < 0.25 * e0
    # no drift: the last stretch averages like the first
    assert abs(energies[-2000:].mean() - energies[:2000].mean()) < 0.005 * e0


def test_explicit_euler_energy_grows(rng):
    # Same cloth, same step: each undamped mode grows by sqrt(1 + (h w)^2)
    # per step, so within a few hundred steps the energy has clearly risen.
    energies = energy_history("explicit_euler", 150, rng)
    assert energies[-1] > 1.2 * energies[0]
    assert np.all(np.diff(energies[::25]) > 0)  # steadily


# -- momentum --------------------------------------------------------------------


def test_free_cloth_conserves_momentum(rng):
    sim = free_cloth(6, damping=0.3)
    shape = sim.positions.shape
    sim.set_state(sim.positions + 0.03 * rng.standard_normal(shape), rng.standard_normal(shape))
    mass = sim.model.mass
    before = mass @ sim.velocities
    sim.advance(200 * sim.dt)
    after = mass @ sim.velocities
    np.testing.assert_allclose(
        after, before, atol=1e-12 * np.abs(mass @ np.abs(sim.velocities)).sum()
    )


# -- settling and equilibrium -------------------------------------------------


def settle(sim, max_seconds=30.0, threshold=1e-10):
    """Run until kinetic energy is below ``threshold`` (J)."""
    while sim.time < max_seconds:
        sim.advance(0.1)
        assert np.isfinite(sim.positions).all()
        if sim.energy()["kinetic"] < threshold:
            return sim
    raise AssertionError(f"did not settle in {max_seconds} s")


@pytest.fixture(scope="module")
def settled_cloth():
    scene = small_scene(8, stiffness=50.0, damping=0.5, air_damping=1.0)
    sim = Simulation(scene)
    sim.dt = 0.5 * sim.stable_dt()
    return settle(sim)


def test_damped_cloth_comes_to_rest_with_pins_in_place(settled_cloth):
    sim = settled_cloth
    pinned = sim.model.pinned
    assert pinned.sum() == 2
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    assert sim.energy()["kinetic"] < 1e-10


def independent_static_solve(scene):
    """Minimise the cloth's potential energy, written here from the documented
    parameterisation with explicit spring lists (not the solver's code)."""
    nx, ny = scene.cloth.resolution
    width, height = scene.cloth.size
    hx, hy = width / (nx - 1), height / (ny - 1)
    x0 = pvcloth.build_model(scene).rest_positions  # the placement is checked elsewhere
    wx = np.ones(nx)
    wx[[0, -1]] = 0.5
    wy = np.ones(ny)
    wy[[0, -1]] = 0.5
    mass = scene.cloth.mass * np.outer(wy, wx).ravel() / np.outer(wy, wx).sum()
    a, b, k = [], [], []
    families = {
        "structural": [(1, 0), (0, 1)],
        "shear": [(1, 1), (1, -1)],
        "bending": [(2, 0), (0, 2)],
    }
    for family, offsets in families.items():
        stiffness = getattr(scene.springs, family).stiffness
        for di, dj in offsets:
            for j in range(ny):
                for i in range(nx):
                    if not (0 <= i + di < nx and 0 <= j + dj < ny):
                        continue
                    share = 1.0
                    if dj == 0:
                        share = hy / hx * wy[j]
                    elif di == 0:
                        share = hx / hy * wx[i]
                    a.append(i + nx * j)
                    b.append(i + di + nx * (j + dj))
                    k.append(stiffness * share)
    a, b, k = np.array(a), np.array(b), np.array(k)
    rest = np.linalg.norm(x0[b] - x0[a], axis=1)
    g = np.array(scene.gravity)
    free = ~pvcloth.build_model(scene).pinned

    def energy(flat):
        x = x0.copy()
        x[free] = flat.reshape(-1, 3)
        d = x[b] - x[a]
        length = np.linalg.norm(d, axis=1)
        e = 0.5 * np.sum(k * (length - rest) ** 2) - mass @ x @ g
        grad = -np.outer(mass, g)
        t = (k * (length - rest) / length)[:, None] * d
        np.add.at(grad, b, t)
        np.add.at(grad, a, -t)
        return e, grad[free].ravel()

    result = minimize(
        energy,
        x0[free].ravel(),
        jac=True,
        method="L-BFGS-B",
        options={"maxiter": 20000, "gtol": 1e-12, "ftol": 1e-15},
    )
    x = x0.copy()
    x[free] = result.x.reshape(-1, 3)
    return x, mass


def test_equilibrium_sag_matches_an_independent_static_solve(settled_cloth):
    sim = settled_cloth
    x_static, mass = independent_static_solve(sim.scene)
    x0 = sim.model.rest_positions
    sag_static = mass @ (x0[:, 2] - x_static[:, 2]) / mass.sum()
    sag_dynamic = mass @ (x0[:, 2] - sim.positions[:, 2]) / mass.sum()
    assert sag_static > 0.01  # a real sag, not a rounding error
    assert sag_dynamic == pytest.approx(sag_static, rel=0.01)
    # and point by point, within 1 % of the largest displacement
    largest = np.abs(x_static - x0).max()
    assert np.abs(sim.positions - x_static).max() < 0.01 * largest


# -- pins, clock and divergence -------------------------------------------------


def test_advance_carries_leftover_time_between_calls():
    sim = Simulation(small_scene(5, dt=1e-3))
    for _ in range(60):
        sim.advance(1 / 60)
    assert sim.steps == 1000
    assert sim.time == pytest.approx(1.0, abs=1e-12)
    sim.advance(0.0)
    assert sim.steps == 1000


def test_a_moving_pin_drags_its_neighbours():
    sim = Simulation(small_scene(6, damping=0.2, air_damping=1.0, dt=5e-4))
    corner = (5, 5)
    k = sim.point_index(corner)
    start = sim.positions[k].copy()
    goal = start + np.array([0.3, 0.0, 0.2])
    sim.move_pin(corner, goal)
    sim.advance(0.05)
    np.testing.assert_array_equal(sim.positions[k], goal)
    neighbour = sim.point_index((4, 5))
    assert sim.positions[neighbour, 0] - sim.model.rest_positions[neighbour, 0] > 0.01
    other = sim.point_index((0, 5))
    np.testing.assert_array_equal(sim.positions[other], sim.model.rest_positions[other])


def test_extra_pins_can_be_added_and_dropped():
    sim = Simulation(small_scene(5))
    sim.pin((2, 2))
    assert sim.control.inv_mass[sim.point_index((2, 2))] == 0.0
    sim.restore_scene_pins()
    assert set(sim.pinned_indices) == set(np.flatnonzero(sim.model.pinned))


@pytest.mark.parametrize("damping", [0.0, 0.5])
def test_symplectic_stable_step_estimate_is_sharp(damping):
    scene = small_scene(
        8, stiffness=400.0, damping=damping, pins=PinSpec(corners=()), gravity=(0, 0, 0)
    )
    limit = Simulation(scene).stable_dt()
    rng = np.random.default_rng(1)
    # A small kick keeps the cloth linear, where the estimate is exact. (Far
    # from rest, nonlinear coupling can destabilise a step above ~0.8 of it.)
    kick = 1e-6 * rng.standard_normal((64, 3))
    for factor, should_diverge in ((0.95, False), (1.05, True)):
        sim = Simulation(scene, dt=factor * limit, stability="ignore")
        sim.set_state(positions=sim.positions + kick)
        try:
            sim.advance(3000 * sim.dt)
            diverged = False
        except DivergenceError:
            diverged = True
        assert diverged == should_diverge, f"dt = {factor} x estimate"


def test_divergence_stops_with_a_helpful_error():
    sim = Simulation(small_scene(8, stiffness=1000.0), dt=0.05, stability="ignore")
    with pytest.raises(DivergenceError) as caught:
        sim.advance(5.0)
    message = str(caught.value)
    for words in ("diverged at t =", "symplectic_euler", "dt = 0.05", "try dt ="):
        assert words in message
    assert np.isfinite(sim.positions).all()  # left at the last good step


@pytest.mark.parametrize("name", ["hanging", "curtain", "hammock", "banner", "flag"])
def test_bundled_scene_runs_stably_with_pins_in_place(name, scenes_dir):
    sim = Simulation.from_file(scenes_dir / f"{name}.toml")
    assert sim.dt < sim.stable_dt()
    sim.advance(1.0)
    pinned = sim.model.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    assert np.isfinite(sim.positions).all()
    assert sim.positions[~pinned, 2].mean() < sim.model.rest_positions[~pinned, 2].mean()
