"""The interface every integrator follows, and the registry that finds them."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

#: Name -> integrator class. Filled by :func:`register`.
INTEGRATORS: dict[str, type[Integrator]] = {}


def register(cls: type[Integrator]) -> type[Integrator]:
    """Class decorator that makes an integrator available by its ``name``."""
    INTEGRATORS[cls.name] = cls
    return cls


class Integrator(ABC):
    """Advances a cloth by one step.

    An integrator knows nothing about wind, spheres or pins: it asks the model
    for forces (and, if implicit, Jacobians) and treats points whose inverse
    mass is zero as immovable. The simulation sets pinned points' velocities
    and positions around each step.

    Attributes
    ----------
    name : str
        Registry key, as written in scene files.
    order : int
        Global order of accuracy.
    """

    name: str = ""
    order: int = 1
    description: str = ""

    @abstractmethod
    def step(self, model, state, control, dt: float):
        """Return the :class:`~pvcloth.state.State` one step ``dt`` later."""

    def stable_dt(self, model, state, control) -> float | None:
        """Largest stable time step near ``state``, or ``None`` if this
        integrator has no step limit (or no useful estimate)."""
        return None

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def largest_stable_step(eigenvalues: np.ndarray, amplification) -> float:
    """Largest ``h`` with ``|amplification(h * lam)| <= 1`` for all eigenvalues.

    ``amplification`` maps ``z = h * lambda`` to the growth factor of the
    method on ``y' = lambda y``; the root is found by bisection.
    """
    lam = np.asarray(eigenvalues, dtype=complex)
    scale = float(np.max(np.abs(lam)))
    if scale == 0.0:
        return float("inf")

    def stable(h):
        return bool(np.all(np.abs(amplification(h * lam)) <= 1.0 + 1e-12))

    low, high = 0.0, 1.0 / scale
    while stable(high):
        low, high = high, 2.0 * high
        if high > 1e6 / scale:
            return float("inf")
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if stable(mid) else (low, mid)
    return low
