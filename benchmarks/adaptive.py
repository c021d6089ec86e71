"""Adaptive steps against fixed ones: error reached and what it cost.

For each scene and method, the method runs once per tolerance (steps chosen
by its error estimate) and once per fixed step, from the same start to the
same end, drawn at 60 frames per second. A run's error is the largest point
distance from RK4 at a tiny fixed step (independent of the methods
measured) over all of its frames: what a movie of it shows at worst. The
summary compares, at the error each adaptive run reached, its wall time with
the same method's fixed-step runs interpolated (log-log) at that error: the
cost of letting the controller choose. Scenes: the 16x16 hanging cloth (a
swing that calms), a 12x12 cloth dropped on the ground (a fall, an impact
and rest: quiet and violent phases) and the 32x32 cotton cloth (stiff and
light: rk23 is held by its stable step), and apart, a 16x16 swing that a strong
air damping calms within 3 s (a violent start and a quiet end, no contact).

Run:  python benchmarks/adaptive.py [--out FILE] [--cases hanging,ground,cotton,calming]
      (writes benchmarks/results/adaptive.md; the calming swing, 3 s, is
      benchmarks/results/adaptive_calm.md:
      python benchmarks/adaptive.py --cases calming --out benchmarks/results/adaptive_calm.md)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

import pvcloth

HERE = Path(__file__).parent
SCENES = HERE.parent / "data" / "scenes"
FPS = 60
#: Per method: the tolerances (m) run adaptive, and the fixed steps as
#: shares of rk23's stable step (the implicit ones' as multiples of it).
METHODS = {
    "rk23": ((1e-2, 1e-3, 1e-4, 1e-5, 1e-6), (0.9, 0.45, 0.2, 0.1, 0.05, 0.02)),
    "implicit_euler": ((1e-1, 1e-2), (8.0, 4.0, 2.0, 1.0, 0.5, 0.25)),
    "fast_mass_spring": ((1e-1, 1e-2, 1e-3), (8.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.1)),
}


def cases():
    """Name -> (title, scene, duration in s, methods measured)."""
    size = (lambda n: 8) if SMOKE else (lambda n: n)
    hanging = pvcloth.load_scene(SCENES / "hanging.toml").with_resolution(size(16))
    ground = pvcloth.load_scene(SCENES / "ground.toml").with_resolution(size(12))
    cotton = pvcloth.load_scene(SCENES / "cotton.toml").with_resolution(size(32))
    duration = 0.1 if SMOKE else 1.0
    return {
        "hanging": ("hanging 16x16", hanging, duration, tuple(METHODS)),
        "ground": ("ground drop 12x12", ground, duration, ("rk23", "fast_mass_spring")),
        "cotton": ("cotton 32x32", cotton, duration / 2, ("rk23",)),
        # A violent start and a quiet end: the swing dies out (air damping
        # 4 /s: e^-12 of its energy is left after 3 s).
        "calming": (
            "calming swing 16x16 (air damping 4 /s)",
            hanging.with_overrides({"air_damping": 4.0}),
            0.1 if SMOKE else 3.0,
            ("rk23",),
        ),
    }


#: Each run is repeated and its median wall time kept: the same step's cost
#: varied by 2x between repeats on this shared machine.
REPEATS = 1 if SMOKE else 3


def run(scene, duration, reference, **solver):
    """The run, its error (the largest over its frames of the largest point
    distance from ``reference``'s frames), its median wall time over
    :data:`REPEATS` identical runs, and whether it finished (runs are
    deterministic: the last one is returned)."""
    walls = []
    for _ in range(REPEATS):
        sim = pvcloth.Simulation(
            scene.with_overrides({f"solver.{k}": v for k, v in solver.items()}), stability="ignore"
        )
        error, start = 0.0, time.perf_counter()
        try:
            for n in sim.frames(len(reference), FPS):
                error = max(error, np.linalg.norm(sim.positions - reference[n], axis=1).max())
        except pvcloth.DivergenceError:
            return sim, np.inf, time.perf_counter() - start, False
        walls.append(time.perf_counter() - start)
    return sim, error, float(np.median(walls)), True


def reference_frames(scene, duration):
    """RK4 at a fixed step of about 1/40000 of the run, a whole number per
    frame (else a frame is read between steps): every frame's positions."""
    frame = 1 / FPS
    sim = pvcloth.Simulation(scene, integrator="rk4", dt=frame / np.ceil(frame * 40000 / duration))
    return [sim.positions.copy() for _ in sim.frames(round(duration * FPS) + 1, FPS)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE / "results" / "adaptive.md")
    parser.add_argument(
        "--cases",
        default="hanging,ground,cotton",
        help="comma-separated: hanging, ground, cotton, calming (default: the first three)",
    )
    args = parser.parse_args()
    chosen = cases()
    unknown = set(args.cases.split(",")) - set(chosen)
    if unknown:
        parser.error(
            f"--cases: unknown {', '.join(sorted(unknown))}; choose from {', '.join(chosen)}"
        )
    lines = [
        "# Adaptive steps against fixed ones",
        "",
        provenance(),
        "",
        f"`{' '.join(['python benchmarks/adaptive.py', *sys.argv[1:]])}`: each method with "
        "`solver.tolerance` (adaptive) and at fixed steps; error = the largest, over the "
        f"run's {FPS} frames per second, of the largest point distance from RK4 at a fixed "
        "step of 1/40000 of the run; wall = median seconds of the frame loop over "
        f"{REPEATS} identical runs (the error checks included, the same for every run). "
        "The stated relation is error <= about tolerance * t / 1 s "
        "(`pvcloth/physics/adaptive.py`).",
    ]
    for title, scene, duration, methods in (chosen[name] for name in args.cases.split(",")):
        base = scene.with_overrides({"solver.dt": None})
        reference = reference_frames(base, duration)
        stable = pvcloth.Simulation(base, integrator="rk23").stable_dt()
        lines += ["", f"## {title}, {duration:g} s (rk23's stable step about {stable:.3g} s)"]
        for method in methods:
            tolerances, shares = METHODS[method]
            rows = []
            for tolerance in tolerances[:2] if SMOKE else tolerances:
                sim, error, wall, ok = run(
                    base, duration, reference, integrator=method, tolerance=tolerance
                )
                rejected = sim.controller.rejected
                rows.append(("adaptive", tolerance, sim.steps, rejected, error, wall, ok))
                print(title, method, rows[-1], flush=True)
            for share in shares[:2] if SMOKE else shares:
                # Whole steps per frame: the frames compared are at the same times.
                dt = (1 / FPS) / np.ceil((1 / FPS) / (share * stable))
                sim, error, wall, ok = run(base, duration, reference, integrator=method, dt=dt)
                rows.append(("fixed", dt, sim.steps, 0, error, wall, ok))
                print(title, method, rows[-1], flush=True)
            lines += _table(method, rows, duration)
    args.out.parent.mkdir(exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


def _table(method, rows, duration) -> list[str]:
    lines = [
        "",
        f"### {method}",
        "",
        "| run | tolerance (m) or dt (s) | steps | rejected | error (m) | "
        "error / (tolerance t) | wall (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for kind, value, steps, rejected, error, wall, ok in rows:
        relation = f"{error / (value * duration):.2f}" if kind == "adaptive" and ok else ""
        shown = f"{error:.3g}" if ok else "diverged"
        lines.append(
            f"| {kind} | {value:.3g} | {steps} | {rejected} | {shown} | {relation} | {wall:.3f} |"
        )
    fixed = sorted((e, w) for k, _, _, _, e, w, ok in rows if k == "fixed" and ok)
    if len(fixed) < 2:
        return lines
    errors, walls = (np.log([f[i] for f in fixed]) for i in (0, 1))
    lines += [
        "",
        "Cost of adaptive against fixed steps at the same error (fixed-step wall time "
        "interpolated log-log at the adaptive run's error; outside the fixed runs' range, "
        "not compared):",
        "",
    ]
    for kind, value, _, _, error, wall, ok in rows:
        if kind != "adaptive" or not ok:
            continue
        if not errors[0] <= np.log(error) <= errors[-1]:
            lines.append(f"- tolerance {value:g} m: error {error:.3g} m, outside the fixed runs'")
            continue
        fixed_wall = float(np.exp(np.interp(np.log(error), errors, walls)))
        lines.append(
            f"- tolerance {value:g} m: error {error:.3g} m, adaptive {wall:.3f} s against "
            f"fixed {fixed_wall:.3f} s: {wall / fixed_wall:.2f}x"
        )
    return lines


if __name__ == "__main__":
    main()
