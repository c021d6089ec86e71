"""The view: the cloth and its scene drawn in a PyVista plotter.

Rendering reads the simulation; it never changes it. :class:`ClothView`
draws the cloth, its pins and the obstacles (:mod:`pvcloth.visual.scenery`),
with lights, a camera and a label. The cloth is the view's own ``PolyData``
of the simulation's points, with normals computed from the grid and only the
field it is coloured by, so a frame costs a copy and one field; drawing
``Simulation.mesh`` (:mod:`pvcloth.visual.cloth_grid`: every field) instead
would turn a StructuredGrid into a surface and recompute its normals by a
VTK pipeline on every change. :func:`plot_cloth` is ``Simulation.plot``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyvista as pv

from pvcloth.errors import InputError
from pvcloth.physics import topology
from pvcloth.physics.fields import point_fields
from pvcloth.physics.step_policy import STEP_SOURCES
from pvcloth.visual.camera import BAR_STRIP, VIEW_ANGLE, VIEWS, FramingCamera
from pvcloth.visual.colors import (
    BACK_COLOR,
    CLOTH_BACK_COLOR,
    CLOTH_COLOR,
    FIELD_TITLES,
    FIELDS,
    ColorRange,
    check_cmap,
    check_field,
)
from pvcloth.visual.framing import motion_bounds
from pvcloth.visual.gl import use_offscreen_gl_if_headless
from pvcloth.visual.scenery import add_obstacles, obstacle_matrix

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation
    from pvcloth.physics.state import Snapshot


#: ``pyvista.plot`` keywords that set up the plotter or its ``show()``; the
#: rest go to ``add_mesh``, as ``pyvista.plot`` passes them.
PLOTTER_KEYWORDS = ("off_screen", "window_size", "notebook", "theme")
SHOW_KEYWORDS = (
    "screenshot",
    "interactive",
    "return_img",
    "return_cpos",
    "return_viewer",
    "jupyter_backend",
    "jupyter_kwargs",
    "full_screen",
    "auto_close",
)


def plot_cloth(sim: Simulation, **kwargs):
    """``sim.mesh.plot(**kwargs)`` in the cloth's colours and smooth shading,
    unless ``scalars`` or ``color`` say otherwise, with the scene's obstacles
    and ground drawn as ``render`` draws them; a field of the mesh gets a
    scalar bar titled with its unit. ``pyvista.plot``'s keywords are taken
    (``off_screen``, ``window_size``, ``screenshot``, ``cpos``,
    ``background``, ``text``, ``show_axes``, ``zoom``; the others go to
    ``add_mesh``)."""
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
    if not sim.model.obstacles:
        return sim.mesh.plot(**kwargs)
    made = {key: kwargs.pop(key) for key in PLOTTER_KEYWORDS if key in kwargs}
    shown = {key: kwargs.pop(key) for key in SHOW_KEYWORDS if key in kwargs}
    cpos, zoom = kwargs.pop("cpos", None), kwargs.pop("zoom", None)
    background, text = kwargs.pop("background", None), kwargs.pop("text", "")
    show_axes = kwargs.pop("show_axes", None)
    plotter = pv.Plotter(**made)
    plotter.add_mesh(sim.mesh, **kwargs)
    add_obstacles(plotter, sim)
    if background is not None:
        plotter.set_background(background)
    if text:
        plotter.add_text(text)
    if show_axes or (show_axes is None and plotter.theme.axes.show):
        plotter.show_axes()
    # Framed on the cloth, as pyvista.plot would frame it alone: a ground
    # drawn four cloths wide must not shrink it to a speck.
    plotter.camera_position = plotter.get_default_cam_pos() if cpos is None else cpos
    plotter.reset_camera(bounds=sim.mesh.bounds)
    plotter.camera_set = True  # show() keeps this framing
    if zoom is not None:
        plotter.camera.zoom(zoom)
    return plotter.show(**shown)


class ClothView:
    """Draws a simulation's cloth, pins and obstacles in a PyVista plotter.

    Parameters
    ----------
    sim : Simulation
        The simulation to read from.
    plotter : pyvista.Plotter
        Where to draw.
    color : str, optional
        A field of :data:`~pvcloth.visual.colors.FIELDS` to colour the cloth
        by, with a scalar bar; ``None`` draws it in its front and back
        colours.
    clim : (float, float), optional
        Fixed colour range; by default it grows with the values seen
        (:class:`~pvcloth.visual.colors.ColorRange`).
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
        self.obstacle_actors = add_obstacles(plotter, sim)
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
            # Upright in the strip on the right that the camera keeps the
            # cloth out of (BAR_STRIP), above the label in the bottom corner.
            scalar_bar_args={
                "title": style.title.replace(" (", "\n("),  # the unit under the name
                "fmt": "%.4g",
                "vertical": True,
                # the box's left edge just right of the framed part; its
                # centre, where the title is centred, 0.11 from the right edge
                "position_x": 1.0 - BAR_STRIP + 0.005,
                "position_y": 0.15,
                "width": BAR_STRIP - 0.06,
                "height": 0.72,
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

    def _set_camera(self, mode: str) -> None:
        if mode == "none":
            return
        spec = self.sim.scene.camera
        camera = self.plotter.camera
        strip = BAR_STRIP if self.field is not None else 0.0  # the scalar bar's place
        camera.SetWindowCenter(strip, 0.0)
        camera.view_angle = VIEW_ANGLE  # a reset starts from VTK's angle again
        if spec.explicit:  # what it frames is squeezed into the part left of the bar
            camera.position, camera.focal_point = spec.position, spec.focal_point
            camera.up = spec.up
            camera.zoom(1.0 - strip)
            self.plotter.renderer.ResetCameraClippingRange()
            return
        direction, up = VIEWS[spec.view]
        if mode == "scene" and spec.follow:
            width, height = self.plotter.window_size
            self.framing = FramingCamera(direction, up, aspect=width / height, right_strip=strip)
            return
        self.plotter.view_vector(direction, viewup=up)
        self.plotter.reset_camera(bounds=motion_bounds(self.sim))
        camera.zoom(1.0 - strip)  # the same region in the narrower framed part

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
        """The step for the overlay and where it came from, in the word the
        summary and the window's status use (:data:`STEP_SOURCES`); for an
        adaptive run, the mean step since the last frame and how many it
        took (its last step alone is often one shortened to land on the frame)."""
        origin = STEP_SOURCES[frame.dt_source]
        if not frame.adaptive:
            return f"dt = {frame.dt:.3g} s ({origin})"
        then, self._clock = self._clock, (frame.t, frame.steps)
        if then is None or frame.steps <= then[1]:
            return f"dt = {frame.dt:.3g} s ({origin})"
        steps = frame.steps - then[1]
        return f"dt = {(frame.t - then[0]) / steps:.3g} s ({origin}, mean of {steps})"
