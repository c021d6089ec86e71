"""
A cloth draped on a ball
========================

A square cloth falls onto a ball that stands on the floor and drapes over
it. Obstacles are not forces: after every step each point's path over the
step is tested against every obstacle and the point is put back outside,
``thickness`` from the surface, with Coulomb friction. So no point ends a
step inside the ball, whatever the integrator or the step.
"""

# %%
# A ball on the floor
# -------------------
# ``ObstacleSpec`` is one ``[[obstacles]]`` table of a scene file: a
# sphere, a box or a ground plane, each with the ``thickness`` the cloth
# keeps from it and its friction.
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

centre, radius, thickness = (0.0, 0.0, 0.3), 0.3, 0.01
ball = pvcloth.ObstacleSpec(
    "sphere", center=centre, radius=radius, thickness=thickness, friction=0.4
)
floor = pvcloth.ObstacleSpec("ground", thickness=0.005, friction=0.6)
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        size=(1.2, 1.2),
        resolution=(17, 17),
        mass=0.25,
        orientation="horizontal",
        center=(0.0, 0.0, 0.8),
    ),
    pins=pvcloth.PinSpec(corners=()),  # nothing holds it
    obstacles=(ball, floor),
    air_damping=0.5,
)
sim = pvcloth.Simulation(scene)

# %%
# Drop it
# -------
# At every frame no point is inside the ball: each keeps at least the
# radius plus the thickness from its centre (to round-off), and none is
# below the floor's thickness.
closest = []
for _ in sim.frames(46, fps=30):
    distance = np.linalg.norm(sim.positions - centre, axis=1)
    closest.append(distance.min())
    assert distance.min() >= radius + thickness - 1e-9
    assert sim.positions[:, 2].min() >= 0.005 - 1e-9
print(
    f"closest to the ball's centre {min(closest):.6f} m, radius + thickness {radius + thickness} m"
)

# %%
# At rest on top
# --------------
# The middle of the cloth landed on the top of the ball and stays there:
# pushed out to exactly the thickness, held by friction.
middle = sim.point_index((8, 8))
assert abs(np.linalg.norm(sim.positions[middle] - centre) - (radius + thickness)) < 1e-3
assert np.linalg.norm(sim.positions[middle, :2]) < 0.01

plotter = pv.Plotter(window_size=(480, 400))
plotter.add_mesh(pv.Sphere(radius=radius, center=centre), color="lightsteelblue")
plotter.add_mesh(pv.Plane(i_size=2.0, j_size=2.0), color="white")
plotter.add_mesh(sim.mesh, color="firebrick", smooth_shading=True)
plotter.camera_position = [(2.0, -2.0, 1.4), (0.0, 0.0, 0.3), (0.0, 0.0, 1.0)]
plotter.show()
