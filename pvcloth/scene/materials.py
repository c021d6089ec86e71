"""Fabric presets from measured cloth: ``cloth.material = "cotton"``.

The numbers come from the ten fabrics Wang, Ramamoorthi and O'Brien measured
("Data-Driven Elastic Models for Cloth: Modeling and Measurement", ACM
Transactions on Graphics 30(4), 2011), as distributed with the ARCSim cloth
simulator (one file per fabric, named below). Each file holds the areal
density and, at six strain levels, the membrane stiffnesses ``c11`` (warp),
``c22`` (weft), ``c12`` (coupling) and ``c33`` (shear) in N/m, and bending
stiffnesses in N m. pvcloth's springs are isotropic and linear, so each
fabric is reduced to

- ``stretch``: the mean over the six strain levels of ``(c11 + c22) / 2``;
- ``shear``: the median of the six ``c33`` (the median, because a few of the
  measured values are negative: the fit is noisy there);
- ``bending_rigidity``: the mean of the bending samples, reported for
  reference only.

and mapped onto the spring families (see :mod:`pvcloth.scene.spec` for their
units). Bending springs are a regulariser, not a plate model (their energy
is not quadratic in the fold angle), so no mapping of a bending rigidity
onto them is faithful: they get :data:`BENDING_SHARE` of the stretch
stiffness, as the bundled scenes use. In a uniform stretch every family
stretches: per unit of its per-cloth stiffness, the shear family adds 1 to
the sheet's stretch modulus (besides its shear modulus of 1) and the bending
family 4 (springs twice as long, overlapping: ``4 (1 - 1/(n - 1))`` on ``n``
points, measured). So the shear family gets ``shear`` and the structural
family ``stretch - shear - 4 bending``: the sheet then stretches and shears
as measured (``tests/test_materials.py`` checks the energy of uniform
strains, on square cells).
No damping was measured; each family's dashpot is its stiffness times
:data:`DAMPING_TIME`. The cloth's mass is the density times its area.

Anything the scene gives explicitly (``cloth.mass``, a spring family's
``stiffness`` or ``damping``) overrides the preset.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from pvcloth.errors import SceneError
from pvcloth.scene.validation import choice

#: Bending springs' stiffness as a share of the stretch stiffness.
BENDING_SHARE = 0.01
#: What the bending family adds to the sheet's stretch modulus per unit of its
#: stiffness (the limit of many points).
BENDING_STRETCH = 4.0
#: Dashpot of each family: its stiffness times this (s), as the bundled
#: hanging scene has it (0.1 N s/m on 400 N/m).
DAMPING_TIME = 2.5e-4


@dataclass(frozen=True)
class Fabric:
    """One measured fabric, reduced as the module docstring says.

    Attributes
    ----------
    source : str
        The ARCSim material file the numbers come from.
    composition, use : str
        As the data set describes the fabric.
    density : float
        kg/m^2.
    stretch : float
        N/m, the sheet's membrane stiffness.
    shear : float
        N/m.
    bending_rigidity : float
        N m (reported, not mapped onto springs).
    """

    source: str
    composition: str
    use: str
    density: float
    stretch: float
    shear: float
    bending_rigidity: float


#: The presets: name -> fabric.
MATERIALS: dict[str, Fabric] = {
    "cotton": Fabric(
        "royal-target.json", "65% cotton, 35% polyester", "pants", 0.220, 2112.0, 40.3, 1.71e-4
    ),
    "denim": Fabric(
        "11oz-black-denim.json", "99% cotton, 1% spandex", "jeans", 0.324, 636.0, 69.5, 7.23e-5
    ),
    "polyester": Fabric(
        "tango-red-jet-set.json", "100% polyester", "jacket", 0.113, 205.0, 9.1, 1.88e-5
    ),
    "knit": Fabric(
        "ivory-rib-knit.json", "95% cotton, 5% spandex", "underwear", 0.276, 110.0, 8.3, 4.63e-5
    ),
    "tshirt": Fabric(
        "gray-interlock.json", "60% cotton, 40% polyester", "t-shirt", 0.187, 183.0, 27.5, 2.18e-5
    ),
}


def preset(name: Any, size: tuple[float, float]) -> dict[str, float]:
    """The dotted scene keys a material sets on a cloth of ``size`` (m).

    Examples
    --------
    >>> values = preset("cotton", (1.0, 1.0))
    >>> values["cloth.mass"], values["springs.structural.stiffness"]
    (0.22, 1987.22)
    """
    fabric = MATERIALS[choice("cloth.material", name, sorted(MATERIALS))]
    width, height = size
    bending = BENDING_SHARE * fabric.stretch
    stiffness = {
        "structural": fabric.stretch - fabric.shear - BENDING_STRETCH * bending,
        "shear": fabric.shear,
        "bending": bending,
    }
    values = {"cloth.mass": round(fabric.density * width * height, 12)}
    for family, k in stiffness.items():
        values[f"springs.{family}.stiffness"] = round(k, 9)
        values[f"springs.{family}.damping"] = round(k * DAMPING_TIME, 12)
    return values


def expand_material(data: dict) -> dict:
    """Scene data (nested tables, as :meth:`pvcloth.Scene.from_dict`
    receives them) with ``cloth.material`` replaced by what it presets,
    keeping every key the data gives itself. ``data`` is not changed."""
    cloth = data.get("cloth")
    if not isinstance(cloth, dict) or "material" not in cloth:
        return data
    data = copy.deepcopy(data)
    cloth = data["cloth"]
    name = cloth.pop("material")
    size = cloth.get("size", (1.0, 1.0))
    try:
        width, height = (float(v) for v in size)
    except (TypeError, ValueError):
        raise SceneError("cloth.size", f"expected two lengths in metres, got {size!r}") from None
    springs = data.setdefault("springs", {})
    if not isinstance(springs, dict):
        return data  # the scene's own validation names the bad table
    for key, value in preset(name, (width, height)).items():
        section, *rest = key.split(".")
        if section == "cloth":
            cloth.setdefault(rest[0], value)
            continue
        family, field = rest
        if family in springs and springs[family] is None:
            continue  # the scene leaves this family out
        table = springs.setdefault(family, {})
        if isinstance(table, dict):
            table.setdefault(field, value)
    return data
