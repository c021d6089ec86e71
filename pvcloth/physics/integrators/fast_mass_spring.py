"""Liu, Bargteil, O'Brien and Kavan (2013), "Fast Simulation of Mass-Spring
Systems": backward Euler solved by local/global iterations with one
prefactorised matrix."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from cholespy import CholeskySolverD, MatrixType

from pvcloth.physics.contact import ObstacleContact
from pvcloth.physics.integrators.base import Integrator, drift_error, register
from pvcloth.physics.lbfgs import Memory
from pvcloth.physics.state import Control, State
from pvcloth.scene.parts import ACCELERATORS
from pvcloth.scene.validation import choice

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@register
class FastMassSpring(Integrator):
    """Implicit (backward) Euler for the springs by block coordinate descent.

    Backward Euler's step minimises ``|x - y|^2_M / (2 h^2) + E_springs(x)``
    with ``y = x + h v + h^2 M^-1 f_other``. Liu et al. write each spring's
    energy with an auxiliary direction ``d`` of the rest length and alternate:
    *local*, ``d = L (x_i - x_j) / |x_i - x_j|`` for every spring; *global*,
    the linear solve ``(M + h^2 K) x = M y + h^2 J d`` whose matrix (mass
    plus the stiffness-weighted graph Laplacian, the same for x, y and z) is
    constant, so it is factorised once and each iteration costs three
    back-substitutions. Plate bending (:mod:`pvcloth.physics.bending`) is
    quadratic with a constant matrix ``Q``, so it needs no local step: it
    joins the matrix, ``M + h^2 (K + Q)``, and is solved exactly. Every
    plain iteration lowers the step's energy, so the step is stable at any
    size given enough iterations (the Chebyshev acceleration below gives up
    that guarantee: on cotton at 32x32 points and 1/60 s steps, three
    iterations multiplied the energy by 1300 in 10 s, six did not:
    ``python benchmarks/frame_step.py --stability``); a few
    iterations give the look of implicit Euler at a fraction of its cost,
    with more numerical damping when stopped early.

    The iterations are accelerated by Chebyshev's semi-iterative method, as
    Wang (2015, "A Chebyshev Semi-Iterative Approach for Accelerating
    Projective and Position-based Dynamics") does: each new iterate is
    extrapolated from the last two with weights set by an estimate ``rho`` of
    the plain iteration's contraction per iteration. Measured here on cotton
    at 1/60 s steps, the plain iteration contracts by 0.96 per iteration at
    32x32, 64x64 and 128x128 alike; with ``rho = 0.95`` ten iterations leave
    0.70 of the plain iteration's distance from the converged step, and six
    are closer than ten plain ones. An estimate above the true contraction
    would make the iterates oscillate; 0.95 is below it. ``rho = 0`` is the
    plain iteration. Where the plain iteration contracts far faster than
    ``rho`` (a few points, or steps far below a frame), the accelerated one
    still converges only about as fast as ``rho`` says: on two bodies and a
    spring at millisecond steps, ten accelerated iterations leave
    ``fast_bdf2`` farther from its answer than ten plain ones
    (``tests/test_integrators.py`` measures the order at 50). There, take
    ``rho = 0`` or more iterations.

    Spring dashpots are not modelled by the method (only air damping, gravity,
    wind and other non-spring forces, taken explicitly in ``y``); pinned points
    are held by their identity rows in the solve, and the factorisation (a
    sparse Cholesky factor, cholespy) is redone when the set of pinned points
    or a stiffness changes. The local step runs in a compiled loop over the
    spring table (NumPy on the NumPy backend). The last few factorisations
    are kept, one per step length (:data:`KEPT_FACTORS`), so an adaptive run
    that goes back to an earlier step does not factorise again. Each step
    leaves backward Euler's error estimate in :attr:`error`
    (:func:`~pvcloth.physics.integrators.base.drift_error`): it measures the
    time discretisation, not the iterations stopped early.

    With ``accelerator="lbfgs"`` the iterations are L-BFGS steps on the
    step's energy instead (Liu, Bouaziz and Kavan 2017, "Quasi-Newton
    methods for real-time simulation of hyperelastic materials"): the
    global matrix is the first estimate of the Hessian, so the first
    iteration is a plain local/global one, and the last :attr:`memory`
    moves refine it; an Armijo line search makes every iteration lower the
    energy (tested against ``backward_euler``'s own potential), where
    Chebyshev's can climb. That bounds each step, not the run: on a light
    undamped cloth, two or three iterations a step still let its energy
    rise 1.3- to 1.9-fold (``benchmarks/results/frame_step_stability.md``).
    Each iteration costs one solve and one pass over the springs, as a
    plain one does, plus a few vector sums per remembered move. It stops
    early only where the energy, in double precision, no longer shows a
    decrease.

    Parameters
    ----------
    iterations : int
        Local/global iterations per step (Liu et al. use about 10).
    rho : float
        Chebyshev's estimate of the plain iteration's contraction (0 <= rho < 1).
    accelerator : {"chebyshev", "lbfgs"}
        How the iterations are sped up (:data:`~pvcloth.scene.parts.ACCELERATORS`).
    memory : int
        Moves L-BFGS remembers.
    """

    name, order = "fast_mass_spring", 1  # registry key; global order of accuracy
    description = "Liu et al. 2013 local/global backward Euler, prefactorised; damps"
    converges_to = "backward_euler"
    iterative = True
    uses_blas = True  # sparse solves and long dot products
    embedded = True  # backward Euler against the trapezoidal rule (drift_error)
    steady_steps = True  # its factorisation depends on the step

    def __init__(
        self,
        iterations: int = 10,
        rho: float = 0.95,
        accelerator: str = "chebyshev",
        memory: int = 5,
    ):
        if memory < 0:
            raise ValueError(f"memory must be 0 or more moves, got {memory}")
        self.iterations = iterations
        self.rho = rho
        self.accelerator = accelerator
        self.memory = memory
        #: The last step's last move (m), its largest over the points: with
        #: Chebyshev, of the plain update before the extrapolation; with
        #: L-BFGS, of the step taken (0 if none was). How fast the iterations
        #: were still moving when stopped, not a distance from the answer.
        self.residual = 0.0
        self._lbfgs_buffers: tuple[np.ndarray, ...] = ()
        self._factors: dict[tuple, _Factor] = {}
        #: Error estimate of the last step (m): see :func:`drift_error`.
        self.error = 0.0
        #: Factorisations made so far (one per step length, pinned set and stiffness).
        self.factorisations = 0
        self._pull: np.ndarray | None = None  # (N, 3) buffers the iterations reuse
        self._memory: Memory | None = None  # L-BFGS's pairs
        #: Whether the obstacles' contact enters the solve (with Chebyshev;
        #: :mod:`pvcloth.physics.contact`); False leaves it to the response
        #: after the step alone, as the explicit integrators have it (what
        #: ``benchmarks/contact_in_step.py`` compares).
        self.contact_in_step = True
        #: The obstacles' contact inside the solve (None without obstacles,
        #: or before the first step).
        self.contact: ObstacleContact | None = None
        self._contact_start: tuple | None = None  # (x, t0, t1) of the step being solved
        self._error_control = False  # a step controller chooses the steps

    @property
    def accelerator(self) -> str:
        """How the iterations are sped up: one of
        :data:`~pvcloth.scene.parts.ACCELERATORS` (checked when set)."""
        return self._accelerator

    @accelerator.setter
    def accelerator(self, value: str) -> None:
        self._accelerator = choice("accelerator", value, ACCELERATORS)

    def stable_dt(self, model: Model, state: State, control: Control) -> float:
        return float("inf")  # the converged step is backward Euler's: A-stable

    def set_error_control(self, on: bool) -> None:
        """Under error control (``on``) the obstacles' contact stays after
        the step, outside the estimate: an inelastic contact impulse is a
        jump in velocity that no step resolves, so inside the solve the
        estimate rejected every step at the first touch (the 12x12 cloth of
        ``ground.toml``: steps under 1e-9 s at 0.36 s, at every tolerance
        from 0.1 to 0.001 m). Newton's penalty, a smooth force, stays in."""
        self._error_control = on

    def held_contacts(self, x: np.ndarray, t: float) -> list:
        if self._contact_start is None:
            return []
        return self.contact.held(x, t)

    def _begin_contact(self, model: Model, state: State, dt: float) -> None:
        """Ready the obstacles' contact for a step of ``dt`` from ``state``:
        none without obstacles, with L-BFGS (whose line search knows only
        the energy), with self-collision (resolved after the step) or under
        error control (:meth:`set_error_control`); the response after the
        step handles their contact."""
        self._contact_start = None
        if not (model.obstacles and self.contact_in_step and self.accelerator == "chebyshev"):
            return
        if self._error_control:  # see set_error_control
            return
        if model.self_collision is not None:
            # Self-contact is resolved after the step: a floor's impulse in the
            # solve would bear only the lowest layer's weight while the layers
            # above drag it (a folded towel on a 14 degree slope crept 1.1 cm
            # a second, held to 0.05 cm with the floor after the step).
            return
        n = model.n_points
        if self.contact is None or self.contact.normal.shape != (len(model.obstacles), n):
            self.contact = ObstacleContact(model.obstacles, n, model.compiled)
        self._contact_start = (state.x, state.t, state.t + dt)

    # -- the constant parts ------------------------------------------------------

    def _prepare(self, model: Model, control: Control, h: float, air: float) -> _Factor:
        # Rebuilt when the step, a spring constant (model.revision) or the
        # pinned set (control.revision) changed: revisions are never reused,
        # by another model or control either, so no array is compared.
        key = (h, air, model.revision, control.revision)
        factor = self._factors.pop(key, None)
        if factor is None:
            factor = _factorise(model, control, h, air)
            self.factorisations += 1
        self._factors[key] = factor  # the most recently used last
        while len(self._factors) > KEPT_FACTORS:
            del self._factors[next(iter(self._factors))]
        n = model.n_points
        if self._pull is None or self._pull.shape[0] != n:
            self._pull = np.empty((n, 3))
            self._rhs = np.empty((n, 3))
            self._iterates = (np.empty((n, 3)), np.empty((n, 3)))
            self._plain = np.empty((n, 3))  # the solve's iterate before Chebyshev's
        return factor

    # -- a step ---------------------------------------------------------------------

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        x, v = state.x, state.v
        self._begin_contact(model, state, dt)
        other = np.zeros_like(x)
        model.add_other_forces(x, v, other)
        end = self.solve(model, control, x, v, dt, other, x + dt * v)
        v_new = (end - x) / dt
        self.error = drift_error(dt, v, v_new)
        return State(end, v_new, state.t + dt)

    def solve(
        self,
        model: Model,
        control: Control,
        x: np.ndarray,
        v: np.ndarray,
        h: float,
        load: np.ndarray,
        targets: np.ndarray,
        air: float = 0.0,
    ) -> np.ndarray:
        """End positions ``x'`` (m, ``(N, 3)``) of ``x' = x + h v'`` and
        ``v' = v + h M^-1 (F_springs(x') + load - air M v')`` by
        :attr:`iterations` local/global iterations.

        ``load`` (N, ``(N, 3)``) holds the forces taken explicitly (all but
        the springs' and the plate's for backward Euler); ``air`` (1/s) is
        an air damping taken implicitly, in the matrix (``0``: none, or in
        ``load``). Pinned points end at ``targets`` (m, ``(N, 3)``; the
        pinned rows are read). Backward Euler's step passes its start and
        its step; BDF2 (:class:`~pvcloth.physics.integrators.fast_bdf2.FastBDF2`)
        its combinations of the last two states and two thirds of its step.
        The result may be a buffer of this integrator's: copy it before the
        next call."""
        factor = self._prepare(model, control, h, air)
        # The global step's right-hand side: M (1 + air h) x + h M v + h^2 load
        y = x + h * v + h * h * load * control.inv_mass[:, None]
        fixed = factor.fixed
        pinned_next = targets[fixed]
        base = model.mass[:, None] * y
        if air:
            base += (air * h) * model.mass[:, None] * x
        base -= factor.coupling @ pinned_next
        base[fixed] = pinned_next
        guess = y
        guess[fixed] = pinned_next
        self._contact_load = None
        if self._contact_start is not None:
            start, t0, t1 = self._contact_start
            self._contact_load = self.contact.begin(
                start, guess, control.movable_index, model.mass, t0, t1
            )
        if self.accelerator == "lbfgs":
            guess = self._lbfgs(model, factor, base, guess)
        else:
            guess = self._chebyshev(model, factor, base, guess)

        if guess is not y:
            y[...] = guess  # the result lives in the step's own array
            guess = y
        return guess

    def _chebyshev(self, model: Model, factor: _Factor, base: np.ndarray, guess: np.ndarray):
        """:attr:`iterations` local/global iterations from ``guess``,
        accelerated by Chebyshev's method (plain with ``rho = 0``)."""
        fixed, pinned_next = factor.fixed, base[factor.fixed]
        pull, rhs = self._pull, self._rhs
        previous, new = self._iterates
        rho2, omega = self.rho**2, 1.0
        contact = self._contact_load
        plain = self._plain if contact is not None else None
        restarted = 0  # the iteration Chebyshev's recurrence starts from
        self.residual = 0.0
        for k in range(self.iterations):
            # local: every spring at its rest length along its current
            # direction (h^2 k L u, summed at its ends); global: one solve,
            # the pinned rows reset to their targets.
            model.spring_projection(guess, factor.weight, pull)
            np.add(base, pull, out=rhs)
            if contact is not None:  # the obstacles' impulses (kg m)
                rhs += contact
            rhs[fixed] = pinned_next
            factor.solver.solve(rhs, new)
            if k == self.iterations - 1:  # the plain iteration's last move
                self.residual = float(np.sqrt(((new - guess) ** 2).sum(axis=1).max()))
            # Chebyshev: x_k+1 = omega (x^_k+1 - x_k-1) + x_k-1, omega from
            # the recurrence of Chebyshev polynomials (omega = 1 at first).
            # Pinned rows stay exact: omega (p - p) + p = p.
            if contact is not None:
                plain[...] = new
            if k > restarted and rho2 > 0:
                omega = 2 / (2 - rho2) if k == restarted + 1 else 4 / (4 - rho2 * omega)
                new -= previous
                new *= omega
                new += previous
            if contact is not None:  # each point's contact solved alone
                touching = self.contact.touching
                contact = self.contact.project(new, plain)
                if self.contact.touching != touching:
                    # Chebyshev's weights are for one linear iteration: a change
                    # of the points in contact starts its recurrence again.
                    restarted, omega = k + 1, 1.0
            previous[...] = guess
            guess, new = new, guess
        return guess

    def _lbfgs(self, model: Model, factor: _Factor, base: np.ndarray, guess: np.ndarray):
        """:attr:`iterations` quasi-Newton iterations from ``guess``: L-BFGS
        on the step's energy with the global matrix as its first Hessian
        (Liu, Bouaziz and Kavan 2017), an Armijo line search keeping every
        iteration downhill.

        Times ``h^2``, the step's energy is ``E(x) = x.A x / 2 - b.x -
        sum(w L |x_a - x_b|)`` (``A`` the global matrix, ``b`` = ``base``,
        ``w = h^2 k`` per spring of rest length ``L``), and its gradient
        ``A x - b - p(x)`` with ``p`` the local step's pull. With nothing
        remembered the direction ``A^-1 (b + p(x)) - x`` is one plain
        local/global iteration; the last :attr:`memory` moves and gradient
        changes bend it towards Newton's (:class:`~pvcloth.physics.lbfgs.Memory`).
        Each iteration costs one solve and one pass over the springs, as a
        plain iteration does, and a few vector sums per remembered move:
        ``A x`` is carried along (``A`` times each move is known from the
        solve), not multiplied out."""
        fixed, solver = factor.fixed, factor.solver
        n = guess.shape[0]
        if self._memory is None or (self._memory.size, self._memory.moves.shape[1]) != (
            self.memory,
            3 * n,
        ):
            self._memory = Memory(self.memory, n)
            self._lbfgs_buffers = tuple(np.empty((n, 3)) for _ in range(6))
        memory = self._memory
        memory.clear()
        trial, product, trial_product, gradient, trial_gradient, direction = self._lbfgs_buffers
        direction_product = self._iterates[0]
        x = guess
        np.copyto(product, (factor.matrix @ x))  # A x, carried along from here
        pull, trial_pull = self._pull, self._rhs  # p(x) and p(trial)
        stretched = self._gradient(model, factor, base, x, product, pull, gradient)
        alpha = 0.0
        for _ in range(self.iterations):
            memory.direction(
                gradient, solver.solve, fixed, direction, direction_product, model.compiled
            )
            slope = np.vdot(gradient, direction)
            if not slope < 0.0:  # no way down left: converged to round-off
                alpha = 0.0
                break
            # Armijo backtracking from the full step, which is almost always
            # taken. The energy's change is summed from differences (the
            # quadratic part exactly: A d is known), as its value would
            # round away the last iterations' changes.
            linear = slope + np.vdot(direction, pull)  # d.(A x - b) on the free rows
            curving = np.vdot(direction, direction_product)  # d.A d
            alpha = 1.0
            for _ in range(ARMIJO_TRIALS):
                np.multiply(direction, alpha, out=trial)
                trial += x
                np.multiply(direction_product, alpha, out=trial_product)
                trial_product += product
                trial_stretched = self._gradient(
                    model, factor, base, trial, trial_product, trial_pull, trial_gradient
                )
                change = alpha * linear + 0.5 * alpha**2 * curving
                change -= trial_stretched - stretched
                if change <= ARMIJO * alpha * slope:
                    break
                alpha *= 0.5
            else:  # no decrease found: start the memory again, or stop
                alpha = 0.0
                if not memory.slots:
                    break
                memory.clear()
                continue
            memory.remember(x, trial, gradient, trial_gradient, product, trial_product)
            x, trial = trial, x
            product, trial_product = trial_product, product
            gradient, trial_gradient = trial_gradient, gradient
            pull, trial_pull = trial_pull, pull
            stretched = trial_stretched
        # The last move's largest: direction holds its direction, unless no
        # move was made (alpha 0; with no iteration, not even written).
        self.residual = alpha * float(np.sqrt((direction**2).sum(axis=1).max())) if alpha else 0.0
        if x is not guess:
            guess[...] = x
        return guess

    def _gradient(
        self,
        model: Model,
        factor: _Factor,
        base: np.ndarray,
        x: np.ndarray,
        product: np.ndarray,
        pull: np.ndarray,
        out: np.ndarray,
    ) -> float:
        """The gradient of the step's energy times ``h^2`` at ``x`` (see
        :meth:`_lbfgs`), given ``product = A x``, into ``out`` ``(N, 3)``
        (zero on pinned rows); the local step's pull into ``pull``. Returns
        ``sum(w L |x_a - x_b|)``."""
        stretched = model.spring_projection(x, factor.weight, pull)
        np.subtract(product, base, out=out)
        out -= pull
        out[factor.fixed] = 0.0
        return stretched


#: Factorisations :class:`FastMassSpring` keeps (the most recently used).
KEPT_FACTORS = 4
#: Armijo's sufficient decrease: a trial step is taken when it lowers the
#: energy by at least this fraction of what the slope promises.
ARMIJO = 1e-4
#: Step lengths (1, 1/2, 1/4 ...) the L-BFGS line search tries before it
#: starts its history again (or, with none, stops: converged to round-off).
ARMIJO_TRIALS = 8


@dataclass
class _Factor:
    """What one step length's global solve needs."""

    solver: CholeskySolverD  # of the system matrix, pinned rows as identity
    fixed: np.ndarray  # (P,) indices of the pinned points
    coupling: sp.csr_matrix  # (N, P) free rows' coupling to the pinned points
    weight: np.ndarray  # (S,) h^2 k per spring
    matrix: sp.csr_matrix  # (N, N) the factorised matrix (L-BFGS's products)


def _factorise(model: Model, control: Control, dt: float, air: float = 0.0) -> _Factor:
    """The global step's matrix ``M (1 + air dt) + dt^2 (G^T K G + Q)`` for
    this step, factorised (``Q`` the plate bending's, when the model has it;
    ``air`` the rate, 1/s, of an air damping taken implicitly)."""
    springs = model.spring_table()
    n = model.n_points
    # Incidence: row s of G is e_a - e_b for spring s.
    s = np.arange(springs.count)
    incidence = sp.csr_matrix(
        (np.r_[np.ones(s.size), -np.ones(s.size)], (np.r_[s, s], np.r_[springs.a, springs.b])),
        shape=(s.size, n),
    )
    laplacian = (incidence.T @ sp.diags(springs.stiffness) @ incidence).tocsr()  # G^T K G
    if model.bending_matrix is not None:  # energy x^T Q x / 2: the solve takes it whole
        laplacian = laplacian + model.bending_matrix
    system = (sp.diags(model.mass * (1.0 + air * dt)) + dt * dt * laplacian).tocsr()
    # Pinned points stay in the system as identity rows and columns, so
    # that every array has all N points and no iteration gathers or
    # scatters the free ones: x_p = target there, and the coupling
    # S_fp x_p moves to the right-hand side of the free rows.
    free = (~control.pinned).astype(float)
    fixed = np.flatnonzero(control.pinned)
    coupling = (sp.diags(free) @ system[:, fixed]).tocsr()
    matrix = (
        sp.diags(free) @ system @ sp.diags(free) + sp.diags(control.pinned.astype(float))
    ).tocsr()
    matrix.sort_indices()
    # A sparse Cholesky factor (CHOLMOD inside cholespy): the matrix is
    # symmetric positive definite; its solves cost a third of SuperLU's
    # here (64x64: 0.29 against 0.89 ms for three right-hand sides).
    solver = CholeskySolverD(
        n,
        matrix.indptr.astype(np.int32),
        matrix.indices.astype(np.int32),
        matrix.data,
        MatrixType.CSR,
    )
    return _Factor(solver, fixed, coupling, dt * dt * springs.stiffness, matrix)
