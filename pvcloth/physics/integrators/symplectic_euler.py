"""Symplectic (semi-implicit) Euler: velocity first, then position."""

from __future__ import annotations

from typing import TYPE_CHECKING

from pvcloth.physics.integrators.base import Integrator, register, reuse_or_allocate
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class SymplecticEuler(Integrator):
    """``v' = v + h a(x, v)``, ``x' = x + h v'``.

    First order, but symplectic: on an undamped spring system its energy
    error stays bounded instead of drifting. Stable on a mode of frequency
    ``omega`` and damping rate ``alpha`` while
    ``h < 2 (sqrt(alpha^2 + omega^2) - alpha) / omega^2`` (``2 / omega``
    without damping), from the Jury conditions on its 2x2 step matrix.
    """

    name, order = "symplectic_euler", 1  # registry key; global order of accuracy
    description = "semi-implicit Euler; 1st order, bounded energy error"

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        f = self.forces(model, state)
        new = reuse_or_allocate(out, state)
        self.check = model.kick_drift(state.x, state.v, f, control.inv_mass, dt, new.x, new.v)
        new.t = state.t + dt
        return new
