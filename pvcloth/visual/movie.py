"""Off-screen movies and pictures: GIF, MP4 or PNG, written safely.

Output goes to a hidden temporary file beside the target and is renamed into
place only when it is complete. If the run is interrupted (Ctrl-C, an error,
a diverging simulation) after some frames, the writer is closed properly and
the frames done so far become the output; with no frame done, no file is
left. :class:`MovieInterrupted` says which happened.

A GIF's frames get delays of whole centiseconds that add up to the movie's
length (:func:`gif_delays`), and a frame rate above 50 is refused. An MP4 is
H.264 with its index at the start (plays while it loads); a frame size with
an odd side is padded by one row or column of edge pixels, never stretched,
and :attr:`RenderStats.notes` says so.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pvcloth.errors import InputError, MovieInterrupted
from pvcloth.io.files import Staged
from pvcloth.progress import frame_bar
from pvcloth.signals import deferred

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation

FORMATS = (".gif", ".mp4", ".png")
#: Highest frame rate a GIF can show: its delays are whole centiseconds, and
#: browsers slow a delay under 2 cs to about 10 cs.
GIF_MAX_FPS = 50.0


def gif_delays(frames: int, fps: float) -> list[int]:
    """Centisecond delays of ``frames`` GIF frames whose running total stays
    within half a centisecond of ``n / fps``: at 30 fps, 3, 4, 3, 3, 4, 3, ...
    so the movie lasts what it should (a constant 3 cs would be 11 % fast).

    Examples
    --------
    >>> gif_delays(6, 30.0)
    [3, 4, 3, 3, 4, 3]
    >>> sum(gif_delays(300, 30.0))  # centiseconds: ten seconds exactly
    1000
    """
    ends = [round(100 * k / fps) for k in range(frames + 1)]
    return [b - a for a, b in zip(ends, ends[1:], strict=False)]


@dataclass
class RenderStats:
    """Where the time of each frame went, in seconds per frame."""

    path: Path
    frames: int
    physics: list[float] = field(default_factory=list)
    drawing: list[float] = field(default_factory=list)
    encoding: list[float] = field(default_factory=list)
    closing: float = 0.0  # finishing the file (a GIF is quantised and written here)
    #: What the writer changed and why (an MP4 padded to even sides).
    notes: list[str] = field(default_factory=list)

    def medians_ms(self) -> dict[str, float]:
        """Median milliseconds per frame of each stage; encoding includes an
        equal share of the time spent finishing the file."""
        stages = {"physics": self.physics, "drawing": self.drawing, "encoding": self.encoding}
        medians = {k: 1e3 * float(np.median(v)) if v else 0.0 for k, v in stages.items()}
        medians["encoding"] += 1e3 * self.closing / max(self.frames, 1)
        return medians

    def __repr__(self) -> str:
        ms = self.medians_ms()
        return (
            f"<RenderStats {self.path.name}: {self.frames} frames; median ms per frame: "
            f"physics {ms['physics']:.1f}, drawing {ms['drawing']:.1f}, "
            f"encoding {ms['encoding']:.1f}>"
        )


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> ``(640, 480)``, with a clear error otherwise."""
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise InputError("size", f"expected WIDTHxHEIGHT like 640x480, got {text!r}") from None
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise InputError("size", f"each side must be 16 to 8192 pixels, got {text!r}")
    return width, height


class _FrameWriter:
    """Writes GIF (Pillow, per-frame delays), MP4 (ffmpeg through imageio)
    or, for PNG, keeps the last frame."""

    def __init__(self, path: Path, fps: float, notes: list[str]):
        self.path, self.fps, self.notes, self.last = path, fps, notes, None
        self.suffix = path.suffix.lower()
        self.frames: list[np.ndarray] = []
        self.writer = None
        if self.suffix == ".mp4":
            import imageio.v2 as imageio

            self.writer = imageio.get_writer(
                path,
                fps=fps,
                codec="libx264",
                quality=7,
                macro_block_size=1,  # sides are padded here, never stretched
                ffmpeg_log_level="error",
                # The index (moov) first: a browser plays while it loads.
                output_params=["-movflags", "+faststart"],
            )

    def append(self, image: np.ndarray) -> None:
        if self.suffix == ".mp4":
            # H.264 in yuv420p needs even sides: pad with the edge pixels.
            height, width = image.shape[:2]
            if height % 2 or width % 2:
                if not self.notes:
                    self.notes.append(
                        f"MP4 frames padded from {width}x{height} to "
                        f"{width + width % 2}x{height + height % 2} (H.264 needs even sides)"
                    )
                image = np.pad(image, ((0, height % 2), (0, width % 2), (0, 0)), mode="edge")
            self.writer.append_data(image)
        elif self.suffix == ".gif":
            self.frames.append(image)
        else:
            self.last = image

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()
        elif self.frames:
            from PIL import Image

            images = [Image.fromarray(frame) for frame in self.frames]
            # Pillow takes milliseconds and stores whole centiseconds; it
            # merges a frame identical to the one before, adding the delays.
            images[0].save(
                self.path,
                format="GIF",
                save_all=True,
                append_images=images[1:],
                duration=[10 * d for d in gif_delays(len(images), self.fps)],
                loop=0,
            )
        elif self.last is not None:
            import imageio.v2 as imageio

            imageio.imwrite(self.path, self.last, format="png")


def render(
    sim: Simulation,
    output: str | os.PathLike,
    *,
    frames: int = 90,
    fps: float = 30.0,
    size: tuple[int, int] = (640, 480),
    progress: bool = True,
    before_frame=None,
    color: str | None = None,
    clim: tuple[float, float] | None = None,
    cmap: str | None = None,
    label: bool = True,
    antialias: bool = True,
) -> RenderStats:
    """Run a simulation and write what it looks like.

    Parameters
    ----------
    sim : Simulation
        Advanced by ``1 / fps`` before every frame but the first.
    output : path
        ``.gif`` or ``.mp4`` for a movie of every frame, ``.png`` for the
        last frame.
    frames : int
        Number of frames (at least 1).
    fps : float
        Frames per second of simulated time and of the movie.
    size : (int, int)
        Width and height in pixels.
    progress : bool
        Show a progress bar with frame rate and time left.
    before_frame : callable, optional
        ``before_frame(sim, n)`` is called before frame ``n`` is advanced,
        e.g. to move a pin along a scripted path (with ``color="error"``, for
        the reference run too).
    color : str, optional
        Colour the cloth by a field (``"stretch"``, ``"speed"``, ``"force"``,
        ``"energy"`` or ``"error"``; see :data:`pvcloth.visual.colors.FIELDS`),
        with a scalar bar in its unit. ``"error"`` runs a fine RK4 reference
        beside the simulation (:class:`pvcloth.physics.reference.FollowingReference`).
    clim : (float, float), optional
        Fixed colour range; by default it grows with the values seen.
    cmap : str, optional
        Colour map name (matplotlib's); each field has its own default.
    label : bool
        Write time, integrator and step in the corner.
    antialias : bool
        FXAA (cheap anti-aliasing: a few ms per frame under software GL,
        ``benchmarks/results/render_cost.md``).

    Returns
    -------
    RenderStats
        Output path and per-frame timings of physics, drawing and encoding.

    Raises
    ------
    MovieInterrupted
        If the run stopped early; the message says whether a shorter valid
        movie was kept.

    Examples
    --------
    >>> import pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(12, 12))))
    >>> stats = pvcloth.render(sim, "hanging.gif", frames=6, size=(160, 120), progress=False)
    >>> stats.path.name, stats.frames, round(sim.time, 3)
    ('hanging.gif', 6, 0.167)
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(12, 12))))
    >>> stats = pvcloth.render(sim, "stretch.png", frames=6, color="stretch", progress=False)
    """
    path = check_output(output, fps)
    from pvcloth.visual.colors import check_cmap, check_field

    check_field(color)
    check_cmap(cmap)
    reference = None
    if color == "error":
        from pvcloth.physics.reference import FollowingReference

        reference = FollowingReference(sim)
        if before_frame is not None:
            scripted = before_frame

            def before_frame(sim, n):  # the reference gets the script's moves too
                scripted(sim, n)
                scripted(reference.sim, n)

    frame_numbers = sim.frames(frames, fps, before_frame)  # checked before any work

    def build(plotter):
        from pvcloth.visual.view import ClothView

        view = ClothView(
            sim, plotter, color=color, clim=clim, cmap=cmap, reference=reference, label=label
        )
        return view.update, lambda: f"t={sim.time:.2f}s"

    return record(path, fps, frames, frame_numbers, build, size, progress, antialias)


def check_output(output: str | os.PathLike, fps: float) -> Path:
    """The movie's path, once its format and frame rate are known to fit."""
    path = Path(output)
    if path.suffix.lower() not in FORMATS:
        raise InputError("output", f"unknown extension {path.suffix!r}; use one of {FORMATS}")
    if path.suffix.lower() == ".gif" and fps > GIF_MAX_FPS:
        raise InputError(
            "fps",
            f"{fps:g} is more than a GIF can show (at most {GIF_MAX_FPS:g}: its delays are "
            "whole centiseconds, and browsers slow delays under 2 cs to 10 cs); use a lower "
            "fps or an MP4",
        )
    return path


def record(
    path: Path,
    fps: float,
    frames: int,
    frame_numbers,
    build,
    size: tuple[int, int],
    progress: bool,
    antialias: bool = True,
    layout: dict | None = None,
) -> RenderStats:
    """The frame loop of every movie: off-screen plotter, frames drawn and
    written as the simulation advances, the file moved into place whole, a
    shorter valid movie kept when interrupted.

    ``build(plotter)`` adds what is drawn and returns ``(update, status)``:
    ``update()`` refreshes it before each frame, ``status()`` is the progress
    bar's note. ``frame_numbers`` advances the simulation(s) as it is
    iterated. ``layout`` holds the plotter's panel keywords (``shape``,
    ``row_weights``).
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    stats = RenderStats(path, 0)
    # Written under a hidden temporary name, published whole when finished
    # or, interrupted, with the frames done; anything else removes it.
    with Staged(path) as output:
        # notebook=False: in Jupyter, show() would otherwise put a picture or a
        # widget of this plotter in the cell, besides the movie asked for.
        with deferred():  # a signal inside VTK's module set-up crashed the process
            import pyvista as pv

            from pvcloth.visual.gl import use_offscreen_gl_if_headless

            use_offscreen_gl_if_headless()
            plotter = pv.Plotter(
                off_screen=True, notebook=False, window_size=list(size), **(layout or {})
            )
        writer = None
        # Only the physics is interrupted at once: a Ctrl-C or SIGTERM that comes
        # while VTK draws (which would swallow it), or while a frame is appended
        # or the file finished, takes effect when that step is done.
        try:
            with deferred():
                update, status = build(plotter)
                # FXAA instead of PyVista's default 4x MSAA: 640x480 drape frame
                # 30 ms against 49 ms under Mesa (15.6 ms with neither). Set on
                # VTK directly: PyVista swaps FXAA for the costlier SSAA under
                # EGL, though VTK's FXAA pass draws there (checked on pictures).
                plotter.render_window.SetMultiSamples(0)
                for renderer in plotter.renderers:
                    renderer.SetUseFXAA(bool(antialias))
                plotter.show(auto_close=False)
                writer = _FrameWriter(output.temporary, fps, stats.notes)
            bar = frame_bar(frame_numbers, frames, f"rendering {path.name}", enabled=progress)
            t0 = time.perf_counter()
            for _ in bar:  # each frame's physics runs inside the loop's next()
                t1 = time.perf_counter()
                with deferred():
                    update()
                    plotter.render()
                    image = plotter.screenshot(return_img=True)
                    t2 = time.perf_counter()
                    writer.append(image)
                    stats.frames += 1
                t3 = time.perf_counter()
                stats.physics.append(t1 - t0)
                stats.drawing.append(t2 - t1)
                stats.encoding.append(t3 - t2)
                bar.set_postfix_str(status())
                t0 = time.perf_counter()
            with deferred():
                t0 = time.perf_counter()
                writer.close()
                stats.closing = time.perf_counter() - t0
                writer = None
                output.publish()
            return stats
        except (Exception, KeyboardInterrupt) as error:
            with deferred(then_raise=False):  # the run is stopping already: finish the salvage
                interrupted = _salvage(writer, output, stats.frames, error)
            raise interrupted from error
        finally:
            with deferred(then_raise=False):
                plotter.close()


def _salvage(writer, output: Staged, done: int, error) -> MovieInterrupted:
    """Close what was written and publish it if it holds a frame; otherwise
    it is left for ``output`` to remove."""
    reason = "interrupted" if isinstance(error, KeyboardInterrupt) else str(error)
    path = output.path
    if writer is not None and done > 0:
        try:
            writer.close()
            output.publish()
            return MovieInterrupted(
                f"stopped after {done} frame(s): {reason}\n"
                f"kept a valid {path.suffix[1:].upper()} of those frames in {path}",
                path,
                done,
            )
        except Exception:  # the writer itself failed: keep nothing
            pass
    return MovieInterrupted(
        f"stopped before any frame was finished: {reason}\nno file written", None, done
    )
