"""Speed-up of a 64-run sweep on 1 and 2 local Dask workers.

The same sweep (4 stiffnesses x 4 steps x 4 integrators on a 12x12 hanging
cloth, 0.1 s simulated per run) runs on a fresh local cluster of 1 and then
2 single-threaded worker processes; the cluster's start is timed apart from
the sweep. Each run's own cost comes from the rows it wrote.

Run:  python benchmarks/sweep_scaling.py   (writes benchmarks/results/sweep_scaling.md)
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np
from dask.distributed import Client, LocalCluster
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.studies.sweep import parse_sets, run_sweep

HERE = Path(__file__).parent
SETS = [
    "springs.structural=100:800:4log",
    "solver.dt=1e-4:1e-3:4log",
    "solver.integrator=explicit_euler,symplectic_euler,verlet,rk4",
]
DURATION = 0.1
if SMOKE:
    SETS, DURATION = ["solver.dt=1e-4,2e-4"], 0.01


def main() -> None:
    scene = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml")
    scene = scene.with_resolution(12)
    sets = parse_sets(SETS)
    rows, costs = [], None
    for workers in (1, 2):
        start = time.perf_counter()
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
        client.run(lambda: __import__("pvcloth"))  # import on every worker before timing
        ready = time.perf_counter() - start
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            done = run_sweep(scene, sets, Path(out), duration=DURATION, client=client)
            wall = time.perf_counter() - start
        client.close()
        cluster.close()
        rows.append((workers, len(done), ready, wall))
        if costs is None:
            costs = [r["wall_per_sim_second"] * DURATION for r in done]
        print(rows[-1])
    base = rows[0][3]
    lines = [
        "# Sweep speed-up on local Dask workers",
        "",
        provenance(),
        "",
        f"`python benchmarks/sweep_scaling.py` ({os.cpu_count()} cores): "
        f"{' '.join('--set ' + s for s in SETS)} on the hanging scene at 12x12, "
        f"{DURATION:g} s simulated per run, single-threaded worker processes.",
        "",
        "| workers | runs | cluster start (s) | sweep wall (s) | speed-up |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {w} | {n} | {r:.1f} | {s:.1f} | {base / s:.2f} |" for w, n, r, s in rows]
    costs = np.array(costs)
    lines += [
        "",
        f"Each run on its own (from the rows): median {np.median(costs):.3f} s, "
        f"max {costs.max():.3f} s, total {costs.sum():.1f} s; the rest of the sweep's wall "
        "time is the references (RK4 at a quarter of the smallest step, one per stiffness), "
        "scheduling and data transfer.",
    ]
    out = HERE / "results" / "sweep_scaling.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
