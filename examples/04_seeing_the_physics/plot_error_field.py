"""
Where a fast integrator is wrong
================================

``fast_mass_spring`` takes one 1/60 s step per frame: fast, stable at any
step, and first order, with numerical damping. A fine RK4 run of the same
scene, kept at the same time beside it
(:class:`~pvcloth.physics.reference.FollowingReference`), says how far
each point is from where it should be: the ``error`` field that
``pvcloth.render(sim, ..., color="error")`` colours movies by.
"""

# %%
# The run and its reference
# -------------------------
import numpy as np
import pyvista as pv

import pvcloth
from pvcloth.physics.reference import FollowingReference

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)

n = 16
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        resolution=(n, n), mass=0.2, orientation="horizontal", center=(0.0, 0.0, 1.5)
    ),
    solver=pvcloth.SolverSpec("fast_mass_spring"),  # no dt: one step per 1/60 s frame
    air_damping=1.0,
)
sim = pvcloth.Simulation(scene)
reference = FollowingReference(sim)  # RK4 at a quarter of the step, at most half its stable one
print(f"steps: {sim.dt:.4f} s, reference {reference.sim.dt:.5f} s")

worst, energy = [], []
for _ in sim.frames(31, fps=30):
    error = reference.error(sim)  # metres per point; the reference catches up first
    worst.append(error.max())
    energy.append((sim.energy()["total"], reference.sim.energy()["total"]))
energy = np.array(energy)
print(f"largest error after 1 s: {worst[-1] * 100:.1f} cm")

# %%
# What the error shows
# --------------------
# The pins hold both runs at the same place: no error there.
assert error[sim.pinned_indices].max() == 0.0
# The scene is symmetric about the cloth's middle, and so is the error.
assert np.allclose(error.reshape(n, n), error.reshape(n, n)[:, ::-1], atol=1e-9)
# Numerical damping: the implicit step takes energy that neither the air
# nor the dashpots take, so the fast run never holds more energy than the
# reference, and ends with less.
assert (energy[:, 0] <= energy[:, 1] + 1e-9).all()
assert energy[-1, 0] < energy[-1, 1] - 0.05

# %%
# The error on the cloth. Any array of one value per point can go on the
# mesh as point data and colour it.
sim.mesh["error"] = error
sim.plot(
    scalars="error",
    cpos="xz",
    window_size=(480, 480),
    scalar_bar_args={"title": "error (m)", "fmt": "%.3f"},
)
