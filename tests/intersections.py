"""An independent check that a cloth does not pass through itself.

Written for the self-collision tests, separately from any code under test
and as plainly as possible: every pair of the grid's triangles that share
no vertex is tested, after a bounding-box cull, by crossing each edge of
one with the other (two triangles in general position intersect exactly
when an edge of one of them crosses the other). No spatial hash, no
continuous collision detection: slow, but hard to get wrong.
"""

from __future__ import annotations

import numpy as np


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


def intersecting_pairs(positions: np.ndarray, triangles: np.ndarray, block: int = 256):
    """Index pairs ``(k, l)`` (``k < l``) of triangles that share no vertex and
    intersect. ``positions`` (N, 3) in metres, ``triangles`` (T, 3)."""
    corners = positions[triangles]  # (T, 3, 3)
    low, high = corners.min(axis=1), corners.max(axis=1)
    found = []
    for start in range(0, len(triangles), block):
        rows = np.arange(start, min(start + block, len(triangles)))
        # boxes that overlap, each pair once (l > k)
        overlap = np.all((low[rows, None] <= high[None]) & (low[None] <= high[rows, None]), axis=2)
        overlap &= np.arange(len(triangles))[None] > rows[:, None]
        k, m = np.nonzero(overlap)
        k = rows[k]
        shared = (triangles[k][:, :, None] == triangles[m][:, None, :]).any(axis=(1, 2))
        k, m = k[~shared], m[~shared]
        if k.size == 0:
            continue
        hit = np.zeros(k.size, bool)
        for one, other in ((k, m), (m, k)):
            a, b, c = (corners[other][:, n] for n in range(3))
            for e in range(3):
                p, q = corners[one][:, e], corners[one][:, (e + 1) % 3]
                hit |= _segments_cross(p, q, a, b, c)
        found.append(np.stack([k[hit], m[hit]], axis=1))
    return np.concatenate(found) if found else np.zeros((0, 2), int)


def count_self_intersections(positions: np.ndarray, resolution: tuple[int, int]) -> int:
    """How many pairs of a grid cloth's triangles pass through each other."""
    return len(intersecting_pairs(positions, grid_triangles(*resolution)))
