"""The view: a PyVista StructuredGrid of the cloth, refreshed from the state.

Rendering reads the simulation; it never changes it. Points are refreshed by
assignment (``grid.points = x``), which tells VTK they changed, so the mesh is
added once and smooth shading follows it.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np
import pyvista as pv

from pvcloth.physics.grid import point_stretch

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation


def use_offscreen_gl_if_headless() -> None:
    """With no X display, ask VTK for an EGL window (software GL via Mesa).

    VTK reads the variable when it builds a render window, so this is
    called just before pvcloth makes a plotter (a movie, ``sim.plot``), not
    at import. Without it VTK first tries X and prints a "bad X server
    connection" warning before falling back; a value already set wins.
    """
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


CLOTH_COLOR = "#c8553d"
BACK_COLOR = "#b7bfc9"
OBSTACLE_COLOR = "#8fa3b8"
GROUND_COLOR = "#d9d4c7"


def obstacle_mesh(obstacle, extent: float) -> pv.PolyData:
    """A surface of the obstacle in its own frame (the actor's matrix places it).

    The ground is drawn as a square of side ``extent`` around its point.
    """
    if obstacle.name == "sphere":
        return pv.Sphere(radius=obstacle.radius, theta_resolution=48, phi_resolution=32)
    if obstacle.name == "box":
        return pv.Box(bounds=np.column_stack([-0.5 * obstacle.size, 0.5 * obstacle.size]).ravel())
    return pv.Plane(i_size=extent, j_size=extent, i_resolution=1, j_resolution=1)


def obstacle_matrix(obstacle, t: float) -> np.ndarray:
    """4x4 matrix from the obstacle's frame to the world at time ``t``."""
    matrix = np.eye(4)
    matrix[:3, :3] = obstacle.axes
    matrix[:3, 3] = obstacle.center_at(t)
    return matrix


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
    >>> from pvcloth.visual.view import cloth_grid
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
    state = sim.state  # one state throughout, should a physics thread replace it
    positions = state.x.copy()
    grid.points = positions
    velocity = state.v.copy()
    fields = {
        "velocity": velocity,
        "speed": np.linalg.norm(velocity, axis=1),
        "stretch": point_stretch(positions, sim.model.rest_positions, sim.model.shape),
        "pinned": sim.control.pinned.astype(np.uint8),
    }
    for name, values in fields.items():
        grid.point_data.set_array(values, name)


#: Scalar-bar titles, with units, of the point data on ``Simulation.mesh``.
FIELD_TITLES = {
    "velocity": "velocity (m/s)",
    "speed": "speed (m/s)",
    "stretch": "stretch (length / rest length)",
    "pinned": "pinned (1 = yes)",
}


def plot_cloth(sim: Simulation, **kwargs):
    """``sim.mesh.plot(**kwargs)`` in the cloth's colour and smooth shading,
    unless ``scalars`` or ``color`` say otherwise; a field of the mesh gets a
    scalar bar titled with its unit."""
    scalars = kwargs.get("scalars")
    if scalars is None:
        kwargs.setdefault("color", CLOTH_COLOR)
    elif isinstance(scalars, str) and scalars in FIELD_TITLES:
        bar = dict(kwargs.get("scalar_bar_args") or {})
        bar.setdefault("title", FIELD_TITLES[scalars])
        bar.setdefault("fmt", "%.4g")  # stretch varies in the third decimal
        kwargs["scalar_bar_args"] = bar
    kwargs.setdefault("smooth_shading", True)
    use_offscreen_gl_if_headless()
    return sim.mesh.plot(**kwargs)


def motion_bounds(sim: Simulation) -> tuple[float, ...]:
    """Box the cloth can reach while it swings from its pins: where it starts,
    that box mirrored through the pins (the far side of the swing), and both
    moved down the gravity direction by the cloth's size."""
    x = sim.model.rest_positions
    low, high = x.min(axis=0), x.max(axis=0)
    if sim.model.pinned.any() and np.any(sim.scene.gravity):
        down = np.asarray(sim.scene.gravity) / np.linalg.norm(sim.scene.gravity)
        shift = max(sim.scene.cloth.size) * down
        centre = x[sim.model.pinned].mean(axis=0)
        horizontal = 1.0 - np.abs(down)  # mirror only across gravity
        mirrored = np.sort(
            [centre + horizontal * (centre - low), centre + horizontal * (centre - high)], axis=0
        )
        low, high = np.minimum(low, mirrored[0]), np.maximum(high, mirrored[1])
        low, high = np.minimum(low, low + shift), np.maximum(high, high + shift)
    for obstacle in sim.model.obstacles:
        if obstacle.name == "ground":  # only the height of its point: it is unbounded
            corner = [obstacle.center_at(sim.time)] * 2
        else:
            grown = obstacle.bounds()[1] - obstacle.thickness
            radius = np.linalg.norm(grown)
            corner = [obstacle.center_at(sim.time) - radius, obstacle.center_at(sim.time) + radius]
        low, high = np.minimum(low, corner[0]), np.maximum(high, corner[1])
    margin = 0.15 * max(sim.scene.cloth.size)
    low, high = low - margin, high + margin
    return (low[0], high[0], low[1], high[1], low[2], high[2])


class ClothView:
    """Draws a simulation's cloth (and its pins) in a PyVista plotter.

    Parameters
    ----------
    sim : Simulation
        The simulation to read from.
    plotter : pyvista.Plotter
        Where to draw.
    show_pins : bool
        Draw pinned points as small spheres.
    own_grid : bool
        Draw a grid of the view's own instead of ``sim.mesh`` (which
        ``Simulation.advance`` refreshes): for the window, whose physics runs
        on another thread while VTK, on the main one, reads the grid.

    Examples
    --------
    >>> import pyvista as pv, pvcloth
    >>> from pvcloth.visual.view import ClothView
    >>> sim = pvcloth.Simulation(pvcloth.Scene())
    >>> plotter = pv.Plotter(off_screen=True)
    >>> view = ClothView(sim, plotter)
    >>> sim.advance(1 / 30); view.update()
    """

    def __init__(
        self,
        sim: Simulation,
        plotter: pv.Plotter,
        *,
        show_pins: bool = True,
        own_grid: bool = False,
    ):
        self.sim = sim
        self.plotter = plotter
        self.own_grid = own_grid
        # The simulation's own grid, point data and all, unless asked not to.
        self.grid = cloth_mesh(sim) if own_grid else sim.mesh
        plotter.set_background(BACK_COLOR, top="white")
        self.actor = plotter.add_mesh(
            self.grid,
            color=CLOTH_COLOR,
            smooth_shading=True,
            specular=0.2,
            name="cloth",
        )
        self.pins = None
        if show_pins:
            self.pins = pv.PolyData(np.array(sim.positions[sim.pinned_indices]))
            # A cloth with no pins yet may get some later (a mouse drag).
            plotter.theme.allow_empty_mesh = True
            plotter.add_points(
                self.pins,
                color="#222222",
                point_size=10,
                render_points_as_spheres=True,
                name="pins",
            )
        self.obstacle_actors = []
        extent = 3.0 * max(sim.scene.cloth.size)
        for n, obstacle in enumerate(sim.model.obstacles):
            ground = obstacle.name == "ground"
            actor = plotter.add_mesh(
                obstacle_mesh(obstacle, extent),
                color=GROUND_COLOR if ground else OBSTACLE_COLOR,
                smooth_shading=not ground,
                specular=0.0 if ground else 0.3,
                name=f"obstacle{n}",
            )
            actor.user_matrix = obstacle_matrix(obstacle, sim.time)
            self.obstacle_actors.append(actor)
        self.reset_camera()

    def reset_camera(self) -> None:
        """Look at the region the cloth will move through, from the front and
        a little above, z up."""
        self.plotter.view_vector((0.9, -1.6, 0.8), viewup=(0, 0, 1))
        self.plotter.reset_camera(bounds=motion_bounds(self.sim))

    def update(self) -> None:
        """Copy the simulation's current state into the drawn meshes."""
        if self.own_grid:
            update_cloth_mesh(self.grid, self.sim)
        else:
            self.sim.update_mesh()
        for obstacle, actor in zip(self.sim.model.obstacles, self.obstacle_actors, strict=True):
            if obstacle.path.size:
                actor.user_matrix = obstacle_matrix(obstacle, self.sim.time)
        if self.pins is not None:
            pins = self.sim.positions[self.sim.pinned_indices]
            if len(pins) == self.pins.n_points:
                self.pins.points = pins
            else:  # pins were added or removed: rebuild the small point cloud
                self.pins.copy_from(pv.PolyData(np.array(pins)))
