"""Classical fourth-order Runge-Kutta on positions and velocities."""

from __future__ import annotations

from typing import TYPE_CHECKING

from pvcloth.physics.integrators.base import Integrator, register
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class RungeKutta4(Integrator):
    """The classical RK4 on ``(x, v)``: fourth order, four force evaluations.

    Most accurate per step of the explicit methods; its undamped step limit is
    ``2 sqrt(2) / omega``, and it loses a little energy per step (it is not
    symplectic).
    """

    name, order = "rk4", 4  # registry key; global order of accuracy
    description = "classical Runge-Kutta; 4th order, 4 force evaluations"

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        def acceleration(x, v):
            return self.acceleration(model, control, x, v)

        x0, v0 = state.x, state.v
        a1 = acceleration(x0, v0)
        v2 = v0 + 0.5 * dt * a1
        a2 = acceleration(x0 + 0.5 * dt * v0, v2)
        v3 = v0 + 0.5 * dt * a2
        a3 = acceleration(x0 + 0.5 * dt * v2, v3)
        v4 = v0 + dt * a3
        a4 = acceleration(x0 + dt * v3, v4)
        x = x0 + dt / 6.0 * (v0 + 2.0 * v2 + 2.0 * v3 + v4)
        v = v0 + dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        return State(x, v, state.t + dt)
