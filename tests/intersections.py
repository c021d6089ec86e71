"""An independent check that a cloth does not pass through itself.

Written for the self-collision tests, separately from any code under test
and as plainly as possible: every pair of the grid's triangles that share
no vertex is tested, after a bounding-box cull, by crossing each edge of
one with the other (two triangles in general position intersect exactly
when an edge of one of them crosses the other). Candidate pairs come from
SciPy's k-d tree on the triangles' centroids, within twice the largest
triangle's reach (a bound that holds for any shape; checked against every
pair in ``tests/test_intersections.py``). No continuous collision
detection: plain, and hard to get wrong.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def grid_triangles(nx: int, ny: int) -> np.ndarray:
    """The two triangles of every cell of an ``nx x ny`` point grid (point
    ``i + nx * j``), as an ``(2 (nx-1) (ny-1), 3)`` index array."""
    i, j = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), indexing="ij")
    a = (i + nx * j).ravel()
    b, c, d = a + 1, a + nx, a + nx + 1
    return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def _segments_cross(p, q, a, b, c, eps=1e-12) -> np.ndarray:
    """Whether each segment ``p -> q`` crosses triangle ``a b c`` (rows
    paired; Moller and Trumbore 1997, "Fast, minimum storage ray-triangle
    intersection", with the ray's parameter kept within the segment)."""
    direction = q - p
    e1, e2 = b - a, c - a
    h = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(det) > eps  # a segment parallel to the plane does not cross it
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = p - a
    u = inv * np.einsum("ij,ij->i", s, h)
    qv = np.cross(s, e1)
    v = inv * np.einsum("ij,ij->i", direction, qv)
    t = inv * np.einsum("ij,ij->i", e2, qv)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def _candidates(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(k, l)`` (``k < l``) of triangles that may touch: any
    point of a triangle lies within ``R`` of its centroid (``R`` its farthest
    corner), so two triangles that touch have centroids at most
    ``R_k + R_l <= 2 max R`` apart; SciPy's k-d tree lists those pairs.
    Their boxes must overlap too."""
    centroids = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centroids[:, None], axis=2).max()
    pairs = cKDTree(centroids).query_pairs(2.0 * radius * (1.0 + 1e-9), output_type="ndarray")
    k, m = pairs[:, 0], pairs[:, 1]
    low, high = corners.min(axis=1), corners.max(axis=1)
    overlap = np.all((low[k] <= high[m]) & (low[m] <= high[k]), axis=1)
    return k[overlap], m[overlap]


def intersecting_pairs(positions: np.ndarray, triangles: np.ndarray, candidates=None):
    """Index pairs ``(k, l)`` (``k < l``) of triangles that share no vertex and
    intersect, sorted. ``positions`` (N, 3) in metres, ``triangles`` (T, 3);
    ``candidates`` ``(k, l)`` arrays of the pairs to test (default: those
    :func:`_candidates` finds)."""
    corners = positions[triangles]  # (T, 3, 3)
    k, m = _candidates(corners) if candidates is None else candidates
    k, m = np.minimum(k, m), np.maximum(k, m)
    shared = (triangles[k][:, :, None] == triangles[m][:, None, :]).any(axis=(1, 2))
    k, m = k[~shared], m[~shared]
    hit = np.zeros(k.size, bool)
    for one, other in ((k, m), (m, k)):
        a, b, c = (corners[other][:, n] for n in range(3))
        for e in range(3):
            p, q = corners[one][:, e], corners[one][:, (e + 1) % 3]
            hit |= _segments_cross(p, q, a, b, c)
    found = np.stack([k[hit], m[hit]], axis=1)
    return found[np.lexsort((found[:, 1], found[:, 0]))]


def count_self_intersections(positions: np.ndarray, resolution: tuple[int, int]) -> int:
    """How many pairs of a grid cloth's triangles pass through each other."""
    return len(intersecting_pairs(positions, grid_triangles(*resolution)))
