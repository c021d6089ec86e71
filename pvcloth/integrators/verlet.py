"""Velocity Verlet (kick-drift-kick leapfrog): second order, symplectic."""

from __future__ import annotations

from ..state import State
from .base import Integrator, register


@register
class VelocityVerlet(Integrator):
    """``v+ = v + h/2 a(x, v)``, ``x' = x + h v+``, ``v' = v+ + h/2 a(x', v+)``.

    Second order and symplectic for position-dependent forces, with the same
    undamped step limit ``2 / omega`` as symplectic Euler, at two force
    evaluations per step. Damping forces are evaluated at the half-step
    velocity, which keeps it explicit.
    """

    name = "verlet"
    order = 2
    description = "velocity Verlet; 2nd order, symplectic, 2 force evaluations"

    def step(self, model, state, control, dt):
        inv_mass = control.inv_mass[:, None]
        half = state.v + 0.5 * dt * inv_mass * model.compute_forces(state.x, state.v)
        x = state.x + dt * half
        v = half + 0.5 * dt * inv_mass * model.compute_forces(x, half)
        return State(x, v, state.t + dt)
