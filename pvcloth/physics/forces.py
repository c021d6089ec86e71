"""Force terms. Each adds its forces into a shared ``(N, 3)`` array.

A term is a small object with one job. The model holds only the terms its
scene asks for, so a scene without, say, wind never pays for it. The springs
are in :mod:`pvcloth.physics.springs`. Every term offers:

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
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.topology import CELL_TRIANGLES

#: Lengths below this count as zero: a spring between coincident points (or
#: a triangle of no area) has no direction, so it exerts no force instead of
#: producing NaN.
TINY_LENGTH = 1e-12


#: A sparse ``(3N, 3N)`` Jacobian block, or ``None`` for a zero one.
Jacobian = sp.csr_matrix | None


class ForceTerm(Protocol):
    """What every force term offers (see the module docstring); springs
    (:class:`pvcloth.physics.springs.Springs`) are one."""

    name: str

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None: ...

    def potential_energy(self, x: np.ndarray) -> float: ...

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]: ...

    def describe(self) -> str: ...


@dataclass
class Gravity:
    """Uniform gravity: ``f += m g``."""

    acceleration: np.ndarray  # (3,), m/s^2
    mass: np.ndarray  # (N,), kg
    name: str = "gravity"

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None:
        f += self.mass[:, None] * self.acceleration

    def potential_energy(self, x: np.ndarray) -> float:
        return float(-(self.mass @ x) @ self.acceleration)

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]:
        return None, None

    def describe(self) -> str:
        return "gravity ({:g}, {:g}, {:g}) m/s^2".format(*self.acceleration)


@dataclass
class AirDamping:
    """Linear drag on absolute velocity: ``f -= gamma m v``."""

    rate: float  # gamma, 1/s
    mass: np.ndarray  # (N,), kg
    name: str = "air damping"

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None:
        f -= (self.rate * self.mass)[:, None] * v

    def potential_energy(self, x: np.ndarray) -> float:
        return 0.0

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]:
        diag = np.repeat(-self.rate * self.mass, 3)
        return None, sp.diags(diag, format="csr")

    def describe(self) -> str:
        return f"air damping {self.rate:g} 1/s"


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
    of the grid, so no scatter. The compiled backend computes the same sums
    triangle by triangle (:func:`pvcloth.physics.kernels.wind_forces`). The
    term gives no Jacobian: implicit integrators treat it explicitly.

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

    #: The two triangles of a cell, as (row, column) offsets of corners
    #: (sliced from the whole grid at once, faster than index lists).
    TRIANGLES = CELL_TRIANGLES

    def __post_init__(self):
        self.velocity = np.array(self.mean_velocity, dtype=float)
        self._gusts: tuple = (None, 0.0, 0.0)  # (period, its two values): _gust_values

    @classmethod
    def from_spec(cls, spec, shape) -> Wind:
        """The term a :class:`~pvcloth.WindSpec` describes."""
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
        a, b = self._gust_values(k)
        blend = 0.5 - 0.5 * math.cos(math.pi * (phase - k))
        return 1.0 + self.gust * float(a + (b - a) * blend)

    def _gust_values(self, k: int) -> tuple[float, float]:
        """The uniform values at the start and end of gust period ``k``,
        each from its own seeded generator; the last period's are kept (a
        generator costs tens of microseconds, and steps ask every time)."""
        if self._gusts[0] != k:
            a, b = (
                float(np.random.default_rng([self.seed, k + n]).uniform(-1.0, 1.0)) for n in (0, 1)
            )
            self._gusts = (k, a, b)
        return self._gusts[1], self._gusts[2]

    def set_time(self, t: float) -> None:
        """Use the wind of time ``t`` until told otherwise."""
        if self.gust:
            self.velocity = self.mean_velocity * self.gust_factor(t)

    def _corners(self, a3, triangle):
        ny, nx = self.shape
        return [a3[dj : ny - 1 + dj, di : nx - 1 + di] for dj, di in triangle]

    def accumulate(self, x: np.ndarray, v: np.ndarray, f: np.ndarray) -> None:
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

    def potential_energy(self, x: np.ndarray) -> float:
        return 0.0

    def jacobians(self, x: np.ndarray, v: np.ndarray) -> tuple[Jacobian, Jacobian]:
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
