"""
Drag a pin from a script
========================

A cloth hangs from its two top corners. Its right corner is pulled out and
up over one second, and a point of its lower edge is grabbed and lifted:
the moving pin the window's mouse uses, driven by code with ``sim.pin`` and
``sim.move_pin``. Every integrator honours a moving pin the same way.
"""

# %%
# A hanging cloth
# ---------------
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(size=(1.0, 1.0), resolution=(20, 20), mass=0.2),
    pins=pvcloth.PinSpec(corners=("top-left", "top-right")),
    solver=pvcloth.SolverSpec("symplectic_euler", dt=2.5e-4),
    air_damping=1.0,
)
sim = pvcloth.Simulation(scene)
nx, ny = sim.resolution

# %%
# Pull one corner, lift another point
# -----------------------------------
# Points are given as ``(i, j)`` (or a flat index ``i + nx * j``). A scene's
# pins can be moved at once; any other point is pinned first, where it is.
# ``move_pin`` sets a target; the point travels to it in a straight line
# over the next ``advance``.
corner = (nx - 1, ny - 1)
grabbed = (nx // 2, 0)
corner_start = sim.positions[sim.point_index(corner)].copy()
pull = np.array([0.4, -0.3, 0.3])  # metres: out, towards us and up

sim.advance(0.5)  # let it hang a little first
before = sim.mesh.copy()  # the cloth as it hangs, kept for the picture
sim.pin(grabbed)
grabbed_start = sim.positions[sim.point_index(grabbed)].copy()
for frame in range(30):
    reach = min((frame + 1) / 20, 1.0)  # there after 20 frames of 1/20 s
    sim.move_pin(corner, corner_start + reach * pull)
    sim.move_pin(grabbed, grabbed_start + [0.0, 0.0, 0.3 * reach])
    sim.advance(1 / 20)

# %%
# What must hold
# --------------
# A pinned point lands on its target at the end of every advance, whatever
# the cloth does around it.
corner_now = sim.positions[sim.point_index(corner)]
assert np.allclose(corner_now, corner_start + pull, atol=1e-12, rtol=0)
assert np.allclose(sim.positions[sim.point_index(grabbed)][2], grabbed_start[2] + 0.3, atol=1e-12)
# The other top corner was never moved.
top_left = sim.point_index((0, ny - 1))
assert np.array_equal(sim.positions[top_left], sim.model.rest_positions[top_left])
# The cloth follows the pull: from where it hung before, its centre of mass
# went the pull's way.
mass = sim.model.mass / sim.model.mass.sum()
assert (mass @ sim.positions - mass @ before.points) @ pull > 0.05

# %%
# The cloth before the pull (grey lines) and at the end (coloured by speed),
# with its pins.
plotter = pv.Plotter(window_size=(480, 480))
plotter.add_mesh(before, style="wireframe", color="grey")
plotter.add_mesh(sim.mesh, scalars="speed", smooth_shading=True, show_scalar_bar=False)
plotter.add_points(
    sim.positions[sim.pinned_indices], color="gold", point_size=16, render_points_as_spheres=True
)
plotter.view_vector((0.4, -1.0, 0.4))
plotter.show()
