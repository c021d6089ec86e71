"""No crossing: conservative advancement finds the first touch of each pair
over a step, and inelastic impulses stop approaching pairs."""

from __future__ import annotations

import math

import numpy as np

from pvcloth.physics.self_collision._compiled import njit, prange
from pvcloth.physics.self_collision.geometry import (
    _closest,
    _contact,
    _corners,
    _dot,
    _free,
    _moved_apart,
    _scale,
)

#: Conservative advancement gives up after this many samples of one pair and
#: reports an approach (an impact zone: safe, only less smooth).
MAX_SAMPLES = 100


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
