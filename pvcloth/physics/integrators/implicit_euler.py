"""Backward Euler linearised once per step (Baraff and Witkin 1998)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import cg, spsolve

from pvcloth.errors import DivergenceError
from pvcloth.physics.integrators.base import Integrator, drift_error, register
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class ImplicitEuler(Integrator):
    """One Newton step of backward Euler, as in Baraff and Witkin (1998).

    Solves ``(M - h C - h^2 K) dv = h (f + h K v)`` for the velocity change,
    with ``K = dF/dx`` and ``C = dF/dv`` from the force terms, then
    ``v' = v + dv`` and ``x' = x + h v'``. Pinned points are left out of the
    system (their velocity is prescribed). The matrix is symmetric positive
    definite (the springs' Jacobian drops the destabilising transverse term of
    compressed springs), so conjugate gradients with a Jacobi preconditioner
    solve it, warm-started from the previous step's ``dv``; if CG stalls (very
    stiff or very light cloths), a sparse direct solve takes over.

    Stable at any step on the linearised cloth, at the price of numerical
    damping that grows with ``h omega``; first order. Each step leaves its
    error estimate in :attr:`error` (:func:`~pvcloth.physics.integrators.base.drift_error`,
    backward Euler against the trapezoidal rule), so ``solver.tolerance``
    may choose its steps; the estimate measures the time discretisation,
    not the one linearisation (that is the solver error studies measure
    against ``backward_euler``; that reference takes each dashpot on its
    spring's change of length over the step, this method on the relative
    velocity along the spring, which differ only as the spring turns
    within the step).

    Parameters
    ----------
    rtol : float
        Relative tolerance of the conjugate-gradient solve.
    """

    name, order = "implicit_euler", 1  # registry key; global order of accuracy
    description = "Baraff-Witkin backward Euler; 1st order, stable at large steps, damps"
    converges_to = "backward_euler"
    uses_blas = True  # sparse solves and long dot products
    embedded = True  # backward Euler against the trapezoidal rule, from the same solve

    def __init__(self, rtol: float = 1e-8, maxiter: int = 2000):
        self.rtol = rtol
        self.maxiter = maxiter
        self._last_dv: np.ndarray | None = None
        self.direct_solves = 0  # steps where CG stalled and a factorisation answered
        #: Error estimate of the last step (m): see :func:`drift_error`.
        self.error = 0.0

    def get_state(self) -> dict[str, np.ndarray]:
        return {} if self._last_dv is None else {"last_dv": self._last_dv.copy()}

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        self._last_dv = state.get("last_dv")

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        x, v = state.x, state.v
        f = model.compute_forces(x, v).ravel()
        dfdx, dfdv = model.jacobians(x, v)
        free = np.repeat(control.inv_mass > 0, 3)
        mass = np.repeat(model.mass, 3)
        system = (sp.diags(mass) - dt * dfdv - dt * dt * dfdx).tocsr()[free][:, free]
        rhs = dt * (f + dt * (dfdx @ v.ravel()))[free]
        if not (np.all(np.isfinite(system.data)) and np.all(np.isfinite(rhs))):
            # A non-finite state gives a non-finite system: no solver can
            # answer it (scipy's direct solve only warns "exactly singular").
            raise DivergenceError(
                f"implicit Euler: the forces or their derivatives are not finite at "
                f"t = {state.t:.6g} s (dt = {dt:.3g} s); the state diverged, try a smaller dt"
            )
        guess = (
            self._last_dv if self._last_dv is not None and self._last_dv.size == rhs.size else None
        )
        preconditioner = sp.diags(1.0 / system.diagonal())
        dv_free, info = cg(
            system, rhs, x0=guess, rtol=self.rtol, maxiter=self.maxiter, M=preconditioner
        )
        if info != 0:
            # Very stiff or very light cloths can stall CG; the matrix is SPD,
            # so a sparse direct solve always answers (more slowly).
            self.direct_solves += 1
            dv_free = spsolve(system.tocsc(), rhs)
        if not np.all(np.isfinite(dv_free)):
            raise DivergenceError(
                f"implicit Euler: the linear solve failed at t = {state.t:.6g} s "
                f"(dt = {dt:.3g} s); try a smaller dt"
            )
        self._last_dv = dv_free
        dv = np.zeros(3 * model.n_points)
        dv[free] = dv_free
        v_new = v + dv.reshape(-1, 3)
        self.error = drift_error(dt, v, v_new)
        return State(x + dt * v_new, v_new, state.t + dt)
