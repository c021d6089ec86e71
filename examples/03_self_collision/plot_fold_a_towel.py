"""
Fold a towel
============

A towel lies on the floor. Its left edge is pinned and carried over on a
half circle in one second, laid just above the rest of the towel and let
go. With self-collision the folded part settles on the part below, one
``thickness`` above it; without, it falls straight through to the floor.
"""

# %%
# The towel and the hand that folds it
# ------------------------------------
# ``fold_a_towel`` (in ``towel_helpers.py`` beside this example, which the
# tests share) builds the towel with soft bending, as a towel's, and a
# ``drive`` function that moves the pinned edge before each frame, then
# unpins it: ``sim.pin``, ``sim.move_pin`` and ``sim.unpin`` from a script.
import numpy as np
import pyvista as pv
from towel_helpers import fold_a_towel

from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

towels = {}
for contact in (True, False):
    sim, drive = fold_a_towel(24, contact=contact)
    while sim.time < 2.0 - 1e-9:  # two seconds: the fold, then one at rest
        drive(sim)
        sim.advance(1 / 30)
    towels[contact] = sim

# %%
# Two layers, or one
# ------------------
# The floor keeps the towel 5 mm above it, and self-collision keeps one
# layer ``thickness`` above another. Folded with contact, a good part of the
# towel lies a whole thickness above the floor layer, on the part below.
floor = 0.005
folded = towels[True]
thickness = folded.model.self_collision.thickness
z = folded.positions[:, 2]
on_top = z > floor + 0.5 * thickness
assert on_top.mean() > 0.25
assert abs(np.median(z[on_top]) - (floor + thickness)) < 0.1 * thickness
# Without contact nothing holds the folded part up: it lies on the floor,
# through the part below.
assert towels[False].positions[:, 2].max() < floor + 1e-3

# One second after the edge was let go the folded towel is at rest: less
# kinetic energy than one step of free fall from rest, (1/2) M (g dt)^2,
# would give it (layers that chattered would gain about that every step).
mass, g = folded.scene.cloth.mass, 9.81
assert folded.energy()["kinetic"] < 0.5 * mass * (g * folded.dt) ** 2

# %%
# Both towels at the end, coloured by height: with contact the folded part
# is a layer above the rest; without, the towel is one flat layer.
plotter = pv.Plotter(shape=(1, 2), window_size=(720, 320))
for column, contact in enumerate((True, False)):
    plotter.subplot(0, column)
    plotter.add_text(f"self-collision {'on' if contact else 'off'}", font_size=10)
    mesh = towels[contact].mesh
    plotter.add_mesh(
        mesh, scalars=mesh.points[:, 2], clim=(0.0, 0.02), cmap="viridis", show_scalar_bar=False
    )
    plotter.view_vector((0.3, -1.0, 1.2))
plotter.link_views()
plotter.show()
