"""
Friction on a slope
===================

A cloth lies on a tilted floor. Below the friction angle static friction
holds it; above it the cloth slides like a block, with the acceleration of
a textbook: ``a = g (sin(theta) - mu_k cos(theta))``. The floor is a
``ground`` obstacle with a tilted ``normal``, and the friction is Coulomb's,
with a static coefficient above the kinetic one.
"""

# %%
# Two slopes
# ----------
# The cloth starts flat on each slope: its rest shape, turned onto the
# slope with ``sim.set_state`` (a rigid turn stretches no spring).
import matplotlib.pyplot as plt
import numpy as np

import pvcloth

g, mu_kinetic, mu_static = 9.81, 0.3, 0.4
fps, seconds = 60, 0.5
slides = {}
for degrees in (15.0, 30.0):
    theta = np.radians(degrees)
    c, s = np.cos(theta), np.sin(theta)
    floor = pvcloth.ObstacleSpec(
        "ground",
        normal=(s, 0.0, c),
        thickness=0.005,
        friction=mu_kinetic,
        static_friction=mu_static,
    )
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(
            size=(0.5, 0.5),
            resolution=(10, 10),
            mass=0.1,
            orientation="horizontal",
            center=(0.0, 0.0, 0.005),  # the thickness above the floor, before the turn
        ),
        pins=pvcloth.PinSpec(corners=()),
        obstacles=(floor,),
        air_damping=0.0,  # no air: friction alone holds the cloth back
    )
    sim = pvcloth.Simulation(scene)
    turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # z onto the normal
    sim.set_state(positions=sim.positions @ turn.T)
    start, downhill = sim.positions.copy(), np.array([c, 0.0, -s])
    slides[degrees] = [
        ((sim.positions - start) @ downhill).mean() for frame in sim.frames(fps // 2 + 1, fps)
    ]

# %%
# Stick or slide
# --------------
# At 15 degrees, ``tan(15) = 0.27`` is below the static coefficient 0.4:
# the cloth does not move at all. At 30 degrees, ``tan(30) = 0.58`` is
# above it: the cloth slides, every point alike, as far as a block
# accelerating at ``g (sin - mu_k cos)`` would, to a percent.
time = np.arange(fps // 2 + 1) / fps
theta = np.radians(30.0)
block = 0.5 * g * (np.sin(theta) - mu_kinetic * np.cos(theta)) * time**2
assert np.abs(slides[15.0]).max() < 1e-9
assert abs(slides[30.0][-1] - block[-1]) < 0.01 * block[-1]

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(time, slides[30.0], "o", label="cloth on 30 degrees")
ax.plot(time, block, label="block: g (sin - mu_k cos) t^2 / 2")
ax.plot(time, slides[15.0], "s", label="cloth on 15 degrees")
ax.set(xlabel="time (s)", ylabel="distance down the slope (m)")
ax.legend()
fig.tight_layout()
plt.show()
