"""Real fabric at frame steps: speed and error of each method on cotton.

``python benchmarks/fabric_speed.py`` runs the bundled cotton scene
(``data/scenes/cotton.toml``: 1 m square, 2112 N/m, 0.22 kg/m^2, hanging
from two corners) at each size, one method after another in one process:

- the implicit ones at one 1/60 s step per frame;
- symplectic Euler at its automatic step (at most half its stable step,
  dividing 1/60 s), the fastest stable explicit option.

For each: the median wall time per 1/60 s of cloth (everything the
simulation does, guard and pins included, timed over ``--seconds`` after
0.2 s of settling), the real-time factor (simulated over wall seconds),
and the RMS distance of the points from a reference at the end: RK4 at
symplectic Euler's step, a solution of the same equations
written independently of the implicit solvers. The error includes both the
time discretisation and, for ``fast_mass_spring``, stopping after its
iterations. (RK4 at that step is stable, its limit being 2.8/omega against
symplectic Euler's 2/omega, and fourth order: its own error is far below
the centimetres measured here.) Writes ``benchmarks/results/fabric_speed.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from pathlib import Path

from smoke import SMOKE

import pvcloth
from pvcloth.studies.runs import dividing_step, rms_distance

HERE = Path(__file__).parent
FRAME = 1 / 60
SETTLE = 0.2
METHODS = ("fast_mass_spring", "implicit_euler", "symplectic_euler")


def run(scene, integrator: str, seconds: float, dt: float | None = None) -> dict:
    sim = pvcloth.Simulation(scene, integrator=integrator, dt=dt, stability="ignore")
    sim.advance(SETTLE)  # compile, leave the flat start
    frames = []
    for _ in range(round(seconds / FRAME)):
        start = time.perf_counter()
        sim.advance(FRAME)
        frames.append(time.perf_counter() - start)
    return {"sim": sim, "ms": 1e3 * statistics.median(frames), "wall": sum(frames)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[8] if SMOKE else [64, 128])
    parser.add_argument("--seconds", type=float, default=0.1 if SMOKE else 0.5)
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--out", default=str(HERE / "results" / "fabric_speed.md"))
    args = parser.parse_args()
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    rows = []
    for n in args.sizes:
        scene = base.with_resolution(n)
        explicit = pvcloth.Simulation(scene, integrator="symplectic_euler").dt
        duration = SETTLE + round(args.seconds / FRAME) * FRAME
        truth = pvcloth.Simulation(
            scene, integrator="rk4", dt=dividing_step(duration, explicit), stability="ignore"
        )
        truth.advance(duration)
        for name in args.methods:
            result = run(
                scene, name, args.seconds, explicit if name == "symplectic_euler" else None
            )
            sim = result["sim"]
            rows.append(
                {
                    "n": n,
                    "method": name,
                    "dt": sim.dt,
                    "ms": result["ms"],
                    "real_time": (sim.time - SETTLE) / result["wall"],
                    "error": rms_distance(sim.positions, truth.positions),
                }
            )
            print(rows[-1], flush=True)
    lines = [
        "# Real fabric at frame steps",
        "",
        f"`python benchmarks/fabric_speed.py{''.join(' ' + a for a in sys.argv[1:])}` on "
        f"{platform.node()}: the cotton scene "
        "(1 m square, 2112 N/m stretch, 0.22 kg/m^2, two corners pinned), each method in "
        f"turn in one process, {args.seconds:g} s of cloth timed after {SETTLE:g} s. ms = "
        "median wall time per 1/60 s of cloth, everything included; real time = simulated "
        "over wall seconds (2 = twice as fast as real time); error = RMS point distance "
        "from RK4 at symplectic Euler's step, at the end.",
        "",
        "| points | method | dt (s) | ms per 1/60 s | real time | error vs RK4 (m) |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['n']}x{r['n']} | {r['method']} | {r['dt']:.3g} | {r['ms']:.1f} "
        f"| {r['real_time']:.2f} | {r['error']:.1e} |"
        for r in rows
    ]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
