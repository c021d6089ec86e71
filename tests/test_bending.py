"""Plate bending (pvcloth.physics.bending) against references of its own:
the energy of a sheet rolled to a cylinder, beam theory, and the heavy
elastica of Peirce's cantilever test solved here with SciPy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_bvp

import pvcloth
from pvcloth.physics.bending import PlateBending, bending_operator
from pvcloth.scene.materials import BENDING_SAMPLES, MATERIALS

COTTON_RIGIDITY, COTTON_DENSITY, G = 1.71e-4, 0.22, 9.81
#: Bending length of cotton (m): (B / w)^(1/3), w the weight per area.
BENDING_LENGTH = (COTTON_RIGIDITY / (COTTON_DENSITY * G)) ** (1 / 3)


def rolled(shape, spacing, curvature, angle_degrees):
    """The flat grid wrapped without stretching onto a cylinder of
    ``curvature`` (1/m), bending along a direction ``angle`` from the rows."""
    ny, nx = shape
    u, v = np.meshgrid(np.arange(nx) * spacing[0], np.arange(ny) * spacing[1])
    a = np.radians(angle_degrees)
    s = u * np.cos(a) + v * np.sin(a)  # along the bend
    t = -u * np.sin(a) + v * np.cos(a)  # along the cylinder's axis
    k = curvature
    return np.stack([np.sin(k * s) / k, t, (1 - np.cos(k * s)) / k], axis=-1).reshape(-1, 3)


@pytest.mark.parametrize("angle", [0.0, 90.0, 30.0])
def test_a_sheet_rolled_to_a_cylinder_holds_b_kappa_squared_over_two_per_area(angle):
    """A plate of Poisson ratio 0 bent to curvature kappa along direction a
    has curvatures k11 = kappa cos^2 a, k22 = kappa sin^2 a, k12 = kappa
    cos a sin a; B/2 (k11^2 + 2 k12^2 + k22^2) = B kappa^2 / 2 per area. The
    grid sees k11 on all but the first and last half cells along a row and
    k22 likewise along a column (the free edges), k12 on every cell."""
    shape, spacing, rigidity, kappa = (31, 41), (0.01, 0.015), 2e-4, 3.0
    term = PlateBending(shape, spacing, rigidity)
    energy = term.potential_energy(rolled(shape, spacing, kappa, angle))
    ny, nx = shape
    area = (nx - 1) * spacing[0] * (ny - 1) * spacing[1]
    c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
    seen = {"11": (nx - 2) / (nx - 1), "22": (ny - 2) / (ny - 1), "12": 1.0}
    expected = 0.5 * rigidity * kappa**2 * area
    expected *= c**4 * seen["11"] + s**4 * seen["22"] + 2 * c**2 * s**2 * seen["12"]
    # second differences of a circle of radius 1/kappa: second order in kappa h
    kh = kappa * max(spacing)
    assert energy == pytest.approx(expected, rel=kh**2 / 6)


def test_the_cylinders_energy_converges_on_finer_grids():
    errors = []
    for n in (11, 21, 41):
        shape, spacing = (n, n), (0.5 / (n - 1), 0.5 / (n - 1))
        energy = PlateBending(shape, spacing, 1.0).potential_energy(rolled(shape, spacing, 4.0, 30))
        errors.append(abs(energy / (0.5 * 4.0**2 * 0.25) - 1))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.03


def test_rigid_motions_store_nothing_and_forces_are_minus_the_energys_gradient(rng):
    shape, spacing = (7, 9), (0.02, 0.03)
    term = PlateBending(shape, spacing, 1e-3)
    flat = rolled(shape, spacing, 1e-9, 0.0)  # the flat sheet (curvature 1e-9 /m)
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    moved = flat @ q.T + rng.standard_normal(3)
    assert term.potential_energy(moved) == pytest.approx(0.0, abs=1e-12)
    x = flat + 0.003 * rng.standard_normal(flat.shape)
    force = np.zeros_like(x)
    term.accumulate(x, x, force)
    d = 1e-6 * rng.standard_normal(x.shape)
    change = term.potential_energy(x + d) - term.potential_energy(x - d)
    assert change / 2 == pytest.approx(-np.vdot(force, d), rel=1e-6)
    # the Jacobian is the same matrix, for each coordinate
    jx, jv = term.jacobians(x, x)
    assert jv is None
    np.testing.assert_allclose(jx @ x.ravel(), force.ravel(), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    "size",
    [
        (70, 66),
        (4, 9),  # every point within two of an edge
        (9, 4),
        (5, 2),
        (3, 12),
        # threads: the serial tier runs without pytest-xdist, whose workers
        # get one thread each
        pytest.param((130, 128), marks=pytest.mark.serial),
    ],
)
def test_the_compiled_forces_equal_numpys(rng, size):
    """The spring pass applies the plate's stencil inside and Q's rows near
    the edges, on blocks of rows that threads share out."""
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(resolution=size, bending_rigidity=3e-4),
        springs=pvcloth.SpringsSpec(bending=None),
    )
    compiled = pvcloth.build_model(scene, backend="numba")
    reference = pvcloth.build_model(scene, backend="numpy")
    x = compiled.rest_positions + 0.01 * rng.standard_normal(compiled.rest_positions.shape)
    v = rng.standard_normal(x.shape)
    np.testing.assert_allclose(
        compiled.compute_forces(x, v), reference.compute_forces(x, v), rtol=1e-9, atol=1e-9
    )


def test_a_plate_without_springs_takes_the_whole_product_compiled(rng):
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(resolution=(12, 10), bending_rigidity=3e-4),
        springs=pvcloth.SpringsSpec(structural=None, shear=None, bending=None),
    )
    compiled = pvcloth.build_model(scene, backend="numba")
    reference = pvcloth.build_model(scene, backend="numpy")
    x = compiled.rest_positions + 0.01 * rng.standard_normal(compiled.rest_positions.shape)
    v = np.zeros_like(x)
    forces = compiled.compute_forces(x, v)
    np.testing.assert_allclose(forces, reference.compute_forces(x, v), rtol=1e-9, atol=1e-12)
    assert np.abs(forces - compiled.mass[:, None] * np.array([0, 0, -9.81])).max() > 1e-3


def test_the_operator_is_symmetric_and_positive_semidefinite():
    q = bending_operator((6, 8), (0.1, 0.07)).toarray()
    np.testing.assert_allclose(q, q.T, atol=1e-9 * np.abs(q).max())
    values = np.linalg.eigvalsh(q)
    assert values.min() > -1e-9 * values.max()
    # null space: constants and the two linear functions of the flat sheet
    assert np.sum(values < 1e-9 * values.max()) == 3


# -- the cantilever ------------------------------------------------------------


def elastica(overhang: float) -> tuple[float, float]:
    """Peirce's heavy cantilever, in units of the bending length c: the angle
    theta(s) of a strip clamped level at s = 0 obeys theta'' = -(L - s) cos
    theta with theta(0) = 0 and theta'(L) = 0 (the moment of the overhanging
    weight). Returns the chord's droop in degrees (clamp to tip) and the tip
    drop in units of c."""
    s = np.linspace(0.0, overhang, 401)

    def slope(s, y):
        return np.vstack([y[1], -(overhang - s) * np.cos(y[0])])

    def ends(start, end):
        return np.array([start[0], end[1]])

    solution = solve_bvp(slope, ends, s, np.zeros((2, s.size)), tol=1e-8, max_nodes=10**5)
    assert solution.success
    theta = solution.sol(s)[0]
    drop, reach = np.trapezoid(np.sin(theta), s), np.trapezoid(np.cos(theta), s)
    return float(np.degrees(np.arctan2(drop, reach))), float(drop)


def test_the_elastica_reference_gives_peirces_41_5_degrees_at_twice_the_bending_length():
    assert elastica(2.0)[0] == pytest.approx(41.5, abs=0.05)  # ASTM D1388's angle


def cantilever(cells: int, overhang: float, integrator: str = "backward_euler", width=0.025):
    """A cotton strip ``width`` wide clamped by its first two columns of
    points and left to come to rest: its droop (degrees, the chord from the
    clamp line to the tip) and tip drop (m). Two pinned columns hold the
    strip level at the line midway between them (their difference is the
    slope there, to second order), so the overhang runs from that line."""
    nx = cells + 2
    h = overhang / (nx - 1.5)
    ny = max(3, round(width / h) + 1)
    scene = pvcloth.Scene.from_dict(
        {
            "gravity": [0.0, 0.0, -G],
            "air_damping": 0.0,
            "cloth": {
                "material": "cotton",
                "size": [(nx - 1) * h, width],
                "resolution": [nx, ny],
                "orientation": "horizontal",
                "center": [0.0, 0.0, 0.0],
            },
            "pins": {"corners": [], "points": [[i, j] for i in (0, 1) for j in range(ny)]},
            "solver": {"integrator": integrator, "dt": 0.5},
        }
    )
    sim = pvcloth.Simulation(scene)
    assert sim.scene.cloth.bending_rigidity == COTTON_RIGIDITY
    for _ in range(40):  # 0.5 s backward Euler steps: at rest in about 20
        sim.step()
    # at rest: what is left moves the tip by under 1e-4 degrees a step, far
    # below the differences between the grids the convergence test orders
    assert np.abs(sim.velocities).max() < 1e-7
    x = sim.positions.reshape(ny, nx, 3)
    clamp = 0.5 * (x[:, 0] + x[:, 1]).mean(axis=0)
    chord = x[:, -1].mean(axis=0) - clamp
    return float(np.degrees(np.arctan2(-chord[2], chord[0]))), float(-chord[2])


def test_a_cotton_strip_droops_as_the_heavy_elastica_says():
    """The quick twin of the validation test below: one grid, two overhangs."""
    for ratio in (1.0, 2.0):
        droop, _ = cantilever(12, ratio * BENDING_LENGTH)
        # within 0.05 degrees (the issue asked for 2; 0.02 is measured)
        assert droop == pytest.approx(elastica(ratio)[0], abs=0.05)


@pytest.mark.validation  # 48 cells take seconds
def test_the_droop_converges_to_the_elastica_at_every_resolution():
    for ratio in (1.0, 2.0):
        reference = elastica(ratio)[0]
        errors = [
            abs(cantilever(cells, ratio * BENDING_LENGTH)[0] - reference) for cells in (12, 24, 48)
        ]
        assert max(errors) <= 0.05, errors
        assert errors[0] > errors[1] > errors[2], errors


def test_a_small_deflection_matches_beam_theory():
    """Euler-Bernoulli: a uniformly loaded cantilever's tip drops w L^4 / (8 B)."""
    overhang = 0.5 * BENDING_LENGTH
    _, drop = cantilever(24, overhang)
    beam = COTTON_DENSITY * G * overhang**4 / (8 * COTTON_RIGIDITY)
    assert drop == pytest.approx(beam, rel=0.01)


def test_implicit_euler_comes_to_the_same_rest():
    """Implicit Euler holds Q in its Jacobian: it settles where backward
    Euler does."""
    expected, _ = cantilever(12, BENDING_LENGTH)
    droop, _ = cantilever(12, BENDING_LENGTH, "implicit_euler")
    assert droop == pytest.approx(expected, abs=0.05)


def test_fast_mass_spring_rests_where_backward_euler_rests():
    """fast_mass_spring holds Q in its prefactorised matrix. Its iterations
    converge slowly where stiff springs must turn (a cotton strip creeps
    for minutes of cloth time), so this strip has soft springs; it droops by
    twice its width, and without Q in the matrix it would hang straight."""
    nx, ny = 14, 6

    def strip(integrator, dt):
        return pvcloth.Scene.from_dict(
            {
                "gravity": [0.0, 0.0, -G],
                "air_damping": 4.0,
                "cloth": {
                    "size": [0.13, 0.05],
                    "resolution": [nx, ny],
                    "mass": COTTON_DENSITY * 0.13 * 0.05,
                    "orientation": "horizontal",
                    "center": [0.0, 0.0, 0.0],
                    "bending_rigidity": COTTON_RIGIDITY,
                },
                "springs": {"structural": {"stiffness": 20.0}, "shear": {"stiffness": 2.0}},
                "pins": {"corners": [], "points": [[i, j] for i in (0, 1) for j in range(ny)]},
                "solver": {"integrator": integrator, "dt": dt, "iterations": 50},
            }
        )

    newton = pvcloth.Simulation(strip("backward_euler", 0.5))
    for _ in range(40):
        newton.step()
    liu = pvcloth.Simulation(strip("fast_mass_spring", 1 / 60))
    liu.advance(4.0)
    assert -0.12 < newton.positions[:, 2].min() < -0.09  # bent, not hanging (-0.13)
    assert np.abs(liu.velocities).max() < 1e-4
    np.testing.assert_allclose(liu.positions, newton.positions, atol=1e-5)


# -- presets, explicit steps, checkpoints ---------------------------------------


@pytest.mark.parametrize("material", sorted(MATERIALS))
def test_each_preset_takes_the_mean_of_its_fifteen_bending_samples(material):
    samples = np.array(BENDING_SAMPLES[material])
    assert samples.shape == (3, 5)  # warp, bias, weft; five curvatures
    rigidity = MATERIALS[material].bending_rigidity
    assert rigidity == pytest.approx(samples.mean(), rel=5e-3)  # three figures
    scene = pvcloth.Scene.from_dict({"cloth": {"material": material}})
    assert scene.cloth.bending_rigidity == rigidity
    assert scene.springs.bending is None  # plate bending, not springs


def test_the_published_cotton_rigidity():
    # Wang et al. 2011's royal-target fabric, as the issue and the docs quote it
    assert MATERIALS["cotton"].bending_rigidity == 1.71e-4


def test_explicit_steps_include_bending_in_their_stable_step():
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(size=(0.2, 0.2), resolution=(21, 21), bending_rigidity=1e-2),
        springs=pvcloth.SpringsSpec(structural=pvcloth.SpringSpec(10.0), shear=None, bending=None),
    )
    without = pvcloth.Simulation(scene.with_overrides({"cloth.bending_rigidity": 0.0}))
    stiff = pvcloth.Simulation(scene)
    assert stiff.dt < 0.5 * without.dt  # the plate is the stiffest part here
    stiff.advance(0.2)  # at its own step: no divergence, energy bounded
    assert np.isfinite(stiff.positions).all()
    assert np.abs(stiff.velocities).max() < 5.0


def test_a_checkpoint_resumes_a_bending_run_bit_for_bit(tmp_path):
    scene = pvcloth.Scene.from_dict(
        {"cloth": {"material": "denim", "resolution": [12, 12]}, "solver": {"dt": 2e-4}}
    )
    sim = pvcloth.Simulation(scene)
    sim.advance(0.01)
    path = pvcloth.save_checkpoint(sim, tmp_path / "run.npz")
    sim.advance(0.01)
    resumed = pvcloth.load_checkpoint(path)
    resumed.advance(0.01)
    assert resumed.scene.cloth.bending_rigidity == MATERIALS["denim"].bending_rigidity
    assert np.array_equal(resumed.positions, sim.positions)


def test_adaptive_steps_see_the_plate():
    """rk23's error estimate includes the plate: on a sheet whose plate is its
    stiffest part, the error after t follows ``tolerance * t`` against a
    fine RK4 reference, and shrinks with the tolerance."""
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(size=(0.2, 0.2), resolution=(11, 11), bending_rigidity=1e-3),
        springs=pvcloth.SpringsSpec(structural=pvcloth.SpringSpec(10.0), shear=None, bending=None),
    )
    t = 0.1
    reference = pvcloth.Simulation(scene, integrator="rk4", dt=t / 4000, stability="ignore")
    reference.advance(t)
    errors = []
    for tolerance in (1e-3, 1e-5):
        sim = pvcloth.Simulation(
            scene.with_overrides({"solver.integrator": "rk23", "solver.tolerance": tolerance})
        )
        sim.advance(t)
        errors.append(float(np.linalg.norm(sim.positions - reference.positions, axis=1).max()))
        assert errors[-1] < tolerance * t, (tolerance, errors[-1])
    assert errors[1] < 0.1 * errors[0]
