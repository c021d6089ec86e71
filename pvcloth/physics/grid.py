"""Geometry of the rectangular point grid: positions, masses, neighbours.

Point ``(i, j)`` has flat index ``i + nx * j``; arrays of points are
``(ny, nx, 3)`` in C order, whose ``(N, 3)`` view is exactly the point order
of a VTK structured grid of dimensions ``(nx, ny, 1)``.
"""

from __future__ import annotations

import numpy as np

#: Grid offsets ``(di, dj)`` of each spring family. ``di >= 0`` and, when
#: ``di == 0``, ``dj > 0``, so every spring is listed once.
SPRING_OFFSETS: dict[str, tuple[tuple[int, int], ...]] = {
    "structural": ((1, 0), (0, 1)),
    "shear": ((1, 1), (1, -1)),
    "bending": ((2, 0), (0, 2)),
}


def initial_positions(cloth) -> np.ndarray:
    """Positions ``(ny, nx, 3)`` of the flat cloth described by a ClothSpec."""
    nx, ny = cloth.resolution
    width, height = cloth.size
    u = (np.arange(nx) / (nx - 1) - 0.5) * width
    w = (np.arange(ny) / (ny - 1) - 0.5) * height
    uu, ww = np.meshgrid(u, w, indexing="xy")  # shape (ny, nx): x fastest
    x = np.zeros((ny, nx, 3))
    x[..., 0] = uu
    if cloth.orientation == "vertical":
        x[..., 2] = ww
    else:
        x[..., 1] = ww
    x += np.asarray(cloth.center)
    return x


def trapezoid_weights(n: int) -> np.ndarray:
    """Weights 1 inside and 1/2 at both ends: the share of a cell strip."""
    weights = np.ones(n)
    weights[[0, -1]] = 0.5
    return weights


def lumped_masses(cloth) -> np.ndarray:
    """Point masses ``(ny, nx)`` that sum to the cloth's mass, lumped by area."""
    nx, ny = cloth.resolution
    area = np.outer(trapezoid_weights(ny), trapezoid_weights(nx))
    return cloth.mass * area / area.sum()


def pair_slices(offset: tuple[int, int], shape: tuple[int, int]):
    """Slices ``(a, b)`` such that ``x[a]`` and ``x[b]`` are the two ends of
    every spring with grid offset ``(di, dj)`` on a ``(ny, nx)`` grid."""
    di, dj = offset
    ny, nx = shape

    def ends(d, n):
        return (slice(0, n - d), slice(d, n)) if d >= 0 else (slice(-d, n), slice(0, n + d))

    (ai, bi), (aj, bj) = ends(di, nx), ends(dj, ny)
    return (aj, ai), (bj, bi)


def border_factor(offset: tuple[int, int], shape: tuple[int, int]) -> np.ndarray:
    """Stiffness share of each spring of one offset: 1/2 for springs lying
    along the border (they stand for half a strip), 1 elsewhere."""
    di, dj = offset
    ny, nx = shape
    a, _ = pair_slices(offset, shape)
    factor = np.ones((ny, nx))
    if dj == 0:  # springs along x: half on the first and last rows
        factor *= trapezoid_weights(ny)[:, None]
    elif di == 0:  # springs along y: half on the first and last columns
        factor *= trapezoid_weights(nx)[None, :]
    return factor[a]


def point_stretch(x: np.ndarray, rest: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Local stretch of every point: the mean, over the grid edges that meet
    at the point (2 to 4), of current length over rest length.

    Parameters
    ----------
    x, rest : ndarray, shape (N, 3)
        Current and rest positions in metres, flat index ``i + nx * j``.
    shape : (int, int)
        ``(ny, nx)``.

    Returns
    -------
    ndarray, shape (N,)
        1 where the cloth is at its rest length, above 1 where it is
        stretched, below 1 where it is compressed (dimensionless).

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.grid import point_stretch
    >>> rest = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> point_stretch(rest * [2, 1, 1], rest, (2, 2))  # twice as wide
    array([1.5, 1.5, 1.5, 1.5])
    """
    ny, nx = shape
    x, rest = x.reshape(ny, nx, 3), rest.reshape(ny, nx, 3)
    total = np.zeros((ny, nx))
    count = np.zeros((ny, nx))
    for a, b in (pair_slices((1, 0), shape), pair_slices((0, 1), shape)):
        ratio = np.linalg.norm(x[b] - x[a], axis=-1) / np.linalg.norm(rest[b] - rest[a], axis=-1)
        for end in (a, b):
            total[end] += ratio
            count[end] += 1
    return (total / count).ravel()
