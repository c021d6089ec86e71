"""Obstacles and the ground as drawn: each obstacle's surface in its own
frame, the matrix that places it in the world at a time, and the checker the
ground is covered with.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from pvcloth.visual.colors import GROUND_COLORS, OBSTACLE_COLOR, nice_ceiling


def obstacle_surface(obstacle, extent: float) -> pv.PolyData:
    """The obstacle's surface (its own :meth:`surface`) in its own frame, the
    ground with texture coordinates for a checker of :func:`ground_cell`."""
    vertices, triangles = obstacle.surface(extent)
    faces = np.column_stack([np.full(len(triangles), 3), triangles]).ravel()
    mesh = pv.PolyData(np.asarray(vertices, dtype=float), faces)
    if obstacle.name == "ground":
        mesh.active_texture_coordinates = vertices[:, :2] / (2.0 * ground_cell(extent))
    elif obstacle.name != "box":  # a box's faces shade flat
        mesh = mesh.compute_normals(auto_orient_normals=False, split_vertices=False)
    return mesh


def ground_cell(extent: float) -> float:
    """Side (m) of one checker square on a ground drawn ``extent`` wide: a
    round length giving about 12 squares across."""
    return nice_ceiling(extent / 12.0)


def checker_texture() -> pv.Texture:
    """A 2x2 checker of :data:`~pvcloth.visual.colors.GROUND_COLORS`, repeated over the ground."""
    light, dark = (np.array(pv.Color(c).int_rgb, dtype=np.uint8) for c in GROUND_COLORS)
    image = np.array([[light, dark], [dark, light]], dtype=np.uint8)
    texture = pv.Texture(image)
    texture.repeat = True
    texture.interpolate = False
    return texture


def add_obstacles(plotter: pv.Plotter, sim) -> list:
    """Draw ``sim``'s obstacles (spheres, boxes, a checkered ground) where
    they are at ``sim.time``, as movies and the window show them; returns
    their actors (whose ``user_matrix`` moves them)."""
    actors = []
    extent = 4.0 * max(sim.scene.cloth.size)
    for n, obstacle in enumerate(sim.model.obstacles):
        ground = obstacle.name == "ground"
        actor = plotter.add_mesh(
            obstacle_surface(obstacle, extent),
            color=None if ground else OBSTACLE_COLOR,
            texture=checker_texture() if ground else None,
            smooth_shading=not ground and obstacle.name != "box",
            # The floor lit mostly by ambient light: it reads as a light
            # floor from any camera, not a dark slab at grazing light.
            ambient=0.7 if ground else 0.25,
            diffuse=0.35 if ground else 0.75,
            specular=0.0 if ground else 0.3,
            name=f"obstacle{n}",
        )
        actor.user_matrix = obstacle_matrix(obstacle, sim.time)
        actors.append(actor)
    return actors


def obstacle_matrix(obstacle, t: float) -> np.ndarray:
    """4x4 matrix from the obstacle's frame to the world at time ``t``."""
    matrix = np.eye(4)
    matrix[:3, :3] = obstacle.axes
    matrix[:3, 3] = obstacle.center_at(t)
    return matrix
