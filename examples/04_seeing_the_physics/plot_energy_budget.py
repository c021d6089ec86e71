"""
Where the energy goes
=====================

A cloth held by two corners falls and swings. Gravity's energy becomes
motion and stretch, and still air takes some away at every instant: air
damping ``gamma`` pulls each point with ``-gamma m v``, so it removes
energy at the rate ``gamma * sum(m v^2)``. Added up over the run, that is
exactly what the cloth lost.
"""

# %%
# A cloth without dashpots
# ------------------------
# The springs have no damping here, so air is the only way out for energy.
# ``sim.energy()`` gives the kinetic and the potential energy (springs and
# gravity) in joules.
import matplotlib.pyplot as plt
import numpy as np

import pvcloth

gamma = 0.5  # 1/s
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        resolution=(16, 16), mass=0.2, orientation="horizontal", center=(0.0, 0.0, 1.5)
    ),
    springs=pvcloth.SpringsSpec(
        structural=pvcloth.SpringSpec(400.0),
        shear=pvcloth.SpringSpec(40.0),
        bending=pvcloth.SpringSpec(4.0),
    ),
    solver=pvcloth.SolverSpec("verlet"),
    air_damping=gamma,
)
sim = pvcloth.Simulation(scene)
mass = sim.model.mass


def air_power():
    """The rate (W) at which the air takes energy from the cloth now."""
    return gamma * mass @ np.einsum("ij,ij->i", sim.velocities, sim.velocities)


# %%
# One step at a time
# ------------------
# ``sim.advance(sim.dt)`` takes exactly one step. The energy the air took is
# the power added up over the steps (the trapezoid rule).
start = sim.energy()["total"]
rows, lost, power = [], 0.0, air_power()
while sim.time < 1.5 - 1e-9:
    sim.advance(sim.dt)
    now = air_power()
    lost += 0.5 * (power + now) * sim.dt
    power = now
    energy = sim.energy()
    gravity = 9.81 * mass @ sim.positions[:, 2]
    rows.append((sim.time, energy["kinetic"], energy["potential"] - gravity, gravity, lost))
time, kinetic, elastic, gravity, lost = np.array(rows).T

# %%
# The budget balances
# -------------------
# What the cloth holds plus what the air took is what it started with, to
# a tenth of a percent of the energy lost: Verlet's own energy error is far
# smaller than that.
total = kinetic + elastic + gravity
assert np.abs(total + lost - start).max() < 1e-3 * lost[-1]
# The cloth fell: it gave up more gravitational energy than it holds in
# motion and stretch.
assert gravity[0] - gravity[-1] > kinetic[-1] + elastic[-1]

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(time, kinetic, label="kinetic")
ax.plot(time, elastic, label="elastic (springs)")
ax.plot(time, gravity - gravity[0], label="gravitational, from the start")
ax.plot(time, lost, label="taken by the air")
ax.plot(time, total + lost - start, "k--", label="held + taken - start")
ax.set(xlabel="time (s)", ylabel="energy (J)")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
