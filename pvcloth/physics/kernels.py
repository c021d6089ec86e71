"""Compiled kernels (numba) for the hot loop: spring forces and the
semi-implicit Euler step.

The NumPy code in :mod:`pvcloth.physics.forces` stays the reference; these kernels
compute the same sums in a different order (equal to round-off, tested) and
are used when numba is installed, unless ``PVCLOTH_BACKEND=numpy`` or
``backend="numpy"`` asks for the pure NumPy path.

Why they are fast (``benchmarks/results/cpu_speed.md``):

- Each spring is evaluated once and added to both ends, row by row. A block
  of rows is first copied component by component (x, y, z, vx, vy, vz rows),
  so every load in the inner loop is contiguous and LLVM vectorises it
  (AVX2); this alone halved the time of the same loop on the ``(N, 3)``
  layout. The block's forces are added back at the end.
- Blocks are handled by threads in two phases (even blocks, then odd
  blocks); a block writes from the row before it to two rows after it, so
  blocks of one phase never write the same point and no atomics are needed.
- Forces, gravity, air damping and the velocity and position update are one
  pass; nothing is allocated per step: blocks work in scratch memory the
  plan holds, and the simulation hands the step a spare state to write
  (fresh memory is fresh pages: 560 page faults and half the time of a
  256x256 step went there).
- Threads come from OpenMP, chosen ahead of numba's default TBB (see
  :data:`THREADING_LAYERS`).
- Kernels are compiled on first use and cached on disk (``cache=True``), so
  a second run starts without compiling. They release the GIL
  (``nogil=True``): the window's physics thread computes while its main
  thread draws.
"""

from __future__ import annotations

import math
import os
import types

import numpy as np

from pvcloth.errors import InputError
from pvcloth.physics.forces import TINY_LENGTH
from pvcloth.physics.topology import CELL_TRIANGLES
from pvcloth.scene.validation import choice
from pvcloth.signals import deferred

try:  # numba is a dependency, but the NumPy path must work without it
    import numba
    from numba import njit, prange
except ImportError:  # pragma: no cover - exercised only where numba is missing
    numba = None

#: Threading layers in the order pvcloth prefers them. numba's own default
#: order puts TBB first whenever libtbb is installed (Debian's comes with
#: Blender, for one). Measured at 64x64 over 50 frames of the hanging scene
#: (``tests/test_kernels.py``'s MANY_FRAMES): OpenMP 21 ms per frame and
#: steady, the workqueue 94-100 ms and steady, TBB 154 ms for the first
#: frames and 465 ms for the last, its memory growing. So TBB comes last:
#: the workqueue always loads, and TBB runs only when asked for by name.
#: ``NUMBA_THREADING_LAYER`` still overrides.
THREADING_LAYERS = ["omp", "workqueue", "tbb"]
if numba is not None and "NUMBA_THREADING_LAYER_PRIORITY" not in os.environ:
    numba.config.THREADING_LAYER_PRIORITY = THREADING_LAYERS


def threading_layer() -> str | None:
    """The threading layer the threaded kernels run on (``"omp"``,
    ``"tbb"`` or ``"workqueue"``), or ``None`` before they first ran."""
    if numba is None:
        return None
    try:
        return numba.threading_layer()
    except ValueError:  # no threaded kernel has run yet
        return None


BACKENDS = ("auto", "numba", "numpy")

#: LLVM fast-math flags: reassociation and contraction for vectorising, but no
#: "no NaN / no inf" assumptions (the divergence guard looks for them).
FASTMATH = {"reassoc", "contract", "arcp", "nsz", "afn"}


def available() -> bool:
    """Whether the compiled kernels can be used (numba imports)."""
    return numba is not None


def resolve_backend(backend: str | None) -> str:
    """``"numba"`` or ``"numpy"``: what ``backend`` (or ``PVCLOTH_BACKEND``) asks
    for, with ``"auto"`` choosing numba when it is installed."""
    if backend is None:
        backend = os.environ.get("PVCLOTH_BACKEND", "auto")
    backend = choice("backend", backend, BACKENDS, error=InputError)
    if backend == "auto":
        return "numba" if available() else "numpy"
    if backend == "numba" and not available():
        raise InputError("backend", "'numba' was asked for but numba is not installed")
    return backend


class SpringPlan:
    """The model's spring groups as the kernels read them: stiffness, damping
    and rest length of group ``g`` in row ``g`` of ``(G, ny, nx)`` arrays
    (the group's own array in the top-left corner), and where each group's
    end a starts and how far end b is from it.

    These are copies, refreshed by :meth:`pvcloth.physics.model.Model.apply`
    (the one way constants change) through :meth:`refresh`.
    """

    def __init__(self, springs, shape):
        self.springs = springs
        self.shape = shape
        groups = self._groups()
        ny, nx = shape
        self.stiffness = np.zeros((len(groups), ny, nx))
        self.damping = np.zeros_like(self.stiffness)
        self.rest = np.ones_like(self.stiffness)
        starts = [(g.a[0].start, g.a[1].start, g.b[0].start, g.b[1].start) for g in groups]
        self.geometry = np.array(
            [(a0, a1, b0 - a0, b1 - a1) for a0, a1, b0, b1 in starts], dtype=np.int64
        ).reshape(-1, 4)
        self.extent = np.array([g.rest.shape for g in groups], dtype=np.int64).reshape(-1, 2)
        self.refresh()
        # Two phases of blocks, two blocks per thread and phase. A block
        # writes from one row before it (offset dj = -1) to two rows after it
        # (dj = 2), so blocks of one phase, separated by a block of at least
        # four rows, never write the same row.
        threads = numba.get_num_threads() if numba is not None else 1
        count = max(1, min(2 * threads, ny // 8))
        self.blocks = np.linspace(0, ny, 2 * count + 1).astype(np.int64)
        # Each block's working copy of its rows (6 components in, 3 forces
        # out) and one row of spring forces, allocated once: allocated per
        # call they were fresh pages at every step on big grids.
        rows = int(np.diff(self.blocks).max()) + 4
        self.scratch = np.empty((self.blocks.size - 1, 9, rows, nx))
        self.row = np.empty((self.blocks.size - 1, 3, nx))
        self.set_plate(None)

    def set_plate(self, matrix) -> None:
        """Take plate bending's matrix ``Q`` (:mod:`pvcloth.physics.bending`,
        a sorted CSR ``(N, N)``), or ``None`` for none: the spring pass then
        adds ``-Q x`` too. Where ``Q``'s stencil is the same at every point
        (two or more points from every edge) it is applied from its six
        distinct values; nearer the edges from ``Q``'s rows. :attr:`plate`
        holds both, as the kernels take them."""
        ny, nx = self.shape
        coefficients = np.zeros(7)  # the six values, then 1 when there is a plate
        if matrix is None:
            empty = np.zeros(1, dtype=np.int64)
            self.plate = (coefficients, empty, empty, np.zeros(0))
            return
        coefficients[6] = 1.0
        j, i = np.divmod(np.arange(ny * nx), nx)
        inner = np.flatnonzero((i >= 2) & (i < nx - 2) & (j >= 2) & (j < ny - 2))
        if inner.size:
            p = int(inner[0])
            span = slice(matrix.indptr[p], matrix.indptr[p + 1])
            row = dict(zip(matrix.indices[span], matrix.data[span], strict=True))
            coefficients[:6] = [row[p + k] for k in (0, 1, 2, nx, 2 * nx, nx + 1)]
        # int64 indices, as without a plate: one compiled signature for both
        indptr, indices = (a.astype(np.int64) for a in (matrix.indptr, matrix.indices))
        self.plate = (coefficients, indptr, indices, matrix.data)

    def _groups(self):
        return [g for family in self.springs for g in family.groups]

    def refresh(self) -> None:
        """Copy the groups' current constants in."""
        for n, g in enumerate(self._groups()):
            rows, cols = g.rest.shape
            self.stiffness[n, :rows, :cols] = g.stiffness
            self.damping[n, :rows, :cols] = g.damping
            self.rest[n, :rows, :cols] = g.rest

    @property
    def empty(self) -> bool:
        return self.stiffness.shape[0] == 0


if numba is not None:

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _row_product(indptr, indices, data, x, r):
        """Row ``r`` of a CSR matrix times ``x`` ``(N, 3)``: the three sums."""
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        for k in range(indptr[r], indptr[r + 1]):
            c, a = indices[k], data[k]
            s0 += a * x[c, 0]
            s1 += a * x[c, 1]
            s2 += a * x[c, 2]
        return s0, s1, s2

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _spring_block(
        x3, v3, f3, stiffness, damping, rest, geometry, extent, plate, lo, hi, scratch, tmp
    ):  # plate: (coefficients, indptr, indices, data), see SpringPlan.set_plate
        """Springs whose end a lies in rows ``[lo, hi)``, computed on a copy of
        the rows they touch laid out component by component (x, y, z, vx, vy,
        vz rows, in ``scratch[:6]``), where every load in the inner loop is
        contiguous; the forces, summed in ``scratch[6:]``, are added back to
        ``f3`` at the end. ``tmp`` holds one row of spring forces. With plate
        bending (``plate[0][6] == 1``), ``-Q x`` at the block's points:
        its stencil on the copy where it is the same at every point (two or
        more points from every edge), ``Q``'s rows (CSR) nearer the edges."""
        ny, nx, _ = x3.shape
        # Rows copied from two before the block (the plate's stencil reads
        # them); forces are written from one row before it, as the phases need.
        r0, r1 = max(lo - 2, 0), min(hi + 2, ny)
        s = scratch[:6]
        for r in range(r1 - r0):
            xr, vr = x3[r0 + r], v3[r0 + r]
            for i in range(nx):
                s[0, r, i] = xr[i, 0]
                s[1, r, i] = xr[i, 1]
                s[2, r, i] = xr[i, 2]
                s[3, r, i] = vr[i, 0]
                s[4, r, i] = vr[i, 1]
                s[5, r, i] = vr[i, 2]
        f = scratch[6:]
        f[:, : r1 - r0] = 0.0
        for g in range(stiffness.shape[0]):
            a0, a1, dj, di = geometry[g, 0], geometry[g, 1], geometry[g, 2], geometry[g, 3]
            rows, cols = extent[g, 0], extent[g, 1]
            b1 = a1 + di
            for r in range(max(lo - a0, 0), min(hi - a0, rows)):
                ja = a0 + r - r0
                jb = ja + dj
                kr, cr, lr = stiffness[g, r], damping[g, r], rest[g, r]
                xa, ya, za = s[0, ja, a1:], s[1, ja, a1:], s[2, ja, a1:]
                ua, va, wa = s[3, ja, a1:], s[4, ja, a1:], s[5, ja, a1:]
                xb, yb, zb = s[0, jb, b1:], s[1, jb, b1:], s[2, jb, b1:]
                ub, vb, wb = s[3, jb, b1:], s[4, jb, b1:], s[5, jb, b1:]
                for q in range(cols):
                    dx = xb[q] - xa[q]
                    dy = yb[q] - ya[q]
                    dz = zb[q] - za[q]
                    length = np.sqrt(dx * dx + dy * dy + dz * dz)
                    inv = 1.0 / max(length, 1e-12)
                    closing = (ub[q] - ua[q]) * dx + (vb[q] - va[q]) * dy + (wb[q] - wa[q]) * dz
                    pull = (kr[q] * (length - lr[q]) + cr[q] * closing * inv) * inv
                    tmp[0, q] = pull * dx
                    tmp[1, q] = pull * dy
                    tmp[2, q] = pull * dz
                for d in range(3):  # separate loops: end a and end b may be the same row
                    fa = f[d, ja, a1:]
                    for q in range(cols):
                        fa[q] += tmp[d, q]
                    fb = f[d, jb, b1:]
                    for q in range(cols):
                        fb[q] -= tmp[d, q]
        coefficients, indptr, indices, data = plate
        if coefficients[6] != 0.0:
            # -Q x at the points whose 13-point stencil has its inner values
            # (pvcloth.physics.bending): centre, row neighbours at 1 and 2,
            # column neighbours at 1 and 2, and the four diagonal ones.
            c0, u1, u2 = coefficients[0], coefficients[1], coefficients[2]
            v1, v2, dg = coefficients[3], coefficients[4], coefficients[5]
            for j in range(max(lo, 2), min(hi, ny - 2)):
                r = j - r0
                for d in range(3):
                    xm2, xm1, x0, xp1, xp2 = (
                        s[d, r - 2],
                        s[d, r - 1],
                        s[d, r],
                        s[d, r + 1],
                        s[d, r + 2],
                    )
                    fd = f[d, r]
                    for i in range(2, nx - 2):
                        fd[i] -= (
                            c0 * x0[i]
                            + u1 * (x0[i - 1] + x0[i + 1])
                            + u2 * (x0[i - 2] + x0[i + 2])
                            + v1 * (xm1[i] + xp1[i])
                            + v2 * (xm2[i] + xp2[i])
                            + dg * (xm1[i - 1] + xm1[i + 1] + xp1[i - 1] + xp1[i + 1])
                        )
            # the points within two of an edge: their rows of Q
            flat = x3.reshape(ny * nx, 3)
            for j in range(lo, hi):
                edge_row = j < 2 or j >= ny - 2
                for i in range(nx):
                    if not edge_row and 2 <= i < nx - 2:
                        continue
                    s0, s1, s2 = _row_product(indptr, indices, data, flat, i + nx * j)
                    f[0, j - r0, i] -= s0
                    f[1, j - r0, i] -= s1
                    f[2, j - r0, i] -= s2
        for r in range(max(lo - 1, 0) - r0, r1 - r0):
            fr = f3[r0 + r]
            for i in range(nx):
                fr[i, 0] += f[0, r, i]
                fr[i, 1] += f[1, r, i]
                fr[i, 2] += f[2, r, i]

    def _spring_forces(
        x3, v3, f3, stiffness, damping, rest, geometry, extent, plate, blocks, scratch, row
    ):
        """Add every spring's force to ``f3``: blocks of rows in two phases,
        block ``b`` working in ``scratch[b]`` and ``row[b]``."""
        count = (blocks.size - 1) // 2
        for phase in range(2):
            for n in prange(count):
                b = 2 * n + phase
                _spring_block(
                    x3,
                    v3,
                    f3,
                    stiffness,
                    damping,
                    rest,
                    geometry,
                    extent,
                    plate,
                    blocks[b],
                    blocks[b + 1],
                    scratch[b],
                    row[b],
                )

    def _body_forces(v3, f3, mass, gravity, air):
        """``f = m g - air m v``: gravity and linear air damping, written over
        whatever ``f3`` held (so it needs no zeroing first)."""
        ny, nx, _ = f3.shape
        for j in prange(ny):
            for i in range(nx):
                m = mass[j, i]
                for d in range(3):
                    f3[j, i, d] = m * (gravity[d] - air * v3[j, i, d])

    def _kick_drift(x3, v3, f3, inv_mass, dt, x_out, v_out):
        """``v' = v + dt f / m``, ``x' = x + dt v'`` (pinned points: 1/m = 0).
        Returns the largest squared speed and a checksum that is finite
        exactly when every new value is, for the divergence guard, at no
        extra pass.

        Why a checksum: under these fast-math flags LLVM folded away an
        ``np.isfinite`` test in this loop (NaN positions ran on silently),
        and may order a max with NaN either way. A sum is only reordered:
        one NaN or inf among its terms still makes it NaN or inf. (A sum of
        finite terms can overflow only in a state that has diverged anyway.)
        """
        ny, nx, _ = x3.shape
        fastest = 0.0
        checksum = 0.0
        for j in prange(ny):
            for i in range(nx):
                w = dt * inv_mass[j, i]
                square = 0.0
                for d in range(3):
                    vn = v3[j, i, d] + w * f3[j, i, d]
                    xn = x3[j, i, d] + dt * vn
                    v_out[j, i, d] = vn
                    x_out[j, i, d] = xn
                    square += vn * vn
                    checksum += xn
                checksum += square
                fastest = max(fastest, square)
        return fastest, checksum

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _wind_on_triangle(x3, v3, f3, j0, i0, j1, i1, j2, i2, air, drag, lift, density):
        """One triangle's drag and lift, a third to each corner: the
        arithmetic of :meth:`pvcloth.physics.forces.Wind.accumulate`, one
        triangle at a time, in scalars (no arrays made per triangle)."""
        ax, ay, az = x3[j0, i0, 0], x3[j0, i0, 1], x3[j0, i0, 2]
        ux, uy, uz = x3[j1, i1, 0] - ax, x3[j1, i1, 1] - ay, x3[j1, i1, 2] - az
        wx, wy, wz = x3[j2, i2, 0] - ax, x3[j2, i2, 1] - ay, x3[j2, i2, 2] - az
        # the air's velocity relative to the triangle's mean velocity
        rx = air[0] - (v3[j0, i0, 0] + v3[j1, i1, 0] + v3[j2, i2, 0]) / 3.0
        ry = air[1] - (v3[j0, i0, 1] + v3[j1, i1, 1] + v3[j2, i2, 1]) / 3.0
        rz = air[2] - (v3[j0, i0, 2] + v3[j1, i1, 2] + v3[j2, i2, 2]) / 3.0
        nx_ = uy * wz - uz * wy
        ny_ = uz * wx - ux * wz
        nz_ = ux * wy - uy * wx
        double_area = np.sqrt(nx_ * nx_ + ny_ * ny_ + nz_ * nz_)
        inverse = 1.0 / max(double_area, TINY_LENGTH)
        nx_ *= inverse
        ny_ *= inverse
        nz_ *= inverse
        across = rx * nx_ + ry * ny_ + rz * nz_
        speed = np.sqrt(rx * rx + ry * ry + rz * rz)
        scale = 0.5 * density * (0.5 * double_area) * speed * across / 3.0
        s0 = drag * scale * nx_
        s1 = drag * scale * ny_
        s2 = drag * scale * nz_
        if lift != 0.0:
            inverse_speed = 1.0 / max(speed, TINY_LENGTH)
            along = across * inverse_speed
            lifted = lift * scale
            s0 += lifted * (nx_ - along * rx * inverse_speed)
            s1 += lifted * (ny_ - along * ry * inverse_speed)
            s2 += lifted * (nz_ - along * rz * inverse_speed)
        f3[j0, i0, 0] += s0
        f3[j0, i0, 1] += s1
        f3[j0, i0, 2] += s2
        f3[j1, i1, 0] += s0
        f3[j1, i1, 1] += s1
        f3[j1, i1, 2] += s2
        f3[j2, i2, 0] += s0
        f3[j2, i2, 1] += s1
        f3[j2, i2, 2] += s2

    def _wind_forces(x3, v3, f3, air, drag, lift, density):
        """Add the wind on every cell's two triangles (``CELL_TRIANGLES``).
        A row of cells writes to two rows of points, so threads take the
        even rows of cells, then the odd ones: no two threads write one
        point, and each point sums its triangles in the same order in the
        serial and the threaded build."""
        ny, nx, _ = x3.shape
        for parity in range(2):
            for half in prange((ny - parity) // 2):
                j = 2 * half + parity
                for i in range(nx - 1):
                    for t in range(2):
                        (j0, i0), (j1, i1), (j2, i2) = CELL_TRIANGLES[t]
                        _wind_on_triangle(
                            x3,
                            v3,
                            f3,
                            j + j0,
                            i + i0,
                            j + j1,
                            i + i1,
                            j + j2,
                            i + i2,
                            air,
                            drag,
                            lift,
                            density,
                        )

    def _compile(function):
        """A serial and a threaded build of one kernel. Threads pay only on
        big grids: waking them costs microseconds, more when other thread
        pools (BLAS) compete for the cores.

        numba names a function's on-disk cache after its qualified name and
        keys it by signature and machine, not by the compile flags, so two
        builds of one function would share one entry and whichever compiled
        first would serve both. The threaded build is therefore made from a
        copy of the function under a name of its own."""
        serial = njit(fastmath=FASTMATH, cache=True, nogil=True)(function)
        twin = types.FunctionType(
            function.__code__,
            function.__globals__,
            f"{function.__name__}_threaded",
            function.__defaults__,
            function.__closure__,
        )
        twin.__qualname__ = f"{function.__qualname__}_threaded"
        threaded = njit(fastmath=FASTMATH, cache=True, nogil=True, parallel=True)(twin)
        return serial, threaded

    @njit(fastmath=FASTMATH, cache=True, nogil=True)
    def _spring_projection(x, a, b, rest, weight, out):
        """Liu et al.'s local step, summed onto the points: every spring's
        ``weight * rest * u`` (``u`` the unit vector from end b to end a)
        added at end a and taken from end b; returns ``sum(weight * rest *
        length)``. Serial: a scatter over springs, a few nanoseconds each."""
        out[:] = 0.0
        total = 0.0
        for s in range(a.size):
            p, q = a[s], b[s]
            dx = x[p, 0] - x[q, 0]
            dy = x[p, 1] - x[q, 1]
            dz = x[p, 2] - x[q, 2]
            length = np.sqrt(dx * dx + dy * dy + dz * dz)
            scale = weight[s] * rest[s] / max(length, 1e-12)
            total += weight[s] * rest[s] * length
            out[p, 0] += scale * dx
            out[p, 1] += scale * dy
            out[p, 2] += scale * dz
            out[q, 0] -= scale * dx
            out[q, 1] -= scale * dy
            out[q, 2] -= scale * dz
        return total

    def _subtract_product(indptr, indices, data, x, f):
        """``f -= A x`` for a CSR matrix ``A`` ``(N, N)`` (``indptr``,
        ``indices``, ``data``) and ``x``, ``f`` ``(N, 3)``: row by row, each
        row's three sums written once (rows are independent: threads need
        no care)."""
        for r in prange(indptr.size - 1):
            s0, s1, s2 = _row_product(indptr, indices, data, x, r)
            f[r, 0] -= s0
            f[r, 1] -= s1
            f[r, 2] -= s2

    _SPRINGS = _compile(_spring_forces)
    _PRODUCT = _compile(_subtract_product)
    _BODY = _compile(_body_forces)
    _KICK = _compile(_kick_drift)
    _WIND = _compile(_wind_forces)

#: Grids with at least this many rows use the threaded kernels.
THREADED_ROWS = 64


def _pick(builds, rows: int):
    # numba's thread count is per calling thread: a thread that asked for
    # one (the window's physics, see use_threads) gets the serial build.
    return warm(builds[rows >= THREADED_ROWS and numba.get_num_threads() > 1])


def warm(kernel):
    """``kernel`` itself once it has run, else its first call wrapped by
    :class:`_Warming` (signals held while it compiles or loads)."""
    return kernel if kernel in _WARM else _Warming(kernel)


#: Kernels that have been compiled or loaded from the disk cache.
_WARM: set = set()


class _Warming:
    """A kernel's first call, with Ctrl-C and SIGTERM held until it returns.

    The first call compiles (seconds, with a cold cache) or loads the
    kernel, inside llvmlite's ctypes callbacks, which swallow an exception
    that pvcloth's signal handler raises there: a SIGTERM at that moment
    printed "Exception ignored ... Traceback" (seen in a fresh clone's
    signal test)."""

    def __init__(self, kernel):
        self.kernel = kernel

    def __call__(self, *args):
        with deferred():
            result = self.kernel(*args)
        _WARM.add(self.kernel)
        return result


def use_threads(count: int) -> None:
    """Let the kernels called from this thread use ``count`` threads (numba
    keeps the number per calling thread); 1 selects the serial builds.

    The window calls this from its physics thread with one thread fewer
    than the machine's cores, because the drawing needs one: OpenMP threads
    that wait at a barrier for a core busy drawing made a 64x64 step take
    280 ms instead of 0.2 ms."""
    if numba is not None:
        numba.set_num_threads(max(1, min(count, numba.config.NUMBA_NUM_THREADS)))


def spring_forces(plan: SpringPlan, x, v, f) -> None:
    """Add all springs' forces to ``f`` (``(N, 3)`` arrays, C-contiguous), and
    plate bending's when the plan has it (:meth:`SpringPlan.set_plate`)."""
    if plan.empty:
        return
    shape = plan.shape + (3,)
    _pick(_SPRINGS, plan.shape[0])(
        x.reshape(shape),
        v.reshape(shape),
        f.reshape(shape),
        plan.stiffness,
        plan.damping,
        plan.rest,
        plan.geometry,
        plan.extent,
        plan.plate,
        plan.blocks,
        plan.scratch,
        plan.row,
    )


def subtract_product(matrix, x, f, rows: int) -> None:
    """``f -= matrix @ x`` (``matrix`` a sorted CSR ``(N, N)``, ``x`` and
    ``f`` ``(N, 3)``), compiled; threaded on grids of ``rows`` from
    :data:`THREADED_ROWS` up."""
    _pick(_PRODUCT, rows)(matrix.indptr, matrix.indices, matrix.data, x, f)


def body_forces(v, f, mass, gravity, air: float, shape) -> None:
    """Set ``f`` to gravity plus linear air damping (the other forces add on)."""
    s3 = shape + (3,)
    _pick(_BODY, shape[0])(v.reshape(s3), f.reshape(s3), mass.reshape(shape), gravity, air)


def wind_forces(wind, x, v, f, shape) -> None:
    """Add ``wind``'s force (a :class:`pvcloth.physics.forces.Wind`, at the
    air velocity of its current time) at positions ``x`` (m) and velocities
    ``v`` (m/s) to ``f`` (N), all ``(N, 3)``; compiled, the same sums as
    ``wind.accumulate`` to round-off."""
    s3 = shape + (3,)
    _pick(_WIND, shape[0])(
        x.reshape(s3),
        v.reshape(s3),
        f.reshape(s3),
        wind.velocity,
        float(wind.drag),
        float(wind.lift),
        float(wind.density),
    )


def kick_drift(x, v, f, inv_mass, dt: float, x_out, v_out, shape) -> tuple[float, bool]:
    """The semi-implicit Euler update from the total force ``f``, into
    ``x_out, v_out``; returns the largest speed and whether all is finite."""
    s3 = shape + (3,)
    fastest, checksum = _pick(_KICK, shape[0])(
        x.reshape(s3),
        v.reshape(s3),
        f.reshape(s3),
        inv_mass.reshape(shape),
        dt,
        x_out.reshape(s3),
        v_out.reshape(s3),
    )
    return float(np.sqrt(fastest)), math.isfinite(checksum)


def spring_projection(x, a, b, rest, weight, out) -> float:
    """Compiled :func:`spring_projection_numpy` (same sums, another order)."""
    return float(warm(_spring_projection)(x, a, b, rest, weight, out))


def spring_projection_numpy(x, a, b, rest, weight, out) -> float:
    """Into ``out`` (``(N, 3)``): for every spring from a to b (``a``, ``b``
    point indices, ``rest`` lengths in m), ``weight * rest * (x_a - x_b) /
    |x_a - x_b|`` added at a and subtracted at b. Returns ``sum(weight *
    rest * |x_a - x_b|)`` (the part of the springs' energy, times the
    weights, that is not quadratic in ``x``). The NumPy reference."""
    d = x[a] - x[b]
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    total = float(np.dot(weight * rest, length))
    d *= (weight * rest / np.maximum(length, 1e-12))[:, None]
    out[:] = 0.0
    for k in range(3):
        out[:, k] = np.bincount(a, d[:, k], out.shape[0]) - np.bincount(b, d[:, k], out.shape[0])
    return total
