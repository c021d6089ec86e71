"""The folded towel, for the gallery and the tests: a cloth lying on the floor
is folded in half by its left edge, let go, and settles on itself.

The left edge is pinned and carried over on a half circle in one second,
laid 2 cm above the right half and released. Bending is soft (0.2 N/m), as
a towel's, so the fold stays folded instead of springing open.

``plot_fold_a_towel.py`` beside this file is the lesson; the self-collision
tests (``tests/contact_scenes.py``, ``tests/test_self_collision.py``) import
:func:`fold_a_towel` from here. The gallery leaves this file out (its name
ends in ``_helpers.py``). Run it to write the movie of the guide:
``python examples/03_self_collision/towel_helpers.py docs/towel_fold.gif``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import pvcloth

# The bundled scene, found from this file so the script runs from any folder.
SCENE = Path(__file__).resolve().parents[2] / "data" / "scenes" / "ground.toml"
#: Seconds the fold takes; the edge is let go at this time.
FOLD_TIME = 1.0


def fold_a_towel(
    resolution: int = 32,
    integrator: str = "fast_mass_spring",
    contact: bool = True,
    friction: float = 0.3,
    in_solve: bool = False,
):
    """The towel on the floor, ready to fold.

    Parameters
    ----------
    resolution : int
        Points along each side of the 1 m square towel.
    integrator : str
        The integrator's name (its automatic step).
    contact : bool
        Turn self-collision on (a ``[self_collision]`` table).
    friction : float
        Coulomb friction between the towel's layers.
    in_solve : bool
        Hold the layers inside the solve of ``backward_euler`` and ``bdf2``
        (``[self_collision] in_solve``).

    Returns
    -------
    sim : pvcloth.Simulation
        The towel flat on the floor, its left edge pinned.
    drive : callable
        ``drive(sim)``, called before each advance, carries the left edge
        over the fold and lets it go at :data:`FOLD_TIME`.
    """
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
        self_collision=pvcloth.SelfCollisionSpec(friction=friction, in_solve=in_solve)
        if contact
        else None
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
