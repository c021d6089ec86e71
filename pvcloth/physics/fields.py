"""Per-point fields of the cloth's springs, for colouring and export.

Each spring's elastic force ``k (l - l0)`` and energy ``k (l - l0)^2 / 2``
are shared out to its two ends: the force as a mean over the springs that
meet at a point (what the cloth pulls with there), the energy half to each
end and divided by the area the point stands for, so the energy density
integrates over the sheet to the springs' total energy. Dashpot forces are
left out: these describe the elastic state, which a still cloth has too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pvcloth.errors import InputError
from pvcloth.physics.grid import point_stretch

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.model import Model
    from pvcloth.physics.simulation import Simulation

#: The point data of ``Simulation.mesh`` and of exports, in this order.
MESH_FIELDS = ("velocity", "speed", "stretch", "force", "energy", "pinned")


def point_areas(model: Model) -> np.ndarray:
    """Area (m^2) of sheet each point stands for, shape (N,): its share of the
    lumped mass times the sheet's rest area, so the areas add up to it."""
    nx = model.shape[1]
    rest = model.rest_positions
    side_u, side_v = rest[nx - 1] - rest[0], rest[-nx] - rest[0]
    area = float(np.linalg.norm(np.cross(side_u, side_v)))
    return model.mass / model.mass.sum() * area


def spring_fields(model: Model, x: np.ndarray) -> dict[str, np.ndarray]:
    """The spring force and elastic energy density at every point.

    Parameters
    ----------
    model : Model
    x : ndarray, shape (N, 3)
        Positions in metres.

    Returns
    -------
    dict
        ``"force"``: mean elastic force magnitude (N) of the springs that
        meet at each point, shape (N,); ``"energy"``: elastic energy density
        (J/m^2), shape (N,), whose sum weighted by :func:`point_areas` is the
        total elastic energy of the springs.

    Examples
    --------
    >>> import numpy as np, pvcloth
    >>> from pvcloth.physics.fields import point_areas, spring_fields
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> at_rest = spring_fields(sim.model, sim.positions)
    >>> float(at_rest["force"].max()), float(at_rest["energy"].max())
    (0.0, 0.0)
    >>> stretched = spring_fields(sim.model, sim.positions * 1.01)  # 1 % larger
    >>> bool((stretched["energy"] > 0).all())
    True
    """
    table = model.spring_table()
    n = x.shape[0]
    if table.count == 0:
        return {"force": np.zeros(n), "energy": np.zeros(n)}
    d = x[table.b] - x[table.a]
    extension = np.sqrt(np.einsum("ij,ij->i", d, d)) - table.rest
    force = np.abs(table.stiffness * extension)
    energy = 0.5 * table.stiffness * extension**2

    def at_points(per_spring):
        return np.bincount(table.a, per_spring, n) + np.bincount(table.b, per_spring, n)

    springs_at = at_points(np.ones(table.count))
    return {
        "force": at_points(force) / np.maximum(springs_at, 1.0),
        "energy": 0.5 * at_points(energy) / point_areas(model),
    }


def point_fields(sim: Simulation, names, reference=None, snapshot=None) -> dict[str, np.ndarray]:
    """The fields ``names`` of the simulation's current state, per point.

    ``velocity`` (N, 3) m/s, ``speed`` m/s, ``stretch`` (length over rest
    length), ``force`` N and ``energy`` J/m^2 (:mod:`pvcloth.physics.fields`),
    ``pinned`` (1 or 0), and ``error`` m, the distance from ``reference``
    (a :class:`~pvcloth.physics.reference.FollowingReference`) at the same time.
    With a ``snapshot`` (:class:`~pvcloth.physics.state.Snapshot`) the
    fields are those of that instant instead of the current state.
    """
    # One state throughout, should a physics thread replace it meanwhile.
    state = sim.state if snapshot is None else snapshot
    x = state.x.copy()
    fields: dict[str, np.ndarray] = {}
    for name in names:
        if name == "velocity":
            fields[name] = state.v.copy()
        elif name == "speed":
            fields[name] = np.linalg.norm(state.v, axis=1)
        elif name == "stretch":
            fields[name] = point_stretch(x, sim.model.rest_positions, sim.model.shape)
        elif name in ("force", "energy"):
            if "force" not in fields:
                fields.update(spring_fields(sim.model, x))
        elif name == "pinned":
            if snapshot is None:
                fields[name] = sim.control.pinned.astype(np.uint8)
            else:
                fields[name] = np.zeros(len(x), dtype=np.uint8)
                fields[name][snapshot.pinned] = 1
        elif name == "error":
            if reference is None:
                raise InputError("color", "the error field needs a reference run beside the cloth")
            fields[name] = reference.error(sim)
        else:
            raise InputError("field", f"{name!r} is not a field of the cloth")
    return {name: fields[name] for name in names}
