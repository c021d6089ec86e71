"""Symplectic (semi-implicit) Euler: velocity first, then position."""

from __future__ import annotations

import numpy as np

from pvcloth.physics.integrators.base import Integrator, register, reuse_or_allocate


@register
class SymplecticEuler(Integrator):
    """``v' = v + h a(x, v)``, ``x' = x + h v'``.

    First order, but symplectic: on an undamped spring system its energy
    error stays bounded instead of drifting. Stable on a mode of frequency
    ``omega`` and damping rate ``alpha`` while
    ``h < 2 (sqrt(alpha^2 + omega^2) - alpha) / omega^2`` (``2 / omega``
    without damping), from the Jury conditions on its 2x2 step matrix.
    """

    name = "symplectic_euler"
    order = 1
    description = "semi-implicit Euler; 1st order, bounded energy error"

    def step(self, model, state, control, dt, out=None):
        f = self.forces(model, state)
        new = reuse_or_allocate(out, state)
        if getattr(model, "compiled", False):
            from pvcloth.physics.kernels import kick_drift

            new.checked = kick_drift(
                state.x, state.v, f, control.inv_mass, dt, new.x, new.v, model.shape
            )
        else:
            f *= control.inv_mass[:, None]
            np.multiply(f, dt, out=new.v)
            new.v += state.v
            np.multiply(new.v, dt, out=new.x)
            new.x += state.x
            new.checked = None
        new.t = state.t + dt
        return new
