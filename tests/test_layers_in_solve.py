"""The cloth's layers inside Newton's solve (``LayerPenalty``): its force is
its potential's slope and its Hessian the force's, the friction after the
step keeps Coulomb's law and momentum, a towel folded on itself rests at
one step a frame with nothing left for the response after the step, and
friction between its layers holds it on a slope."""

from __future__ import annotations

import numpy as np
import pytest
from derivatives import (
    assert_force_is_minus_the_energy_slope,
    assert_hessian_is_minus_the_force_derivative,
)
from intersections import count_self_intersections

from pvcloth.physics.integrators import penalties
from pvcloth.physics.self_collision import SelfCollision
from pvcloth.physics.self_collision.response import rub

THICKNESS = 0.004


def two_layers(rng, squeeze=0.5):
    """A 3x6 grid whose left half lies over its right half (folded at the
    middle), ``THICKNESS + squeeze`` penalty layers above it, a little
    rumpled: ``(contact, positions, every VF pair)``."""
    ny, nx = 3, 6
    contact = SelfCollision((ny, nx), THICKNESS, friction=0.3)
    spacing = 0.02
    x = np.zeros((ny * nx, 3))
    layer = penalties.PENALTY_LAYER * THICKNESS
    for row in range(ny):
        for col in range(nx):
            i = row * nx + col
            mirror = nx - 1 - col if col < nx // 2 else col
            height = THICKNESS + squeeze * layer if col < nx // 2 else 0.0
            x[i] = (mirror * spacing, row * spacing, height)
    x += 1e-4 * rng.normal(size=x.shape)
    points = np.arange(ny * nx)
    pairs = [
        (0, p, t)
        for p in points
        for t in range(len(contact.triangles))
        if p not in contact.triangles[t]
    ]
    return contact, x, np.array(pairs, np.int64)


def test_the_layers_penalty_force_is_its_potential_s_slope_and_its_hessian_the_force_s():
    """``add_force`` is minus the slope of ``change`` along random moves
    (central differences), and ``hessian`` is minus the force's slope:
    the gap along the pair's fixed direction is linear, so the Hessian is
    exact where the layers press."""
    rng = np.random.default_rng(5)
    contact, x, pairs = two_layers(rng)
    inv_mass = np.full(len(x), 100.0)
    inv_mass[0] = 0.0  # a pinned corner: its pairs take the others' mass
    penalty = penalties.LayerPenalty(contact, pairs, x, x, inv_mass, 1 / 60)
    force = np.zeros_like(x)
    penalty.add_force(x, force)
    assert penalty.held(x).pushed.size >= 6  # the layers press
    assert np.abs(force.sum(axis=0)).max() < 1e-9 * np.abs(force).max()  # action, reaction
    assert_force_is_minus_the_energy_slope(penalty, x, rng)
    hessian = assert_hessian_is_minus_the_force_derivative(penalty, x, rng)
    np.testing.assert_allclose(hessian, hessian.T)


def test_the_layers_rest_in_the_penalty_s_layer_outside_the_thickness():
    """A pair pressed by ``m g`` sinks ``sqrt(g l) / omega`` into the layer
    (the cubic law ``k D^2 / l = m g``, ``k = m omega^2``): far less than
    the layer, so the response after the step (at the thickness) finds
    nothing to push."""
    layer = penalties.PENALTY_LAYER * THICKNESS
    scale = max(layer, penalties.PENALTY_SCALE)
    mass = 0.01
    stiffness = np.array([mass * penalties.PENALTY_FREQUENCY**2])
    law = penalties.PenaltyLaw(stiffness, layer, np.array([0.0]), 1 / 60, damped=False)
    sink = np.sqrt(9.81 * scale) / penalties.PENALTY_FREQUENCY
    assert law.force(np.array([layer - sink]))[0] == pytest.approx(mass * 9.81, rel=1e-12)
    assert sink < 0.1 * layer


def test_friction_between_held_layers_sticks_within_the_cone_and_slides_at_the_coulomb_rate():
    """One pair, a point over a triangle's middle: a relative tangential
    velocity within ``friction`` times the push's normal change is stopped,
    one beyond it is slowed by exactly that much; momentum is kept and the
    normal velocity is left as the solve made it."""
    rng = np.random.default_rng(2)
    corners = np.array([[0, 1, 2, 3]])
    weights = np.array([[1.0, -1 / 3, -1 / 3, -1 / 3]])
    normal = np.array([[0.0, 0.0, 1.0]])
    mass = np.array([0.02, 0.01, 0.03, 0.015])
    for slide, sticks in ((0.01, True), (0.2, False)):
        v = 0.05 * rng.normal(size=(4, 3))
        tangential = np.array([slide, 0.0, 0.0]) - (weights[0] @ v) * [1, 1, 0]
        v[0] += tangential  # the pair's relative tangential velocity is (slide, 0)
        x = rng.normal(size=(4, 3))
        before_v, before_x = v.copy(), x.copy()
        pushed = np.array([0.1])  # m/s: the limit is 0.03 m/s
        stuck = rub(corners, weights, normal, pushed, x, v, 1 / mass, 0.3, 0.01)
        assert stuck == int(sticks)
        relative = weights[0] @ v
        expected = 0.0 if sticks else slide - 0.3 * 0.1
        normal_before = weights[0] @ before_v[:, 2]
        np.testing.assert_allclose(relative, [expected, 0.0, normal_before], atol=1e-12)
        np.testing.assert_allclose(mass @ v, mass @ before_v, atol=1e-15)
        np.testing.assert_allclose(x - before_x, 0.01 * (v - before_v), atol=1e-15)


def resting_towel(n, mode):
    """The towel of ``tests/contact_scenes.py`` folded and let go, played
    by ``bdf2`` at one 1/60 s step a frame to 3 s, the layers (and the
    floor) in its solve (``mode`` "in", ``[self_collision] in_solve``) or after the
    step only ("after", the default): ``(simulation, worst
    count of intersections, largest kinetic energy (J) and the response's
    pushes over the last second)``."""
    from contact_scenes import fold_a_towel  # the gallery's towel, as the other tests have it

    sim, drive = fold_a_towel(n, "bdf2", in_solve=mode == "in")
    worst = pushes = 0
    kinetic = 0.0
    while sim.state.t < 3.0 - 1e-9:
        drive(sim)
        sim.advance(1 / 60)
        worst = max(worst, count_self_intersections(sim.state.x, sim.resolution))
        if sim.state.t > 2.0:
            pushes += sim.model.self_collision.report.contacts
            kinetic = max(kinetic, sim.model.kinetic_energy(sim.velocities))
    return sim, worst, kinetic, pushes


@pytest.mark.parametrize("n", [16, pytest.param(32, marks=pytest.mark.validation)])
def test_a_towel_folded_on_itself_rests_at_one_step_a_frame(n):
    """With the layers in the solve, the fold comes to rest at one 1/60 s
    step a frame (no split for contact), its top layer held in the
    penalty's layer: over the third second the response after the step
    pushes nothing, nothing intersects, and the kinetic energy stays under
    a hundredth of the whole cloth's after one step of free fall (the bound
    of ``test_a_folded_towel_at_rest_does_not_chatter``). After the step
    alone (32x32), the top layer falls into the bottom one every step and
    is pushed back: it stays over that bound."""
    sim, worst, kinetic, pushes = resting_towel(n, "in")
    bound = 0.01 * 0.5 * sim.scene.cloth.mass * (9.81 / 60) ** 2
    assert sim.dt == pytest.approx(1 / 60) and sim.contact_step() == np.inf
    assert worst == 0 and pushes == 0
    assert len(sim.integrator.held_layers(sim.state.x).pushed) > n  # the layers do press
    assert sim.positions[:, 2].max() > 0.02  # still folded
    assert kinetic < bound, f"kinetic energy {kinetic:.2e} J at rest, bound {bound:.2e} J"
    if n >= 32:
        after, worst_after, jitter, pushes_after = resting_towel(n, "after")
        assert worst_after == 0 and pushes_after > 0
        assert jitter > bound


def test_friction_between_the_layers_in_the_solve_holds_a_fold_on_a_slope():
    """The 16x16 towel folded by ``bdf2`` with its layers in the solve and
    settled for a second, then the floor tilted by 14 degrees towards the
    crease (gravity turned instead; tan 14 = 0.25): friction 0.3 between
    the layers keeps the top layer where it lies on the bottom one over a
    second, and with none, from the same state, the top layer slides
    towards the crease. The floor's static friction (0.7) is the same in
    both. With the layers in the solve, a tilt along the crease (the
    direction ``test_friction_between_layers_holds_a_fold_on_a_slope``
    uses with the layers after the step) does not tell friction apart:
    the crease ties the top layer to the bottom one."""
    from contact_scenes import fold_a_towel

    sim, drive = fold_a_towel(16, "bdf2", friction=0.3, in_solve=True)
    while sim.state.t < 2.0 - 1e-9:
        drive(sim)
        sim.advance(1 / 60)
    top = sim.positions[:, 2] > sim.model.self_collision.thickness
    assert 60 < top.sum() < 140  # about half the cloth is the top layer
    bare, bare_drive = fold_a_towel(16, "bdf2", friction=0.0, in_solve=True)
    bare.set_state(sim.state.x, sim.state.v, sim.state.t)
    bare_drive(bare)  # past the fold's time: lets the edge go
    assert not bare.control.pinned.any()
    slid = {}
    angle = np.radians(14.0)
    for friction, towel in ((0.3, sim), (0.0, bare)):
        towel.update({"gravity": [-9.81 * np.sin(angle), 0.0, -9.81 * np.cos(angle)]})
        before = towel.positions[top, 0].mean() - towel.positions[~top, 0].mean()
        worst = 0
        while towel.state.t < 3.0 - 1e-9:
            towel.advance(1 / 60)
            worst = max(worst, count_self_intersections(towel.state.x, towel.resolution))
        assert worst == 0
        slid[friction] = towel.positions[top, 0].mean() - towel.positions[~top, 0].mean() - before
    # Measured: 0.6 mm with friction, 24 mm without (towards the crease, -x).
    assert abs(slid[0.3]) < 0.003  # held: under 3 mm relative to the bottom layer
    assert slid[0.0] < -0.012
