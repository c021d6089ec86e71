"""Contact as a penalty in Newton's incremental potential (backward Euler's
and BDF2's, :mod:`~pvcloth.physics.integrators.backward_euler`): the
obstacles (:class:`ObstaclePenalty`) and the cloth's layers against each
other (:class:`LayerPenalty`).

Both use one law along a gap ``g`` (m) per row (:class:`PenaltyLaw`): a
cubic penalty in a thin layer outside the shape the response after the step
keeps, with (for the obstacles) a Hunt and Crossley dashpot taken at the
step's end, so that the force is the gap's derivative of a potential and
Newton sees all of it. The layers' penalty enters only on request
(``[self_collision] in_solve``). The
response after the step (:mod:`~pvcloth.physics.obstacles`,
:mod:`~pvcloth.physics.self_collision`) stays as the fail-safe that
guarantees no point ends inside an obstacle and no layer crosses another.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.obstacles import Contacts

#: ``omega`` (rad/s): the penalty's stiffness per point over its mass is
#: ``omega^2`` at the depth scale. A point arriving at speed ``v`` stops
#: within the layer ``l`` while ``v < omega l / sqrt(1.5)``: 6 m/s for a
#: 1 cm thickness, 3 m/s for 5 mm (at 600 rad/s a cloth dropped 9 cm onto a
#: sphere went through it, and the response after the step, removing the
#: approach, threw an adaptive run's error estimate off at every step
#: length). Fixed, not scaled with the step: a stiffness of ``100 m / h^2``
#: made the model change with the step, and where an adaptive run shortened
#: it, a point left deep by a long step was thrown out by a far stiffer one.
PENALTY_FREQUENCY = 3000.0
#: Where the penalty starts, as a share of the obstacle's thickness: a point
#: at rest under its weight stays outside the grown shape, where the
#: response after the step leaves it alone.
PENALTY_LAYER = 0.25
#: ``beta`` (s/m): the penalty's dashpot as a share of its force per unit
#: speed (Hunt and Crossley 1975); a point leaves the layer at no more than
#: about ``1 / beta`` (3.3 cm/s) while the dashpot holds it. With it, a 6x6
#: cotton landing on the ground at 0.75 m/s at 1/2000 s steps rises again
#: at under 5 % of that, without it at over a fifth
#: (``tests/test_contact_in_step.py``).
PENALTY_DAMPING = 30.0
#: The smallest depth scale (m) of the cubic penalty (see :class:`ObstaclePenalty`).
PENALTY_SCALE = 1e-3
#: Points whose gap at the step's end time is under this many times the
#: step's largest inertial move and fall under gravity (plus the thickness)
#: are watched.
PENALTY_REACH = 4.0


class PenaltyLaw:
    """The penalty's law along one gap ``g`` (m) per row: the cubic penalty
    ``E = k D^3 / (3 l)`` on the depth ``D = max(d - g, 0)`` into a layer
    of ``d`` metres, with ``l = max(d, PENALTY_SCALE)``, and Hunt and
    Crossley's dashpot at the step's end, ``beta k (D^4 / 4 - D_0 D^3 / 3) /
    (l h)`` (``D_0 = d - g_0``, signed; ``beta`` is :data:`PENALTY_DAMPING`).
    :class:`ObstaclePenalty` explains both; the force along the gap is
    ``-dE/dg`` and its curvature ``d^2E/dg^2`` (clamped at zero).

    Parameters
    ----------
    stiffness : numpy.ndarray
        ``k`` per row (N/m), shape (R,).
    layer : float
        ``d`` (m).
    start_gap : numpy.ndarray
        ``g_0`` per row (m), shape (R,): the gap where the solve starts.
    dt : float
        The potential's step ``h`` (s).
    damped : bool
        Whether the dashpot acts.
    """

    def __init__(self, stiffness, layer: float, start_gap, dt: float, damped: bool = True):
        self.stiffness = stiffness  # (R,) N/m
        self.layer = layer  # m
        #: The depth (m) at which the cubic penalty is as stiff as ``k``:
        #: the layer, or a millimetre for a thin one.
        self.scale = max(layer, PENALTY_SCALE)
        self.start_gap = start_gap  # (R,) m
        self.dt = dt
        #: beta k / l per row (kg/(s m^2)), zero without the dashpot.
        self.damping = PENALTY_DAMPING * stiffness / self.scale if damped else 0.0 * stiffness

    def depth(self, gap: np.ndarray) -> np.ndarray:
        """``D = max(d - g, 0)`` (m)."""
        return np.maximum(self.layer - gap, 0.0)

    def change(self, gap_a: np.ndarray, gap_b: np.ndarray) -> float:
        """``E(a) - E(b)`` (J) summed over the rows, from the differences of
        the powers (the terms themselves are large against the last Newton
        iterations' changes)."""
        a, b = self.depth(gap_a), self.depth(gap_b)
        cubes = (a - b) * (a * a + a * b + b * b)
        fourths = (a - b) * (a + b) * (a * a + b * b)
        start = self.layer - self.start_gap  # D_0, signed
        penalty = float(self.stiffness @ cubes) / (3 * self.scale)
        return penalty + float(self.damping @ (fourths / 4 - start * cubes / 3)) / self.dt

    def pushes(self, gap: np.ndarray, rows=slice(None)):
        """The penalty's outward force ``k D^2 / l`` and the dashpot's pull
        ``beta k D^2 (g - g_0) / (l h)`` (N, along the gap) on ``rows`` (all
        by default), from the gaps ``gap`` (m) of those rows."""
        square = self.depth(gap) ** 2
        push = self.stiffness[rows] * square / self.scale
        damped = self.damping[rows] * square * (gap - self.start_gap[rows]) / self.dt
        return push, damped

    def force(self, gap: np.ndarray) -> np.ndarray:
        """``-dE/dg`` (N): the push less the dashpot's pull."""
        push, damped = self.pushes(gap)
        return push - damped

    def curvature(self, gap: np.ndarray) -> np.ndarray:
        """``d^2E/dg^2`` (N/m): ``2 k D / l + beta k D (D - 2 (g - g_0)) /
        (l h)``, the dashpot's part clamped at zero where it is negative (a
        row leaving the layer fast: Newton stays a descent). Clamping the
        sum instead, exact wherever it is positive, let Newton rest the
        towel's layers on the floor from a state settled by the fast solve
        (``bdf2``, 32x32, layers in the solve) where this clamp stops short
        of the tolerance, but ``bdf2`` then found no descent when the 6x6
        cloth of ``benchmarks/contact_in_step.py`` landed on its sphere."""
        depth = self.depth(gap)
        moved = gap - self.start_gap
        damped = self.damping * depth * np.maximum(depth - 2 * moved, 0.0) / self.dt
        return 2 * self.stiffness * depth / self.scale + damped


class ObstaclePenalty:
    """The obstacles inside Newton's solve: a one-sided cubic penalty in
    the step's incremental potential (backward Euler's and BDF2's).

    For a point ``i`` and an obstacle, ``E = k_i D_i^3 / (3 l)`` with the
    depth ``D_i = max(d - g_i, 0)`` into a layer ``d = PENALTY_LAYER T`` over
    the obstacle grown by its thickness ``T`` (``g_i`` the point's gap to it),
    ``l = max(d, PENALTY_SCALE)`` and ``k_i = m_i omega^2`` (``omega`` is
    :data:`PENALTY_FREQUENCY`). Cubic, so that its force ``k D^2 / l`` and
    the force's slope both start from zero: a quadratic penalty's force
    switched on with a kink, which BDF2's error estimate (from the third
    derivative) saw at every step length, and an adaptive run's steps fell
    to a nanosecond where a point first entered the layer. A point at rest
    under its weight sinks ``sqrt(g l) / omega`` (37 um in a 1.25 mm
    layer) into it, outside the grown shape, where the response after the
    step leaves it. The penalty does not depend on the step, so smaller
    steps converge to it, its dashpot's (below) included. Its gradient and
    its Hessian's ``2 k D / l n n^T`` join the potential's (the curvature
    of a sphere's gap, a small term, negative for the penalty, is left out:
    Newton stays a descent method). Friction is not in the potential: the solve reports
    each held point's normal impulse (:meth:`held`) and the response after
    the step applies Coulomb's law with it
    (:meth:`~pvcloth.physics.obstacles.Obstacle._hold`), which on a slope
    sticks below the friction angle and slides at the Coulomb rate.

    The penalty alone is elastic: a point landing in the layer is thrown
    back once the steps are short enough to follow the landing (about
    1/3000 s), so the finer the step, the more the model converged to a
    cloth that bounced and never settled, where at 1/60 s the implicit
    step's own damping had stopped it (``tests/test_contact_in_step.py``
    measures the bounce with and without the dashpot). A dashpot
    in the manner of Hunt and Crossley (1975, "Coefficient of restitution
    interpreted as damping in vibroimpact") takes the landing: its force
    ``-beta k D^2 (g - g_0) / (l h)`` along the normal (``beta`` is
    :data:`PENALTY_DAMPING`), the penalty's force at the step's end depth
    ``D`` times ``beta`` times the point's speed along the normal, ``(g -
    g_0) / h`` (``g_0`` the gap where the solve starts). Taken at the end,
    as every other force of the step, it is the derivative along the gap of
    ``beta k (D^4 / 4 - D_0 D^3 / 3) / (l h)`` (``D_0 = d - g_0``), so it
    joins the potential exactly; its curvature, ``beta k D (D - 2 (g -
    g_0)) / (l h)``, is negative where a point leaves the layer fast and
    is clamped at zero in the Hessian. It vanishes at rest and where a
    point enters the layer, so it keeps the force's smooth start; like
    Hunt and Crossley's, it holds back a point leaving the layer faster
    than ``1 / beta``. An earlier dashpot took its coefficient at the
    step's start, lagged, and capped it at ``m / h``: the model then
    depended on the step, and on a 6x6 cloth dropped onto a sphere ``bdf2``'s
    fixed-step errors wandered between 0.05 and 0.4 mm from 1/240 to
    1/7680 s, where this one's fall 2.9, 2.7 and 3.6 times at the halvings
    below 1/1920 s (``benchmarks/results/contact_convergence_6.md``).

    Parameters
    ----------
    obstacles : list of Obstacle
    rows : list of numpy.ndarray
        Per obstacle, the points watched.
    stiffness : list of numpy.ndarray
        Per obstacle, ``k_i`` of its rows (N/m).
    dt : float
        The potential's step (s).
    end_time : float
        Where the obstacles are met (s).
    mass : numpy.ndarray
        The points' masses (kg), shape (N,).
    start : numpy.ndarray, optional
        The solve's start ``x`` (m, ``(N, 3)``; BDF2's combination of its
        last two states), where the dashpot takes its gaps ``g_0`` (at
        ``end_time - dt``); without it, no dashpot.
    """

    def __init__(self, obstacles, rows, stiffness, dt: float, end_time: float, mass, start=None):
        self.obstacles, self.rows = obstacles, rows
        self.dt, self.end_time, self.mass = dt, end_time, mass
        #: Per obstacle, the law of its rows (:class:`PenaltyLaw`); the
        #: dashpot takes each row's gap at the solve's start (at
        #: ``end_time - dt``), none without ``start``.
        self.laws = []
        for k, obstacle in enumerate(obstacles):
            layer = PENALTY_LAYER * obstacle.thickness
            if start is None or not rows[k].size:
                start_gap, damped = np.zeros(rows[k].size), False
            else:
                start_gap, _ = obstacle.gap(start[rows[k]], end_time - dt)
                damped = True
            self.laws.append(PenaltyLaw(stiffness[k], layer, start_gap, dt, damped))

    @classmethod
    def build(cls, model, control, x, dt: float, guess, end_time: float):
        """The penalty for a solve from ``x`` (m) whose first iterate is
        ``guess``, or None without obstacles."""
        if not model.obstacles:
            return None
        movable = control.movable_index
        move = float(np.sqrt(((guess - x) ** 2).sum(axis=1).max(initial=0.0)))
        fall = one_step_fall(model, dt)
        reach = PENALTY_REACH * (move + fall)
        rows, stiffness = [], []
        for obstacle in model.obstacles:
            gap, _ = obstacle.gap(x[movable], end_time)
            watched = movable[gap < reach + obstacle.thickness]
            rows.append(watched)
            stiffness.append(PENALTY_FREQUENCY**2 * model.mass[watched])
        return cls(model.obstacles, rows, stiffness, dt, end_time, model.mass, x)

    def _gaps(self, k: int, t: np.ndarray):
        """``(gap, normal)`` of obstacle ``k``'s rows at ``t``: each row's
        gap (m) to the grown shape and its outward normal."""
        return self.obstacles[k].gap(t[self.rows[k]], self.end_time)

    def change(self, t: np.ndarray, trial: np.ndarray) -> float:
        """The penalty's and its dashpot's ``E(trial) - E(t)`` (J)."""
        total = 0.0
        for k, law in enumerate(self.laws):
            if self.rows[k].size:
                total += law.change(self._gaps(k, trial)[0], self._gaps(k, t)[0])
        return total

    def add_force(self, t: np.ndarray, force: np.ndarray) -> None:
        """Add the penalty's force at ``t`` (N, outward: ``k D^2 / l``) and
        its dashpot's (``-beta k D^2 (g - g_0) / (l h)`` along the normal)
        into ``force``."""
        for k, law in enumerate(self.laws):
            if self.rows[k].size:
                gap, normal = self._gaps(k, t)
                force[self.rows[k]] += law.force(gap)[:, None] * normal

    def hessian(self, t: np.ndarray) -> sp.csr_matrix:
        """:meth:`PenaltyLaw.curvature` times ``n n^T`` per point pressed,
        ``(3N, 3N)`` (N/m)."""
        size = 3 * self.mass.size
        blocks, cells = [], []
        for k, law in enumerate(self.laws):
            if self.rows[k].size:
                gap, normal = self._gaps(k, t)
                curve = law.curvature(gap)
                pressed = curve > 0.0
                if pressed.any():
                    n = normal[pressed]
                    blocks.append(curve[pressed, None, None] * (n[:, :, None] * n[:, None, :]))
                    cells.append(self.rows[k][pressed])
        if not blocks:
            return sp.csr_matrix((size, size))
        return block_matrix(np.concatenate(cells)[:, None], np.concatenate(blocks), size)

    def held(self, x: np.ndarray, t: float) -> list:
        """The points the penalty pushes on at ``x`` (m), one
        :class:`~pvcloth.physics.obstacles.Contacts` per obstacle with their
        normals, the normal impulse per unit mass the push gave them over
        the step (m/s: ``h k D^2 / (l m)``, with the dashpot's share where
        the point ends inside the grown shape) and the potential's step ``h`` as
        the lever of a change of velocity, for friction after the step.

        The dashpot's force counts only for a point that ends inside the
        grown shape. In the layer, counted, it made each landing's friction,
        applied after the step, a jump in velocity that an adaptive run's
        estimate rejected down to ``solver.min_dt`` (``bdf2`` at 1e-4 m on
        the sphere drop of ``benchmarks/contact_convergence.py`` stopped at
        the landing, where without it the run completes). On a surface of
        no thickness, whose layer is empty, every held point is inside and
        the dashpot bears part of its weight at every step: left out, the
        cloth slid 4 to 6 % too far (``tests/test_contact_in_step.py``)."""
        held = []
        for k, obstacle in enumerate(self.obstacles):
            rows = self.rows[k]
            gap, normal = obstacle.gap(x[rows], t)
            law = self.laws[k]
            pressed = law.depth(gap) > 0.0
            index = rows[pressed]
            push, damped = law.pushes(gap[pressed], pressed)
            # The dashpot's share, where the point ends inside the grown shape
            push = np.where(gap[pressed] < 0.0, np.maximum(push - damped, 0.0), push)
            impulse = self.dt * push / self.mass[index]
            held.append(Contacts(index, normal[pressed], impulse, self.dt))
        return held


class LayerPenalty:
    """The cloth's layers inside Newton's solve: the penalty of
    :class:`PenaltyLaw` on each pair of a point and a triangle of the
    other layer that the step may bring close (with
    ``[self_collision] in_solve = true``; off by default).

    The pairs are the self-collision's (its broad phase and screen,
    :class:`~pvcloth.physics.self_collision.SelfCollision`), listed once a
    step over the path from the step's start to the solve's first iterate,
    grown by the fall under gravity of one step and the penalty's layer.
    Each is fixed at the step's start, as ARCSim's proximity penalties are
    (Narain, Samii and O'Brien 2012, "Adaptive anisotropic remeshing for
    cloth simulation"): the closest points' weights ``w_k`` and the unit
    direction ``n`` from the triangle's closest point to the point. Along
    it the pair's gap is linear in the positions, ``g = sum_k w_k n . x_k -
    T`` (``T`` the thickness the response after the step keeps, a fifth of
    it across a crease), so its gradient ``w_k n`` is exact and its Hessian
    ``curvature (w w^T) (x) (n n^T)`` is positive semi-definite: Newton
    stays a descent method. The layer is ``PENALTY_LAYER`` of the
    thickness over ``T``, the stiffness ``m omega^2`` with ``m = 1 / sum_k
    w_k^2 / m_k`` the pair's effective mass. A layer resting on another is
    held in the penalty's layer, outside the thickness, where the response
    after the step finds nothing to push; it stays as the fail-safe for
    pairs the linearisation misses (a point sliding off its triangle
    within the step) and proves no crossing.

    Friction between the layers is not in the potential (see
    :meth:`held`).

    Unlike the obstacles' penalty it has no dashpot. With one (the
    obstacles', at the step's end), Newton stopped short of its tolerance
    in a towel being folded by ``bdf2``: with the dashpot's curvature
    clamped apart from the penalty's it converged linearly, and with the
    two clamped together it found no descent where the 16x16 towel's
    layers landed. Without it the towel rests to round-off at 16x16: the
    implicit step's own damping takes the landing of one layer on another
    at frame steps.

    Parameters
    ----------
    contact : SelfCollision
        The model's self-collision (its thickness, triangles, broad phase).
    pairs : numpy.ndarray
        ``(kind, first, second)`` rows (``(P, 3)``, int64) of the pairs.
    positions : numpy.ndarray
        The step's start (m, ``(N, 3)``), where each pair is fixed.
    start : numpy.ndarray
        The solve's start ``x`` (m, ``(N, 3)``; BDF2's combination of its
        last two states), where the law takes its start gaps (which only a
        dashpot would use).
    inv_mass : numpy.ndarray
        ``(N,)`` (1/kg), zero for pinned points.
    dt : float
        The potential's step (s).
    """

    def __init__(self, contact, pairs, positions, start, inv_mass, dt: float):
        corners, weights, direction, target, mass = contact.linearise(pairs, positions, inv_mass)
        kept = mass > 0.0
        #: ``(P, 4)``: each pair's point, then its triangle's corners.
        self.corners = corners[kept]
        #: ``(P, 4)``: the closest points' weights, the point's positive.
        self.weights = weights[kept]
        #: ``(P, 4, 3)``: the gradient of each pair's gap at its corners, ``w_k n``.
        self.slope = weights[kept, :, None] * direction[kept, None, :]
        #: ``(P,)`` m: the distance each pair is kept at, ``T`` or a crease's.
        self.target = target[kept]
        #: ``(P, 3)``: each pair's unit normal, from its triangle to its point.
        self.direction = direction[kept]
        #: ``(P,)`` kg: each pair's effective mass, ``1 / sum_k w_k^2 / m_k``.
        self.mass = mass[kept]
        stiffness = PENALTY_FREQUENCY**2 * self.mass
        layer = PENALTY_LAYER * contact.thickness
        self.law = PenaltyLaw(stiffness, layer, self.gaps(start), dt, damped=False)

    @classmethod
    def build(cls, model, control, x, dt: float, guess, positions=None):
        """The penalty for a solve from ``x`` (m) whose first iterate is
        ``guess`` (m), its pairs fixed at ``positions`` (the step's start,
        ``x`` if not given), or None without self-collision."""
        contact = model.self_collision
        if contact is None:
            return None
        positions = x if positions is None else positions
        fall = one_step_fall(model, dt)
        near = PENALTY_LAYER * contact.thickness
        reach = fall + near
        pairs = contact.point_triangle_pairs(positions, guess, reach, contact.thickness + near)
        return cls(contact, pairs, positions, x, control.inv_mass, dt)

    def gaps(self, t: np.ndarray) -> np.ndarray:
        """Each pair's gap (m, ``(P,)``) at ``t``: ``sum_k w_k n . t_k - T``."""
        return np.einsum("pkc,pkc->p", self.slope, t[self.corners]) - self.target

    def change(self, t: np.ndarray, trial: np.ndarray) -> float:
        """The penalty's ``E(trial) - E(t)`` (J)."""
        return self.law.change(self.gaps(trial), self.gaps(t))

    def add_force(self, t: np.ndarray, force: np.ndarray) -> None:
        """Add each pair's force at ``t`` (N), ``-dE/dg w_k n`` on corner
        ``k``, into ``force`` ``(N, 3)``."""
        along = self.law.force(self.gaps(t))
        pressed = along != 0.0
        if not pressed.any():
            return
        share = (along[pressed, None, None] * self.slope[pressed]).reshape(-1, 3)
        corner = self.corners[pressed].ravel()
        n = force.shape[0]
        for axis in range(3):
            force[:, axis] += np.bincount(corner, share[:, axis], minlength=n)

    def hessian(self, t: np.ndarray) -> sp.csr_matrix:
        """``curvature (w w^T) (x) (n n^T)`` per pair pressed, ``(3N, 3N)`` (N/m)."""
        size = 3 * t.shape[0]
        curve = self.law.curvature(self.gaps(t))
        pressed = curve > 0.0
        if not pressed.any():
            return sp.csr_matrix((size, size))
        slope = self.slope[pressed].reshape(-1, 12)  # (P, 12): corner k, axis a
        block = curve[pressed, None, None] * slope[:, :, None] * slope[:, None, :]
        return block_matrix(self.corners[pressed], block, size)

    def held(self, x: np.ndarray) -> HeldPairs:
        """The pairs the penalty pushes on at ``x`` (m), with the normal
        change of relative velocity the push gave each over the step (m/s:
        ``h f / m``, ``f`` the penalty's force, ``m`` the
        pair's effective mass), for friction after the step
        (:func:`~pvcloth.physics.self_collision.response.rub`)."""
        gap = self.gaps(x)
        pressed = np.flatnonzero(self.law.depth(gap) > 0.0)
        push, damped = self.law.pushes(gap[pressed], pressed)
        pushed = self.law.dt * np.maximum(push - damped, 0.0) / self.mass[pressed]
        return HeldPairs(
            self.corners[pressed], self.weights[pressed], self.direction[pressed], pushed,
            self.law.dt,
        )  # fmt: skip


def one_step_fall(model, dt: float) -> float:
    """``g dt^2`` (m; 0 without gravity): how far a point at rest falls in
    one implicit step of ``dt`` (s) under the model's gravity, the
    penalties' reach beyond the solve's first iterate (``dt`` is the
    potential's step: backward Euler's, or two thirds of BDF2's).

    Examples
    --------
    >>> import pvcloth
    >>> from pvcloth.physics.integrators.penalties import one_step_fall
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(4, 4))))
    >>> round(one_step_fall(sim.model, 0.1), 6)  # 9.81 m/s^2 times (0.1 s)^2
    0.0981
    """
    gravity = model.gravity
    return dt * dt * float(np.linalg.norm(gravity.acceleration)) if gravity else 0.0


def block_matrix(points: np.ndarray, blocks: np.ndarray, size: int) -> sp.csr_matrix:
    """The ``(size, size)`` sparse sum of dense blocks: block ``b``
    (``blocks[b]``, ``(3K, 3K)``) on the coordinates of its ``K`` points
    ``points[b]`` (``(B, K)`` int), point by point and axis by axis.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.integrators.penalties import block_matrix
    >>> block = np.arange(36.0).reshape(1, 6, 6)  # points 2 and 0, in that order
    >>> matrix = block_matrix(np.array([[2, 0]]), block, 9).toarray()
    >>> float(matrix[6, 0]), float(matrix[0, 6])  # (point 2, x) with (point 0, x), and back
    (3.0, 18.0)
    """
    width = 3 * points.shape[1]
    cell = (3 * points[:, :, None] + np.arange(3)).reshape(-1, width)
    rows = np.repeat(cell[:, :, None], width, axis=2)
    cols = np.repeat(cell[:, None, :], width, axis=1)
    return sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(size, size))


class HeldPairs(NamedTuple):
    """Pairs of layers a solve's penalty held apart over a step."""

    corners: np.ndarray  # (P, 4) the point, then its triangle's corners
    weights: np.ndarray  # (P, 4) closest-point weights, the point's positive
    direction: np.ndarray  # (P, 3) unit normal, from the triangle to the point
    pushed: np.ndarray  # (P,) m/s: the push's normal change of relative velocity
    lever: float  # s: how far a corner moves per unit change of its end velocity
