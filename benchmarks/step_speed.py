"""Wall time of one solver step per integrator and cloth size.

Interleaves the integrators round by round (so machine noise hits all of
them alike) and reports the median of the rounds.

Run:  python benchmarks/step_speed.py      (writes benchmarks/results/step_speed.md)
"""

from __future__ import annotations

import platform
import time
from pathlib import Path

import numpy as np

import pvcloth

HERE = Path(__file__).parent
SIZES = (32, 64, 128, 256)
ROUNDS = 7


def simulation(n: int, integrator: str) -> pvcloth.Simulation:
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml")
    return pvcloth.Simulation(
        scene.with_resolution(n), integrator=integrator, dt=1e-5, stability="ignore"
    )


def main() -> None:
    names = sorted(pvcloth.INTEGRATORS)
    rows = []
    for n in SIZES:
        sims = {name: simulation(n, name) for name in names}
        steps = max(3, int(2e5 / n**2))
        times = {name: [] for name in names}
        for _ in range(ROUNDS):
            for name, sim in sims.items():
                start = time.perf_counter()
                for _ in range(steps):
                    sim.step()
                times[name].append((time.perf_counter() - start) / steps)
        for name in names:
            rows.append((n, name, 1e3 * float(np.median(times[name]))))
            print(rows[-1])
    lines = [
        "# Solver step speed",
        "",
        f"`python benchmarks/step_speed.py` on {platform.node()}, numpy {np.__version__}, "
        f"pure NumPy path, float64. Median of {ROUNDS} interleaved rounds, ms per step "
        "(hanging scene, all three spring families, gravity, air damping; dt = 1e-5 s for all, "
        "so implicit Euler's CG needs few iterations and its cost is mostly assembly).",
        "",
        "| points per side | integrator | ms per step |",
        "|---|---|---|",
    ]
    lines += [f"| {n} | {name} | {ms:.3f} |" for n, name, ms in rows]
    out = HERE / "results" / "step_speed.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
