"""What self-collision costs: step time with ``[self_collision]`` on against
off, side by side in one run, on these states:

- **resting fold**: the towel fold of the self-collision tests
  (``tests/contact_scenes.py``): a cloth on the floor folded in half, let go
  at 1 s and settled until ``--settle`` seconds (with self-collision on);
  both timed runs start from that state. Off, the top half falls through;
  the first steps are timed, while it still lies on the bottom half;
- **violent crumple** (``data/scenes/crumple.toml``): a tall cloth let go
  above the floor piles onto itself (timed from the start);
- **fold in the wind** (``data/scenes/fold.toml``, only with ``--windy``):
  the long cloth after ``--windy`` seconds of falling over the bar in the
  wind, still flapping. Costly to reach beyond 32x32 (minutes at 64x64).

Each measured frame is ``sim.advance(1 / 60)``: one step of
``fast_mass_spring`` off, and on as many steps as the self-collision step
bound needs (``Simulation.contact_step``: a resting layer must not fall
further in one step than the response may move it back; 1/120 s from 64
points per side). The median over ``--steps`` frames is quoted, and the
ratio on / off: the cost of a simulated second, whatever the steps. On and
off take turns of ``BLOCK`` frames, so a slow spell of the machine falls on
both.

With ``--integrator`` another integrator is timed from the same states
(each at its automatic step, the contact step bound applying as above): an
explicit one takes the many steps its stability asks for, and its
self-collision runs after every one of them.

With ``--layers-in-solve`` (``backward_euler`` or ``bdf2``), the layers and
the floor enter the timed integrator's solve with self-collision on
(``[self_collision] in_solve``: no step split), and the towel is folded
and settled by that integrator, its layers in the solve from the start
(from a fold settled by ``fast_mass_spring``, Newton stops short of its
tolerance in its first steps). A case whose Newton iterations do not
converge is a row that says which run stalled and how the other went.

Run:  python benchmarks/self_collision_cost.py [--sizes 32 64 128] [--steps 40]
      [--integrator symplectic_euler] [--integrator bdf2 --layers-in-solve]
      (writes benchmarks/results/self_collision_cost.md, with another
      integrator benchmarks/results/self_collision_cost_INTEGRATOR.md,
      with --layers-in-solve self_collision_cost_INTEGRATOR_in_solve.md)
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance

HERE = Path(__file__).parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # the tests' scenes are the ones timed

from contact_scenes import fold_a_towel  # noqa: E402

from pvcloth import Simulation, load_scene  # noqa: E402
from pvcloth.errors import DivergenceError  # noqa: E402
from pvcloth.physics.integrators import get_integrator  # noqa: E402

#: One frame of simulated time (s), the unit each measurement advances.
FRAME = 1.0 / 60.0


def starts(
    n: int,
    settle: float,
    windy: float,
    cases=("resting", "crumple"),
    folder: str = "fast_mass_spring",
    in_solve: bool = False,
):
    """``(name, scene, state)``: each case's scene and the simulation (with
    self-collision) whose state both timed runs start from; the towel folded
    by ``folder``, its layers in the solve with ``in_solve``."""
    if "resting" in cases:
        towel, drive = fold_a_towel(n, folder, in_solve=in_solve)
        while towel.state.t < settle - 1e-9:
            drive(towel)
            towel.advance(towel.dt)
        yield "resting fold", towel.scene, towel
    if "crumple" in cases:
        crumple = load_scene(ROOT / "data" / "scenes" / "crumple.toml").with_resolution(n)
        yield "violent crumple", crumple, Simulation(crumple)
    if windy > 0.0:
        fold = load_scene(ROOT / "data" / "scenes" / "fold.toml").with_resolution(n)
        flapping = Simulation(fold)
        flapping.advance(windy)
        yield "fold in the wind", fold, flapping


#: Frames timed in a row on one simulation before turning to the other.
BLOCK = 5
#: What each case's row is called.
NAMES = {"resting": "resting fold", "crumple": "violent crumple", "windy": "fold in the wind"}


class Stalled(Exception):
    """A timed run (``which``: "on" or "off") whose Newton iterations did
    not converge (``error``)."""

    def __init__(self, which: str, error: DivergenceError):
        super().__init__(f"{which}: {error}")
        self.which, self.error = which, error


def outcome(sim: Simulation, until: float) -> str:
    """Play ``sim`` on alone to ``until`` (s): "converged to t = ..." or
    where Newton did not (the other run of a case that stalled, so that the
    row says whether self-collision is what stopped it)."""
    try:
        while sim.state.t < until - 1e-9:
            sim.advance(FRAME)
    except DivergenceError as error:
        return f"did not converge ({error})"
    return f"converged to t = {sim.state.t:.3g} s"


def timed(on: Simulation, off: Simulation, frames: int) -> tuple[float, float, int, list[int]]:
    """Median seconds per frame with self-collision on and off, taken in
    turns of ``BLOCK`` frames each (a slow spell of this shared machine
    falls on both; within a turn the caches hold one simulation, as in a
    real run: turns of one frame made both slower, on the more), the
    candidate pairs of the last step on, and the points in impact zones at
    each step on."""
    contact = on.model.self_collision
    resolve = contact.resolve
    zoned: list[int] = []

    def counted(*args, **kwargs):
        report = resolve(*args, **kwargs)
        zoned.append(report.zoned)
        return report

    contact.resolve = counted  # an instance attribute: this simulation only
    times: tuple[list[float], list[float]] = ([], [])
    for first in range(0, frames, BLOCK):
        for sim, kept in zip((on, off), times, strict=True):
            for _ in range(min(BLOCK, frames - first)):
                start = time.perf_counter()
                try:
                    sim.advance(FRAME)
                except DivergenceError as error:  # Newton's: say which run
                    raise Stalled("on" if sim is on else "off", error) from error
                kept.append(time.perf_counter() - start)
    del contact.resolve
    return float(np.median(times[0])), float(np.median(times[1])), contact.report.candidates, zoned


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128])
    parser.add_argument("--steps", type=int, default=40, help="frames timed per case")
    parser.add_argument("--settle", type=float, default=2.5, help="seconds of the towel fold")
    parser.add_argument(
        "--windy", type=float, default=0.0, help="seconds of the fold in the wind (0: not run)"
    )
    parser.add_argument(
        "--cases", nargs="+", default=["resting", "crumple"], choices=["resting", "crumple"]
    )
    parser.add_argument(
        "--integrator", default="fast_mass_spring", help="the integrator timed (its automatic step)"
    )
    parser.add_argument(
        "--layers-in-solve",
        action="store_true",
        help="with self-collision on, the layers in the solve ([self_collision] in_solve); "
        "the towel folded by the timed integrator",
    )
    parser.add_argument(
        "--out",
        help="the results file (default benchmarks/results/self_collision_cost.md, with "
        "another integrator self_collision_cost_INTEGRATOR.md)",
    )
    args = parser.parse_args()
    if args.layers_in_solve and not get_integrator(args.integrator).holds_layers:
        parser.error(f"--layers-in-solve: {args.integrator} cannot hold the layers in its solve")
    if args.out is None:
        named = "" if args.integrator == "fast_mass_spring" else f"_{args.integrator}"
        named += "_in_solve" if args.layers_in_solve else ""
        args.out = str(HERE / "results" / f"self_collision_cost{named}.md")
    rows = []
    folder = args.integrator if args.layers_in_solve else "fast_mass_spring"
    for n in args.sizes:
        # Case by case: a fold that fails (Newton's, with --layers-in-solve)
        # ends its own generator only.
        for case in [*args.cases, *(["windy"] if args.windy > 0.0 else [])]:
            windy = args.windy if case == "windy" else 0.0
            made = starts(n, args.settle, windy, [case], folder, args.layers_in_solve)
            try:
                name, scene, start = next(made)
            except DivergenceError as error:  # the start itself, by the timed integrator
                rows.append((n, NAMES[case], f"its start, on: {error}"))
                print(f"{n} {NAMES[case]}: its start, on: {error}", flush=True)
                continue
            scene = scene.with_overrides({"solver.integrator": args.integrator, "solver.dt": None})
            if args.layers_in_solve:
                contact = dataclasses.replace(scene.self_collision, in_solve=True)
                scene = scene.replace(self_collision=contact)
            on = Simulation(scene)
            off = Simulation(scene.replace(self_collision=None))
            for sim in (on, off):
                sim.set_state(start.state.x, start.state.v)
            try:
                timed(on, off, 2)  # compile, warm caches
                energy = on.energy()["kinetic"]
                t_on, t_off, candidates, zoned = timed(on, off, args.steps)
            except Stalled as stalled:
                failed, other = (on, off) if stalled.which == "on" else (off, on)
                rest = outcome(other, failed.state.t + FRAME)
                text = f"{stalled}; {'off' if stalled.which == 'on' else 'on'}: {rest}"
                rows.append((n, name, text))
                print(f"{n} {name}: {text}", flush=True)
                continue
            zones = f"{sum(z > 0 for z in zoned)} of {len(zoned)} ({max(zoned):,} points)"
            steps = (round(FRAME / off.dt), round(FRAME / on.dt))
            rows.append((n, name, t_off, t_on, steps, candidates, zones, energy))
            print(f"{n} {name}: off {t_off * 1e3:.2f} ms, on {t_on * 1e3:.2f} ms", flush=True)
    in_solve = f"; the layers in the solve, the towel folded by {folder}" * args.layers_in_solve
    split = (
        "the same step, no split: the layers are in its solve"
        if args.layers_in_solve
        else "the steps the self-collision step bound asks for"
    )
    lines = [
        "# Self-collision: step time on against off",
        "",
        provenance(),
        "",
        f"`{' '.join(['python benchmarks/self_collision_cost.py', *sys.argv[1:]])}` "
        f"(sizes {' '.join(map(str, args.sizes))}, cases {' '.join(args.cases)}, "
        f"{args.steps} frames timed, fold settled {args.settle:g} s, windy {args.windy:g} s"
        f"{in_solve}); "
        f"median ms per 1/60 s frame of `{args.integrator}` (its automatic step off; on, "
        f"{split}), on and off measured side by side from the "
        f"same state, in turns of {BLOCK} frames each.",
        "",
        "Impact zones: the timed steps on in which any formed (and the most points "
        "one step held in them); kinetic energy: the cloth's at the start of the timing "
        "(the resting fold's after settling).",
        "",
        "| points per side | scene | off (ms) | on (ms) | on / off | steps per frame off "
        "| steps per frame on | candidate pairs | steps with impact zones | kinetic energy (J) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        if len(row) == 3:  # Newton did not converge
            n, name, error = row
            lines.append(f"| {n} | {name} | did not converge: {error} |||||||| ")
            continue
        n, name, t_off, t_on, (steps_off, steps_on), candidates, zones, energy = row
        lines.append(
            f"| {n} | {name} | {t_off * 1e3:.2f} | {t_on * 1e3:.2f} | {t_on / t_off:.1f}x "
            f"| {steps_off} | {steps_on} | {candidates:,} | {zones} | {energy:.2g} |"
        )
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
