"""Did a change cost speed? The same steps under two commits, side by side in one run.

A change that should leave the physics alone (a refactor) must leave its
cost alone too. This runs one worker process per commit, each importing its
own checkout of pvcloth, builds the same cases in both, then times them
round by round, the two commits taking turns within each round, so a slow
spell of the shared machine falls on both. The table gives the median of the
rounds, milliseconds per call, and the ratio after / before.

The cases are the three speed tables of the project, each cut to its core:

- **step** (``benchmarks/cpu_speed.py``): ``Simulation.step()`` of every
  integrator on the hanging cloth at 64x64, at a step all can take;
- **frame** (``benchmarks/fabric_speed.py``): ``advance(1 / 60)`` of the
  frame-step methods on the cotton scene at 64x64 (not ``backward_euler``:
  seconds a frame there);
- **contact** (``benchmarks/self_collision_cost.py``): ``advance(1 / 60)``
  of the crumple scene at 32x32 with ``[self_collision]`` on and off, after
  0.3 s of falling.

Run:  python benchmarks/before_after.py BEFORE [AFTER] [--rounds 7] [--batch 0.2]
      [--grid N] [--out FILE]

``BEFORE`` and ``AFTER`` are git commits of this repository (``AFTER``
defaults to the working tree); each is checked out into a temporary folder
(``git worktree``), removed at the end. A folder holding a checkout may be
given instead of a commit. ``--grid N`` runs every case at N x N (a quick
look; the table is then not the one the docs quote). Writes
``benchmarks/results/before_after.md`` unless ``--out`` says otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from provenance import cpu_name, provenance

HERE = Path(__file__).parent
ROOT = HERE.parent

#: (name, scene file, resolution, integrator, dt or None, self-collision, warm-up s, call)
CASES = [
    *(
        (f"step {name}", "hanging.toml", 64, name, 1e-5, None, 50e-5, "step")
        for name in (
            "explicit_euler",
            "symplectic_euler",
            "verlet",
            "rk4",
            "rk23",
            "implicit_euler",
            "fast_mass_spring",
        )
    ),
    *(
        (f"frame {name}", "cotton.toml", 64, name, 1 / 60, None, 0.2, "frame")
        for name in ("fast_mass_spring", "implicit_euler")
    ),
    ("contact crumple on", "crumple.toml", 32, None, None, True, 0.3, "frame"),
    ("contact crumple off", "crumple.toml", 32, None, None, False, 0.3, "frame"),
]

#: The worker: reads one JSON request per line, answers one JSON line.
WORKER = r"""
import json, sys, time
import pvcloth
def call(sim, kind):
    sim.step() if kind == "step" else sim.advance(1 / 60)
sims = {}
for line in sys.stdin:
    ask = json.loads(line)
    if ask["do"] == "build":
        name, scene_file, n, integrator, dt, contact, warm, kind = ask["case"]
        scene = pvcloth.load_scene(scene_file).with_resolution(n)
        if contact is False:
            scene = scene.replace(self_collision=None)
        sim = pvcloth.Simulation(scene, integrator=integrator, dt=dt, stability="ignore")
        sim.advance(warm)
        sims[name] = (sim, kind)
        start = time.perf_counter()
        call(sim, kind)
        answer = {"dt": sim.dt, "module": pvcloth.__file__, "once": time.perf_counter() - start}
    else:
        sim, kind = sims[ask["case"]]
        time.sleep(0.2)  # the other worker's threads go quiet first
        start = time.perf_counter()
        for _ in range(ask["calls"]):
            call(sim, kind)
        answer = {"seconds": (time.perf_counter() - start) / ask["calls"]}
    print(json.dumps(answer), flush=True)
"""


class Worker:
    """One process running one checkout of pvcloth."""

    def __init__(self, tree: Path):
        # Passive OpenMP threads: a worker's threads would otherwise spin on
        # the cores for a while after each step, while the other one is timed.
        environment = dict(os.environ, PYTHONPATH=str(tree), OMP_WAIT_POLICY="PASSIVE")
        self.process = subprocess.Popen(
            [sys.executable, "-c", WORKER],
            cwd=tree / "data" / "scenes",
            env=environment,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )

    def ask(self, **request) -> dict:
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError(f"a worker stopped while asked {request}")
        return json.loads(line)

    def close(self) -> None:
        self.process.stdin.close()
        self.process.wait(timeout=60)


def checkout(commit: str, folder: Path) -> Path:
    """``commit`` as a worktree in ``folder`` (a folder given is taken as it is)."""
    if Path(commit).is_dir():
        return Path(commit).resolve()
    subprocess.run(
        ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(folder), commit],
        check=True,
        capture_output=True,
    )
    return folder


def short(commit: str) -> str:
    if Path(commit).is_dir():
        return Path(commit).name
    done = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", commit],
        check=True,
        capture_output=True,
        text=True,
    )
    return done.stdout.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", help="the commit measured first (e.g. before a refactor)")
    parser.add_argument("after", nargs="?", help="the commit after (default: the working tree)")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument(
        "--batch", type=float, default=0.2, help="seconds of calls timed per case and round"
    )
    parser.add_argument("--grid", type=int, help="every case at this many points per side")
    parser.add_argument("--only", help="only the cases whose name contains this text")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "before_after.md")
    args = parser.parse_args()

    labels = [short(args.before), short(args.after) if args.after else "working tree"]
    cases = [case if args.grid is None else (*case[:2], args.grid, *case[3:]) for case in CASES]
    cases = [case for case in cases if args.only is None or args.only in case[0]]
    made = []  # worktrees this run added, removed at the end
    with tempfile.TemporaryDirectory() as temporary:
        trees = []
        for n, commit in enumerate((args.before, args.after)):
            if commit is None:
                trees.append(ROOT)
                continue
            trees.append(checkout(commit, Path(temporary) / f"tree{n}"))
            if not Path(commit).is_dir():
                made.append(trees[-1])
        workers = [Worker(tree) for tree in trees]
        try:
            steps, calls = {}, {}
            for case in cases:
                answers = [worker.ask(do="build", case=case) for worker in workers]
                steps[case[0]] = answers[0]["dt"]
                once = max(answer["once"] for answer in answers)
                calls[case[0]] = max(1, round(args.batch / once))
                if answers[0]["module"] == answers[1]["module"] and trees[0] != trees[1]:
                    raise RuntimeError(f"both workers imported {answers[0]['module']}")
                if answers[0]["dt"] != answers[1]["dt"]:
                    raise RuntimeError(f"{case[0]}: the two commits chose different steps")
                print(f"built {case[0]} (dt {answers[0]['dt']:.3g} s)", flush=True)
            times = {case[0]: ([], []) for case in cases}
            for round_ in range(args.rounds):
                order = workers if round_ % 2 == 0 else workers[::-1]
                for case in cases:
                    for worker in order:
                        asked = worker.ask(do="time", case=case[0], calls=calls[case[0]])
                        seconds = asked["seconds"]
                        times[case[0]][workers.index(worker)].append(seconds)
                print(f"round {round_ + 1} of {args.rounds}", flush=True)
        finally:
            for worker in workers:
                worker.close()
            for tree in made:
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                    check=False,
                )

    rows = []
    for case in cases:
        before, after = (statistics.median(series) for series in times[case[0]])
        rows.append(
            f"| {case[0]} | {case[2]}x{case[2]} | {steps[case[0]]:.3g} | {1e3 * before:.3f} "
            f"| {1e3 * after:.3f} | {after / before:.2f} |"
        )
    machine = f"{cpu_name()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    text = "\n".join(
        [
            f"# Before and after: {labels[0]} against {labels[1]}",
            "",
            provenance(),
            "",
            f"`python benchmarks/before_after.py {labels[0]}"
            + (f" {labels[1]}" if args.after else "")
            + (f" --grid {args.grid}" if args.grid else "")
            + (f" --only {args.only!r}" if args.only else "")
            + f" --rounds {args.rounds} --batch {args.batch}` on {machine}. Median of "
            f"{args.rounds} rounds, each timing about {args.batch} s of calls (at least one) per "
            "case and commit, the commits taking turns; ms per call (`step()`, or "
            "`advance(1 / 60)` for frames). OpenMP threads passive, so the idle worker's "
            "do not spin while the other is timed.",
            "",
            f"| case | grid | dt (s) | {labels[0]} (ms) | {labels[1]} (ms) | after / before |",
            "|---|---|---|---|---|---|",
            *rows,
            "",
        ]
    )
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
