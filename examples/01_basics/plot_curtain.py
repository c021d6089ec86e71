"""
A curtain pushed sideways
=========================

A tall cloth held along its whole top edge hangs still; its lower half is
given a push out of its plane, and the curtain swings out and back. The
push is an edit of the state, ``sim.set_state(velocities=...)``: the state
the simulation holds is read-only.
"""

# %%
# The curtain
# -----------
# A scene built in Python, no TOML file: 1 m wide, 1.6 m tall, pinned along
# its top edge, with a fixed step of symplectic Euler.
import matplotlib.pyplot as plt
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

scene = pvcloth.Scene(
    name="curtain",
    cloth=pvcloth.ClothSpec(size=(1.0, 1.6), resolution=(12, 20), mass=0.4),
    springs=pvcloth.SpringsSpec(
        structural=pvcloth.SpringSpec(300.0, 0.1),
        shear=pvcloth.SpringSpec(30.0, 0.01),
        bending=pvcloth.SpringSpec(3.0, 0.001),
    ),
    pins=pvcloth.PinSpec(corners=(), edges=("top",)),
    solver=pvcloth.SolverSpec("symplectic_euler", dt=4e-4),
    air_damping=0.5,
)
sim = pvcloth.Simulation(scene)

# %%
# The push
# --------
# Points are numbered ``i + nx * j``, ``j`` up from the lower edge, so the
# first half of the indices is the lower half of the curtain. It gets
# 1.5 m/s along y, out of the curtain's plane.
nx, ny = sim.resolution
lower = np.arange(nx * ny) < nx * ny // 2
push = np.zeros((nx * ny, 3))
push[lower, 1] = 1.5
sim.set_state(velocities=push)

# Masses are lumped by area, so the lower half (by index) holds half the
# 0.4 kg: the push gave it (1/2) (M/2) v^2 of kinetic energy.
assert np.isclose(sim.energy()["kinetic"], 0.5 * 0.2 * 1.5**2, rtol=0.01)

# %%
# The swing
# ---------
# ``sim.frames`` is the frame loop movies use: one frame every 1/30 s. A
# copy of the mesh keeps the curtain as it was at a frame.
energy, shapes = [], []
for frame in sim.frames(31, fps=30):
    energy.append(sim.energy()["total"])
    if frame % 5 == 0:
        shapes.append(sim.mesh.copy())

# Nothing does work on the curtain but gravity and its springs (the pins
# stand still) while air and the dashpots take energy out: the total can
# only fall (to within 1e-4 J of the 4 J, room for the integrator's own
# small energy error), and it falls by far more than that.
assert np.diff(energy).max() < 1e-4
assert energy[-1] < energy[0] - 0.05
# The lower edge swung out and is on its way back.
lower_edge = [shape.points[:nx, 1].mean() for shape in shapes]
assert 0.3 < max(lower_edge) and lower_edge[-1] < max(lower_edge)

# %%
# Seen from the side: the curtain's middle column every 1/6 s, from dark
# (the push) to light (one second later); the push is to the right.
middle = nx // 2 + nx * np.arange(ny)
plotter = pv.Plotter(window_size=(480, 480))
for k, shape in enumerate(shapes):
    profile = pv.lines_from_points(shape.points[middle])
    plotter.add_mesh(profile, color=plt.cm.viridis(k / 6)[:3], line_width=5)
plotter.view_yz()
plotter.enable_parallel_projection()
plotter.show()
