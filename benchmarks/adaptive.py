"""Adaptive steps against fixed ones: error reached and what it cost.

For each scene, ``rk23`` runs once per tolerance (steps chosen by its error
estimate) and once per fixed step, from the same start to the same end; each
run's error is its largest point distance from RK4 at a tiny fixed step
(independent of the method measured). The table lists both kinds; the
summary compares, at the error each adaptive run reached, its wall time with
the fixed-step run's interpolated (log-log) at that error: the cost of
letting the controller choose. Scenes: the 16x16 hanging cloth (a swing
that calms) and a 12x12 cloth dropped on the ground (a fall, an impact and
rest: quiet and violent phases).

Run:  python benchmarks/adaptive.py [--out FILE]
      (writes benchmarks/results/adaptive.md)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from smoke import SMOKE

import pvcloth

HERE = Path(__file__).parent
SCENES = HERE.parent / "data" / "scenes"
TOLERANCES = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)


def cases():
    hanging = pvcloth.load_scene(SCENES / "hanging.toml").with_resolution(8 if SMOKE else 16)
    ground = pvcloth.load_scene(SCENES / "ground.toml").with_resolution(8 if SMOKE else 12)
    duration = 0.1 if SMOKE else 1.0
    return [("hanging 16x16", hanging, duration), ("ground drop 12x12", ground, duration)]


#: Each run is repeated and its median wall time kept: the same step's cost
#: varied by 2x between repeats on this shared machine.
REPEATS = 1 if SMOKE else 3


def run(scene, duration, **solver):
    """The run, its median wall time over :data:`REPEATS` identical runs, and
    whether it finished (runs are deterministic: the last one is returned)."""
    walls = []
    for _ in range(REPEATS):
        sim = pvcloth.Simulation(
            scene.with_overrides({f"solver.{k}": v for k, v in solver.items()}), stability="ignore"
        )
        start = time.perf_counter()
        try:
            sim.advance(duration)
        except pvcloth.DivergenceError:
            return sim, time.perf_counter() - start, False
        walls.append(time.perf_counter() - start)
    return sim, float(np.median(walls)), True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE / "results" / "adaptive.md")
    args = parser.parse_args()
    lines = [
        "# Adaptive steps against fixed ones",
        "",
        f"`{' '.join(['python benchmarks/adaptive.py', *sys.argv[1:]])}`: rk23 with "
        "`solver.tolerance` (adaptive) and at fixed steps, error = largest point distance "
        "from RK4 at a fixed step of 1/40000 of the run, wall = median seconds of `advance` "
        f"over {REPEATS} identical runs. "
        "The stated relation is error <= about tolerance * t / 1 s "
        "(`pvcloth/physics/adaptive.py`).",
    ]
    for title, scene, duration in cases():
        base = scene.with_overrides({"solver.dt": None})
        reference = pvcloth.Simulation(base, integrator="rk4", dt=duration / 40000)
        reference.advance(duration)
        stable = pvcloth.Simulation(base, integrator="rk23").stable_dt()
        rows = []
        for tolerance in TOLERANCES[:2] if SMOKE else TOLERANCES:
            sim, wall, ok = run(base, duration, integrator="rk23", tolerance=tolerance)
            error = np.linalg.norm(sim.positions - reference.positions, axis=1).max()
            rows.append(
                ("adaptive", tolerance, sim.steps, sim.controller.rejected, error, wall, ok)
            )
            print(title, rows[-1], flush=True)
        for share in (0.9, 0.45, 0.2, 0.1, 0.05, 0.02)[: 2 if SMOKE else None]:
            dt = duration / np.ceil(duration / (share * stable))
            sim, wall, ok = run(base, duration, integrator="rk23", dt=dt)
            error = np.linalg.norm(sim.positions - reference.positions, axis=1).max()
            rows.append(("fixed", dt, sim.steps, 0, error, wall, ok))
            print(title, rows[-1], flush=True)
        lines += [
            "",
            f"## {title}, {duration:g} s (rk23's stable step about {stable:.3g} s)",
            "",
            "| run | tolerance (m) or dt (s) | steps | rejected | error (m) | "
            "error / (tolerance t) | wall (s) |",
            "|---|---|---|---|---|---|---|",
        ]
        for kind, value, steps, rejected, error, wall, ok in rows:
            relation = f"{error / (value * duration):.2f}" if kind == "adaptive" else ""
            shown = f"{error:.3g}" if ok else "diverged"
            lines.append(
                f"| {kind} | {value:.3g} | {steps} | {rejected} | {shown} | {relation} "
                f"| {wall:.3f} |"
            )
        fixed = sorted((e, w) for k, _, _, _, e, w, ok in rows if k == "fixed" and ok)
        if len(fixed) >= 2:
            errors, walls = (np.log([f[i] for f in fixed]) for i in (0, 1))
            lines += [
                "",
                "Cost of adaptive against fixed steps at the same error "
                "(fixed-step wall time interpolated log-log at the adaptive run's error):",
                "",
            ]
            for kind, value, _, _, error, wall, ok in rows:
                if kind != "adaptive" or not ok or not errors[0] <= np.log(error) <= errors[-1]:
                    continue
                fixed_wall = float(np.exp(np.interp(np.log(error), errors, walls)))
                lines.append(
                    f"- tolerance {value:g} m: error {error:.3g} m, adaptive {wall:.3f} s against "
                    f"fixed {fixed_wall:.3f} s: {wall / fixed_wall:.2f}x"
                )
    args.out.parent.mkdir(exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
