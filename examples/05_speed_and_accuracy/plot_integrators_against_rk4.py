"""
Integrators against a fine reference
====================================

The same falling cloth under several integrators, each at its own step,
and how far each ends from a fine RK4 run of the scene: the trade between
speed and accuracy. ``pvcloth.physics.reference`` holds the rule the
studies use: RK4 at a quarter of the smallest step compared (at most half
its stable step), and the RMS distance between the cloths point by point.
"""

# %%
# The runs
# --------
# Explicit integrators get their automatic step (half their stable step);
# the implicit ones, stable at any step, take frame-sized steps.
import time

import matplotlib.pyplot as plt

import pvcloth
from pvcloth.physics.reference import reference_run, reference_step, rms_distance

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        resolution=(12, 12), mass=0.2, orientation="horizontal", center=(0.0, 0.0, 1.5)
    ),
    air_damping=1.0,
)
duration = 0.25
runs = [
    ("symplectic_euler", None),
    ("verlet", None),
    ("rk4", None),
    ("implicit_euler", 1 / 60),
    ("fast_mass_spring", 1 / 60),
    ("fast_mass_spring", 1 / 240),
]
results = {}
for name, dt in runs:
    # The first run of an integrator in a process also loads its compiled
    # kernels: time a second one.
    for _ in range(2):
        sim = pvcloth.Simulation(scene, integrator=name, dt=dt)
        started = time.perf_counter()
        sim.advance(duration)
        wall = time.perf_counter() - started
    results[name, dt] = sim, wall / duration

# %%
# The reference, and each run's error
# -----------------------------------
smallest = min(sim.dt for sim, _ in results.values())
reference = reference_run(scene, duration, reference_step(scene, smallest, duration))
error = {key: rms_distance(sim.positions, reference.positions) for key, (sim, _) in results.items()}
for (name, dt), (sim, cost) in results.items():
    print(f"{name:17s} dt {sim.dt:.2e} s: error {error[name, dt]:.1e} m, {cost:.2f} s per s")

# Second order beats first order at a similar step, and RK4 (fourth
# order) beats both.
assert error["rk4", None] < error["verlet", None] < error["symplectic_euler", None]
# fast_mass_spring is first order: a step four times as long ends about
# four times as far from the reference (more than twice, at least).
assert error["fast_mass_spring", 1 / 60] > 2 * error["fast_mass_spring", 1 / 240]
# Every run ended within a few centimetres of the reference.
assert max(error.values()) < 0.05

# %%
# Error against cost
# ------------------
fig, ax = plt.subplots(figsize=(6, 4))
for (name, dt), (sim, cost) in results.items():
    ax.loglog(cost, error[name, dt], "o")
    ax.annotate(f" {name}\n dt {sim.dt:.1e} s", (cost, error[name, dt]), fontsize=7)
ax.xaxis.set_minor_formatter(plt.NullFormatter())
ax.margins(x=0.4, y=0.2)
ax.set(xlabel="wall seconds per simulated second", ylabel="RMS distance from RK4 (m)")
fig.tight_layout()
plt.show()
