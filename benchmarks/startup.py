"""Start-up cost: ``import pvcloth`` and the first frame, with and without the
compiled kernels' on-disk cache, for the hanging scene and for a scene with
self-collision (``fold.toml``, whose kernels compile on its first step).

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
from provenance import provenance
from smoke import SMOKE

HERE = Path(__file__).parent
SCENES = HERE.parent / "data" / "scenes"

IMPORT = "import time; t = time.perf_counter(); import pvcloth; print(time.perf_counter() - t)"


def first_frame(scene: str) -> str:
    """Code that builds ``scene`` and simulates 1/30 s, printing the seconds
    from before the import."""
    return (
        "import time; t = time.perf_counter(); import pvcloth; "
        f"sim = pvcloth.Simulation.from_file({str(SCENES / scene)!r}); sim.advance(1 / 30); "
        "print(time.perf_counter() - t)"
    )


def seconds(code: str, env: dict) -> float:
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout.strip().splitlines()[-1])


REPEATS = 1 if SMOKE else 5


def cold_and_warm(code: str, env: dict) -> tuple[float, float]:
    """Medians (s) of ``code`` run with an empty numba cache (it compiles)
    and again with the cache that run left."""
    cold, warm = [], []
    for _ in range(REPEATS):
        with tempfile.TemporaryDirectory() as cache:
            env = dict(env, NUMBA_CACHE_DIR=cache)
            cold.append(seconds(code, env))
            warm.append(seconds(code, env))
    return float(np.median(cold)), float(np.median(warm))


def main() -> None:
    rows = []
    for backend in ("numba", "numpy"):
        env = dict(os.environ, PVCLOTH_BACKEND=backend)
        rows.append(
            (backend, "import pvcloth", np.median([seconds(IMPORT, env) for _ in range(REPEATS)]))
        )
        if backend == "numba":
            for scene, what in (("hanging.toml", ""), ("fold.toml", ", fold.toml")):
                cold, warm = cold_and_warm(first_frame(scene), env)
                rows.append((backend, f"import + first frame{what}, cold cache (compiles)", cold))
                rows.append((backend, f"import + first frame{what}, warm cache", warm))
        else:
            code = first_frame("hanging.toml")
            rows.append(
                (
                    backend,
                    "import + first frame",
                    np.median([seconds(code, env) for _ in range(REPEATS)]),
                )
            )
    lines = [
        "# Start-up",
        "",
        provenance(),
        "",
        "`python benchmarks/startup.py`: fresh processes, median of 5, seconds. The first "
        "frame is building the hanging scene (32x32, its stable-step check included) and "
        "simulating 1/30 s; with fold.toml, the same for the long cloth over the bar "
        "(32x32, self-collision on: its kernels compile on the first step).",
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
