"""The arrays that change every step, and the per-step inputs.

Following Warp and Newton, constants live in :class:`~pvcloth.physics.model.Model`,
changing arrays in :class:`State` and what the user imposes from outside
(pins and their targets, the mouse drag) in :class:`Control`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class State:
    """Positions ``x`` and velocities ``v`` (``(N, 3)`` float64) at time ``t``."""

    x: np.ndarray
    v: np.ndarray
    t: float = 0.0
    #: ``(largest speed, all finite)`` if the integrator found them on the
    #: way (the compiled step does), so the divergence guard need not look.
    checked: tuple[float, bool] | None = None

    def copy(self) -> State:
        return State(self.x.copy(), self.v.copy(), self.t)


@dataclass
class Control:
    """Pinned points and where they should be.

    A pinned point has infinite mass for the integrators (its inverse mass
    is zero), and the simulation moves it to its target at every step, so a
    target that changes over time drags the cloth.

    Attributes
    ----------
    pinned : ndarray of bool, shape (N,)
        Which points are held.
    targets : ndarray, shape (N, 3)
        Target positions; only rows of pinned points are used.
    inv_mass : ndarray, shape (N,)
        Inverse masses with zeros at pinned points: what integrators use.
    pinned_index, movable_index : ndarray of int
        Indices of the pinned and of the free points (kept by :meth:`refresh`).
    """

    pinned: np.ndarray
    targets: np.ndarray
    inv_mass: np.ndarray

    def __post_init__(self):
        self.pinned_index = np.flatnonzero(self.pinned)
        self.movable_index = np.flatnonzero(~self.pinned)

    @classmethod
    def from_model(cls, model) -> Control:
        pinned = model.pinned.copy()
        control = cls(pinned, model.rest_positions.copy(), np.zeros(model.n_points))
        control.refresh(model)
        return control

    def refresh(self, model) -> None:
        """Recompute ``inv_mass`` after ``pinned`` changed."""
        np.divide(1.0, model.mass, out=self.inv_mass)
        self.inv_mass[self.pinned] = 0.0
        self.pinned_index = np.flatnonzero(self.pinned)
        self.movable_index = np.flatnonzero(~self.pinned)
