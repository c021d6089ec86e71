"""What a fixed camera frames: the box the cloth can reach as it swings from
its pins, with the obstacles (:func:`motion_bounds`). A camera that follows
the cloth instead is :class:`pvcloth.visual.camera.FramingCamera`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation


def motion_bounds(sim: Simulation) -> tuple[float, ...]:
    """Box the cloth can reach while it swings from its pins: where it starts,
    that box mirrored through the pins (the far side of the swing), and both
    moved down the gravity direction by the cloth's size (a fixed camera
    frames this)."""
    x = sim.model.rest_positions
    low, high = x.min(axis=0), x.max(axis=0)
    if sim.model.pinned.any() and np.any(sim.scene.gravity):
        down = np.asarray(sim.scene.gravity) / np.linalg.norm(sim.scene.gravity)
        shift = max(sim.scene.cloth.size) * down
        centre = x[sim.model.pinned].mean(axis=0)
        horizontal = 1.0 - np.abs(down)  # mirror only across gravity
        mirrored = np.sort(
            [centre + horizontal * (centre - low), centre + horizontal * (centre - high)], axis=0
        )
        low, high = np.minimum(low, mirrored[0]), np.maximum(high, mirrored[1])
        low, high = np.minimum(low, low + shift), np.maximum(high, high + shift)
    for obstacle in sim.model.obstacles:
        if obstacle.name == "ground":  # only the height of its point: it is unbounded
            corner = [obstacle.center_at(sim.time)] * 2
        else:
            grown = obstacle.bounds()[1] - obstacle.thickness
            radius = np.linalg.norm(grown)
            corner = [obstacle.center_at(sim.time) - radius, obstacle.center_at(sim.time) + radius]
        low, high = np.minimum(low, corner[0]), np.maximum(high, corner[1])
    margin = 0.15 * max(sim.scene.cloth.size)
    low, high = low - margin, high + margin
    return (low[0], high[0], low[1], high[1], low[2], high[2])
