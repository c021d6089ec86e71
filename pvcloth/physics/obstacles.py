"""Rigid obstacles and the collision response of cloth points against them.

Collisions are resolved after every integrator step, on positions and
velocities, so every integrator gets the same response (as pins do).

How no point ends a step inside an obstacle (no tunnelling)
-------------------------------------------------------------
Each obstacle is convex and is grown by its ``thickness``. For every free
point, the straight path it took during the step, expressed in the obstacle's
own frame (so a moving obstacle is handled by relative motion), is tested
against the grown shape. If the path enters it, the entry point and the outward
normal there define a supporting plane of the grown shape, and the point is
moved onto that plane if it lies behind it. A convex body lies entirely on one
side of any of its supporting planes, so the corrected point is outside the
grown shape: at least ``thickness`` from the real surface. Because the whole
path is tested, not just its end, a fast point cannot skip over a thin box or
through a sphere between two steps. A point that starts a step inside (an
obstacle moved onto it, or the scene started that way) is pushed to the
nearest surface point. The guarantee is per obstacle and for cloth points;
with overlapping obstacles the last one wins, and a coarse cloth's triangles
can still cut a thin box's edge between two points.

Response (Bridson, Fedkiw and Anderson 2002, "Robust treatment of collisions,
contact and friction for cloth animation", section 7.2): the part of the
velocity relative to the obstacle that goes into the surface is removed; that
change ``dv_n`` is the normal impulse per unit mass. Coulomb friction then
stops the tangential relative velocity if it is at most
``static_friction * dv_n`` and otherwise reduces it by ``friction * dv_n``.
On a slope of angle ``theta`` under gravity this sticks exactly when
``tan(theta) <= static_friction`` and slides with acceleration
``g (sin(theta) - friction cos(theta))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from pvcloth.physics import topology

#: Paths shorter than this (m) cannot cross a surface by themselves.
TINY = 1e-15


@dataclass
class Contacts:
    """Points that touched an obstacle in one step (indices into the free points)."""

    index: np.ndarray  # (k,) point indices
    normal: np.ndarray  # (k, 3) outward unit normals, world frame
    #: (k,) m/s: the normal impulse per unit mass an integrator's own solve
    #: gave each point (a penalty's push), for Coulomb friction after the
    #: step; None when the solve applied friction itself, or for the
    #: response's own contacts.
    impulse: np.ndarray | None = None
    #: s: how far a point of the solve moves per unit change of its end
    #: velocity (the step for backward Euler, two thirds of it for BDF2),
    #: so friction's change of velocity moves the point consistently.
    lever: float | None = None


class Obstacle:
    """A rigid convex obstacle, possibly moving along key frames.

    Subclasses describe the shape in the obstacle's own frame, grown by the
    thickness: :meth:`entry` (where a path enters) and :meth:`distance`
    (signed distance to the real surface).
    """

    name = "obstacle"

    def __init__(self, center, rotation, thickness, friction, static_friction, path=()):
        self.center = np.asarray(center, dtype=float)
        #: Columns are the obstacle's axes in world coordinates.
        self.axes = np.asarray(rotation, dtype=float)
        self.thickness = float(thickness)
        self.friction = float(friction)
        self.static_friction = float(static_friction)
        self.path = np.asarray(path, dtype=float).reshape(-1, 4)
        self._world_half = None

    # -- motion ---------------------------------------------------------------

    def center_at(self, t: float) -> np.ndarray:
        """Centre at time ``t`` (linear between key frames, held outside)."""
        if self.path.shape[0] == 0:
            return self.center
        times = self.path[:, 0]
        return np.array([np.interp(t, times, self.path[:, 1 + k]) for k in range(3)])

    def to_local(self, points: np.ndarray, t: float) -> np.ndarray:
        return (points - self.center_at(t)) @ self.axes

    def to_world(self, local: np.ndarray, t: float) -> np.ndarray:
        return local @ self.axes.T + self.center_at(t)

    # -- geometry (own frame) -------------------------------------------------

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners of a box in the own frame that holds the
        grown shape."""
        raise NotImplementedError

    def may_touch(self, low: np.ndarray, high: np.ndarray, t0: float, t1: float) -> bool:
        """Whether anything in the world box ``[low, high]`` can touch the
        grown shape during ``t0 -> t1``: a test of two corners that lets a
        cloth far from the obstacle skip the per-point work."""
        if self._world_half is None:  # world half-extent of the grown shape
            self._world_half = np.abs(self.axes) @ self.bounds()[1]
        half = self._world_half
        if self.path.size:
            c0, c1 = self.center_at(t0), self.center_at(t1)
            top, bottom = np.maximum(c0, c1) + half, np.minimum(c0, c1) - half
        else:
            top, bottom = self.center + half, self.center - half
        return bool((low <= top).all() and (high >= bottom).all())

    def entry(self, q0: np.ndarray, q1: np.ndarray):
        """Where the paths ``q0 -> q1`` (own frame, ``(k, 3)``) first enter
        the grown shape.

        Returns
        -------
        hit : ndarray of bool, shape (k,)
        point : ndarray, shape (k, 3)
            Entry point (nearest surface point for paths starting inside).
        normal : ndarray, shape (k, 3)
            Outward unit normal at the entry point.
        """
        raise NotImplementedError

    def distance(self, points: np.ndarray, t: float = 0.0) -> np.ndarray:
        """Signed distance of world points to the real surface (negative inside)."""
        raise NotImplementedError

    def gap(self, points: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """How far world ``points`` (m, ``(k, 3)``) are outside the grown
        shape at time ``t``: ``(gap, normal)``, the signed distance (m,
        ``(k,)``, negative inside) and the outward unit normal at the
        nearest surface point (``(k, 3)``, world frame). What a contact
        inside the step keeps at zero or above
        (:mod:`pvcloth.physics.contact`)."""
        gap, normal = self._gap_local(self.to_local(points, t))
        return gap, normal @ self.axes.T

    def _gap_local(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    # -- response -------------------------------------------------------------

    def collide(self, x0, x1, v1, free, t0: float, t1: float) -> Contacts:
        """Move points of ``x1`` out of the obstacle and apply the velocity
        response and friction to ``v1``, both in place.

        Parameters
        ----------
        x0, x1 : ndarray, shape (N, 3)
            Positions at the start and end of the step.
        v1 : ndarray, shape (N, 3)
            Velocities at the end of the step.
        free : ndarray of int
            Indices of the points that may be moved (not pinned).
        t0, t1 : float
            Start and end time of the step.
        """
        q0 = self.to_local(x0[free], t0)
        q1 = self.to_local(x1[free], t1)
        low, high = self.bounds()
        # Broad phase: a path whose bounding box misses the shape's cannot hit.
        near = np.all((np.minimum(q0, q1) <= high) & (np.maximum(q0, q1) >= low), axis=1)
        candidates = np.flatnonzero(near)
        if candidates.size == 0:
            return Contacts(np.empty(0, int), np.empty((0, 3)))
        hit, point, normal = self.entry(q0[candidates], q1[candidates])
        rows = candidates[hit]
        point, normal = point[hit], normal[hit]
        q = q1[rows]
        behind = np.einsum("ij,ij->i", q - point, normal)
        q -= np.minimum(behind, 0.0)[:, None] * normal
        index = free[rows]
        normal_world = normal @ self.axes.T
        dt = max(t1 - t0, TINY)
        obstacle_velocity = (self.center_at(t1) - self.center_at(t0)) / dt
        slowed = self._respond(v1, index, normal_world, obstacle_velocity)
        # Friction acted over the whole step: take the tangential distance it
        # took away off the position too (else a stuck point would creep by
        # dt^2 * a per step), staying on the supporting plane.
        x1[index] = self.to_world(q, t1) - dt * slowed
        return Contacts(index, normal_world)

    def _hold(self, x1, v1, held: Contacts, t0: float, t1: float) -> None:
        """Coulomb friction on the points a solve's penalty pushed on, with
        its normal impulse per unit mass. A point that also ends inside the
        grown shape gets friction again in :meth:`collide`, with the approach
        removed there: a second part of its normal impulse, not the same one
        twice (on a slope of no thickness, where the penalty's layer is
        empty, the two together slide at the Coulomb rate; the penalty's
        alone let the cloth slide 1.2 % too far in 0.5 s)."""
        dt = max(t1 - t0, TINY)
        obstacle_velocity = (self.center_at(t1) - self.center_at(t0)) / dt
        slowed = self._respond(v1, held.index, held.normal, obstacle_velocity, held.impulse)
        x1[held.index] -= (dt if held.lever is None else held.lever) * slowed

    def _respond(self, v, index, normal, obstacle_velocity, pushed=None) -> np.ndarray:
        """Remove the approach velocity, apply friction; return the tangential
        velocity that friction removed. ``pushed`` (m/s per point) is a normal
        impulse per unit mass already in the velocities (a solve's penalty):
        friction takes it, and the normal motion is left as the solve made it
        (removing the approach there threw the error estimate of an adaptive
        BDF2 run off at the first touch, at every step length)."""
        relative = v[index] - obstacle_velocity
        if pushed is None:
            approach = np.einsum("ij,ij->i", relative, normal)
            into = approach < 0.0
            dv_n = np.where(into, -approach, 0.0)  # normal impulse per unit mass
            relative += dv_n[:, None] * normal
        else:  # a solve's push, in the velocity already: its normal motion is its own
            dv_n, into = pushed, pushed > 0.0
        tangential = relative - np.einsum("ij,ij->i", relative, normal)[:, None] * normal
        speed = np.linalg.norm(tangential, axis=1)
        sticks = into & (speed <= self.static_friction * dv_n)
        with np.errstate(divide="ignore", invalid="ignore"):
            keep = np.where(sticks, 0.0, np.clip(1.0 - self.friction * dv_n / speed, 0.0, 1.0))
        keep = np.where(into, keep, 1.0)
        slowed = (1.0 - keep)[:, None] * tangential
        v[index] = relative - slowed + obstacle_velocity
        return slowed

    def describe(self) -> str:
        moving = f", moving through {self.path.shape[0]} key frames" if self.path.size else ""
        return (
            f"{self._shape_text()}, thickness {self.thickness:g} m, friction "
            f"{self.friction:g} (static {self.static_friction:g}){moving}"
        )

    def _shape_text(self) -> str:
        raise NotImplementedError

    def surface(self, extent: float) -> tuple[np.ndarray, np.ndarray]:
        """The real surface (not grown by the thickness) as triangles, in the
        obstacle's own frame, for drawing: ``(vertices, triangles)``.

        Parameters
        ----------
        extent : float
            Size in metres to draw an unbounded surface at (the ground's
            side); bounded shapes ignore it.

        Returns
        -------
        vertices : ndarray, shape (V, 3)
            Metres, in the obstacle's frame (:meth:`to_world` places them).
        triangles : ndarray of int, shape (T, 3)
            Vertex indices, counter-clockwise seen from outside.

        A new obstacle shape gives its own; the views draw whatever it gives.
        """
        raise NotImplementedError(f"{type(self).__name__} has no surface(): give it one to draw it")


class Sphere(Obstacle):
    """A sphere of ``radius`` about its centre."""

    name = "sphere"

    def __init__(self, radius, **common):
        super().__init__(rotation=np.eye(3), **common)
        self.radius = float(radius)
        self.grown = self.radius + self.thickness

    def bounds(self):
        return np.full(3, -self.grown), np.full(3, self.grown)

    def entry(self, q0, q1):
        d = q1 - q0
        a = np.einsum("ij,ij->i", d, d)
        b = np.einsum("ij,ij->i", q0, d)
        c = np.einsum("ij,ij->i", q0, q0) - self.grown**2
        inside = c <= 0.0
        # |q0 + s d|^2 = R^2 -> a s^2 + 2 b s + c = 0; the smaller root enters.
        disc = b * b - a * c
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
        crosses = ~inside & (a > TINY) & (disc >= 0.0) & (s >= 0.0) & (s <= 1.0)
        s = np.where(crosses, s, 0.0)
        point = q0 + s[:, None] * d
        length = np.linalg.norm(point, axis=1)
        normal = np.where(
            length[:, None] > TINY, point / np.maximum(length, TINY)[:, None], [0.0, 0.0, 1.0]
        )
        point = self.grown * normal  # on the surface exactly (also for inside starts)
        return inside | crosses, point, normal

    def distance(self, points, t=0.0):
        return np.linalg.norm(points - self.center_at(t), axis=1) - self.radius

    def _gap_local(self, q):
        length = np.linalg.norm(q, axis=1)
        normal = np.where(
            length[:, None] > TINY, q / np.maximum(length, TINY)[:, None], [0.0, 0.0, 1.0]
        )
        return length - self.grown, normal

    def _shape_text(self):
        return "sphere r = {:g} m at ({:g}, {:g}, {:g})".format(self.radius, *self.center)

    def surface(self, extent, rings: int = 32, segments: int = 48):
        """A latitude-longitude sphere; the poles are rings of coincident
        vertices, which draw as points (their triangles have no area)."""
        polar = np.linspace(0.0, np.pi, rings + 1)[:, None]
        azimuth = np.linspace(0.0, 2.0 * np.pi, segments + 1)[None, :]
        unit = np.stack(
            np.broadcast_arrays(
                np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)
            ),
            axis=-1,
        ).reshape(-1, 3)
        # Rows run from the north pole down: reverse the winding to face out.
        return self.radius * unit, topology.triangles((rings + 1, segments + 1))[:, ::-1]


class Box(Obstacle):
    """A box of edge lengths ``size`` along its own axes, turned by ``angles``
    (degrees about the fixed x, y and z axes, in that order)."""

    name = "box"

    def __init__(self, size, angles=(0.0, 0.0, 0.0), **common):
        super().__init__(
            rotation=Rotation.from_euler("xyz", angles, degrees=True).as_matrix(), **common
        )
        self.angles = tuple(angles)
        self.size = np.asarray(size, dtype=float)
        self.half = 0.5 * self.size + self.thickness

    def bounds(self):
        return -self.half, self.half

    def entry(self, q0, q1):
        h = self.half
        d = q1 - q0
        inside = np.all(np.abs(q0) <= h, axis=1)
        # Slab test: the path is inside the box for s in [enter, leave].
        with np.errstate(divide="ignore", invalid="ignore"):
            s_a = (-h - q0) / d
            s_b = (h - q0) / d
        parallel = np.abs(d) <= TINY
        low = np.where(parallel, np.where(np.abs(q0) <= h, -np.inf, np.inf), np.minimum(s_a, s_b))
        high = np.where(parallel, np.where(np.abs(q0) <= h, np.inf, -np.inf), np.maximum(s_a, s_b))
        enter, leave = low.max(axis=1), high.min(axis=1)
        crosses = ~inside & (enter <= leave) & (enter >= 0.0) & (enter <= 1.0)
        rows = np.arange(q0.shape[0])
        axis = np.where(inside, np.argmin(h - np.abs(q0), axis=1), np.argmax(low, axis=1))
        sign = np.where(inside, np.sign(q0[rows, axis]), -np.sign(d[rows, axis]))
        sign = np.where(sign == 0.0, 1.0, sign)
        point = np.where(inside[:, None], q0, q0 + np.where(crosses, enter, 0.0)[:, None] * d)
        point[rows, axis] = sign * h[axis]
        normal = np.zeros_like(q0)
        normal[rows, axis] = sign
        return inside | crosses, point, normal

    def distance(self, points, t=0.0):
        q = np.abs(self.to_local(points, t)) - 0.5 * self.size
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        return outside + np.minimum(q.max(axis=1), 0.0)

    def _gap_local(self, q):
        # Outside: from the nearest point of the grown box; inside: out
        # through the nearest face.
        beyond = q - np.clip(q, -self.half, self.half)
        length = np.linalg.norm(beyond, axis=1)
        depth = self.half - np.abs(q)  # (k, 3) m to each face pair
        rows = np.arange(q.shape[0])
        axis = np.argmin(depth, axis=1)
        face = np.zeros_like(q)
        face[rows, axis] = np.where(q[rows, axis] < 0.0, -1.0, 1.0)
        outside = length > 0.0
        normal = np.where(outside[:, None], beyond / np.where(outside, length, 1.0)[:, None], face)
        return np.where(outside, length, -depth[rows, axis]), normal

    def surface(self, extent):
        """Six faces of four vertices each (so each face shades flat)."""
        vertices, triangles = [], []
        for axis in range(3):
            u, w = (axis + 1) % 3, (axis + 2) % 3
            for sign in (-1.0, 1.0):
                corners = np.zeros((4, 3))
                corners[:, axis] = sign
                corners[:, u] = [-1.0, 1.0, 1.0, -1.0]
                corners[:, w] = [-1.0, -1.0, 1.0, 1.0]
                first = 4 * len(vertices)
                quad = [[0, 1, 2], [0, 2, 3]] if sign > 0 else [[0, 2, 1], [0, 3, 2]]
                triangles += [[first + i for i in tri] for tri in quad]
                vertices.append(0.5 * self.size * corners)
        return np.concatenate(vertices), np.array(triangles)

    def _shape_text(self):
        text = "box {:g} x {:g} x {:g} m at ({:g}, {:g}, {:g})".format(*self.size, *self.center)
        if any(self.angles):
            text += ", turned ({:g}, {:g}, {:g}) deg about x, y, z".format(*self.angles)
        return text


class Ground(Obstacle):
    """The half-space behind a plane; its own z axis is the plane's normal."""

    name = "ground"

    def __init__(self, normal, **common):
        n = np.asarray(normal, dtype=float)
        n = n / np.linalg.norm(n)
        # Any right-handed frame whose third axis is n will do.
        helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        u = np.cross(helper, n)
        u /= np.linalg.norm(u)
        super().__init__(rotation=np.column_stack([u, np.cross(n, u), n]), **common)
        self.normal = n

    def bounds(self):
        # Unbounded along the plane and below it; bounded above by the thickness.
        return np.full(3, -np.inf), np.array([np.inf, np.inf, self.thickness])

    def may_touch(self, low, high, t0, t1):
        lowest = np.where(self.normal > 0, low, high)  # the box corner deepest below
        height = min(float((lowest - self.center_at(t)) @ self.normal) for t in (t0, t1))
        return height <= self.thickness

    def entry(self, q0, q1):
        z0, z1 = q0[:, 2], q1[:, 2]
        inside = z0 <= self.thickness
        crosses = ~inside & (z1 < self.thickness)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(crosses, (z0 - self.thickness) / (z0 - z1), 0.0)
        point = q0 + s[:, None] * (q1 - q0)
        point[:, 2] = self.thickness
        normal = np.zeros_like(q0)
        normal[:, 2] = 1.0
        return inside | crosses, point, normal

    def distance(self, points, t=0.0):
        return (points - self.center_at(t)) @ self.normal

    def _gap_local(self, q):
        normal = np.zeros_like(q)
        normal[:, 2] = 1.0
        return q[:, 2] - self.thickness, normal

    def surface(self, extent):
        """A square of side ``extent`` centred on the plane's point."""
        h = 0.5 * extent
        vertices = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
        return vertices, np.array([[0, 1, 2], [0, 2, 3]])

    def _shape_text(self):
        return "ground through ({:g}, {:g}, {:g}), normal ({:.3g}, {:.3g}, {:.3g})".format(
            *self.center, *self.normal
        )


def build_obstacle(spec) -> Obstacle:
    """The obstacle an :class:`~pvcloth.ObstacleSpec` describes."""
    common = dict(
        center=spec.center,
        thickness=spec.thickness,
        friction=spec.friction,
        static_friction=spec.static_friction,
        path=spec.path,
    )
    if spec.type == "sphere":
        return Sphere(spec.radius, **common)
    if spec.type == "box":
        return Box(spec.size, spec.rotation, **common)
    return Ground(spec.normal, **common)
