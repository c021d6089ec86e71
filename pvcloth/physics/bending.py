"""Plate bending with a physical rigidity: the cloth as a thin Kirchhoff plate.

A thin sheet of bending rigidity ``B`` (N m) stores
``E = B/2 * integral of (k11^2 + 2 k12^2 + k22^2) dA`` when it bends, with
``k`` the curvature tensor (a plate of Poisson ratio 0: woven fabric has no
measurable anticlastic coupling at the curvatures cloth sees). A sheet rolled
to a cylinder of curvature ``kappa`` holds ``B kappa^2 / 2`` per unit area,
and a strip bent in its plane obeys Euler-Bernoulli beam theory with ``B``
per unit width.

**Why this energy is quadratic.** When a flat sheet bends without
stretching, its second derivatives ``x_uu``, ``x_uv``, ``x_vv`` (``u``, ``v``
the rest coordinates along the grid's rows and columns) are normal to the
surface and their lengths are the curvatures, so
``|x_uu|^2 + 2 |x_uv|^2 + |x_vv|^2`` is the integrand above. Measured this
way the energy is a quadratic form ``E = 1/2 sum_c x_c^T Q x_c`` in the
positions (one for each of x, y, z) with a **constant** matrix ``Q``: the
forces ``-Q x`` are one sparse product per step, implicit integrators add
``Q`` to their matrices once, and the energy does not change under a rigid
motion (each difference annihilates constants and linear functions). This
is the observation behind Bergou, Wardetzky, Harmon, Zorin and Grinspun,
"A Quadratic Bending Model for Inextensible Surfaces" (SGP 2006), who build
``Q`` from cotangent weights on triangles; pvcloth's grid is regular, so the
derivatives are central finite differences instead:

- ``x_uu`` at every point not on the left or right edge,
  ``(x[i-1] - 2 x[i] + x[i+1]) / hu^2``, standing for the cell around the
  point (area ``hu hv``, halved on the top and bottom rows);
- ``x_vv`` likewise along the columns;
- ``x_uv`` at the centre of every cell, from its four corners, over
  ``hu hv``.

Second differences are second-order accurate in the spacing. The points
on the edges carry no curvature of their own across the edge: the discrete
form of a free edge's zero moment. So on a sheet of ``nu`` points along
``u`` a uniform curvature is felt over ``nu - 2`` cells out of ``nu - 1``;
what converges as the grid is refined is the energy, and a clamped strip's
shape (``tests/test_bending.py`` checks both against references of their
own).

**Where it holds.** The energy is exact for bending that does not stretch
the sheet, at any rotation and any size of displacement, and for curvatures
up to about one radian per cell (a fold sharper than that is spread over
more cells by the grid anyway). Stretching is the springs' job; where the
sheet stretches unevenly this term adds a small in-plane force of order
``B / h^2`` times the strain, negligible beside a fabric's stretch
stiffness. The rest shape is flat: curved rest shapes need hinges on the
dihedral angles (Grinspun et al. 2003, Bridson et al. 2003), which pvcloth
does not have.

**Why not hinges.** The common alternative puts a hinge on every interior
edge of a triangulation, with energy in the dihedral angle (Grinspun et al.
2003, Bridson et al. 2003). Measured on this grid before choosing
(``benchmarks/bending_models.py``): with each cell split along a diagonal,
hinges hold three times as much energy for a bend along that diagonal as
for one along the rows, the columns or the other diagonal, on every grid
from 11 to 81 points a side, so a strip cut on the bias would be stiffer
than one cut along the threads. The plate's directions differ only by what
its free edges leave out (6 % at 11 points a side, 0.6 % at 81), and every
direction converges to ``B kappa^2 / 2`` (within 1.3 % at 81 points). Hinges are also
nonlinear: their Hessian changes every step (``fast_mass_spring`` could not
keep one factor), and one force evaluation in NumPy cost 68 to 91 times
the plate's sparse product.

**Its cost and its place.** ``Q`` has 13 entries per row (the grid's
biharmonic stencil). The compiled backend applies it inside the threaded
spring pass (:mod:`pvcloth.physics.kernels`), NumPy through SciPy's sparse
product; per step that costs 0.63 to 1.15 times what bending springs did
(``benchmarks/bending_cost.py``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.forces import Jacobian
from pvcloth.physics.grid import trapezoid_weights


def _second_differences(n: int, h: float) -> sp.csr_matrix:
    """``(n - 2, n)``: rows ``(1, -2, 1) / h^2`` at the interior points."""
    if n < 3:
        return sp.csr_matrix((0, n))
    rows = np.repeat(np.arange(n - 2), 3)
    cols = (np.arange(n - 2)[:, None] + np.arange(3)).ravel()
    values = np.tile([1.0, -2.0, 1.0], n - 2) / (h * h)
    return sp.csr_matrix((values, (rows, cols)), shape=(n - 2, n))


def _differences(n: int, h: float) -> sp.csr_matrix:
    """``(n - 1, n)``: rows ``(-1, 1) / h`` between neighbours."""
    return sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n)) / h


def bending_operator(shape: tuple[int, int], spacing: tuple[float, float]) -> sp.csr_matrix:
    """The constant matrix ``Q / B`` of the module docstring, ``(N, N)`` in
    1/m^2 (per unit rigidity), for a grid of ``shape = (ny, nx)`` points
    spaced ``spacing = (hu, hv)`` metres along a row and along a column, in
    the grid's point order (index ``i + nx * j``).

    Examples
    --------
    >>> import numpy as np
    >>> q = bending_operator((4, 5), (0.1, 0.2))
    >>> q.shape, bool(np.allclose(q @ np.ones(20), 0.0))  # a translation bends nothing
    ((20, 20), True)
    """
    ny, nx = shape
    hu, hv = spacing
    cell = hu * hv
    # Point weights: a point's share of the sheet along the direction the
    # difference does not run (half a cell on the border rows/columns).
    along_v = trapezoid_weights(ny) if ny > 1 else np.ones(1)
    along_u = trapezoid_weights(nx) if nx > 1 else np.ones(1)
    d_uu = sp.kron(sp.identity(ny), _second_differences(nx, hu), format="csr")
    w_uu = cell * np.kron(along_v, np.ones(max(nx - 2, 0)))
    d_vv = sp.kron(_second_differences(ny, hv), sp.identity(nx), format="csr")
    w_vv = cell * np.kron(np.ones(max(ny - 2, 0)), along_u)
    d_uv = sp.kron(_differences(ny, hv), _differences(nx, hu), format="csr")
    w_uv = np.full(d_uv.shape[0], 2.0 * cell)  # x_uv counts twice: k12 and k21
    operator = sum(d.T @ sp.diags(w) @ d for d, w in ((d_uu, w_uu), (d_vv, w_vv), (d_uv, w_uv)))
    operator = sp.csr_matrix(operator)
    operator.sum_duplicates()
    operator.sort_indices()
    return operator


class PlateBending:
    """Bending of the sheet as a thin plate of rigidity ``B`` (N m): the force
    term of the module docstring.

    Parameters
    ----------
    shape : (int, int)
        ``(ny, nx)`` of the grid.
    spacing : (float, float)
        Rest distance between neighbours along a row and along a column (m).
    rigidity : float
        ``B`` in N m (newton metres per metre of width bent).

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix, shape (N, N)
        ``Q`` in N/m: the energy is ``1/2 sum_c x_c^T Q x_c`` over the three
        coordinates and the force ``-Q x``.
    """

    name = "plate bending"

    def __init__(self, shape: tuple[int, int], spacing: tuple[float, float], rigidity: float):
        self.shape = tuple(shape)
        self.spacing = tuple(spacing)
        # Fixed for the run: the cloth is not a live key (a new rigidity is
        # a new model, whose plan and fast_mass_spring factor follow it).
        self.rigidity = float(rigidity)
        self.matrix = (self.rigidity * bending_operator(self.shape, self.spacing)).tocsr()
        self._hessian = None

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None:
        """Add ``-Q x`` (N) to ``f`` ``(N, 3)``."""
        f -= self.matrix @ x

    def potential_energy(self, x: np.ndarray) -> float:
        """``1/2 sum_c x_c^T Q x_c`` in joules."""
        # Q annihilates constants: taken from the centre, a flat sheet far
        # from the origin gives zero, not the round-off of large products.
        y = x - x.mean(axis=0)
        return 0.5 * float(np.vdot(y, self.matrix @ y))

    def hessian(self) -> sp.csr_matrix:
        """``Q`` for every coordinate: ``(3N, 3N)`` in the point-major order
        of the other Jacobians (made once)."""
        if self._hessian is None:
            self._hessian = sp.kron(self.matrix, sp.identity(3), format="csr")
        return self._hessian

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]:
        return -self.hessian(), None

    def describe(self) -> str:
        return f"plate bending, rigidity {self.rigidity:g} N m"
