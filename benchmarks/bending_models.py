"""Which bending model: plate bending against discrete-shell hinges.

pvcloth's plate bending (:mod:`pvcloth.physics.bending`) measures curvature
with finite differences on the grid, a quadratic energy with a constant
matrix. The common alternative is a hinge on every interior edge of a
triangulation, with energy in the dihedral angle ``theta`` (Grinspun et al.
2003, Bridson et al. 2003; the weight ``3 |e|^2 / (A0 + A1)`` of Wardetzky
et al. 2007 makes the sum approximate the integral of the squared mean
curvature, ``kappa^2`` on a cylinder)::

    E = B / 2 * sum over edges of 3 |e|^2 / (A0 + A1) * theta^2

with ``|e|`` and the triangle areas ``A0``, ``A1`` taken at rest. Both are
measured here in the same NumPy terms, on the grid pvcloth uses (each cell
split along one diagonal for the hinges):

- **energy**: a square sheet rolled onto a cylinder of curvature ``kappa``,
  along the rows, the columns and the diagonals, against ``B kappa^2 / 2``
  per unit area, on finer and finer grids;
- **cost**: one force evaluation (the energy's gradient) at 64x64 and
  128x128, median of repeats, both in NumPy and SciPy.

Run: ``python benchmarks/bending_models.py`` (about ten seconds).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

from pvcloth.physics.bending import PlateBending

HERE = Path(__file__).resolve().parent


def grid_triangles(nu: int, nv: int) -> np.ndarray:
    """``(2 (nu-1) (nv-1), 3)`` counter-clockwise triangles, each cell split
    along its diagonal from ``(i, j)`` to ``(i+1, j+1)``; point index
    ``j * nu + i``."""
    j, i = np.meshgrid(np.arange(nv - 1), np.arange(nu - 1), indexing="ij")
    a = (j * nu + i).ravel()
    b, c, d = a + 1, a + nu + 1, a + nu
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


class Hinges:
    """Dihedral-angle bending on every interior edge of ``triangles``."""

    def __init__(self, triangles: np.ndarray, rest: np.ndarray, rigidity: float):
        # every directed edge of every triangle; an interior edge appears
        # once in each direction
        edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
        opposite = np.concatenate([triangles[:, 2], triangles[:, 0], triangles[:, 1]])
        key = {(int(p), int(q)): k for k, (p, q) in enumerate(edges)}
        first, second = [], []
        for k, (p, q) in enumerate(edges):
            other = key.get((int(q), int(p)))
            if other is not None and p < q:
                first.append(k)
                second.append(other)
        first, second = np.array(first), np.array(second)
        # x0 -> x1 the shared edge as the first triangle runs it, x2 that
        # triangle's third point, x3 the other triangle's
        self.index = np.stack(
            [edges[first, 0], edges[first, 1], opposite[first], opposite[second]], 1
        )
        x0, x1, x2, x3 = (rest[self.index[:, k]] for k in range(4))
        area0 = 0.5 * np.linalg.norm(np.cross(x1 - x0, x2 - x0), axis=1)
        area1 = 0.5 * np.linalg.norm(np.cross(x0 - x1, x3 - x1), axis=1)
        self.weight = rigidity * 3 * np.sum((x1 - x0) ** 2, axis=1) / (area0 + area1)
        self.n_points = len(rest)

    def angles(self, x: np.ndarray) -> np.ndarray:
        x0, x1, x2, x3 = (x[self.index[:, k]] for k in range(4))
        n0 = np.cross(x1 - x0, x2 - x0)
        n1 = np.cross(x0 - x1, x3 - x1)
        e = x1 - x0
        sine = np.einsum("ij,ij->i", np.cross(n0, n1), e) / np.linalg.norm(e, axis=1)
        return np.arctan2(sine, np.einsum("ij,ij->i", n0, n1))

    def energy(self, x: np.ndarray) -> float:
        return float(0.5 * np.sum(self.weight * self.angles(x) ** 2))

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """``(n, 3)``: dE/dx, from the angle's gradient in Bridson et al.
        (2003)'s form: each opposite point moves along its triangle's
        normal, the edge's points take the rest so that the sum is zero."""
        x0, x1, x2, x3 = (x[self.index[:, k]] for k in range(4))
        e = x1 - x0
        length = np.linalg.norm(e, axis=1)[:, None]
        n0 = np.cross(x1 - x0, x2 - x0)
        n1 = np.cross(x0 - x1, x3 - x1)
        m0 = n0 / np.sum(n0 * n0, axis=1)[:, None]
        m1 = n1 / np.sum(n1 * n1, axis=1)[:, None]
        d2 = -length * m0
        d3 = -length * m1
        along = lambda a: np.sum(a * e, axis=1)[:, None] / length  # noqa: E731
        d0 = -along(x2 - x1) * m0 - along(x3 - x1) * m1
        d1 = along(x2 - x0) * m0 + along(x3 - x0) * m1
        scale = (self.weight * self.angles(x))[:, None]
        out = np.zeros((self.n_points, 3))
        for k, d in enumerate((d0, d1, d2, d3)):
            for c in range(3):
                out[:, c] += np.bincount(
                    self.index[:, k], weights=scale[:, 0] * d[:, c], minlength=self.n_points
                )
        return out


def rolled(n: int, side: float, curvature: float, degrees: float) -> tuple[np.ndarray, float]:
    """A flat ``n`` x ``n`` grid of ``side`` metres wrapped without stretching
    onto a cylinder, bending along ``degrees`` from the rows; and its spacing."""
    h = side / (n - 1)
    v, u = np.meshgrid(np.arange(n) * h, np.arange(n) * h, indexing="ij")
    a = np.radians(degrees)
    s = u * np.cos(a) + v * np.sin(a)
    t = -u * np.sin(a) + v * np.cos(a)
    k = curvature
    x = np.stack([np.sin(k * s) / k, t, (1 - np.cos(k * s)) / k], -1).reshape(-1, 3)
    return x, h


def flat(n: int, h: float) -> np.ndarray:
    v, u = np.meshgrid(np.arange(n) * h, np.arange(n) * h, indexing="ij")
    return np.stack([u, v, np.zeros_like(u)], -1).reshape(-1, 3)


def check_gradient(hinges: Hinges, x: np.ndarray) -> float:
    """Largest relative difference between the gradient and central
    differences of the energy, over a few coordinates."""
    rng = np.random.default_rng(1)
    grad = hinges.gradient(x)
    worst, step = 0.0, 1e-7
    for flat_index in rng.choice(x.size, 20, replace=False):
        p, c = divmod(int(flat_index), 3)
        plus, minus = x.copy(), x.copy()
        plus[p, c] += step
        minus[p, c] -= step
        numeric = (hinges.energy(plus) - hinges.energy(minus)) / (2 * step)
        worst = max(worst, abs(numeric - grad[p, c]) / (np.abs(grad).max()))
    return worst


def median_seconds(call, repeats: int = 15) -> float:
    call()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def force_costs(n: int, kappa: float, rigidity: float) -> tuple[int, float, float]:
    """Milliseconds per force evaluation on an ``n`` x ``n`` rolled sheet:
    ``(n, plate, hinges)``."""
    x, h = rolled(n, 1.0, kappa, 30.0)
    plate = PlateBending((n, n), (h, h), rigidity)
    hinges = Hinges(grid_triangles(n, n), flat(n, h), rigidity)
    f = np.zeros_like(x)
    plate_ms = 1e3 * median_seconds(lambda: plate.accumulate(x, x, f))
    hinge_ms = 1e3 * median_seconds(lambda: hinges.gradient(x))
    print(f"{n}x{n}: plate {plate_ms:.2f} ms, hinges {hinge_ms:.2f} ms")
    return n, plate_ms, hinge_ms


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE / "results" / "bending_models.md")
    args = parser.parse_args(argv)
    rigidity, side, kappa = 1.0, 0.5, 4.0
    exact = 0.5 * rigidity * kappa**2 * side**2
    rows = []
    for n in (11, 21) if SMOKE else (11, 21, 41, 81):
        for degrees in (0.0, 45.0, 90.0, 135.0):
            x, h = rolled(n, side, kappa, degrees)
            plate = PlateBending((n, n), (h, h), rigidity).potential_energy(x)
            hinge = Hinges(grid_triangles(n, n), flat(n, h), rigidity).energy(x)
            rows.append((n, degrees, plate / exact, hinge / exact))
            print(
                f"{n:3d} points, {degrees:5.1f} deg: plate {plate / exact:.4f}, "
                f"hinges {hinge / exact:.4f}"
            )
    x, h = rolled(21, side, kappa, 30.0)
    hinges = Hinges(grid_triangles(21, 21), flat(21, h), rigidity)
    gradient_error = check_gradient(
        hinges, x + 1e-3 * np.random.default_rng(0).normal(size=x.shape)
    )
    assert gradient_error < 1e-5, gradient_error
    costs = [force_costs(n, kappa, rigidity) for n in ((8,) if SMOKE else (64, 128))]
    lines = [
        "# Which bending model: plate against hinges",
        "",
        provenance(),
        "",
        "`python benchmarks/bending_models.py`. Energy of a square sheet (0.5 m) rolled "
        "without stretching onto a cylinder of curvature 4 /m, bending along a direction "
        "measured from the grid's rows, over B kappa^2 / 2 times its area: 1 is exact. "
        "The plate leaves the outermost half cells at the free edges out, so it "
        "approaches 1 from below as the grid is refined; its directions differ by "
        "what those edges leave out, less on every finer grid. "
        "The hinges sit on the grid with each cell split along the diagonal at 45 "
        "degrees, weight 3 |e|^2 / (A0 + A1); whatever constant calibrates them, they "
        "hold three times as much energy for a bend along that diagonal (45) as along "
        "the rows, the columns or the other diagonal, on every grid. "
        f"Their gradient agrees with central differences of their energy to "
        f"{gradient_error:.0e} (relative).",
        "",
        "| points | direction (deg) | plate | hinges |",
        "|---|---|---|---|",
    ]
    lines += [f"| {n}x{n} | {d:g} | {p:.4f} | {q:.4f} |" for n, d, p, q in rows]
    lines += [
        "",
        "One force evaluation in NumPy/SciPy (median of 15; plate: one sparse product, "
        "hinges: angles, their gradients and a scatter). pvcloth's compiled backend "
        "applies the plate inside its threaded spring pass instead "
        "([bending_cost.md](bending_cost.md)).",
        "",
        "| points | plate (ms) | hinges (ms) | hinges / plate |",
        "|---|---|---|---|",
    ]
    lines += [f"| {n}x{n} | {p:.2f} | {q:.2f} | {q / p:.1f} |" for n, p, q in costs]
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
