"""
Energy without damping
======================

A free cloth, with no gravity, no air and no dashpots, is stretched and
let go: its energy should stay what it was. No integrator keeps it
exactly, and how each fails is its character: symplectic Euler and Verlet
keep it within a band, RK4 at a large step loses some, implicit Euler damps
nearly all of it, and explicit Euler gains until it blows up.
"""

# %%
# A free, undamped cloth
# ----------------------
import matplotlib.pyplot as plt
import numpy as np

import pvcloth

springs = pvcloth.SpringsSpec(
    structural=pvcloth.SpringSpec(400.0),  # no damping given: none
    shear=pvcloth.SpringSpec(40.0),
    bending=pvcloth.SpringSpec(4.0),
)
scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(resolution=(10, 10), orientation="horizontal", center=(0, 0, 0)),
    springs=springs,
    pins=pvcloth.PinSpec(corners=()),
    gravity=(0.0, 0.0, 0.0),
)

# %%
# Explicit Euler has no stable step on undamped springs: the simulation
# refuses it, and says so. ``stability="ignore"`` runs it anyway (the
# divergence guard still stops it).
try:
    pvcloth.Simulation(scene, integrator="explicit_euler", dt=1e-4)
except pvcloth.SceneError as error:
    print(error)

# %%
# Two seconds each
# ----------------
# The same start for all: stretched by 2 % and bulged out of its plane.
runs = {
    "symplectic_euler": None,  # None: the automatic step, half the stable one
    "verlet": None,
    "rk4": None,
    "implicit_euler": 1 / 60,
    "explicit_euler": 1e-4,
}
ratio = {}
for name, dt in runs.items():
    sim = pvcloth.Simulation(scene, integrator=name, dt=dt, stability="ignore")
    x = sim.positions.copy()
    x[:, :2] *= 1.02
    x[:, 2] = 0.05 * np.sin(np.pi * x[:, 0]) * np.sin(np.pi * x[:, 1])
    sim.set_state(positions=x)
    start, ratio[name] = sim.energy()["total"], []
    try:
        for _ in sim.frames(61, fps=30):
            ratio[name].append(sim.energy()["total"] / start)
    except pvcloth.DivergenceError as error:
        print(f"{name}: {error}")
    ratio[name] = np.array(ratio[name])

# %%
# What each did
# -------------
# The symplectic methods keep the energy within a band around its start,
# with no drift: symplectic Euler within 15 %, Verlet within 5 %.
assert np.abs(ratio["symplectic_euler"] - 1).max() < 0.15
assert np.abs(ratio["verlet"] - 1).max() < 0.05
# RK4 is not symplectic: at half its stable step it loses energy.
assert ratio["rk4"][-1] < 0.9
# Implicit Euler damps nearly all of it (numerical damping).
assert ratio["implicit_euler"][-1] < 0.01
# Explicit Euler gains energy until the guard stops the run, short of 2 s.
assert len(ratio["explicit_euler"]) < 61 and ratio["explicit_euler"].max() > 10

fig, ax = plt.subplots(figsize=(6, 4))
for name, values in ratio.items():
    ax.semilogy(np.arange(len(values)) / 30, values, label=name)
ax.set(xlabel="time (s)", ylabel="energy / energy at the start", ylim=(1e-4, 1e3))
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
