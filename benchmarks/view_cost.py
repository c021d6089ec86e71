"""What each look costs to draw: colourings and compare panels, per frame.

Renders the hanging scene off-screen (PNG, so no encoding is timed) at 32x32
and 64x64 points and at 640x480 and 1280x720 pixels: in the cloth's own
colours, coloured by each field, and as a compare movie of three panels
(symplectic Euler at its automatic step, implicit Euler and fast_mass_spring
at 1/60 s). Drawing is what a frame costs besides the simulation's own
physics: updating the meshes (and the field), rendering with FXAA and
reading the picture back; for ``error`` it includes advancing the fine RK4
reference run, which is that colouring's price. Median ms per frame.

Run:  python benchmarks/view_cost.py [--frames 20] [--sizes 32 64] [--out FILE]
      (writes benchmarks/results/view_cost.md)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyvista
from provenance import provenance
from smoke import SMOKE

import pvcloth
from pvcloth.visual.compare import compare
from pvcloth.visual.movie import render

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"
LOOKS = (None, "stretch", "speed", "force", "energy", "error")
PIXELS = ((640, 480), (1280, 720))
PANELS = (["symplectic_euler", "implicit_euler", "fast_mass_spring"], [None, 1 / 60, 1 / 60])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64])
    parser.add_argument("--out", type=Path, default=HERE / "results" / "view_cost.md")
    args = parser.parse_args()
    frames, sizes = (3, [8]) if SMOKE else (args.frames, args.sizes)
    base = pvcloth.load_scene(SCENE)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            # The automatic step: the scene's own is above the stable one at 64x64.
            scene = base.with_resolution(n).with_overrides({"solver.dt": None})
            for pixels in PIXELS:
                for look in LOOKS:
                    sim = pvcloth.Simulation(scene)
                    stats = render(
                        sim,
                        Path(tmp) / "v.png",
                        frames=frames,
                        size=pixels,
                        color=look,
                        progress=False,
                    )
                    ms = stats.medians_ms()
                    rows.append((n, pixels, look or "plain", ms["drawing"], ms["physics"]))
                    print(rows[-1])
                start = time.perf_counter()
                stats = compare(
                    scene,
                    Path(tmp) / "c.png",
                    PANELS[0],
                    dts=PANELS[1],
                    frames=frames,
                    size=pixels,
                    progress=False,
                )
                wall = (time.perf_counter() - start) / frames
                ms = stats.medians_ms()
                rows.append((n, pixels, "compare, 3 panels", ms["drawing"], 1e3 * wall))
                print(rows[-1])
    command = " ".join(["python benchmarks/view_cost.py", *sys.argv[1:]])
    lines = [
        "# What each look costs to draw",
        "",
        provenance(),
        "",
        f"`{command}`, pyvista {pyvista.__version__}, off-screen EGL "
        f"(Mesa llvmpipe, software GL), FXAA on, hanging scene, {frames} frames per row. "
        "Drawing: median ms per frame besides the simulation's own steps (meshes and field "
        "updated, rendered, read back; for `error`, the RK4 reference run advanced too). "
        "Physics: median ms of the simulation's steps per frame (for compare, the whole "
        "frame's mean wall time, all three panels' physics included). A 30 fps movie's "
        "budget is 33 ms per frame.",
        "",
        "| cloth | pixels | look | drawing (ms) | physics (ms) |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {n}x{n} | {w}x{h} | {look} | {drawing:.1f} | {physics:.1f} |"
        for n, (w, h), look, drawing, physics in rows
    ]
    plain = {(n, p): d for n, p, look, d, _ in rows if look == "plain"}
    worst = max(
        d / plain[n, p]
        for n, p, look, d, _ in rows
        if look not in ("plain", "error") and not look.startswith("compare")
    )
    lines += [
        "",
        f"Largest cost of a field colouring over the plain look: {worst:.2f}x "
        f"(`error` left out: it runs a second simulation). Medians: "
        f"{np.median(list(plain.values())):.1f} ms plain.",
    ]
    args.out.parent.mkdir(exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
