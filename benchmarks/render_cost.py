"""Rendering cost per frame: physics vs drawing vs encoding.

Renders the bundled hanging scene off-screen at 32x32 and 128x128 points, at
640x480 and 1280x720 pixels, to GIF and MP4, and records the median
milliseconds per frame of each stage. The step ``dt`` is half the estimated
stable step of each cloth.

Run:  python benchmarks/render_cost.py [--frames 12]   (writes benchmarks/results/render_cost.md)
"""

from __future__ import annotations

import argparse
import platform
import tempfile
from pathlib import Path

import pyvista

import pvcloth
from pvcloth.movie import render

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=12)
    args = parser.parse_args()
    base = pvcloth.load_scene(SCENE)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (32, 128):
            scene = base.with_resolution(n)
            # half the estimated stable step (dashpots make it shrink faster than h)
            dt = 0.5 * pvcloth.Simulation(scene).stable_dt()
            for size in ((640, 480), (1280, 720)):
                for fmt in ("gif", "mp4"):
                    sim = pvcloth.Simulation(scene, dt=dt)
                    stats = render(
                        sim,
                        Path(tmp) / f"b.{fmt}",
                        frames=args.frames,
                        fps=30,
                        size=size,
                        progress=False,
                    )
                    ms = stats.medians_ms()
                    total = sum(ms.values())
                    rows.append((n, f"{size[0]}x{size[1]}", fmt, ms, total, dt))
                    print(rows[-1])
    lines = [
        "# Rendering cost per frame",
        "",
        f"`python benchmarks/render_cost.py --frames {args.frames}` on {platform.node()} "
        f"({platform.machine()}), pyvista {pyvista.__version__}, "
        "off-screen EGL (Mesa llvmpipe, software). Median ms per frame; "
        "physics is one frame (1/30 s) of symplectic Euler at half its stable step "
        "(dt column); encoding includes a share of finishing the file.",
        "",
        "| cloth | dt (s) | pixels | format | physics | drawing | encoding | total | physics |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for n, px, fmt, ms, total, dt in rows:
        lines.append(
            f"| {n}x{n} | {dt:.2g} | {px} | {fmt} | {ms['physics']:.1f} | {ms['drawing']:.1f} | "
            f"{ms['encoding']:.1f} | {total:.1f} | {100 * ms['physics'] / total:.0f} % |"
        )
    out = HERE / "results" / "render_cost.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
