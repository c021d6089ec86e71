"""pvcloth against NVIDIA Newton on this CPU, the same cotton cloth side by side.

``pip install newton warp-lang`` (the ``peers`` extra), then
``python benchmarks/newton_peer.py``. One process builds the bundled cotton
scene (``data/scenes/cotton.toml``: 1 m square, 0.22 kg/m^2, 2112 N/m,
hanging from two corners, 64x64 points) in pvcloth and, as closely as
Newton's cloth allows, in Newton (``ModelBuilder.add_cloth_grid``: the same
points, mass and corners; its triangles are an isotropic StVK membrane,
given the measured shear modulus as Lame mu and the rest of the measured
stretch modulus as lambda, ``lambda + 2 mu = stretch``, so that a stretch
along a thread and a shear cost what they cost the measured fabric, as
pvcloth's springs do; bending ``edge_ke`` the measured 1.71e-4 N m; spring
dashpots as pvcloth's, k times 2.5e-4 s; no air damping, which Newton's
cloth has no term for). Each method runs ``--seconds`` of cloth from the flat
start, timed per 1/60 s frame by the wall clock after 0.2 s of warm-up:

- pvcloth ``fast_mass_spring`` (one step per frame, 6 and 10 iterations)
  and ``symplectic_euler`` at its automatic step;
- Newton ``SolverVBD`` (Vertex Block Descent, Chen et al. 2024, the solver
  Newton recommends for cloth) and ``SolverXPBD`` (on springs), each at
  ``--substeps`` substeps of ``--iterations`` iterations per frame, as
  Newton's own cloth example runs them.

Reported: the median wall time per frame, cloth seconds per wall second,
and what each left: how far the lowest point hangs below the pins (the
sag), and the 99th percentile and largest strain of the cloth's grid edges
(length over rest length minus one; cotton under its own weight stretches
well under 1 %: a larger strain is an iteration that did not converge).
pvcloth's own error against its RK4 reference is in ``fabric_speed.md``.
Writes ``benchmarks/results/newton_peer.md``.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.scene.materials import MATERIALS

HERE = Path(__file__).parent
FRAME = 1 / 60
WARMUP = 0.2
PVCLOTH_METHODS = ("fast_mass_spring:6", "fast_mass_spring:10", "symplectic_euler")
NEWTON_METHODS = ("vbd", "xpbd")
DAMPING_TIME = 2.5e-4  # s: dashpot over stiffness, as pvcloth's presets


def grid_strain(x: np.ndarray, n: int, spacing: float) -> np.ndarray:
    """Strain of every horizontal and vertical edge of an ``n x n`` grid."""
    grid = x.reshape(n, n, 3)
    lengths = np.concatenate(
        [
            np.linalg.norm(grid[:, 1:] - grid[:, :-1], axis=-1).ravel(),
            np.linalg.norm(grid[1:] - grid[:-1], axis=-1).ravel(),
        ]
    )
    return lengths / spacing - 1.0


def summary(method, frames, x, n, spacing, pin_height) -> dict:
    strain = grid_strain(x, n, spacing)
    wall = sum(frames)
    return {
        "method": method,
        "ms": 1e3 * statistics.median(frames),
        "rate": len(frames) * FRAME / wall,
        "finite": bool(np.isfinite(x).all()),
        "sag": float(pin_height - np.nanmin(x[:, 2])),
        "p99": float(np.nanpercentile(strain, 99)),
        "max": float(np.nanmax(strain)),
    }


def run_pvcloth(scene, method: str, seconds: float) -> tuple[list[float], np.ndarray]:
    name, _, iterations = method.partition(":")
    if iterations:
        scene = scene.with_overrides({"solver.iterations": int(iterations)})
    sim = pvcloth.Simulation(scene, integrator=name)
    sim.advance(WARMUP)
    frames = []
    for _ in range(round(seconds / FRAME)):
        start = time.perf_counter()
        sim.advance(FRAME)
        frames.append(time.perf_counter() - start)
    return frames, sim.positions.copy()


def run_newton(scene, method: str, seconds: float, substeps: int, iterations: int):
    import newton
    import warp as wp

    n = scene.cloth.resolution[0]
    size = scene.cloth.size[0]
    cells = n - 1
    spacing = size / cells
    mass = scene.cloth.mass * size * size / (n * n)  # pvcloth lumps by area; uniform inside
    cotton = MATERIALS["cotton"]
    builder = newton.ModelBuilder()
    center = np.array(scene.cloth.center)
    common = dict(
        pos=wp.vec3(*(center - [size / 2, size / 2, 0.0])),
        rot=wp.quat_identity(),
        vel=wp.vec3(0.0, 0.0, 0.0),
        dim_x=cells,
        dim_y=cells,
        cell_x=spacing,
        cell_y=spacing,
        mass=mass,
        edge_ke=cotton.bending_rigidity,
        edge_kd=0.0,
        particle_radius=spacing / 4,
    )
    if method == "vbd":
        mu, lam = cotton.shear, cotton.stretch - 2 * cotton.shear
        builder.add_cloth_grid(**common, tri_ke=mu, tri_ka=lam, tri_kd=DAMPING_TIME)
        builder.color(include_bending=True)
    else:
        builder.add_cloth_grid(
            **common,
            add_springs=True,
            spring_ke=cotton.stretch,
            spring_kd=cotton.stretch * DAMPING_TIME,
        )
    # Pin the two top corners (pvcloth's "top-left" and "top-right": the
    # last row), as kinematic particles: mass zero, not active.
    for index in (n * (n - 1), n * n - 1):
        builder.particle_mass[index] = 0.0
        builder.particle_flags[index] = builder.particle_flags[index] & ~newton.ParticleFlags.ACTIVE
    model = builder.finalize(device="cpu")
    if method == "vbd":
        solver = newton.solvers.SolverVBD(model=model, iterations=iterations)
    else:
        solver = newton.solvers.SolverXPBD(model=model, iterations=iterations)
    state_0, state_1 = model.state(), model.state()
    control = model.control()
    dt = FRAME / substeps

    def frame():
        nonlocal state_0, state_1
        for _ in range(substeps):
            state_0.clear_forces()
            solver.step(state_0, state_1, control, None, dt)
            state_0, state_1 = state_1, state_0

    frames_warm = round(WARMUP / FRAME)
    for _ in range(frames_warm):
        frame()
    frames = []
    for _ in range(round(seconds / FRAME)):
        start = time.perf_counter()
        frame()
        wp.synchronize()
        frames.append(time.perf_counter() - start)
    return frames, state_0.particle_q.numpy().astype(float)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=8 if SMOKE else 64)
    parser.add_argument("--seconds", type=float, default=0.05 if SMOKE else 1.0)
    parser.add_argument("--substeps", type=int, default=10)
    parser.add_argument("--iterations", type=int, default=10)
    parser.add_argument("--out", default=str(HERE / "results" / "newton_peer.md"))
    args = parser.parse_args()
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    scene = scene.with_resolution(args.size)
    n, spacing = args.size, scene.cloth.size[0] / (args.size - 1)
    pin_height = scene.cloth.center[2]
    rows = []
    for method in PVCLOTH_METHODS:
        frames, x = run_pvcloth(scene, method, args.seconds)
        rows.append(summary(f"pvcloth {method}", frames, x, n, spacing, pin_height))
        print(rows[-1], flush=True)
    have_newton = importlib.util.find_spec("newton") is not None
    if have_newton:
        import warp as wp

        wp.config.quiet = True
        for method in NEWTON_METHODS:
            frames, x = run_newton(scene, method, args.seconds, args.substeps, args.iterations)
            label = f"Newton {method} {args.substeps}x{args.iterations}"
            rows.append(summary(label, frames, x, n, spacing, pin_height))
            print(rows[-1], flush=True)
    versions = ""
    if have_newton:
        import newton
        import warp as wp

        versions = f" (Newton {newton.__version__}, Warp {wp.__version__}, CPU)"
    lines = [
        "# pvcloth and NVIDIA Newton on the same cotton cloth",
        "",
        provenance(),
        "",
        f"`python benchmarks/newton_peer.py{''.join(' ' + a for a in sys.argv[1:])}` "
        f"{versions}: the cotton scene at {n}x{n} points, "
        f"{args.seconds:g} s of cloth after {WARMUP:g} s, one method after another in one "
        "process. ms = median wall time per 1/60 s frame; cloth s per wall s = simulated "
        "over wall time; sag = lowest point below the pins (m); strain = edge length over "
        "rest length minus one (p99 and largest).",
        "",
        "| method | ms per frame | cloth s per wall s | sag (m) | strain p99 | strain max |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if not r["finite"]:
            lines.append(f"| {r['method']} | {r['ms']:.1f} | {r['rate']:.2f} | NaN | - | - |")
            continue
        lines.append(
            f"| {r['method']} | {r['ms']:.1f} | {r['rate']:.2f} | {r['sag']:.3f} "
            f"| {r['p99']:.2%} | {r['max']:.2%} |"
        )
    if not have_newton:
        lines += ["", "Newton is not installed here (`pip install newton warp-lang`)."]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
