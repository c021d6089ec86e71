"""The view: the cloth and its scene drawn in a PyVista plotter.

Rendering reads the simulation; it never changes it. Two meshes show the
cloth:

- ``Simulation.mesh``, a ``pyvista.StructuredGrid`` of dimensions
  ``(nx, ny, 1)`` with every field as point data (:func:`cloth_mesh`), for
  users, notebooks and exports;
- the view's own ``PolyData`` of the same points (:class:`ClothView`), with
  normals computed from the grid and only the field it is coloured by, so a
  frame costs a copy and one field (a StructuredGrid is turned into a
  surface and its normals recomputed by a VTK pipeline on every change).

Fields (:data:`FIELDS`) are per point, with units; ``error`` needs a
reference run beside the simulation (:class:`pvcloth.physics.reference.FollowingReference`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pyvista as pv

from pvcloth.errors import InputError
from pvcloth.physics import topology
from pvcloth.physics.fields import MESH_FIELDS, point_fields
from pvcloth.visual.camera import VIEWS, FramingCamera

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation
    from pvcloth.physics.state import Snapshot


def use_offscreen_gl_if_headless() -> None:
    """With no X display, ask VTK for an EGL window (software GL via Mesa).

    VTK reads the variable when it builds a render window, so this is
    called just before pvcloth makes a plotter (a movie, ``sim.plot``), not
    at import. Without it VTK first tries X and prints a "bad X server
    connection" warning before falling back; a value already set wins.
    """
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


#: Front of the cloth (the side its grid normal points to) and back.
CLOTH_COLOR = "#c8553d"
CLOTH_BACK_COLOR = "#4f7fae"
BACK_COLOR = "#b7bfc9"
OBSTACLE_COLOR = "#8fa3b8"
#: The ground's checker: two close tones, so motion over it reads.
GROUND_COLORS = ("#ddd8cc", "#c9c3b5")


@dataclass(frozen=True)
class FieldStyle:
    """How a field is shown: scalar-bar title (with unit) and colour map."""

    title: str
    cmap: str
    #: Values the colour range always includes (1 for stretch: at rest).
    anchor: float = 0.0
    #: Colour range symmetric about the anchor (a diverging map).
    symmetric: bool = False


#: The fields a cloth can be coloured by (``--color``), all per point.
FIELDS = {
    "stretch": FieldStyle("stretch (length / rest length)", "coolwarm", 1.0, True),
    "speed": FieldStyle("speed (m/s)", "viridis"),
    "force": FieldStyle("spring force (N)", "magma"),
    "energy": FieldStyle("elastic energy (J/m^2)", "inferno"),
    "error": FieldStyle("distance from the reference (m)", "plasma"),
}


def check_field(name: str | None) -> str | None:
    """``name`` if it is a field of :data:`FIELDS` (or ``None``), else a
    clear :class:`~pvcloth.errors.InputError`."""
    if name is not None and name not in FIELDS:
        raise InputError("color", f"{name!r} is not a field; choose one of {', '.join(FIELDS)}")
    return name


def check_cmap(name: str | None) -> str | None:
    """``name`` if matplotlib knows the colour map (or ``None``), else a clear
    :class:`~pvcloth.errors.InputError`."""
    if name is None:
        return None
    import matplotlib

    if name not in matplotlib.colormaps:
        close = [known for known in sorted(matplotlib.colormaps) if known.lower() == name.lower()]
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(
            "cmap", f"{name!r} is not a colour map{hint}; e.g. viridis, coolwarm, magma, plasma"
        )
    return name


#: Scalar-bar titles of the point data on ``Simulation.mesh``.
FIELD_TITLES = {
    "velocity": "velocity (m/s)",
    "pinned": "pinned (1 = yes)",
    **{name: style.title for name, style in FIELDS.items()},
}


def cloth_grid(positions: np.ndarray, resolution: tuple[int, int]) -> pv.StructuredGrid:
    """A StructuredGrid of dimensions ``(nx, ny, 1)`` whose point ``k`` is
    ``positions[k]``: the solver's order is VTK's order, no reordering.

    Parameters
    ----------
    positions : ndarray, shape (nx * ny, 3)
    resolution : (int, int)
        ``(nx, ny)``.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.visual.view import cloth_grid
    >>> grid = cloth_grid(np.random.rand(12, 3), (4, 3))
    >>> grid.dimensions
    (4, 3, 1)
    """
    nx, ny = resolution
    grid = pv.StructuredGrid()
    grid.points = np.array(positions, dtype=float)
    grid.dimensions = (nx, ny, 1)
    return grid


def cloth_mesh(sim: Simulation) -> pv.StructuredGrid:
    """A new grid of the simulation's cloth with its point data (what
    ``Simulation.mesh`` holds; see there for the fields)."""
    grid = cloth_grid(sim.positions, sim.resolution)
    update_cloth_mesh(grid, sim)
    return grid


def update_cloth_mesh(grid: pv.StructuredGrid, sim: Simulation) -> None:
    """Refresh ``grid``'s points and point data from ``sim`` in place.

    Point arrays are assigned, not copied into, so VTK sees the change. No
    array is made the active scalars: a plotter that draws the grid in one
    colour keeps doing so.
    """
    grid.points = sim.state.x.copy()
    for name, values in point_fields(sim, MESH_FIELDS).items():
        grid.point_data.set_array(values, name)


def nice_ceiling(value: float) -> float:
    """The smallest of 1, 2, 2.5, 5 times a power of ten that is at least
    ``value`` (> 0): colour-range ends that read well and change rarely.

    Examples
    --------
    >>> from pvcloth.visual.view import nice_ceiling
    >>> nice_ceiling(0.0123), nice_ceiling(3.0), nice_ceiling(7.0)
    (0.02, 5.0, 10.0)
    """
    power = 10.0 ** math.floor(math.log10(value))
    for step in (1.0, 2.0, 2.5, 5.0, 10.0):
        if value <= step * power * (1 + 1e-12):
            return step * power
    return 10.0 * power


class ColorRange:
    """A colour range that only grows: a colour means the same value from
    the frame it first appears on (a range refitted to every frame would
    let colours drift while the values stand still).

    The range is the anchor to a rounded-up extreme of everything seen (for
    stretch, symmetric about 1); a fixed ``clim`` never changes.

    Examples
    --------
    >>> from pvcloth.visual.view import ColorRange
    >>> scale = ColorRange("stretch")
    >>> scale.update([0.999, 1.004])
    (0.995, 1.005)
    >>> scale.update([1.001])  # a calmer frame keeps the range
    (0.995, 1.005)
    """

    def __init__(self, field: str, clim=None):
        self.style = FIELDS[field]
        self.fixed = None if clim is None else (float(clim[0]), float(clim[1]))
        self.span = 0.0

    def update(self, values) -> tuple[float, float]:
        if self.fixed is not None:
            return self.fixed
        values = np.asarray(values, dtype=float)
        finite = values[np.isfinite(values)]
        anchor = self.style.anchor
        reach = float(np.abs(finite - anchor).max(initial=0.0))
        if reach > self.span:
            self.span = nice_ceiling(reach) if reach > 0 else 0.0
        span = self.span or (1e-3 if self.style.symmetric else 1e-6)
        if self.style.symmetric:
            return anchor - span, anchor + span
        low = min(anchor, float(finite.min(initial=anchor)))
        return low, low + span


def parse_clim(text: str) -> tuple[float, float]:
    """``"LOW,HIGH"`` -> ``(LOW, HIGH)`` with ``LOW < HIGH``, or a clear error."""
    try:
        low, high = (float(part) for part in text.split(","))
    except ValueError:
        raise InputError("clim", f"expected LOW,HIGH like 0.99,1.01, got {text!r}") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise InputError("clim", f"needs finite LOW < HIGH, got {text!r}")
    return low, high


def obstacle_surface(obstacle, extent: float) -> pv.PolyData:
    """The obstacle's surface (its own :meth:`surface`) in its own frame, the
    ground with texture coordinates for a checker of :func:`ground_cell`."""
    vertices, triangles = obstacle.surface(extent)
    faces = np.column_stack([np.full(len(triangles), 3), triangles]).ravel()
    mesh = pv.PolyData(np.asarray(vertices, dtype=float), faces)
    if obstacle.name == "ground":
        mesh.active_texture_coordinates = vertices[:, :2] / (2.0 * ground_cell(extent))
    elif obstacle.name != "box":  # a box's faces shade flat
        mesh = mesh.compute_normals(auto_orient_normals=False, split_vertices=False)
    return mesh


def ground_cell(extent: float) -> float:
    """Side (m) of one checker square on a ground drawn ``extent`` wide: a
    round length giving about 12 squares across."""
    return nice_ceiling(extent / 12.0)


def checker_texture() -> pv.Texture:
    """A 2x2 checker of :data:`GROUND_COLORS`, repeated over the ground."""
    light, dark = (np.array(pv.Color(c).int_rgb, dtype=np.uint8) for c in GROUND_COLORS)
    image = np.array([[light, dark], [dark, light]], dtype=np.uint8)
    texture = pv.Texture(image)
    texture.repeat = True
    texture.interpolate = False
    return texture


def obstacle_matrix(obstacle, t: float) -> np.ndarray:
    """4x4 matrix from the obstacle's frame to the world at time ``t``."""
    matrix = np.eye(4)
    matrix[:3, :3] = obstacle.axes
    matrix[:3, 3] = obstacle.center_at(t)
    return matrix


def motion_bounds(sim: Simulation) -> tuple[float, ...]:
    """Box the cloth can reach while it swings from its pins: where it starts,
    that box mirrored through the pins (the far side of the swing), and both
    moved down the gravity direction by the cloth's size (a fixed camera
    frames this)."""
    x = sim.model.rest_positions
    low, high = x.min(axis=0), x.max(axis=0)
    if sim.model.pinned.any() and np.any(sim.scene.gravity):
        down = np.asarray(sim.scene.gravity) / np.linalg.norm(sim.scene.gravity)
        shift = max(sim.scene.cloth.size) * down
        centre = x[sim.model.pinned].mean(axis=0)
        horizontal = 1.0 - np.abs(down)  # mirror only across gravity
        mirrored = np.sort(
            [centre + horizontal * (centre - low), centre + horizontal * (centre - high)], axis=0
        )
        low, high = np.minimum(low, mirrored[0]), np.maximum(high, mirrored[1])
        low, high = np.minimum(low, low + shift), np.maximum(high, high + shift)
    for obstacle in sim.model.obstacles:
        if obstacle.name == "ground":  # only the height of its point: it is unbounded
            corner = [obstacle.center_at(sim.time)] * 2
        else:
            grown = obstacle.bounds()[1] - obstacle.thickness
            radius = np.linalg.norm(grown)
            corner = [obstacle.center_at(sim.time) - radius, obstacle.center_at(sim.time) + radius]
        low, high = np.minimum(low, corner[0]), np.maximum(high, corner[1])
    margin = 0.15 * max(sim.scene.cloth.size)
    low, high = low - margin, high + margin
    return (low[0], high[0], low[1], high[1], low[2], high[2])


def plot_cloth(sim: Simulation, **kwargs):
    """``sim.mesh.plot(**kwargs)`` in the cloth's colours and smooth shading,
    unless ``scalars`` or ``color`` say otherwise; a field of the mesh gets a
    scalar bar titled with its unit."""
    scalars = kwargs.get("scalars")
    if scalars is None:
        kwargs.setdefault("color", CLOTH_COLOR)
    elif isinstance(scalars, str) and scalars in FIELD_TITLES:
        bar = dict(kwargs.get("scalar_bar_args") or {})
        bar.setdefault("title", FIELD_TITLES[scalars])
        bar.setdefault("fmt", "%.4g")  # stretch varies in the third decimal
        kwargs["scalar_bar_args"] = bar
    kwargs.setdefault("smooth_shading", True)
    use_offscreen_gl_if_headless()
    return sim.mesh.plot(**kwargs)


class ClothView:
    """Draws a simulation's cloth, pins and obstacles in a PyVista plotter.

    Parameters
    ----------
    sim : Simulation
        The simulation to read from.
    plotter : pyvista.Plotter
        Where to draw.
    color : str, optional
        A field of :data:`FIELDS` to colour the cloth by, with a scalar bar;
        ``None`` draws it in its front and back colours.
    clim : (float, float), optional
        Fixed colour range; by default it grows with the values seen
        (:class:`ColorRange`).
    cmap : str, optional
        A matplotlib colour map name; each field has its own default.
    reference : FollowingReference, optional
        What the ``error`` field is measured against.
    camera : {"scene", "fixed", "none"}
        ``"scene"``: as ``sim.scene.camera`` says (a camera that follows the
        cloth by default); ``"fixed"``: the scene's view direction on the
        region the cloth can reach, not moving (the window, whose camera
        the user turns); ``"none"``: left to the caller (``compare`` frames
        several views with one camera).
    label : bool
        Write time, integrator and step in a corner.
    show_pins : bool
        Draw pinned points as small spheres.

    Examples
    --------
    >>> import pyvista as pv, pvcloth
    >>> from pvcloth.visual.view import ClothView
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> plotter = pv.Plotter(off_screen=True, window_size=(160, 120))
    >>> view = ClothView(sim, plotter, color="stretch")
    >>> sim.advance(1 / 30); view.update()
    >>> view.field, view.clim[0] < 1.0 < view.clim[1]
    ('stretch', True)
    """

    def __init__(
        self,
        sim: Simulation,
        plotter: pv.Plotter,
        *,
        color: str | None = None,
        clim=None,
        cmap: str | None = None,
        reference=None,
        camera: str = "scene",
        label: bool = False,
        show_pins: bool = True,
    ):
        self.sim = sim
        self.plotter = plotter
        self.field = check_field(color)
        check_cmap(cmap)
        if self.field == "error" and reference is None:
            raise InputError("color", "the error field needs a reference run beside the cloth")
        self.reference = reference
        self.range = ColorRange(self.field, clim) if self.field else None
        self.clim: tuple[float, float] | None = None
        plotter.set_background(BACK_COLOR, top="white")
        self._light(plotter)
        self.surface = pv.PolyData(sim.state.x.copy(), topology.vtk_faces(sim.model.shape))
        self._refresh_surface(sim.snapshot())
        self.actor = self._add_cloth(cmap)
        self.pins = None
        if show_pins:
            self.pins = pv.PolyData(np.array(sim.positions[sim.pinned_indices]))
            # A cloth with no pins yet may get some later (a mouse drag).
            plotter.theme.allow_empty_mesh = True
            plotter.add_points(
                self.pins,
                color="#222222",
                point_size=10,
                render_points_as_spheres=True,
                name="pins",
            )
        self.obstacle_actors = self._add_obstacles()
        self.text = None
        self._clock = None  # (time, steps) when the overlay last said the step
        if label:
            # Sized to the frame (9 points at 480 rows), so it never covers a
            # small picture.
            height = plotter.window_size[1] / plotter.shape[0]
            self.text = plotter.add_text(
                "",
                position=(0.015, 0.02),
                viewport=True,
                font_size=max(5, round(9 * height / 480)),
                color="#222222",
            )
            self.text.GetTextProperty().SetBackgroundColor(1.0, 1.0, 1.0)
            self.text.GetTextProperty().SetBackgroundOpacity(0.65)
        self.framing = None
        self._set_camera(camera)
        self.update()

    # -- building --------------------------------------------------------------

    @staticmethod
    def _light(plotter) -> None:
        """A headlight and a soft light from above, with some ambient light
        in the materials: a sheet facing the camera shows close to its own
        colour (VTK's default light kit showed a vertical sheet at half of
        it from the default camera) and folds still shade."""
        renderer = plotter.renderer  # this view's panel only
        renderer.remove_all_lights()
        renderer.add_light(pv.Light(light_type="headlight", intensity=0.85))
        # From straight above, wherever the camera is: a lying sheet is lit too.
        renderer.add_light(
            pv.Light(
                position=(0.0, 0.0, 1.0),
                focal_point=(0.0, 0.0, 0.0),
                intensity=0.25,
                positional=False,
                light_type="scene light",
            )
        )

    def _add_cloth(self, cmap):
        # Gouraud: shaded with the grid's point normals (PyVista draws flat
        # unless asked to smooth, which would recompute normals per frame).
        material = dict(
            ambient=0.25, diffuse=0.75, specular=0.1, specular_power=20.0, interpolation="gouraud"
        )
        if self.field is None:
            actor = self.plotter.add_mesh(self.surface, color=CLOTH_COLOR, name="cloth", **material)
            actor.backface_prop = pv.Property(color=CLOTH_BACK_COLOR, **material)
            return actor
        style = FIELDS[self.field]
        rows = self.plotter.window_size[1] / self.plotter.shape[0]
        text = max(5, round(12 * rows / 480))  # points: readable, never larger than the frame
        actor = self.plotter.add_mesh(
            self.surface,
            scalars=self.field,
            clim=self.clim,
            cmap=cmap or style.cmap,
            name="cloth",
            scalar_bar_args={
                "title": style.title,
                "fmt": "%.4g",
                "vertical": False,
                "position_x": 0.52,
                "position_y": 0.04,
                "width": 0.45,
                "height": 0.09,
                "n_labels": 3,
                "title_font_size": text,
                "label_font_size": text - 1,
                "color": "#222222",
            },
            **material,
        )
        # A colour map colours both sides; the back is drawn darker.
        actor.backface_prop = pv.Property(**{**material, "diffuse": 0.45, "ambient": 0.12})
        return actor

    def _add_obstacles(self) -> list:
        actors = []
        extent = 4.0 * max(self.sim.scene.cloth.size)
        for n, obstacle in enumerate(self.sim.model.obstacles):
            ground = obstacle.name == "ground"
            actor = self.plotter.add_mesh(
                obstacle_surface(obstacle, extent),
                color=None if ground else OBSTACLE_COLOR,
                texture=checker_texture() if ground else None,
                smooth_shading=not ground and obstacle.name != "box",
                # The floor lit mostly by ambient light: it reads as a light
                # floor from any camera, not a dark slab at grazing light.
                ambient=0.7 if ground else 0.25,
                diffuse=0.35 if ground else 0.75,
                specular=0.0 if ground else 0.3,
                name=f"obstacle{n}",
            )
            actor.user_matrix = obstacle_matrix(obstacle, self.sim.time)
            actors.append(actor)
        return actors

    def _set_camera(self, mode: str) -> None:
        if mode == "none":
            return
        spec = self.sim.scene.camera
        camera = self.plotter.camera
        if spec.explicit:
            camera.position, camera.focal_point = spec.position, spec.focal_point
            camera.up = spec.up
            self.plotter.renderer.ResetCameraClippingRange()
            return
        direction, up = VIEWS[spec.view]
        if mode == "scene" and spec.follow:
            width, height = self.plotter.window_size
            self.framing = FramingCamera(direction, up, aspect=width / height)
            return
        self.plotter.view_vector(direction, viewup=up)
        self.plotter.reset_camera(bounds=motion_bounds(self.sim))

    def reset_camera(self) -> None:
        """Back to the starting camera (a following camera starts afresh)."""
        if self.framing is not None:
            self.framing.focal = None
        self._set_camera("scene" if self.framing is not None else "fixed")

    # -- every frame -----------------------------------------------------------

    def _refresh_surface(self, frame: Snapshot) -> None:
        x = np.array(frame.x)
        self.surface.points = x
        self.surface.point_data["Normals"] = topology.normals(x, self.sim.model.shape)
        self.surface.point_data.active_normals_name = "Normals"
        if self.field is not None:
            values = point_fields(self.sim, [self.field], self.reference, frame)[self.field]
            self.surface.point_data[self.field] = values
            self.clim = self.range.update(values)

    def update(self, frame: Snapshot | None = None) -> None:
        """Draw one instant, ``frame`` (default: the simulation's current
        state), into the meshes (and move a following camera). Everything
        drawn comes from that one snapshot: a window passes the one its
        physics thread published, so no picture mixes two states."""
        sim = self.sim
        frame = sim.snapshot() if frame is None else frame
        self._refresh_surface(frame)
        if self.field is not None:
            self.actor.mapper.scalar_range = self.clim
        for obstacle, actor in zip(sim.model.obstacles, self.obstacle_actors, strict=True):
            if obstacle.path.size:
                actor.user_matrix = obstacle_matrix(obstacle, frame.t)
        if self.pins is not None:
            pins = frame.x[frame.pinned]
            if len(pins) == self.pins.n_points:
                self.pins.points = pins
            else:  # pins were added or removed: rebuild the small point cloud
                self.pins.copy_from(pv.PolyData(np.array(pins)))
        if self.framing is not None:
            position, focal, up = self.framing.frame(self.surface.points)
            camera = self.plotter.camera
            camera.position, camera.focal_point, camera.up = position, focal, up
            self.plotter.renderer.ResetCameraClippingRange()
        if self.text is not None:
            step = self._step_text(frame)
            self.text.SetInput(f"t = {frame.t:5.2f} s   {frame.integrator}, {step}")

    def _step_text(self, frame: Snapshot) -> str:
        """The step for the overlay: ``dt``, or for an adaptive run the mean
        step since the last frame and how many it took (its last step alone
        is often one shortened to land on the frame)."""
        if not frame.adaptive:
            return f"dt = {frame.dt:.3g} s"
        then, self._clock = self._clock, (frame.t, frame.steps)
        if then is None or frame.steps <= then[1]:
            return f"dt = {frame.dt:.3g} s (adaptive)"
        steps = frame.steps - then[1]
        return f"dt = {(frame.t - then[0]) / steps:.3g} s (adaptive, mean of {steps})"
