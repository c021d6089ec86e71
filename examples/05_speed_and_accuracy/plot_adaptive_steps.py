"""
Set the error, not the step
===========================

With ``solver.tolerance`` (metres) the simulation chooses every step from
the integrator's own error estimate: each second of simulation may add
about ``tolerance`` of position error. A step over its share is rejected
and retried shorter. Here ``rk23``, which measures its error with an
embedded second-order pair, runs a falling cloth at three tolerances, and
a fine RK4 run alongside says how far each really is.
"""

# %%
# Three tolerances
# ----------------
# ``sim.dt`` is the step the controller will try next, ``sim.stats`` counts
# the steps taken and rejected.
import matplotlib.pyplot as plt
import numpy as np

import pvcloth
from pvcloth.physics.reference import rms_distance

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(
        resolution=(12, 12), mass=0.2, orientation="horizontal", center=(0.0, 0.0, 1.5)
    ),
    air_damping=1.0,
)
fps, tolerances = 60, (1e-3, 1e-4, 1e-5)
fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 5.5), sharex=True)
for tolerance in tolerances:
    sim = pvcloth.Simulation(
        scene.with_overrides({"solver.integrator": "rk23", "solver.tolerance": tolerance})
    )
    # The reference: RK4 at fixed steps that divide a frame, kept at the same time.
    reference = pvcloth.Simulation(scene, integrator="rk4", dt=1 / (100 * fps))
    time, error, step = [], [], []
    for frame in sim.frames(fps + 1, fps):
        if frame:
            reference.advance(1 / fps)
            time.append(sim.time)
            error.append(rms_distance(sim.positions, reference.positions))
            step.append(sim.dt)
    time, error = np.array(time), np.array(error)
    print(
        f"tolerance {tolerance:g} m: {sim.stats['steps']} steps, "
        f"{sim.stats['rejected']} rejected, error at 1 s {error[-1]:.1e} m"
    )

    # The error follows the tolerance: at every frame it is within ten times
    # what the tolerance allows for the time run, tolerance * t.
    assert (error <= 10 * tolerance * time).all()
    top.loglog(time, error, label=f"{tolerance:g} m")
    top.loglog(time, tolerance * time, "k:", linewidth=0.8)
    bottom.semilogy(time, step, label=f"{tolerance:g} m")

# At 1e-3 m the step is held by stability rather than by the error: an
# explicit method's step stays under 0.8 of its stable step, so that run
# ends far more accurate than it asked.
top.set(ylabel="RMS distance from RK4 (m)", title="dotted: tolerance * t")
bottom.set(xlabel="time (s)", ylabel="step the controller chose (s)")
bottom.legend(title="tolerance", fontsize=8)
fig.tight_layout()
plt.show()
