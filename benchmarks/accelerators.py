"""Chebyshev against L-BFGS: how close one frame step of the fast implicit
integrators comes to its own converged answer, against its cost.

``python benchmarks/accelerators.py`` runs the bundled cotton scene
(``data/scenes/cotton.toml``, 64x64 points) with ``fast_bdf2`` to 0.5 s,
where the cloth swings, and from that state takes one 1/60 s step of
``fast_mass_spring`` and of ``fast_bdf2`` with each ``solver.accelerator``
and 5 to 100 iterations. For each: the RMS distance of the points from the
same step solved to convergence (L-BFGS until no iteration lowers the
step's energy, checked against Chebyshev run as long), the last
iteration's largest move of a point (the integrator's ``residual``), and
the median wall time of the step over repeats (BLAS held to one thread, as
in a simulation). Both accelerators are timed in turn in one process.
Writes ``benchmarks/results/accelerators.md``.

This is the solver's share of one step only; over a run the time error
adds to it and the solver's error feeds the next steps
(``benchmarks/frame_step.py`` measures that).
"""

from __future__ import annotations

import argparse
import copy
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.physics.blas import one_blas_thread
from pvcloth.physics.pipeline import PinVelocities
from pvcloth.physics.reference import rms_distance

HERE = Path(__file__).parent
FRAME = 1 / 60
START = 3 / 60 if SMOKE else 0.5  # s
ITERATIONS = (5, 10) if SMOKE else (5, 10, 20, 50, 100)
REPEATS = 2 if SMOKE else 9
#: Iterations of the converged step (L-BFGS stops before, once no step
#: lowers the energy), and of Chebyshev's run that checks it.
CONVERGED, CHECK = (200, 400) if SMOKE else (3000, 20000)


def one_step(sim, start, accelerator: str, iterations: int, repeats: int):
    """``(end positions, median seconds, last move in m)`` of one step of
    ``sim``'s integrator from ``start``, its history put back each time."""
    integrator = sim.integrator
    history = copy.deepcopy(getattr(integrator, "history", None))
    integrator.accelerator, integrator.iterations = accelerator, iterations
    times = []
    for _ in range(repeats):
        if history is not None:
            integrator.history = copy.deepcopy(history)
        begin = time.perf_counter()
        end = integrator.step(sim.model, start, sim.control, FRAME)
        times.append(time.perf_counter() - begin)
    if history is not None:
        integrator.history = history
    return end.x.copy(), statistics.median(times), integrator.residual


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=8 if SMOKE else 64)
    parser.add_argument("--out", default=str(HERE / "results" / "accelerators.md"))
    args = parser.parse_args()
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "cotton.toml")
    scene = scene.with_resolution(args.size)
    rows, checks = [], []
    with one_blas_thread():
        for name in ("fast_mass_spring", "fast_bdf2"):
            sim = pvcloth.Simulation(scene, integrator=name)
            sim.advance(START)
            pinned = np.flatnonzero(sim.control.pinned)
            # the state a step starts from, its pins at their landing velocity
            start, _ = PinVelocities(sim.model.n_points)(
                sim.state, pinned, sim.state.x[pinned], FRAME
            )
            converged, _, _ = one_step(sim, start, "lbfgs", CONVERGED, 1)
            check, _, _ = one_step(sim, start, "chebyshev", CHECK, 1)
            for iterations in ITERATIONS:
                cells = []
                for accelerator in ("chebyshev", "lbfgs"):
                    end, seconds, move = one_step(sim, start, accelerator, iterations, REPEATS)
                    cells.append(
                        f"{1e3 * rms_distance(end, converged):.3f} | {1e3 * move:.3f} "
                        f"| {1e3 * seconds:.2f}"
                    )
                row = f"| {name} | {iterations} | {' | '.join(cells)} |"
                print(row, flush=True)
                rows.append(row)
            checks.append(
                f"`{name}`: Chebyshev with {CHECK} iterations ends "
                f"{1e3 * rms_distance(check, converged):.4f} mm from it."
            )
    lines = [
        "# Chebyshev against L-BFGS: one frame step",
        "",
        provenance(),
        "",
        f"`python benchmarks/accelerators.py{''.join(' ' + a for a in sys.argv[1:])}`: the "
        f"cotton scene at {args.size}x{args.size} points run with each integrator to "
        f"{START:g} s, then one 1/60 s step from that state with each `solver.accelerator` "
        "and K iterations. *distance* = RMS point distance from the same step solved to "
        "convergence (mm); *last move* = the integrator's `residual` (mm): the last "
        "iteration's largest move of a point, of the plain update before the extrapolation "
        "for Chebyshev and of the step taken for L-BFGS (how fast each was still moving, "
        f"not a distance); ms = median wall time of the step over {REPEATS} repeats.",
        "",
        "| integrator | K | Chebyshev: distance (mm) | last move (mm) | ms "
        "| L-BFGS: distance (mm) | last move (mm) | ms |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        f"The converged step: L-BFGS with up to {CONVERGED} iterations, which stops once no "
        "step lowers the energy in double precision. " + " ".join(checks) + " Where "
        "compressed springs make the step's energy non-convex (the cloth folds), long runs "
        "of either kind may settle apart: a distance below the check's is not resolved.",
    ]
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
