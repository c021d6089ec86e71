"""Drag a corner from a script: the moving pin the mouse uses, driven by code.

A cloth hangs from its two top corners; the right one is pulled outwards and
up over one second, and the cloth follows.
Run:  python examples/pinned_and_dragged.py [OUTPUT.gif]
"""

import sys
from pathlib import Path

import numpy as np

import pvcloth

# The bundled scene, found from this file so the script runs from any folder.
SCENE = Path(__file__).resolve().parents[1] / "data" / "scenes" / "hanging.toml"

scene = pvcloth.load_scene(SCENE).replace(
    cloth=pvcloth.ClothSpec(resolution=(24, 24), mass=0.2, orientation="vertical")
)
sim = pvcloth.Simulation(scene)
nx, ny = sim.resolution
corner = (nx - 1, ny - 1)
start = sim.positions[sim.point_index(corner)].copy()


def pull_corner(sim, frame):
    """Move the corner's target out and up over the first second."""
    reach = min((frame + 1) / 20, 1.0)
    sim.move_pin(corner, start + reach * np.array([0.4, -0.3, 0.3]))


output = sys.argv[1] if len(sys.argv) > 1 else "dragged.gif"
pvcloth.render(sim, output, frames=30, fps=20, size=(400, 400), before_frame=pull_corner)
print(f"wrote {output}; corner at {np.round(sim.positions[sim.point_index(corner)], 3)}")
