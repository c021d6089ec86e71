"""Fresh memory per step: reused (double-buffered) states against new ones.

``python benchmarks/step_allocations.py`` runs the hanging scene with each
integrator twice in one process, side by side: as pvcloth runs it (the state
a step replaces becomes the memory the next step writes, when nothing else
holds it) and with that reuse switched off (every step allocates its new
state, as pvcloth did before). For each it reports the minor page faults and
the traced bytes allocated beyond what was already held, per step, and the
median wall time per step. A page fault here is the kernel handing the
process a fresh page: what a new array of a big grid costs on first touch.
Writes ``benchmarks/results/step_allocations.md``.
"""

from __future__ import annotations

import argparse
import platform
import resource
import statistics
import time
import tracemalloc
from pathlib import Path

from provenance import provenance
from smoke import SMOKE

import pvcloth

HERE = Path(__file__).parent
INTEGRATORS = ("symplectic_euler", "verlet", "rk4")


def measure(n: int, integrator: str, reuse: bool, steps: int) -> dict:
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml")
    # The automatic step: the scene's own is unstable on finer grids.
    scene = scene.with_resolution(n).with_overrides({"solver.dt": None})
    sim = pvcloth.Simulation(scene, integrator=integrator)
    if not reuse:  # every step takes new memory: the spare state is not offered
        step = sim.integrator.step
        sim.integrator.step = lambda model, state, control, dt, out=None: step(
            model, state, control, dt
        )
    for _ in range(20):  # compile, warm caches
        sim.step()
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        sim.step()
        times.append(time.perf_counter() - start)
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
    tracemalloc.start()
    held = tracemalloc.get_traced_memory()[0]
    tracemalloc.reset_peak()
    sim.step()
    peak = tracemalloc.get_traced_memory()[1] - held
    tracemalloc.stop()
    new_state = 2 * sim.positions.nbytes  # positions and velocities
    if not reuse and peak < new_state:
        raise RuntimeError(
            f"the new-states arm allocated {peak} B in a step, less than a state "
            f"({new_state} B): its hook no longer reaches the step"
        )
    return {
        "faults": faults / steps,
        "peak_bytes": peak,
        "ms": 1e3 * statistics.median(times),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[8] if SMOKE else [64, 256])
    parser.add_argument("--steps", type=int, default=5 if SMOKE else 300)
    parser.add_argument("--out", default=str(HERE / "results" / "step_allocations.md"))
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        for name in INTEGRATORS:
            fresh = measure(n, name, False, args.steps)
            reused = measure(n, name, True, args.steps)
            rows.append((n, name, fresh, reused))
            print(n, name, fresh, reused, flush=True)
    lines = [
        "# Fresh memory per step",
        "",
        provenance(),
        "",
        f"`python benchmarks/step_allocations.py` "
        f"({platform.processor() or platform.machine()}): hanging scene, compiled backend, "
        f"{args.steps} steps each, both ways in one process. *new states*: every step "
        "allocates its result (pvcloth before the double buffer); *reused*: the state a "
        "step replaced is written by the next one. Faults = minor page faults per step "
        "(fresh pages from the kernel); traced = bytes allocated within one step beyond "
        "what was held before it (tracemalloc peak); ms = median wall time per step.",
        "",
        "| points | integrator | faults/step, new states | faults/step, reused "
        "| traced B/step, new states | traced B/step, reused | ms, new states | ms, reused "
        "| reused / new |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for n, name, fresh, reused in rows:
        lines.append(
            f"| {n}x{n} | {name} | {fresh['faults']:.1f} | {reused['faults']:.1f} "
            f"| {fresh['peak_bytes']:,} | {reused['peak_bytes']:,} "
            f"| {fresh['ms']:.3f} | {reused['ms']:.3f} | {reused['ms'] / fresh['ms']:.2f} |"
        )
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
