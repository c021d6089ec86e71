"""Contact with obstacles inside a local/global solve (the Newton
integrators' counterpart is a penalty in their potential:
:class:`~pvcloth.physics.integrators.penalties.ObstaclePenalty`).

``fast_mass_spring`` and ``fast_bdf2`` solve their step by iterations on
one factorised matrix ``A`` (:mod:`~pvcloth.physics.integrators.fast_mass_spring`).
Resolved after the step only, contact is invisible to those iterations: a
cloth lying on the ground falls ``g h^2`` into it every step and is pushed
back, its springs solved as if nothing held it, and it never rests. Here
the obstacles' contact impulses join the solve as Ly, Jouve and
Bertails-Descoubes (2020, "Projective Dynamics with dry frictional
contact", ACM TOG 39(4)) put them: on the right-hand side, the matrix
unchanged.

Each point ``i`` near an obstacle carries a contact impulse ``r_i = h^2 f_i``
(kg m, the global step's units): a normal part ``lambda_i n_i``
(``lambda_i >= 0``) and a friction part ``tau_i`` in the tangent plane.
After each global solve every such point's contact is solved alone, the
point standing for itself with its mass ``m_i`` (a projected Jacobi step):

- normal (Signorini): ``lambda_i <- max(0, lambda_i - m_i g_i)`` with
  ``g_i`` the point's gap to the obstacle grown by its thickness (negative
  inside); a point still inside is put on the surface;
- friction (Coulomb): ``tau_i <- tau_i - m_i u_i``, ``u_i`` the point's
  tangential move relative to the obstacle over the step; kept if
  ``|tau_i| <= static_friction * lambda_i`` (the point sticks), else
  scaled to ``friction * lambda_i`` (it slides), the point moved by the
  change over ``m_i``. On a slope of angle ``theta`` this sticks exactly
  when ``tan(theta) <= static_friction`` and slides at ``g (sin(theta) -
  friction cos(theta))``, as the response after the step does.

The next global solve takes the impulses on its right-hand side, so the
springs see what holds the cloth. The mass is the exact compliance for a
sheet moving as one (a cloth lying on the ground: its weight is found in
one iteration) and too small for one point alone (which then takes several
iterations to be held, and the response after the step is the fail-safe).
Tried and dropped on the way (on 32x32 and 64x64 cotton at 1/60 s steps):
``A``'s diagonal in place of the mass, which overshoots a sheet by
``A_ii / m_i`` and diverged; impulses updated once a step instead of every
iteration, which lags them and diverged; and impulses kept from one step to
the next, which left a cloth on a sphere sliding (0.02 J at 16x16 where
starting each step from none settled to 5e-4 J).

Chebyshev's extrapolation (``fast_mass_spring``'s default) is made for one
linear iteration: the impulses are taken from the solve's own answer, the
touching points are not extrapolated, and its recurrence starts again
whenever the number of points in contact changes; without that, 30 iterations threw a
cloth off a sphere. L-BFGS, whose line search knows only the energy, keeps
the response after the step, and so does a scene with self-collision (its
layers meet after the step, so a floor's impulse inside the solve would bear
only the lowest layer's weight while the layers above drag it), and so does
a run under error control
(:meth:`~pvcloth.physics.integrators.fast_mass_spring.FastMassSpring.set_error_control`).

Only points within reach of an obstacle take part: those whose gap (to the
obstacle at the start or the end of the step) is below :data:`REACH` times
the largest move of the step's inertial guess (which holds gravity's),
plus the obstacle's thickness. The response after the
step (:class:`~pvcloth.physics.pipeline.ObstacleContacts`) stays, as the
fail-safe that guarantees no point ends a step inside.
"""

from __future__ import annotations

import math

import numpy as np

from pvcloth.physics.kernels import FASTMATH, warm
from pvcloth.physics.obstacles import Box, Contacts, Ground, Sphere

try:  # numba is a dependency, but the NumPy path must work without it
    from numba import njit
except ImportError:  # pragma: no cover - exercised only where numba is missing
    njit = None

#: Points whose gap at the step's start is under this many times the
#: largest inertial move of the step (plus the thickness) take part.
REACH = 4.0
#: The shapes the compiled kernel knows, by number.
SPHERE, GROUND, BOX = 0, 1, 2


class ObstacleContact:
    """The contact impulses of one cloth against its obstacles during one
    solve (see the module's description).

    Parameters
    ----------
    obstacles : list of Obstacle
        The model's obstacles (:mod:`pvcloth.physics.obstacles`).
    n : int
        Points of the cloth.
    compiled : bool
        Whether the projection runs compiled (numba; the model's springs
        do) or in NumPy (the same arithmetic, tested).

    Attributes
    ----------
    normal : numpy.ndarray
        ``lambda``, shape ``(O, N)``, kg m: each obstacle's normal impulse
        on each point times the step (``h^2`` times the force, the global
        step's units).
    friction : numpy.ndarray
        ``tau``, shape ``(O, N, 3)``, kg m: the friction impulses likewise.
    load : numpy.ndarray
        Shape ``(N, 3)``, kg m: the sum the global step adds to its
        right-hand side.
    """

    def __init__(self, obstacles, n: int, compiled: bool = False):
        self.obstacles = list(obstacles)
        self.normal = np.zeros((len(self.obstacles), n))
        self.friction = np.zeros((len(self.obstacles), n, 3))
        self.load = np.zeros((n, 3))
        self.compiled = compiled and njit is not None
        self._rows: list[np.ndarray] = []

    def begin(
        self,
        start: np.ndarray,
        guess: np.ndarray,
        movable: np.ndarray,
        mass: np.ndarray,
        t0: float,
        t1: float,
    ) -> np.ndarray:
        """Prepare a solve from ``start`` (m, ``(N, 3)``,
        the positions at ``t0``) to ``t1``; ``guess`` (m) is the solve's
        first iterate, ``movable`` the free points' indices and ``mass``
        (kg, ``(N,)``) the points' masses. Returns :attr:`load` for the
        first right-hand side: zero, the impulses starting from none."""
        self.normal[:] = 0.0
        self.friction[:] = 0.0
        self.load[:] = 0.0
        self._start, self._mass = start, mass
        reach = REACH * float(np.sqrt(((guess - start) ** 2).sum(axis=1).max(initial=0.0)))
        self._rows, self._shapes = [], []
        for obstacle in self.obstacles:
            # At both ends of the step: a moving obstacle comes to the cloth.
            gap = np.minimum(
                obstacle.gap(start[movable], t0)[0], obstacle.gap(start[movable], t1)[0]
            )
            self._rows.append(movable[gap < reach + obstacle.thickness])
            self._shapes.append(_shape(obstacle, t0, t1))
        return self.load

    def project(self, iterate: np.ndarray, plain: np.ndarray | None = None) -> np.ndarray:
        """One projected Jacobi step on ``iterate`` (m, ``(N, 3)``, changed
        in place): the impulses updated, the points still inside put on the
        surface, the sticking ones held. Returns the new :attr:`load`.

        ``plain`` (m, ``(N, 3)``) is the global solve's own answer when
        ``iterate`` was extrapolated from it (Chebyshev): the impulses are
        taken from it and the touching points start from it, since an
        extrapolation past the surface, fed back through the impulses, grew
        without bound (cotton on a sphere at 1/60 s)."""
        kernel = warm(_project_compiled) if self.compiled else _project_numpy
        self.load[:] = 0.0
        for k, obstacle in enumerate(self.obstacles):
            rows = self._rows[k]
            if rows.size == 0:
                continue
            kind, center, axes, size, move = self._shapes[k]
            kernel(
                rows,
                iterate,
                iterate if plain is None else plain,
                plain is not None,
                self._start,
                self._mass,
                self.normal[k],
                self.friction[k],
                kind,
                center,
                axes,
                size,
                move,
                obstacle.static_friction,
                obstacle.friction,
                self.load,
            )
        return self.load

    def held(self, x: np.ndarray, t: float) -> list[Contacts]:
        """The points an obstacle pushes on (a normal impulse above zero), one
        :class:`~pvcloth.physics.obstacles.Contacts` per obstacle, their
        normals at positions ``x`` (m) and time ``t`` (s): self-collision
        then does not push them into it."""
        held = []
        for k, obstacle in enumerate(self.obstacles):
            index = np.flatnonzero(self.normal[k] > 0.0)
            held.append(Contacts(index, obstacle.gap(x[index], t)[1]))
        return held

    @property
    def touching(self) -> int:
        """Points some obstacle pushes on now."""
        return int((self.normal > 0.0).any(axis=0).sum())


def _shape(obstacle, t0: float, t1: float):
    """``(kind, centre, axes, size, move)`` of ``obstacle`` at the step's
    end for the kernels: the grown radius (sphere), the thickness (ground) or
    the grown half sizes (box) as ``size``; ``move`` (m) its centre's move over
    the step."""
    center = obstacle.center_at(t1)
    move = center - obstacle.center_at(t0)
    axes = np.ascontiguousarray(obstacle.axes, dtype=float)
    if isinstance(obstacle, Sphere):
        return SPHERE, center, axes, np.full(3, obstacle.grown), move
    if isinstance(obstacle, Ground):
        return GROUND, center, axes, np.full(3, obstacle.thickness), move
    if isinstance(obstacle, Box):
        return BOX, center, axes, np.asarray(obstacle.half, dtype=float), move
    raise TypeError(f"no contact inside the step for {type(obstacle).__name__}")


def _gap_numpy(points, kind, center, axes, size):
    """Gap (m, ``(k,)``) and outward normal (``(k, 3)``) of world ``points``
    to the grown shape: :meth:`Obstacle.gap` from the kernels' description."""
    q = (points - center) @ axes
    if kind == SPHERE:
        length = np.linalg.norm(q, axis=1)
        normal = np.where(
            length[:, None] > 0.0, q / np.maximum(length, 1e-300)[:, None], [0, 0, 1.0]
        )
        gap = length - size[0]
    elif kind == GROUND:
        normal = np.zeros_like(q)
        normal[:, 2] = 1.0
        gap = q[:, 2] - size[0]
    else:
        beyond = q - np.clip(q, -size, size)
        length = np.linalg.norm(beyond, axis=1)
        depth = size - np.abs(q)
        rows = np.arange(q.shape[0])
        axis = np.argmin(depth, axis=1)
        face = np.zeros_like(q)
        face[rows, axis] = np.where(q[rows, axis] < 0.0, -1.0, 1.0)
        outside = length > 0.0
        normal = np.where(outside[:, None], beyond / np.where(outside, length, 1.0)[:, None], face)
        gap = np.where(outside, length, -depth[rows, axis])
    return gap, normal @ axes.T


def _project_numpy(
    rows,
    iterate,
    source,
    reset,
    start,
    mass,
    normal,
    friction,
    kind,
    center,
    axes,
    size,
    move,
    static_friction,
    kinetic_friction,
    load,
):
    """The projection of :meth:`ObstacleContact.project` for one obstacle,
    in NumPy (the compiled kernel's twin)."""
    m = mass[rows, None]
    # Normal (Signorini), from the solve's own answer: push out, let go when pulled.
    gap, _ = _gap_numpy(source[rows], kind, center, axes, size)
    new = np.maximum(normal[rows] - m[:, 0] * gap, 0.0)
    normal[rows] = new
    if reset:  # the touching points not extrapolated
        touching = rows[(new > 0.0) | (gap < 0.0)]
        iterate[touching] = source[touching]
    # Every point left inside put on the surface.
    gap, direction = _gap_numpy(iterate[rows], kind, center, axes, size)
    iterate[rows] += np.maximum(-gap, 0.0)[:, None] * direction
    # Friction (Coulomb) against the tangential move relative to the obstacle.
    slip = iterate[rows] - start[rows] - move
    slip -= np.einsum("ij,ij->i", slip, direction)[:, None] * direction
    old = friction[rows]
    old -= np.einsum("ij,ij->i", old, direction)[:, None] * direction
    tau = old - m * slip
    length = np.linalg.norm(tau, axis=1)
    sticks = length <= static_friction * new
    with np.errstate(divide="ignore", invalid="ignore"):
        slide = np.where(length > 0.0, kinetic_friction * new / length, 0.0)
    tau *= np.where(sticks, 1.0, slide)[:, None]
    iterate[rows] += (tau - old) / m
    friction[rows] = tau
    load[rows] += new[:, None] * direction + tau


if njit is not None:

    @njit(fastmath=FASTMATH, cache=True, nogil=True, inline="always")
    def _gap_point(p, i, kind, center, axes, size, out, j):
        """Gap (m) of world point ``p[i]`` to the grown shape; its outward
        normal into row ``j`` of ``out`` (``(k, 3)``), world frame. Scalars
        and conditional expressions only: the builtins ``min``, ``max`` and
        ``abs`` and tuple assignments in the box's branch made it three
        times slower."""
        d0 = p[i, 0] - center[0]
        d1 = p[i, 1] - center[1]
        d2 = p[i, 2] - center[2]
        q0 = d0 * axes[0, 0] + d1 * axes[1, 0] + d2 * axes[2, 0]
        q1 = d0 * axes[0, 1] + d1 * axes[1, 1] + d2 * axes[2, 1]
        q2 = d0 * axes[0, 2] + d1 * axes[1, 2] + d2 * axes[2, 2]
        n0 = 0.0
        n1 = 0.0
        n2 = 0.0
        if kind == 0:  # sphere
            length = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
            if length > 0.0:
                n0 = q0 / length
                n1 = q1 / length
                n2 = q2 / length
            else:
                n2 = 1.0
            gap = length - size[0]
        elif kind == 1:  # ground
            n2 = 1.0
            gap = q2 - size[0]
        else:  # box
            s0 = size[0]
            s1 = size[1]
            s2 = size[2]
            b0 = q0 - s0 if q0 > s0 else (q0 + s0 if q0 < -s0 else 0.0)
            b1 = q1 - s1 if q1 > s1 else (q1 + s1 if q1 < -s1 else 0.0)
            b2 = q2 - s2 if q2 > s2 else (q2 + s2 if q2 < -s2 else 0.0)
            outside = b0 * b0 + b1 * b1 + b2 * b2
            if outside > 0.0:
                length = math.sqrt(outside)
                n0 = b0 / length
                n1 = b1 / length
                n2 = b2 / length
                gap = length
            else:
                e0 = s0 - math.fabs(q0)
                e1 = s1 - math.fabs(q1)
                e2 = s2 - math.fabs(q2)
                if e0 <= e1 and e0 <= e2:
                    n0 = -1.0 if q0 < 0.0 else 1.0
                    gap = -e0
                elif e1 <= e2:
                    n1 = -1.0 if q1 < 0.0 else 1.0
                    gap = -e1
                else:
                    n2 = -1.0 if q2 < 0.0 else 1.0
                    gap = -e2
        for a in range(3):
            out[j, a] = axes[a, 0] * n0 + axes[a, 1] * n1 + axes[a, 2] * n2
        return gap

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _gaps_compiled(rows, p, kind, center, axes, size, gap, direction):
        """Gaps (m, into ``gap``, ``(k,)``) and outward normals (into
        ``direction``, ``(k, 3)``) of the points ``p[rows]``. One loop per
        shape, its kind a constant in each: with the kind tested inside the
        loop, a point cost four to eight times as much (measured at 4096
        points on the ground)."""
        if kind == SPHERE:
            for j in range(rows.size):
                gap[j] = _gap_point(p, rows[j], SPHERE, center, axes, size, direction, j)
        elif kind == GROUND:
            for j in range(rows.size):
                gap[j] = _gap_point(p, rows[j], GROUND, center, axes, size, direction, j)
        else:
            for j in range(rows.size):
                gap[j] = _gap_point(p, rows[j], BOX, center, axes, size, direction, j)

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _project_compiled(
        rows,
        iterate,
        source,
        reset,
        start,
        mass,
        normal,
        friction,
        kind,
        center,
        axes,
        size,
        move,
        static_friction,
        kinetic_friction,
        load,
    ):
        gap = np.empty(rows.size)
        direction = np.empty((rows.size, 3))
        tau = np.empty(3)
        # Normal (Signorini), from the solve's own answer.
        _gaps_compiled(rows, source, kind, center, axes, size, gap, direction)
        for j in range(rows.size):
            i = rows[j]
            new = normal[i] - mass[i] * gap[j]
            if new < 0.0:
                new = 0.0
            normal[i] = new
            if reset and (new > 0.0 or gap[j] < 0.0):
                for a in range(3):
                    iterate[i, a] = source[i, a]
        # Points left inside put on the surface; friction (Coulomb).
        _gaps_compiled(rows, iterate, kind, center, axes, size, gap, direction)
        for j in range(rows.size):
            i = rows[j]
            m = mass[i]
            new = normal[i]
            if gap[j] < 0.0:
                for a in range(3):
                    iterate[i, a] -= gap[j] * direction[j, a]
            slip_n = 0.0
            old_n = 0.0
            for a in range(3):
                slip_n += (iterate[i, a] - start[i, a] - move[a]) * direction[j, a]
                old_n += friction[i, a] * direction[j, a]
            length = 0.0
            for a in range(3):
                slip = iterate[i, a] - start[i, a] - move[a] - slip_n * direction[j, a]
                tau[a] = friction[i, a] - old_n * direction[j, a] - m * slip
                length += tau[a] * tau[a]
            length = math.sqrt(length)
            keep = 1.0
            if length > static_friction * new:
                keep = kinetic_friction * new / length if length > 0.0 else 0.0
            for a in range(3):
                old = friction[i, a] - old_n * direction[j, a]
                tau[a] *= keep
                iterate[i, a] += (tau[a] - old) / m
                friction[i, a] = tau[a]
                load[i, a] += new * direction[j, a] + tau[a]

else:  # pragma: no cover - exercised only where numba is missing
    _project_compiled = None
