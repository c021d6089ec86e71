"""Self-collision: the cloth against itself, after every step of any integrator.

Like the obstacles (:mod:`pvcloth.physics.obstacles`), this acts after the
integrator's step, on positions and velocities, so every integrator gets the
same response. It runs only when the scene has a ``[self_collision]`` table;
otherwise the model holds no :class:`SelfCollision` and no code of this
module runs. ``backward_euler`` and ``bdf2`` also hold the layers apart
inside their solve, with a penalty on the pairs this module lists
(:class:`~pvcloth.physics.integrators.penalties.LayerPenalty`); for them
the response here is the fail-safe, and :meth:`SelfCollision.rub` gives
the pairs their penalty held Coulomb friction.

The cloth's surface is the grid's triangles, two per cell (the wind's split:
corners ``(a, a+1, a+nx+1)`` and ``(a, a+nx+1, a+nx)``), and its edges are
the triangles' edges. Contact is between a point and a triangle it is not a
corner of (*VF*), and between two edges that share no point (*EE*).

One step ``x0 -> x1`` (``x0`` the start, free of intersections)
-----------------------------------------------------------------
1. **Pair list** (broad phase): each point gets a box holding its path
   over the step, grown by the response's ``reach``; every VF and EE pair
   whose points' boxes come within ``thickness`` of each other is listed,
   found through a uniform hash grid (:func:`box_pairs`; each overlap found
   once, from the cell holding its lower corner; no O(N^2) pass). Boxes are
   convex, so while each point's start and end stay in its box
   (:func:`inside`), so does everything the step does to it, and an
   unlisted pair stays at least ``thickness`` apart. Each step's list is
   the same pairs, in one sorted order, whatever the run's history: it is
   filtered from a kept list with wider boxes while the boxes stay in
   those, and the step's result so never depends on which list was kept.
2. **Screen** (:func:`screen`): a listed pair can change its distance
   from the *anchor* (the start of the step) by at most the largest
   motion of its other points relative to its first one
   (for a point and a triangle; for two edges the first edge's other end
   adds its own), which :func:`_relative` bounds by the start's offset from
   the anchor, the step's relative motion and twice ``reach``. Only pairs
   this bound lets within ``thickness`` go on; a pair of points of one
   flat layer moves together and is screened out.
3. **Proximity** (Bridson, Fedkiw and Anderson 2002, "Robust treatment of
   collisions, contact and friction for cloth animation", sections 7.1-7.3):
   each pair closer than ``thickness`` at the end of the step is pushed
   apart along the line of its closest points to the thickness (a position
   projection, which adds no velocity and so no bounce), its approaching
   relative velocity is removed (inelastic), and Coulomb friction with
   ``friction`` times that normal change holds or slows its sliding. The
   push is shared by the inverse masses and the closest point's barycentric
   weights, so pinned points do not move and momentum is kept. Two sides
   of one crease (points one grid step apart) are kept only ``CREASE``
   thickness apart: a one-cell fold cannot open wider. No point is
   moved more than ``reach`` (half the thickness) from where the step put
   it, as steps 1 and 2 assumed. A pair whose distance at the start, less
   its points' motion relative to each other since (the bound of step 2),
   is still over the thickness is passed over without a closest-point
   search, and a later sweep looks only at pairs with a point that moved
   since their last look: the same result, for less work.
4. **No crossing** (continuous, :func:`approaches`): for every pair the
   screen kept, the distance between its two primitives along the step's
   straight-line motion ``x0 + s (x1 - x0)``, ``s`` in ``[0, 1]``, is
   bounded from below by conservative advancement. The distance is
   Lipschitz in ``s``: for a point and a triangle it changes by at most
   ``L = max |da - dp|`` per unit ``s`` (the closest point of the
   triangle, held at its barycentric weights, moves relative to the point
   by at most its farthest corner's relative motion); for two edges by at
   most ``|dq - dp| + max |da - dp|``. So after a distance ``d`` at ``s``,
   no contact can occur before ``s + d / L``; the check advances by that
   much (less half the margin ``eta``) until ``s`` passes 1 (the distance
   at ``s = 0`` is the one step 1 listed), and reports an
   approach when the distance falls below ``eta`` (a tenth of the
   thickness, or half the start distance if that is smaller). A reported
   pair first gets an inelastic impulse (:func:`impulses`; Bridson et al.
   2002, section 7.4): the part of its relative motion and velocity along
   the line between the pair at that moment that closes it is taken away;
   up to ``SWEEPS`` sweeps, with the list built again if a point left its
   box and the screen made again on the new paths. The free points of
   pairs still reported join an **impact zone** (Provot 1997; Bridson
   et al. 2002, section 8, here without rotation): the zone moves over the
   step by its members' mass-weighted mean motion and takes their mean
   velocity, so its pairs keep the distances they had at the start and
   momentum is kept. Zones changed the paths of their triangles and edges,
   so the check runs again on every listed pair with a point that moved,
   merging zones that still approach; if zones carried points past their
   boxes, the list is built again around the new paths and every pair of
   those points checked. A zone that still approaches on its own can only
   be pushed by a pinned point of one of its pairs; it then moves with that
   pin (a translation, which keeps its distances to the pin), and if a
   second pin drives into it as well, it is held at the start of the step.
   The start was free of intersections, and zones only grow, follow a pin
   or become held, so this ends, at worst with the whole cloth one zone.

Why no intersection appears: between two triangles that share no point, an
intersection can only begin when a corner of one passes through the other or
an edge of one passes through an edge of the other, while their points move
on straight lines. Step 4 proves, with a margin, that no such VF or EE pair
touches during the final motion of the step, so a cloth that started the step
without intersections ends it without them. The exception is motion imposed
on pinned points: they cannot join a zone, and a zone that two pins moving
differently both drive into is held, so those pins can still push the cloth
through (counted in :attr:`Report.unresolved`).

The kernels are compiled with numba when it is installed; without it the
same functions run as plain Python (correct, and slow).

The package, one module per job: :class:`SelfCollision` here drives the
steps above; ``pairs`` lists and screens the pairs (steps 1 and 2),
``geometry`` holds the closest points they all use, ``response`` pushes
close pairs apart (step 3), ``continuous`` finds first touches and stops
approaches with impulses, and ``zones`` merges what still approaches into
impact zones (step 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pvcloth.errors import DivergenceError
from pvcloth.physics import topology
from pvcloth.physics.self_collision.continuous import approaches, impulses
from pvcloth.physics.self_collision.geometry import linearise, point_triangle, segment_segment
from pvcloth.physics.self_collision.pairs import (
    PairList,
    box_pairs,
    contains,
    inside,
    item_boxes,
    overlapping,
    pair_distances,
    screen,
    sort_rows,
)
from pvcloth.physics.self_collision.response import CREASE, respond, rub
from pvcloth.physics.self_collision.zones import ZoneArrays, impact_zones, new_zones

#: The margin ``eta`` as a share of the thickness.
MARGIN = 0.1
#: Gauss-Seidel sweeps of the proximity response over the candidates.
SWEEPS = 3
#: More candidate pairs than this in one step means points moved far more
#: in the step than a cloth does (each pair takes 16 bytes while listing):
#: the step is refused rather than the memory run out.
MAX_PAIRS = 20_000_000
#: The kept, wider pair list's boxes are grown by this share of the
#: thickness beyond each step's own (see ``SelfCollision._build``).
SKIN = 0.5


@dataclass
class Report:
    """What the self-collision of one step did (counts of pairs and points)."""

    candidates: int = 0  # VF and EE pairs in the pair list (step 1)
    near: int = 0  # of those, pairs the step's motion may bring into contact (step 2)
    contacts: int = 0  # pair pushes of the proximity response, summed over its sweeps
    zoned: int = 0  # points moved as one with an impact zone
    unresolved: int = 0  # pairs still approaching with their zone held (pins pushed them)


class SelfCollision:
    """Cloth-cloth contact for a grid cloth (see the module docstring).

    Parameters
    ----------
    shape : (int, int)
        ``(ny, nx)`` of the grid.
    thickness : float
        Distance (m) the layers are kept apart.
    friction : float
        Coulomb friction coefficient between layers (>= 0).
    in_solve : bool
        Whether an integrator that can (``Integrator.holds_layers``) holds
        the layers inside its solve as well.

    Attributes
    ----------
    triangles : ndarray of int, shape (T, 3)
    edges : ndarray of int, shape (E, 2)
    reach : float
        How far (m) the proximity response may move a point in one step.
    report : Report
        What the last :meth:`resolve` did.
    """

    def __init__(
        self, shape: tuple[int, int], thickness: float, friction: float, in_solve: bool = False
    ):
        self.shape = tuple(shape)
        self.thickness = float(thickness)
        self.friction = float(friction)
        self.in_solve = bool(in_solve)
        self.reach = 0.5 * self.thickness
        self.triangles = topology.triangles(self.shape)
        self.edges = topology.edges(self.shape)
        ny, nx = self.shape
        self._cells = np.stack(np.divmod(np.arange(nx * ny), nx)[::-1], 1)  # (N, 2): column, row
        self.report = Report()
        self._wide = np.empty((0, 3), np.int64)  # the wider list it is taken from
        self._wide_lo = np.empty((0, 3))  # (N, 3) m: the wider list's boxes
        self._wide_hi = np.empty((0, 3))
        self._served = 0  # calls of _build the wider list has served
        self._reuse = 1.0  # how often wider lists served more than one call, lately
        self._rebuilds = 0
        self._capacity = [1 << 16, 1 << 16]  # room for VF and for EE pairs

    def longest_step(self, gravity: float) -> float:
        """The longest step (s) in which a layer lying on another is held up,
        under ``gravity`` (m/s^2, its magnitude): starting at rest, the
        layer falls ``gravity dt^2`` in one step, and the response may move
        a point back by at most ``reach``. A longer step lets the layer sink
        a little further every step, until the continuous check has to stop
        it with impulses and zones (measured on the towel folded at 64x64,
        reach 1.7 mm: at 1/60 s, a fall of 2.7 mm a step, it never came to
        rest, 0.15 m/s and 320 ms a step after 3 s; at 1/120 s it rested at
        0.02 m/s and 54 ms a step).

        Examples
        --------
        >>> from pvcloth.physics.self_collision import SelfCollision
        >>> contact = SelfCollision((64, 64), thickness=0.0034, friction=0.3)
        >>> round(contact.longest_step(9.81), 4)  # sqrt(0.0017 / 9.81)
        0.0132
        """
        return math.inf if gravity <= 0.0 else math.sqrt(self.reach / gravity)

    def point_triangle_pairs(
        self, x0: np.ndarray, x1: np.ndarray, reach: float, within: float
    ) -> np.ndarray:
        """Rows ``(0, point, triangle)`` (``(P, 3)``, int64) of the VF
        pairs that may come within ``within`` (m) over the straight paths
        ``x0 -> x1`` (m, ``(N, 3)``) grown by ``reach`` (m): steps 1 and 2
        of the module docstring for those distances, ``x0`` the anchor."""
        listed = self._build(x0, x1, reach)
        count = int(np.searchsorted(listed.rows[:, 0], 1))  # sorted: the VF rows first
        rows = listed.rows[:count]
        near = screen(
            rows, listed.gaps[:count], listed.anchor, x0, x1, self.triangles, self.edges, reach,
            within,
        )  # fmt: skip
        return rows[near]

    def linearise(self, pairs: np.ndarray, x: np.ndarray, inv_mass) -> tuple:
        """Each of ``pairs`` fixed at ``x`` (m, ``(N, 3)``), ``inv_mass``
        (1/kg, ``(N,)``) saying who may move: its corners, closest-point
        weights, unit direction, the distance it is kept at (the thickness,
        ``CREASE`` of it across a crease) and effective mass
        (:func:`~pvcloth.physics.self_collision.geometry.linearise`)."""
        return linearise(
            pairs, self.triangles, self.edges, self._cells, x, inv_mass, self.thickness, CREASE
        )

    def rub(self, held, x1: np.ndarray, v1: np.ndarray, inv_mass) -> int:
        """Coulomb friction, in place on ``x1`` (m) and ``v1`` (m/s), on
        the pairs an integrator's solve held apart with a penalty
        (``held``: :class:`~pvcloth.physics.integrators.penalties.HeldPairs`);
        :func:`~pvcloth.physics.self_collision.response.rub`. Returns the
        pairs that stuck."""
        return int(
            rub(
                held.corners,
                held.weights,
                held.direction,
                held.pushed,
                x1,
                v1,
                inv_mass,
                self.friction,
                held.lever,
            )  # fmt: skip
        )

    def resolve(
        self, x0: np.ndarray, x1: np.ndarray, v1: np.ndarray, inv_mass, dt: float, resting=()
    ):
        """Make the step ``x0 -> x1`` free of self-intersection, in place on
        ``x1`` (m) and ``v1`` (m/s), both ``(N, 3)``; ``inv_mass`` ``(N,)``
        (1/kg, zero for pinned points) says who may move. ``resting`` are the
        obstacles' :class:`~pvcloth.physics.obstacles.Contacts` of this step:
        the proximity response does not push those points into their
        obstacle (a layer lying on them would, and the next step's contact
        push them back, so a folded cloth on the ground would never come to
        rest). Returns the :class:`Report`."""
        d, reach = self.thickness, self.reach
        # A list kept from an earlier step would do (every pair it adds is
        # proven apart), but which pairs the zones meet, and so the step's
        # result, would then depend on the run's history: a resumed run
        # would not repeat a continuous one bit for bit. So each step lists.
        pairs = self._build(x0, x1, reach)
        rows = pairs.rows
        near = screen(rows, pairs.gaps, pairs.anchor, x0, x1, self.triangles, self.edges, reach, d)
        start = x1.copy()
        floor = np.zeros_like(x1)  # per point: its obstacle's outward normal, or zero
        for contact in resting:
            floor[contact.index] = contact.normal
        contacts = respond(
            rows, near, pairs.gaps, self._cells, self.triangles, self.edges, x0, x1, v1, start,
            inv_mass, floor, d, self.friction, dt, reach, SWEEPS,
        )  # fmt: skip
        fresh = np.ones(len(x0), np.bool_)
        clear = False
        for sweep in range(SWEEPS):
            count, fresh, found = impulses(
                rows, near, pairs.gaps, self.triangles, self.edges, x0, x1, v1, inv_mass,
                floor, MARGIN * d, fresh,
            )  # fmt: skip
            # Nothing in the first sweep approaches: the zones' first pass
            # would check the same pairs on the same paths and find the same.
            clear = sweep == 0 and found == 0
            if not count:
                break
            # The impulses may move points by more than the response's reach:
            # list again if one left its box, and screen the new paths (the
            # pairs a sweep sees do not depend on the list's history).
            if not inside(pairs.low, pairs.high, x0, x1, 0.0):
                pairs = self._build(x0, x1, 0.0)
                rows = pairs.rows
            near = screen(
                rows, pairs.gaps, pairs.anchor, x0, x1, self.triangles, self.edges, 0.0, d
            )
        zoned = unresolved = 0
        checked = near
        zones = None if clear else new_zones(x0, x1, v1)
        while zones is not None:
            zoned, unresolved, done = impact_zones(
                rows, checked, pairs.gaps, self.triangles, self.edges, x0, x1, v1, inv_mass,
                MARGIN * d, zones, pairs.low, pairs.high,
            )  # fmt: skip
            if done:
                break
            # Zones carried points past their boxes: list again around the
            # paths as they are, and go on with every pair of those points
            # (the others were checked against a list that held them). Zones
            # only grow, follow a pin or are held, so this ends.
            pairs = self._build(x0, x1, 0.0)
            rows = pairs.rows
            outside = zones.outside
            zones.fresh[outside] = True
            outside[:] = False
            checked = np.arange(len(rows))
        self.report = Report(len(rows), len(near), int(contacts), int(zoned), int(unresolved))
        return self.report

    def _build(self, x0: np.ndarray, x1: np.ndarray, reach: float) -> PairList:
        """List every pair whose points' boxes come within ``thickness``:
        each box holds the point's step ``x0 -> x1`` grown by ``reach`` (m);
        ``x0`` is the anchor of the screen.

        The list is the pairs of a kept, wider list (each box grown by
        ``SKIN`` thickness more) whose boxes overlap: while every box stays
        inside its wider one, that list holds every such pair, so the
        result is the same pairs in the same order as a list built afresh;
        only when a box leaves is the wider list built again."""
        low = np.minimum(x0, x1) - reach
        high = np.maximum(x0, x1) + reach
        half = 0.5 * self.thickness
        lo, hi = low - half, high + half
        grow = -1.0
        if self._wide_lo.shape != lo.shape or not contains(self._wide_lo, self._wide_hi, lo, hi):
            # The wider list costs more to build; it pays only while boxes
            # stay in it (a cloth at rest), not when every call leaves it
            # (a crumple). Which list is used changes no result, only time.
            self._reuse = 0.8 * self._reuse + 0.2 * (self._served > 1)
            self._rebuilds += 1
            wide = self._reuse > 0.3 or self._rebuilds % 10 == 0
            grow = SKIN * self.thickness if wide else 0.0
            self._wide_lo, self._wide_hi = lo - grow, hi + grow
            self._wide = self._pairs(self._wide_lo, self._wide_hi)
            self._served = 0
        self._served += 1
        exact = self._served == 1 and grow == 0.0  # built from these very boxes
        rows = self._wide if exact else overlapping(self._wide, lo, hi, self.triangles, self.edges)
        anchor = x0.copy()
        gaps = pair_distances(rows, self.triangles, self.edges, anchor)
        return PairList(rows, gaps, anchor, low, high)

    def _pairs(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Rows ``(kind, first, second)`` of every VF and EE pair whose boxes
        (from the points' boxes ``lo``-``hi``) overlap, sorted."""
        vf, ee = self._box_pairs(lo, hi, 0), self._box_pairs(lo, hi, 1)
        rows = np.empty((len(vf) + len(ee), 3), np.int64)
        rows[: len(vf), 0], rows[len(vf) :, 0] = 0, 1
        rows[: len(vf), 1:], rows[len(vf) :, 1:] = vf, ee
        # One order whatever the boxes were (the hash grid's cells follow
        # them): the response sweeps pairs in this order, so a run repeats
        # itself bit for bit whichever lists it kept.
        return sort_rows(rows)

    def _box_pairs(self, lo, hi, kind: int) -> np.ndarray:
        items = self.triangles if kind == 0 else self.edges
        item_lo, item_hi = item_boxes(lo, hi, items)
        query_lo, query_hi = (lo, hi) if kind == 0 else (item_lo, item_hi)
        extent = (item_hi - item_lo).max(axis=1)
        # Most boxes fit one cell; the few long ones (a fast point) span several.
        cell = max(float(np.percentile(extent, 90)), 1e-9 * float(np.abs(hi).max() + 1.0))
        while True:
            out = np.empty((self._capacity[kind], 2), np.int64)
            n = box_pairs(query_lo, query_hi, item_lo, item_hi, items, kind, cell, out)
            if n > MAX_PAIRS:
                raise DivergenceError(
                    f"self-collision: {n:,} candidate pairs in one step (more than "
                    f"{MAX_PAIRS:,}): a point's path in this step spans {extent.max():.3g} m. "
                    "The step is too long for this motion; lower solver.dt"
                )
            fits = n <= self._capacity[kind]
            # Room for this step's count and a little more; a one-step burst
            # does not keep a large buffer for the rest of the run.
            self._capacity[kind] = max(1 << 16, int(1.5 * n))
            if fits:
                return out[:n]
