"""
A tablecloth on a turned box
============================

A cloth falls onto a box turned 30 degrees about the vertical: a small
table. The box keeps the cloth ``thickness`` away from each of its faces,
the part that lands on the top rests there, and the rest hangs over the
edges.
"""

# %%
# The table
# ---------
# A box is given by its centre, its edge lengths along its own axes and its
# ``rotation``: degrees about the fixed x, y and z axes, in that order.
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

centre, size, turn, thickness = (0.0, 0.0, 0.4), (0.6, 0.6, 0.2), 30.0, 0.01
table = pvcloth.ObstacleSpec(
    "box",
    center=centre,
    size=size,
    rotation=(0.0, 0.0, turn),
    thickness=thickness,
    friction=0.5,
)
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        size=(1.0, 1.0),
        resolution=(25, 25),
        mass=0.2,
        orientation="horizontal",
        center=(0.0, 0.0, 0.7),
    ),
    pins=pvcloth.PinSpec(corners=()),
    obstacles=(table,),
    air_damping=1.0,
)
sim = pvcloth.Simulation(scene)

# %%
# Drop it, and look inside the box
# --------------------------------
# In the box's own axes (turned back by 30 degrees about z) a point is
# inside the box grown by the thickness when each coordinate is within
# half the edge plus the thickness. After every frame, none is.
a = np.radians(turn)
to_box = np.array([[np.cos(a), np.sin(a), 0.0], [-np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
half = 0.5 * np.array(size) + thickness
for frame in sim.frames(31, fps=30):
    local = (sim.positions - centre) @ to_box.T
    inside = np.all(np.abs(local) < half - 1e-9, axis=1)
    assert not inside.any(), f"{inside.sum()} points inside the box at frame {frame}"

# The middle of the cloth rests on the top, the thickness above it.
top = centre[2] + size[2] / 2 + thickness
middle = sim.point_index((12, 12))
assert abs(sim.positions[middle, 2] - top) < 1e-6

# %%
# The table and its cloth, coloured by stretch: the cloth is stretched most
# where it folds over the table's edges.
box = pv.Cube(center=centre, x_length=size[0], y_length=size[1], z_length=size[2])
box = box.rotate_z(turn, point=centre)
plotter = pv.Plotter(window_size=(480, 400))
plotter.add_mesh(box, color="burlywood")
plotter.add_mesh(
    sim.mesh,
    scalars="stretch",
    smooth_shading=True,
    cmap="magma",
    scalar_bar_args={"fmt": "%.3f"},
)
plotter.camera_position = [(1.6, -1.6, 1.4), (0.0, 0.0, 0.35), (0.0, 0.0, 1.0)]
plotter.show()
