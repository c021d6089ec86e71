"""The same cloth in Taichi, for side-by-side timing (an optional extra).

Taichi's well-known cloth example steps a grid with springs to the 12
neighbours with ``|di| + |dj| <= 2`` by semi-implicit Euler in Taichi
kernels. This module builds that kind of solver for pvcloth's own model: the
same springs with the same per-spring stiffness, damping and rest length
(taken from a pvcloth Model, so border springs are halved the same way),
gravity, linear air damping and pins. As in Taichi's example, stiffness,
damping and rest length are constants per neighbour offset (no per-spring
arrays to read), and the border rule (springs along the border count half)
is two integer tests. Each point gathers the forces of its springs (each
spring is evaluated from both ends: Taichi's usual parallel-friendly form).
``benchmarks/cpu_speed.py`` times it and checks it against pvcloth's own step.

Requires ``pip install taichi`` (the ``taichi`` extra); pvcloth never imports it.
"""

from __future__ import annotations

import numpy as np
import taichi as ti

from pvcloth.physics.grid import SPRING_OFFSETS

_STARTED: list = []


def init(threads: int | None = None) -> None:
    """Start Taichi's CPU backend once per process (fields choose their own
    precision, so float32 and float64 cloths can be timed side by side)."""
    if _STARTED:
        return
    # Literals default to float32: measured, this keeps the float32 cloth free
    # of float64 promotions and costs the float64 cloth nothing (its
    # constants are cast once at compile time).
    options = {"arch": ti.cpu, "default_fp": ti.f32}
    if threads:
        options["cpu_max_num_threads"] = threads
    ti.init(**options, log_level=ti.WARN)
    _STARTED.append(True)


def _offsets():
    """The 12 neighbour offsets ``(dj, di)``: each family's offsets both ways."""
    forward = [(dj, di) for family in SPRING_OFFSETS.values() for di, dj in family]
    return forward + [(-dj, -di) for dj, di in forward]


@ti.data_oriented
class TaichiCloth:
    """Semi-implicit Euler for a pvcloth model: two parallel loops per step."""

    def __init__(self, model, inv_mass, dt: float, gravity, air_damping: float, precision):
        ny, nx = model.shape
        offsets = _offsets()
        real = np.float32 if precision == "float32" else np.float64
        k, c, rest = (np.zeros(len(offsets)) for _ in range(3))
        for springs in model.springs:
            for g in springs.groups:
                dj, di = g.b[0].start - g.a[0].start, g.b[1].start - g.a[1].start
                # interior constants; border springs get half (checked in the kernel)
                inner = np.unravel_index(np.argmax(g.stiffness), g.stiffness.shape)
                for o in (offsets.index((dj, di)), offsets.index((-dj, -di))):
                    k[o], c[o], rest[o] = g.stiffness[inner], g.damping[inner], g.rest[inner]
        self.shape = (ny, nx)
        self.n_offsets = len(offsets)
        self.dt = dt
        self.air = air_damping
        self.gravity = ti.Vector(list(gravity), dt=ti.f32 if real is np.float32 else ti.f64)
        self.offset = ti.Vector.field(2, ti.i32, shape=len(offsets))
        self.offset.from_numpy(np.array(offsets, dtype=np.int32))
        fp = ti.f32 if real is np.float32 else ti.f64
        self.fp = fp
        self.k = ti.field(fp, shape=len(offsets))
        self.c = ti.field(fp, shape=len(offsets))
        self.rest = ti.field(fp, shape=len(offsets))
        self.k.from_numpy(k.astype(real))
        self.c.from_numpy(c.astype(real))
        self.rest.from_numpy(rest.astype(real))
        self.inv_mass = ti.field(fp, shape=(ny, nx))
        self.inv_mass.from_numpy(inv_mass.reshape(ny, nx).astype(real))
        self.x = ti.Vector.field(3, fp, shape=(ny, nx))
        self.v = ti.Vector.field(3, fp, shape=(ny, nx))
        self.f = ti.Vector.field(3, fp, shape=(ny, nx))
        self.real = real

    def set_state(self, x: np.ndarray, v: np.ndarray) -> None:
        ny, nx = self.shape
        self.x.from_numpy(x.reshape(ny, nx, 3).astype(self.real))
        self.v.from_numpy(v.reshape(ny, nx, 3).astype(self.real))

    def get_state(self):
        return (
            self.x.to_numpy().reshape(-1, 3).astype(float),
            self.v.to_numpy().reshape(-1, 3).astype(float),
        )

    @ti.kernel
    def step(self):
        ny, nx = self.shape
        fp = self.fp  # literals in the working precision, not promoted
        for j, i in self.x:  # forces from the old state
            total = ti.Vector.zero(fp, 3)
            for o in ti.static(range(12)):
                jn, inb = j + self.offset[o][0], i + self.offset[o][1]
                if 0 <= jn < ny and 0 <= inb < nx:
                    share = ti.cast(1.0, fp)
                    if self.offset[o][0] == 0 and (j == 0 or j == ny - 1):
                        share = ti.cast(0.5, fp)  # along x on the first or last row
                    if self.offset[o][1] == 0 and (i == 0 or i == nx - 1):
                        share = ti.cast(0.5, fp)  # along y on the first or last column
                    d = self.x[jn, inb] - self.x[j, i]
                    length = d.norm()
                    u = d / ti.max(length, ti.cast(1e-12, fp))
                    pull = self.k[o] * (length - self.rest[o])
                    pull += self.c[o] * (self.v[jn, inb] - self.v[j, i]).dot(u)
                    total += share * pull * u
            self.f[j, i] = total
        dt, air = ti.cast(self.dt, fp), ti.cast(self.air, fp)
        for j, i in self.x:  # then velocities and positions (Taichi runs the loops in order)
            w = self.inv_mass[j, i]
            if w > 0:
                self.v[j, i] += dt * (w * self.f[j, i] + self.gravity - air * self.v[j, i])
                self.x[j, i] += dt * self.v[j, i]
