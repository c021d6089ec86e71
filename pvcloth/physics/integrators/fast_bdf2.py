"""BDF2 by local/global iterations on one prefactorised matrix: the second-order
twin of ``fast_mass_spring``."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pvcloth.physics.integrators.base import register
from pvcloth.physics.integrators.bdf2 import History, KeepsLastStep, bdf2_error, bdf2_start
from pvcloth.physics.integrators.fast_mass_spring import FastMassSpring
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


#: Fewest local/global iterations :class:`FastBDF2` takes a step (see there).
MIN_ITERATIONS = 10
#: Fewest iterations with ``accelerator="lbfgs"``, whose every iteration
#: lowers the step's energy (see :class:`FastBDF2`).
MIN_LBFGS_ITERATIONS = 5


@register
class FastBDF2(KeepsLastStep, FastMassSpring):
    """BDF2 (:class:`~pvcloth.physics.integrators.bdf2.BDF2`) solved as
    ``fast_mass_spring`` solves backward Euler: local/global iterations,
    accelerated by Chebyshev's method, on one factorised matrix.

    BDF2's step is backward Euler's equation with the combinations of the
    last two states in place of the start and two thirds of the step
    (:func:`~pvcloth.physics.integrators.bdf2.bdf2_start`), so the global
    matrix is ``M (1 + r h) + h^2 (K + Q)`` with ``h = 2 dt / 3``: constant
    while the step is, factorised once. Air damping (rate ``r``) is in that
    matrix, implicit; gravity is constant; the wind is taken at the state
    extrapolated from the last two to the step's end (``2 y - y_prev`` at a
    constant step), second order like the rest. The springs' dashpots are
    left out, as ``fast_mass_spring`` leaves them out (their share of the
    error is measured in ``benchmarks/results/frame_step.md``). The first
    step, and the first after a reset or an edit of the state, is
    ``fast_mass_spring``'s. Stopped
    after :attr:`iterations`, the step is not BDF2's answer: its distance
    from :class:`~pvcloth.physics.integrators.bdf2.BDF2` at the same step
    is the solver's share of its error, the time discretisation's being
    ``bdf2``'s own.

    It needs :data:`MIN_ITERATIONS` iterations a step. Stopped earlier,
    the solver's error feeds BDF2's recurrence, which takes the velocity
    from positions over two thirds of a step and builds on two steps: on
    cotton at 32x32 points and 1/60 s steps, five and six iterations
    multiplied the energy by 170 and 160 within 10 s, and on that cloth a
    hundred times lighter and undamped by 16,000 and 11,000; with eight and
    more it never rose 2 % above its start (``python benchmarks/frame_step.py
    --stability``). Ten leaves a margin over the eight measured stable.
    With ``accelerator="lbfgs"``, whose every iteration lowers the step's
    energy, it needs :data:`MIN_LBFGS_ITERATIONS`: with three and five the
    energy never rose above its start on cotton and at most 1.3-fold and
    1.09-fold on the light undamped cloth (the same runs). That bound is
    looser than the 2 % that set Chebyshev's ten (six to eight were not
    measured): what it rules out is growth without bound.

    Parameters
    ----------
    iterations : int
        Local/global iterations per step, at least :data:`MIN_ITERATIONS`
        (:data:`MIN_LBFGS_ITERATIONS` with L-BFGS;
        :func:`~pvcloth.physics.integrators.get_integrator` refuses fewer;
        a study that measures fewer sets :attr:`iterations` after).
    rho : float
        Chebyshev's estimate of the plain iteration's contraction (0 <= rho < 1).
    accelerator : {"chebyshev", "lbfgs"}
        How the iterations are sped up (see ``fast_mass_spring``).
    memory : int
        Moves L-BFGS remembers.
    """

    name, order = "fast_bdf2", 2  # registry key; global order of accuracy when converged
    description = "BDF2 by local/global iterations, prefactorised; second order when converged"
    converges_to = "bdf2"
    min_iterations = MIN_ITERATIONS
    too_few_iterations = (
        f"fewer were measured to gain energy (it takes {MIN_ITERATIONS} with Chebyshev, "
        f"{MIN_LBFGS_ITERATIONS} with L-BFGS; fast_mass_spring takes fewer)"
    )

    @classmethod
    def fewest_iterations(cls, accelerator: str | None = None) -> int:
        """:data:`MIN_LBFGS_ITERATIONS` with L-BFGS, else :data:`MIN_ITERATIONS`."""
        return MIN_LBFGS_ITERATIONS if accelerator == "lbfgs" else MIN_ITERATIONS

    def __init__(
        self,
        iterations: int = MIN_ITERATIONS,
        rho: float = 0.95,
        accelerator: str = "chebyshev",
        memory: int = 5,
    ):
        super().__init__(iterations, rho, accelerator, memory)
        self.history = History()
        #: Whether the last step was the backward Euler start-up.
        self.started_up = False

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        last = self.history.before(state, dt)
        self.started_up = last is None
        if last is None:
            result = super().step(model, state, control, dt, out)
            self.history.after(state, dt)
            return result
        x, v = state.x, state.v
        self._begin_contact(model, state, dt)
        x_hat, v_hat, h = bdf2_start(last, x, v, dt)
        load = np.zeros_like(x)
        model.add_gravity(x, v, load)
        if model.wind is not None:  # at the state extrapolated to the step's end
            w = dt / last.dt
            model.add_wind(x + w * (x - last.x), v + w * (v - last.v), load)
        end = self.solve(model, control, x_hat, v_hat, h, load, x + dt * v, air=model.air_rate)
        v_new = (end - x_hat) / h
        v_new[control.pinned] = v[control.pinned]
        self.error = bdf2_error(last, v, v_new, dt)
        self.history.after(state, dt)
        return State(end, v_new, state.t + dt)
