"""
Measure an integrator's order
=============================

An integrator of order ``p`` ends a run with an error proportional to
``dt^p``: halving the step divides the error by ``2^p``. Two runs, at a
step and at half of it, against a reference far finer than both, measure
``p = log2(e(dt) / e(dt / 2))``. Each integrator states its order
(``sim.integrator.order``); here it is checked.
"""

# %%
# Two steps each, one reference
# -----------------------------
# A small falling cloth for 0.2 s. The reference is RK4 at an eighth of the
# smaller step: its own error is far below the runs' errors.
import matplotlib.pyplot as plt
import numpy as np

import pvcloth
from pvcloth.physics.reference import reference_run, rms_distance

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        resolution=(8, 8), mass=0.2, orientation="horizontal", center=(0.0, 0.0, 1.5)
    ),
    air_damping=1.0,
)
duration = 0.2
steps = {"symplectic_euler": 1e-3, "verlet": 1.25e-3, "rk4": 2e-3, "implicit_euler": 1e-2}
pairs, errors, measured = {}, {}, {}
for name, dt in steps.items():
    dt = duration / round(duration / dt)  # whole steps end the run exactly at 0.2 s
    pairs[name] = pair = [dt, dt / 2]
    reference = reference_run(scene, duration, pair[1] / 8)
    errors[name] = []
    for step in pair:
        sim = pvcloth.Simulation(scene, integrator=name, dt=step)
        sim.advance(duration)
        errors[name].append(rms_distance(sim.positions, reference.positions))
    measured[name] = np.log2(errors[name][0] / errors[name][1])
    print(f"{name:16s} order {sim.integrator.order}, measured {measured[name]:.2f}")

    # The measured order is the stated one, to within 0.3.
    assert abs(measured[name] - sim.integrator.order) < 0.3

# %%
# Error against step
# ------------------
# On log-log axes each integrator is a line of slope ``p``.
fig, ax = plt.subplots(figsize=(6, 4))
for name, pair in pairs.items():
    ax.loglog(pair, errors[name], "o-", label=f"{name}: {measured[name]:.2f}")
ax.set(xlabel="step (s)", ylabel="RMS distance from the reference (m)")
ax.legend(title="measured order", fontsize=8)
fig.tight_layout()
plt.show()
