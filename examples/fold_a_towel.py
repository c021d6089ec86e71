"""Fold a towel: a cloth lying on the floor is folded in half by its left
edge, let go, and settles on itself; self-collision keeps the top half on
the bottom one (without it the top half falls through).

The left edge is pinned and carried over on a half circle in one second,
laid 2 cm above the right half and released. Bending is soft (0.2 N/m), as
a towel's, so the fold stays folded instead of springing open.
Run:  python examples/fold_a_towel.py [OUTPUT.gif]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import pvcloth

# The bundled scene, found from this file so the script runs from any folder.
SCENE = Path(__file__).resolve().parents[1] / "data" / "scenes" / "ground.toml"
#: Seconds the fold takes; the edge is let go at this time.
FOLD_TIME = 1.0


def fold_a_towel(
    resolution: int = 32,
    integrator: str = "fast_mass_spring",
    contact: bool = True,
    friction: float = 0.3,
):
    """The towel on the floor, ready to fold: ``(sim, drive)``; call
    ``drive(sim)`` before each advance to move (and then let go) the edge.
    ``contact`` turns self-collision on, with ``friction`` between layers."""
    scene = pvcloth.load_scene(SCENE).with_resolution(resolution)
    scene = scene.with_overrides(
        {
            "cloth.center": [0.0, 0.0, 0.01],
            "pins.corners": [],
            "springs.bending.stiffness": 0.2,
            "solver.integrator": integrator,
            "solver.dt": None,
        }
    )
    scene = scene.replace(
        self_collision=pvcloth.SelfCollisionSpec(friction=friction) if contact else None
    )
    sim = pvcloth.Simulation(scene)
    nx, ny = sim.resolution
    edge = [(0, j) for j in range(ny)]
    starts = [sim.positions[sim.point_index(p)].copy() for p in edge]
    for point in edge:
        sim.pin(point)
    held = [True]

    def drive(sim):
        if not held[0]:
            return
        share = min(sim.state.t / FOLD_TIME, 1.0)
        if share == 1.0:
            for point in edge:
                sim.unpin(point)
            held[0] = False
            return
        angle = np.pi * share
        for point, start in zip(edge, starts, strict=True):
            r = -start[0]  # the distance to the fold line x = 0
            up = r * np.sin(angle) + 0.02 * share
            sim.move_pin(point, [-r * np.cos(angle), start[1], start[2] + up])

    return sim, drive


if __name__ == "__main__":
    output = sys.argv[1] if len(sys.argv) > 1 else "towel.gif"
    sim, drive = fold_a_towel()
    pvcloth.render(
        sim, output, frames=60, fps=30, size=(320, 240), before_frame=lambda sim, n: drive(sim)
    )
    report = sim.model.self_collision.report
    print(
        f"wrote {output}; top of the fold {sim.positions[:, 2].max() * 100:.1f} cm up, "
        f"{report.contacts} layer contacts in the last step"
    )
