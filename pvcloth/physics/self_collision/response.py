"""The proximity response: pairs closer than the thickness pushed apart with
friction, in sweeps."""

from __future__ import annotations

import math

import numpy as np

from pvcloth.physics.self_collision._compiled import njit
from pvcloth.physics.self_collision.geometry import (
    _contact,
    _corners,
    _crease,
    _dot,
    _free,
    _moved_apart,
    _scale,
)

#: Two sides of one crease (a pair with points one grid step apart) are
#: kept this share of the thickness apart, not the whole: a fold of one
#: cell cannot open its crease that wide, and pushing it to would make
#: the crease chatter against gravity at rest. No crossing still holds.
CREASE = 0.2


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


# -- friction of pairs a solve held ------------------------------------------------


@njit(cache=True)
def rub(corners, weights, direction, pushed, x, v, inv_mass, friction, lever):  # pragma: no cover
    """Coulomb friction on pairs an integrator's solve held apart with a
    penalty, in place on ``x`` (m) and ``v`` (m/s), one Gauss-Seidel sweep:
    each pair's relative tangential velocity ``sum_k w_k v_k`` (corners
    ``(P, 4)``, weights ``(P, 4)``, unit normal ``direction`` ``(P, 3)``) is
    stopped while it is within ``friction`` times the normal change of
    relative velocity the push gave it over the step (``pushed``, m/s,
    ``(P,)``), and slowed by that much beyond. The change is shared by the
    corners as the proximity response shares its own, and each corner
    moves ``lever`` (s) times its change of velocity, as the solve would
    have moved it. Returns the pairs that stuck."""
    ids = np.empty(4, np.int64)
    free = np.empty(4)
    stuck = 0
    for p in range(corners.shape[0]):
        if pushed[p] <= 0.0:
            continue
        share = 0.0
        rel = [0.0, 0.0, 0.0]
        for k in range(4):
            i = corners[p, k]
            ids[k] = i
            free[k] = inv_mass[i]
            share += weights[p, k] * weights[p, k] * free[k]
            for a in range(3):
                rel[a] += weights[p, k] * v[i, a]
        if share == 0.0:
            continue
        normal = (direction[p, 0], direction[p, 1], direction[p, 2])
        vn = rel[0] * normal[0] + rel[1] * normal[1] + rel[2] * normal[2]
        tangent = (rel[0] - vn * normal[0], rel[1] - vn * normal[1], rel[2] - vn * normal[2])
        slide = math.sqrt(_dot(tangent, tangent))
        limit = friction * pushed[p]
        stop = 1.0 if slide <= limit else limit / slide
        stuck += slide <= limit
        for k in range(4):
            scale = _scale(weights[p, k], free[k], share)
            if scale == 0.0:
                continue
            i = ids[k]
            for a in range(3):
                dv = scale * stop * tangent[a]
                v[i, a] -= dv
                x[i, a] -= lever * dv
    return stuck
