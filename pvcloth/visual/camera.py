"""Cameras: presets, a scene's explicit camera, and one that frames the cloth.

:class:`FramingCamera` looks along a fixed direction and moves its focal
point and distance with the cloth, so the cloth fills the frame through the
whole motion without leaving it:

- Each frame it computes the *fit*: the cloth's box centre as focal point,
  and the distance at which every cloth point projects inside the frame
  with a margin (:func:`fit_distance`; exact for a perspective camera,
  points nearer than the focal plane included).
- The camera follows the fit through first-order filters (a time constant
  of about a third of a second at 30 frames per second), so it glides
  instead of jittering with each swing; three times as fast when the cloth grows,
  and up to 2.5 times when it has shrunk to under :data:`CATCH_UP` of the
  frame (a tall cloth collapsing into a pile is not left small).
- With a scalar bar, the cloth is framed in the frame without its right
  strip (:data:`BAR_STRIP`), where the bar stands.
- After filtering, the distance is raised to what the filtered focal point
  needs for every point to stay inside the frame: whatever the lag, the
  cloth never leaves the picture.

Nothing here reads the physics beyond point positions.
"""

from __future__ import annotations

import math

import numpy as np

#: Preset directions (from the scene towards the camera) and view-up vectors;
#: z is up in every scene.
VIEWS = {
    "iso": ((0.9, -1.6, 0.8), (0.0, 0.0, 1.0)),
    "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "side": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
}
#: VTK's default vertical view angle, degrees.
VIEW_ANGLE = 30.0
#: A following camera catches up fast once the cloth's box spans less than
#: this share of the framed part (otherwise it follows slowly, so that a
#: swing is not chased).
CATCH_UP = 0.62
#: Share of the frame's width kept free on the right for a scalar bar: the
#: cloth is framed in the rest (:class:`FramingCamera`'s ``right_strip``).
BAR_STRIP = 0.17


def camera_axes(direction, up) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit ``(right, up, back)`` of a camera looking against ``direction``
    (``back`` points from the scene towards the camera)."""
    back = np.asarray(direction, dtype=float)
    back = back / np.linalg.norm(back)
    right = np.cross(np.asarray(up, dtype=float), back)
    if np.linalg.norm(right) < 1e-9:  # up along the view: any other up will do
        right = np.cross([0.0, 1.0, 0.0] if abs(back[1]) < 0.9 else [1.0, 0.0, 0.0], back)
    right /= np.linalg.norm(right)
    return right, np.cross(back, right), back


def half_angle_tangents(aspect: float, view_angle: float = VIEW_ANGLE) -> tuple[float, float]:
    """``tan`` of half the horizontal and half the vertical view angle of a
    frame ``aspect = width / height`` wide (VTK's view angle is vertical)."""
    vertical = math.tan(math.radians(view_angle) / 2.0)
    return vertical * aspect, vertical


def fit_distance(points, focal, axes, tangents, fill: float) -> float:
    """Camera distance from ``focal`` at which every point projects inside
    ``fill`` (0 to 1) of the frame's half-width and half-height.

    A point at screen offsets ``(s, u)`` from the focal point and depth
    ``z`` towards the camera is seen at ``s / (d - z)`` of the distance
    ``d``; inside the frame when that is at most ``fill`` times the half
    angle's tangent, so ``d >= z + |s| / (fill tan)``, and the same for ``u``.
    """
    right, up, back = axes
    offset = np.asarray(points, dtype=float) - focal
    s, u, z = np.abs(offset @ right), np.abs(offset @ up), offset @ back
    needed = z + np.maximum(s / (fill * tangents[0]), u / (fill * tangents[1]))
    return float(needed.max(initial=0.0))


class FramingCamera:
    """A camera along ``direction`` that keeps the cloth framed (see the
    module's description).

    Parameters
    ----------
    direction, up : 3-sequences
        From the scene towards the camera, and the view-up vector.
    aspect : float
        Frame width over height.
    fill : float
        Share of the frame's half-width or half-height the farthest cloth
        point is fitted to (the cloth's box then spans about this share of
        the frame along its limiting side).
    follow : float
        Share of the distance to the fit covered per frame (1: no smoothing).
    right_strip : float
        Share of the frame's width on the right that the cloth is kept out
        of (a scalar bar's place): the camera frames the rest, and
        :meth:`window_center` is where VTK must put the centre of its view
        for that.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.visual.camera import FramingCamera
    >>> camera = FramingCamera((0, -1, 0), (0, 0, 1), aspect=1.0)
    >>> square = np.array([[-1.0, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]])
    >>> position, focal, up = camera.frame(square)
    >>> focal.tolist(), up.tolist()
    ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    >>> float(camera.visible_share(square))  # the square's half-side over the frame's
    0.85
    """

    def __init__(
        self,
        direction,
        up,
        aspect: float,
        *,
        fill: float = 0.85,
        follow: float = 0.15,
        right_strip: float = 0.0,
    ):
        self.axes = camera_axes(direction, up)
        horizontal, vertical = half_angle_tangents(aspect)
        # The framed part of the frame is 1 - right_strip of its width,
        # centred right_strip (in VTK's -1 to 1 units) left of the middle.
        self.right_strip = right_strip
        self.tangents = (horizontal * (1.0 - right_strip), vertical)
        self.fill = fill
        self.follow = follow
        self.focal: np.ndarray | None = None
        self.distance = 0.0

    def frame(self, points) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Move towards the fit of ``points`` (m, shape (N, 3)) and return the
        camera's ``(position, focal_point, view_up)``."""
        points = np.asarray(points, dtype=float)
        target = 0.5 * (points.min(axis=0) + points.max(axis=0))
        if self.focal is None:
            self.focal = target
            self.distance = fit_distance(points, target, self.axes, self.tangents, self.fill)
        else:
            # Out fast, in slowly: a cloth that grows in the picture is met
            # before it reaches the edge, one that shrinks is not chased,
            # unless its box comes to span less than CATCH_UP of the framed
            # part (a tall cloth collapsing to a pile): then focal point and
            # distance speed up, smoothly, to 2.5 times the rate 0.1 below it.
            fast = min(1.0, 3.0 * self.follow)
            hurry = float(np.clip((CATCH_UP - self.box_share(points)) / 0.1, 0.0, 1.0))
            rate = min(1.0, self.follow * (1.0 + 1.5 * hurry))
            self.focal = self.focal + rate * (target - self.focal)
            wanted = fit_distance(points, self.focal, self.axes, self.tangents, self.fill)
            self.distance += (fast if wanted > self.distance else rate) * (wanted - self.distance)
        # Never lose the cloth: the lagging focal point may need more distance
        # than the filtered one gives (a little more margin than the fit).
        inside = fit_distance(points, self.focal, self.axes, self.tangents, 0.95)
        self.distance = max(self.distance, inside, 1e-6)
        right, up, back = self.axes
        return self.focal + self.distance * back, self.focal.copy(), up

    def window_center(self) -> tuple[float, float]:
        """VTK's window centre (``vtkCamera.SetWindowCenter``) that puts the
        camera's axis in the middle of the framed part of the frame."""
        return (self.right_strip, 0.0)

    def box_share(self, points) -> float:
        """Share of the framed part's width or height (the larger) that the
        box of ``points``, as projected by the camera where it is now, spans."""
        right, up, back = self.axes
        offset = np.asarray(points, dtype=float) - self.focal
        depth = np.maximum(self.distance - offset @ back, 1e-9)
        s, u = offset @ right / depth, offset @ up / depth
        return float(max(np.ptp(s) / self.tangents[0], np.ptp(u) / self.tangents[1]) / 2.0)

    def visible_share(self, points) -> float:
        """Largest projected offset of ``points`` from the framed part's
        centre as a share of its half-width or half-height (1 = on the edge)."""
        right, up, back = self.axes
        offset = np.asarray(points, dtype=float) - self.focal
        depth = self.distance - offset @ back
        s, u = np.abs(offset @ right) / depth, np.abs(offset @ up) / depth
        return float(np.maximum(s / self.tangents[0], u / self.tangents[1]).max())
