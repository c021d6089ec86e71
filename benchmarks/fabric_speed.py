"""Real fabric at frame steps: speed and error of each method on cotton.

``python benchmarks/fabric_speed.py`` runs the bundled cotton scene
(``data/scenes/cotton.toml``: 1 m square, 2112 N/m, 0.22 kg/m^2, hanging
from two corners) at each size, one method after another in one process:

- the implicit ones at one 1/60 s step per frame (``NAME:K`` runs
  ``NAME`` with ``solver.iterations = K``);
- symplectic Euler at its automatic step (at most half its stable step,
  dividing 1/60 s), the fastest stable explicit option.

For each: the median wall time per 1/60 s of cloth (everything the
simulation does, guard and pins included, timed over ``--seconds`` after
0.2 s of settling), the real-time factor (simulated over wall seconds),
and the RMS distance of the points from a reference at the end: RK4 at
symplectic Euler's step, a solution of the same equations written
independently of the implicit solvers (RK4 at that step is stable, its
limit being 2.8/omega against symplectic Euler's 2/omega, and fourth
order: its own error is far below what is measured here).

At the sizes in ``--converged`` the implicit methods' error is split with
``backward_euler`` (Newton until no point has more than 1e-3 m/s^2
unbalanced) at the same 1/60 s step:
*time*, backward Euler's own distance from RK4 (only a smaller step lowers
it), and *solver*, the method's distance from backward Euler (what stopping
early or leaving terms out costs). The dashpots ``fast_mass_spring`` leaves
out are measured there too: converged backward Euler with them against
without them. Writes ``benchmarks/results/fabric_speed.md``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.physics.reference import rms_distance
from pvcloth.studies.runs import dividing_step

HERE = Path(__file__).parent
FRAME = 1 / 60
SETTLE = 0.2
METHODS = (
    "fast_mass_spring:6",
    "fast_mass_spring:10",
    "fast_mass_spring:20",
    "implicit_euler",
    "symplectic_euler",
)
CONVERGED = "backward_euler"


def run(scene, method: str, seconds: float, dt: float | None = None) -> dict:
    name, _, iterations = method.partition(":")
    if iterations:
        scene = scene.with_overrides({"solver.iterations": int(iterations)})
    sim = pvcloth.Simulation(scene, integrator=name, dt=dt, stability="ignore")
    sim.advance(SETTLE)  # compile, leave the flat start
    frames = []
    for _ in range(round(seconds / FRAME)):
        start = time.perf_counter()
        sim.advance(FRAME)
        frames.append(time.perf_counter() - start)
    return {"sim": sim, "ms": 1e3 * statistics.median(frames), "wall": sum(frames)}


def undamped(scene):
    """``scene`` with every spring's dashpot removed (the families it has)."""
    families = [f for f in ("structural", "shear", "bending") if getattr(scene.springs, f)]
    return scene.with_overrides({f"springs.{family}.damping": 0.0 for family in families})


def metres(value: float | None) -> str:
    return "-" if value is None else f"{value:.1e}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[8] if SMOKE else [64, 128])
    parser.add_argument("--seconds", type=float, default=0.1 if SMOKE else 0.5)
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument(
        "--converged",
        type=int,
        nargs="*",
        default=[8] if SMOKE else [64],
        help="sizes at which to split the error with converged backward Euler (slow: "
        "seconds per step at 64x64)",
    )
    parser.add_argument("--out", default=str(HERE / "results" / "fabric_speed.md"))
    args = parser.parse_args()
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    rows, gaps, failures = [], {}, {}
    for n in args.sizes:
        scene = base.with_resolution(n)
        explicit = pvcloth.Simulation(scene, integrator="symplectic_euler").dt
        duration = SETTLE + round(args.seconds / FRAME) * FRAME
        truth = pvcloth.Simulation(
            scene, integrator="rk4", dt=dividing_step(duration, explicit), stability="ignore"
        )
        truth.advance(duration)
        finals = {}
        for method in args.methods:
            dt = explicit if method == "symplectic_euler" else None
            result = run(scene, method, args.seconds, dt)
            sim = result["sim"]
            finals[method] = (sim.positions, sim.integrator.converges_to == CONVERGED)
            row = {
                "n": n,
                "method": method,
                "dt": sim.dt,
                "ms": result["ms"],
                "real_time": (sim.time - SETTLE) / result["wall"],
                "error": rms_distance(sim.positions, truth.positions),
                "time": None,
                "solver": None,
            }
            rows.append(row)
            print(row, flush=True)
        if n in args.converged:
            # After the timed runs, so that their clocks ran on a quiet
            # machine: converged backward Euler takes seconds per step.
            try:
                converged = run(scene, CONVERGED, args.seconds)["sim"]
                free = run(undamped(scene), CONVERGED, args.seconds)["sim"].positions
            except pvcloth.DivergenceError as error:
                failures[n] = str(error).splitlines()[0]
                print({"n": n, "converged": failures[n]}, flush=True)
                continue
            for row in rows:
                positions, approximates = finals[row["method"]]
                if row["n"] == n and approximates:
                    row["time"] = rms_distance(converged.positions, truth.positions)
                    row["solver"] = rms_distance(positions, converged.positions)
            gaps[n] = rms_distance(free, converged.positions)
            print({"n": n, "dashpot gap": gaps[n]}, flush=True)
    lines = [
        "# Real fabric at frame steps",
        "",
        provenance(),
        "",
        f"`python benchmarks/fabric_speed.py{''.join(' ' + a for a in sys.argv[1:])}`: "
        "the cotton scene (1 m square, 2112 N/m stretch, 0.22 kg/m^2, two corners pinned), "
        "each method in "
        f"turn in one process, {args.seconds:g} s of cloth timed after {SETTLE:g} s. ms = "
        "median wall time per 1/60 s of cloth, everything included; real time = simulated "
        "over wall seconds (2 = twice as fast as real time); error = RMS point distance "
        f"from RK4 at symplectic Euler's step, at the end (t = {duration:.3g} s). "
        "`fast_mass_spring:K` = K local/global iterations per step. For the implicit "
        f"methods, *time* is converged backward Euler's error at the same step (`{CONVERGED}`, "
        "Newton until no point has more than 1e-3 m/s^2 unbalanced) and *solver* the "
        "method's distance from it.",
        "",
        "| points | method | dt (s) | ms per 1/60 s | real time | error vs RK4 (m) "
        "| of which time (m) | solver (m) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['n']}x{r['n']} | {r['method']} | {r['dt']:.3g} | {r['ms']:.1f} "
        f"| {r['real_time']:.2f} | {r['error']:.1e} "
        f"| {metres(r['time'])} | {metres(r['solver'])} |"
        for r in rows
    ]
    for n, gap in gaps.items():
        lines += [
            "",
            f"Dashpots, which `fast_mass_spring` leaves out, at {n}x{n}: converged backward "
            f"Euler with and without them ends {gap:.1e} m apart (part of its solver error).",
        ]
    for n, failure in failures.items():
        lines += ["", f"At {n}x{n} the converged reference failed, so no split: {failure}"]
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
