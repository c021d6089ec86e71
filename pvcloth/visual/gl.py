"""Which OpenGL window VTK makes: an off-screen EGL one (software GL through
Mesa) on a machine with no display, so movies and pictures render there
too."""

from __future__ import annotations

import os


def use_offscreen_gl_if_headless() -> None:
    """With no X display, ask VTK for an EGL window (software GL via Mesa).

    VTK reads the variable when it builds a render window, so this is
    called just before pvcloth makes a plotter (a movie, ``sim.plot``), not
    at import. Without it VTK first tries X and prints a "bad X server
    connection" warning before falling back; a value already set wins.
    """
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
