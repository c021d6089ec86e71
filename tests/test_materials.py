"""Fabric presets: the sheet built from a preset stretches and shears as the
measured fabric does, and explicit values override the preset."""

from __future__ import annotations

import numpy as np
import pytest

import pvcloth
from conftest import SCENES
from pvcloth import SceneError, build_model
from pvcloth.scene.materials import MATERIALS


def _sheet(material: str, n: int = 33) -> pvcloth.Scene:
    return pvcloth.Scene.from_dict(
        {
            "cloth": {
                "material": material,
                "size": [1.0, 1.0],
                "resolution": [n, n],
                "orientation": "horizontal",
            }
        }
    )


def _energy_density(model, deformed) -> float:
    """Elastic energy per area (J/m^2) of the flat sheet mapped by ``deformed``."""
    area = 1.0
    x = deformed(model.rest_positions - model.rest_positions.mean(axis=0))
    return sum(term.potential_energy(x) for term in model.forces if term.name != "gravity") / area


@pytest.mark.parametrize("material", sorted(MATERIALS))
def test_a_uniform_strain_costs_what_the_measured_fabric_says(material):
    # Energy density of a small uniform strain, against continuum elasticity
    # with the measured moduli: 1/2 E e^2 for a stretch e along x or y (no
    # lateral contraction), 1/2 G g^2 for a shear g.
    fabric = MATERIALS[material]
    model = build_model(_sheet(material))
    e = 1e-4
    for axis in (0, 1):
        stretched = _energy_density(model, lambda x, a=axis: x + e * x * np.eye(3)[a])
        assert stretched == pytest.approx(0.5 * fabric.stretch * e**2, rel=2e-3)
    sheared = _energy_density(model, lambda x: x + e * x[:, [1]] * np.array([1.0, 0.0, 0.0]))
    assert sheared == pytest.approx(0.5 * fabric.shear * e**2, rel=2e-2)


@pytest.mark.parametrize("material", sorted(MATERIALS))
def test_the_mass_is_the_density_times_the_area(material):
    scene = _sheet(material, 9)
    assert scene.cloth.mass == pytest.approx(MATERIALS[material].density)
    assert build_model(scene).mass.sum() == pytest.approx(scene.cloth.mass)


def test_explicit_values_override_the_preset_and_bad_names_are_refused():
    scene = pvcloth.Scene.from_dict(
        {"cloth": {"material": "denim", "mass": 0.5}, "springs": {"shear": {"stiffness": 5.0}}}
    )
    assert scene.cloth.mass == 0.5 and scene.springs.shear.stiffness == 5.0
    assert scene.springs.structural.stiffness == pytest.approx(636.0 - 69.5)
    # the same through the dotted keys of --set and live edits
    edited = pvcloth.Scene().with_overrides({"cloth.material": "polyester", "cloth.mass": 0.3})
    assert edited.cloth.mass == 0.3
    assert edited.springs.shear.stiffness == MATERIALS["polyester"].shear
    with pytest.raises(SceneError, match="cloth.material.*did you mean 'denim'"):
        pvcloth.Scene.from_dict({"cloth": {"material": "denm"}})


def test_the_bundled_cotton_scene_uses_the_preset():
    scene = pvcloth.load_scene(SCENES / "cotton.toml")
    cotton = MATERIALS["cotton"]
    assert scene.cloth.mass == pytest.approx(cotton.density)
    springs = scene.springs
    assert springs.structural.stiffness + springs.shear.stiffness == pytest.approx(cotton.stretch)
    assert springs.bending is None and scene.cloth.bending_rigidity == cotton.bending_rigidity
