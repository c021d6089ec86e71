"""Wind: aerodynamic drag from relative velocity across the surface."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import SCENES, small_scene
from pvcloth import (
    ClothSpec,
    DivergenceError,
    PinSpec,
    Scene,
    SceneError,
    Simulation,
    SpringsSpec,
    WindSpec,
    build_model,
)


def wind_only(wind, orientation="horizontal", size=(2.0, 1.0)):
    scene = Scene(
        cloth=ClothSpec(size=size, resolution=(9, 5), orientation=orientation),
        springs=SpringsSpec(None, None, None),
        pins=PinSpec(corners=()),
        gravity=(0, 0, 0),
        wind=wind,
    )
    return build_model(scene)


def total_force(model, v=None):
    x = model.rest_positions
    return model.compute_forces(x, np.zeros_like(x) if v is None else v).sum(axis=0)


def test_wind_across_a_flat_cloth_pushes_with_half_rho_cd_a_w_squared():
    model = wind_only(WindSpec(velocity=(0, 0, -7.0), drag=1.3, density=1.2))
    expected = 0.5 * 1.2 * 1.3 * (2.0 * 1.0) * 7.0**2
    np.testing.assert_allclose(total_force(model), [0, 0, -expected], rtol=1e-12)


def test_wind_along_the_surface_or_moving_with_the_cloth_exerts_nothing():
    along = wind_only(WindSpec(velocity=(5.0, 3.0, 0.0)))
    np.testing.assert_allclose(total_force(along), 0, atol=1e-12)
    carried = wind_only(WindSpec(velocity=(0, 0, 4.0)))
    v = np.tile([0.0, 0.0, 4.0], (carried.n_points, 1))
    np.testing.assert_allclose(total_force(carried, v), 0, atol=1e-12)


def test_no_wind_term_unless_asked():
    assert "wind" not in [t.name for t in build_model(small_scene(5)).forces]
    windy = small_scene(5).replace(wind=WindSpec())
    assert "wind" in [t.name for t in build_model(windy).forces]


@pytest.mark.parametrize(
    ("data", "key"),
    [
        ({"wind": {"drag": -1.0}}, "wind.drag"),
        ({"wind": {"density": 0.0}}, "wind.density"),
        ({"wind": {"velocity": [1.0, float("inf"), 0.0]}}, "wind.velocity[1]"),
        ({"wind": {"speed": 3.0}}, "wind.speed"),
    ],
)
def test_bad_wind_values(data, key):
    with pytest.raises(SceneError) as caught:
        Scene.from_dict(data)
    assert caught.value.key == key


@pytest.mark.parametrize("seconds", [1.5, pytest.param(4.0, marks=pytest.mark.validation)])
def test_flag_flutters_and_stays_finite_for_a_long_run(seconds):
    sim = Simulation.from_file(SCENES / "flag.toml")
    tips = []
    for _ in range(round(seconds / 0.1)):
        sim.advance(0.1)
        tips.append(sim.positions[-1].copy())  # the top corner of the fly end
    tips = np.array(tips)
    assert np.isfinite(sim.positions).all()
    assert sim.positions[:, 0].mean() > 0.4  # blown out from the pole, not hanging
    assert tips[len(tips) // 2 :, 1].std() > 1e-3  # still moving: fluttering, not frozen


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler"])
def test_wind_of_100_m_per_s_ends_bounded_or_with_a_clear_error(integrator):
    scene = small_scene(
        10,
        stiffness=2e4,
        damping=1.0,
        air_damping=0.2,
        integrator=integrator,
        dt=1 / 120,
        stability="substep",
        pins=PinSpec(corners=(), edges=("left",)),
    )
    sim = Simulation(scene.replace(wind=WindSpec(velocity=(100.0, 20.0, 0.0))))
    try:
        sim.advance(0.5)
    except DivergenceError as error:
        assert "diverged at t =" in str(error)
        assert np.isfinite(sim.positions).all()
        return
    assert np.isfinite(sim.positions).all()
    pinned = sim.model.pinned
    np.testing.assert_array_equal(sim.positions[pinned], sim.model.rest_positions[pinned])
    # Held, not exploded: no further from the pole than the cloth's diagonal
    # plus the stretch that the whole wind force (1/2 rho C_d A w^2) would
    # cause on one row of springs, with 50 % slack.
    force = 0.5 * 1.2 * 1.0 * 1.0 * (100.0**2 + 20.0**2)
    reach = np.linalg.norm(sim.positions - sim.model.rest_positions[pinned].mean(0), axis=1)
    assert reach.max() < 1.5 * (np.sqrt(2) + force / 2e4)


def test_lift_is_across_the_wind_and_peaks_at_45_degrees():
    """A flat plate at angle of attack a feels lift 1/2 rho C_l A w^2 sin a cos a,
    perpendicular to the wind; face-on and edge-on it feels none."""
    w, area = 6.0, 2.0
    for degrees in (0.0, 20.0, 45.0, 90.0):
        a = np.radians(degrees)
        wind = np.array([w * np.cos(a), 0.0, -w * np.sin(a)])  # meets the x-y cloth at a
        lifted = total_force(wind_only(WindSpec(velocity=tuple(wind), drag=0.0, lift=1.5)))
        expected = 0.5 * 1.2 * 1.5 * area * w**2 * np.sin(a) * np.cos(a)
        assert np.linalg.norm(lifted) == pytest.approx(expected, abs=1e-9)
        assert abs(lifted @ wind) < 1e-9  # perpendicular to the relative wind


def test_gusts_are_reproducible_bounded_and_change_with_the_seed():
    def speeds(seed):
        model = wind_only(WindSpec(velocity=(0, 0, -5.0), gust=0.4, gust_period=0.3, seed=seed))
        wind = model.forces[0]
        return np.array([wind.gust_factor(t) for t in np.linspace(0, 6, 601)])

    first, again, other = speeds(7), speeds(7), speeds(8)
    np.testing.assert_array_equal(first, again)
    assert np.abs(first - other).max() > 0.05
    assert first.min() >= 0.6 and first.max() <= 1.4
    assert first.max() - first.min() > 0.3  # it does gust
    # Smooth: the cosine ramp between values 2 * gust apart changes at most
    # gust * 2 * (pi / 2) / period per second; samples are 0.01 s apart.
    assert np.abs(np.diff(first)).max() <= 0.4 * 2 * (np.pi / 2) / 0.3 * 0.01


def test_a_gusty_wind_force_follows_its_factor():
    model = wind_only(WindSpec(velocity=(0, 0, -5.0), gust=0.5, seed=3))
    wind = model.forces[0]
    steady = total_force(model)[2]
    for t in (0.0, 0.37, 1.9):
        model.set_time(t)
        assert total_force(model)[2] == pytest.approx(steady * wind.gust_factor(t) ** 2)
