"""
Export a time series and read it back
=====================================

``pvcloth.export`` runs a simulation and writes every frame: ``.pvd`` (a
VTU file per frame and a ParaView index of their times), ``.xdmf`` (with
its HDF5 file) or ``.obj`` (a file per frame, for Blender). Each VTU frame
carries the fields of ``sim.mesh``. Read back with PyVista, the file holds
the simulation's positions exactly.
"""

# %%
# Export ten frames
# -----------------
# Into a temporary folder here; give any path of your own. The first frame
# is the current state, each next one ``1 / fps`` later.
import tempfile
from pathlib import Path

import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(resolution=(12, 12), orientation="horizontal", center=(0, 0, 1.5)),
    air_damping=1.0,
)
frames, fps = 10, 20
workdir = tempfile.TemporaryDirectory()  # removed when the script ends
folder = Path(workdir.name)
index = pvcloth.export(
    pvcloth.Simulation(scene), folder / "cloth.pvd", frames=frames, fps=fps, progress=False
)
print(sorted(p.name for p in folder.iterdir()), len(list((folder / "cloth_vtu").iterdir())))

# %%
# Read it back
# ------------
# PyVista reads the ``.pvd`` index: one time value per frame, each frame a
# mesh with the fields as point data.
reader = pv.get_reader(index)
assert np.allclose(reader.time_values, np.arange(frames) / fps)
saved = []
for k in range(frames):
    reader.set_active_time_point(k)
    saved.append(reader.read()[0])

# A second simulation of the same scene, run frame by frame, is the same
# run (the same arithmetic in the same order): every frame read back holds
# its positions bit for bit, and its speed field.
twin = pvcloth.Simulation(scene)
for k in twin.frames(frames, fps):
    assert np.array_equal(saved[k].points, twin.positions)
    assert np.allclose(saved[k]["speed"], np.linalg.norm(twin.velocities, axis=1))

# %%
# The series as read from the files: every other frame, coloured by speed.
plotter = pv.Plotter(window_size=(480, 400))
for mesh in saved[::2]:
    plotter.add_mesh(mesh, scalars="speed", clim=(0.0, 3.0), smooth_shading=True)
plotter.view_vector((1.0, -1.0, 0.3))
plotter.show()
