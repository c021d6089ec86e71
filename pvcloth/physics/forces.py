"""Force terms. Each adds its forces into a shared ``(N, 3)`` array.

A term is a small object with one job. The model holds only the terms its
scene asks for, so a scene without, say, bending springs never pays for them.
Every term offers:

``accumulate(x, v, f)``
    add its forces at positions ``x`` and velocities ``v`` into ``f`` (in place);
``potential_energy(x)``
    its stored energy in joules (0 for dissipative terms);
``jacobians(x, v)``
    sparse ``(dF/dx, dF/dv)`` of shape ``(3N, 3N)`` (or ``None`` for a zero
    block), for implicit integrators and stability estimates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.grid import SPRING_OFFSETS, border_factor, pair_slices

#: Lengths below this count as zero: a spring between coincident points has
#: no direction, so it exerts no force instead of producing NaN.
TINY_LENGTH = 1e-12


@dataclass
class Gravity:
    """Uniform gravity: ``f += m g``."""

    acceleration: np.ndarray
    mass: np.ndarray  # (N,)
    name: str = "gravity"

    def accumulate(self, x, v, f) -> None:
        f += self.mass[:, None] * self.acceleration

    def potential_energy(self, x) -> float:
        return float(-(self.mass @ x) @ self.acceleration)

    def jacobians(self, x, v):
        return None, None

    def describe(self) -> str:
        return "gravity ({:g}, {:g}, {:g}) m/s^2".format(*self.acceleration)


@dataclass
class AirDamping:
    """Linear drag on absolute velocity: ``f -= gamma m v``."""

    rate: float  # gamma, 1/s
    mass: np.ndarray
    name: str = "air damping"

    def accumulate(self, x, v, f) -> None:
        f -= (self.rate * self.mass)[:, None] * v

    def potential_energy(self, x) -> float:
        return 0.0

    def jacobians(self, x, v):
        diag = np.repeat(-self.rate * self.mass, 3)
        return None, sp.diags(diag, format="csr")

    def describe(self) -> str:
        return f"air damping {self.rate:g} 1/s"


@dataclass
class _SpringGroup:
    """All springs of one grid offset: slices of both ends and constants."""

    a: tuple[slice, slice]
    b: tuple[slice, slice]
    rest: np.ndarray  # rest lengths, shape of the slice
    stiffness: np.ndarray  # k per spring (N/m)
    damping: np.ndarray  # c per spring (N s/m)
    ia: np.ndarray  # flat index of end a, per spring
    ib: np.ndarray


@dataclass
class Springs:
    """One family of Hooke springs with dashpots over the grid.

    The force on end ``a`` of a spring from ``a`` to ``b`` is
    ``k (L - L0) u + c ((v_b - v_a) . u) u`` with ``L = |x_b - x_a|`` and
    ``u = (x_b - x_a) / L``: a stretched spring pulls its ends together.
    End ``b`` gets the opposite force, so internal forces sum to zero.
    Every group of springs is a pair of strided views of the position array:
    no Python loop over springs and no scatter-add.

    Parameters
    ----------
    family : str
        ``"structural"``, ``"shear"`` or ``"bending"``.
    positions : ndarray, shape (ny, nx, 3)
        Rest configuration; rest lengths are taken from it.
    stiffness, damping : float
        Per-cloth constants of the family (see :mod:`pvcloth.scene`).
    spacing : (float, float)
        Grid spacing ``(hx, hy)`` in metres.
    """

    family: str
    shape: tuple[int, int]  # (ny, nx)
    groups: list[_SpringGroup] = field(default_factory=list)
    name: str = "springs"
    _pattern: BlockPattern | None = field(default=None, repr=False, compare=False)

    @classmethod
    def build(cls, family, positions, stiffness, damping, spacing) -> Springs:
        ny, nx, _ = positions.shape
        hx, hy = spacing
        index = np.arange(nx * ny).reshape(ny, nx)
        groups = []
        for di, dj in SPRING_OFFSETS[family]:
            if di >= nx or abs(dj) >= ny:
                continue  # grid too small for this offset
            a, b = pair_slices((di, dj), (ny, nx))
            rest = np.linalg.norm(positions[b] - positions[a], axis=-1)
            # Springs along x stand for a strip hy wide and hx long (and vice
            # versa), which makes the sheet stiffness independent of the grid.
            if dj == 0:
                scale = hy / hx
            elif di == 0:
                scale = hx / hy
            else:
                scale = 1.0
            share = scale * border_factor((di, dj), (ny, nx))
            groups.append(
                _SpringGroup(
                    a,
                    b,
                    rest,
                    stiffness * share,
                    damping * share,
                    index[a].ravel(),
                    index[b].ravel(),
                )
            )
        return cls(family=family, shape=(ny, nx), groups=groups, name=f"{family} springs")

    @property
    def count(self) -> int:
        """Number of springs in this family."""
        return sum(g.rest.size for g in self.groups)

    @property
    def damped(self) -> bool:
        return any(np.any(g.damping) for g in self.groups)

    def accumulate(self, x, v, f) -> None:
        # (N, 3) -> (ny, nx, 3) views: the arrays are C-contiguous, no copy.
        x3, v3, f3 = (arr.reshape(self.shape + (3,)) for arr in (x, v, f))
        damped = self.damped
        for g in self.groups:
            d = x3[g.b] - x3[g.a]
            length = np.sqrt(np.einsum("...k,...k->...", d, d))
            d /= np.maximum(length, TINY_LENGTH)[..., None]  # d is now u
            magnitude = g.stiffness * (length - g.rest)
            if damped:
                magnitude += g.damping * np.einsum("...k,...k->...", v3[g.b] - v3[g.a], d)
            d *= magnitude[..., None]
            f3[g.a] += d
            f3[g.b] -= d

    def potential_energy(self, x) -> float:
        x3 = x.reshape(self.shape + (3,))
        total = 0.0
        for g in self.groups:
            length = np.linalg.norm(x3[g.b] - x3[g.a], axis=-1)
            total += 0.5 * float(np.sum(g.stiffness * (length - g.rest) ** 2))
        return total

    def jacobians(self, x, v):
        """Force Jacobians. The transverse (geometric) stiffness is clamped
        at zero for compressed springs, as Choi and Ko (2002) do, so that
        ``-dF/dx`` stays positive semi-definite."""
        ia = np.concatenate([g.ia for g in self.groups])
        ib = np.concatenate([g.ib for g in self.groups])
        k = np.concatenate([g.stiffness.ravel() for g in self.groups])
        c = np.concatenate([g.damping.ravel() for g in self.groups])
        rest = np.concatenate([g.rest.ravel() for g in self.groups])
        d = x[ib] - x[ia]
        length = np.linalg.norm(d, axis=1)
        u = d / np.maximum(length, TINY_LENGTH)[:, None]
        uu = u[:, :, None] * u[:, None, :]
        transverse = np.clip(1.0 - rest / np.maximum(length, TINY_LENGTH), 0.0, None)
        eye = np.eye(3)[None]
        stiff = k[:, None, None] * (uu + transverse[:, None, None] * (eye - uu))
        if self._pattern is None:  # the springs never change: neither does the pattern
            self._pattern = BlockPattern(ia, ib, x.shape[0])
        dfdx = self._pattern.assemble(stiff)
        dfdv = self._pattern.assemble(c[:, None, None] * uu) if self.damped else None
        return dfdx, dfdv

    def describe(self) -> str:
        k = max(float(g.stiffness.max()) for g in self.groups) if self.groups else 0.0
        return f"{self.name}: {self.count} springs, k up to {k:g} N/m"


class BlockPattern:
    """The sparsity pattern of ``dF/dx``-shaped matrices of two-point
    interactions, computed once: every later assembly is one ``bincount``
    into the CSR arrays instead of a COO-to-CSR conversion with sorting.

    Each 3x3 ``block`` is ``dF_a/dx_b``; the four blocks of a pair are
    ``(a,a) = -B, (a,b) = B, (b,a) = B, (b,b) = -B``.
    """

    def __init__(self, ia, ib, n_points: int):
        rows3 = np.arange(3)
        size = 3 * n_points
        keys = []
        for p, q in ((ia, ia), (ia, ib), (ib, ia), (ib, ib)):
            r = 3 * p[:, None, None] + rows3[None, :, None]
            c = 3 * q[:, None, None] + rows3[None, None, :]
            keys.append((r * size + c).ravel())
        unique, self.slot = np.unique(np.concatenate(keys), return_inverse=True)
        self.indices = (unique % size).astype(np.int32)
        self.indptr = np.searchsorted(unique // size, np.arange(size + 1)).astype(np.int32)
        self.shape = (size, size)
        self.pairs = ia.size

    def assemble(self, blocks: np.ndarray) -> sp.csr_matrix:
        """The matrix for per-pair ``blocks`` of shape ``(pairs, 3, 3)``."""
        b = blocks.reshape(self.pairs, 9)
        values = np.concatenate([-b, b, b, -b]).ravel()
        data = np.bincount(self.slot, weights=values, minlength=self.indices.size)
        return sp.csr_matrix((data, self.indices, self.indptr), shape=self.shape)


@dataclass
class Wind:
    """Aerodynamic drag and lift of (possibly gusty) wind on each triangle.

    Each grid cell is split into two triangles. On a triangle of area ``A``
    and unit normal ``n``, with ``u`` the air velocity minus the triangle's
    mean velocity, drag is ``1/2 rho C_d A |u| (u . n) n``: only the
    component of the relative wind across the surface pushes it, and a
    triangle moving with the air feels nothing. Lift is
    ``1/2 rho C_l A |u| (u . n) (n - (n . u_hat) u_hat)``: perpendicular to
    the relative wind, of size ``1/2 rho C_l A |u|^2 sin(a) cos(a)`` at angle
    of attack ``a`` (a flat plate's lift, zero both edge-on and face-on). A
    third of the force goes to each corner. Triangle corners are strided views
    of the grid, so no scatter. The term gives no Jacobian: implicit
    integrators treat it explicitly.

    Gusts scale the wind speed by ``1 + gust * g(t)``, where ``g`` takes
    independent uniform values in ``[-1, 1]`` every ``gust_period`` seconds
    (each drawn from its own seeded generator, so the value at a time does not
    depend on the order of calls) joined by a smooth cosine ramp.
    """

    mean_velocity: np.ndarray  # air velocity without gusts (m/s)
    drag: float  # C_d
    density: float  # rho (kg/m^3)
    shape: tuple[int, int]  # (ny, nx)
    lift: float = 0.0  # C_l
    gust: float = 0.0
    gust_period: float = 0.5
    seed: int = 0
    name: str = "wind"

    #: The two triangles of cell (i, j), as (row, column) offsets of corners.
    TRIANGLES = (((0, 0), (0, 1), (1, 1)), ((0, 0), (1, 1), (1, 0)))

    def __post_init__(self):
        self.velocity = np.array(self.mean_velocity, dtype=float)

    @classmethod
    def from_spec(cls, spec, shape) -> Wind:
        """The term a :class:`~pvcloth.scene.WindSpec` describes."""
        return cls(
            np.asarray(spec.velocity, dtype=float),
            spec.drag,
            spec.density,
            shape,
            lift=spec.lift,
            gust=spec.gust,
            gust_period=spec.gust_period,
            seed=spec.seed,
        )

    def gust_factor(self, t: float) -> float:
        """Wind speed at time ``t`` relative to the mean."""
        if self.gust == 0.0:
            return 1.0
        phase = t / self.gust_period
        k = math.floor(phase)
        a, b = (np.random.default_rng([self.seed, k + n]).uniform(-1.0, 1.0) for n in (0, 1))
        blend = 0.5 - 0.5 * math.cos(math.pi * (phase - k))
        return 1.0 + self.gust * float(a + (b - a) * blend)

    def set_time(self, t: float) -> None:
        """Use the wind of time ``t`` until told otherwise."""
        if self.gust:
            self.velocity = self.mean_velocity * self.gust_factor(t)

    def _corners(self, a3, triangle):
        ny, nx = self.shape
        return [a3[dj : ny - 1 + dj, di : nx - 1 + di] for dj, di in triangle]

    def accumulate(self, x, v, f) -> None:
        x3, v3, f3 = (arr.reshape(self.shape + (3,)) for arr in (x, v, f))
        for triangle in self.TRIANGLES:
            p0, p1, p2 = self._corners(x3, triangle)
            normal = np.cross(p1 - p0, p2 - p0)  # length = 2 * area
            double_area = np.sqrt(np.einsum("...k,...k->...", normal, normal))
            unit = normal / np.maximum(double_area, TINY_LENGTH)[..., None]
            q0, q1, q2 = self._corners(v3, triangle)
            relative = self.velocity - (q0 + q1 + q2) / 3.0
            across = np.einsum("...k,...k->...", relative, unit)
            speed = np.sqrt(np.einsum("...k,...k->...", relative, relative))
            # 1/2 rho A |u| (u . n), shared by three corners.
            scale = 0.5 * self.density * (0.5 * double_area) * speed * across / 3.0
            share = (self.drag * scale)[..., None] * unit
            if self.lift:
                # n minus its part along the wind: |.| = cos(angle of attack).
                along = across / np.maximum(speed, TINY_LENGTH)
                wind_dir = relative / np.maximum(speed, TINY_LENGTH)[..., None]
                share += (self.lift * scale)[..., None] * (unit - along[..., None] * wind_dir)
            for corner in self._corners(f3, triangle):
                corner += share

    def potential_energy(self, x) -> float:
        return 0.0

    def jacobians(self, x, v):
        return None, None

    def describe(self) -> str:
        text = "wind ({:g}, {:g}, {:g}) m/s, drag coefficient {:g}".format(
            *self.mean_velocity, self.drag
        )
        if self.lift:
            text += f", lift coefficient {self.lift:g}"
        if self.gust:
            text += (
                f", gusts +/-{100 * self.gust:g} % every {self.gust_period:g} s (seed {self.seed})"
            )
        return text
