"""Hooke springs with dashpots over the grid: the one spring table that
forces, Jacobians, compiled kernels and integrators read.

A family (structural, shear or bending) is a :class:`Springs` force term made
of :class:`SpringGroup` s, one per grid offset. A group's springs join every
point ``(i, j)`` to ``(i + di, j + dj)``, so both ends are strided views of
the position array (no Python loop over springs and no scatter-add in the
NumPy forces). :meth:`Springs.table` gives the same springs as flat
per-spring arrays (:class:`SpringTable`) for code that wants a list of
springs (Jacobians, Liu et al.'s solver, descriptions).

Constants change only through :meth:`Springs.set_constants`, which derives
every spring's stiffness and damping from the family's per-cloth values the
same way the build did, so a model edited mid-run and one built afresh from
the edited scene hold identical numbers (a resumed checkpoint repeats the
live run bit for bit).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.forces import TINY_LENGTH, Jacobian
from pvcloth.physics.grid import SPRING_OFFSETS, border_factor, pair_slices


@dataclass
class SpringGroup:
    """All springs of one grid offset.

    Attributes
    ----------
    offset : (int, int)
        ``(di, dj)``: end b is ``di`` points along a row and ``dj`` rows
        from end a.
    a, b : (slice, slice)
        ``(rows, columns)`` slices of a ``(ny, nx, ...)`` grid array that
        select ends a and b of every spring of the group.
    rest : ndarray, shape (rows, cols)
        Rest lengths in metres.
    share : ndarray, shape (rows, cols)
        Each spring's weight relative to the family's per-cloth constants
        (aspect ratio of the cell it stands for, halved on borders).
    stiffness : ndarray, shape (rows, cols)
        ``k`` per spring in N/m: the family's stiffness times ``share``.
    damping : ndarray, shape (rows, cols)
        ``c`` per spring in N s/m: the family's damping times ``share``.
    ia, ib : ndarray of int, shape (rows * cols,)
        Flat point indices of ends a and b.
    """

    offset: tuple[int, int]
    a: tuple[slice, slice]
    b: tuple[slice, slice]
    rest: np.ndarray
    share: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    ia: np.ndarray
    ib: np.ndarray


@dataclass(frozen=True)
class SpringTable:
    """Springs as flat arrays, one entry per spring (``S`` springs).

    Attributes
    ----------
    a, b : ndarray of int, shape (S,)
        Flat point indices of the two ends.
    rest : ndarray, shape (S,)
        Rest lengths in metres.
    stiffness : ndarray, shape (S,)
        N/m.
    damping : ndarray, shape (S,)
        N s/m.
    """

    a: np.ndarray
    b: np.ndarray
    rest: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray

    @classmethod
    def join(cls, tables: list[SpringTable]) -> SpringTable:
        """One table holding the springs of ``tables`` in order."""
        if not tables:
            empty = np.zeros(0)
            return cls(np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp), empty, empty, empty)
        return cls(
            *(
                np.concatenate([getattr(t, name) for t in tables])
                for name in cls.__dataclass_fields__
            )
        )

    @property
    def count(self) -> int:
        return self.a.size


@dataclass
class Springs:
    """One family of Hooke springs with dashpots over the grid.

    The force on end ``a`` of a spring from ``a`` to ``b`` is
    ``k (L - L0) u + c ((v_b - v_a) . u) u`` with ``L = |x_b - x_a|`` and
    ``u = (x_b - x_a) / L``: a stretched spring pulls its ends together.
    End ``b`` gets the opposite force, so internal forces sum to zero.

    Attributes
    ----------
    family : str
        ``"structural"``, ``"shear"`` or ``"bending"``.
    shape : (int, int)
        ``(ny, nx)`` of the grid.
    groups : list of SpringGroup
        One per grid offset that fits the grid.
    """

    family: str
    shape: tuple[int, int]
    groups: list[SpringGroup] = field(default_factory=list)
    name: str = "springs"
    _pattern: BlockPattern | None = field(default=None, repr=False, compare=False)
    _table: SpringTable | None = field(default=None, repr=False, compare=False)

    @classmethod
    def build(
        cls,
        family: str,
        positions: np.ndarray,
        stiffness: float,
        damping: float,
        spacing: tuple[float, float],
    ) -> Springs:
        """The family's springs on a grid at rest.

        Parameters
        ----------
        family : str
            ``"structural"``, ``"shear"`` or ``"bending"``.
        positions : ndarray, shape (ny, nx, 3)
            Rest configuration in metres; rest lengths are taken from it.
        stiffness, damping : float
            Per-cloth constants of the family, N/m and N s/m (see
            :class:`pvcloth.SpringSpec`).
        spacing : (float, float)
            Grid spacing ``(hx, hy)`` in metres.
        """
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
            share = np.broadcast_to(share, rest.shape).copy()
            groups.append(
                SpringGroup(
                    (di, dj),
                    a,
                    b,
                    rest,
                    share,
                    share.copy(),
                    share.copy(),
                    index[a].ravel(),
                    index[b].ravel(),
                )
            )
        springs = cls(family=family, shape=(ny, nx), groups=groups, name=f"{family} springs")
        springs.set_constants(stiffness, damping)
        return springs

    def set_constants(self, stiffness: float, damping: float) -> None:
        """Give the family new per-cloth constants (N/m, N s/m): every
        spring's are these times its :attr:`SpringGroup.share`."""
        for group in self.groups:
            np.multiply(group.share, stiffness, out=group.stiffness)
            np.multiply(group.share, damping, out=group.damping)
        self._table = None

    @property
    def count(self) -> int:
        """Number of springs in this family."""
        return sum(g.rest.size for g in self.groups)

    @property
    def damped(self) -> bool:
        return any(np.any(g.damping) for g in self.groups)

    def table(self) -> SpringTable:
        """The family's springs as flat arrays (kept until the constants change)."""
        if self._table is None:
            self._table = SpringTable(
                np.concatenate([g.ia for g in self.groups]),
                np.concatenate([g.ib for g in self.groups]),
                np.concatenate([g.rest.ravel() for g in self.groups]),
                np.concatenate([g.stiffness.ravel() for g in self.groups]),
                np.concatenate([g.damping.ravel() for g in self.groups]),
            )
        return self._table

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None:
        """Add the springs' forces (N) at ``x`` (m), ``v`` (m/s) into ``f``;
        all ``(N, 3)``."""
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

    def potential_energy(self, x: np.ndarray) -> float:
        """Elastic energy in joules at positions ``x`` (``(N, 3)``, m)."""
        x3 = x.reshape(self.shape + (3,))
        total = 0.0
        for g in self.groups:
            length = np.linalg.norm(x3[g.b] - x3[g.a], axis=-1)
            total += 0.5 * float(np.sum(g.stiffness * (length - g.rest) ** 2))
        return total

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]:
        """Force Jacobians ``(dF/dx, dF/dv)``, sparse ``(3N, 3N)``. The
        transverse (geometric) stiffness is clamped at zero for compressed
        springs, as Choi and Ko (2002) do, so that ``-dF/dx`` stays positive
        semi-definite, and the dashpots' dependence on their direction is
        left out."""
        table = self.table()
        d = x[table.b] - x[table.a]
        stiff = stiffness_blocks(d, table.rest, table.stiffness, exact=False)
        if self._pattern is None:  # the springs never change: neither does the pattern
            self._pattern = BlockPattern(table.a, table.b, x.shape[0])
        dfdx = self._pattern.assemble(stiff)
        dfdv = None
        if self.damped:
            u = d / np.maximum(np.linalg.norm(d, axis=1), TINY_LENGTH)[:, None]
            dfdv = self._pattern.assemble(
                table.damping[:, None, None] * u[:, :, None] * u[:, None, :]
            )
        return dfdx, dfdv

    def describe(self) -> str:
        k = max(float(g.stiffness.max()) for g in self.groups) if self.groups else 0.0
        return f"{self.name}: {self.count} springs, k up to {k:g} N/m"


def stiffness_blocks(
    d: np.ndarray, rest: np.ndarray, stiffness: np.ndarray, exact: bool
) -> np.ndarray:
    """Each spring's ``dF_a/dx_b`` ``(S, 3, 3)`` (N/m) for Hooke springs with
    end-to-end vectors ``d`` ``(S, 3)`` (m), ``rest`` (m) and ``stiffness``
    (N/m): ``k (u u^T + (1 - rest / L) (I - u u^T))``. Unless ``exact``,
    the transverse part is clamped at zero for compressed springs, which
    keeps ``-dF/dx`` positive semi-definite (Choi and Ko 2002); ``exact``
    keeps the true, possibly indefinite derivative."""
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, TINY_LENGTH)[:, None]
    uu = u[:, :, None] * u[:, None, :]
    transverse = 1.0 - rest / np.maximum(length, TINY_LENGTH)
    if not exact:
        transverse = np.clip(transverse, 0.0, None)
    return stiffness[:, None, None] * (uu + transverse[:, None, None] * (np.eye(3)[None] - uu))


class BlockPattern:
    """The sparsity pattern of ``dF/dx``-shaped matrices of two-point
    interactions, computed once: every later assembly is one ``bincount``
    into the CSR arrays instead of a COO-to-CSR conversion with sorting.

    Each 3x3 ``block`` is ``dF_a/dx_b``; the four blocks of a pair are
    ``(a,a) = -B, (a,b) = B, (b,a) = B, (b,b) = -B``.
    """

    def __init__(self, ia: np.ndarray, ib: np.ndarray, n_points: int):
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
