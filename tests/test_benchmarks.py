"""Every benchmark runs to the end as committed, at a tiny size.

Each script runs from a copy of the repository (so the results files it
writes are the copy's, not the ones the README links), with
``PVCLOTH_BENCHMARK_SMOKE=1`` or its own size arguments shrinking it to
seconds. The numbers mean nothing; a crash, a refused step or a result
file not written fails. (``render_cost.py`` once crashed at 128x128 on a
refused step and nobody noticed.)
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

RUNS = {
    "accelerators.py": ([], "accelerators.md"),
    "adaptive.py": ([], "adaptive.md"),
    "contact_convergence.py": ([], "contact_convergence.md"),
    "contact_in_step.py": ([], "contact_in_step.md"),
    "bending_cost.py": ([], "bending_cost.md"),
    "bending_models.py": ([], "bending_models.md"),
    "view_cost.py": ([], "view_cost.md"),
    "blas_threads.py": ([], "blas_threads.md"),
    # the copy (no .git) against itself, in place of two commits
    "before_after.py": (
        [".", ".", "--grid", "8", "--rounds", "1", "--batch", "0.01"],
        "before_after.md",
    ),
    "cpu_speed.py": (["--sizes", "8", "--rounds", "1"], "cpu_speed.md"),
    "environment_cost.py": ([], "environment_cost.md"),
    "fabric_speed.py": ([], "fabric_speed.md"),
    "frame_step.py": ([], "frame_step.md"),
    "frame_step.py --stability": (["--stability"], "frame_step_stability.md"),
    "frame_step.py --convergence": (["--convergence"], "frame_step_convergence.md"),
    "finite_check.py": ([], "finite_check.md"),
    "fresh_clone.py": (["--quick"], "fresh_clone.md"),
    "fuzz.py": (["--examples", "3"], "fuzz.md"),
    "implicit_crossover.py": (
        ["--sizes", "8", "--factors", "1", "--output", "results/implicit_crossover.md"],
        "implicit_crossover.md",
    ),
    "interactive_fps.py": (
        [
            "--sizes",
            "8",
            "--seconds",
            "0.5",
            "--integrators",
            "symplectic_euler",
            "fast_mass_spring",
        ],
        "interactive_fps.md",
    ),
    "memory.py": ([], "memory.md"),
    "newton_peer.py": ([], "newton_peer.md"),
    "render_cost.py": (["--frames", "2", "--sizes", "8"], "render_cost.md"),
    "self_collision_cost.py": (
        ["--sizes", "8", "--steps", "2", "--settle", "1.1", "--windy", "0.1"],
        "self_collision_cost.md",
    ),
    "self_collision_cost.py --layers-in-solve": (
        ["--sizes", "8", "--steps", "2", "--settle", "1.1", "--cases", "resting"]
        + ["--integrator", "bdf2", "--layers-in-solve"],
        "self_collision_cost_bdf2_in_solve.md",
    ),
    "startup.py": ([], "startup.md"),
    "step_allocations.py": ([], "step_allocations.md"),
    "sweep_scaling.py": ([], "sweep_scaling.md"),
}


def test_every_benchmark_script_is_listed_here():
    scripts = {p.name for p in (ROOT / "benchmarks").glob("*.py")}
    helpers = {"taichi_cloth.py", "smoke.py", "provenance.py"}  # imported by the others
    assert scripts - helpers == {run.split()[0] for run in RUNS}  # "NAME.py --mode" too


def test_every_results_table_says_which_commit_and_machine_measured_it():
    """A number is read with the code and the machine that made it: every
    table names the commit it was measured on, the CPU and its cores, and
    the command that made it (the performance pages show each as it is)."""
    import re

    unstamped = []
    for table in sorted((ROOT / "benchmarks" / "results").glob("*.md")):
        head = "\n".join(table.read_text(encoding="utf-8").splitlines()[:8])
        stamped = (
            re.search(r"\bcommit [0-9a-f]{7,40}\b", head)
            and re.search(r"\b\d+ cores\b", head)
            and re.search(r"`(xvfb-run .*)?python ", head)
        )
        if not stamped:
            unstamped.append(table.name)
    assert not unstamped, f"measure again (their commands head them): {unstamped}"


@pytest.fixture(scope="module")
def copy(tmp_path_factory):
    """The repository's files (no venv, no git) in a scratch folder."""
    target = tmp_path_factory.mktemp("repository") / "pvcloth"
    shutil.copytree(
        ROOT,
        target,
        ignore=shutil.ignore_patterns(".venv", ".git", "__pycache__", "*.egg-info", ".*cache"),
    )
    for stale in (target / "benchmarks" / "results").glob("*.md"):
        stale.unlink()
    return target


#: The benchmark the quick tier runs (the others are validation): it goes
#: through the same smoke-size switch and results-file writing as the rest.
QUICK_TWIN = "step_allocations.py"


@pytest.mark.parametrize(
    "script",
    [s if s == QUICK_TWIN else pytest.param(s, marks=pytest.mark.validation) for s in sorted(RUNS)],
)
def test_the_benchmark_runs_to_the_end(copy, script):
    arguments, result = RUNS[script]
    command = [sys.executable, str(copy / "benchmarks" / script.split()[0]), *arguments]
    env = dict(os.environ, PVCLOTH_BENCHMARK_SMOKE="1")
    if script == "interactive_fps.py":  # a real window, on a virtual screen
        if shutil.which("xvfb-run") is None:
            pytest.skip("xvfb-run not installed (apt-get install xvfb xauth)")
        env.pop("VTK_DEFAULT_OPENGL_WINDOW", None)
        command = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", *command]
    done = subprocess.run(
        command,
        cwd=copy / "benchmarks" if script == "implicit_crossover.py" else copy,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-3000:]
    written = copy / "benchmarks" / "results" / result
    assert written.exists() and "|" in written.read_text()
    if script.startswith("self_collision_cost.py"):
        # Its rows may report a Newton run that did not converge; at the
        # smoke size each must, or the timed path goes untried.
        assert "did not converge" not in written.read_text()
