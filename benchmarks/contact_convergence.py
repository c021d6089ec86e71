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

``--size``, ``--halvings``, ``--finer`` (the reference's step, in halvings
below the finest fixed one) and ``--tolerances`` change the cloth, the steps
and the tolerances: a 6x6 cloth is cheap enough for a reference at
1/122880 s (``--size 6 --halvings 9 --finer 3 --tolerances 1e-2 1e-3 1e-4
1e-5 --out benchmarks/results/contact_convergence_6.md``). A fixed-step run that raises a
:class:`~pvcloth.errors.DivergenceError` (Newton's iterations stopped short
of their tolerance at one of the finest steps, in the runs made) is marked
"did not finish" in the table.

Writes ``benchmarks/results/contact_convergence.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import sys
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
N = 6 if SMOKE else 16  # points a side (--size)
AT = 0.05 if SMOKE else 0.2  # s
#: Fixed steps: 1/60 s and the halvings below it, this many in all (--halvings).
HALVINGS = 2 if SMOKE else 6
TOLERANCES = (1e-2, 1e-3) if SMOKE else (1e-2, 1e-3, 1e-4)  # m (--tolerances)
SPHERE = ObstacleSpec("sphere", center=(0, 0, 0.25), radius=0.25, thickness=0.01)


def scene(integrator: str, dt: float | None, tolerance: float | None = None, size: int = N):
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    base = base.with_resolution(size).with_overrides(
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


def run(integrator: str, dt: float | None, inside: bool = True, tolerance=None, size: int = N):
    """``(positions at AT, wall seconds, steps)``."""
    sim = Simulation(scene(integrator, dt, tolerance, size), stability="ignore")
    sim.integrator.contact_in_step = inside
    begin = time.perf_counter()
    sim.advance(AT)
    return sim.positions.copy(), time.perf_counter() - begin, sim.steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=N, help="points a side")
    parser.add_argument(
        "--halvings", type=int, default=HALVINGS, help="fixed steps: 1/60 s and this many halvings"
    )
    parser.add_argument(
        "--finer",
        type=int,
        default=2,
        help="the reference's step: this many halvings below the finest fixed step",
    )
    parser.add_argument("--tolerances", type=float, nargs="+", default=TOLERANCES)
    parser.add_argument("--out", default=str(HERE / "results" / "contact_convergence.md"))
    args = parser.parse_args()
    if args.finer < 1:
        parser.error(f"--finer must be 1 or more halvings, got {args.finer}")
    size = args.size
    reference = 1 / (60 * 2 ** (args.halvings - 1 + args.finer))
    truth, wall, _ = run("bdf2", reference, size=size)
    print(f"reference: bdf2 at 1/{round(1 / reference)} s, {wall:.0f} s", flush=True)
    # Each point's landing is an event inside a step, and the friction after
    # the step is first order, so the error is taken as first order (an
    # over-estimate if it falls faster): the run at k times the reference's
    # step is off by about k times its error, their distance k - 1 times it.
    for times in (2, 4, 8):  # a run may stop at one of these steps (see above)
        try:
            coarser, _, _ = run("bdf2", times * reference, size=size)
        except DivergenceError as error:
            print(f"bdf2 at {times} times the reference's step: {error}", flush=True)
        else:
            break
    else:
        raise SystemExit("no coarser reference run converged: give another --finer")
    own = rms_distance(coarser, truth) / (times - 1)  # first order: e(k h) = k e(h)
    steps = [1 / (60 * 2**k) for k in range(args.halvings)]
    columns = [(name, inside) for name in ("backward_euler", "bdf2") for inside in (True, False)]
    errors = {column: [] for column in columns}
    for dt in steps:
        for name, inside in columns:
            try:
                x, _, _ = run(name, dt, inside, size=size)
            except DivergenceError as error:
                print(f"{name} at 1/{round(1 / dt)} s: {error}", flush=True)
                errors[(name, inside)].append(None)
            else:
                errors[(name, inside)].append(rms_distance(x, truth))
        print(f"1/{round(1 / dt)} s done", flush=True)
    head = " | ".join(f"{n} ({'inside' if i else 'after'})" for n, i in columns)
    lines = [
        "# Contact convergence: a cloth dropped onto a sphere",
        "",
        provenance(),
        "",
        f"`{shlex.join(['python', 'benchmarks/contact_convergence.py', *sys.argv[1:]])}`: "
        f"{size}x{size} cotton, 0.6 m square, dropped "
        f"flat from 9 cm above a 0.25 m sphere; RMS distance of the points at {AT:g} s from "
        f"`bdf2` with the obstacle inside its solve at 1/{round(1 / reference)} s (mm), and "
        f"in brackets its ratio to the row above (2 is first order, 4 second). *inside*: "
        f"a penalty in Newton's potential; *after*: the response after the step alone. "
        f"The reference's own error is about {1e3 * own:.3g} mm (its distance from the same "
        + (
            "run at twice its step"
            if times == 2
            else f"run at {times} times its step, over {times - 1}"
        )
        + ": its error if first order, an over-estimate if it falls faster), and no error "
        "below it "
        "can be measured here.",
        "",
        f"| step | {head} |",
        "|---|" + "---|" * len(columns),
    ]
    for row, dt in enumerate(steps):
        cells = []
        for column in columns:
            error, above = errors[column][row], errors[column][row - 1] if row else None
            if error is None:
                cells.append("did not finish")
                continue
            ratio = f" ({above / error:.2f})" if above is not None else ""
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
    for tolerance in args.tolerances:
        try:
            x, wall, taken = run("bdf2", None, True, tolerance, size)
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
