"""Backward Euler solved to convergence: the reference for the implicit methods."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from cholespy import CholeskySolverD, MatrixType
from scipy.sparse.linalg import splu

from pvcloth.errors import DivergenceError
from pvcloth.physics.integrators.base import Integrator, drift_error, register
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class BackwardEuler(Integrator):
    """Backward Euler, Newton's method with a line search run to a stated residual.

    Finds the positions ``x'`` one step later that satisfy, at every free
    point, ``r(x') = x' - x - h v - h^2 M^-1 F(x', v') = 0`` with ``v' =
    (x' - x) / h``: every force, spring dashpots included, taken at the end
    of the step. Each Newton iteration solves ``(M - h^2 K - h C) dx = -M r``
    with the force Jacobians ``K = dF/dx`` and ``C = dF/dv`` at the current
    iterate, and a backtracking line search halves the step until ``|r|``
    falls. Far from the solution (unbalanced acceleration above :attr:`exact_below`) the
    Jacobian is the clamped, positive definite one
    :class:`~pvcloth.physics.integrators.implicit_euler.ImplicitEuler` uses
    (sparse Cholesky, cholespy): where springs buckle the exact one is
    indefinite and its steps were measured to wander between solutions.
    Close to it the exact Jacobian (compressed springs' negative transverse
    stiffness and the dashpots' turning with their spring included; sparse
    LU, SuperLU) converges quadratically; should its direction not lower
    the residual, the step goes back to the clamped one.

    A step has converged when no point is left with an unbalanced
    acceleration (``r / h^2``, the force the step leaves unbalanced over the
    mass) above :attr:`tolerance`, ``1e-3`` m/s^2 (a ten-thousandth of g):
    ``x'`` is then backward Euler's answer to within about ``1e-3 h^2``
    metres (2.8e-7 m at a 1/60 s step; the Newton matrix is the identity
    plus a positive semi-definite part in the mass metric, so its inverse
    does not magnify the residual), far below the errors it is used to
    measure. (A tolerance in metres would accept the first guess at small
    steps, whose residual ``h^2 F / m`` is tiny: at 7e-5 s it left out the
    forces.) The factorisation is kept from one iteration to the next while
    the residual at least halves each time (a chord step), and redone when
    it does not. That makes
    it the reference that separates, for an implicit method at a step ``h``,
    the error of stopping its iterations early (its distance from this
    method at the same ``h``) from the error of the time discretisation
    (this method's distance from a fine reference). Several factorisations
    per step (seconds per step at 64x64): a measuring instrument, not an
    interactive method. Known limit: on stiff, light cloth that buckles at
    frame steps (the cotton scene at 1/60 s, 32x32 and 64x64) the line
    search stalls and the step raises instead of converging; the hanging
    scene converges at every step measured.

    Parameters
    ----------
    iterations : int
        The most Newton iterations per step; a step that has not converged
        by then raises :class:`~pvcloth.errors.DivergenceError` (a smaller
        step converges in fewer).
    """

    name, order = "backward_euler", 1  # registry key; global order of accuracy
    description = "backward Euler, Newton to 1e-3 m/s^2 unbalanced; the implicit methods' reference"
    interactive = False  # seconds per step at 64x64: not offered by the window's key
    uses_blas = True  # sparse solves and long dot products
    embedded = True  # against the trapezoidal rule from the same velocities (drift_error)
    #: Largest unbalanced acceleration (m/s^2) of any point in a converged step.
    tolerance = 1e-3  # 1e-4 was measured to stall near 1e-3 on a 32x32 cotton step
    #: Unbalanced acceleration (m/s^2) below which Newton takes the exact Jacobian.
    exact_below = 0.5

    def __init__(self, iterations: int = 100):
        self.iterations = iterations
        #: Newton iterations the last step took, and factorisations.
        self.last_iterations = self.last_factorisations = 0
        #: Error estimate of the last step (m): see :func:`drift_error`.
        self.error = 0.0

    def stable_dt(self, model: Model, state: State, control: Control) -> float:
        return float("inf")  # the converged step is backward Euler's: A-stable

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        x, v = state.x, state.v
        moves = control.inv_mass > 0
        free = np.repeat(moves, 3)
        mass = np.repeat(model.mass, 3)
        # Explicit drift as the start (a start from the last step's change
        # of velocity was measured to save nothing); pinned points where the
        # simulation sends them (it set their velocity).
        guess = x + dt * v
        residual = self._residual(model, x, v, guess, dt, control)
        size = np.abs(residual).max() / dt**2
        solve, exact, fresh, banned, forced = None, False, False, False, False
        factorisations, previous_size = 0, np.inf
        for count in range(self.iterations + 1):
            if size <= self.tolerance:
                self.last_iterations, self.last_factorisations = count, factorisations
                v_new = (guess - x) / dt
                self.error = drift_error(dt, v, v_new)
                return State(guess, v_new, state.t + dt)
            if count == self.iterations:
                break
            # Far from the solution the clamped, positive definite Jacobian
            # (the exact one is indefinite where springs buckle, and its
            # Newton steps wander between solutions); close to it the exact
            # one, for quadratic convergence.
            want_exact = (size < self.exact_below or forced) and not banned
            if solve is None or want_exact != exact or size > 0.5 * previous_size:
                exact = want_exact
                solve = self._factorise(model, guess, (guess - x) / dt, dt, mass, free, exact)
                factorisations, fresh = factorisations + 1, True
            previous_size = size
            correction = np.zeros_like(x)
            correction[moves] = solve(-(model.mass[:, None] * residual)[moves].ravel()).reshape(
                -1, 3
            )
            # Backtracking on |r|_2: the full step first, halved until the
            # residual falls (1e-4 of the predicted fall, as Armijo asks).
            norm = np.linalg.norm(residual)
            alpha, trial_norm = 1.0, np.nan
            while alpha >= 1 / 1024:
                trial = guess + alpha * correction
                trial_residual = self._residual(model, x, v, trial, dt, control)
                if np.linalg.norm(trial_residual) <= (1.0 - 1e-4 * alpha) * norm:
                    trial_norm = np.linalg.norm(trial_residual)
                    break
                alpha /= 2
            if not np.isfinite(trial_norm):
                # No descent: a factor kept from an earlier iterate is
                # redone here; a fresh exact one gives way to the clamped,
                # and a fresh clamped one to the exact (once each).
                if fresh and exact:
                    banned, forced = True, False
                elif fresh:
                    if banned or forced:
                        break
                    forced = True
                solve = None
                continue
            guess, residual, fresh, forced = trial, trial_residual, False, False
            size = np.abs(residual).max() / dt**2
        raise DivergenceError(
            f"backward Euler did not converge at t = {state.t:.6g} s: Newton's method left "
            f"{size:.3g} m/s^2 unbalanced after {self.iterations} iterations (tolerance "
            f"{self.tolerance:g} m/s^2); a smaller dt converges in fewer"
        )

    @staticmethod
    def _factorise(model, x, v, dt, mass, free, exact: bool):
        """A solver of ``(M - h^2 dF/dx - h dF/dv) dx = b`` at ``x, v`` on the
        free rows: the exact Jacobian by sparse LU (SuperLU: it may be
        indefinite), or the clamped, positive definite one by Cholesky."""
        dfdx, dfdv = model.jacobians(x, v, exact=exact)
        matrix = (sp.diags(mass) - dt * dfdv - dt * dt * dfdx).tocsr()[free][:, free]
        if exact:
            try:
                return splu(matrix.tocsc()).solve
            except RuntimeError:  # exactly singular: the caller falls back
                return lambda rhs: np.full_like(rhs, np.nan)
        matrix.sort_indices()
        factor = CholeskySolverD(
            matrix.shape[0],
            matrix.indptr.astype(np.int32),
            matrix.indices.astype(np.int32),
            matrix.data,
            MatrixType.CSR,
        )

        def solve(rhs):
            result = np.empty_like(rhs)
            factor.solve(rhs, result)
            return result

        return solve

    @staticmethod
    def _residual(model, x, v, trial, dt, control) -> np.ndarray:
        """``r`` at ``trial`` ``(N, 3)`` in metres, zero at pinned points."""
        force = model.compute_forces(trial, (trial - x) / dt)
        return trial - x - dt * v - dt * dt * force * control.inv_mass[:, None]
