"""Start-up cost: ``import pvcloth`` and the first frame, with and without the
compiled kernels' on-disk cache.

Each measurement is a fresh Python process (median of 5). "Cold" points
numba's cache at an empty directory, so the kernels are compiled; "warm"
runs again with the cache that run left behind.

Run:  python benchmarks/startup.py   (writes benchmarks/results/startup.md)
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from smoke import SMOKE

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"

IMPORT = "import time; t = time.perf_counter(); import pvcloth; print(time.perf_counter() - t)"
FIRST_FRAME = (
    "import time; t = time.perf_counter(); import pvcloth; "
    f"sim = pvcloth.Simulation.from_file({str(SCENE)!r}); sim.advance(1 / 30); "
    "print(time.perf_counter() - t)"
)


def seconds(code: str, env: dict) -> float:
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout.strip().splitlines()[-1])


REPEATS = 1 if SMOKE else 5


def main() -> None:
    rows = []
    for backend in ("numba", "numpy"):
        env = dict(os.environ, PVCLOTH_BACKEND=backend)
        rows.append(
            (backend, "import pvcloth", np.median([seconds(IMPORT, env) for _ in range(REPEATS)]))
        )
        cold, warm = [], []
        for _ in range(REPEATS if backend == "numba" else 0):
            with tempfile.TemporaryDirectory() as cache:
                env["NUMBA_CACHE_DIR"] = cache
                cold.append(seconds(FIRST_FRAME, env))
                warm.append(seconds(FIRST_FRAME, env))
        if backend == "numba":
            rows.append((backend, "import + first frame, cold cache (compiles)", np.median(cold)))
            rows.append((backend, "import + first frame, warm cache", np.median(warm)))
        else:
            env.pop("NUMBA_CACHE_DIR", None)
            rows.append(
                (
                    backend,
                    "import + first frame",
                    np.median([seconds(FIRST_FRAME, env) for _ in range(REPEATS)]),
                )
            )
    lines = [
        "# Start-up",
        "",
        "`python benchmarks/startup.py`: fresh processes, median of 5, seconds. The first "
        "frame is building the hanging scene (32x32, its stable-step check included) and "
        "simulating 1/30 s.",
        "",
        "| backend | what | seconds |",
        "|---|---|---|",
    ]
    lines += [f"| {b} | {what} | {s:.2f} |" for b, what, s in rows]
    out = HERE / "results" / "startup.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
