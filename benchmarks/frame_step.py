"""Second order at frame steps: each implicit method's error at 0.5 s and 1 s
on cotton falling from flat, against its cost.

``python benchmarks/frame_step.py`` runs the bundled cotton scene
(``data/scenes/cotton.toml``: 1 m square, 2112 N/m, 0.22 kg/m^2, plate
bending, air damping 1/s, held by two corners, starting flat) from rest,
one method after another in one process. ``NAME:K`` runs ``NAME`` with
``solver.iterations = K``; ``NAME+lbfgs`` with ``solver.accelerator =
"lbfgs"``; ``NAME@S`` takes ``S`` steps per 1/60 s frame (one by default).

For each: the RMS distance of the points from a reference at 0.5 s and at
1 s; the total energy (kinetic, gravity's and the springs') at 1 s; the
median wall time per 1/60 s frame (everything the simulation does) and the
real-time factor (1/60 s over that median). The reference is RK4 at symplectic
Euler's automatic step (written independently of the implicit solvers; its
distance from RK4 at half that step is printed under the table). For the
methods solved by a fixed count of iterations the distance from the method
they approximate, solved to convergence at the same step (``converges_to``:
``backward_euler`` or ``bdf2``, Newton until no point has 1e-3 m/s^2
unbalanced), is the *solver* part of their error. The dashpots that
``fast_mass_spring`` and ``fast_bdf2`` leave out are measured as RK4's
distance with and without them. Writes ``benchmarks/results/frame_step.md``.

``--stability`` runs instead each method for 10 s at 1/60 s steps on cotton
at 32x32 points and on the same cloth a hundred times lighter with neither
dashpots nor air damping (the stiffest, lightest and least damped case),
and writes the largest and the last total energy over the initial, and the
fastest point at the end, to ``benchmarks/results/frame_step_stability.md``.
Iteration counts below what ``fast_bdf2`` accepts are set on the integrator
after it is made.

``--convergence`` runs instead ``bdf2`` solved to convergence at 1, 2, 4 ...
steps per frame on cotton at 8x8 and 32x32 points, each against RK4 on its
grid, and writes where the error at 0.5 s and at 1 s starts to fall as the
square of the step to ``benchmarks/results/frame_step_convergence.md``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.physics.reference import rms_distance
from pvcloth.studies.runs import dividing_step

HERE = Path(__file__).parent
FRAME = 1 / 60
#: Frames run, and the two at which the error is measured (0.5 s and 1 s).
FRAMES, CHECKS = (6, (3, 6)) if SMOKE else (60, (30, 60))
#: The fast methods first, timed while nothing else runs; the Newton
#: references (seconds per step) after them.
METHODS = (
    "fast_mass_spring:10",
    "fast_mass_spring:20",
    "fast_bdf2:10",
    "fast_bdf2:20",
    "fast_bdf2:50",
    "fast_bdf2:200",
    "fast_bdf2+lbfgs:5",
    "fast_bdf2+lbfgs:10",
    "fast_bdf2+lbfgs:20",
    "fast_bdf2+lbfgs:50",
    "backward_euler",
    "bdf2",
    "bdf2@2",
)


def parse(method: str) -> tuple[str, int | None, int, str | None]:
    """``"fast_bdf2+lbfgs:20@2"`` -> ``("fast_bdf2", 20, 2, "lbfgs")``: the
    integrator, its iterations, steps per frame and ``solver.accelerator``."""
    head, _, per_frame = method.partition("@")
    head, _, iterations = head.partition(":")
    name, _, accelerator = head.partition("+")
    return (
        name,
        int(iterations) if iterations else None,
        int(per_frame or 1),
        accelerator or None,
    )


def configured(scene, method: str):
    """``scene`` with ``method``'s iterations and accelerator, and its
    integrator's name and steps per frame."""
    name, iterations, per_frame, accelerator = parse(method)
    changes = {"solver.iterations": iterations, "solver.accelerator": accelerator}
    return scene.with_overrides({k: v for k, v in changes.items() if v}), name, per_frame


def run(scene, method: str, frames: int) -> dict:
    """Positions at each check, energy at the end, wall time per frame."""
    scene, name, per_frame = configured(scene, method)
    sim = pvcloth.Simulation(scene, integrator=name, dt=FRAME / per_frame, stability="ignore")
    positions, walls, failure = {}, [], None
    try:
        for frame in range(1, frames + 1):
            start = time.perf_counter()
            sim.advance(FRAME)
            walls.append(time.perf_counter() - start)
            if frame in CHECKS:
                positions[frame] = sim.positions.copy()
    except pvcloth.DivergenceError as error:  # a Newton reference can stall
        failure = str(error).splitlines()[0]
    return {
        "sim": sim,
        "positions": positions,
        "failure": failure,
        "energy": energy(sim),
        "ms": 1e3 * statistics.median(walls) if walls else float("nan"),
        "real_time": FRAME / statistics.median(walls) if walls else float("nan"),
    }


def energy(sim) -> float:
    """Kinetic plus potential energy (J) of the current state."""
    return sim.model.kinetic_energy(sim.velocities) + sim.model.potential_energy(sim.positions)


def undamped(scene):
    """``scene`` with every spring's dashpot removed (the families it has)."""
    families = [f for f in ("structural", "shear", "bending") if getattr(scene.springs, f)]
    return scene.with_overrides({f"springs.{family}.damping": 0.0 for family in families})


def pair(a: dict, b: dict) -> str:
    """``a`` against ``b`` at each check, in centimetres."""
    return " / ".join(
        f"{100 * rms_distance(a[k], b[k]):.2f}" if k in a and k in b else "-" for k in CHECKS
    )


#: The stability runs: fewer iterations than the front's, to find the edge.
STABILITY = (
    "fast_mass_spring:3",
    "fast_mass_spring:6",
    "fast_mass_spring:10",
    "fast_bdf2:5",
    "fast_bdf2:6",
    "fast_bdf2:8",
    "fast_bdf2:10",
    "fast_bdf2:20",
    "fast_mass_spring+lbfgs:2",
    "fast_mass_spring+lbfgs:3",
    "fast_bdf2+lbfgs:3",
    "fast_bdf2+lbfgs:5",
    "backward_euler",
    "bdf2",
)


def stability(args) -> list[str]:
    """Table rows: each method for 10 s on two cloths, energies over the initial."""
    cotton = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    cotton = cotton.with_resolution(8 if SMOKE else 32).with_overrides({"solver.iterations": None})
    light = undamped(cotton).with_overrides(
        {"cloth.mass": cotton.cloth.mass / 100, "air_damping": 0.0}
    )
    rows = []
    for label, scene in (("cotton", cotton), ("light, undamped", light)):
        for method in args.methods:
            name, iterations, _, accelerator = parse(method)
            sim = pvcloth.Simulation(
                scene.with_overrides({"solver.accelerator": accelerator}),
                integrator=name,
                dt=FRAME,
                stability="ignore",
            )
            if iterations:
                sim.integrator.iterations = iterations  # below fast_bdf2's minimum too
            energies, outcome = [energy(sim)], ""
            try:
                for _ in range(12 if SMOKE else 600):
                    sim.advance(FRAME)
                    energies.append(energy(sim))
            except pvcloth.PvclothError as error:
                outcome = str(error).splitlines()[0]
            start = energies[0]
            speed = float(np.linalg.norm(sim.velocities, axis=1).max())
            row = (
                f"| {label} | {method} | {max(energies) / start:.3g} | {energies[-1] / start:.3g} "
                f"| {speed:.3g} | {sim.time:.2f} | {outcome or '-'} |"
            )
            print(row, flush=True)
            rows.append(row)
    return [
        "# Second order at frame steps: stability",
        "",
        provenance(),
        "",
        f"`python benchmarks/frame_step.py{''.join(' ' + a for a in sys.argv[1:])}`: each "
        "method for 10 s at 1/60 s steps from flat and at rest on the cotton scene at "
        f"{cotton.cloth.resolution[0]}x{cotton.cloth.resolution[1]} points, and on the same "
        "cloth a hundred times lighter with neither dashpots nor air damping. Energy = "
        "kinetic + gravity + springs + plate, over its initial value (gravity's, the cloth "
        "being flat and at rest): the physics only loses energy, so a largest value far "
        "above 1 is energy the method made. `NAME:K` = K local/global iterations per step, "
        "`+lbfgs` = L-BFGS in place of Chebyshev's acceleration (`solver.accelerator`).",
        "",
        "| cloth | method | largest energy | energy at the end | fastest point at the end "
        "(m/s) | ran (s) | stopped by |",
        "|---|---|---|---|---|---|---|",
        *rows,
    ]


#: The convergence runs: each grid size and the steps per frame bdf2 takes there.
CONVERGENCE = (
    ((8, (1, 2)),) if SMOKE else ((8, (1, 2, 4, 8, 16, 32, 64, 128)), (32, (1, 2, 4, 8, 16, 32)))
)


def convergence(args) -> list[str]:
    """Table rows: converged bdf2's error at 0.5 s and 1 s as its step shrinks."""
    cotton = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    rows = []
    for size, per_frame in CONVERGENCE:
        scene = cotton.with_resolution(size)
        explicit = pvcloth.Simulation(scene, integrator="symplectic_euler").dt
        truth = pvcloth.Simulation(
            scene, integrator="rk4", dt=dividing_step(FRAME, explicit), stability="ignore"
        )
        reference = {}
        for frame in range(1, FRAMES + 1):
            truth.advance(FRAME)
            if frame in CHECKS:
                reference[frame] = truth.positions.copy()
        before = None
        for steps in per_frame:
            sim = pvcloth.Simulation(scene, integrator="bdf2", dt=FRAME / steps, stability="ignore")
            errors = []
            for frame in range(1, FRAMES + 1):
                sim.advance(FRAME)
                if frame in CHECKS:
                    errors.append(rms_distance(sim.positions, reference[frame]))
            ratios = (
                " / ".join(
                    f"{b / e:.1f}" if e > 0 else "-" for b, e in zip(before, errors, strict=True)
                )
                if before
                else "-"
            )
            before = errors
            row = (
                f"| {size}x{size} | {steps} | {FRAME / steps:.3g} | "
                f"{' / '.join(f'{100 * e:.3f}' for e in errors)} | {ratios} |"
            )
            print(row, flush=True)
            rows.append(row)
    return [
        "# Second order at frame steps: where the error converges",
        "",
        provenance(),
        "",
        f"`python benchmarks/frame_step.py{''.join(' ' + a for a in sys.argv[1:])}`: `bdf2` "
        "(Newton until no point has 1e-3 m/s^2 unbalanced) on the cotton scene from flat and "
        "at rest, at smaller and smaller steps, each against RK4 at symplectic Euler's "
        "automatic step on the same grid. *error* = RMS point distance at 0.5 s / 1 s (cm); "
        "*ratio* = the previous row's error over this one's (4 for a second-order method "
        "in its asymptotic range, 2 for a first-order one).",
        "",
        "| grid | steps per 1/60 s | dt (s) | error (cm) | ratio |",
        "|---|---|---|---|---|",
        *rows,
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=8 if SMOKE else 64)
    parser.add_argument("--methods", nargs="+")
    parser.add_argument("--stability", action="store_true", help="the stability runs instead")
    parser.add_argument(
        "--convergence", action="store_true", help="converged bdf2 at shrinking steps instead"
    )
    parser.add_argument("--out")
    args = parser.parse_args()
    if args.convergence:
        out = Path(args.out or HERE / "results" / "frame_step_convergence.md")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text("\n".join(convergence(args)) + "\n")
        print(f"wrote {out}")
        return
    if args.stability:
        args.methods = args.methods or list(STABILITY)
        out = Path(args.out or HERE / "results" / "frame_step_stability.md")
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text("\n".join(stability(args)) + "\n")
        print(f"wrote {out}")
        return
    args.methods = args.methods or list(METHODS)
    args.out = args.out or str(HERE / "results" / "frame_step.md")
    frames = FRAMES
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    scene = scene.with_resolution(args.size)
    explicit = pvcloth.Simulation(scene, integrator="symplectic_euler").dt
    step = dividing_step(FRAME, explicit)
    truths = []
    # RK4 at its step, at half of it (the reference's own error), and
    # without the dashpots (the share of the motion they make).
    for cloth, dt in ((scene, step), (scene, step / 2), (undamped(scene), step)):
        truth = pvcloth.Simulation(cloth, integrator="rk4", dt=dt, stability="ignore")
        kept = {}
        for frame in range(1, frames + 1):
            truth.advance(FRAME)
            if frame in CHECKS:
                kept[frame] = truth.positions.copy()
        truths.append((kept, energy(truth)))
        print({"reference dt": dt, "energy": truths[-1][1]}, flush=True)
    (truth, truth_energy), (half, _), (free, _) = truths
    for method in args.methods:
        run(scene, method, 2)  # compiles its kernels before any clock runs
    results = {}
    for method in args.methods:
        results[method] = run(scene, method, frames)
        error = pair(results[method]["positions"], truth)
        failure = results[method]["failure"]
        print(
            {"method": method, "error cm": error, "ms": results[method]["ms"], "failure": failure}
        )
    lines = [
        "# Second order at frame steps",
        "",
        provenance(),
        "",
        f"`python benchmarks/frame_step.py{''.join(' ' + a for a in sys.argv[1:])}`: the "
        f"cotton scene at {args.size}x{args.size} points (1 m square, 2112 N/m, 0.22 kg/m^2, "
        "plate bending, air damping 1/s, two corners pinned) falling from flat and at rest, "
        "each method in turn in one process. *error* = RMS point distance from RK4 at "
        f"{step:.3g} s steps, at 0.5 s / 1 s (cm); *solver* = distance from the converged "
        "method it approximates at the same step (`backward_euler` or `bdf2`: Newton until no "
        "point has more than 1e-3 m/s^2 unbalanced); energy = kinetic + gravity + springs + "
        f"plate at 1 s (RK4: {truth_energy:.4f} J); ms = median wall time per 1/60 s frame; "
        "real time = 1/60 s over that median (2 = twice as fast as real time; each "
        "integrator ran two untimed frames first, which compile its kernels). `NAME:K` = "
        "K local/global iterations per step, `+lbfgs` = L-BFGS in place of Chebyshev's "
        "acceleration (`solver.accelerator`), `@2` = two steps per frame.",
        "",
        "| method | dt (s) | error (cm) | solver (cm) | energy at 1 s (J) | ms per 1/60 s "
        "| real time |",
        "|---|---|---|---|---|---|---|",
    ]
    failures = []
    for method, r in results.items():
        sim = r["sim"]
        target = sim.integrator.converges_to
        twin = next(
            (
                other
                for name, other in results.items()
                if parse(name)[0] == target and other["sim"].dt == sim.dt
            ),
            None,
        )
        solver = pair(r["positions"], twin["positions"]) if twin else "-"
        if r["failure"]:
            lines.append(
                f"| {method} | {sim.dt:.4g} | {pair(r['positions'], truth)} | {solver} "
                f"| - | - | - |"
            )
            failures.append(f"`{method}`: {r['failure']}.")
            continue
        lines.append(
            f"| {method} | {sim.dt:.4g} | {pair(r['positions'], truth)} | {solver} "
            f"| {r['energy']:.4f} | {r['ms']:.1f} | {r['real_time']:.2f} |"
        )
    if failures:
        lines += [
            "",
            "Stopped before 1 s (the Newton solve stalled; a dash where there is no "
            "position to compare): " + " ".join(failures),
        ]
    lines += [
        "",
        f"The reference: RK4 at half its step ends {pair(half, truth)} cm from it. The "
        "dashpots `fast_mass_spring` and `fast_bdf2` leave out: RK4 without them ends "
        f"{pair(free, truth)} cm from RK4 with them.",
    ]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
