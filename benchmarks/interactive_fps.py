"""What the interactive window delivers, by the wall clock, under Xvfb.

Opens the real ``pvcloth run`` window (ClothApp, its own timer and event
loop, 1024x768, software GL) on the hanging scene for each cloth size and
each integrator at the step the window gives it (``a``: half the stable
step, or 1/60 s for implicit ones), lets it run, and measures:

- frames per second: frames drawn over wall seconds, with the median and the
  worst interval between two frames (a frame that blocks shows here);
- the real-time fraction: simulated seconds over wall seconds;
- the longest physics chunk (work that runs beside the drawing).

With ``--wind`` the wind blows from the start, at what the window's ``w``
key turns on in a scene without wind of its own.

With ``--drag`` a point in the lower half of the cloth is grabbed once the
warm-up is over and carried round a circle of 80 pixels' radius every 2 s
(mouse events into the window's interactor, as the mouse gives them) for
the whole measurement, then let go.

Run:  xvfb-run -a -s "-screen 0 1280x1024x24" python benchmarks/interactive_fps.py
      [--scene data/scenes/hanging.toml] [--sizes 32 64] [--seconds 6]
      [--integrators ...] [--wind] [--drag] [--size 1024x768] [--out FILE]
      (writes benchmarks/results/interactive_fps.md)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from provenance import provenance

import pvcloth
from pvcloth.visual.interaction import world_to_display
from pvcloth.visual.window import DEFAULT_WIND, ClothApp

HERE = Path(__file__).parent
WARM_UP = 1.0  # wall seconds before measuring (compilation, first chunks)


DRAG_RADIUS, DRAG_PERIOD = 80.0, 2.0  # pixels, wall seconds per turn


def measure(
    scene,
    integrator: str,
    seconds: float,
    drag: bool = False,
    size=(1024, 768),
    scene_step: bool = False,
) -> dict:
    sim = pvcloth.Simulation(scene, integrator=integrator, stability="substep")
    if not scene_step:
        sim.set_step(None)  # what the window's "a" and "i" keys give
    app = ClothApp(sim, window_size=size)
    frames, chunks = [], []
    start = {}
    original = app.frame

    iren = app.plotter.iren
    nx, ny = sim.resolution
    held = {}

    def frame(*args):
        original(*args)
        now = time.perf_counter()
        frames.append(now)
        chunks.append(app.physics.chunk_ms)
        if "wall" not in start and now - frames[0] >= WARM_UP:
            start.update(wall=now, sim=sim.time, frame=len(frames) - 1)
            if drag:  # press on a free point a third of the way up
                k = nx // 2 + nx * (ny // 3)
                x, y, _ = world_to_display(app.plotter.renderer, sim.positions[k : k + 1])[0]
                held.update(x=x, y=y)
                iren._mouse_left_button_press(int(round(x)), int(round(y)))
                held["grabbed"] = app.style.grabbed is not None
        elif held:
            angle = 2 * np.pi * (now - start["wall"]) / DRAG_PERIOD
            iren._mouse_move(
                int(round(held["x"] + DRAG_RADIUS * np.sin(angle))),
                int(round(held["y"] + DRAG_RADIUS * (1 - np.cos(angle)))),
            )
        if "wall" in start and now - start["wall"] >= seconds:
            if held:
                iren._mouse_left_button_release(int(round(held["x"])), int(round(held["y"])))
            app.quit()

    app.frame = frame
    app.run()
    wall = frames[-1] - start["wall"]
    intervals = np.diff(frames[start["frame"] :])
    return {
        "n": scene.cloth.resolution[0],
        "integrator": integrator,
        "dt": sim.dt,
        "fps": len(intervals) / wall,
        "median_ms": 1e3 * float(np.median(intervals)),
        "worst_ms": 1e3 * float(intervals.max()),
        "real_time": (sim.time - start["sim"]) / wall,
        "chunk_ms": max(chunks[start["frame"] :]),
        "dragged": bool(held.get("grabbed")),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--scene", type=Path, default=HERE.parent / "data" / "scenes" / "hanging.toml"
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64])
    parser.add_argument("--seconds", type=float, default=6.0)
    parser.add_argument(
        "--integrators",
        nargs="+",
        default=sorted(n for n, cls in pvcloth.INTEGRATORS.items() if cls.interactive),
    )
    parser.add_argument("--drag", action="store_true", help="drag a point all the while")
    parser.add_argument(
        "--wind", action="store_true", help="wind from the start (the scene's, or the w key's)"
    )
    parser.add_argument(
        "--scene-step",
        action="store_true",
        help="the scene's own step, as pvcloth run opens it (default: the automatic step)",
    )
    parser.add_argument("--size", default="1024x768", help="window WIDTHxHEIGHT")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "interactive_fps.md")
    args = parser.parse_args()
    base = pvcloth.load_scene(args.scene)
    if args.wind and base.wind is None:
        base = base.replace(wind=DEFAULT_WIND)
    size = tuple(int(v) for v in args.size.split("x"))
    rows = []
    for n in args.sizes:
        for integrator in args.integrators:
            scene = base.with_resolution(n)
            rows.append(measure(scene, integrator, args.seconds, args.drag, size, args.scene_step))
            print(rows[-1], flush=True)
    lines = [
        "# The interactive window, by the wall clock",
        "",
        provenance(),
        "",
        '`xvfb-run -a -s "-screen 0 1280x1024x24" python benchmarks/interactive_fps.py'
        f"{''.join(' ' + a for a in sys.argv[1:])}`: "
        f"the real window ({args.size}, Xvfb, Mesa llvmpipe, its own 30 fps timer) on the "
        f"{base.name} scene"
        + (f" with wind {tuple(base.wind.velocity)} m/s" if base.wind else "")
        + f", {args.seconds:g} s measured after {WARM_UP:g} s of warm-up, "
        + (
            "each integrator at the scene's own step (as `pvcloth run` opens it). "
            if args.scene_step
            else "each integrator at the step the window's a key gives it. "
        )
        + "fps is frames drawn over wall "
        "seconds; the worst interval is the longest wait between two frames; real time "
        "is simulated over wall seconds (1 = real time; below it the window runs in slow "
        "motion and says so). Physics runs on its own thread: a long chunk slows the "
        "cloth, not the drawing."
        + (
            f" Dragging: a point grabbed and carried round a {DRAG_RADIUS:g} px circle every "
            f"{DRAG_PERIOD:g} s throughout ('dragged' says the press grabbed it)."
            if args.drag
            else ""
        ),
        "",
        "| cloth | integrator | dt (s) | fps | median frame (ms) | worst frame (ms) "
        "| real time | longest physics chunk (ms) |" + (" dragged |" if args.drag else ""),
        "|---|---|---|---|---|---|---|---|" + ("---|" if args.drag else ""),
    ]
    lines += [
        f"| {r['n']}x{r['n']} | {r['integrator']} | {r['dt']:.3g} | {r['fps']:.1f} "
        f"| {r['median_ms']:.1f} | {r['worst_ms']:.1f} | {r['real_time']:.2f} "
        f"| {r['chunk_ms']:.0f} |" + (f" {'yes' if r['dragged'] else 'NO'} |" if args.drag else "")
        for r in rows
    ]
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
