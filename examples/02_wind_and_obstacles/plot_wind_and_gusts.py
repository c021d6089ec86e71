"""
Wind and gusts
==============

A cloth hangs from its top edge and the wind blows through it. Each
triangle feels a drag ``1/2 rho C_d A |u| (u.n) n`` from the air's velocity
``u`` relative to it, so the cloth is pushed downwind until gravity holds
it. Gusts make the wind's speed wander between ``1 - gust`` and
``1 + gust`` times the mean, from a seeded sequence: the same seed gives
the same gusts.
"""

# %%
# A cloth, and three winds
# ------------------------
# ``sim.set_wind`` replaces the wind of a running simulation (``None``
# removes it), like every live edit through ``sim.update``.
import matplotlib.pyplot as plt
import numpy as np
import pyvista as pv

import pvcloth

pv.OFF_SCREEN = True  # draw off-screen when run as a script (the gallery sets it too)

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(size=(1.0, 1.0), resolution=(12, 12), mass=0.2),
    pins=pvcloth.PinSpec(corners=(), edges=("top",)),
    solver=pvcloth.SolverSpec("symplectic_euler"),
    air_damping=0.5,
)
winds = {
    "steady": pvcloth.WindSpec(velocity=(0.0, 2.5, 0.0)),  # drag coefficient 1 by default
    "gusty": pvcloth.WindSpec(velocity=(0.0, 2.5, 0.0), gust=0.5, gust_period=0.3, seed=1),
    "gusty, same seed": pvcloth.WindSpec(
        velocity=(0.0, 2.5, 0.0), gust=0.5, gust_period=0.3, seed=1
    ),
}


def centre_of_mass(sim):
    """The cloth's centre of mass in metres, shape (3,)."""
    return sim.model.mass @ sim.positions / sim.model.mass.sum()


fps = 30
downwind, cloths = {}, {}
for name, wind in winds.items():
    sim = pvcloth.Simulation(scene)
    sim.set_wind(wind)
    downwind[name] = [centre_of_mass(sim)[1] for _ in sim.frames(2 * fps + 1, fps)]
    cloths[name] = sim

# %%
# What the wind did
# -----------------
# The cloth hangs in the x-z plane and the wind blows along +y: nothing
# else pushes along y, so the cloth's centre of mass goes downwind. Gusts
# of at most 50 % never turn the wind round: the cloth never goes upwind.
steady, gusty = np.array(downwind["steady"]), np.array(downwind["gusty"])
assert steady[-1] > 0.2 and gusty.min() >= 0.0
# A steady wind lets the cloth settle: over the last half second its centre
# moves less than a centimetre. Gusts keep it moving by more than that.
settled = slice(-fps // 2, None)
assert np.ptp(steady[settled]) < 0.01 < np.ptp(gusty[settled])
# The same seed gives the same gusts, and so the same cloth, bit for bit.
assert np.array_equal(cloths["gusty"].positions, cloths["gusty, same seed"].positions)

time = np.arange(steady.size) / fps
fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(time, steady, label="steady 2.5 m/s")
ax.plot(time, gusty, label="gusts of +-50 %")
ax.set(xlabel="time (s)", ylabel="centre of mass downwind (m)")
ax.legend()
fig.tight_layout()
plt.show()

# %%
# The cloth in the gusty wind at the end, coloured by its speed.
# sphinx_gallery_thumbnail_number = 2
cloths["gusty"].plot(scalars="speed", cpos="iso", window_size=(480, 400))
