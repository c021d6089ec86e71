"""Forward (explicit) Euler: the cheapest and least stable method."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pvcloth.physics.integrators.base import Integrator, register, reuse_or_allocate
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class ExplicitEuler(Integrator):
    """``x' = x + h v``, ``v' = v + h a(x, v)``.

    First order. Its growth factor on an oscillator is ``|1 + h lambda| > 1``
    for every undamped mode, so without damping it gains energy at any step;
    with damping it is stable while ``h < 2 alpha / omega^2`` for each mode.
    """

    name, order = "explicit_euler", 1  # registry key; global order of accuracy
    description = "forward Euler; 1st order, gains energy, needs damping"

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        new = reuse_or_allocate(out, state)
        a = self.forces(model, state)
        a *= control.inv_mass[:, None]
        np.multiply(state.v, dt, out=new.x)
        new.x += state.x
        np.multiply(a, dt, out=new.v)
        new.v += state.v
        new.t = state.t + dt
        return new
