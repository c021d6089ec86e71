"""L-BFGS's memory and its two-loop recursion, on a prefactorised first Hessian.

The fast implicit integrators (:mod:`pvcloth.physics.integrators.fast_mass_spring`)
minimise a step's energy whose Hessian the constant global matrix ``A``
approximates. L-BFGS (Nocedal and Wright, *Numerical Optimization*,
algorithm 7.4) improves on ``A`` with the last few moves ``s = x_k+1 -
x_k`` and gradient changes ``y = g_k+1 - g_k``: the direction ``d = -H g``
is two loops over the remembered pairs around one solve with ``A``. As Liu,
Bouaziz and Kavan (2017) note, with no pairs that direction is one plain
local/global iteration.

:class:`Memory` also keeps ``A s`` for each pair, so that ``A d`` comes out
of the same loops (``A`` times the solve's answer is its right-hand side):
the caller then knows ``A x`` along its iterates without multiplying by
``A``. The loops run compiled (numba) when the model's springs do, in NumPy
otherwise; both are the same sums (tested).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pvcloth.physics.kernels import FASTMATH, warm

try:  # numba is a dependency, but the NumPy path must work without it
    from numba import njit
except ImportError:  # pragma: no cover - exercised only where numba is missing
    njit = None


class Memory:
    """The last ``size`` pairs of an L-BFGS run on ``n`` points.

    Attributes
    ----------
    moves, changes, products : numpy.ndarray
        Per slot, shape (size + 1, N * 3): a move ``s`` (m), the gradient's
        change ``y`` over it and ``A s`` (the gradient's units); one slot
        more than ``size``, so a new pair is written into a free slot and
        looked at before it replaces the oldest.
    inverse_curvatures : numpy.ndarray
        ``1 / (s . y)`` per slot, shape (size,).
    slots : list of int
        The slots in use, oldest pair first.
    """

    def __init__(self, size: int, n: int):
        self.size = size
        self.moves = np.empty((size + 1, 3 * n))
        self.changes = np.empty((size + 1, 3 * n))
        self.products = np.empty((size + 1, 3 * n))
        self.inverse_curvatures = np.empty(size + 1)
        self._weights = np.empty(size + 1)
        self.slots: list[int] = []

    def clear(self) -> None:
        """Forget every pair (the next direction is a plain iteration's)."""
        self.slots.clear()

    def remember(self, x0, x1, g0, g1, p0, p1) -> bool:
        """Keep the pair from ``x0`` to ``x1`` (gradients ``g0``, ``g1``,
        products with ``A`` ``p0``, ``p1``; all ``(N, 3)``), in place of the
        oldest when full; whether it was kept (only a pair with ``s . y >
        0``, which keeps the estimate positive definite: a rejected pair
        leaves the kept ones as they were)."""
        if self.size == 0:
            return False
        slot = next(k for k in range(self.size + 1) if k not in self.slots)
        move, change = self.moves[slot], self.changes[slot]
        np.subtract(x1.ravel(), x0.ravel(), out=move)
        np.subtract(g1.ravel(), g0.ravel(), out=change)
        curvature = float(np.dot(move, change))
        if not curvature > 0.0:
            return False
        np.subtract(p1.ravel(), p0.ravel(), out=self.products[slot])
        self.inverse_curvatures[slot] = 1.0 / curvature
        if len(self.slots) == self.size:
            self.slots.pop(0)
        self.slots.append(slot)
        return True

    def direction(
        self,
        gradient: np.ndarray,
        solve: Callable[[np.ndarray, np.ndarray], None],
        fixed: np.ndarray,
        direction: np.ndarray,
        product: np.ndarray,
        compiled: bool,
    ) -> None:
        """``direction = -H gradient`` and ``product = A direction`` (all
        ``(N, 3)``), ``H`` the inverse Hessian estimate on ``A^-1``;
        ``solve(rhs, out)`` solves with ``A``, whose ``fixed`` rows are
        identity rows that stay put."""
        order = np.array(self.slots[::-1], dtype=np.int64)  # newest first
        q = product  # the right-hand side is built where A d will be
        np.copyto(q, gradient)
        if compiled and _LOOPS is not None:
            loops = tuple(warm(loop) for loop in _LOOPS)
        else:
            loops = _LOOPS_NUMPY
        loops[0](q.ravel(), self.moves, self.changes, self.inverse_curvatures, order, self._weights)
        q[fixed] = 0.0
        solve(q, direction)  # A direction = q: A d starts as q
        loops[1](
            direction.ravel(),
            q.ravel(),
            self.moves,
            self.changes,
            self.products,
            self.inverse_curvatures,
            order[::-1].copy(),
            self._weights,
        )
        np.negative(direction, out=direction)
        np.negative(product, out=product)


def _backward(q, moves, changes, inverse_curvatures, order, weights):
    """The first loop, newest pair first: ``a = s.q / (s.y)``, ``q -= a y``."""
    n = q.size
    for j in range(order.size):
        i = order[j]
        total = 0.0
        for t in range(n):
            total += moves[i, t] * q[t]
        a = total * inverse_curvatures[i]
        weights[i] = a
        for t in range(n):
            q[t] -= a * changes[i, t]


def _forward(r, p, moves, changes, products, inverse_curvatures, order, weights):
    """The second loop, oldest pair first: ``c = a - y.r / (s.y)``, ``r +=
    c s`` and, alongside, ``p += c A s`` (so ``p`` stays ``A r``)."""
    n = r.size
    for j in range(order.size):
        i = order[j]
        total = 0.0
        for t in range(n):
            total += changes[i, t] * r[t]
        c = weights[i] - total * inverse_curvatures[i]
        for t in range(n):
            r[t] += c * moves[i, t]
            p[t] += c * products[i, t]


def _backward_numpy(q, moves, changes, inverse_curvatures, order, weights):
    """:func:`_backward` in NumPy."""
    for i in order:
        weights[i] = inverse_curvatures[i] * np.dot(moves[i], q)
        q -= weights[i] * changes[i]


def _forward_numpy(r, p, moves, changes, products, inverse_curvatures, order, weights):
    """:func:`_forward` in NumPy."""
    for i in order:
        c = weights[i] - inverse_curvatures[i] * np.dot(changes[i], r)
        r += c * moves[i]
        p += c * products[i]


_LOOPS_NUMPY = (_backward_numpy, _forward_numpy)
_LOOPS = (
    None
    if njit is None
    else tuple(njit(fastmath=FASTMATH, cache=True, nogil=True)(f) for f in (_backward, _forward))
)
