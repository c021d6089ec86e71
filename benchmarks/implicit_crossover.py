"""When does implicit Euler pay? Simulated cloth-seconds per wall-second of
implicit Euler at a 1/60 s step against the best explicit method at its
largest stable step, across stiffness, with the accuracy each gives up.

For each stiffness of the hanging scene's structural springs (shear and
bending scaled alike), each explicit integrator runs at 0.9 of its own
stable step (the step its ``stable_dt`` reports; half of it if 0.9 diverges) and implicit Euler at
1/60 s; both simulate the same 0.1 s from the same start, timed. Accuracy:
RMS point distance at the end from an RK4 run at a quarter of the explicit
step, and the total energy relative to it (implicit Euler's numerical
damping shows as energy lost). The implicit methods' error is split with
``backward_euler`` (Newton until no point has more than 1e-3 m/s^2
unbalanced) at the same 1/60 s step:
its own error is the time discretisation's, and each method's distance
from it is the solver's (one linearised Newton step for implicit Euler;
stopping after its iterations and leaving out the dashpots for Liu).

Run:  python benchmarks/implicit_crossover.py [--sizes 64] [--factors 0.25 1 4 16 64]
      [--output benchmarks/results/implicit_crossover.md]
      (the 128x128 file: --sizes 128 --factors 0.25 1 4 16
       --output benchmarks/results/implicit_crossover_128.md)
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from provenance import provenance

import pvcloth
from pvcloth.physics.reference import rms_distance

HERE = Path(__file__).parent
EXPLICIT = ("symplectic_euler", "verlet", "rk4")
DURATION = 0.1
FRAME = 1 / 60


def scene_at(n: int, factor: float) -> pvcloth.Scene:
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml").with_resolution(n)
    changes = {}
    for family in ("structural", "shear", "bending"):
        spec = getattr(scene.springs, family)
        if spec is not None:
            changes[f"springs.{family}.stiffness"] = spec.stiffness * factor
            changes[f"springs.{family}.damping"] = spec.damping * factor
    return scene.with_overrides(changes)


def timed(scene, integrator, dt):
    sim = pvcloth.Simulation(scene, integrator=integrator, dt=dt, stability="ignore")
    sim.advance(0.05)  # leave the flat start (and compile) before timing
    start = time.perf_counter()
    sim.advance(DURATION)
    return sim, time.perf_counter() - start


def split(sim, converged) -> float:
    """The solver's share of ``sim``'s error: its distance from converged
    backward Euler, NaN when that reference did not converge."""
    return math.nan if converged is None else rms_distance(sim.positions, converged.positions)


def cell(value: float) -> str:
    return "did not converge" if math.isnan(value) else f"{value:.1e}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64])
    parser.add_argument("--factors", type=float, nargs="+", default=[0.25, 1, 4, 16, 64])
    parser.add_argument("--output", default=str(HERE / "results" / "implicit_crossover.md"))
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        for factor in args.factors:
            scene = scene_at(n, factor)
            best = None
            for name in EXPLICIT:
                probe = pvcloth.Simulation(scene, integrator=name, stability="ignore")
                # 0.9 of the linearised limit; far from rest that can still
                # diverge (README: about 0.8 is safe), then half of it.
                for share in (0.9, 0.5):
                    dt = share * probe.stable_dt()
                    dt = DURATION / math.ceil(DURATION / dt)
                    try:
                        sim, wall = timed(scene, name, dt)
                        break
                    except pvcloth.DivergenceError:
                        print(f"{name} diverged at {share} of its stable step")
                rate = DURATION / wall
                if best is None or rate > best[1]:
                    best = (name, rate, dt, sim)
            name, rate, dt, explicit = best
            implicit, wall = timed(scene, "implicit_euler", FRAME)
            liu, liu_wall = timed(scene, "fast_mass_spring", FRAME)
            bdf2, bdf2_wall = timed(scene, "fast_bdf2", FRAME)
            try:
                converged, _ = timed(scene, "backward_euler", FRAME)
            except pvcloth.DivergenceError as error:
                # Its Newton can stall on a stiff, fine cloth: the split is
                # then unknown, and the table says so rather than guess it.
                print(f"no converged reference: {error}")
                converged = None
            truth = pvcloth.Simulation(scene, integrator="rk4", dt=dt / 4, stability="ignore")
            truth.advance(0.05 + DURATION)
            # Compare at the same time: implicit ended on a 1/60 grid.
            end = implicit.time
            truth.advance(max(0.0, end - truth.time))
            e_ref = truth.energy()["total"]

            def rms(sim, truth=truth):
                return rms_distance(sim.positions, truth.positions)

            rows.append(
                dict(
                    n=n,
                    factor=factor,
                    k=scene.springs.structural.stiffness,
                    explicit=name,
                    dt=dt,
                    explicit_rate=rate,
                    implicit_rate=DURATION / wall,
                    explicit_error=rms(explicit),
                    implicit_error=rms(implicit),
                    implicit_energy=(implicit.energy()["total"] - e_ref) / abs(e_ref),
                    liu_rate=DURATION / liu_wall,
                    liu_error=rms(liu),
                    bdf2_rate=DURATION / bdf2_wall,
                    bdf2_error=rms(bdf2),
                    time_error=math.nan if converged is None else rms(converged),
                    implicit_solver=split(implicit, converged),
                    liu_solver=split(liu, converged),
                )
            )
            print(rows[-1])
    lines = [
        "# Implicit Euler against the best explicit method",
        "",
        provenance(),
        "",
        f"`{' '.join(['python benchmarks/implicit_crossover.py', *sys.argv[1:]])}`: "
        "hanging scene, all "
        "spring stiffnesses and dampings scaled together; explicit methods at 0.9 of their "
        f"stable step, implicit Euler at 1/60 s; {DURATION:g} s simulated after 0.05 s. Rate = "
        "simulated seconds per wall second (higher is faster). Errors: RMS point distance from "
        "RK4 at a quarter of the explicit step (explicit compared at its end time, implicit at "
        "its own); energy: implicit Euler's total energy relative to the reference "
        "(negative = numerical damping). Liu = `fast_mass_spring` (Liu et al. 2013, "
        "10 local/global iterations per step, prefactorised) at 1/60 s. Time = converged "
        "backward Euler's error at 1/60 s (the time discretisation's share of every implicit "
        'error); solver = the method\'s distance from it ("did not converge": backward '
        "Euler's Newton stalled at that stiffness, so the split is unknown there). BDF2 = "
        "`fast_bdf2` (second order, 10 local/global iterations) at 1/60 s.",
        "",
        "| points | structural k (N/m) | best explicit | its dt (s) | explicit rate "
        "| implicit rate | implicit / explicit | explicit error (m) | implicit error (m) "
        "| implicit energy | Liu rate | Liu / explicit | Liu error (m) | time (m) "
        "| implicit solver (m) | Liu solver (m) | BDF2 rate | BDF2 / explicit | BDF2 error (m) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['n']}x{r['n']} | {r['k']:g} | {r['explicit']} | {r['dt']:.2g} | "
            f"{r['explicit_rate']:.3g} | {r['implicit_rate']:.3g} | "
            f"{r['implicit_rate'] / r['explicit_rate']:.2f} | {r['explicit_error']:.1e} | "
            f"{r['implicit_error']:.1e} | {r['implicit_energy']:+.1%} | {r['liu_rate']:.3g} | "
            f"{r['liu_rate'] / r['explicit_rate']:.1f} | {r['liu_error']:.1e} | "
            f"{cell(r['time_error'])} | {cell(r['implicit_solver'])} | {cell(r['liu_solver'])} | "
            f"{r['bdf2_rate']:.3g} | {r['bdf2_rate'] / r['explicit_rate']:.1f} | "
            f"{r['bdf2_error']:.1e} |"
        )
    out = Path(args.output)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
