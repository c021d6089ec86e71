"""Contact inside the fast implicit solve against the response after the step.

``python benchmarks/contact_in_step.py`` drops cotton (``data/scenes/cotton.toml``'s
fabric, unpinned) flat onto the ground from 2 cm, and onto a 0.25 m sphere
standing on the ground from 0.6 m, at one 1/60 s step a frame: with
``fast_bdf2`` at 32x32 and 64x64 points (contact impulses in its
local/global solve, :mod:`pvcloth.physics.contact`) and with ``bdf2`` at
16x16 (a penalty in Newton's potential,
:class:`~pvcloth.physics.integrators.penalties.ObstaclePenalty`; seconds
a step at 64x64). Each runs two ways in one process, in turns of five frames: with the
obstacles inside the solve (the default) and with them left to the response
after the step alone (``integrator.contact_in_step = False``, as the
explicit integrators have them). For each: the kinetic energy over the last simulated
second (mean and largest: a cloth at rest has none, a jittering one keeps
some), the smallest gap to an obstacle grown by its thickness over every
frame (negative: inside), and the median wall time of a frame.
Writes ``benchmarks/results/contact_in_step.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth import ObstacleSpec
from pvcloth.physics.simulation import Simulation

HERE = Path(__file__).parent
CASES = (
    (("fast_bdf2", 8), ("bdf2", 6))
    if SMOKE
    else (("fast_bdf2", 32), ("fast_bdf2", 64), ("bdf2", 16))
)
SECONDS = 0.2 if SMOKE else 5.0
GROUND = ObstacleSpec("ground", thickness=0.005, friction=0.5, static_friction=0.7)
SPHERE = ObstacleSpec("sphere", center=(0, 0, 0.25), radius=0.25, thickness=0.01)
SCENES = {"ground": ([GROUND], 0.02), "sphere": ([SPHERE, GROUND], 0.6)}


def simulation(integrator: str, n: int, scene: str, inside: bool) -> Simulation:
    """The cotton cloth of ``n x n`` points over ``scene``'s obstacles."""
    obstacles, height = SCENES[scene]
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    base = base.with_resolution(n).with_overrides(
        {"solver.integrator": integrator, "solver.dt": 1 / 60, "pins.corners": []}
    )
    cloth = dataclasses.replace(base.cloth, orientation="horizontal", center=(0, 0, height))
    sim = Simulation(dataclasses.replace(base, cloth=cloth, obstacles=tuple(obstacles)))
    sim.integrator.contact_in_step = inside
    return sim


#: Frames each way advances in its turn: a slow spell of the shared machine
#: falls on both, and within a turn the caches hold one simulation, as in a
#: real run (``self_collision_cost.py`` found turns of one frame slowed both).
BLOCK = 5


def run(integrator: str, n: int, scene: str) -> dict:
    """Both ways of ``scene``, advanced in turns of :data:`BLOCK` frames (the
    one to go first alternating)."""
    sims = {inside: simulation(integrator, n, scene, inside) for inside in (True, False)}
    frames = round(SECONDS * 60)
    last = max(1, min(60, frames // 2))
    energies = {inside: [] for inside in sims}
    walls = {inside: [] for inside in sims}
    closest = dict.fromkeys(sims, float("inf"))
    for first in range(0, frames, BLOCK):
        for inside in (True, False) if first // BLOCK % 2 == 0 else (False, True):
            sim = sims[inside]
            for _ in range(min(BLOCK, frames - first)):
                begin = time.perf_counter()
                sim.advance(1 / 60)
                walls[inside].append(time.perf_counter() - begin)
                energies[inside].append(sim.model.kinetic_energy(sim.velocities))
                for obstacle in sim.model.obstacles:
                    gap = float(obstacle.gap(sim.positions, sim.time)[0].min())
                    closest[inside] = min(closest[inside], gap)
    return {
        inside: {
            "mean": statistics.fmean(energies[inside][-last:]),
            "most": max(energies[inside][-last:]),
            "closest": closest[inside],
            "frame": statistics.median(walls[inside]),
        }
        for inside in sims
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(HERE / "results" / "contact_in_step.md"))
    args = parser.parse_args()
    lines = [
        "# Contact inside the fast implicit solve",
        "",
        provenance(),
        "",
        f"`python benchmarks/contact_in_step.py`: cotton with `fast_bdf2` (10 iterations; "
        f"impulses in its solve) and `bdf2` (Newton; a penalty in its potential) at "
        f"one 1/60 s step a frame for {SECONDS:g} s, dropped flat onto the ground from 2 cm "
        f"and onto a 0.25 m sphere on the ground from 0.6 m. Kinetic energy over the last "
        f"simulated second (J), the smallest gap to an obstacle grown by its thickness over "
        f"every frame (mm; negative is inside) and the median wall time of a frame (ms), the "
        f"two ways advanced in turns of {BLOCK} frames in one process.",
        "",
        "| integrator | points | scene | contact | KE mean (J) | KE largest (J) | closest (mm) "
        "| ms / frame |",
        "|---|---|---|---|---|---|---|---|",
    ]
    ratios = []
    for integrator, n in CASES:
        for scene in SCENES:
            results = run(integrator, n, scene)
            for inside, result in results.items():
                way = "inside the solve" if inside else "after the step"
                lines.append(
                    f"| {integrator} | {n}x{n} | {scene} | {way} | {result['mean']:.2g} "
                    f"| {result['most']:.2g} | {1e3 * result['closest']:.3f} "
                    f"| {1e3 * result['frame']:.1f} |"
                )
                print(lines[-1], flush=True)
            ratio = results[True]["frame"] / results[False]["frame"]
            ratios.append((integrator, n, scene, ratio))
    lines += ["", "Cost of a frame, inside the solve over after the step:", ""]
    lines += [f"- {name} {n}x{n} {scene}: {ratio:.2f}" for name, n, scene, ratio in ratios]
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
