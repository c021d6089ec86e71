"""The self-intersection counter the self-collision tests will rely on,
checked on cases whose answer is known by construction."""

from __future__ import annotations

import numpy as np
import pytest
from intersections import count_self_intersections, grid_triangles, intersecting_pairs


def flat_grid(n: int, size: float = 1.0) -> np.ndarray:
    u = np.linspace(0.0, size, n)
    x, y = np.meshgrid(u, u, indexing="ij")
    # point i + n * j: i along x, j along y
    return np.stack([x.T.ravel(), y.T.ravel(), np.zeros(n * n)], axis=1)


def test_two_crossing_triangles_and_two_apart():
    triangles = np.array([[0, 1, 2], [3, 4, 5]])
    crossing = np.array(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.9, 0.9, 0.5]]
    )
    assert intersecting_pairs(crossing, triangles).tolist() == [[0, 1]]
    apart = crossing.copy()
    apart[3:, 2] += 2.0  # the second lifted clear of the first's plane
    assert len(intersecting_pairs(apart, triangles)) == 0
    # just past the edge: no crossing
    beside = crossing.copy()
    beside[3:] += np.array([1.0, 1.0, 0.0])
    assert len(intersecting_pairs(beside, triangles)) == 0


def test_triangles_that_share_a_vertex_are_not_counted():
    triangles = np.array([[0, 1, 2], [0, 3, 4]])
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, -1], [0.3, 0.3, 1]])
    assert len(intersecting_pairs(positions, triangles)) == 0


def test_grid_triangles_cover_every_cell_once():
    triangles = grid_triangles(4, 3)
    assert triangles.shape == (2 * 3 * 2, 3)
    positions = flat_grid(4)[: 4 * 3]
    corners = positions[triangles]
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    assert area.sum() == pytest.approx((1.0) * (2.0 / 3.0))


@pytest.mark.parametrize("n", [8, 16])
def test_a_flat_or_gently_folded_sheet_does_not_intersect(n):
    positions = flat_grid(n)
    assert count_self_intersections(positions, (n, n)) == 0
    # folded over a line with a gap: two layers 2 cm apart
    folded = positions.copy()
    far = folded[:, 0] > 0.5
    folded[far, 0] = 1.0 - folded[far, 0]
    folded[far, 2] = 0.02
    assert count_self_intersections(folded, (n, n)) == 0


@pytest.mark.parametrize("n", [8, 16])
def test_a_sheet_folded_through_itself_is_caught(n):
    """Half the sheet turned up and back down through the other half: its
    far edge strip passes from above to below the near half."""
    positions = flat_grid(n)
    far = positions[:, 0] > 0.5
    folded = positions.copy()
    folded[far, 0] = 1.0 - positions[far, 0]
    # a tilt carries the folded half from 5 cm above, at the fold, to 5 cm below
    folded[far, 2] = 0.05 - 0.2 * (positions[far, 0] - 0.5) * 2
    count = count_self_intersections(folded, (n, n))
    assert count > 0
    # moved clear above, the same folded shape is free again
    clear = folded.copy()
    clear[far, 2] += 0.3
    assert count_self_intersections(clear, (n, n)) == 0


@pytest.mark.parametrize("spread", [0.02, 0.3, 1.0])
def test_the_candidate_search_misses_no_pair_of_all_pairs(spread):
    # A 12x12 grid jittered from gently to wildly (long thin triangles
    # included): the pairs found equal those of every pair tested.
    rng = np.random.default_rng(3)
    positions = flat_grid(12) + spread * rng.standard_normal((144, 3))
    triangles = grid_triangles(12, 12)
    every = np.triu_indices(len(triangles), 1)
    expected = intersecting_pairs(positions, triangles, candidates=every)
    if spread > 0.1:
        assert len(expected) > 100
    assert np.array_equal(intersecting_pairs(positions, triangles), expected)
