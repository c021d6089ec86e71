"""Interactive frame rate (physics + render) of the window, under Xvfb.

Opens the real ClothApp window on the hanging scene at 32x32 and 64x64
points and times frames as the timer would run them (advance 1/30 s of
simulated time within the physics budget, update, render).

Run:  xvfb-run -a -s "-screen 0 1280x1024x24" python benchmarks/interactive_fps.py
      (writes benchmarks/results/interactive_fps.md)
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import pvcloth
from pvcloth.app import ClothApp

HERE = Path(__file__).parent
FRAMES = 60


def main() -> None:
    base = pvcloth.load_scene(HERE.parent / "data" / "scenes" / "hanging.toml")
    rows = []
    for n in (32, 64):
        scene = base.with_resolution(n)
        for integrator in ("symplectic_euler", "implicit_euler"):
            dt = 1 / 60 if integrator == "implicit_euler" else None
            sim = pvcloth.Simulation(scene, integrator=integrator, dt=dt, stability="substep")
            app = ClothApp(sim, window_size=(1024, 768))
            app.plotter.show(auto_close=False, interactive_update=True)
            frame, physics, draw = [], [], []
            for _ in range(FRAMES):
                start = time.perf_counter()
                app.frame()
                frame.append(time.perf_counter() - start)
                physics.append(app.physics_ms / 1e3)
                draw.append(app.render_ms / 1e3)
            app.plotter.close()
            f, p, d = (np.median(a[5:]) for a in (frame, physics, draw))
            rows.append((n, integrator, sim.dt, 1 / f, 1e3 * f, 1e3 * p, 1e3 * d, app.speed))
            print(rows[-1])
    lines = [
        "# Interactive frame rate",
        "",
        '`xvfb-run -a -s "-screen 0 1280x1024x24" python benchmarks/interactive_fps.py`: '
        f"the real window (1024x768, Xvfb, Mesa llvmpipe) on the hanging scene, median of "
        f"{FRAMES - 5} frames. Speed is simulated seconds per wall second the app settled "
        "on (1 = real time; below 1 the physics could not keep up and it slowed down).",
        "",
        "| cloth | integrator | dt (s) | fps | ms per frame | physics ms | drawing ms | speed |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {n}x{n} | {name} | {dt:.2g} | {fps:.1f} | {ms:.1f} | {pms:.1f} | {dms:.1f} "
        f"| {speed:.2f} |"
        for n, name, dt, fps, ms, pms, dms, speed in rows
    ]
    out = HERE / "results" / "interactive_fps.md"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
