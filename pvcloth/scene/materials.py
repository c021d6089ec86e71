"""Fabric presets from measured cloth: ``cloth.material = "cotton"``.

The numbers come from the ten fabrics Wang, Ramamoorthi and O'Brien measured
("Data-Driven Elastic Models for Cloth: Modeling and Measurement", ACM
Transactions on Graphics 30(4), 2011), as distributed with the ARCSim cloth
simulator (one file per fabric, named below). Each file holds the areal
density; at six strain levels, the membrane stiffnesses ``c11`` (warp),
``c22`` (weft), ``c12`` (coupling) and ``c33`` (shear) in N/m; and bending
rigidities in N m at five curvatures in each of three directions (warp,
bias, weft: :data:`BENDING_SAMPLES`). pvcloth's material is isotropic and
linear, so each fabric is reduced to

- ``stretch``: the mean over the six strain levels of ``(c11 + c22) / 2``;
- ``shear``: the median of the six ``c33`` (the median, because a few of the
  measured values are negative: the fit is noisy there);
- ``bending_rigidity``: the mean of the fifteen bending samples (the
  directions differ by up to a factor of 2.6 and the curvatures by up to 3:
  a linear isotropic plate can only take a mean; ``tests/test_materials.py``
  checks it against the samples).

The bending rigidity goes to the cloth's plate bending
(:mod:`pvcloth.physics.bending`), a converging model of it, and the preset
builds no bending springs: their energy is not quadratic in the fold angle,
so no stiffness of theirs is faithful to a measured rigidity. In a uniform
stretch the shear springs stretch as well: per unit of their per-cloth
stiffness they add 1 to the sheet's stretch modulus (besides its shear
modulus of 1). So the shear family gets ``shear`` and the structural family
``stretch - shear``: the sheet then stretches and shears as measured
(``tests/test_materials.py`` checks the energy of uniform strains, on square
cells). Plate bending stores nothing in a uniform strain.
No damping was measured; each family's dashpot is its stiffness times
:data:`DAMPING_TIME`. The cloth's mass is the density times its area.

Anything the scene gives explicitly (``cloth.mass``, ``cloth.bending_rigidity``,
a spring family's ``stiffness`` or ``damping``, or a bending spring family of
its own) overrides the preset.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from pvcloth.errors import SceneError
from pvcloth.scene.validation import choice

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
        N m: the mean of the fabric's :data:`BENDING_SAMPLES`.
    """

    source: str
    composition: str
    use: str
    density: float
    stretch: float
    shear: float
    bending_rigidity: float


#: The measured bending rigidities (N m), as the data set's files give them:
#: rows at 0 (warp), 45 (bias) and 90 degrees (weft), the order ARCSim
#: interpolates them in; columns five curvatures, increasing.
BENDING_SAMPLES: dict[str, tuple[tuple[float, ...], ...]] = {
    "cotton": (
        (125.409805e-6, 167.284561e-6, 215.412750e-6, 215.090790e-6, 223.861038e-6),
        (107.997696e-6, 120.583267e-6, 144.141678e-6, 140.606689e-6, 153.048309e-6),
        (125.409805e-6, 167.284561e-6, 215.412750e-6, 215.090790e-6, 227.861038e-6),
    ),
    "denim": (
        (64.196457e-6, 60.286175e-6, 60.943428e-6, 62.433697e-6, 19.824701e-6),
        (73.384567e-6, 59.671982e-6, 61.080757e-6, 68.242569e-6, 36.033474e-6),
        (96.951576e-6, 107.848228e-6, 113.060738e-6, 120.569740e-6, 79.781021e-6),
    ),
    "polyester": (
        (14.293814e-6, 8.949391e-6, 30.011126e-6, 36.081490e-6, 18.363136e-6),
        (21.951700e-6, 22.446325e-6, 18.408735e-6, 19.598495e-6, 12.071854e-6),
        (20.345654e-6, 22.696880e-6, 15.698071e-6, 13.466827e-6, 7.556618e-6),
    ),
    "knit": (
        (46.237591e-6, 63.086697e-6, 83.192772e-6, 97.574425e-6, 80.726685e-6),
        (30.015930e-6, 30.097424e-6, 30.172081e-6, 30.648300e-6, 24.726685e-6),
        (32.243889e-6, 37.341282e-6, 38.817448e-6, 39.812527e-6, 30.437820e-6),
    ),
    "tshirt": (
        (23.191698e-6, 32.932217e-6, 34.406498e-6, 39.014420e-6, 23.382786e-6),
        (24.749964e-6, 18.651314e-6, 16.370552e-6, 25.095791e-6, 8.860165e-6),
        (14.267624e-6, 7.052906e-6, 14.515154e-6, 24.665127e-6, 19.383726e-6),
    ),
}


def _mean_rigidity(name: str) -> float:
    """The mean of a fabric's fifteen bending samples (N m), to three figures."""
    samples = [value for row in BENDING_SAMPLES[name] for value in row]
    return float(f"{sum(samples) / len(samples):.3g}")


#: The presets: name -> fabric.
MATERIALS: dict[str, Fabric] = {
    "cotton": Fabric(
        "royal-target.json",
        "65% cotton, 35% polyester",
        "pants",
        0.220,
        2112.0,
        40.3,
        _mean_rigidity("cotton"),
    ),
    "denim": Fabric(
        "11oz-black-denim.json",
        "99% cotton, 1% spandex",
        "jeans",
        0.324,
        636.0,
        69.5,
        _mean_rigidity("denim"),
    ),
    "polyester": Fabric(
        "tango-red-jet-set.json",
        "100% polyester",
        "jacket",
        0.113,
        205.0,
        9.1,
        _mean_rigidity("polyester"),
    ),
    "knit": Fabric(
        "ivory-rib-knit.json",
        "95% cotton, 5% spandex",
        "underwear",
        0.276,
        110.0,
        8.3,
        _mean_rigidity("knit"),
    ),
    "tshirt": Fabric(
        "gray-interlock.json",
        "60% cotton, 40% polyester",
        "t-shirt",
        0.187,
        183.0,
        27.5,
        _mean_rigidity("tshirt"),
    ),
}


def preset(name: Any, size: tuple[float, float]) -> dict[str, float]:
    """The dotted scene keys a material sets on a cloth of ``size`` (m).

    Examples
    --------
    >>> values = preset("cotton", (1.0, 1.0))
    >>> values["cloth.mass"], values["springs.structural.stiffness"]
    (0.22, 2071.7)
    >>> values["cloth.bending_rigidity"], values["springs.bending"]
    (0.000171, None)
    """
    fabric = MATERIALS[choice("cloth.material", name, sorted(MATERIALS))]
    width, height = size
    stiffness = {"structural": fabric.stretch - fabric.shear, "shear": fabric.shear}
    values: dict[str, Any] = {
        "cloth.mass": round(fabric.density * width * height, 12),
        "cloth.bending_rigidity": fabric.bending_rigidity,
    }
    for family, k in stiffness.items():
        values[f"springs.{family}.stiffness"] = round(k, 9)
        values[f"springs.{family}.damping"] = round(k * DAMPING_TIME, 12)
    values["springs.bending"] = None  # plate bending instead (module docstring)
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
        if value is None:
            continue  # a family missing from the table is not built
        family, field = rest
        if family in springs and springs[family] is None:
            continue  # the scene leaves this family out
        table = springs.setdefault(family, {})
        if isinstance(table, dict):
            table.setdefault(field, value)
    return data
