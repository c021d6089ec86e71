"""L-BFGS in place of Chebyshev for the fast implicit integrators
(``solver.accelerator = "lbfgs"``): downhill on the step's own potential,
written separately in ``backward_euler``, and closer to the converged step
than Chebyshev for the same count of iterations."""

import copy

import numpy as np
import pytest

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import Simulation
from pvcloth.physics.integrators import get_integrator
from pvcloth.physics.integrators.backward_euler import _StepPotential
from pvcloth.physics.springs import BlockPattern

DT = 1 / 60


def swinging(scene, seconds: float) -> Simulation:
    sim = Simulation(scene, integrator="fast_mass_spring", dt=DT)
    sim.advance(seconds)
    return sim


def step_end(sim, name: str, accelerator: str, iterations: int) -> np.ndarray:
    """Where one step of a new ``name`` integrator takes ``sim``'s state."""
    integrator = get_integrator(name, accelerator=accelerator)
    integrator.iterations = iterations  # 0 too: the start of the iterations
    return integrator.step(sim.model, sim.state, sim.control, DT).x.copy()


def test_every_iteration_lowers_the_step_potential():
    """Backward Euler's step minimises a potential (inertia, springs,
    gravity); ``backward_euler`` computes it on its own. Each L-BFGS
    iteration, the first (a plain local/global iteration) included, ends
    lower on it than the one before: with an Armijo line search the step
    cannot climb, whatever the count (Chebyshev's extrapolation can)."""
    scene = small_scene(12, stiffness=2000.0, orientation="horizontal", dt=DT)
    scene = scene.with_overrides({"pins.corners": ["top-left", "top-right"]})
    sim = swinging(scene, 0.3)
    model = sim.model
    table = model.spring_table()
    potential = _StepPotential(
        model,
        sim.positions,
        sim.velocities,
        DT,
        sim.control.inv_mass,
        BlockPattern(table.a, table.b, model.n_points),
    )
    ends = [step_end(sim, "fast_mass_spring", "lbfgs", k) for k in range(16)]
    changes = np.array([potential.change(a, b) for a, b in zip(ends[:-1], ends[1:], strict=True)])
    assert (changes < 0).all(), changes
    assert abs(changes[-1]) > 1e-6 * abs(changes[0])  # far above round-off: still falling
    # the same measure tells Chebyshev's iterations climb (here at the second)
    chebyshev = [step_end(sim, "fast_mass_spring", "chebyshev", k) for k in range(16)]
    assert (
        max(potential.change(a, b) for a, b in zip(chebyshev[:-1], chebyshev[1:], strict=True)) > 0
    )


@pytest.mark.parametrize("name", ["fast_mass_spring", "fast_bdf2"])
def test_closer_to_the_converged_step_than_chebyshev_for_the_same_iterations(name):
    """One frame step of the cotton scene at 16x16 points while it swings:
    the distance from the step solved to convergence after 20 and 50
    iterations (at 64x64 points: ``benchmarks/results/accelerators.md``)."""
    scene = pvcloth.load_scene(SCENES / "cotton.toml").with_resolution(16)
    sim = Simulation(scene, integrator=name)
    sim.advance(0.3)

    def end(accelerator, iterations):
        integrator = sim.integrator
        saved = (integrator.accelerator, integrator.iterations)
        history = copy.deepcopy(getattr(integrator, "history", None))  # fast_bdf2's
        integrator.accelerator, integrator.iterations = accelerator, iterations
        try:
            return integrator.step(sim.model, sim.state, sim.control, DT).x.copy()
        finally:
            integrator.accelerator, integrator.iterations = saved
            if history is not None:
                integrator.history = history

    converged = end("lbfgs", 2000)
    # L-BFGS stops where the energy rounds away its changes
    np.testing.assert_allclose(end("chebyshev", 3000), converged, atol=5e-6)
    for iterations in (20, 50):
        lbfgs, chebyshev = (
            np.sqrt(((end(kind, iterations) - converged) ** 2).sum(axis=1).mean())
            for kind in ("lbfgs", "chebyshev")
        )
        assert lbfgs < 0.8 * chebyshev, (iterations, lbfgs, chebyshev)


def test_accelerator_is_a_scene_key_and_a_live_edit():
    scene = small_scene(6, dt=DT, integrator="fast_bdf2")
    sim = Simulation(scene)
    assert sim.integrator.accelerator == "chebyshev"
    sim.update({"solver.accelerator": "lbfgs"})
    assert sim.integrator.accelerator == "lbfgs"
    assert "lbfgs accelerator" in dict(sim.scene.summary())["solver"]
    assert sim.snapshot().integrator == "fast_bdf2+lbfgs"  # what the window shows
    sim.update({"solver.integrator": "rk4", "solver.dt": None})  # the i key's way
    assert sim.snapshot().integrator == "rk4"  # no accelerator for one that does not iterate
    sim.update({"solver.integrator": "fast_bdf2", "solver.dt": None})
    sim.advance(0.1)
    assert np.isfinite(sim.positions).all()
    with pytest.raises(pvcloth.SceneError, match=r"solver.accelerator.*chebyshev, lbfgs"):
        scene.with_overrides({"solver.accelerator": "newton"})


def test_the_compiled_two_loop_recursion_is_the_numpy_one(rng):
    """The direction and its product with ``A`` from three remembered pairs,
    on a diagonal ``A`` (solved by division), compiled and in NumPy; and,
    as L-BFGS's defining property, ``H y = s`` for the newest pair."""
    from pvcloth.physics.lbfgs import Memory

    n, diagonal = 7, rng.uniform(1.0, 2.0, size=(7, 1))
    fixed = np.array([0])

    def solve(rhs, out):
        np.divide(rhs, diagonal, out=out)

    memory = Memory(3, n)
    x, g = rng.standard_normal((n, 3)), rng.standard_normal((n, 3))
    x[fixed] = g[fixed] = 0.0
    for _ in range(4):  # four pairs: the first is forgotten
        x1, g1 = x + rng.standard_normal((n, 3)), g + rng.standard_normal((n, 3))
        x1[fixed] = g1[fixed] = 0.0
        if np.vdot(x1 - x, g1 - g) < 0:
            g1 = g - (g1 - g)  # keep the pair's curvature positive
        assert memory.remember(x, x1, g, g1, diagonal * x, diagonal * x1)
        x, g, newest = x1, g1, (x1 - x, g1 - g)
    assert len(memory.slots) == 3
    gradient = rng.standard_normal((n, 3))
    results = []
    for compiled in (True, False):
        direction, product = np.empty((n, 3)), np.empty((n, 3))
        memory.direction(gradient, solve, fixed, direction, product, compiled)
        results.append((direction, product))
    (d1, p1), (d0, p0) = results
    np.testing.assert_allclose(d1, d0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(p1, p0, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(p0, diagonal * d0, atol=1e-12)  # A d rides along
    assert (d0[fixed] == 0).all()
    move, change = newest
    memory.direction(-change, solve, fixed, d0, p0, False)  # H y
    np.testing.assert_allclose(d0, move, atol=1e-12)


def test_fast_bdf2_takes_fewer_iterations_with_lbfgs():
    assert get_integrator("fast_bdf2", 5, "lbfgs").iterations == 5
    with pytest.raises(pvcloth.InputError, match="at least 5 iterations a step with the lbfgs"):
        get_integrator("fast_bdf2", 4, "lbfgs")
    with pytest.raises(pvcloth.InputError, match="at least 10 iterations a step with the che"):
        get_integrator("fast_bdf2", 5, "chebyshev")


def test_a_pair_turned_away_leaves_the_memory_as_it_was(rng):
    """A full memory offered a pair of negative curvature (a fold makes the
    step's energy non-convex) keeps its pairs: the direction, and ``A``
    times it, are those of before."""
    from pvcloth.physics.lbfgs import Memory

    n, diagonal = 5, rng.uniform(1.0, 2.0, size=(5, 1))
    fixed = np.array([], dtype=int)

    def solve(rhs, out):
        np.divide(rhs, diagonal, out=out)

    memory = Memory(2, n)
    x, g = np.zeros((n, 3)), np.zeros((n, 3))
    for _ in range(2):
        move = rng.standard_normal((n, 3))
        assert memory.remember(
            x, x + move, g, g + diagonal * move, diagonal * x, diagonal * (x + move)
        )
        x, g = x + move, g + diagonal * move
    gradient = rng.standard_normal((n, 3))
    before = np.empty((n, 3)), np.empty((n, 3))
    memory.direction(gradient, solve, fixed, *before, compiled=False)
    slots = list(memory.slots)
    move = rng.standard_normal((n, 3))
    assert not memory.remember(x, x + move, g, g - move, diagonal * x, diagonal * (x + move))
    assert memory.slots == slots
    after = np.empty((n, 3)), np.empty((n, 3))
    memory.direction(gradient, solve, fixed, *after, compiled=False)
    np.testing.assert_array_equal(after[0], before[0])
    np.testing.assert_allclose(after[1], diagonal * after[0], atol=1e-12)  # still A d
