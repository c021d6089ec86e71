"""BLAS threads beside the kernels' OpenMP threads: held to one, or free.

pvcloth steps with every BLAS library held to one thread while its compiled
kernels run (``pvcloth.physics.blas``). This times the implicit
integrators, whose solvers call BLAS (conjugate gradients' dot products,
SuperLU's dense blocks) between kernel calls, both ways side by side: rounds
interleaved, each round a few steps of each arm from the same state. The
table gives the median and the slowest step and the process's CPU time over
wall time (2 would mean both cores busy all the time).

Run:  python benchmarks/blas_threads.py [--sizes 64 128] [--rounds 5]
      (writes benchmarks/results/blas_threads.md)
"""

from __future__ import annotations

import argparse
import contextlib
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE
from threadpoolctl import threadpool_info

import pvcloth
from pvcloth.physics.simulation import Simulation

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"
DT = 1.0 / 240.0
INTEGRATORS = ("implicit_euler", "backward_euler")
STEPS_PER_ROUND = 2


def build(n: int, integrator: str) -> Simulation:
    scene = pvcloth.load_scene(SCENE).with_resolution(n)
    sim = pvcloth.Simulation(scene, integrator=integrator, dt=DT, stability="ignore")
    sim.advance(4 * DT)  # moving, compiled, factorisations made once
    return sim


def time_steps(sim: Simulation, held: bool) -> list[tuple[float, float]]:
    """(wall, cpu) seconds of each step, with pvcloth's BLAS limit or without."""
    original = Simulation._one_pool
    if not held:
        Simulation._one_pool = lambda self: contextlib.nullcontext()
    try:
        timings = []
        for _ in range(STEPS_PER_ROUND):
            cpu, wall = time.process_time(), time.perf_counter()
            sim.step()
            timings.append((time.perf_counter() - wall, time.process_time() - cpu))
        return timings
    finally:
        Simulation._one_pool = original


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 128])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "blas_threads.md")
    args = parser.parse_args()
    sizes, rounds = ([8], 1) if SMOKE else (args.sizes, args.rounds)
    rows = []
    for n in sizes:
        for integrator in INTEGRATORS:
            sims = {"held": build(n, integrator), "free": build(n, integrator)}
            timings = {arm: [] for arm in sims}
            for _ in range(rounds):
                for arm, sim in sims.items():
                    timings[arm] += time_steps(sim, held=arm == "held")
            for arm, steps in timings.items():
                wall = np.array([w for w, _ in steps])
                cpu = np.array([c for _, c in steps])
                ratio = cpu.sum() / wall.sum()
                rows.append((n, integrator, arm, np.median(wall), wall.max(), ratio))
                print(f"{n:4d} {integrator:16s} {arm}: median {1e3 * rows[-1][3]:.1f} ms")
    libraries = [i for i in threadpool_info() if i["user_api"] == "blas"]
    blas = sorted(
        {f"{i['internal_api']} {i['version']} ({i['num_threads']} threads)" for i in libraries}
    )
    lines = [
        "# BLAS threads beside the kernels' threads",
        "",
        provenance(),
        "",
        f"`python benchmarks/blas_threads.py`: hanging scene, dt = 1/240 s, {rounds} interleaved "
        f"rounds of {STEPS_PER_ROUND} steps per arm. *held*: pvcloth's default, every BLAS "
        "library on one thread while a step runs; *free*: BLAS at its own thread count "
        f"(here: {', '.join(blas)}). ms per step; CPU over wall is the process's CPU time over "
        "wall time during the steps (2 = both cores busy throughout).",
        "",
        "| points per side | integrator | BLAS | median (ms) | slowest (ms) | CPU / wall |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {n} | {integrator} | {arm} | {1e3 * median:.1f} | {1e3 * worst:.1f} | {ratio:.2f} |"
        for n, integrator, arm, median, worst, ratio in rows
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
