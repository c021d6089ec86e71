"""What self-collision costs: step time with ``[self_collision]`` on against
off, side by side in one run, on three states:

- **fold in the wind** (``data/scenes/fold.toml``): the long cloth after it
  has fallen over the bar and the wind has laid one half on the other (run
  for ``--settle`` seconds with self-collision on first; both runs then
  start from that state); the wind keeps it moving;
- **resting fold**: the same, with the wind then switched off and
  ``--calm`` more seconds to settle;
- **violent crumple** (``data/scenes/crumple.toml``): a tall cloth let go
  above the floor piles onto itself (timed from the start).

Each measured step is ``sim.advance(dt)`` (one step: integrator, obstacles,
pins, self-collision); the median over ``--steps`` steps is quoted, and the
ratio on / off. The scene's integrator (``fast_mass_spring`` at 1/60 s).

Run:  python benchmarks/self_collision_cost.py [--sizes 32 64 128] [--steps 40]
      (writes benchmarks/results/self_collision_cost.md)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from pvcloth import Simulation, load_scene

HERE = Path(__file__).parent
ROOT = HERE.parent


def starts(n: int, settle: float, calm: float):
    """``(name, scene, state)``: each case's scene and the simulation (with
    self-collision) whose state both timed runs start from."""
    fold = load_scene(ROOT / "data" / "scenes" / "fold.toml").with_resolution(n)
    windy = Simulation(fold)
    windy.advance(settle)
    yield "fold in the wind", fold, windy
    windy.update({"wind.velocity": [0.0, 0.0, 0.0]})
    windy.advance(calm)
    yield "resting fold", fold.with_overrides({"wind.velocity": [0.0, 0.0, 0.0]}), windy
    crumple = load_scene(ROOT / "data" / "scenes" / "crumple.toml").with_resolution(n)
    yield "violent crumple", crumple, Simulation(crumple)


def timed(sim: Simulation, steps: int) -> tuple[float, int]:
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        sim.advance(sim.dt)
        times.append(time.perf_counter() - start)
    candidates = sim.model.self_collision.report.candidates if sim.model.self_collision else 0
    return float(np.median(times)), candidates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128])
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--settle", type=float, default=1.5)
    parser.add_argument("--calm", type=float, default=3.0)
    parser.add_argument("--out", default=str(HERE / "results" / "self_collision_cost.md"))
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        for name, scene, start in starts(n, args.settle, args.calm):
            on = Simulation(scene)
            off = Simulation(scene.replace(self_collision=None))
            for sim in (on, off):
                sim.state.x[:] = start.state.x
                sim.state.v[:] = start.state.v
            timed(on, 2), timed(off, 2)  # compile, warm caches
            t_on, candidates = timed(on, args.steps)
            t_off, _ = timed(off, args.steps)
            rows.append((n, name, t_off, t_on, candidates))
            print(f"{n} {name}: off {t_off * 1e3:.2f} ms, on {t_on * 1e3:.2f} ms", flush=True)
    lines = [
        "# Self-collision: step time on against off",
        "",
        f"`python benchmarks/self_collision_cost.py --sizes {' '.join(map(str, args.sizes))} "
        f"--steps {args.steps} --settle {args.settle:g} --calm {args.calm:g}`; median ms per "
        "step of `fast_mass_spring` at 1/60 s (the scenes'), on and off measured side by "
        "side from the same state.",
        "",
        "| points per side | scene | off (ms) | on (ms) | on / off | candidate pairs |",
        "|---|---|---|---|---|---|",
    ]
    for n, name, t_off, t_on, candidates in rows:
        lines.append(
            f"| {n} | {name} | {t_off * 1e3:.2f} | {t_on * 1e3:.2f} | {t_on / t_off:.1f}x "
            f"| {candidates:,} |"
        )
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
