"""Backward Euler solved to convergence: the reference for the implicit methods."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from cholespy import CholeskySolverD, MatrixType
from scipy.sparse.linalg import splu

from pvcloth.errors import DivergenceError
from pvcloth.physics.forces import TINY_LENGTH
from pvcloth.physics.integrators.base import Integrator, drift_error, register
from pvcloth.physics.integrators.penalties import LayerPenalty, ObstaclePenalty
from pvcloth.physics.springs import BlockPattern, stiffness_blocks
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class BackwardEuler(Integrator):
    """Backward Euler as a minimisation, by Newton's method to a stated residual.

    The step's end positions ``x'`` minimise the incremental potential
    (Martin et al. 2011, Gast et al. 2015)

    ``Psi(t) = |t - x - h v|^2_M / (2 h^2) + sum_s E_s(t) + A(t) - f . t``

    whose stationary point is backward Euler's equation ``x' - x - h v - h^2
    M^-1 F(x', v') = 0`` with ``v' = (x' - x) / h``. Each spring's energy
    ``E_s = k/2 (L - rest)^2 + c/(2h) (L - L_0)^2`` holds its Hooke spring
    and its dashpot, which acts on the change of the spring's length ``L``
    over the step (``L_0`` at its start): ``c (L' - L_0)/h``, backward
    Euler's value of the dashpot's ``c dL/dt``, along the spring's direction
    at the end of the step. Both terms together are one spring of stiffness
    ``k + c/h`` and rest length ``(k rest + c/h L_0) / (k + c/h)``. Air
    damping is ``A = sum r m |t - x|^2 / (2 h)``; gravity and the wind are
    ``f``, the wind (which has no potential) taken at an anchor iterate and
    re-taken until it agrees with the end of the step. Plate bending
    (:mod:`pvcloth.physics.bending`) adds ``sum_c t_c^T Q t_c / 2``, whose
    Hessian ``Q`` is constant and positive semi-definite.

    Each Newton iteration solves ``(M (1 + r h) + h^2 H) dx = -M r_psi``
    with ``H`` the springs' Hessian: clamped to positive semi-definite far
    from the solution (unbalanced acceleration above :attr:`exact_below`;
    sparse Cholesky, cholespy), exact close to it (compressed springs'
    negative transverse stiffness; sparse LU, SuperLU) for quadratic
    convergence. A backtracking line search on ``Psi`` (Armijo) accepts
    the step: the clamped direction always descends it, so a short enough
    step always lowers it, and an exact direction that does not is dropped
    for the clamped one. (A search on ``|r|`` stalled where springs buckle,
    the cotton scene at 1/60 s: ``|r|`` has local minima that are not
    solutions, while every minimum of ``Psi`` is one. Within ten times the
    tolerance a fall of ``|r|`` passes too: there a small step's last
    iterations change ``Psi`` by less than its rounding.) The factorisation
    is kept from one iteration to the next while the residual at least
    halves (a chord step).

    With obstacles (and no self-collision) the potential holds a penalty
    for each (:class:`~pvcloth.physics.integrators.penalties.ObstaclePenalty`),
    so the solve sees what holds the cloth; the response after the step
    stays as the fail-safe and applies the friction. With
    ``[self_collision] in_solve = true``, it holds one for each pair of
    layers the step may bring close as well
    (:class:`~pvcloth.physics.integrators.penalties.LayerPenalty`), the
    obstacles' too with self-collision, and no step is split for
    self-collision.

    A step has converged when no point is left with an unbalanced
    acceleration (``r / h^2``, the force the step leaves unbalanced over the
    mass) above :attr:`tolerance`, ``1e-3`` m/s^2 (a ten-thousandth of g):
    ``x'`` is then backward Euler's answer to within about ``1e-3 h^2``
    metres (2.8e-7 m at a 1/60 s step; the Newton matrix is the identity
    plus a positive semi-definite part in the mass metric, so its inverse
    does not magnify the residual), far below the errors it is used to
    measure. (A tolerance in metres would accept the first guess at small
    steps, whose residual ``h^2 F / m`` is tiny: at 7e-5 s it left out the
    forces.) That makes it the reference that separates, for an implicit
    method at a step ``h``, the error of stopping its iterations early (its
    distance from this method at the same ``h``) from the error of the time
    discretisation (this method's distance from a fine reference). Several
    factorisations per step (seconds per step at 64x64): a measuring
    instrument, not an interactive method.

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
    tolerance = 1e-3
    #: Unbalanced acceleration (m/s^2) below which Newton takes the exact Hessian.
    exact_below = 0.5

    def __init__(self, iterations: int = 200):
        self.iterations = iterations
        #: Newton iterations the last step took, and factorisations.
        self.last_iterations = self.last_factorisations = 0
        #: Error estimate of the last step (m): see :func:`drift_error`.
        self.error = 0.0
        self._pattern: tuple[int, BlockPattern] | None = None
        #: The obstacles' penalty of the last step's solve (None without
        #: obstacles): see :class:`ObstaclePenalty`.
        self.penalty: ObstaclePenalty | None = None
        #: The layers' penalty of the last step's solve (None unless the
        #: scene's self-collision asks for it, ``in_solve``): see :class:`LayerPenalty`.
        self.layers: LayerPenalty | None = None
        #: Whether the obstacles and the layers enter the solve (False: after
        #: the step only, as the explicit integrators have them).
        self.contact_in_step = True

    @property
    def holds_layers(self) -> bool:
        return self.contact_in_step

    def held_layers(self, x: np.ndarray):
        return None if self.layers is None else self.layers.held(x)

    def held_contacts(self, x: np.ndarray, t: float) -> list:
        if self.penalty is None:
            return []
        return self.penalty.held(x, t)

    def stable_dt(self, model: Model, state: State, control: Control) -> float:
        return float("inf")  # the converged step is backward Euler's: A-stable

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        x, v = state.x, state.v
        # Explicit drift as the start (a start from the last step's change
        # of velocity was measured to save nothing); pinned points where the
        # simulation sends them (it set their velocity).
        end = self.solve(model, control, x, v, dt, x + dt * v, state.t)
        v_new = (end - x) / dt
        self.error = drift_error(dt, v, v_new)
        return State(end, v_new, state.t + dt)

    def solve(
        self,
        model: Model,
        control: Control,
        x: np.ndarray,
        v: np.ndarray,
        dt: float,
        guess: np.ndarray,
        t: float,
        end_time: float | None = None,
        positions: np.ndarray | None = None,
    ) -> np.ndarray:
        """The end positions ``x'`` (m, ``(N, 3)``) of the implicit equation
        ``x' = x + dt v + dt^2 M^-1 F(x', (x' - x) / dt)``, by Newton from
        ``guess`` (which holds the pinned points' end positions: they stay).

        Backward Euler's step of length ``dt`` takes ``x``, ``v`` from the
        start of the step; BDF2 (:mod:`~pvcloth.physics.integrators.bdf2`)
        has the same equation with its combinations of the last two steps
        for ``x``, ``v`` and two thirds of its step for ``dt``. ``t`` (s) is
        the step's start (it names the step in the error raised when Newton
        does not converge); ``end_time`` (s, ``t + dt`` if not given) where
        the obstacles are met (:class:`ObstaclePenalty`); ``positions`` (m,
        ``(N, 3)``, ``x`` if not given) the step's start, where the layers'
        pairs are fixed (:class:`LayerPenalty`)."""
        table = model.spring_table()
        # The pattern depends only on the springs' ends, which never change
        # for a model: kept until another model comes.
        if self._pattern is None or self._pattern[0] != model.serial:
            self._pattern = (model.serial, BlockPattern(table.a, table.b, model.n_points))
        end_time = t + dt if end_time is None else end_time
        self.penalty = self.layers = None
        # With the layers after the step, the obstacles stay after it too: a
        # floor inside the solve would bear the lowest layer's weight alone
        # while the layers above drag it (a folded towel crept down a slope).
        layers = model.self_collision is not None and model.self_collision.in_solve
        if self.contact_in_step and (model.self_collision is None or layers):
            self.penalty = ObstaclePenalty.build(model, control, x, dt, guess, end_time)
            self.layers = LayerPenalty.build(model, control, x, dt, guess, positions)
        penalties = [p for p in (self.penalty, self.layers) if p is not None]
        potential = _StepPotential(model, x, v, dt, control.inv_mass, self._pattern[1], penalties)
        potential.anchor(guess)
        residual = potential.residual(guess)
        size = np.abs(residual).max() / dt**2
        solve, exact, fresh = None, False, False
        exact_limit = self.exact_below  # lowered when an exact direction fails
        factorisations, previous_size = 0, np.inf
        for count in range(self.iterations + 1):
            if size <= self.tolerance and potential.anchor(guess):
                residual = potential.residual(guess)  # the wind taken here
                size = np.abs(residual).max() / dt**2
            if size <= self.tolerance:
                self.last_iterations, self.last_factorisations = count, factorisations
                return guess
            if count == self.iterations:
                break
            # Far from the solution the clamped, positive definite Hessian
            # (the exact one is indefinite where springs buckle); close to
            # it the exact one, for quadratic convergence.
            want_exact = size < exact_limit
            if solve is None or want_exact != exact or size > 0.5 * previous_size:
                exact = want_exact
                solve = potential.factorise(guess, exact, control.pinned)
                factorisations, fresh = factorisations + 1, True
            previous_size = size
            correction = solve(-model.mass[:, None] * residual)
            trial = potential.search(guess, residual, correction, size < 10 * self.tolerance)
            if trial is None:
                # No descent: a kept factor is redone; a fresh exact one
                # gives way to the clamped until the residual is a quarter
                # of what it is now (where springs buckle, the exact matrix
                # can be indefinite some way from the solution and fine
                # closer to it); a fresh clamped one cannot fail but at
                # rounding level, where the step is given up.
                if fresh and not exact:
                    break
                if fresh:
                    exact_limit = size / 4
                solve = None
                continue
            guess, fresh = trial, False
            residual = potential.residual(guess)
            size = np.abs(residual).max() / dt**2
        raise DivergenceError(
            f"{self.name} did not converge at t = {t:.6g} s: Newton's method left "
            f"{size:.3g} m/s^2 unbalanced after {count} iterations (tolerance "
            f"{self.tolerance:g} m/s^2); a smaller dt converges in fewer"
        )


class _StepPotential:
    """One step's incremental potential ``Psi`` (see :class:`BackwardEuler`):
    its value, its gradient as a residual, its Hessian factorised, and the
    line search along a Newton direction."""

    def __init__(
        self, model: Model, x, v, dt: float, inv_mass, pattern: BlockPattern, penalties=()
    ):
        table = model.spring_table()
        self.penalties = list(penalties)  # ObstaclePenalty, LayerPenalty
        self.model, self.x, self.dt, self.inv_mass, self.pattern = model, x, dt, inv_mass, pattern
        self.a, self.b = table.a, table.b
        self.drift = x + dt * v  # (N, 3) m
        self.rate = model.air_rate  # 1/s
        # Spring and dashpot as one spring (see the class docstring).
        start = np.linalg.norm(x[table.b] - x[table.a], axis=1)
        viscous = table.damping / dt
        self.stiffness = table.stiffness + viscous  # (S,) N/m
        self.rest = np.where(
            self.stiffness > 0,
            (table.stiffness * table.rest + viscous * start) / np.maximum(self.stiffness, 1e-300),
            table.rest,
        )  # (S,) m
        # Plate bending: energy x^T Q x / 2 per coordinate (or None).
        self.bending = model.bending_matrix
        self.gravity = np.zeros_like(x)  # (N, 3) N
        model.add_gravity(x, v, self.gravity)
        self.constant = self.gravity.copy()  # gravity, plus the wind at the anchor
        self._anchored_at: np.ndarray | None = None

    def anchor(self, t: np.ndarray) -> bool:
        """Take the wind at ``t``; whether that changed ``Psi`` (never without
        wind, or when ``t`` is the anchor already)."""
        if self._anchored_at is not None and np.array_equal(t, self._anchored_at):
            return False
        constant = self.gravity.copy()
        if not self.model.add_wind(t, (t - self.x) / self.dt, constant):
            return False
        self.constant = constant
        self._anchored_at = t.copy()
        return True

    def change(self, t: np.ndarray, trial: np.ndarray) -> float:
        """``Psi(trial) - Psi(t)`` in joules, from differences (``Psi`` itself
        is large against the last iterations' changes, which its rounding
        would hide)."""
        dt, mass = self.dt, self.model.mass
        move = trial - t
        length_t = np.linalg.norm(t[self.b] - t[self.a], axis=1)
        length_trial = np.linalg.norm(trial[self.b] - trial[self.a], axis=1)
        # |p|^2 - |q|^2 = (p - q) . (p + q), for the gaps and the lengths alike
        sum_gap = trial + t - 2 * self.drift
        sum_moved = trial + t - 2 * self.x
        inertia = 0.5 / dt**2 * float(mass @ np.einsum("ij,ij->i", move, sum_gap))
        air = 0.5 * self.rate / dt * float(mass @ np.einsum("ij,ij->i", move, sum_moved))
        springs = 0.5 * float(
            self.stiffness @ ((length_trial - length_t) * (length_trial + length_t - 2 * self.rest))
        )
        bending = 0.0
        if self.bending is not None:  # x'Qx/2 - t'Qt/2 = (x - t)'Q(x + t)/2, Q symmetric
            bending = 0.5 * float(np.vdot(move, self.bending @ (trial + t)))
        contact = sum(penalty.change(t, trial) for penalty in self.penalties)
        return inertia + air + springs + bending + contact - float(np.vdot(self.constant, move))

    def residual(self, t: np.ndarray) -> np.ndarray:
        """``r(t) = h^2 M^-1 grad Psi`` ``(N, 3)`` in metres, zero at pinned
        points: ``t - x - h v - h^2 M^-1 F(t, (t - x)/h)``."""
        dt, mass = self.dt, self.model.mass
        d = t[self.b] - t[self.a]
        length = np.linalg.norm(d, axis=1)
        pull = self.stiffness * (length - self.rest) / np.maximum(length, TINY_LENGTH)
        on_a = d * pull[:, None]  # (S, 3) N, on end a (and minus it on end b)
        force = self.constant - (self.rate / dt * mass)[:, None] * (t - self.x)
        if self.bending is not None:
            force -= self.bending @ t
        for penalty in self.penalties:
            penalty.add_force(t, force)
        n = t.shape[0]
        for axis in range(3):
            force[:, axis] += np.bincount(self.a, on_a[:, axis], minlength=n)
            force[:, axis] -= np.bincount(self.b, on_a[:, axis], minlength=n)
        moves = (self.inv_mass > 0)[:, None]
        return (t - self.drift - dt * dt * force * self.inv_mass[:, None]) * moves

    def matrix(self, t: np.ndarray, exact: bool, pinned: np.ndarray) -> sp.csr_matrix:
        """Newton's matrix ``M (1 + r h) + h^2 H(t)`` on the free points'
        coordinates (the derivative of ``M r`` at ``t``): ``H`` the springs'
        exact Hessian, or with compressed springs' transverse part clamped
        at zero (positive definite)."""
        dt, mass = self.dt, self.model.mass
        blocks = stiffness_blocks(t[self.b] - t[self.a], self.rest, self.stiffness, exact)
        dfdx = self.pattern.assemble(blocks)
        if self.bending is not None:
            dfdx = dfdx - self.model.bending_hessian()
        for penalty in self.penalties:
            dfdx = dfdx - penalty.hessian(t)
        free = np.repeat(~pinned, 3)
        diagonal = np.repeat(mass * (1.0 + self.rate * dt), 3)
        return (sp.diags(diagonal) - dt * dt * dfdx).tocsr()[free][:, free]

    def factorise(self, t: np.ndarray, exact: bool, pinned: np.ndarray):
        """A solver of :meth:`matrix` ``dx = b``, ``b`` and ``dx`` ``(N, 3)``
        (zero at pinned points): the exact matrix by sparse LU (it may be
        indefinite), the clamped one by Cholesky."""
        matrix = self.matrix(t, exact, pinned)
        if exact:
            try:
                lu = splu(matrix.tocsc())
            except RuntimeError:  # exactly singular: the caller falls back
                return lambda rhs: np.full_like(rhs, np.nan)
            inner = lu.solve
        else:
            matrix.sort_indices()
            factor = CholeskySolverD(
                matrix.shape[0],
                matrix.indptr.astype(np.int32),
                matrix.indices.astype(np.int32),
                matrix.data,
                MatrixType.CSR,
            )

            def inner(rhs):
                result = np.empty_like(rhs)
                factor.solve(rhs, result)
                return result

        def solve(rhs: np.ndarray) -> np.ndarray:
            result = np.zeros_like(rhs)
            result[~pinned] = inner(np.ascontiguousarray(rhs[~pinned]).ravel()).reshape(-1, 3)
            return result

        return solve

    def search(self, guess: np.ndarray, residual: np.ndarray, correction: np.ndarray, near: bool):
        """Backtracking on ``Psi`` along ``correction`` from ``guess``, whose
        residual is ``residual``: the full step, halved until ``Psi`` falls
        by 1e-4 of the predicted fall (Armijo). ``near`` the solution (within
        ten times the tolerance) a fall of ``|r|`` by as much passes too: at
        small steps the last iterations change ``Psi`` by less than its
        rounding (measured: 1.7e-17 J predicted at a 7.5e-5 s step, where
        the full step took the residual from 1e-3 to 2e-8 m/s^2). Anywhere,
        a full step whose promised fall and inertial energy are both within
        :data:`ROUNDING` times the rounding of ``Psi``'s change passes if it
        halves ``|r|`` (``bdf2`` stopped at a landing at 1/30720 s, 12 times
        its tolerance: 6.8e-16 J promised, +5e-16 J of rounding measured,
        the residual cut 20,000-fold by the full step). The accepted point,
        or None when the direction does not descend or no length down to
        1/1024 passes."""
        slope = float(np.vdot(self.model.mass[:, None] * residual, correction)) / self.dt**2
        if not slope < 0:  # also NaN: an exactly singular matrix
            return None
        norm = np.linalg.norm(residual) if near else 0.0
        # Psi's change cannot be told from its rounding when the fall
        # promised is near the rounding of its largest terms: the inertial
        # forces of the moving points (as large as all the others together)
        # times the positions' rounding. There a full step that halves the
        # residual passes, if it is that small in inertial energy too (an
        # exact Hessian can be indefinite: a small slope alone does not
        # bound the step).
        moving = self.model.mass * (self.inv_mass > 0)
        inertia = np.linalg.norm(guess - self.drift, axis=1) @ moving / self.dt**2
        rounding = np.finfo(float).eps * float(np.abs(guess).max()) * float(inertia)
        kinetic = 0.5 * float(moving @ (correction * correction).sum(axis=1)) / self.dt**2
        if max(-slope, kinetic) < ROUNDING * rounding:
            trial = guess + correction
            if np.linalg.norm(self.residual(trial)) <= 0.5 * np.linalg.norm(residual):
                return trial
        alpha = 1.0
        while alpha >= 1 / 1024:
            trial = guess + alpha * correction
            if self.change(guess, trial) <= 1e-4 * alpha * slope:
                return trial
            if near and np.linalg.norm(self.residual(trial)) <= (1 - 1e-4 * alpha) * norm:
                return trial
            alpha /= 2
        return None


#: The line search judges a full Newton step by the residual's fall when the
#: fall of ``Psi`` it promises and its inertial energy are both under this
#: many times the rounding of ``Psi``'s change (:meth:`_StepPotential.search`).
ROUNDING = 1000.0
