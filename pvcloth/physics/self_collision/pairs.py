"""The pair list: the broad phase (a hash grid of the points' boxes) and the
screen that keeps only the pairs a step can bring within reach."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from pvcloth.physics.self_collision._compiled import njit, prange
from pvcloth.physics.self_collision.geometry import _closest, _corners, _dot


class PairList(NamedTuple):
    """What the broad phase hands every later stage of a step (the screen,
    the response, the impulses, the zones): the pairs that may meet, and
    where and within which boxes they were listed."""

    #: (P, 3) int64: ``(kind, first, second)``, kind 0 a point and a
    #: triangle, 1 two edges; sorted.
    rows: np.ndarray
    #: (P,) m: each pair's distance at the anchor.
    gaps: np.ndarray
    #: (N, 3) m: the positions the list was built at (the step's start).
    anchor: np.ndarray
    #: (N, 3) m: the box each point must stay in for the list to hold.
    low: np.ndarray
    high: np.ndarray


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


# -- the pair list and its screen -------------------------------------------------


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
