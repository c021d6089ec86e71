"""
Save a checkpoint and resume it bit for bit
===========================================

``pvcloth.save_checkpoint`` writes the whole simulation to one ``.npz``
file: the scene as it runs (live edits included), the step, positions,
velocities, clock, pins and the integrator's own state.
``pvcloth.load_checkpoint`` rebuilds it, and the resumed run continues
exactly as the uninterrupted one would have: the same numbers, bit for bit.
"""

# %%
# A run, edited on the way
# ------------------------
# Implicit Euler keeps state of its own between steps (the last solve, as
# the next one's first guess): a checkpoint saves that too. The wind is
# turned on mid-run, a live edit the checkpoint keeps.
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
    solver=pvcloth.SolverSpec("implicit_euler", dt=1 / 120),
    air_damping=0.5,
)
sim = pvcloth.Simulation(scene)
sim.advance(0.25)
sim.set_wind(pvcloth.WindSpec(velocity=(0.0, 3.0, 0.0), gust=0.3, seed=7))
sim.advance(0.25)

# %%
# Save, then carry on
# -------------------
workdir = tempfile.TemporaryDirectory()  # removed when the script ends
path = pvcloth.save_checkpoint(sim, Path(workdir.name) / "run.npz")
resumed = pvcloth.load_checkpoint(path)
assert resumed.scene == sim.scene and resumed.time == sim.time

# Both go on for another half second, frame by frame. At every frame the
# resumed run is the uninterrupted one: positions and velocities equal to
# the last bit.
for _ in zip(sim.frames(16, fps=30), resumed.frames(16, fps=30), strict=True):
    assert np.array_equal(resumed.positions, sim.positions)
    assert np.array_equal(resumed.velocities, sim.velocities)
print(resumed)

# %%
# Both cloths at the end: the uninterrupted run, and the one resumed from
# the file, coloured by speed.
plotter = pv.Plotter(shape=(1, 2), window_size=(720, 360))
for column, (label, run) in enumerate((("uninterrupted", sim), ("resumed", resumed))):
    plotter.subplot(0, column)
    plotter.add_text(label, font_size=10)
    plotter.add_mesh(
        run.mesh.copy(),
        scalars="speed",
        clim=(0.0, 2.0),
        smooth_shading=True,
        show_scalar_bar=column == 1,
    )
    plotter.view_vector((1.0, -0.3, 0.3))
plotter.link_views()
plotter.show()
