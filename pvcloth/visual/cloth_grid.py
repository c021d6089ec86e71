"""The cloth as a PyVista grid: ``Simulation.mesh``, a
``pyvista.StructuredGrid`` of dimensions ``(nx, ny, 1)`` whose point ``k`` is
the solver's point ``k``, with every field as point data
(:data:`pvcloth.physics.fields.MESH_FIELDS`), for users, notebooks and
exports. The view draws its own lighter mesh of the same points
(:class:`pvcloth.visual.view.ClothView`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyvista as pv

from pvcloth.physics.fields import MESH_FIELDS, point_fields

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation


def cloth_grid(positions: np.ndarray, resolution: tuple[int, int]) -> pv.StructuredGrid:
    """A StructuredGrid of dimensions ``(nx, ny, 1)`` whose point ``k`` is
    ``positions[k]``: the solver's order is VTK's order, no reordering.

    Parameters
    ----------
    positions : ndarray, shape (nx * ny, 3)
    resolution : (int, int)
        ``(nx, ny)``.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.visual.cloth_grid import cloth_grid
    >>> grid = cloth_grid(np.random.rand(12, 3), (4, 3))
    >>> grid.dimensions
    (4, 3, 1)
    """
    nx, ny = resolution
    grid = pv.StructuredGrid()
    grid.points = np.array(positions, dtype=float)
    grid.dimensions = (nx, ny, 1)
    return grid


def cloth_mesh(sim: Simulation) -> pv.StructuredGrid:
    """A new grid of the simulation's cloth with its point data (what
    ``Simulation.mesh`` holds; see there for the fields)."""
    grid = cloth_grid(sim.positions, sim.resolution)
    update_cloth_mesh(grid, sim)
    return grid


def update_cloth_mesh(grid: pv.StructuredGrid, sim: Simulation) -> None:
    """Refresh ``grid``'s points and point data from ``sim`` in place.

    Point arrays are assigned, not copied into, so VTK sees the change. No
    array is made the active scalars: a plotter that draws the grid in one
    colour keeps doing so.
    """
    grid.points = sim.state.x.copy()
    for name, values in point_fields(sim, MESH_FIELDS).items():
        grid.point_data.set_array(values, name)
