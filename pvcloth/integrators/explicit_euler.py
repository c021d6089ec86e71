"""Forward (explicit) Euler: the cheapest and least stable method."""

from __future__ import annotations

from ..stability import stiffest_mode
from ..state import State
from .base import Integrator, largest_stable_step, register


@register
class ExplicitEuler(Integrator):
    """``x' = x + h v``, ``v' = v + h a(x, v)``.

    First order. Its growth factor on an oscillator is ``|1 + h lambda| > 1``
    for every undamped mode, so without damping it gains energy at any step;
    with damping it is stable while ``h < 2 alpha / omega^2`` for each mode.
    """

    name = "explicit_euler"
    order = 1
    description = "forward Euler; 1st order, gains energy, needs damping"

    def step(self, model, state, control, dt):
        a = model.compute_forces(state.x, state.v)
        a *= control.inv_mass[:, None]
        x = state.x + dt * state.v
        v = state.v + dt * a
        return State(x, v, state.t + dt)

    def stable_dt(self, model, state, control):
        mode = stiffest_mode(model, state.x, state.v, control.inv_mass)
        if mode.alpha <= 1e-9 * mode.omega:
            return 0.0  # an undamped oscillation grows at any step
        return largest_stable_step(mode.eigenvalues(), lambda z: 1.0 + z)
