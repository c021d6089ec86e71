"""The converged backward Euler reference: it solves the implicit equation
(checked against a root found independently), it is what Liu et al.'s
iterations converge to, and it says when it cannot converge."""

import numpy as np
import pytest
from scipy.optimize import fsolve

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import DivergenceError, PinSpec, Simulation, WindSpec

DT = 1 / 60


def test_one_step_is_the_root_of_the_implicit_equation():
    """A 2x2 cloth with three corners pinned leaves one free point on three
    damped springs. Its backward Euler step is the root of three equations,
    written here from Hooke's law and the dashpot on the spring's change of
    length over the step (backward Euler's value of ``c dL/dt``), and found
    by MINPACK; the integrator must land on it."""
    k, c = 300.0, 0.8
    scene = small_scene(
        2,
        stiffness=k,
        damping=c,
        pins=PinSpec(corners=(), indices=(0, 1, 2)),
        orientation="horizontal",
    )
    sim = Simulation(scene, integrator="backward_euler", dt=DT)
    push = sim.velocities.copy()
    push[3] = (0.3, -0.2, 0.5)
    sim.set_state(velocities=push)
    x0 = sim.positions.copy()
    v0 = sim.velocities[3].copy()
    mass = sim.model.mass[3]
    gravity = np.array(scene.gravity)
    # The three springs at point 3: structural to 1 and 2 (on the border,
    # so each is half the family's: a border edge belongs to one cell, not
    # two), shear to 0.
    springs = [(1, k / 2, c / 2, 1.0), (2, k / 2, c / 2, 1.0), (0, k / 10, c / 10, np.sqrt(2.0))]

    def equation(x):
        force = mass * gravity
        for other, stiffness, damping, rest in springs:
            d = x - x0[other]  # the pinned ends stay where they are
            length = np.linalg.norm(d)
            rate = (length - np.linalg.norm(x0[3] - x0[other])) / DT  # dL/dt
            force = force - (stiffness * (length - rest) + damping * rate) * d / length
        return mass * (x - x0[3] - DT * v0) - DT**2 * force

    root = fsolve(equation, x0[3] + DT * v0, xtol=1e-13)
    sim.step()
    assert sim.integrator.tolerance == 1e-3  # m/s^2 unbalanced: 2.8e-7 m at this step
    np.testing.assert_allclose(sim.positions[3], root, rtol=0, atol=1e-7)
    np.testing.assert_allclose(sim.positions[:3], x0[:3], rtol=0, atol=0)
    np.testing.assert_allclose(sim.velocities[3], (root - x0[3]) / DT, rtol=0, atol=1e-5)


def test_every_step_meets_the_stated_residual():
    """Cotton hung from two corners in a gusty wind: after every frame step
    the implicit equation holds at every free point to the stated 1e-3 m/s^2
    of unbalanced acceleration (each dashpot acting on its spring's change
    of length over the step); and at a tiny step too, where a tolerance in
    metres would take the first guess, which leaves the forces out."""
    scene = pvcloth.load_scene(SCENES / "cotton.toml").with_resolution(10)
    scene = scene.replace(wind=WindSpec(velocity=(0.0, 3.0, 0.0), gust=0.5, lift=0.3))
    sim = Simulation(scene, integrator="backward_euler")
    assert sim.dt == DT
    free = ~sim.control.pinned
    for _ in range(6):
        x, v = sim.positions.copy(), sim.velocities.copy()
        sim.step()
        x_new = sim.positions
        force = sim.model.compute_forces(x_new, (x_new - x) / DT)
        # compute_forces has each dashpot on the relative velocity along the
        # spring; the step's dashpot acts on the change of its length.
        springs = sim.model.spring_table()
        d_new, d_old = (p[springs.b] - p[springs.a] for p in (x_new, x))
        length = np.linalg.norm(d_new, axis=1)
        u = d_new / length[:, None]
        along = np.einsum("ij,ij->i", u, d_new - d_old) / DT
        rate = (length - np.linalg.norm(d_old, axis=1)) / DT
        on_a = (springs.damping * (rate - along))[:, None] * u
        np.add.at(force, springs.a, on_a)
        np.add.at(force, springs.b, -on_a)
        residual = x_new - x - DT * v - DT**2 * force / sim.model.mass[:, None]
        assert np.abs(residual[free]).max() <= 1e-3 * DT**2
        assert 1 <= sim.integrator.last_iterations <= 100
    tiny = Simulation(scene, integrator="backward_euler", dt=7e-5)
    explicit = Simulation(scene, integrator="symplectic_euler", dt=7e-5, stability="ignore")
    for sim in (tiny, explicit):
        for _ in range(20):
            sim.step()
    assert tiny.integrator.last_iterations >= 1
    np.testing.assert_allclose(tiny.positions, explicit.positions, rtol=0, atol=1e-5)


def test_it_converges_where_the_cloth_buckles():
    """The cotton scene at 1/60 s folds as it falls, where the compressed
    springs' exact Hessian is indefinite: a line search on the residual's
    norm stalled there (at 20x20 it left 2.84 m/s^2 unbalanced at t = 0.88
    s). On the step's potential every step of the first second converges."""
    scene = pvcloth.load_scene(SCENES / "cotton.toml").with_resolution(20)
    sim = Simulation(scene, integrator="backward_euler")
    iterations = []
    while sim.time < 1.0 - 1e-9:
        sim.step()
        iterations.append(sim.integrator.last_iterations)
    assert max(iterations) < sim.integrator.iterations
    lowest = sim.positions[:, 2].min()
    assert scene.cloth.center[2] - lowest > 0.5  # it fell and hangs, folded


def test_liu_iterations_converge_to_it():
    """Without dashpots or air damping (which Liu et al.'s method leaves out
    or takes explicitly), its local/global iterations, run long, reach the
    same backward Euler step by another road."""
    scene = small_scene(8, stiffness=500.0, dt=DT, orientation="horizontal")
    scene = scene.with_overrides({"pins.corners": ["top-left", "top-right"]})
    newton = Simulation(scene, integrator="backward_euler")
    liu = Simulation(
        scene.with_overrides({"solver.iterations": 4000}), integrator="fast_mass_spring"
    )
    assert liu.integrator.iterations == 4000
    for _ in range(4):
        newton.step()
        liu.step()
    moved = np.abs(newton.positions - small_start(scene)).max()
    assert moved > 0.01  # the cloth falls: the comparison is not of a resting cloth
    np.testing.assert_allclose(liu.positions, newton.positions, rtol=0, atol=1e-7)


def small_start(scene) -> np.ndarray:
    return Simulation(scene, integrator="symplectic_euler", dt=1e-3).positions


def test_a_step_that_cannot_converge_says_so():
    scene = small_scene(6, stiffness=2000.0, damping=1.0, dt=DT, orientation="horizontal")
    scene = scene.with_overrides({"pins.corners": ["top-left", "top-right"]})
    sim = Simulation(scene, integrator="backward_euler")
    sim.integrator.iterations = 1
    with pytest.raises(DivergenceError, match=r"did not converge at t = 0 s.*1 iterations"):
        sim.advance(0.5)
    assert np.isfinite(sim.positions).all()


def test_iterations_are_a_scene_key_and_a_live_edit():
    scene = small_scene(6, dt=DT, integrator="fast_mass_spring")
    sim = Simulation(scene.with_overrides({"solver.iterations": 3}))
    assert sim.integrator.iterations == 3
    assert "3 iterations" in dict(sim.scene.summary())["solver"]
    sim.update({"solver.iterations": 25})
    assert sim.integrator.iterations == 25
    with pytest.raises(pvcloth.SceneError, match="solver.iterations"):
        scene.with_overrides({"solver.iterations": 0})


def test_the_step_potential_has_the_residual_as_gradient_and_newton_as_hessian():
    """Central differences on a moving cotton cloth (springs both stretched
    and compressed), with gusty wind: the potential's change along a
    direction is ``M r / h^2`` dotted with it, and the exact Newton matrix
    is the derivative of ``M r``, both to second order (halving the step
    quarters the misfit); the clamped matrix differs from the exact one."""
    from pvcloth.physics.integrators.backward_euler import _StepPotential
    from pvcloth.physics.springs import BlockPattern

    scene = pvcloth.load_scene(SCENES / "cotton.toml").with_resolution(8)
    scene = scene.replace(wind=WindSpec(velocity=(0.0, 3.0, 0.0), gust=0.5, lift=0.3))
    sim = Simulation(scene)
    sim.advance(3 / 60)
    model, x, v, pinned = sim.model, sim.positions, sim.velocities, sim.control.pinned
    table = model.spring_table()
    pattern = BlockPattern(table.a, table.b, model.n_points)
    potential = _StepPotential(model, x, v, DT, sim.control.inv_mass, pattern)
    t = x + DT * v + 1e-3 * np.random.default_rng(3).standard_normal(x.shape)
    t[pinned] = x[pinned] + DT * v[pinned]
    potential.anchor(t)
    direction = np.random.default_rng(7).standard_normal(x.shape)
    direction[pinned] = 0.0
    mass = model.mass[:, None]
    slope = np.vdot(mass * potential.residual(t), direction) / DT**2

    def misfit_value(h):
        central = potential.change(t, t + h * direction) - potential.change(t, t - h * direction)
        return abs(central / (2 * h) - slope) / abs(slope)

    assert misfit_value(1e-5) < 1e-5
    assert misfit_value(1e-5) / misfit_value(2e-5) == pytest.approx(0.25, abs=0.05)
    exact = potential.matrix(t, exact=True, pinned=pinned)
    free = ~pinned

    def misfit_matrix(h):
        plus, minus = (potential.residual(t + s * h * direction) for s in (1, -1))
        change = (mass * (plus - minus) / 2)[free].ravel()
        return np.abs(change - exact @ (h * direction[free]).ravel()).max() / np.abs(change).max()

    assert misfit_matrix(1e-5) < 1e-6
    assert misfit_matrix(1e-5) / misfit_matrix(2e-5) == pytest.approx(0.25, abs=0.05)
    assert abs(potential.matrix(t, exact=False, pinned=pinned) - exact).max() > 0


@pytest.mark.validation
def test_it_converges_at_steps_too_small_for_the_potential_to_resolve():
    """At a 7.5e-5 s step the last Newton iterations change the potential by
    about 1e-17 J, below its rounding: a search on the potential alone
    stopped the 16x16 hanging cloth at step 2132 (t = 0.159 s) with 1e-3
    m/s^2 left, where the full step took the residual to 2e-8 m/s^2. Near
    the solution a fall of the residual's norm passes too: the run ends."""
    scene = pvcloth.load_scene(SCENES / "hanging.toml").with_resolution(16)
    sim = Simulation(scene, integrator="backward_euler", dt=7.451564828614009e-05)
    sim.advance(0.25)
    assert sim.time == pytest.approx(0.25)
