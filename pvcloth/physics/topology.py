"""The cloth grid's topology: which points make its cells, triangles and
edges, and the normals at its points. One definition for the physics
(self-collision, wind, the obstacles' drawn surfaces), the view and the
exports, so that what is drawn, exported and collided is the same surface.

Points are numbered row by row: point (row ``j``, column ``i``) of a grid of
``shape = (ny, nx)`` points is ``j * nx + i``. Cell ``(j, i)`` has the corners
``a = (j, i)``, ``b = (j, i + 1)``, ``c = (j + 1, i + 1)`` and
``d = (j + 1, i)``, counter-clockwise seen from the front (the side the
normals point to), and is split along its diagonal ``a c`` into the
triangles ``a b c`` and ``a c d``.

Examples
--------
>>> from pvcloth.physics import topology
>>> topology.quads((2, 3)).tolist()  # 2 rows of 3 points: 2 cells
[[0, 1, 4, 3], [1, 2, 5, 4]]
>>> topology.triangles((2, 3)).tolist()
[[0, 1, 4], [1, 2, 5], [0, 4, 3], [1, 5, 4]]
"""

from __future__ import annotations

import numpy as np

#: The two triangles of a cell, as (row, column) offsets of their corners
#: from ``a``: ``a b c`` and ``a c d``.
CELL_TRIANGLES = (((0, 0), (0, 1), (1, 1)), ((0, 0), (1, 1), (1, 0)))


def _corners(shape: tuple[int, int]) -> tuple[np.ndarray, ...]:
    """``a, b, c, d``: each cell's corners, cells row by row, shape (M,)."""
    ny, nx = shape
    k = np.arange(ny * nx, dtype=np.int64).reshape(ny, nx)
    return k[:-1, :-1].ravel(), k[:-1, 1:].ravel(), k[1:, 1:].ravel(), k[1:, :-1].ravel()


def quads(shape: tuple[int, int]) -> np.ndarray:
    """The cells as point indices ``a b c d``, shape ``((ny-1)(nx-1), 4)``."""
    return np.column_stack(_corners(shape))


def triangles(shape: tuple[int, int]) -> np.ndarray:
    """Every cell's first triangle (``a b c``), then every cell's second
    (``a c d``), as point indices, shape ``(2 (ny-1)(nx-1), 3)``."""
    a, b, c, d = _corners(shape)
    return np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def edges(shape: tuple[int, int]) -> np.ndarray:
    """Every edge of :func:`triangles` once: along the rows, along the
    columns, then the cells' diagonals ``a c``; shape ``(E, 2)``.

    Examples
    --------
    >>> edges((2, 2)).tolist()
    [[0, 1], [2, 3], [0, 2], [1, 3], [0, 3]]
    """
    ny, nx = shape
    k = np.arange(ny * nx, dtype=np.int64).reshape(ny, nx)
    along_rows = np.column_stack([k[:, :-1].ravel(), k[:, 1:].ravel()])
    along_columns = np.column_stack([k[:-1, :].ravel(), k[1:, :].ravel()])
    a, _, c, _ = _corners(shape)
    return np.concatenate([along_rows, along_columns, np.column_stack([a, c])])


def vtk_faces(shape: tuple[int, int]) -> np.ndarray:
    """The cells in VTK's flat face layout (``4, a, b, c, d`` per cell), for
    ``pyvista.PolyData``."""
    cells = quads(shape)
    return np.column_stack([np.full(len(cells), 4, dtype=np.int64), cells]).ravel()


def normals(x: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Unit normals at the points, shape (N, 3): at each point the sum of
    the normals of the cells around it, each the cross product of the
    cell's diagonals (so weighted by its area). A point whose cells have no
    area gets a zero vector.

    Parameters
    ----------
    x : numpy.ndarray
        Point positions (m), shape (ny * nx, 3), row by row.
    shape : tuple of int
        ``(ny, nx)``.

    Examples
    --------
    >>> import numpy as np
    >>> i, j = np.meshgrid(np.arange(3.0), np.arange(2.0))
    >>> flat = np.column_stack([i.ravel(), j.ravel(), np.zeros(6)])  # in the x-y plane
    >>> normals(flat, (2, 3))[0].tolist()
    [0.0, 0.0, 1.0]
    """
    cells = quads(shape)
    diagonals = np.cross(x[cells[:, 2]] - x[cells[:, 0]], x[cells[:, 3]] - x[cells[:, 1]])
    summed = np.zeros_like(x, dtype=float)
    for corner in range(4):
        np.add.at(summed, cells[:, corner], diagonals)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    return summed / np.where(length > 0, length, 1.0)
