"""The README's two commands from a fresh clone, by the wall clock.

``python benchmarks/fresh_clone.py`` clones the repository's checked-out
commit into a scratch folder and runs, there, the two command blocks of the
README's "Install" section exactly as written: the first (system packages, a
fresh virtual environment, the install and the first movie) and the second
(the test command CI runs). It times each, splits the second by the summary
line each pytest run prints, and checks that the first left a movie.
``--quick`` then times the quick tier alone with the compiled kernels'
cache emptied first, as a fresh clone meets it. Nothing else should run on
the machine meanwhile. Writes ``benchmarks/results/fresh_clone.md``.

It needs root or sudo (the blocks call apt-get) and takes about 15 minutes
on 2 cores.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from provenance import ROOT, provenance
from smoke import SMOKE

HERE = Path(__file__).parent
QUICK = 'python -m pytest -n auto -m "not validation and not serial and not exhaustive"'
#: what pytest prints last: "=== 901 passed, 1 skipped in 486.45s (0:08:06) ==="
SUMMARY = re.compile(r"^=+ (?P<counts>.*?) in (?P<seconds>[\d.]+)s\b", re.MULTILINE)


def install_blocks(readme: str) -> list[str]:
    """The ``bash`` blocks of the README's Install section, in order."""
    section = readme.split("\n## Install", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.*?)\n```", section, re.DOTALL)


def run(command: str, cwd: Path, log: Path) -> tuple[float, str]:
    """Wall seconds of ``bash -c command`` in ``cwd`` and its output (also in ``log``)."""
    start = time.perf_counter()
    done = subprocess.run(
        ["bash", "-c", command], cwd=cwd, capture_output=True, text=True, check=False
    )
    seconds = time.perf_counter() - start
    output = done.stdout + done.stderr
    log.write_text(output)
    if done.returncode != 0:
        sys.exit(
            f"exit status {done.returncode} from {command!r} (all of it in {log}); "
            f"the last lines:\n{output[-3000:]}"
        )
    return seconds, output


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="also time the quick tier alone")
    parser.add_argument("--out", default=str(HERE / "results" / "fresh_clone.md"))
    args = parser.parse_args()
    blocks = install_blocks((ROOT / "README.md").read_text(encoding="utf-8"))
    if len(blocks) != 2:
        sys.exit(f"the README's Install section has {len(blocks)} bash blocks, expected 2")
    scratch = Path(tempfile.mkdtemp(prefix="pvcloth-fresh-"))
    clone = scratch / "pvcloth"
    if SMOKE:  # the copy the suite runs this from is no checkout: time stand-ins
        clone.mkdir()
        (clone / "hanging.gif").write_bytes(b"GIF89a")
        commands = ["true", "echo '=== 1 passed in 0.01s ==='; echo '=== 1 passed in 0.01s ==='"]
        quick = "echo '=== 1 passed in 0.01s ==='"
    else:
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        commands, quick = blocks, QUICK
    rows = []
    seconds, _ = run(commands[0], clone, scratch / "install.log")
    movie = clone / "hanging.gif"
    if not movie.is_file() or movie.stat().st_size == 0:
        sys.exit("the README's first command left no hanging.gif")
    rows.append(("install and the first movie (first command)", seconds, f"{movie.name} written"))
    seconds, output = run(commands[1], clone, scratch / "tests.log")
    runs = list(SUMMARY.finditer(output))
    if len(runs) != 2:
        sys.exit(f"expected two pytest summaries in the test command's output, found {len(runs)}")
    rows.append(("the test command (second command)", seconds, ""))
    tiers = ("quick and validation tiers", "serial tier")
    for name, found in zip(tiers, runs, strict=True):
        rows.append((f"of which the {name}", float(found["seconds"]), found["counts"]))
    pytest_seconds = sum(float(found["seconds"]) for found in runs)
    rows.append(("of which install and the rest", seconds - pytest_seconds, ""))
    if args.quick:
        shutil.rmtree(clone / ".cache" / "numba", ignore_errors=True)
        command = quick if SMOKE else f". .venv/bin/activate && {quick}"
        seconds, output = run(command, clone, scratch / "quick.log")
        found = SUMMARY.search(output)
        rows.append((f"quick tier alone, kernels compiled on the way (`{QUICK}`)", seconds,
                     found["counts"] if found else ""))  # fmt: skip
    lines = [
        "# The README's two commands from a fresh clone",
        "",
        provenance(),
        "",
        f"`{' '.join(['python benchmarks/fresh_clone.py', *sys.argv[1:]])}`: a clone of "
        "that commit in a scratch folder, the README's Install blocks run there as "
        "written, one after the other, nothing else running; wall minutes. The test "
        "command's parts come from the summary line each pytest run prints (collection "
        "included); the rest of it is apt-get, the virtual environment and pip.",
        "",
        "| what | minutes | outcome |",
        "|---|---|---|",
    ]
    lines += [f"| {what} | {seconds / 60:.1f} | {outcome} |" for what, seconds, outcome in rows]
    Path(args.out).write_text("\n".join(lines) + "\n", encoding="utf-8")
    shutil.rmtree(scratch, ignore_errors=True)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
