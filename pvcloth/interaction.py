"""Mouse dragging of cloth points: an interactor style that decides on press.

VTK's trackball style takes the mouse on a button press, after which
interactor observers no longer see moves and releases. So this style decides
itself: a left press within a few pixels of a cloth point grabs that point
(the camera stays still); anywhere else the usual trackball rotation runs.
While dragging, the point follows the mouse on the plane through it parallel
to the view plane, as a moving pin inside the solver, so every integrator
respects it. Releasing lets it go; releasing with Shift leaves it pinned.

No physics here: the style only calls ``Simulation.pin``, ``move_pin`` and
``unpin``.
"""

from __future__ import annotations

import numpy as np
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleTrackballCamera

#: How close (pixels) a press must be to a cloth point to grab it.
PICK_RADIUS_PX = 12.0


def world_to_display(renderer, points: np.ndarray) -> np.ndarray:
    """Display coordinates ``(x, y, depth)`` of world points, vectorised
    through the renderer's composite projection matrix."""
    camera = renderer.GetActiveCamera()
    aspect = renderer.GetTiledAspectRatio()
    matrix = camera.GetCompositeProjectionTransformMatrix(aspect, -1, 1)
    m = np.array([[matrix.GetElement(i, j) for j in range(4)] for i in range(4)])
    homogeneous = np.c_[points, np.ones(len(points))] @ m.T
    ndc = homogeneous[:, :3] / homogeneous[:, 3:4]
    width, height = renderer.GetRenderWindow().GetSize()
    (vx0, vy0, vx1, vy1) = renderer.GetViewport()
    x = (vx0 + (ndc[:, 0] + 1) / 2 * (vx1 - vx0)) * width
    y = (vy0 + (ndc[:, 1] + 1) / 2 * (vy1 - vy0)) * height
    return np.c_[x, y, (ndc[:, 2] + 1) / 2]


def display_to_world(renderer, x: float, y: float, depth: float) -> np.ndarray:
    """The world point under display ``(x, y)`` at display ``depth``."""
    renderer.SetDisplayPoint(x, y, depth)
    renderer.DisplayToWorld()
    wx, wy, wz, w = renderer.GetWorldPoint()
    return np.array([wx, wy, wz]) / w


class ClothDragStyle(vtkInteractorStyleTrackballCamera):
    """Trackball camera, except that a press on the cloth drags a point.

    Parameters
    ----------
    sim : Simulation
        The simulation whose points are dragged.
    on_change : callable, optional
        Called after each grab, move or release (e.g. to re-render).
    """

    def __init__(self, sim, on_change=None):
        super().__init__()
        self.sim = sim
        self.on_change = on_change
        self.grabbed: int | None = None
        self.was_pinned = False
        self._depth = 0.0
        self.AddObserver("LeftButtonPressEvent", self._press)
        self.AddObserver("MouseMoveEvent", self._move)
        self.AddObserver("LeftButtonReleaseEvent", self._release)

    def _renderer(self):
        x, y = self.GetInteractor().GetEventPosition()
        self.FindPokedRenderer(x, y)
        return self.GetCurrentRenderer()

    def nearest_point(self, x: float, y: float) -> int | None:
        """Index of the cloth point nearest display ``(x, y)``, if within
        :data:`PICK_RADIUS_PX` pixels."""
        renderer = self._renderer()
        display = world_to_display(renderer, self.sim.positions)
        distance = np.hypot(display[:, 0] - x, display[:, 1] - y)
        close = np.flatnonzero(distance <= PICK_RADIUS_PX)
        if close.size == 0:
            return None
        return int(close[np.argmin(distance[close])])

    def _press(self, obj, event):
        x, y = self.GetInteractor().GetEventPosition()
        k = self.nearest_point(x, y)
        if k is None:
            self.OnLeftButtonDown()  # empty space: rotate the camera as usual
            return
        self.grabbed = k
        self.was_pinned = bool(self.sim.control.pinned[k])
        self._depth = world_to_display(self._renderer(), self.sim.positions[k : k + 1])[0, 2]
        self.sim.pin(k)
        self._changed()

    def _move(self, obj, event):
        if self.grabbed is None:
            self.OnMouseMove()
            return
        x, y = self.GetInteractor().GetEventPosition()
        self.sim.move_pin(self.grabbed, display_to_world(self._renderer(), x, y, self._depth))
        self._changed()

    def _release(self, obj, event):
        if self.grabbed is None:
            self.OnLeftButtonUp()
            return
        keep = self.GetInteractor().GetShiftKey() or self.was_pinned
        if not keep:
            self.sim.unpin(self.grabbed)
        self.grabbed = None
        self._changed()

    def _changed(self):
        if self.on_change is not None:
            self.on_change()
