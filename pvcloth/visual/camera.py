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
  instead of jittering with each swing.
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
    ):
        self.axes = camera_axes(direction, up)
        self.tangents = half_angle_tangents(aspect)
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
            self.focal = self.focal + self.follow * (target - self.focal)
            wanted = fit_distance(points, self.focal, self.axes, self.tangents, self.fill)
            # Out fast, in slowly: a cloth that grows in the picture is met
            # before it reaches the edge, one that shrinks is not chased.
            rate = min(1.0, 3.0 * self.follow) if wanted > self.distance else self.follow
            self.distance += rate * (wanted - self.distance)
        # Never lose the cloth: the lagging focal point may need more distance
        # than the filtered one gives (a little more margin than the fit).
        inside = fit_distance(points, self.focal, self.axes, self.tangents, 0.95)
        self.distance = max(self.distance, inside, 1e-6)
        right, up, back = self.axes
        return self.focal + self.distance * back, self.focal.copy(), up

    def visible_share(self, points) -> float:
        """Largest projected offset of ``points`` from the frame's centre as a
        share of the frame's half-width or half-height (1 = on the edge)."""
        right, up, back = self.axes
        offset = np.asarray(points, dtype=float) - self.focal
        depth = self.distance - offset @ back
        s, u = np.abs(offset @ right) / depth, np.abs(offset @ up) / depth
        return float(np.maximum(s / self.tangents[0], u / self.tangents[1]).max())
