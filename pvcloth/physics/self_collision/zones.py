"""Impact zones, the failsafe: points whose pairs still approach are merged
into rigid groups (union-find) that move together."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from pvcloth.physics.self_collision._compiled import njit
from pvcloth.physics.self_collision.continuous import _advance
from pvcloth.physics.self_collision.geometry import _corners


class ZoneArrays(NamedTuple):
    """What :func:`impact_zones` carries between its calls in one step,
    each an array over the points (N,): zone fields are read at a zone's
    root point."""

    #: Union-find parent of each point (itself for a root).
    parent: np.ndarray
    #: Whether the point is in a zone.
    zoned: np.ndarray
    #: Whether the zone is held at the start of the step (a pinned point's
    #: approach reaches it).
    held: np.ndarray
    #: Whether the zone grew in this pass.
    dirty: np.ndarray
    #: The pinned point the zone follows (-1: none).
    follow: np.ndarray
    #: Whether the point moved since its pairs were last checked.
    fresh: np.ndarray
    #: The point's own motion over the step before any zone (m), (N, 3).
    own: np.ndarray
    #: The point's own velocity before any zone (m/s), (N, 3).
    own_v: np.ndarray
    #: Whether a zone carried the point out of its box since the list was built.
    outside: np.ndarray


def new_zones(x0: np.ndarray, x1: np.ndarray, v1: np.ndarray) -> ZoneArrays:
    """No zones yet, for the step ``x0 -> x1`` ending at velocities ``v1``."""
    n = len(x0)
    return ZoneArrays(
        parent=np.arange(n),
        zoned=np.zeros(n, np.bool_),
        held=np.zeros(n, np.bool_),
        dirty=np.zeros(n, np.bool_),
        follow=np.full(n, -1),
        fresh=np.ones(n, np.bool_),
        own=x1 - x0,
        own_v=v1.copy(),
        outside=np.zeros(n, np.bool_),
    )


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
    each listed pair's distance at ``x0``, m). ``zones`` (a
    :class:`ZoneArrays`, from :func:`new_zones`) carries the zones between
    calls. If a zone carried a point out of its box ``low``-``high``, the
    list may have missed a pair of it: the call returns unfinished, and the caller lists
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
