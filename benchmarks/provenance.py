"""Where and on what a benchmark's numbers were measured: one Markdown line
that every results table (``benchmarks/results/*.md``) carries under its title."""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _git(*arguments: str) -> str:
    """The output of ``git arguments`` in the repository, stripped."""
    done = subprocess.run(
        ["git", "-C", str(ROOT), *arguments],
        capture_output=True,
        text=True,
        check=True,
        timeout=30,
    )
    return done.stdout.strip()


def _commit() -> str:
    """The checked-out commit, and whether tracked files differ from it."""
    try:
        top = _git("rev-parse", "--show-toplevel")
        commit = _git("rev-parse", "--short", "HEAD")
        # the results files a run rewrites are not a change of the code measured
        changed = _git(
            "status", "--porcelain", "--untracked-files=no", "--", ".", ":!benchmarks/results"
        )
    except (OSError, subprocess.SubprocessError):
        return "commit unknown (not a git checkout)"
    # A copy of the repository inside some other checkout is not a checkout of pvcloth.
    if not commit or Path(top).resolve() != ROOT:
        return "commit unknown (not a git checkout)"
    return f"commit {commit}" + (" (plus uncommitted changes)" if changed else "")


def cpu_name() -> str:
    """The CPU's model name as Linux gives it (the processor or architecture elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def provenance() -> str:
    """One Markdown line naming the commit, machine, Python and date of a measurement.

    Returns
    -------
    str
        For example ``Measured on commit 1a2b3c4 (plus uncommitted changes) ·
        AMD EPYC 9R14, 2 cores · Python 3.11.7 · 2026-12-04.`` The commit is
        ``git rev-parse --short HEAD`` of the repository holding this folder,
        "plus uncommitted changes" when tracked files differ from it, and
        ``commit unknown (not a git checkout)`` when git or the repository is
        missing (as in the copy ``tests/test_benchmarks.py`` runs).

    Examples
    --------
    >>> lines = ["# My benchmark", provenance(), ""]  # doctest: +SKIP
    """
    cores = os.cpu_count()
    return (
        f"Measured on {_commit()} · {cpu_name()}, {cores or 'unknown'} cores · "
        f"Python {platform.python_version()} · {datetime.date.today().isoformat()}."
    )


if __name__ == "__main__":
    print(provenance())
