"""A curtain: a tall cloth held along its whole top edge, pushed sideways.

Builds its scene in Python (no TOML file), runs it, and writes a picture.
Run:  python examples/curtain.py [OUTPUT.png]
"""

import sys

import numpy as np

import pvcloth

scene = pvcloth.Scene(
    name="curtain",
    cloth=pvcloth.ClothSpec(size=(1.0, 1.6), resolution=(20, 32), mass=0.4),
    springs=pvcloth.SpringsSpec(
        structural=pvcloth.SpringSpec(300.0, 0.1),
        shear=pvcloth.SpringSpec(30.0, 0.01),
        bending=pvcloth.SpringSpec(3.0, 0.001),
    ),
    pins=pvcloth.PinSpec(corners=(), edges=("top",)),
    solver=pvcloth.SolverSpec("symplectic_euler", dt=4e-4),
    air_damping=0.5,
)
sim = pvcloth.Simulation(scene)
# a push out of the plane on the lower half, so the curtain swings
nx, ny = sim.resolution
lower = np.arange(nx * ny) < nx * ny // 2
push = sim.velocities.copy()
push[lower, 1] = 1.5
sim.set_state(velocities=push)

output = sys.argv[1] if len(sys.argv) > 1 else "curtain.png"
pvcloth.render(sim, output, frames=20, fps=30, size=(480, 480))
print(f"wrote {output} at t = {sim.time:.2f} s")
