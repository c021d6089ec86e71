"""The interactive window: the cloth animates in real time and can be dragged.

A plotter timer advances the simulation at the frame rate. Each frame gets a
wall-time budget for physics; when the physics cannot keep up, the frame
simulates less time (slow motion, shown in the status line) instead of
queueing ever more substeps.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import dataclasses
import math
import os
import sys
import time

from .errors import DisplayError, DivergenceError
from .integrators import INTEGRATORS
from .interaction import ClothDragStyle
from .scene import WindSpec

#: Wind the ``w`` key turns on in a scene that has none: across a cloth that
#: hangs in the x-z plane, away from the default camera.
DEFAULT_WIND = WindSpec(velocity=(0.0, 6.0, 0.0))

KEYS = {
    "space": "pause / resume",
    "n": "single step (one frame)",
    "b": "back to the start",
    "i": "cycle integrator",
    "w": "wind on / off",
    "k": "screenshot (pvcloth_NNN.png)",
    "u": "unpin points pinned by dragging",
    "q": "quit",
}
HELP = "drag the cloth with the left button (Shift+release: leave pinned)\n" + "\n".join(
    f"{key:>5}: {what}" for key, what in KEYS.items()
)


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


class ClothApp:
    """A PyVista window running a simulation that the mouse can drag.

    Parameters
    ----------
    sim : Simulation
    fps : float
        Target frames per second.
    physics_share : float
        Largest share of a frame's wall time that physics may use before the
        animation slows down; less when drawing needs more of the frame.
    off_screen : bool
        Build the window off-screen (for tests and benchmarks).
    window_size : (int, int)

    Examples
    --------
    ``pvcloth run SCENE`` opens the window; from Python, ``ClothApp(sim).run()``
    does. Off-screen, a frame can be driven by hand:

    >>> import pvcloth
    >>> from pvcloth.app import ClothApp
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> app = ClothApp(sim, off_screen=True, window_size=(320, 240))
    >>> app.frame()  # advance by at most one frame of real time, then draw
    >>> 0 < sim.time <= 1 / 30
    True
    >>> app.plotter.close()
    """

    def __init__(
        self,
        sim,
        *,
        fps: float = 30.0,
        physics_share: float = 0.6,
        off_screen: bool = False,
        window_size=(1024, 768),
    ):
        import pyvista as pv

        from .view import ClothView

        self.sim = sim
        self.fps = fps
        self.physics_share = physics_share
        self.budget = physics_share / fps
        self.render_ms = 0.0
        self.message = ""
        self.paused = False
        self.speed = 1.0  # simulated seconds per wall second (1 = real time)
        self.physics_ms = 0.0
        self.frame_ms = 0.0
        self._last_frame = None
        self._shots = 0
        # No multisampling: under software GL (llvmpipe) 4x MSAA triples the
        # cost of a frame (benchmarks/results/interactive_fps.md).
        self.plotter = pv.Plotter(
            off_screen=off_screen,
            window_size=list(window_size),
            title=f"pvcloth - {sim.scene.name}",
        )
        self.plotter.render_window.SetMultiSamples(0)  # before the window first draws
        self.view = ClothView(sim, self.plotter)
        self.style = ClothDragStyle(sim, on_change=self.view.update)
        self.plotter.iren.style = self.style  # PyVista keeps it through show()
        self.status = self.plotter.add_text("", position="upper_left", font_size=9)
        self.plotter.add_text(HELP, position="lower_left", font_size=8)
        for key, action in (
            ("space", self.toggle_pause),
            ("n", self.single_step),
            ("b", self.restart),
            ("i", self.cycle_integrator),
            ("w", self.toggle_wind),
            ("k", self.screenshot),
            ("u", self.unpin_extras),
        ):
            self.plotter.add_key_event(key, action)
        self._stiffness = 1.0  # the slider calls back once as it is made
        self.plotter.add_slider_widget(
            self._set_stiffness,
            rng=[0.1, 10.0],
            value=1.0,
            title="stiffness x",
            pointa=(0.7, 0.92),
            pointb=(0.97, 0.92),
            style="modern",
            fmt="%.2f",
        )
        self._wind = sim.scene.wind or DEFAULT_WIND  # what "w" turns on
        speed = math.hypot(*self._wind.velocity)
        self._wind_direction = (
            tuple(c / speed for c in self._wind.velocity) if speed else (0.0, 1.0, 0.0)
        )
        self.plotter.add_slider_widget(
            self._set_wind_speed,
            rng=[0.0, 20.0],
            value=speed,
            title="wind m/s",
            pointa=(0.7, 0.8),
            pointb=(0.97, 0.8),
            style="modern",
            fmt="%.1f",
        )
        self._update_status()

    # -- the frame loop --------------------------------------------------------

    def frame(self, *_):
        """Advance one frame (called by the timer) and redraw."""
        now = time.perf_counter()
        if self._last_frame is not None:
            self.frame_ms = 0.8 * self.frame_ms + 0.2 * 1e3 * (now - self._last_frame)
        self._last_frame = now
        if not self.paused:
            self._guarded(self._advance, self.speed / self.fps)
        self.view.update()
        self._update_status()
        start = time.perf_counter()
        self.plotter.render()
        drawn = 1e3 * (time.perf_counter() - start)
        self.render_ms = drawn if not self.render_ms else 0.8 * self.render_ms + 0.2 * drawn
        # Physics gets what drawing leaves of the frame (at least a fifth).
        period = 1.0 / self.fps
        self.budget = min(
            self.physics_share * period, max(0.2 * period, period - 1.1e-3 * self.render_ms)
        )

    def _advance(self, seconds: float):
        start = time.perf_counter()
        self.sim.advance(seconds)
        spent = time.perf_counter() - start
        self.physics_ms = 1e3 * spent
        # Slow down gracefully: aim the next frame's simulated time at the
        # physics budget, never above real time, never more than 2x change.
        if spent > 0:
            target = self.speed * self.budget / spent
            self.speed = min(1.0, max(0.5 * self.speed, min(2.0 * self.speed, target)))

    def _update_status(self):
        fps = 1e3 / self.frame_ms if self.frame_ms else 0.0
        slow = (
            "" if self.speed > 0.99 else f"  SLOW MOTION x{self.speed:.2f} (physics cannot keep up)"
        )
        state = "PAUSED  " if self.paused else ""
        wind = self.sim.scene.wind
        blowing = "" if wind is None else f"   wind {math.hypot(*wind.velocity):.1f} m/s"
        text = (
            f"{state}t = {self.sim.time:6.2f} s   {fps:4.1f} fps   "
            f"physics {self.physics_ms:5.1f} ms   draw {self.render_ms:5.1f} ms"
            f"   {self.sim.integrator.name}, dt {self.sim.dt:.2g} s{blowing}{slow}"
        )
        if self.message:
            text += "\n" + self.message
        self.status.SetText(2, text)

    # -- keys and widgets ----------------------------------------------------

    def toggle_pause(self):
        self.paused = not self.paused
        self._update_status()

    def _guarded(self, advance, seconds: float) -> None:
        """Advance; a divergence pauses with a message instead of raising
        out of a VTK callback (the state is the last good step)."""
        try:
            advance(seconds)
        except DivergenceError as error:
            self.paused = True
            self.message = f"DIVERGED - press b to restart. {error}"

    def single_step(self):
        self.paused = True
        self._guarded(self.sim.advance, 1.0 / self.fps)
        self.view.update()
        self._update_status()

    def restart(self):
        self.style.grabbed = None  # a point held by the mouse is released too
        self.sim.reset()
        if self.message:  # restarting after a divergence runs again
            self.paused = False
        self.message = ""
        self.view.update()
        self._update_status()

    def toggle_wind(self):
        """Turn the wind off, or back on at the slider's speed."""
        self.sim.set_wind(None if self.sim.scene.wind is not None else self._wind)
        self._update_status()

    def cycle_integrator(self):
        names = sorted(INTEGRATORS)
        following = names[(names.index(self.sim.integrator.name) + 1) % len(names)]
        self.sim.set_integrator(following)
        self._update_status()

    def screenshot(self):
        self._shots += 1
        self.plotter.screenshot(f"pvcloth_{self._shots:03d}.png")

    def unpin_extras(self):
        self.sim.restore_scene_pins()
        self.view.update()

    def _set_stiffness(self, value):
        self.sim.scale_stiffness(value / self._stiffness)
        self._stiffness = value

    def _set_wind_speed(self, value):
        """Keep the wind's direction, change its speed (applied now if it blows)."""
        velocity = tuple(value * c for c in self._wind_direction)
        self._wind = dataclasses.replace(self._wind, velocity=velocity)
        if self.sim.scene.wind is not None:
            self.sim.set_wind(self._wind)

    def run(self, max_frames: int = 10**9):
        """Open the window and animate until it is closed (or ``q``)."""
        self.plotter.add_timer_event(
            max_steps=max_frames, duration=int(1000 / self.fps), callback=self.frame
        )
        self.plotter.show()
