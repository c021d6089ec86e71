"""
Second order at frame steps
===========================

Cotton falling from flat, held by two corners, at one 1/60 s step per
frame: first-order ``fast_mass_spring`` against second-order ``fast_bdf2``
at the same cost, and both solved to convergence (``backward_euler`` and
``bdf2``), each as far from a fine RK4 run as the plot shows, frame by
frame. The grid is coarse (24x24) so that the example runs in seconds; the
64x64 numbers are in the guide's "Second order at frame steps".
"""

# %%
# The runs
# --------
# Every run takes one step per frame and keeps its positions at each frame;
# RK4 at half its stable step is the reference.
import matplotlib.pyplot as plt
import numpy as np

import pvcloth
from pvcloth.physics.reference import rms_distance

# The bundled cotton scene (data/scenes/cotton.toml), at 24x24 points.
scene = pvcloth.Scene.from_dict(
    {
        "cloth.material": "cotton",
        "cloth.resolution": [24, 24],
        "cloth.orientation": "horizontal",
        "cloth.center": [0.0, 0.0, 1.5],
        "pins.corners": ["top-left", "top-right"],
        "air_damping": 1.0,
    }
)
frames, frame = 60, 1 / 60


def trajectory(integrator: str, dt: float | None = frame) -> list[np.ndarray]:
    sim = pvcloth.Simulation(scene, integrator=integrator, dt=dt)
    kept = []
    for _ in range(frames):
        sim.advance(frame)
        kept.append(sim.positions.copy())
    return kept


truth = trajectory("rk4", None)
runs = ("fast_mass_spring", "fast_bdf2", "backward_euler", "bdf2")
error = {
    name: np.array([rms_distance(x, y) for x, y in zip(trajectory(name), truth, strict=True)])
    for name in runs
}
for name in runs:
    print(
        f"{name:17s} at 0.5 s {100 * error[name][29]:.2f} cm, at 1 s {100 * error[name][-1]:.2f} cm"
    )

# At the same cost (ten local/global iterations each) BDF2 ends closer to
# the reference at 1 s than backward Euler, and so it does solved to
# convergence (here: 4.4 against 13.2 cm, and 1.8 against 9.8 cm).
assert error["fast_bdf2"][-1] < error["fast_mass_spring"][-1]
assert error["bdf2"][-1] < error["backward_euler"][-1]

# %%
# The error, frame by frame
# -------------------------
fig, ax = plt.subplots(figsize=(6, 4))
seconds = frame * np.arange(1, frames + 1)
for name, style in zip(runs, ("C0--", "C1--", "C0-", "C1-"), strict=True):
    ax.plot(seconds, 100 * error[name], style, label=name)
ax.set(xlabel="time (s)", ylabel="RMS distance from RK4 (cm)")
ax.legend(title="one 1/60 s step per frame")
fig.tight_layout()
plt.show()
