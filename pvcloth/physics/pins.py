"""Pins on a running simulation: points given by index or ``(i, j)``
held at targets that a user adds, moves and removes.

:class:`Pins` is one part of :class:`~pvcloth.physics.simulation.Simulation`;
the pins themselves live in its :class:`~pvcloth.physics.state.Control`,
which the integrators read.
"""

from __future__ import annotations

import numpy as np

from pvcloth.errors import InputError
from pvcloth.scene.parts import MAX_LENGTH
from pvcloth.scene.validation import integer


class Pins:
    """The pin methods of :class:`~pvcloth.physics.simulation.Simulation`
    (they read its ``resolution``, ``state``, ``control`` and ``model``)."""

    def point_index(self, point) -> int:
        """Flat index of a point given as an index or an ``(i, j)`` pair."""
        nx, ny = self.resolution
        if isinstance(point, (tuple, list)) and len(point) == 2:
            i = integer("point[0] (i)", point[0], minimum=0, maximum=nx - 1, error=InputError)
            j = integer("point[1] (j)", point[1], minimum=0, maximum=ny - 1, error=InputError)
            return i + nx * j
        if isinstance(point, (int, np.integer)) and not isinstance(point, bool):
            return integer("point", point, minimum=0, maximum=nx * ny - 1, error=InputError)
        raise InputError(
            "point",
            f"expected an index 0..{nx * ny - 1} or an (i, j) pair of whole numbers, got {point!r}",
        )

    @staticmethod
    def _target(position) -> np.ndarray:
        """A pin target: three finite coordinates in metres, within
        ``MAX_LENGTH`` of the origin (like every position in a scene)."""
        try:
            target = np.asarray(position, dtype=float)
        except (TypeError, ValueError, OverflowError):
            target = None
        if target is None or target.shape != (3,) or not np.isfinite(target).all():
            raise InputError(
                "position",
                f"expected three finite coordinates (x, y, z) in metres, got {position!r}",
            )
        if np.abs(target).max() > MAX_LENGTH:
            raise InputError(
                "position", f"each coordinate must be within +-{MAX_LENGTH:g} m, got {position!r}"
            )
        return target

    def pin(self, point, position=None) -> None:
        """Hold a point at ``position`` (default: where it is now)."""
        k = self.point_index(point)
        target = self.state.x[k] if position is None else self._target(position)
        self.control.pin(k, target)

    def move_pin(self, point, position) -> None:
        """Set a pinned point's target; it gets there over the next advance."""
        k = self.point_index(point)
        if not self.control.pinned[k]:
            raise InputError("point", f"point {k} is not pinned; pin it first")
        self.control.targets[k] = self._target(position)

    def unpin(self, point) -> None:
        """Let a pinned point move freely."""
        self.control.unpin(self.point_index(point))

    def restore_scene_pins(self) -> None:
        """Drop every pin added since the start; keep the scene's own."""
        self.control.pinned = self.model.pinned

    @property
    def pinned_indices(self) -> np.ndarray:
        return self.control.pinned_index
