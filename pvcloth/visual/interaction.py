"""Mouse dragging of cloth points: an interactor style that decides on press.

VTK's trackball style takes the mouse on a button press, after which
interactor observers no longer see moves and releases. So this style decides
itself: a left press within a few pixels of a cloth point grabs that point
(the camera stays still); anywhere else the usual trackball rotation runs.
While dragging, the point follows the mouse on the plane through it parallel
to the view plane, as a moving pin inside the solver, so every integrator
respects it. Releasing lets it go; releasing with Shift leaves it pinned.

The drag happens in the cloth's time: :class:`DragPath` records the cursor's
path against the wall clock and replays it on the simulation's clock, so in
slow motion the pin moves as fast in cloth time as the hand moved in real
time (played at wall speed, a 240 px drag in slow motion had thrown a cloth
25 m). No physics here: the style reports grabs, moves and releases to
callables (by default ``Simulation.pin``, ``move_pin`` and ``unpin``).
"""

from __future__ import annotations

import numpy as np
from vtkmodules.vtkInteractionStyle import vtkInteractorStyleTrackballCamera

#: How close (pixels) a press must be to a cloth point to grab it.
PICK_RADIUS_PX = 12.0

#: Fastest a dragged point moves, in metres per second of cloth time: a
#: flick of the mouse does not become a pin at tens of metres per second.
MAX_DRAG_SPEED = 5.0


class DragPath:
    """The cursor's path while a point is dragged, replayed on the cloth's
    clock: the pin is where the cursor was ``t - t0`` wall seconds after
    the grab when the cloth is ``t - t0`` simulated seconds after it.

    Parameters
    ----------
    point : ndarray, shape (3,)
        Where the grabbed point was (m).
    wall : float
        Wall-clock time of the grab (s).
    sim_time : float
        Simulated time of the grab (s).

    Examples
    --------
    A 0.3 m drag over one wall second, replayed at a fifth of real time:

    >>> import numpy as np
    >>> path = DragPath(np.zeros(3), wall=100.0, sim_time=2.0)
    >>> path.add(np.array([0.3, 0.0, 0.0]), wall=101.0)
    >>> path.at(2.2)  # 0.2 s of cloth time after the grab
    array([0.06, 0.  , 0.  ])
    >>> path.at(9.0)  # after the end: where the cursor stopped
    array([0.3, 0. , 0. ])
    """

    def __init__(self, point: np.ndarray, wall: float, sim_time: float):
        self.walls = [0.0]
        self.points = [np.asarray(point, dtype=float)]
        self.wall0, self.sim0 = wall, sim_time

    def add(self, point: np.ndarray, wall: float) -> None:
        """The cursor is at ``point`` (m) at wall-clock time ``wall`` (s)."""
        self.walls.append(max(wall - self.wall0, self.walls[-1]))
        self.points.append(np.asarray(point, dtype=float))

    @property
    def cursor(self) -> np.ndarray:
        """The latest cursor point (m)."""
        return self.points[-1]

    def at(self, sim_time: float) -> np.ndarray:
        """Where the path is ``sim_time - sim0`` seconds after the grab."""
        elapsed = sim_time - self.sim0
        # The physics thread reads while the main thread adds: take the
        # samples both lists already hold (add appends to one, then the other).
        count = min(len(self.walls), len(self.points))
        walls, points = self.walls[:count], np.array(self.points[:count])
        return np.array([np.interp(elapsed, walls, points[:, d]) for d in range(3)])

    def target(self, pin: np.ndarray, sim_time: float, seconds: float) -> np.ndarray:
        """Where a pin now at ``pin`` should be after ``seconds`` more of
        cloth time ending at ``sim_time``: on the path, at most
        :data:`MAX_DRAG_SPEED` away."""
        goal = self.at(sim_time)
        move = goal - pin
        distance = float(np.linalg.norm(move))
        reach = MAX_DRAG_SPEED * seconds
        return goal if distance <= reach else pin + move * (reach / distance)


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
        The simulation whose points are dragged (read for picking).
    on_grab, on_move, on_release : callable, optional
        Called with the grabbed point's index, with the cursor's world point
        (m) and with ``keep`` (leave the point pinned); by default they pin,
        move and unpin the point in ``sim`` at once.
    on_hover : callable, optional
        Called with the index a press would grab (or ``None``) as the mouse
        moves without a grab.
    snapshot : callable, optional
        Gives the :class:`~pvcloth.physics.state.Snapshot` the picture shows,
        where the points are picked (default: ``sim.snapshot``; a window
        passes the one its physics thread published).

    VTK's default character handlers (``w`` wireframe, ``s`` surface, ``r``
    reset, ``e``/``q`` exit, ``f`` fly to, ``p`` pick, ``3`` stereo, ...) are
    off: a real key press sends a character event too, and ``w`` toggled
    the wind and the wireframe at once.
    """

    def __init__(
        self, sim, on_grab=None, on_move=None, on_release=None, on_hover=None, snapshot=None
    ):
        super().__init__()
        self.sim = sim
        self.snapshot = snapshot or sim.snapshot
        self.on_grab = on_grab or sim.pin
        self.on_move = on_move or (lambda point: sim.move_pin(self.grabbed, point))
        self.on_release = on_release or self._unpin_unless_kept
        self.on_hover = on_hover
        self.grabbed: int | None = None
        self.was_pinned = False
        self._depth = 0.0
        self.AddObserver("LeftButtonPressEvent", self._press)
        self.AddObserver("MouseMoveEvent", self._move)
        self.AddObserver("LeftButtonReleaseEvent", self._release)
        # An observer replaces the style's own OnChar (vtkInteractorStyle
        # calls observers instead of its handler when there are any).
        self.AddObserver("CharEvent", lambda obj, event: None)

    def _renderer(self):
        x, y = self.GetInteractor().GetEventPosition()
        self.FindPokedRenderer(x, y)
        return self.GetCurrentRenderer()

    def nearest_point(self, x: float, y: float) -> int | None:
        """Index of the cloth point nearest display ``(x, y)``, if within
        :data:`PICK_RADIUS_PX` pixels."""
        renderer = self._renderer()
        display = world_to_display(renderer, self.snapshot().x)
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
        frame = self.snapshot()
        self.grabbed = k
        self.was_pinned = bool(np.isin(k, frame.pinned))
        self._depth = world_to_display(self._renderer(), frame.x[k : k + 1])[0, 2]
        self.on_grab(k)

    def _move(self, obj, event):
        x, y = self.GetInteractor().GetEventPosition()
        if self.grabbed is None:
            if self.on_hover is not None:
                self.on_hover(self.nearest_point(x, y))
            self.OnMouseMove()
            return
        self.on_move(display_to_world(self._renderer(), x, y, self._depth))

    def _release(self, obj, event):
        if self.grabbed is None:
            self.OnLeftButtonUp()
            return
        keep = bool(self.GetInteractor().GetShiftKey()) or self.was_pinned
        self.on_release(keep)
        self.grabbed = None

    def _unpin_unless_kept(self, keep: bool) -> None:
        if not keep:
            self.sim.unpin(self.grabbed)
