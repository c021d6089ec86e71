"""Rendering cost per frame: physics vs drawing vs encoding.

Renders the bundled hanging scene off-screen at 32x32 and 128x128 points, at
640x480 and 1280x720 pixels, to GIF and MP4, and records the median
milliseconds per frame of each stage. The step ``dt`` is the automatic one
(at most half the estimated stable step, dividing 1/60 s).

Run:  python benchmarks/render_cost.py [--frames 12] [--sizes 32 128] [--out FILE]
      (writes benchmarks/results/render_cost.md)
"""

from __future__ import annotations

import argparse
import platform
import tempfile
from pathlib import Path

import pyvista
from provenance import provenance

import pvcloth
from pvcloth.visual.movie import render

HERE = Path(__file__).parent
SCENE = HERE.parent / "data" / "scenes" / "hanging.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=12)
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 128])
    parser.add_argument("--out", type=Path, default=HERE / "results" / "render_cost.md")
    args = parser.parse_args()
    base = pvcloth.load_scene(SCENE)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            scene = base.with_resolution(n)
            # The scene's own step is unstable at 128x128: the automatic one.
            dt = pvcloth.Simulation(scene, stability="ignore").automatic_dt()
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
        provenance(),
        "",
        f"`python benchmarks/render_cost.py --frames {args.frames}` "
        f"({platform.machine()}), pyvista {pyvista.__version__}, "
        "off-screen EGL (Mesa llvmpipe, software). Median ms per frame; "
        "physics is one frame (1/30 s) of symplectic Euler at the automatic step "
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
    args.out.parent.mkdir(exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
