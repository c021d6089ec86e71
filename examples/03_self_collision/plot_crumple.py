"""
Turn self-collision on
======================

A long cloth stands on its edge and is tipped over by a breeze: it buckles
and folds onto itself on the floor. Without self-collision its layers pass
through each other; with a ``[self_collision]`` table they keep a
``thickness`` apart. A plain, separate check counts the triangles that
cross each other, frame by frame.
"""

# %%
# The scene, with and without contact
# -----------------------------------
# In a scene file self-collision is a table, ``[self_collision]``, with the
# layers' ``friction`` and ``thickness`` (left out: 0.3 of the gap between
# the closest parts of the flat grid that share no point). In Python it is a
# ``SelfCollisionSpec``.
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.visual.gl import use_offscreen_gl_if_headless

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)
use_offscreen_gl_if_headless()  # no display: VTK's EGL window, as pvcloth's own plots

contact = pvcloth.SelfCollisionSpec(friction=0.3)
assert pvcloth.Scene.from_dict({"self_collision": {"friction": 0.3}}).self_collision == contact

n = 16
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(size=(0.6, 1.6), resolution=(n, n), mass=0.3, center=(0, 0, 0.85)),
    springs=pvcloth.SpringsSpec(
        structural=pvcloth.SpringSpec(2000.0, 0.5),
        shear=pvcloth.SpringSpec(200.0, 0.05),
        bending=pvcloth.SpringSpec(5.0, 0.005),
    ),
    pins=pvcloth.PinSpec(corners=()),
    wind=pvcloth.WindSpec(velocity=(0.0, 1.0, 0.0), drag=0.5),  # tips it over
    obstacles=(pvcloth.ObstacleSpec("ground", friction=0.5),),
    solver=pvcloth.SolverSpec("fast_mass_spring"),
    air_damping=0.5,
)
# That gap is the distance from a cell's diagonal to its corner off it,
# hx hy / hypot(hx, hy).
hx, hy = 0.6 / (n - 1), 1.6 / (n - 1)
assert np.isclose(contact.thickness_for(scene.cloth), 0.3 * hx * hy / np.hypot(hx, hy))


# %%
# An independent count of crossings
# ---------------------------------
# Two triangles of the grid that share no corner cross each other when an
# edge of one passes through the other (Moller and Trumbore's segment test).
# Plain and brute force, nothing of pvcloth's contact code.
i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
base = (i + n * j).ravel()  # each cell's first corner, then its two triangles
triangles = np.concatenate(
    [np.stack([base, base + 1, base + n + 1], 1), np.stack([base, base + n + 1, base + n], 1)]
)


def crosses(p, q, a, b, c):
    """Whether each segment ``p -> q`` passes through triangle ``a b c`` (rows paired)."""
    d, e1, e2 = q - p, b - a, c - a
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(det) > 1e-14  # a segment parallel to the triangle does not cross it
    inv = 1.0 / np.where(ok, det, 1.0)
    s, r = p - a, np.cross(p - a, e1)
    u, v, t = (inv * np.einsum("ij,ij->i", w, z) for w, z in ((s, h), (d, r), (e2, r)))
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def crossings(x):
    """The number of pairs of triangles, sharing no corner, that cross."""
    corners = x[triangles]
    low, high = corners.min(axis=1), corners.max(axis=1)
    near = np.all((low[:, None] <= high[None]) & (low[None] <= high[:, None]), axis=2)
    k, m = np.nonzero(np.triu(near, 1))
    apart = ~(triangles[k][:, :, None] == triangles[m][:, None, :]).any(axis=(1, 2))
    k, m = k[apart], m[apart]
    hit = np.zeros(k.size, bool)
    for one, other in ((k, m), (m, k)):
        a, b, c = corners[other].transpose(1, 0, 2)
        for e in range(3):
            hit |= crosses(corners[one][:, e], corners[one][:, (e + 1) % 3], a, b, c)
    return int(hit.sum())


# %%
# Two seconds, with and without
# -----------------------------
counts, piles = {}, {}
for label, table in (("on", contact), ("off", None)):
    sim = pvcloth.Simulation(scene.replace(self_collision=table))
    counts[label] = [crossings(sim.positions) for _ in sim.frames(61, fps=30)]
    piles[label] = sim.mesh.copy()
    print(f"self-collision {label}: at most {max(counts[label])} crossing pairs in a frame")

# With contact no frame has a crossing; without, the layers pass through
# each other and many pairs cross (hundreds, here).
assert max(counts["on"]) == 0
assert max(counts["off"]) > 50

# %%
# The two piles at the end, coloured by height.
plotter = pv.Plotter(shape=(1, 2), window_size=(720, 360))
for column, label in enumerate(("on", "off")):
    plotter.subplot(0, column)
    plotter.add_text(f"self-collision {label}: {counts[label][-1]} crossings", font_size=10)
    plotter.add_mesh(
        piles[label], scalars=piles[label].points[:, 2], cmap="viridis", show_scalar_bar=False
    )
    plotter.view_vector((1.0, -0.6, 0.8))
plotter.link_views()
plotter.show()
