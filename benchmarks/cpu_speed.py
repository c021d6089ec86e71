"""Step speed of every integrator, pvcloth's compiled and NumPy paths, and the
same cloth in Taichi's CPU backend, timed side by side.

For each size the solvers are built first and then timed round by round,
interleaved, so machine noise hits all of them alike; the table gives the
median of the rounds, ms per step, and the ratio pvcloth / Taichi. The
pvcloth numbers are ``Simulation.step()``, the whole user-facing step
(pins, divergence guard). Taichi runs the same model (benchmarks/taichi_cloth.py,
checked here against pvcloth's step) when ``pip install taichi`` has been
done; otherwise its columns are left out.

Run:  python benchmarks/cpu_speed.py [--sizes 32 64 128 256] [--rounds 7]
      [--out FILE] (writes benchmarks/results/cpu_speed.md)
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance

import pvcloth
from pvcloth.physics.kernels import threading_layer

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"
DT = 1e-5  # small enough for every integrator at every size


def pvcloth_solver(n: int, integrator: str, backend: str):
    scene = pvcloth.load_scene(SCENE).with_resolution(n)
    sim = pvcloth.Simulation(
        scene, integrator=integrator, dt=DT, stability="ignore", backend=backend
    )
    sim.advance(50 * DT)  # moving, and every kernel compiled
    return sim.step, sim


KERNELS_ALONE = "kernels alone (symplectic_euler's forces and update)"


def kernels_alone(sim):
    """The compiled calls of one symplectic Euler step and nothing else:
    ``Simulation.step()`` minus this is the Python around the kernels (pins,
    divergence guard, bookkeeping)."""
    from pvcloth.physics.kernels import kick_drift

    model, state, inv_mass = sim.model, sim.state.copy(), sim.control.inv_mass
    f, x, v = (np.empty_like(state.x) for _ in range(3))

    def step():
        model.compute_forces(state.x, state.v, out=f)
        kick_drift(state.x, state.v, f, inv_mass, DT, x, v, model.shape)

    return step


def taichi_solvers(n: int, reference):
    """Taichi float32 and float64 cloths started from ``reference``'s state,
    and how far one step of each lands from pvcloth's step."""
    sys.path.insert(0, str(HERE))
    import taichi as ti
    import taichi_cloth

    taichi_cloth.init()
    solvers, errors = {}, {}
    before = reference.state.copy()
    reference.step()
    for precision in ("float32", "float64"):
        cloth = taichi_cloth.TaichiCloth(
            reference.model,
            reference.control.inv_mass,
            DT,
            reference.scene.gravity,
            reference.scene.air_damping,
            precision,
        )
        cloth.set_state(before.x, before.v)
        cloth.step()
        x, _ = cloth.get_state()
        errors[precision] = float(np.abs(x - reference.state.x).max())

        def step(cloth=cloth):
            cloth.step()

        solvers[f"taichi {precision}"] = step
    return solvers, errors, ti.sync


def time_round(step, reps: int, sync=None) -> float:
    # Let the previous solver's thread pool go idle (spinning threads of one
    # pool slow the other's), then warm this one up before timing it.
    time.sleep(0.05)
    for _ in range(3):
        step()
    if sync:
        sync()
    start = time.perf_counter()
    for _ in range(reps):
        step()
    if sync:
        sync()
    return (time.perf_counter() - start) / reps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128, 256])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "cpu_speed.md")
    args = parser.parse_args()
    try:
        import taichi  # noqa: F401

        have_taichi = True
    except ImportError:
        have_taichi = False
        print("taichi not installed: timing pvcloth only (pip install taichi)")
    results, checks = [], []
    for n in args.sizes:
        solvers, syncs = {}, {}
        # Every integrator a user steps with; backward_euler measures others
        # (seconds per step at 64x64) and is left out.
        for name in sorted(k for k, cls in pvcloth.INTEGRATORS.items() if cls.interactive):
            solvers[f"pvcloth {name}"], sim = pvcloth_solver(n, name, "auto")
            if name == "symplectic_euler":
                reference = sim
        solvers["pvcloth symplectic_euler, NumPy path"], _ = pvcloth_solver(
            n, "symplectic_euler", "numpy"
        )
        solvers[KERNELS_ALONE] = kernels_alone(reference)
        if have_taichi:
            extra, errors, sync = taichi_solvers(n, reference)
            for key in extra:
                syncs[key] = sync
            solvers.update(extra)
            checks.append((n, errors))
        reps = {key: max(3, int(3e5 / n**2)) for key in solvers}
        for key in solvers:
            if "implicit" in key or "rk4" in key:
                reps[key] = max(2, reps[key] // 8)
        times = {key: [] for key in solvers}
        for _ in range(args.rounds):
            for key, step in solvers.items():
                times[key].append(time_round(step, reps[key], syncs.get(key)))
        medians = {key: float(np.median(t)) for key, t in times.items()}
        for key, median in medians.items():
            results.append((n, key, median, medians))
            print(f"{n:4d}  {key:42s} {1e3 * median:8.3f} ms")
    write(results, checks, args.rounds, have_taichi, args.out, sys.argv[1:])


def write(results, checks, rounds, have_taichi, out: Path, arguments: list[str]) -> None:
    import numba

    command = " ".join(["python benchmarks/cpu_speed.py", *arguments])
    lines = [
        "# CPU step speed: pvcloth and Taichi side by side",
        "",
        provenance(),
        "",
        f"`{command}` ({os.cpu_count()} cores), "
        f"Python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}"
        + (f", taichi {__import__('taichi').__version__}" if have_taichi else "")
        + f". Hanging scene (12 springs per point, gravity, air damping, two pins), "
        f"dt = {DT:g} s; median of {rounds} interleaved rounds, ms per step. "
        "pvcloth rows time `Simulation.step()`: float64, compiled kernels (numba, "
        f"{numba.get_num_threads()} threads from 64 rows up on numba's "
        f"`{threading_layer()}` threading layer) unless marked NumPy path. "
        "Ratios below 1 mean pvcloth is faster.",
        "",
        "| points per side | solver | ms per step | vs Taichi float32 | vs Taichi float64 |",
        "|---|---|---|---|---|",
    ]
    for n, key, median, medians in results:
        f32 = medians.get("taichi float32")
        f64 = medians.get("taichi float64")
        ratio32 = f"{median / f32:.2f}" if f32 and key.startswith("pvcloth") else ""
        ratio64 = f"{median / f64:.2f}" if f64 and key.startswith("pvcloth") else ""
        lines.append(f"| {n} | {key} | {1e3 * median:.3f} | {ratio32} | {ratio64} |")
    lines += [
        "",
        "Python around the kernels: `Simulation.step()` of symplectic Euler against its "
        "compiled calls alone (forces and update on the same arrays), same rounds:",
        "",
        "| points per side | step (ms) | kernels alone (ms) | share outside the kernels |",
        "|---|---|---|---|",
    ]
    for n, key, median, medians in results:
        if key == KERNELS_ALONE:
            step = medians["pvcloth symplectic_euler"]
            lines.append(
                f"| {n} | {1e3 * step:.3f} | {1e3 * median:.3f} | {1 - median / step:.0%} |"
            )
    if checks:
        lines += [
            "",
            "Same physics: largest position difference after one step from the same "
            "state, Taichi minus pvcloth's symplectic Euler (m):",
            "",
            "| points per side | Taichi float32 | Taichi float64 |",
            "|---|---|---|",
        ]
        lines += [f"| {n} | {e['float32']:.1e} | {e['float64']:.1e} |" for n, e in checks]
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
