"""The model holds what the scene asks for, in VTK point order, with forces
that have the right sign, no NaN, and Jacobians that match the forces."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import free_cloth, small_scene
from pvcloth import PinSpec, SpringsSpec, build_model
from pvcloth.physics.springs import Springs


def test_model_builds_only_the_terms_the_scene_needs():
    scene = small_scene(6).replace(springs=SpringsSpec(bending=None), gravity=(0, 0, 0))
    names = [term.name for term in build_model(scene).forces]
    assert names == ["structural springs", "shear springs"]
    with_air = small_scene(6, air_damping=0.5)
    assert "air damping" in [t.name for t in build_model(with_air).forces]


@pytest.mark.parametrize(("nx", "ny"), [(2, 2), (3, 5), (7, 4)])
def test_spring_counts(nx, ny):
    scene = small_scene().replace(cloth=pvcloth.ClothSpec(resolution=(nx, ny)))
    counts = {s.family: s.count for s in build_model(scene).springs}
    assert counts["structural"] == (nx - 1) * ny + nx * (ny - 1)
    assert counts["shear"] == 2 * (nx - 1) * (ny - 1)
    assert counts.get("bending", 0) == max(nx - 2, 0) * ny + nx * max(ny - 2, 0)


def test_point_order_is_vtk_order_and_masses_sum():
    scene = small_scene().replace(
        cloth=pvcloth.ClothSpec(size=(2, 1), resolution=(5, 3), mass=0.7, center=(0, 0, 0))
    )
    model = build_model(scene)
    nx = 5
    for k in (0, 1, 4, 5, 14):
        i, j = k % nx, k // nx
        expected = (-1.0 + 2.0 * i / 4, 0.0, -0.5 + 1.0 * j / 2)
        np.testing.assert_allclose(model.rest_positions[k], expected, atol=1e-15)
    assert model.mass.sum() == pytest.approx(0.7, rel=1e-14)
    assert model.mass[0] == pytest.approx(model.mass[nx + 1] / 4)  # corner vs interior


def test_pins_by_corner_edge_point_and_index():
    pins = PinSpec(corners=("bottom-right",), edges=("left",), points=((2, 1),), indices=(7,))
    scene = small_scene().replace(cloth=pvcloth.ClothSpec(resolution=(4, 3)), pins=pins)
    pinned = set(np.flatnonzero(build_model(scene).pinned))
    assert pinned == {3, 0, 4, 8, 2 + 4 * 1, 7}


def two_points(separation, velocity=(0.0, 0.0, 0.0), k=10.0, c=0.0):
    x = np.array([[[0.0, 0.0, 0.0], [separation, 0.0, 0.0]]])  # (ny=1, nx=2, 3)
    springs = Springs.build("structural", np.array([[[0, 0, 0], [1.0, 0, 0]]]), k, c, (1.0, 1.0))
    v = np.zeros((2, 3))
    v[1] = velocity
    f = np.zeros((2, 3))
    springs.accumulate(x.reshape(2, 3), v, f)
    return f, springs


def test_stretched_spring_pulls_and_compressed_spring_pushes():
    f, _ = two_points(1.5)
    assert f[0, 0] > 0 and f[1, 0] < 0  # ends pulled together
    f, _ = two_points(0.5)
    assert f[0, 0] < 0 and f[1, 0] > 0  # ends pushed apart
    f, springs = two_points(1.5)
    k = springs.groups[0].stiffness.item()
    assert f[0, 0] == pytest.approx(k * 0.5)  # Hooke: k (L - L0)


def test_dashpot_resists_separation():
    f, _ = two_points(1.0, velocity=(2.0, 0.0, 0.0), c=0.3)
    assert f[1, 0] < 0 and f[0, 0] == pytest.approx(-f[1, 0])


def test_coincident_points_give_no_nan():
    f, _ = two_points(0.0, velocity=(1.0, 0.0, 0.0), c=0.3)
    assert np.isfinite(f).all()
    sim = free_cloth(4, damping=0.1)
    sim.set_state(positions=np.broadcast_to(sim.positions[0], sim.positions.shape))  # one spot
    sim.advance(10 * sim.dt)
    assert np.isfinite(sim.positions).all()


def test_internal_forces_sum_to_zero(rng):
    sim = free_cloth(6, damping=0.2, air_damping=0.0)
    x = sim.state.x + 0.05 * rng.standard_normal(sim.state.x.shape)
    v = rng.standard_normal(x.shape)
    f = sim.model.compute_forces(x, v)
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * np.abs(f).max()


def test_potential_gradient_is_minus_force(rng):
    model = build_model(small_scene(5))
    x = model.rest_positions + 0.03 * rng.standard_normal(model.rest_positions.shape)
    f = model.compute_forces(x, np.zeros_like(x))
    h = 1e-6
    for k in rng.choice(x.size, 12, replace=False):
        xp, xm = x.copy(), x.copy()
        xp.flat[k] += h
        xm.flat[k] -= h
        grad = (model.potential_energy(xp) - model.potential_energy(xm)) / (2 * h)
        assert grad == pytest.approx(-f.flat[k], rel=1e-5, abs=1e-7)


def numeric_jacobian_columns(function, arr, columns, h=1e-6):
    """Central differences of ``function(arr)`` along the given flat entries."""
    for k in columns:
        plus, minus = arr.copy(), arr.copy()
        plus.flat[k] += h
        minus.flat[k] -= h
        yield k, (function(plus) - function(minus)).ravel() / (2 * h)


def stretched_state(model, rng):
    # Every spring stretched: the clamp on the transverse term is inactive,
    # so the analytic Jacobian must equal the true derivative.
    x = 1.2 * model.rest_positions + 0.01 * rng.standard_normal(model.rest_positions.shape)
    return x, rng.standard_normal(x.shape)


def test_position_jacobian_matches_finite_differences(rng):
    model = build_model(small_scene(4))  # undamped: dF/dx is exact
    x, v = stretched_state(model, rng)
    dfdx, _ = model.jacobians(x, v)
    columns = rng.choice(x.size, 12, replace=False)
    for k, column in numeric_jacobian_columns(lambda y: model.compute_forces(y, v), x, columns):
        np.testing.assert_allclose(dfdx[:, k].toarray().ravel(), column, atol=1e-5)


def test_velocity_jacobian_matches_finite_differences(rng):
    model = build_model(small_scene(4, damping=0.3, air_damping=0.2))
    x, v = stretched_state(model, rng)
    _, dfdv = model.jacobians(x, v)
    columns = rng.choice(x.size, 12, replace=False)
    for k, column in numeric_jacobian_columns(lambda w: model.compute_forces(x, w), v, columns):
        np.testing.assert_allclose(dfdv[:, k].toarray().ravel(), column, atol=1e-6)
