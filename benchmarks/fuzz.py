"""The long fuzz run: the suite's fuzz tests with many more cases.

Runs ``tests/test_fuzz.py`` (scene files through ``pvcloth info`` and
``simulate``, API call sequences, damaged and tampered checkpoints) with
``PVCLOTH_FUZZ_EXAMPLES`` cases per test, asks hypothesis for its statistics,
and records how many cases each test ran and whether any ended in anything
but success or pvcloth's own error (a traceback, a hang past hypothesis's
patience, or a silent NaN fails the test).

Run:  python benchmarks/fuzz.py [--examples 2500]   (writes benchmarks/results/fuzz.md)
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from provenance import provenance

HERE = Path(__file__).parent
ROOT = HERE.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=2500, help="cases per fuzz test")
    args = parser.parse_args()
    start = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:randomly", "tests/test_fuzz.py",
         "--hypothesis-show-statistics", "-p", "no:cacheprovider"],
        cwd=ROOT,
        env=dict(os.environ, PVCLOTH_FUZZ_EXAMPLES=str(args.examples)),
        capture_output=True,
        text=True,
    )  # fmt: skip
    wall = time.perf_counter() - start
    output = result.stdout
    # hypothesis's statistics: a test name line, then "- N passing examples, ..."
    rows = re.findall(
        r"tests/test_fuzz\.py::(\w+):\s*\n\s*\n?\s*- during generate phase.*?- (\d+) passing",
        output,
        flags=re.S,
    )
    if not rows:  # the layout of the statistics differs between versions
        names = re.findall(r"tests/test_fuzz\.py::(\w+):", output)
        counts = re.findall(r"- (\d+) passing examples", output)
        rows = list(zip(names, counts, strict=False))
    total = sum(int(n) for _, n in rows)
    summary = output.strip().splitlines()[-1] if output.strip() else result.stderr[-300:]
    lines = [
        "# Fuzzing",
        "",
        provenance(),
        "",
        f"`python benchmarks/fuzz.py --examples {args.examples}`: "
        f"{total:,} generated cases in {wall:.0f} s; pytest says: `{summary}`.",
        "",
        "A case passes when it ends in success or in pvcloth's own error (exit code 2 with a "
        "message, or a `PvclothError`) and no state it leaves holds a NaN.",
        "",
        "| fuzz test | cases that passed |",
        "|---|---|",
        *(f"| `{name}` | {int(count):,} |" for name, count in rows),
        "",
    ]
    out = HERE / "results" / "fuzz.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"wrote {out}")
    sys.exit(result.returncode)


if __name__ == "__main__":
    main()
