"""The arrays that change every step, and the per-step inputs.

Following Warp and Newton, constants live in :class:`~pvcloth.physics.model.Model`,
changing arrays in :class:`State` and what the user imposes from outside
(pins and their targets, the mouse drag) in :class:`Control`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from pvcloth.errors import InputError

#: Revision numbers for everything integrators cache work on (a model's
#: constants, a control's pinned set): drawn from one counter, so a number is
#: never reused, not by another object either, and a cache keyed by it needs
#: no ``id()`` (which a new object may inherit from a freed one).
REVISIONS = itertools.count(1)


@dataclass
class State:
    """The cloth at one instant.

    Attributes
    ----------
    x : ndarray, shape (N, 3)
        Positions in metres, in VTK point order (index ``i + nx * j``).
    v : ndarray, shape (N, 3)
        Velocities in m/s.
    t : float
        Time in seconds.
    """

    x: np.ndarray
    v: np.ndarray
    t: float = 0.0

    def copy(self) -> State:
        return State(self.x.copy(), self.v.copy(), self.t)


class Control:
    """Pinned points and where they should be.

    A pinned point has infinite mass for the integrators (its inverse mass
    is zero), and the simulation moves it to its target at every step, so a
    target that changes over time drags the cloth.

    The arrays derived from ``pinned`` cannot go stale: ``pinned`` is
    read-only and is changed by assigning a whole mask (``control.pinned =
    mask``) or through :meth:`pin` and :meth:`unpin`, each of which
    recomputes them and counts a new :attr:`revision` (what integrators
    with cached factorisations watch).

    Parameters
    ----------
    mass : ndarray, shape (N,)
        Point masses in kg (from the model).
    pinned : ndarray of bool, shape (N,)
        Which points are held.
    targets : ndarray, shape (N, 3)
        Target positions in metres.

    Attributes
    ----------
    targets : ndarray, shape (N, 3)
        Target positions in metres; only rows of pinned points are used.
        Writable: moving a target changes nothing else.
    revision : int
        A number new with every change of the pinned set, never used by
        another control (:data:`REVISIONS`).
    """

    def __init__(self, mass: np.ndarray, pinned: np.ndarray, targets: np.ndarray):
        self._mass = np.asarray(mass, dtype=float)
        self.targets = np.asarray(targets, dtype=float)
        self.pinned = pinned

    def get_state(self) -> dict[str, np.ndarray]:
        """What a checkpoint keeps of the pins: ``pinned`` (N,) bool and
        ``targets`` (N, 3) m (:meth:`set_state` takes it back)."""
        return {"pinned": self.pinned, "targets": self.targets}

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        """Take back what :meth:`get_state` gave (copied)."""
        self.targets[:] = state["targets"]
        self.pinned = state["pinned"]

    @classmethod
    def from_model(cls, model) -> Control:
        """The scene's pins, targets at the rest positions."""
        return cls(model.mass, model.pinned, model.rest_positions.copy())

    @property
    def pinned(self) -> np.ndarray:
        """Read-only ``(N,)`` bool mask of the held points."""
        return self._pinned

    @pinned.setter
    def pinned(self, mask: np.ndarray) -> None:
        mask = np.array(mask, dtype=bool)  # a copy: the caller's array stays theirs
        if mask.shape != self._mass.shape:
            raise InputError("pinned", f"expected shape {self._mass.shape}, got {mask.shape}")
        inv_mass = 1.0 / self._mass
        inv_mass[mask] = 0.0
        for array in (mask, inv_mass):
            array.flags.writeable = False
        self._pinned, self._inv_mass = mask, inv_mass
        self._pinned_index = np.flatnonzero(mask)
        self._movable_index = np.flatnonzero(~mask)
        self.revision = next(REVISIONS)

    @property
    def inv_mass(self) -> np.ndarray:
        """Read-only ``(N,)`` inverse masses in 1/kg, zero at pinned points:
        what integrators use."""
        return self._inv_mass

    @property
    def pinned_index(self) -> np.ndarray:
        """Indices of the pinned points, ``(P,)``."""
        return self._pinned_index

    @property
    def movable_index(self) -> np.ndarray:
        """Indices of the free points, ``(N - P,)``."""
        return self._movable_index

    def pin(self, k: int, target: np.ndarray) -> None:
        """Hold point ``k`` at ``target`` (metres)."""
        self.targets[k] = target
        if not self._pinned[k]:
            mask = self._pinned.copy()
            mask[k] = True
            self.pinned = mask

    def unpin(self, k: int) -> None:
        """Let point ``k`` move freely."""
        if self._pinned[k]:
            mask = self._pinned.copy()
            mask[k] = False
            self.pinned = mask


@dataclass(frozen=True)
class Snapshot:
    """What a viewer on another thread draws: one instant of a simulation,
    copied whole, so no picture mixes two states (positions of one, pins or
    time of another). Made by :meth:`Simulation.snapshot
    <pvcloth.physics.simulation.Simulation.snapshot>`; its arrays are
    read-only copies.

    Attributes
    ----------
    x, v : ndarray, shape (N, 3)
        Positions (m) and velocities (m/s).
    t : float
        Time (s).
    steps : int
        Steps taken since the start.
    pinned : ndarray, shape (P,)
        Indices of the pinned points.
    integrator : str
        The integrator's name (``+ACCELERATOR`` when the scene names one).
    dt : float
        The step (s).
    dt_source : str
        Where the step came from (``Simulation.dt_source``).
    adaptive : bool
        Whether a controller chooses the steps.
    wind : WindSpec or None
        The wind blowing.
    """

    x: np.ndarray
    v: np.ndarray
    t: float
    steps: int
    pinned: np.ndarray
    integrator: str
    dt: float
    dt_source: str
    adaptive: bool
    wind: object = None

    def __post_init__(self):
        for array in (self.x, self.v, self.pinned):
            array.flags.writeable = False
