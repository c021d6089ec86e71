"""What plate bending costs against bending springs: the step time of every
integrator on measured cotton, side by side in one run.

Two versions of ``data/scenes/cotton.toml`` at ``--size`` points a side:

- **springs**: bending springs at 1 % of the stretch stiffness, the structural
  springs lowered so that the sheet still stretches as measured (what the
  fabric presets built before plate bending); no plate bending;
- **plate**: the preset as it is: plate bending at the measured rigidity
  (``pvcloth/physics/bending.py``), no bending springs.

Each integrator steps both at one step: the smaller of the two versions'
automatic steps (1/60 s for the implicit integrators; for the explicit
ones the stable step pvcloth chooses, quoted for both versions: a
simulated second costs the step time divided by the step). Steps are
timed in turns of ``BLOCK`` on each version, so a slow spell of the machine
falls on both; the median is quoted.

Run:  python benchmarks/bending_cost.py [--size 64] [--steps 30]
      (writes benchmarks/results/bending_cost.md)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

HERE = Path(__file__).parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from pvcloth import Simulation, load_scene  # noqa: E402
from pvcloth.physics.integrators import INTEGRATORS  # noqa: E402
from pvcloth.scene.materials import DAMPING_TIME, MATERIALS  # noqa: E402

#: Bending springs' stiffness as a share of the stretch stiffness, and what
#: they add to the sheet's stretch modulus per unit of it (as the presets had it).
SPRING_SHARE, SPRING_STRETCH = 0.01, 4.0
#: Steps timed in a row on one version before turning to the other.
BLOCK = 5


def versions(size: int):
    """``{"springs": scene, "plate": scene}`` for cotton at ``size`` points a side."""
    plate = load_scene(ROOT / "data" / "scenes" / "cotton.toml").with_resolution(size)
    cotton = MATERIALS["cotton"]
    bending = SPRING_SHARE * cotton.stretch
    structural = cotton.stretch - cotton.shear - SPRING_STRETCH * bending
    springs = plate.with_overrides(
        {
            "cloth.bending_rigidity": 0.0,
            "springs.structural.stiffness": structural,
            "springs.structural.damping": structural * DAMPING_TIME,
            "springs.bending.stiffness": bending,
            "springs.bending.damping": bending * DAMPING_TIME,
        }
    )
    return {"springs": springs, "plate": plate}


def timed(sims: dict[str, Simulation], steps: int) -> dict[str, float]:
    """Median seconds per step of each simulation, in turns of ``BLOCK``."""
    times: dict[str, list[float]] = {name: [] for name in sims}
    for first in range(0, steps, BLOCK):
        for name, sim in sims.items():
            for _ in range(min(BLOCK, steps - first)):
                start = time.perf_counter()
                sim.step()
                times[name].append(time.perf_counter() - start)
    return {name: float(np.median(kept)) for name, kept in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=64, help="points a side")
    parser.add_argument("--steps", type=int, default=30, help="steps timed per version")
    parser.add_argument(
        "--integrators", nargs="+", default=sorted(INTEGRATORS), choices=sorted(INTEGRATORS)
    )
    parser.add_argument("--out", default=str(HERE / "results" / "bending_cost.md"))
    args = parser.parse_args()
    size, steps = (8, 4) if SMOKE else (args.size, args.steps)
    scenes = versions(size)
    rows = []
    for name in args.integrators:
        integrator = INTEGRATORS[name]
        probes = {key: Simulation(scene, integrator=name) for key, scene in scenes.items()}
        stable = {key: sim.dt for key, sim in probes.items()}  # the automatic steps
        dt = min(stable.values())
        sims = {key: Simulation(scene, integrator=name, dt=dt) for key, scene in scenes.items()}
        timed(sims, 2)  # compile, factorise, warm the caches
        medians = timed(sims, steps)
        ratio = medians["plate"] / medians["springs"]
        rows.append((name, integrator.order, dt, stable, medians, ratio))
        print(
            f"{name}: springs {medians['springs'] * 1e3:.3f} ms, plate "
            f"{medians['plate'] * 1e3:.3f} ms, {ratio:.2f}x",
            flush=True,
        )
    lines = [
        "# Plate bending against bending springs: step time",
        "",
        provenance(),
        "",
        f"`python benchmarks/bending_cost.py --size {size} --steps {steps} --integrators "
        f"{' '.join(args.integrators)}`; measured cotton "
        f"({size}x{size} points, `data/scenes/cotton.toml`) with bending springs at 1 % of the "
        "stretch stiffness (springs) and with plate bending at the measured rigidity (plate); "
        f"median ms per step over {steps} steps, the two taken in turns of {BLOCK} steps at "
        "the same step, the smaller of the two automatic steps (1/60 s for the implicit "
        "integrators, the stable step pvcloth picks for the explicit ones).",
        "",
        "| integrator | step (s) | springs: ms per step | plate: ms per step | plate / springs "
        "| springs: automatic step (s) | plate: automatic step (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, _order, dt, stable, medians, ratio in rows:
        lines.append(
            f"| {name} | {dt:.3g} | {medians['springs'] * 1e3:.3f} | {medians['plate'] * 1e3:.3f} "
            f"| {ratio:.2f}x | {stable['springs']:.3g} | {stable['plate']:.3g} |"
        )
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
