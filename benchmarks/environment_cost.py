"""What wind and obstacles cost per step, and that a scene without them pays nothing.

The same cloth (the hanging scene) is stepped with nothing extra, with one
obstacle of each type placed where the cloth never reaches (so the collision
code runs but finds nothing), with one that it does touch, and with wind.
Variants are interleaved round by round so machine noise hits all alike;
the table gives the median ms per step and the ratio to the plain cloth.

Run:  python benchmarks/environment_cost.py   (writes benchmarks/results/environment_cost.md)
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth import ObstacleSpec, WindSpec

HERE = Path(__file__).parent
SIZES = (8,) if SMOKE else (32, 64)
ROUNDS = 1 if SMOKE else 9

VARIANTS = {
    "plain (no wind, no obstacles)": {},
    "unused ground, 10 m below": {"obstacles": (ObstacleSpec("ground", center=(0, 0, -10)),)},
    "unused sphere, 10 m away": {
        "obstacles": (ObstacleSpec("sphere", center=(10, 0, 0), radius=0.3),)
    },
    "unused box, 10 m away": {
        "obstacles": (ObstacleSpec("box", center=(10, 0, 0), size=(0.5, 0.5, 0.5)),)
    },
    "sphere the cloth lies on": {
        "obstacles": (ObstacleSpec("sphere", center=(0, 0, 1.2), radius=0.3),)
    },
    "steady wind": {"wind": WindSpec(velocity=(3, 1, 0))},
    "gusty wind with lift": {"wind": WindSpec(velocity=(3, 1, 0), lift=0.5, gust=0.3)},
}


def simulation(n: int, changes: dict) -> pvcloth.Simulation:
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml")
    sim = pvcloth.Simulation(scene.with_resolution(n).replace(**changes), stability="substep")
    sim.advance(0.3)  # fallen onto the sphere, where there is one
    return sim


def main() -> None:
    rows = []
    for n in SIZES:
        sims = {name: simulation(n, changes) for name, changes in VARIANTS.items()}
        steps = 2 if SMOKE else max(20, int(4e5 / n**2))
        times = {name: [] for name in sims}
        for _ in range(ROUNDS):
            for name, sim in sims.items():
                start = time.perf_counter()
                for _ in range(steps):
                    sim.step()
                times[name].append((time.perf_counter() - start) / steps)
        plain = float(np.median(times[next(iter(sims))]))
        for name, sim in sims.items():
            median = float(np.median(times[name]))
            terms = len(sim.model.forces) + len(sim.model.obstacles)
            rows.append((n, name, terms, 1e3 * median, median / plain))
            print(rows[-1])
    lines = [
        "# What wind and obstacles cost",
        "",
        provenance(),
        "",
        f"`python benchmarks/environment_cost.py`, numpy "
        f"{np.__version__}. Hanging scene, symplectic Euler at the scene's step; median of "
        f"{ROUNDS} interleaved rounds. *Terms* counts force terms plus obstacles that "
        "the model built (`pvcloth info` lists them): the plain scene builds neither wind "
        "nor obstacles, so no collision or wind code runs for it.",
        "",
        "| points per side | scene | terms built | ms per step | vs plain |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {n} | {name} | {t} | {ms:.3f} | {r:.2f} |" for n, name, t, ms, r in rows]
    out = HERE / "results" / "environment_cost.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
