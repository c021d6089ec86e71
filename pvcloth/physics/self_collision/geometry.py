"""Closest points between a point and a triangle and between two segments,
at a moment of a step, and the small helpers the response and the
continuous check share (3-vectors as tuples: values, never allocated)."""

from __future__ import annotations

import math

import numpy as np

from pvcloth.physics.self_collision._compiled import njit

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


@njit(cache=True)
def linearise(pairs, triangles, edges, cells, x, inv_mass, thickness, crease):  # pragma: no cover
    """Each pair ``(kind, first, second)`` of ``pairs`` (``(P, 3)``) fixed
    at ``x``: its corners (``(P, 4)``), closest-point weights (``(P, 4)``,
    the first primitive's positive), unit direction from the second
    primitive's closest point to the first's (``(P, 3)``), the distance it
    is to be kept at (m, ``(P,)``: the ``thickness``, ``crease`` times it
    across a crease) and its effective
    mass (kg, ``(P,)``: ``1 / sum_k w_k^2 / m_k``; zero when no corner may
    move, or when the primitives touch and leave no side). Along that
    fixed direction with those fixed weights, a pair's distance is linear
    in the positions: ``sum_k w_k n . x_k``."""
    count = pairs.shape[0]
    corners = np.empty((count, 4), np.int64)
    weights = np.empty((count, 4))
    direction = np.zeros((count, 3))
    target = np.empty(count)
    mass = np.zeros(count)
    for n in range(count):
        kind = pairs[n, 0]
        i0, i1, i2, i3 = _corners(kind, pairs[n, 1], pairs[n, 2], triangles, edges)
        w, gap = _closest(kind, i0, i1, i2, i3, x, x, 0.0)
        corners[n, 0], corners[n, 1], corners[n, 2], corners[n, 3] = i0, i1, i2, i3
        share = 0.0
        for k in range(4):
            weights[n, k] = w[k]
            share += w[k] * w[k] * inv_mass[corners[n, k]]
        length = math.sqrt(_dot(gap, gap))
        target[n] = (crease if _crease(kind, i0, i1, i2, i3, cells) else 1.0) * thickness
        if share == 0.0 or length <= 1e-9 * thickness:
            continue
        mass[n] = 1.0 / share
        for a in range(3):
            direction[n, a] = gap[a] / length
    return corners, weights, direction, target, mass
