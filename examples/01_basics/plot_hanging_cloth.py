"""
A hanging cloth
===============

A square cloth lies flat, held along one edge. It swings down under gravity,
air damping calms it, and it comes to rest hanging: one metre long plus the
little its springs stretch under its own weight. Coloured by ``stretch``,
the top, which carries the whole cloth, is stretched most.
"""

# %%
# The scene
# ---------
# A scene is built in Python from its parts (the same keys as a TOML scene
# file). Every value is checked where it enters: a bad one raises an error
# naming its key. No ``solver.dt``: the simulation takes half the
# integrator's stable step.
import numpy as np
import pyvista as pv

import pvcloth

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)

n = 16
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        size=(1.0, 1.0), resolution=(n, n), mass=0.2, orientation="horizontal", center=(0, 0, 1.5)
    ),
    springs=pvcloth.SpringsSpec(
        structural=pvcloth.SpringSpec(400.0, 0.1),  # stiffness N/m, damping N s/m
        shear=pvcloth.SpringSpec(40.0, 0.01),
        bending=pvcloth.SpringSpec(4.0, 0.001),
    ),
    pins=pvcloth.PinSpec(corners=(), edges=("top",)),
    solver=pvcloth.SolverSpec("symplectic_euler"),
    air_damping=2.0,  # 1/s: still air that slows every point
)
sim = pvcloth.Simulation(scene)
print(sim)

# %%
# Let it fall and settle
# ----------------------
# ``advance`` runs as many fixed steps as the time asked for covers.
for _ in range(6):
    sim.advance(1.0)
    print(f"t = {sim.time:.0f} s: kinetic energy {sim.energy()['kinetic']:.2e} J")

# %%
# How far it hangs
# ----------------
# Hanging, the cloth at height ``s`` above its lower edge holds the weight
# below it, ``M g s / H``, spread over its width ``W``. A vertical strain
# ``e`` stores ``structural e^2 / 2`` per unit area in the vertical springs
# and, each diagonal of a square cell being strained by ``e / 2``,
# ``shear e^2 / 2`` in the diagonal ones: the cloth resists with about
# ``k = structural + shear`` per unit width. Integrated over the length, it
# stretches by ``M g H / (2 W k)``: a couple of millimetres.
mass, g, height, width = 0.2, 9.81, 1.0, 1.0
k = 400.0 + 40.0
expected = mass * g * height / (2 * width * k)
pins = sim.positions[sim.pinned_indices]
drop = pins[:, 2].mean() - sim.positions[:, 2].min()
print(f"stretched by {1e3 * (drop - height):.2f} mm, expected {1e3 * expected:.2f} mm")

# At rest, the springs hold the weight alone: the lowest point is the
# cloth's length plus that stretch below the pins (to a tenth of it), and
# the motion has died away.
assert abs(drop - height - expected) < 0.1 * expected
assert sim.energy()["kinetic"] < 1e-5
# Pins stay exactly where the scene put them.
assert np.array_equal(pins, sim.model.rest_positions[sim.pinned_indices])

# %%
# Where it stretches
# ------------------
# ``sim.mesh`` is a :class:`pyvista.StructuredGrid` kept up to date, with
# fields as point data. ``stretch`` is the local length over the rest length:
# largest at the top, which carries the weight of the whole cloth, and
# about 1 at the free lower edge, which carries almost none.
stretch = sim.mesh["stretch"].reshape(n, n)  # rows are j, from the free edge up
assert stretch[-2].mean() > stretch[n // 2].mean() > stretch[0].mean()
sim.plot(scalars="stretch", cpos="xz", window_size=(480, 480), scalar_bar_args={"fmt": "%.4f"})
