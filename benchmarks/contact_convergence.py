"""Does contact converge in the step? A cloth dropped onto a sphere.

``python benchmarks/contact_convergence.py`` drops a 16x16 cotton cloth
(``data/scenes/cotton.toml``'s fabric, 0.6 m square, unpinned) flat from
9 cm above a 0.25 m sphere, and compares its points at 0.2 s (landed at
0.135 s, draping; by 0.25 s its corners fold, and the errors no longer
fell with the step) with a reference: ``bdf2`` with the obstacle inside
its solve at a step of 1/7680 s, whose own error the run at twice its step
estimates.

- Fixed steps from 1/60 s down to 1/1920 s, halving, for ``backward_euler``
  (first order) and ``bdf2`` (second order), each with the obstacle inside
  Newton's solve (a penalty in its potential) and with it after the step
  alone (``contact_in_step = False``): the RMS distance from the reference
  and its ratio per halving (2 for first order, 4 for second).
- Adaptive ``bdf2`` (obstacle inside) at tolerances 1e-2 to 1e-4 m: the
  RMS distance over ``tolerance * t``, which the controller aims to keep
  within a factor of 10; a run whose steps fell under ``solver.min_dt`` says
  where it stopped.

Writes ``benchmarks/results/contact_convergence.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth import ObstacleSpec
from pvcloth.errors import DivergenceError
from pvcloth.physics.reference import rms_distance
from pvcloth.physics.simulation import Simulation

HERE = Path(__file__).parent
N = 6 if SMOKE else 16
AT = 0.05 if SMOKE else 0.2  # s
#: Fixed steps: 1/60 s and the halvings below it, this many in all.
HALVINGS = 2 if SMOKE else 6
REFERENCE = 1 / (60 * 2 ** (HALVINGS + 1))
TOLERANCES = (1e-2, 1e-3) if SMOKE else (1e-2, 1e-3, 1e-4)
SPHERE = ObstacleSpec("sphere", center=(0, 0, 0.25), radius=0.25, thickness=0.01)


def scene(integrator: str, dt: float | None, tolerance: float | None = None):
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    base = base.with_resolution(N).with_overrides(
        {
            "solver.integrator": integrator,
            "solver.dt": dt,
            "solver.tolerance": tolerance,
            "pins.corners": [],
        }
    )
    cloth = dataclasses.replace(
        base.cloth, size=(0.6, 0.6), orientation="horizontal", center=(0, 0, 0.6)
    )
    return dataclasses.replace(base, cloth=cloth, obstacles=(SPHERE,))


def run(integrator: str, dt: float | None, inside: bool = True, tolerance=None):
    """``(positions at AT, wall seconds, steps)``."""
    sim = Simulation(scene(integrator, dt, tolerance), stability="ignore")
    sim.integrator.contact_in_step = inside
    begin = time.perf_counter()
    sim.advance(AT)
    return sim.positions.copy(), time.perf_counter() - begin, sim.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(HERE / "results" / "contact_convergence.md"))
    args = parser.parse_args()
    truth, wall, _ = run("bdf2", REFERENCE)
    print(f"reference: bdf2 at 1/{round(1 / REFERENCE)} s, {wall:.0f} s", flush=True)
    # The landings make every method first order (each point's is an event
    # inside a step): the reference is off by about its distance from the
    # run at twice its step.
    coarser, _, _ = run("bdf2", 2 * REFERENCE)
    own = rms_distance(coarser, truth)
    steps = [1 / (60 * 2**k) for k in range(HALVINGS)]
    columns = [(name, inside) for name in ("backward_euler", "bdf2") for inside in (True, False)]
    errors = {column: [] for column in columns}
    for dt in steps:
        for name, inside in columns:
            x, _, _ = run(name, dt, inside)
            errors[(name, inside)].append(rms_distance(x, truth))
        print(f"1/{round(1 / dt)} s done", flush=True)
    head = " | ".join(f"{n} ({'inside' if i else 'after'})" for n, i in columns)
    lines = [
        "# Contact convergence: a cloth dropped onto a sphere",
        "",
        provenance(),
        "",
        f"`python benchmarks/contact_convergence.py`: {N}x{N} cotton, 0.6 m square, dropped "
        f"flat from 9 cm above a 0.25 m sphere; RMS distance of the points at {AT:g} s from "
        f"`bdf2` with the obstacle inside its solve at 1/{round(1 / REFERENCE)} s (mm), and "
        f"in brackets its ratio to the row above (2 is first order, 4 second). *inside*: "
        f"a penalty in Newton's potential; *after*: the response after the step alone. "
        f"The reference is {1e3 * own:.3g} mm from the same run at twice its step: its own "
        f"error is about that (first order, from the landings), and no error below it "
        f"can be measured here.",
        "",
        f"| step | {head} |",
        "|---|" + "---|" * len(columns),
    ]
    for row, dt in enumerate(steps):
        cells = []
        for column in columns:
            error = errors[column][row]
            ratio = f" ({errors[column][row - 1] / error:.2f})" if row else ""
            cells.append(f"{1e3 * error:.4g}{ratio}")
        lines.append(f"| 1/{round(1 / dt)} s | " + " | ".join(cells) + " |")
    lines += [
        "",
        f"Adaptive `bdf2` with the obstacle inside: RMS distance at {AT:g} s over "
        f"`tolerance * t`, steps taken and wall time.",
        "",
        "| tolerance (m) | error (mm) | error / (tolerance t) | steps | wall (s) |",
        "|---|---|---|---|---|",
    ]
    for tolerance in TOLERANCES:
        try:
            x, wall, taken = run("bdf2", None, True, tolerance)
        except DivergenceError as error:
            stopped = str(error).split(":")[0]
            lines.append(f"| {tolerance:g} | {stopped} | | | |")
        else:
            error = rms_distance(x, truth)
            lines.append(
                f"| {tolerance:g} | {1e3 * error:.4g} | {error / (tolerance * AT):.3g} | {taken} "
                f"| {wall:.1f} |"
            )
        print(lines[-1], flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[8:]))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
