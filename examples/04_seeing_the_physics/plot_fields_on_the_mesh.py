"""
Fields on the mesh
==================

``sim.mesh`` is the cloth as a :class:`pyvista.StructuredGrid`, the same
object for the whole run, updated in place after every step. Its point data
are fields of the physics: ``speed`` (m/s), ``stretch`` (local length over
rest length), ``force`` (the mean elastic force of the springs at a point,
N) and ``energy`` (elastic energy density, J/m^2), besides ``velocity`` and
``pinned``. Movies colour by the same fields, and exports carry them.
"""

# %%
# A cloth mid-swing
# -----------------
# Held by its two top corners, it has fallen for 0.6 s and is swinging.
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

nx = ny = 20
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        size=(1.0, 1.0),
        resolution=(nx, ny),
        mass=0.2,
        orientation="horizontal",
        center=(0.0, 0.0, 1.5),
    ),
    solver=pvcloth.SolverSpec("verlet"),
    air_damping=1.0,
)
sim = pvcloth.Simulation(scene)
mesh = sim.mesh
sim.advance(0.6)
assert sim.mesh is mesh  # one mesh, kept current
print(sorted(mesh.point_data.keys()))

# %%
# What the fields mean
# --------------------
# ``speed`` is the length of each point's velocity, now.
assert np.allclose(mesh["speed"], np.linalg.norm(sim.velocities, axis=1))
assert np.array_equal(mesh.points, sim.positions)

# ``energy`` is a density: weighted by the area each point stands for (a
# cell's area, shared among its four corners: half at the border, a quarter
# at a corner) it adds up to the springs' elastic energy. That is the
# potential energy less gravity's, ``sum(m g z)``.
hx, hy = 1.0 / (nx - 1), 1.0 / (ny - 1)
wx, wy = np.ones(nx), np.ones(ny)
wx[[0, -1]] = wy[[0, -1]] = 0.5
area = np.outer(wy, wx).ravel() * hx * hy  # point i + nx * j
gravitational = 9.81 * sim.model.mass @ sim.positions[:, 2]
elastic = sim.energy()["potential"] - gravitational
assert np.isclose(mesh["energy"] @ area, elastic, rtol=1e-9)

# The two pinned corners hold the whole cloth: the springs pull hardest
# there, and the cloth is stretched most there.
pins = sim.pinned_indices
assert mesh["force"][pins].min() > np.percentile(mesh["force"], 95)
assert mesh["stretch"][pins].min() > np.median(mesh["stretch"])

# %%
# Four fields, four pictures
# --------------------------
# Force and energy span decades, from the free edge to the pins: their
# colours are on a log scale.
plotter = pv.Plotter(shape=(2, 2), window_size=(720, 640))
for k, name in enumerate(("speed", "stretch", "force", "energy")):
    plotter.subplot(k // 2, k % 2)
    plotter.add_mesh(
        mesh.copy(),
        scalars=name,
        cmap="viridis",
        smooth_shading=True,
        log_scale=name in ("force", "energy"),
        scalar_bar_args={"title": name, "n_labels": 3, "fmt": "%.3g"},
    )
    plotter.view_vector((0.6, -1.0, 0.4))
plotter.link_views()
plotter.show()
