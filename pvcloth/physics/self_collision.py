"""Self-collision: the cloth against itself, after every step of any integrator.

Like the obstacles (:mod:`pvcloth.physics.obstacles`), this acts after the
integrator's step, on positions and velocities, so every integrator gets the
same response. It runs only when the scene has a ``[self_collision]`` table;
otherwise the model holds no :class:`SelfCollision` and no code of this
module runs.

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pvcloth.errors import DivergenceError
from pvcloth.physics import topology

try:
    from numba import njit, prange
except ImportError:  # pragma: no cover - exercised only where numba is missing
    prange = range

    def njit(*args, **kwargs):
        if args and callable(args[0]):
            return args[0]
        return lambda function: function


#: Conservative advancement gives up after this many samples of one pair and
#: reports an approach (an impact zone: safe, only less smooth).
MAX_SAMPLES = 100
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
#: Two sides of one crease (a pair with points one grid step apart) are
#: kept this share of the thickness apart, not the whole: a fold of one
#: cell cannot open its crease that wide, and pushing it to would make
#: the crease chatter against gravity at rest. No crossing still holds.
CREASE = 0.2


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

    Attributes
    ----------
    triangles : ndarray of int, shape (T, 3)
    edges : ndarray of int, shape (E, 2)
    reach : float
        How far (m) the proximity response may move a point in one step.
    report : Report
        What the last :meth:`resolve` did.
    """

    def __init__(self, shape: tuple[int, int], thickness: float, friction: float):
        self.shape = tuple(shape)
        self.thickness = float(thickness)
        self.friction = float(friction)
        self.reach = 0.5 * self.thickness
        self.triangles = topology.triangles(self.shape)
        self.edges = topology.edges(self.shape)
        ny, nx = self.shape
        self._cells = np.stack(np.divmod(np.arange(nx * ny), nx)[::-1], 1)  # (N, 2): column, row
        self.report = Report()
        self._anchor: np.ndarray | None = None  # (N, 3) m: where the list was built
        self._low = np.empty((0, 3))  # (N, 3) m: the box each point must stay in
        self._high = np.empty((0, 3))
        self._rows = np.empty((0, 3), np.int64)  # the pair list: (kind, first, second)
        self._wide = np.empty((0, 3), np.int64)  # the wider list it is taken from
        self._wide_lo = np.empty((0, 3))  # (N, 3) m: the wider list's boxes
        self._wide_hi = np.empty((0, 3))
        self._served = 0  # calls of _build the wider list has served
        self._reuse = 1.0  # how often wider lists served more than one call, lately
        self._rebuilds = 0
        self._gaps = np.empty(0)  # (P,) m: each listed pair's distance at the anchor
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
        self._build(x0, x1, reach)
        rows = self._rows
        near = screen(rows, self._gaps, self._anchor, x0, x1, self.triangles, self.edges, reach, d)
        start = x1.copy()
        floor = np.zeros_like(x1)  # per point: its obstacle's outward normal, or zero
        for contact in resting:
            floor[contact.index] = contact.normal
        contacts = respond(
            rows, near, self._gaps, self._cells, self.triangles, self.edges, x0, x1, v1, start,
            inv_mass, floor, d, self.friction, dt, reach, SWEEPS,
        )  # fmt: skip
        fresh = np.ones(len(x0), np.bool_)
        clear = False
        for sweep in range(SWEEPS):
            count, fresh, found = impulses(
                rows, near, self._gaps, self.triangles, self.edges, x0, x1, v1, inv_mass,
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
            if not inside(self._low, self._high, x0, x1, 0.0):
                self._build(x0, x1, 0.0)
                rows = self._rows
            near = screen(
                rows, self._gaps, self._anchor, x0, x1, self.triangles, self.edges, 0.0, d
            )
        zoned = unresolved = 0
        checked = near
        zones = None if clear else _zones(x0, x1, v1)
        while zones is not None:
            zoned, unresolved, done = impact_zones(
                rows, checked, self._gaps, self.triangles, self.edges, x0, x1, v1, inv_mass,
                MARGIN * d, zones, self._low, self._high,
            )  # fmt: skip
            if done:
                break
            # Zones carried points past their boxes: list again around the
            # paths as they are, and go on with every pair of those points
            # (the others were checked against a list that held them). Zones
            # only grow, follow a pin or are held, so this ends.
            self._build(x0, x1, 0.0)
            rows = self._rows
            outside = zones[8]
            zones[5][outside] = True
            outside[:] = False
            checked = np.arange(len(rows))
        self.report = Report(len(rows), len(near), int(contacts), int(zoned), int(unresolved))
        return self.report

    def _build(self, x0: np.ndarray, x1: np.ndarray, reach: float) -> None:
        """List every pair whose points' boxes come within ``thickness``:
        each box holds the point's step ``x0 -> x1`` grown by ``reach`` (m);
        ``x0`` is the anchor of the screen.

        The list is the pairs of a kept, wider list (each box grown by
        ``SKIN`` thickness more) whose boxes overlap: while every box stays
        inside its wider one, that list holds every such pair, so the
        result is the same pairs in the same order as a list built afresh;
        only when a box leaves is the wider list built again."""
        self._low = np.minimum(x0, x1) - reach
        self._high = np.maximum(x0, x1) + reach
        half = 0.5 * self.thickness
        lo, hi = self._low - half, self._high + half
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
        self._anchor = x0.copy()
        self._rows = rows
        self._gaps = pair_distances(rows, self.triangles, self.edges, self._anchor)

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


# -- the pair list and its screen -------------------------------------------------


def _zones(x0: np.ndarray, x1: np.ndarray, v1: np.ndarray):
    """Fresh impact-zone arrays for :func:`impact_zones`: union-find
    parents; per point whether it is zoned and whether it moved since its
    pairs were last checked; per zone root whether it is held, grew in this
    pass, and the pinned point it follows (-1: none); each point's own
    motion (m) and velocity (m/s) before any zone; per point whether a zone
    carried it out of its box since the list was built."""
    n = len(x0)
    return (
        np.arange(n),
        np.zeros(n, np.bool_),
        np.zeros(n, np.bool_),
        np.zeros(n, np.bool_),
        np.full(n, -1),
        np.ones(n, np.bool_),
        x1 - x0,
        v1.copy(),
        np.zeros(n, np.bool_),
    )


@njit(cache=True)
def inside(low, high, x0, x1, reach):  # pragma: no cover
    """Whether every point's ``x0`` and its ``x1`` grown by ``reach`` lie in
    its box ``low``-``high`` (N, 3) (step 1 of the module docstring)."""
    for i in range(low.shape[0]):
        for a in range(3):
            if x0[i, a] < low[i, a] or x0[i, a] > high[i, a]:
                return False
            if x1[i, a] - reach < low[i, a] or x1[i, a] + reach > high[i, a]:
                return False
    return True


# The passes over every listed pair, each pair on its own, run on numba's
# threads (as many as the calling thread allows: one in the window's
# physics thread, see pvcloth.physics.kernels.use_threads); the results do
# not depend on how many.


@njit(cache=True, parallel=True)
def pair_distances(rows, triangles, edges, x):  # pragma: no cover
    """Distance (m) between the two primitives of every pair at ``x``."""
    gaps = np.empty(rows.shape[0])
    for n in prange(rows.shape[0]):
        kind = rows[n, 0]
        i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
        _, gap = _closest(kind, i0, i1, i2, i3, x, x, 0.0)
        gaps[n] = math.sqrt(_dot(gap, gap))
    return gaps


@njit(cache=True, inline="always")
def _relative(anchor, x0, x1, k, ref, reach):  # pragma: no cover
    """Bound on how far point ``k`` moves relative to point ``ref`` from
    the anchor, over the step and its response."""
    start = 0.0
    motion = 0.0
    for a in range(3):
        start += (x0[k, a] - anchor[k, a] - x0[ref, a] + anchor[ref, a]) ** 2
        motion += (x1[k, a] - x0[k, a] - x1[ref, a] + x0[ref, a]) ** 2
    return math.sqrt(start) + math.sqrt(motion) + 2.0 * reach


@njit(cache=True, parallel=True)
def screen(rows, gaps, anchor, x0, x1, triangles, edges, reach, thickness):  # pragma: no cover
    """Indices of the listed pairs that may come within ``thickness``
    during the step or its response (step 2 of the module docstring)."""
    keep = np.empty(rows.shape[0], np.bool_)
    for n in prange(rows.shape[0]):
        kind = rows[n, 0]
        i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
        r1 = _relative(anchor, x0, x1, i1, i0, reach)
        r2 = _relative(anchor, x0, x1, i2, i0, reach)
        r3 = _relative(anchor, x0, x1, i3, i0, reach)
        bound = max(r1, max(r2, r3)) if kind == 0 else r1 + max(r2, r3)
        keep[n] = gaps[n] - bound < thickness
    return np.nonzero(keep)[0]


# -- broad phase ---------------------------------------------------------------


def sort_rows(rows: np.ndarray) -> np.ndarray:
    """Rows ``(kind, first, second)`` (int64, shape (P, 3)) sorted by kind,
    then first, then second.

    One key per row and NumPy's stable sort: 7 ms for 135,000 rows, against
    11 ms for a compiled sort of each run of one ``first``, which also took
    7 s to compile (numba builds its sort from Python source on first use).
    The key is below ``2 F S`` (``F``, ``S``: the largest first and
    second), which fits int64 for any grid under 26,000 points a side.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.self_collision import sort_rows
    >>> sort_rows(np.array([[1, 0, 5], [0, 2, 1], [0, 1, 9], [0, 1, 3]])).tolist()
    [[0, 1, 3], [0, 1, 9], [0, 2, 1], [1, 0, 5]]
    """
    if len(rows) == 0:
        return rows
    firsts, seconds = int(rows[:, 1].max()) + 1, int(rows[:, 2].max()) + 1
    key = (rows[:, 0] * firsts + rows[:, 1]) * seconds + rows[:, 2]
    return rows[np.argsort(key, kind="stable")]


@njit(cache=True)
def contains(outer_lo, outer_hi, lo, hi):  # pragma: no cover
    """Whether every box ``lo``-``hi`` (N, 3) lies inside its ``outer`` box."""
    for i in range(lo.shape[0]):
        for a in range(3):
            if lo[i, a] < outer_lo[i, a] or hi[i, a] > outer_hi[i, a]:
                return False
    return True


@njit(cache=True, parallel=True)
def overlapping(rows, lo, hi, triangles, edges):  # pragma: no cover
    """The rows whose two primitives' boxes overlap, in their order; the box
    of a triangle or edge is the union of its points' boxes ``lo``-``hi``,
    as in :func:`box_pairs`."""
    keep = np.empty(rows.shape[0], np.bool_)
    for n in prange(rows.shape[0]):
        kind = rows[n, 0]
        i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
        overlap = True
        for a in range(3):
            if kind == 0:
                first_lo, first_hi = lo[i0, a], hi[i0, a]
                second_lo = min(lo[i1, a], min(lo[i2, a], lo[i3, a]))
                second_hi = max(hi[i1, a], max(hi[i2, a], hi[i3, a]))
            else:
                first_lo, first_hi = min(lo[i0, a], lo[i1, a]), max(hi[i0, a], hi[i1, a])
                second_lo, second_hi = min(lo[i2, a], lo[i3, a]), max(hi[i2, a], hi[i3, a])
            if first_lo > second_hi or first_hi < second_lo:
                overlap = False
        keep[n] = overlap
    return rows[keep]


@njit(cache=True)
def item_boxes(lo, hi, items):  # pragma: no cover
    """Boxes ``(low, high)`` of triangles or edges: the union of their
    points' boxes ``lo``, ``hi`` (N, 3)."""
    n, corners = items.shape
    low = np.empty((n, 3))
    high = np.empty((n, 3))
    for j in range(n):
        for a in range(3):
            low[j, a] = lo[items[j, 0], a]
            high[j, a] = hi[items[j, 0], a]
        for k in range(1, corners):
            i = items[j, k]
            for a in range(3):
                low[j, a] = min(low[j, a], lo[i, a])
                high[j, a] = max(high[j, a], hi[i, a])
    return low, high


def box_pairs(qlo, qhi, blo, bhi, items, kind: int, cell: float, out) -> int:
    """Pairs ``(i, j)`` of query box ``i`` and item box ``j`` that overlap,
    written into ``out`` (as many as fit); returns how many there are.

    ``kind`` 0: queries are points, items triangles; a point is not paired
    with a triangle it is a corner of. ``kind`` 1: queries and items are the
    same edges; each pair once (``i < j``), none sharing a point.

    A uniform hash grid of cubes of side ``cell`` (m): each item is entered
    in every cell its box touches (:func:`_cell_entries`), the entries are
    sorted by cell with NumPy (a compiled sort took seconds to build on
    first use), and each query looks in the cells its box touches
    (:func:`_query_cells`).
    """
    origin = np.minimum(qlo.min(axis=0), blo.min(axis=0))
    top = np.maximum(qhi.max(axis=0), bhi.max(axis=0))
    dims = ((top - origin) / cell).astype(np.int64) + 1
    keys, ids = _cell_entries(blo, bhi, origin, dims, cell)
    # The entries' order within a cell changes only the order pairs are
    # found in; the pair list is sorted afterwards (sort_rows).
    order = np.argsort(keys, kind="stable")
    keys, ids = keys[order], ids[order]
    return _query_cells(qlo, qhi, blo, bhi, items, kind, cell, origin, dims, keys, ids, out)


@njit(cache=True)
def _cell_entries(blo, bhi, origin, dims, cell):  # pragma: no cover
    """Every (cell key, item) pair of :func:`box_pairs`' hash grid: each item
    box ``blo``-``bhi`` in each cell it touches."""
    nb = blo.shape[0]
    c0 = np.empty((nb, 3), np.int64)
    c1 = np.empty((nb, 3), np.int64)
    total = 0
    for j in range(nb):
        span = 1
        for a in range(3):
            c0[j, a] = int((blo[j, a] - origin[a]) / cell)
            c1[j, a] = int((bhi[j, a] - origin[a]) / cell)
            span *= c1[j, a] - c0[j, a] + 1
        total += span
    keys = np.empty(total, np.int64)
    ids = np.empty(total, np.int64)
    m = 0
    for j in range(nb):
        for cx in range(c0[j, 0], c1[j, 0] + 1):
            for cy in range(c0[j, 1], c1[j, 1] + 1):
                for cz in range(c0[j, 2], c1[j, 2] + 1):
                    keys[m] = (cx * dims[1] + cy) * dims[2] + cz
                    ids[m] = j
                    m += 1
    return keys, ids


@njit(cache=True)
def _query_cells(
    qlo, qhi, blo, bhi, items, kind, cell, origin, dims, keys, ids, out
):  # pragma: no cover
    """:func:`box_pairs`' search: each query box against the items entered
    in the cells it touches (``keys`` sorted, ``ids`` in the same order)."""
    total = keys.shape[0]
    found = 0
    capacity = out.shape[0]
    for i in range(qlo.shape[0]):
        x0 = int((qlo[i, 0] - origin[0]) / cell)
        y0 = int((qlo[i, 1] - origin[1]) / cell)
        z0 = int((qlo[i, 2] - origin[2]) / cell)
        x1 = int((qhi[i, 0] - origin[0]) / cell)
        y1 = int((qhi[i, 1] - origin[1]) / cell)
        z1 = int((qhi[i, 2] - origin[2]) / cell)
        for cx in range(x0, x1 + 1):
            for cy in range(y0, y1 + 1):
                for cz in range(z0, z1 + 1):
                    key = (cx * dims[1] + cy) * dims[2] + cz
                    first = np.searchsorted(keys, key)
                    while first < total and keys[first] == key:
                        j = ids[first]
                        first += 1
                        if kind == 1 and j <= i:
                            continue
                        if (
                            qlo[i, 0] > bhi[j, 0] or qhi[i, 0] < blo[j, 0]
                            or qlo[i, 1] > bhi[j, 1] or qhi[i, 1] < blo[j, 1]
                            or qlo[i, 2] > bhi[j, 2] or qhi[i, 2] < blo[j, 2]
                        ):  # fmt: skip
                            continue
                        # Only the cell of the overlap's lower corner reports it.
                        if (
                            int((max(qlo[i, 0], blo[j, 0]) - origin[0]) / cell) != cx
                            or int((max(qlo[i, 1], blo[j, 1]) - origin[1]) / cell) != cy
                            or int((max(qlo[i, 2], blo[j, 2]) - origin[2]) / cell) != cz
                        ):  # fmt: skip
                            continue
                        if kind == 0:
                            if i == items[j, 0] or i == items[j, 1] or i == items[j, 2]:
                                continue
                        else:
                            a0, a1 = items[i, 0], items[i, 1]
                            b0, b1 = items[j, 0], items[j, 1]
                            if a0 == b0 or a0 == b1 or a1 == b0 or a1 == b1:
                                continue
                        if found < capacity:
                            out[found, 0] = i
                            out[found, 1] = j
                        found += 1
    return found


# -- closest points (3-vectors as tuples: values, never allocated) ------------------


@njit(cache=True, inline="always")
def _sub(a, b):  # pragma: no cover
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, inline="always")
def _dot(a, b):  # pragma: no cover
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _clamp01(value):  # pragma: no cover
    return min(1.0, max(0.0, value))


@njit(cache=True, inline="always")
def _at(x0, x1, s, i):  # pragma: no cover
    """Point ``i`` at share ``s`` of the straight step ``x0 -> x1``."""
    return (
        x0[i, 0] + s * (x1[i, 0] - x0[i, 0]),
        x0[i, 1] + s * (x1[i, 1] - x0[i, 1]),
        x0[i, 2] + s * (x1[i, 2] - x0[i, 2]),
    )


@njit(cache=True)
def point_segment(p, a, b):  # pragma: no cover
    """Parameter ``s`` of the point of segment ``a b`` closest to ``p``."""
    ab = _sub(b, a)
    length2 = _dot(ab, ab)
    if length2 <= 0.0:
        return 0.0
    return _clamp01(_dot(_sub(p, a), ab) / length2)


@njit(cache=True)
def point_triangle(p, a, b, c):  # pragma: no cover
    """Barycentric weights ``(u, v, w)`` of the point ``u a + v b + w c`` of
    triangle ``a b c`` closest to ``p`` (the Voronoi regions of corners,
    edges and face, as in Ericson 2005, "Real-Time Collision Detection",
    5.1.5). Points are 3-tuples."""
    ab = _sub(b, a)
    ac = _sub(c, a)
    ap = _sub(p, a)
    d1 = _dot(ab, ap)
    d2 = _dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    bp = _sub(p, b)
    d3 = _dot(ab, bp)
    d4 = _dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0
    cp = _sub(p, c)
    d5 = _dot(ab, cp)
    d6 = _dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w
    total = va + vb + vc
    if total <= 0.0:  # a triangle of no area: the nearest point of its edges
        t_ab, t_bc, t_ac = point_segment(p, a, b), point_segment(p, b, c), point_segment(p, a, c)
        g_ab = _sub(p, (a[0] + t_ab * ab[0], a[1] + t_ab * ab[1], a[2] + t_ab * ab[2]))
        g_ac = _sub(p, (a[0] + t_ac * ac[0], a[1] + t_ac * ac[1], a[2] + t_ac * ac[2]))
        bc = _sub(c, b)
        g_bc = _sub(p, (b[0] + t_bc * bc[0], b[1] + t_bc * bc[1], b[2] + t_bc * bc[2]))
        e_ab, e_bc, e_ac = _dot(g_ab, g_ab), _dot(g_bc, g_bc), _dot(g_ac, g_ac)
        if e_ab <= e_bc and e_ab <= e_ac:
            return 1.0 - t_ab, t_ab, 0.0
        if e_bc <= e_ac:
            return 0.0, 1.0 - t_bc, t_bc
        return 1.0 - t_ac, 0.0, t_ac
    v = vb / total
    w = vc / total
    return 1.0 - v - w, v, w


@njit(cache=True)
def segment_segment(p1, q1, p2, q2):  # pragma: no cover
    """Parameters ``(s, t)`` of the closest points ``p1 + s (q1 - p1)`` and
    ``p2 + t (q2 - p2)`` of two segments (as in Ericson 2005, 5.1.9)."""
    d1 = _sub(q1, p1)
    d2 = _sub(q2, p2)
    r = _sub(p1, p2)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    if a <= 0.0 and e <= 0.0:
        return 0.0, 0.0
    if a <= 0.0:
        return 0.0, _clamp01(f / e)
    c = _dot(d1, r)
    if e <= 0.0:
        return _clamp01(-c / a), 0.0
    b = _dot(d1, d2)
    denominator = a * e - b * b
    s = _clamp01((b * f - c * e) / denominator) if denominator > 0.0 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return _clamp01(-c / a), 0.0
    if t > 1.0:
        return _clamp01((b - c) / a), 1.0
    return s, t


@njit(cache=True, inline="always")
def _corners(kind, first, second, triangles, edges):  # pragma: no cover
    """The four points of a VF (kind 0: point ``first``, then triangle
    ``second``'s) or EE (kind 1: edge ``first``'s, then edge ``second``'s) pair."""
    if kind == 0:
        return first, triangles[second, 0], triangles[second, 1], triangles[second, 2]
    return edges[first, 0], edges[first, 1], edges[second, 0], edges[second, 1]


@njit(cache=True)
def _closest(kind, i0, i1, i2, i3, x0, x1, s):  # pragma: no cover
    """Signed weights ``(w0, w1, w2, w3)`` of the pair's closest points at
    share ``s`` of the step, and the gap vector ``sum w_k x_k`` from the
    second primitive's closest point to the first's."""
    p0, p1, p2, p3 = _at(x0, x1, s, i0), _at(x0, x1, s, i1), _at(x0, x1, s, i2), _at(x0, x1, s, i3)
    if kind == 0:
        u, v, t = point_triangle(p0, p1, p2, p3)
        w = (1.0, -u, -v, -t)
    else:
        a, b = segment_segment(p0, p1, p2, p3)
        w = (1.0 - a, a, b - 1.0, -b)
    gap = (
        w[0] * p0[0] + w[1] * p1[0] + w[2] * p2[0] + w[3] * p3[0],
        w[0] * p0[1] + w[1] * p1[1] + w[2] * p2[1] + w[3] * p3[1],
        w[0] * p0[2] + w[1] * p1[2] + w[2] * p2[2] + w[3] * p3[2],
    )
    return w, gap


@njit(cache=True, inline="always")
def _contact(kind, i0, i1, i2, i3, x0, x1, s, start, thickness):  # pragma: no cover
    """Closest-point weights, unit normal (from the second primitive to the
    first) and distance (m) of a pair at share ``s`` of ``x0 -> x1``. Two
    primitives that touch have no line between them: the normal is then
    the side they came from, at ``start``; zero if that is undefined too."""
    w, gap = _closest(kind, i0, i1, i2, i3, x0, x1, s)
    distance = math.sqrt(_dot(gap, gap))
    length = distance
    if length <= 1e-9 * thickness:
        _, gap = _closest(kind, i0, i1, i2, i3, start, start, 0.0)
        length = math.sqrt(_dot(gap, gap))
        if length == 0.0:
            return w, (0.0, 0.0, 0.0), distance
    return w, (gap[0] / length, gap[1] / length, gap[2] / length), distance


@njit(cache=True, inline="always")
def _free(w, normal, ids, inv_mass, floor, free):  # pragma: no cover
    """Fill ``free`` (4,) with the inverse mass (1/kg) each corner of a pair
    takes part with, and return the pair's share ``sum w_k^2 free_k``. A
    corner the push along ``normal`` would drive into its obstacle (more
    than ~6 degrees off its surface, whose normal ``floor`` holds) takes no
    part, like a pin: else the obstacle pushes it back next step and it
    never rests."""
    share = 0.0
    for k in range(4):
        i = ids[k]
        into = w[k] * (normal[0] * floor[i, 0] + normal[1] * floor[i, 1] + normal[2] * floor[i, 2])
        free[k] = 0.0 if into < -0.1 else inv_mass[i]
        share += w[k] * w[k] * free[k]
    return share


@njit(cache=True, inline="always")
def _scale(weight, free, share):  # pragma: no cover
    """The share of a pair's change that one corner takes. A corner that
    moves the contact point only a little (a small weight, the others
    pinned) would need a large change: none changes by more than the whole."""
    if share == 0.0:
        return 0.0
    return max(-1.0, min(1.0, weight * free / share))


@njit(cache=True, inline="always")
def _crease(kind, i0, i1, i2, i3, cells):  # pragma: no cover
    """Whether a point of the pair's first primitive and one of its second
    are at most one grid step apart (``cells`` (N, 2): each point's column
    and row): two sides of a crease through those points, not two layers."""
    # VF: point i0 and corners i1-i3; EE: ends i0, i1 and ends i2, i3.
    first = (i0, i0) if kind == 0 else (i0, i1)
    second = (i1, i2, i3) if kind == 0 else (i2, i3, i3)
    for a in first:
        for b in second:
            if abs(cells[a, 0] - cells[b, 0]) <= 1 and abs(cells[a, 1] - cells[b, 1]) <= 1:
                return True
    return False


@njit(cache=True, inline="always")
def _moved_apart(kind, i0, i1, i2, i3, x0, x):  # pragma: no cover
    """Bound (m) on how much the pair's distance changed from ``x0`` to
    ``x``: the largest motion of its points relative to its first point
    (for two edges, the first edge's other end adds its own), as in
    step 2 of the module docstring."""
    d0 = _sub(x[i0], x0[i0])
    r1 = _sub(_sub(x[i1], x0[i1]), d0)
    r2 = _sub(_sub(x[i2], x0[i2]), d0)
    r3 = _sub(_sub(x[i3], x0[i3]), d0)
    m1 = math.sqrt(_dot(r1, r1))
    m23 = math.sqrt(max(_dot(r2, r2), _dot(r3, r3)))
    return max(m1, m23) if kind == 0 else m1 + m23


# -- proximity response ------------------------------------------------------------


@njit(cache=True)
def respond(
    rows, near, gaps, cells, triangles, edges, x0, x, v, start, inv_mass, floor,
    thickness, friction, dt, reach, sweeps,
):  # fmt: skip  # pragma: no cover
    """Push every pair ``rows[near]`` closer than ``thickness`` apart, in
    place on ``x`` and ``v`` (step 3 of the module docstring); no point ends
    farther than ``reach`` from ``start``, and none is pushed into the
    obstacle whose outward normal ``floor`` holds for it (zero: none).
    Two sides of one crease (points one grid step apart, ``cells`` (N, 2)
    holding each point's column and row) are kept only ``CREASE``
    thickness apart. Returns how many pair pushes there were, summed over
    the sweeps.

    A pair whose distance at ``x0`` (``gaps``, per listed pair, m), less
    how far its points have moved relative to each other since, is still
    over the thickness needs no closest-point search.

    A sweep after the first looks again only at pairs with a point that
    moved since the pair was last looked at: the others would be found as
    they were, apart, so skipping them changes nothing (a resting fold has
    a few hundred touching pairs among tens of thousands listed)."""
    ids = np.empty(4, np.int64)
    free = np.empty(4)
    contacts = 0
    clock = 1  # counts the looks; ``moved_at[i]``: the look that last moved point i
    moved_at = np.zeros(x.shape[0], np.int64)
    looked_at = np.zeros(near.shape[0], np.int64)
    for sweep in range(sweeps):
        touched = 0
        for m in range(near.shape[0]):
            n = near[m]
            kind = rows[n, 0]
            i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
            if sweep > 0:
                last = max(max(moved_at[i0], moved_at[i1]), max(moved_at[i2], moved_at[i3]))
                if last < looked_at[m]:
                    continue
            clock += 1
            looked_at[m] = clock
            # (The bound is taken a little short, so that rounding cannot
            # skip a pair the search would have found within the thickness.)
            if gaps[n] - _moved_apart(kind, i0, i1, i2, i3, x0, x) > thickness * (1.0 + 1e-9):
                continue
            w, normal, distance = _contact(kind, i0, i1, i2, i3, x, x, 0.0, x0, thickness)
            if distance >= thickness or normal[0] == normal[1] == normal[2] == 0.0:
                continue
            target = thickness
            if _crease(kind, i0, i1, i2, i3, cells):
                target = CREASE * thickness
                if distance >= target:
                    continue
            ids[0], ids[1], ids[2], ids[3] = i0, i1, i2, i3
            share = _free(w, normal, ids, inv_mass, floor, free)
            if share == 0.0:
                continue
            touched += 1
            rel = [0.0, 0.0, 0.0]
            for k in range(4):
                for a in range(3):
                    rel[a] += w[k] * v[ids[k], a]
            vn = rel[0] * normal[0] + rel[1] * normal[1] + rel[2] * normal[2]
            approach = max(0.0, -vn)
            tangent = (
                rel[0] - vn * normal[0],
                rel[1] - vn * normal[1],
                rel[2] - vn * normal[2],
            )
            slide = math.sqrt(_dot(tangent, tangent))
            limit = friction * approach
            stop = 1.0 if slide <= limit else limit / slide  # share of the slide removed
            push = target - distance
            for k in range(4):
                i = ids[k]
                scale = _scale(w[k], free[k], share)
                if scale == 0.0:
                    continue
                moved_at[i] = clock
                far2 = 0.0
                for a in range(3):
                    dv = approach * normal[a] - stop * tangent[a]
                    v[i, a] += scale * dv
                    x[i, a] += scale * (push * normal[a] - dt * stop * tangent[a])
                    far2 += (x[i, a] - start[i, a]) ** 2
                if far2 > reach * reach:
                    shrink = reach / math.sqrt(far2)
                    for a in range(3):
                        x[i, a] = start[i, a] + shrink * (x[i, a] - start[i, a])
        contacts += touched
        if touched == 0:
            break
    return contacts


# -- no crossing ----------------------------------------------------------------------


@njit(cache=True)
def first_touch(kind, i0, i1, i2, i3, x0, x1, margin):  # pragma: no cover
    """Share ``s`` of the step ``x0 -> x1`` at which the pair's distance may
    first fall below the margin (step 4 of the module docstring), or -1.0
    when it is proven not to."""
    _, gap = _closest(kind, i0, i1, i2, i3, x0, x1, 0.0)
    distance = math.sqrt(_dot(gap, gap))
    return _advance(kind, i0, i1, i2, i3, x0, x1, margin, distance)


@njit(cache=True)
def _advance(kind, i0, i1, i2, i3, x0, x1, margin, distance):  # pragma: no cover
    """:func:`first_touch` given the pair's ``distance`` (m) at ``x0``: the
    pair list holds it (:func:`pair_distances`), so the many pairs that are
    cleared at once cost no closest-point search."""
    # The distance does not change under a common translation, so motions
    # are taken relative to the first point's: a pair moving together is
    # cleared at once. This bound is the distance's Lipschitz constant in s.
    lipschitz = _moved_apart(kind, i0, i1, i2, i3, x0, x1)
    if distance <= 0.0:
        return 0.0
    eta = min(margin, 0.5 * distance)
    s = 0.0
    for _ in range(MAX_SAMPLES):
        if distance - lipschitz * (1.0 - s) > 0.5 * eta:
            return -1.0  # cannot come within eta/2 before the end
        s += (distance - 0.5 * eta) / lipschitz
        if s >= 1.0:
            return -1.0
        _, gap = _closest(kind, i0, i1, i2, i3, x0, x1, s)
        distance = math.sqrt(_dot(gap, gap))
        if distance <= eta:
            return s
    return s


@njit(cache=True)
def approaches(kind, i0, i1, i2, i3, x0, x1, margin):  # pragma: no cover
    """Whether the pair's distance along ``x0 -> x1`` may fall below the
    margin (step 4 of the module docstring). ``False`` is proven; ``True``
    may be a near miss."""
    return first_touch(kind, i0, i1, i2, i3, x0, x1, margin) >= 0.0


@njit(cache=True, parallel=True)
def _approaching(rows, near, gaps, triangles, edges, x0, x1, margin, fresh):  # pragma: no cover
    """Per pair of ``rows[near]``, whether it has a ``fresh`` point and may
    come within the margin during the step (:func:`first_touch`)."""
    out = np.zeros(near.shape[0], np.bool_)
    for m in prange(near.shape[0]):
        n = near[m]
        kind = rows[n, 0]
        i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
        if fresh[i0] or fresh[i1] or fresh[i2] or fresh[i3]:
            out[m] = _advance(kind, i0, i1, i2, i3, x0, x1, margin, gaps[n]) >= 0.0
    return out


@njit(cache=True)
def impulses(
    rows, near, gaps, triangles, edges, x0, x1, v1, inv_mass, floor, margin, fresh
):  # pragma: no cover
    """One sweep before the impact zones: for each pair of ``rows[near]``
    with a ``fresh`` point that comes within the margin during the step,
    take away the part of its relative motion (and velocity) along the line
    between the pair at that moment that brings it closer (an inelastic
    impulse, Bridson et al. 2002, section 7.4), in place on ``x1`` and
    ``v1``. Most contacts end here, each pair on its own, so fewer and
    smaller zones are needed. Like :func:`respond`, it does not drive a
    point into the obstacle whose normal ``floor`` holds for it. ``gaps``
    holds each listed pair's distance (m) at ``x0``. Returns ``(impulses,
    points moved, pairs found approaching)``."""
    moved = np.zeros(x0.shape[0], np.bool_)
    ids = np.empty(4, np.int64)
    free = np.empty(4)
    # Which pairs take part is settled before any moves: the list may hold
    # more pairs than these (they are proven apart), and a move made here
    # must not decide whether such a pair is looked at.
    touching = near[_approaching(rows, near, gaps, triangles, edges, x0, x1, margin, fresh)]
    found = touching.shape[0]
    count = 0
    for n in touching:
        kind = rows[n, 0]
        i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
        s = _advance(kind, i0, i1, i2, i3, x0, x1, margin, gaps[n])
        if s < 0.0:
            continue
        w, normal, _ = _contact(kind, i0, i1, i2, i3, x0, x1, s, x0, margin)
        if normal[0] == normal[1] == normal[2] == 0.0:
            continue
        ids[0], ids[1], ids[2], ids[3] = i0, i1, i2, i3
        share = _free(w, normal, ids, inv_mass, floor, free)
        closing = 0.0
        speed = 0.0
        for k in range(4):
            i = ids[k]
            for a in range(3):
                closing += w[k] * (x1[i, a] - x0[i, a]) * normal[a]
                speed += w[k] * v1[i, a] * normal[a]
        if share == 0.0 or closing >= 0.0:
            continue
        count += 1
        for k in range(4):
            i = ids[k]
            scale = _scale(w[k], free[k], share)
            if scale == 0.0:
                continue
            moved[i] = True
            for a in range(3):
                x1[i, a] -= scale * closing * normal[a]
                if speed < 0.0:
                    v1[i, a] -= scale * speed * normal[a]
    return count, moved, found


@njit(cache=True)
def _root(parent, i):  # pragma: no cover
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def _one_zone(i0, i1, i2, i3, zoned, parent, dirty):  # pragma: no cover
    """Whether all four points are in one zone that has not changed since
    it last moved: they then moved by one translation, so the pair keeps
    the distance it started with and cannot approach (what
    :func:`approaches` would find, without its cost)."""
    if not (zoned[i0] and zoned[i1] and zoned[i2] and zoned[i3]):
        return False
    root = _root(parent, i0)
    if dirty[root]:
        return False
    return _root(parent, i1) == root and _root(parent, i2) == root and _root(parent, i3) == root


@njit(cache=True)
def impact_zones(
    rows, near, gaps, triangles, edges, x0, x1, v1, inv_mass, margin, zones, low, high
):  # pragma: no cover
    """Join the free points of every approaching pair into a zone that moves
    as one over the step, until no pair approaches (step 4 of the module
    docstring); a zone an approach with pinned points still reaches is held
    at the start of the step. The first pass checks the pairs ``rows[near]``,
    later ones every listed pair with a point the zones moved (``gaps``:
    each listed pair's distance at ``x0``, m). ``zones``
    (from :func:`_zones`) carries the zones between calls. If a zone
    carried a point out of its box ``low``-``high``, the list may have
    missed a pair of it: the call returns unfinished, and the caller lists
    again, marks those points moved and calls once more with every listed
    pair. Returns ``(points in zones, pairs left approaching that no zone
    can clear, whether it finished)``."""
    parent, zoned, held, dirty, follow, fresh, own, own_v, outside = zones
    n_points = x0.shape[0]
    mass = np.zeros(n_points)
    sums = np.zeros((n_points, 6))
    unresolved = 0
    checked = near
    while True:
        changed = False
        stuck = 0
        for n in checked:
            kind = rows[n, 0]
            i0, i1, i2, i3 = _corners(kind, rows[n, 1], rows[n, 2], triangles, edges)
            if not (fresh[i0] or fresh[i1] or fresh[i2] or fresh[i3]):
                continue
            if _one_zone(i0, i1, i2, i3, zoned, parent, dirty):
                continue  # one translation moved all four: the distance is kept
            if _advance(kind, i0, i1, i2, i3, x0, x1, margin, gaps[n]) < 0.0:
                continue
            here = False
            first = -1
            for i in (i0, i1, i2, i3):
                if inv_mass[i] <= 0.0:
                    continue
                root = _root(parent, i)
                if not zoned[i]:
                    zoned[i] = True
                    dirty[root] = True
                    here = True
                if first < 0:
                    first = root
                elif root != first:
                    parent[root] = first
                    held[first] = held[first] or held[root]
                    if follow[first] < 0:
                        follow[first] = follow[root]
                    elif follow[root] >= 0 and follow[root] != follow[first]:
                        held[first] = True  # two pins pull it: it cannot follow both
                    dirty[first] = True
                    here = True
            if not here and first >= 0:
                if dirty[first]:
                    here = True  # its zone moves as one from the next pass on
                elif not held[first]:
                    # Moving as one did not clear it: a pinned point of the
                    # pair drives into the zone. The zone first moves with
                    # that pin (its distances to it are then kept); if that
                    # fails too, it stays where it started.
                    pin = -1
                    for i in (i0, i1, i2, i3):
                        if inv_mass[i] <= 0.0:
                            pin = i
                            break
                    if pin >= 0 and follow[first] < 0:
                        follow[first] = pin
                    else:
                        held[first] = True
                    dirty[first] = True  # its pairs are checked again once it moved
                    here = True
            if here:
                changed = True
            else:
                stuck += 1
        if not changed:
            unresolved = stuck
            break
        # Each zone moves by its members' mass-weighted mean motion and
        # takes their mean velocity (momentum is kept); a zone a pin drove
        # into moves with that pin; a held zone stays where it started, at rest.
        mass[:] = 0.0
        sums[:] = 0.0
        for i in range(n_points):
            if zoned[i]:
                r = _root(parent, i)
                m = 1.0 / inv_mass[i]
                mass[r] += m
                for a in range(3):
                    sums[r, a] += m * own[i, a]
                    sums[r, 3 + a] += m * own_v[i, a]
        fresh[:] = False
        for i in range(n_points):
            if zoned[i]:
                r = _root(parent, i)
                f = follow[r]
                for a in range(3):
                    if held[r]:
                        motion, velocity = 0.0, 0.0
                    elif f >= 0:
                        motion, velocity = x1[f, a] - x0[f, a], v1[f, a]
                    else:
                        motion, velocity = sums[r, a] / mass[r], sums[r, 3 + a] / mass[r]
                    moved = x0[i, a] + motion
                    if moved != x1[i, a] or dirty[r]:
                        fresh[i] = True
                    x1[i, a] = moved
                    v1[i, a] = velocity
        dirty[:] = False
        checked = np.arange(rows.shape[0])
        for i in range(n_points):
            if fresh[i]:
                for a in range(3):
                    if x1[i, a] < low[i, a] or x1[i, a] > high[i, a]:
                        outside[i] = True
    if outside.any():  # the list may have missed pairs of these points
        return int(zoned.sum()), unresolved, False
    return int(zoned.sum()), unresolved, True
