"""The same scene under several integrators, side by side in one movie.

Each panel runs its own simulation of the scene (an integrator, and a step
or the automatic one); every frame advances all of them by the same
simulated time and draws them under one camera that frames all the cloths,
each panel labelled with its integrator and step, the wall time it took per
simulated second (its own clock, measured while the movie is made) and its
RMS distance from one shared reference: a fine RK4 run
(:class:`pvcloth.physics.reference.FollowingReference`, at a quarter of the
smallest step compared). A panel whose simulation diverges stops on its
last good state and says so; the others go on.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from pvcloth.compilation import compile_seconds
from pvcloth.errors import DivergenceError, InputError
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.physics.reference import FollowingReference
from pvcloth.physics.simulation import Simulation
from pvcloth.scene.parts import ACCELERATORS
from pvcloth.scene.spec import Scene
from pvcloth.visual.movie import RenderStats, check_output, record

#: Most panels in one movie.
MAX_PANELS = 6
#: Pixels of one panel when no size is given.
PANEL_SIZE = (480, 360)
#: Height of the cloth panels against the band of labels above them.
LABEL_ROWS = 3


@dataclass
class Panel:
    """One panel's run and what it cost.

    Attributes
    ----------
    sim : Simulation
    wall : float
        Wall seconds spent advancing it (drawing excluded).
    error : float
        RMS distance (m) from the reference at the last frame drawn.
    diverged : str
        The divergence message, or ``""``.
    """

    sim: Simulation
    wall: float = 0.0
    error: float = 0.0
    diverged: str = ""

    @property
    def wall_per_second(self) -> float:
        """Wall seconds per simulated second so far."""
        return self.wall / self.sim.time if self.sim.time > 0 else 0.0

    def label(self) -> str:
        sim = self.sim
        lines = [
            f"{sim.integrator_label}, dt = {sim.dt:.3g} s",
            f"{self.wall_per_second:.3g} s wall per simulated s",
            f"error {self.error:.3g} m RMS"
            + (f"   DIVERGED at {sim.time:.2f} s" if self.diverged else ""),
        ]
        return "\n".join(lines)


@dataclass
class CompareStats(RenderStats):
    """A compare movie's timings (as :class:`~pvcloth.visual.movie.RenderStats`)
    and its panels."""

    panels: list[Panel] = field(default_factory=list)


def parse_list(key: str, text: str) -> list[str]:
    """``"a,b,c"`` -> ``["a", "b", "c"]`` (blanks dropped)."""
    items = [item.strip() for item in text.split(",") if item.strip()]
    if not items:
        raise InputError(key, f"expected a comma-separated list, got {text!r}")
    return items


def parse_steps(text: str) -> list[float | None]:
    """``"1e-4,auto,1/60"`` -> ``[1e-4, None, 0.01666...]``."""
    steps: list[float | None] = []
    for item in parse_list("dts", text):
        if item == "auto":
            steps.append(None)
            continue
        try:
            if "/" in item:
                top, bottom = item.split("/")
                value = float(top) / float(bottom)
            else:
                value = float(item)
        except (ValueError, ZeroDivisionError):
            raise InputError("dts", f"{item!r} is not a step in seconds (or auto)") from None
        if not (math.isfinite(value) and value > 0):
            raise InputError("dts", f"{item!r}: a step must be a positive number of seconds")
        steps.append(value)
    return steps


def panel_scene(scene: Scene, method: str, dt: float | None) -> Scene:
    """``scene`` under ``method`` (an integrator's name, ``+ACCELERATOR``
    optional) at step ``dt``.

    >>> import pvcloth
    >>> solver = panel_scene(pvcloth.Scene(), "fast_bdf2+lbfgs", 1 / 60).solver
    >>> solver.integrator, solver.accelerator
    ('fast_bdf2', 'lbfgs')
    """
    name, plus, accelerator = method.partition("+")
    changes = {"solver.integrator": name, "solver.dt": dt}
    if plus:
        iterating = sorted(n for n, cls in INTEGRATORS.items() if cls.iterative)
        if name not in iterating or not accelerator:
            raise InputError(
                "integrators",
                f"{method!r}: +ACCELERATOR (one of {', '.join(ACCELERATORS)}) follows an "
                f"integrator that iterates ({', '.join(iterating)})",
            )
        changes["solver.accelerator"] = accelerator
    return scene.with_overrides(changes)


def compare(
    scene: Scene,
    output: str | os.PathLike,
    integrators: list[str],
    *,
    dts: list[float | None] | None = None,
    frames: int = 90,
    fps: float = 30.0,
    size: tuple[int, int] | None = None,
    color: str | None = None,
    progress: bool = True,
) -> CompareStats:
    """Write a movie of ``scene`` under each integrator, side by side.

    Parameters
    ----------
    scene : Scene
    output : path
        ``.gif``, ``.mp4`` or ``.png`` (the last frame).
    integrators : list of str
        One panel each (1 to :data:`MAX_PANELS`); a name may repeat with
        different steps, and may end in ``+ACCELERATOR`` for the fast
        implicit ones (``"fast_bdf2+lbfgs"``: ``solver.accelerator``).
    dts : list of float or None, optional
        Each panel's step (``None``: the automatic one); one value for all
        panels, or one per panel. By default the scene's.
    frames, fps : int, float
        As for :func:`pvcloth.render`.
    size : (int, int), optional
        The whole frame; by default 480x360 per panel.
    color : str, optional
        Colour every cloth by a field (one shared colour range).
    progress : bool

    Returns
    -------
    CompareStats

    Examples
    --------
    >>> import pvcloth
    >>> from pvcloth.visual.compare import compare
    >>> scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    >>> stats = compare(scene, "trade.png", ["symplectic_euler", "fast_mass_spring"],
    ...                 dts=[None, 1 / 60], frames=4, progress=False)
    >>> [panel.sim.integrator.name for panel in stats.panels], stats.frames
    (['symplectic_euler', 'fast_mass_spring'], 4)
    >>> bool(stats.panels[1].error > stats.panels[0].error)  # the frame-sized step errs more
    True
    """
    path = check_output(output, fps)
    if not 1 <= len(integrators) <= MAX_PANELS:
        raise InputError(
            "integrators", f"give 1 to {MAX_PANELS} integrators, got {len(integrators)}"
        )
    if dts is None:
        dts = [scene.solver.dt] * len(integrators)
    elif len(dts) == 1:
        dts = list(dts) * len(integrators)
    elif len(dts) != len(integrators):
        raise InputError(
            "dts", f"give one step or one per integrator ({len(integrators)}), got {len(dts)}"
        )
    panels = [
        Panel(Simulation(panel_scene(scene, method, dt)))
        for method, dt in zip(integrators, dts, strict=True)
    ]
    for panel in panels:
        panel.sim.frames(frames, fps)  # checks frames, fps and the run length
    finest = min(panels, key=lambda panel: panel.sim.dt).sim
    reference = FollowingReference(finest)
    width, height = size or (PANEL_SIZE[0] * len(panels), PANEL_SIZE[1])

    def frame_numbers():
        for n in range(frames):
            if n:
                for panel in panels:
                    if panel.diverged:
                        continue
                    start, compiled = time.perf_counter(), compile_seconds()
                    try:
                        panel.sim.advance(1.0 / fps)
                    except DivergenceError as error:
                        panel.diverged = str(error)
                    # A first run's kernel compilation is not the method's cost.
                    panel.wall += time.perf_counter() - start - (compile_seconds() - compiled)
            yield n

    def build(plotter):
        return _draw_panels(plotter, panels, reference, color)

    # A band of labels above the panels: the text never covers a cloth.
    layout = {"shape": (2, len(panels)), "row_weights": [1, LABEL_ROWS]}
    stats = record(
        path, fps, frames, frame_numbers(), build, (width, height), progress, layout=layout
    )
    return CompareStats(**vars(stats), panels=panels)


def _draw_panels(plotter, panels: list[Panel], reference, color):
    """One view per panel under a shared framing camera; returns the frame
    update and the progress note."""
    from pvcloth.visual.camera import BAR_STRIP, VIEWS, FramingCamera
    from pvcloth.visual.colors import ColorRange
    from pvcloth.visual.view import ClothView

    shared = ColorRange(color) if color else None
    views, labels = [], []
    columns = len(panels)
    for k, panel in enumerate(panels):
        plotter.subplot(1, k)
        view = ClothView(
            panel.sim, plotter, color=color, reference=reference, camera="none", show_pins=True
        )
        if shared is not None:
            view.range = shared
        views.append(view)
        plotter.subplot(0, k)
        plotter.set_background("white", all_renderers=False)
        band = plotter.window_size[1] / (LABEL_ROWS + 1)  # pixels of the label band
        labels.append(
            plotter.add_text(
                "",
                position=(0.03, 0.92),
                viewport=True,
                font_size=max(4, round(band / 11)),  # four lines fill the band
                color="#222222",
            )
        )
        labels[-1].GetTextProperty().SetVerticalJustificationToTop()
    plotter.link_views([columns + k for k in range(columns)])  # the cloth row
    scene = panels[0].sim.scene
    width, height = plotter.window_size
    plotter.subplot(1, 0)  # plotter.camera: the cloth row's shared camera
    framing = None
    if scene.camera.explicit:
        camera = plotter.camera
        camera.position, camera.focal_point = scene.camera.position, scene.camera.focal_point
        camera.up = scene.camera.up
    else:
        direction, up = VIEWS[scene.camera.view]
        panel_height = height * LABEL_ROWS / (LABEL_ROWS + 1)
        framing = FramingCamera(
            direction,
            up,
            aspect=width / columns / panel_height,
            right_strip=BAR_STRIP if color else 0.0,  # each panel's scalar bar
        )
        plotter.camera.SetWindowCenter(*framing.window_center())

    def update():
        for panel, view, text in zip(panels, views, labels, strict=True):
            view.update()
            panel.error = float(np.sqrt(np.mean(reference.error(panel.sim) ** 2)))
            text.SetInput(f"t = {panel.sim.time:.2f} s\n" + panel.label())
        if framing is not None:
            points = np.concatenate([view.surface.points for view in views])
            position, focal, up = framing.frame(points)
            camera = plotter.camera
            camera.position, camera.focal_point, camera.up = position, focal, up
            for renderer in plotter.renderers[columns:]:
                renderer.ResetCameraClippingRange()

    def status():
        return f"t={panels[0].sim.time:.2f}s"

    return update, status
