"""The interactive window: the cloth animates in real time and can be dragged.

Two threads. The main one belongs to VTK: it draws at the frame rate and
turns keys, sliders and the mouse into requests. One physics thread owns the
simulation and carries the requests out in order, between chunks of time
steps, so nothing that takes long (a stable-step estimate, an implicit step
of a quarter second) stops the window from drawing and following the mouse.

Time is the wall clock's: each chunk simulates the wall time that passed
since the previous one, as many steps as fit in a frame's physics budget
(at least one); what does not fit is dropped, which is slow motion, and the
status line shows the real-time fraction actually reached (simulated over
wall seconds, over the last second).
"""

from __future__ import annotations

import collections
import ctypes
import ctypes.util
import dataclasses
import math
import os
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

from pvcloth.errors import DisplayError, DivergenceError, SceneError
from pvcloth.io.files import atomic_write
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.physics.step_policy import STEP_SOURCES
from pvcloth.scene.parts import WindSpec
from pvcloth.visual.interaction import ClothDragStyle, DragPath
from pvcloth.visual.window_physics import PhysicsThread

#: Wind the ``w`` key turns on in a scene that has none: across a cloth that
#: hangs in the x-z plane, away from the default camera.
DEFAULT_WIND = WindSpec(velocity=(0.0, 6.0, 0.0))

#: Period of the event loop's timer (ms): frames are drawn on the ticks
#: where one is due (see :meth:`ClothApp.tick`).
TICK_MS = 5
#: Characters per line of a message in the status text (fits the left two
#: thirds of the window at its normalized font size).
STATUS_COLUMNS = 90

#: Keys the window answers, by VTK key symbol, with what they do. No other
#: key acts (VTK's and PyVista's default handlers are removed).
KEYS = {
    "space": "pause / resume",
    "n": "one frame of cloth time, then pause",
    "b": "back to the start",
    "i": "next integrator (with its own step)",
    "bracketleft": "[ halve the step",
    "bracketright": "] double the step",
    "a": "automatic step (a whole part of 1/60 s: stable, holds contact)",
    "w": "wind on / off",
    "k": "screenshot (file name shown)",
    "u": "unpin points pinned by dragging",
    "q": "quit",
}
HELP = (
    "drag the cloth with the left button (Shift+release: leave pinned)\n"
    + "\n".join(f"{key:>5}: {what}" for key, what in KEYS.items() if not key.startswith("bracket"))
    + "\n  [ ]: halve / double the step"
)

#: Font of the help text: VTK's built-in Arial draws ``[`` and ``]`` as
#: round brackets, so the help's "[ ]" read as "( )"; its Courier draws
#: them square (and lines up the key column).
HELP_FONT = "courier"

_NO_DISPLAY_HINT = (
    "On a machine without a screen, run it inside a virtual one: "
    "xvfb-run -a pvcloth run SCENE (Debian/Ubuntu: apt-get install xvfb xauth)."
)


def check_display() -> None:
    """Raise :class:`DisplayError` when a window cannot be opened.

    On Linux a window needs an X server (VTK's pip wheel draws through X).
    With no ``DISPLAY``, or one that no server answers, VTK only prints
    "bad X server connection" and its event loop returns at once, so the
    window would close silently; this asks Xlib directly instead.
    """
    if not sys.platform.startswith("linux"):
        return
    display = os.environ.get("DISPLAY")
    if not display:
        raise DisplayError(f"no display: DISPLAY is not set. {_NO_DISPLAY_HINT}")
    library = ctypes.util.find_library("X11")
    if library is None:  # cannot ask; VTK needs libX11 for a window anyway
        raise DisplayError(f"no X11 library (libX11) to open a window with. {_NO_DISPLAY_HINT}")
    xlib = ctypes.CDLL(library)
    xlib.XOpenDisplay.restype = ctypes.c_void_p
    xlib.XOpenDisplay.argtypes = [ctypes.c_char_p]
    xlib.XCloseDisplay.argtypes = [ctypes.c_void_p]
    connection = xlib.XOpenDisplay(display.encode())
    if not connection:
        raise DisplayError(f"cannot connect to the X display {display!r}. {_NO_DISPLAY_HINT}")
    xlib.XCloseDisplay(connection)


def next_screenshot_path(folder: Path, stem: str) -> Path:
    """``folder/STEM_NNN.png`` with the first number not taken, so no shot
    overwrites an earlier one, from this session or another."""
    taken = {p.name for p in folder.glob(f"{stem}_*.png")}
    n = 1
    while f"{stem}_{n:03d}.png" in taken:
        n += 1
    return folder / f"{stem}_{n:03d}.png"


class ClothApp:
    """A PyVista window running a simulation that the mouse can drag.

    Parameters
    ----------
    sim : Simulation
        Owned by the window's physics thread from here on: change it through
        the window (keys, sliders, mouse) or :meth:`request`.
    fps : float
        Target frames per second.
    physics_share : float
        Wall time of one chunk of steps, as a share of a frame: the longest
        a request (a key, a slider) waits for the physics thread.
    off_screen : bool
        Build the window off-screen (for tests and benchmarks).
    window_size : (int, int)
    shot_folder : path
        Where ``k`` writes screenshots.

    Examples
    --------
    ``pvcloth run SCENE`` opens the window; from Python, ``ClothApp(sim).run()``
    does. Off-screen, frames can be driven by hand:

    >>> import pvcloth
    >>> from pvcloth.visual.window import ClothApp
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> app = ClothApp(sim, off_screen=True, window_size=(320, 240))
    >>> app.single_frame(); app.wait()  # one frame of cloth time
    >>> round(sim.time * 30, 6)
    1.0
    >>> app.close()
    """

    def __init__(
        self,
        sim,
        *,
        fps: float = 30.0,
        physics_share: float = 0.6,
        off_screen: bool = False,
        window_size=(1024, 768),
        shot_folder: str | Path = ".",
    ):
        import pyvista as pv

        from pvcloth.visual.view import ClothView

        self.sim = sim
        self.fps = fps
        self.physics_share = physics_share
        self.shot_folder = Path(shot_folder)
        self.message = ""
        self.render_ms = 0.0
        self.frame_times: collections.deque[float] = collections.deque(maxlen=31)
        self._requests = []  # Futures of requests not yet looked at
        self._hovered = None
        self._next_frame = 0.0  # perf_counter time the next frame is due
        self.physics = PhysicsThread(sim, chunk_seconds=physics_share / fps)
        # No multisampling: under software GL (llvmpipe) 4x MSAA triples the
        # cost of a frame (benchmarks/results/interactive_fps.md).
        self.plotter = pv.Plotter(
            off_screen=off_screen,
            window_size=list(window_size),
            title=f"pvcloth - {sim.scene.name}",
        )
        self.plotter.render_window.SetMultiSamples(0)  # before the window first draws
        self.view = ClothView(sim, self.plotter, camera="fixed")
        self.style = ClothDragStyle(
            sim,
            on_grab=self._grab,
            on_move=self._drag_to,
            on_release=self._release,
            on_hover=self._hover,
            snapshot=lambda: self.physics.snapshot,  # pick what the picture shows
        )
        self.plotter.iren.style = self.style  # PyVista keeps it through show()
        self._add_handles()
        self._add_text()
        self._add_keys()
        self._add_sliders()
        self._update_status()

    # -- building the window -------------------------------------------------

    def _add_text(self):
        # Text in normalized viewport coordinates at a fixed font size: it
        # stays in its corner and readable at any window size (a corner
        # annotation shrank its text as the line grew).
        self.status = self.plotter.add_text(
            "", position=(0.01, 0.985), viewport=True, font_size=7, name="status"
        )
        self.status.GetTextProperty().SetVerticalJustificationToTop()
        self.help = self.plotter.add_text(
            HELP, position=(0.01, 0.01), viewport=True, font_size=6, font=HELP_FONT, name="help"
        )

    def _add_keys(self):
        iren = self.plotter.iren
        iren.clear_key_event_callbacks()  # PyVista's own (b, v, C, +, -, Up, Down, q)
        actions = {
            "space": self.toggle_pause,
            "n": self.single_frame,
            "b": self.restart,
            "i": self.cycle_integrator,
            "bracketleft": lambda: self.scale_step(0.5),
            "bracketright": lambda: self.scale_step(2.0),
            "a": self.automatic_step,
            "w": self.toggle_wind,
            "k": self.screenshot,
            "u": self.unpin_extras,
            "q": self.quit,
        }
        assert actions.keys() == KEYS.keys()
        for key, action in actions.items():
            self.plotter.add_key_event(key, action)

    def _add_sliders(self):
        # Right-hand column in normalized display coordinates.
        self._stiffness = 1.0
        self.stiffness_slider = self._slider(
            self._set_stiffness, (0.1, 10.0), 1.0, "stiffness x", 0.74, "%.2f"
        )
        self._wind = self.sim.scene.wind or DEFAULT_WIND  # what "w" turns on
        speed = math.hypot(*self._wind.velocity)
        self._wind_direction = (
            tuple(c / speed for c in self._wind.velocity) if speed else (0.0, 1.0, 0.0)
        )
        self.wind_slider = self._slider(
            self._set_wind_speed, (0.0, 20.0), speed, "wind m/s", 0.62, "%.1f"
        )
        self._show_wind_slider(self.sim.scene.wind is not None)

    def _slider(self, callback, limits, value: float, title: str, height: float, fmt: str):
        """A slider in the right-hand column at ``height`` (normalized display
        coordinates, so it keeps its place and size whatever the window's)."""
        slider = self.plotter.add_slider_widget(
            callback,
            rng=list(limits),
            value=value,
            title=title,
            pointa=(0.76, height),
            pointb=(0.98, height),
            style="modern",
            fmt=fmt,
            title_height=0.025,
            slider_width=0.02,
            tube_width=0.005,
        )
        # A VTK widget turns itself on and off at the "i" key unless told
        # not to: "i" (next integrator) hid the stiffness slider.
        slider.KeyPressActivationOff()
        return slider

    def _show_wind_slider(self, on: bool) -> None:
        (self.wind_slider.On if on else self.wind_slider.Off)()

    def _add_handles(self):
        """The grabbed point, the line from it to the cursor and the hover
        marker, drawn in a renderer layer above the scene (never hidden by
        cloth in front of them) that shares its camera."""
        import pyvista as pv
        from vtkmodules.vtkRenderingCore import vtkRenderer

        window = self.plotter.render_window
        main = self.plotter.renderer
        self.overlay = vtkRenderer()
        self.overlay.SetLayer(1)
        self.overlay.InteractiveOff()  # the mouse and the camera belong to the scene's
        self.overlay.SetActiveCamera(main.GetActiveCamera())
        window.SetNumberOfLayers(2)
        window.AddRenderer(self.overlay)
        self.handle = pv.PolyData(np.zeros((1, 3)))
        self.hover = pv.PolyData(np.zeros((1, 3)))
        self.leash = pv.Line((0, 0, 0), (0, 0, 0))
        actors = []
        for mesh, color, size in (
            (self.handle, "#e8590c", 16),
            (self.hover, "#1c7ed6", 12),
            (self.leash, "#e8590c", 3),
        ):
            mapper = pv.DataSetMapper(mesh)
            # pv.Line carries a "Distance" array; drawn as scalars it made the
            # leash purple instead of its colour.
            mapper.SetScalarVisibility(False)
            actor = pv.Actor(mapper=mapper)
            actor.prop.color = color
            actor.prop.point_size = size
            actor.prop.line_width = size
            actor.prop.render_points_as_spheres = True
            actor.visibility = False
            self.overlay.AddActor(actor)
            actors.append(actor)
        self.handle_actor, self.hover_actor, self.leash_actor = actors

    # -- requests to the physics thread -----------------------------------

    @property
    def paused(self) -> bool:
        return self.physics.paused

    def request(self, change, *args):
        """Run ``change(*args)`` on the physics thread after what is queued;
        errors it raises (a refused step, a divergence) show on screen."""
        future = self.physics.request(change, *args)
        self._requests.append(future)
        return future

    def wait(self) -> None:
        """Block until the physics thread has run every request so far
        (tests, benchmarks and closing use this; the window never does)."""
        self.physics.wait()
        self._collect()

    def _collect(self) -> None:
        """Errors of finished requests, and a divergence, onto the screen."""
        pending = []
        for future in self._requests:
            if not future.done():
                pending.append(future)
                continue
            error = future.exception()
            if isinstance(error, SceneError):
                self.message = f"refused: {error}"
            elif error is not None and not isinstance(error, DivergenceError):
                self.message = f"error: {type(error).__name__}: {error}"
        self._requests = pending
        if self.physics.diverged:
            self.message, self.physics.diverged = self.physics.diverged, None

    # -- the frame loop --------------------------------------------------------

    def frame(self, *_):
        """One frame (the timer calls it): show what the physics thread has
        reached, and any message."""
        self.frame_times.append(time.perf_counter())
        self._collect()
        self.draw()

    def draw(self) -> None:
        """Draw the instant the physics thread last published (one snapshot
        for the cloth, the handles and the status: no frame mixes two
        states) and render."""
        frame = self.physics.snapshot
        self.view.update(frame)
        self._update_handles(frame)
        self._update_status(frame)
        start = time.perf_counter()
        self.plotter.render()
        drawn = 1e3 * (time.perf_counter() - start)
        self.render_ms = drawn if not self.render_ms else 0.8 * self.render_ms + 0.2 * drawn

    @property
    def fps_measured(self) -> float | None:
        """Frames drawn per wall second over the last 30 frames."""
        if len(self.frame_times) < 2:
            return None
        span = self.frame_times[-1] - self.frame_times[0]
        return (len(self.frame_times) - 1) / span if span > 0 else None

    @property
    def real_time_fraction(self) -> float | None:
        """Simulated seconds per wall second over the last second, measured."""
        return None if self.paused else self.physics.meter.fraction

    def _update_status(self, frame=None):
        frame = self.physics.snapshot if frame is None else frame
        fps = self.fps_measured
        fraction = self.real_time_fraction
        pace = "" if fraction is None else f"   x{fraction:.2f} of real time"
        slow = "   SLOW MOTION" if fraction is not None and fraction < 0.95 else ""
        state = "PAUSED   " if self.paused else ""
        wind = frame.wind
        blowing = "" if wind is None else f"   wind {math.hypot(*wind.velocity):.1f} m/s"
        started = self.physics.chunk_started
        running = 0.0 if started is None else time.perf_counter() - started
        busy = f"   (a step running for {running:.1f} s)" if running > 2.0 / self.fps else ""
        text = (
            f"{state}t = {frame.t:6.2f} s{pace}{slow}{busy}\n"
            f"{'' if fps is None else f'{fps:4.1f} frames a second   '}drawing a frame "
            f"{self.render_ms:.1f} ms, the last steps {self.physics.chunk_ms:.1f} ms\n"
            f"{frame.integrator}, dt {frame.dt:.3g} s "
            f"({STEP_SOURCES[frame.dt_source]}){blowing}"
        )
        if self.message:
            # Wrapped: a refusal names a step and what to do, longer than a
            # line; unwrapped it ran off the window's right edge.
            text += "\n" + textwrap.fill(self.message, STATUS_COLUMNS)
        self.status.SetInput(text)

    def _update_handles(self, frame):
        k = self.style.grabbed
        drag = self.physics.drag
        grabbing = k is not None and drag is not None
        self.handle_actor.visibility = grabbing
        self.leash_actor.visibility = grabbing
        if grabbing:
            point = np.array(frame.x[k])
            self.handle.points = point[None]
            self.leash.points = np.array([point, drag[1].cursor])
        self.hover_actor.visibility = self._hovered is not None and not grabbing
        if self.hover_actor.visibility:
            self.hover.points = np.array(frame.x[self._hovered])[None]

    # -- the mouse -----------------------------------------------------------

    def _grab(self, k: int) -> None:
        frame = self.physics.snapshot  # the instant the press was aimed at
        path = DragPath(frame.x[k], time.perf_counter(), frame.t)
        self.request(self.sim.pin, k)
        self.physics.drag = (k, path)

    def _drag_to(self, point) -> None:
        drag = self.physics.drag
        if drag is not None:
            drag[1].add(point, time.perf_counter())

    def _release(self, keep: bool) -> None:
        """Let go; a point left pinned still finishes the cursor's path in
        cloth time (in a paused window, all of it after the pause)."""
        if not keep:
            self.physics.drag = None
            self.request(self.sim.unpin, self.style.grabbed)

    def _hover(self, k) -> None:
        self._hovered = k

    # -- keys and widgets ----------------------------------------------------

    def toggle_pause(self):
        self.physics.paused = not self.physics.paused
        self.physics.meter.restart()
        if not self.paused and self.message.startswith("DIVERGED"):
            self.message = ""

    def single_frame(self):
        """Pause, then one frame (1/fps) of cloth time."""
        self.physics.paused = True

        def one_frame():
            self.physics.run_chunk(max(1, round(1.0 / (self.fps * self.sim.dt))))

        self.request(one_frame)

    def restart(self):
        self.style.grabbed = None  # a point held by the mouse is released too
        self.physics.drag = None
        if self.message.startswith("DIVERGED"):  # restarting after a divergence runs again
            self.physics.paused = False
        self.message = ""

        def back_to_start():
            self.sim.reset()
            # Here, after the reset and on the physics thread: forgotten
            # before it, a sample taken at the old time could be kept and
            # the first span measured backwards (x-16 of real time).
            self.physics.forget_pace()

        self.request(back_to_start)

    def toggle_wind(self):
        """Turn the wind off, or back on at the slider's speed."""
        blowing = self.physics.snapshot.wind is not None
        self._show_wind_slider(not blowing)
        self.request(self.sim.set_wind, None if blowing else self._wind)

    def cycle_integrator(self):
        """The next integrator, at its own automatic step (1/60 s split
        under half its stable step and, with self-collision, the contact
        step: see :meth:`Simulation.automatic_dt
        <pvcloth.physics.simulation.Simulation.automatic_dt>`); the
        measuring-only ones (``backward_euler``, ``bdf2``) are left out,
        and with a tolerance those that cannot measure their error, and
        those that need more iterations than the scene gives (every key
        press would be refused)."""

        def switch():  # on the physics thread, which owns the simulation
            solver = self.sim.scene.solver
            adaptive = solver.tolerance is not None
            iterations = solver.iterations
            names = sorted(
                name
                for name, cls in INTEGRATORS.items()
                if cls.interactive
                and (cls.embedded or not adaptive)
                and (iterations is None or iterations >= cls.fewest_iterations(solver.accelerator))
            )
            current = self.sim.integrator.name
            at = names.index(current) + 1 if current in names else 0
            following = names[at % len(names)]
            self.sim.update({"solver.integrator": following, "solver.dt": None})
            self.physics.forget_pace()

        self.request(switch)

    def scale_step(self, factor: float) -> None:
        """Halve or double the step (refused above the stable share)."""
        self.message = ""

        def rescale():
            self.sim.set_step(self.sim.dt * factor)
            self.physics.forget_pace()

        self.request(rescale)

    def automatic_step(self) -> None:
        """The step ``solver.dt`` left out would give."""
        self.message = ""

        def automatic():
            self.sim.set_step(None)
            self.physics.forget_pace()

        self.request(automatic)

    def screenshot(self) -> Path:
        path = next_screenshot_path(self.shot_folder, f"pvcloth_{self.sim.scene.name}")
        # Written whole under a temporary name: whoever watches the folder
        # (a file manager, a test) never reads half a picture.
        atomic_write(path, lambda temporary: self.plotter.screenshot(temporary))
        self.message = f"screenshot: {path}"
        print(f"pvcloth: screenshot written to {path}", flush=True)
        return path

    def unpin_extras(self):
        self.request(self.sim.restore_scene_pins)

    def quit(self):
        self.plotter.iren.terminate_app()

    def _set_stiffness(self, value):
        factor = value / self._stiffness
        self._stiffness = value
        if factor != 1.0:

            def rescale():
                self.sim.scale_stiffness(factor)
                self.physics.forget_pace()

            self.request(rescale)

    def _set_wind_speed(self, value):
        """Keep the wind's direction, change its speed (applied now if it blows)."""
        velocity = tuple(value * c for c in self._wind_direction)
        self._wind = dataclasses.replace(self._wind, velocity=velocity)
        wind = self._wind

        def blow():  # on the physics thread: applied only while the wind blows
            if self.sim.scene.wind is not None:
                self.sim.set_wind(wind)

        self.request(blow)

    def tick(self, *_):
        """The event loop's timer, every :data:`TICK_MS`: a frame when one is
        due, else a short sleep.

        Why the sleeps: VTK's event loop holds Python's GIL while it waits
        for events, so the physics thread runs only while Python does; one
        timer per frame left it a few milliseconds per frame (measured: the
        cloth barely moved in a real window). Sleeping releases the GIL, and
        the loop still handles the mouse and keys between ticks."""
        now = time.perf_counter()
        if now >= self._next_frame - 0.5e-3 * TICK_MS:
            # Due times on a fixed grid of 1/fps, not "1/fps after the last
            # frame": a tick that comes late does not delay every later
            # frame (that cost 10 % of the frame rate: 27 fps for 30). A
            # window that fell a frame behind starts the grid again.
            period = 1.0 / self.fps
            self._next_frame = max(self._next_frame + period, now - 0.5 * period)
            self.frame()
            self._frames_left -= 1
            if self._frames_left <= 0:
                self.quit()
        else:
            time.sleep(0.8e-3 * TICK_MS)

    def run(self, max_frames: int = 10**9):
        """Open the window and animate until it is closed (or ``q``, or
        ``max_frames`` frames)."""
        self._frames_left = max_frames
        # VTK's own timer, not PyVista's add_timer_event: that one renders
        # after every callback, which made each 5 ms tick a full redraw.
        interactor = self.plotter.iren.interactor
        interactor.AddObserver("TimerEvent", self.tick)
        interactor.CreateRepeatingTimer(TICK_MS)
        self.physics.start()
        try:
            self.plotter.show()
        finally:
            self.close()

    def close(self) -> None:
        """Stop the physics thread (after its current chunk) and the window."""
        self.physics.stop()
        self.plotter.close()
