"""What the pictures show: fields with the right values and colours, a
camera that frames the cloth, readable surfaces, panels side by side.

Each picture check reads pixels of an off-screen render and compares them
with something computed here independently (a projection of the cloth's
points, a colour map sampled by matplotlib, a continuum formula)."""

from __future__ import annotations

import subprocess
import sys

import imageio.v3 as iio
import matplotlib
import numpy as np
import pytest

import pvcloth
from conftest import SCENES
from pvcloth import Simulation
from pvcloth.physics.fields import point_areas, spring_fields

pytestmark = pytest.mark.usefixtures("rendering")


def structural_sheet(n=9, size=(1.0, 0.5), stiffness=300.0) -> Simulation:
    """A flat sheet with structural springs only, no pins (for hand formulas)."""
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(resolution=(n, n), size=size, orientation="horizontal"),
        springs=pvcloth.SpringsSpec(
            structural=pvcloth.SpringSpec(stiffness, 0.0), shear=None, bending=None
        ),
        pins=pvcloth.PinSpec(corners=()),
    )
    return Simulation(scene)


# -- fields -------------------------------------------------------------------


def test_energy_density_of_a_uniform_stretch_is_the_continuum_one():
    # Stretched by a strain e along x, a sheet of stretch modulus S (N/m)
    # stores S e^2 / 2 per square metre; inside, every point shows that.
    sim = structural_sheet()
    e, modulus = 0.02, 300.0
    x = sim.model.rest_positions.copy()
    x[:, 0] *= 1.0 + e
    fields = spring_fields(sim.model, x)
    n = 9
    inner = np.zeros((n, n), dtype=bool)
    inner[1:-1, 1:-1] = True
    np.testing.assert_allclose(fields["energy"][inner.ravel()], 0.5 * modulus * e**2, rtol=1e-9)
    # and over the whole sheet, borders included, it adds up to the springs'
    table = sim.model.spring_table()
    d = x[table.b] - x[table.a]
    total = 0.5 * np.sum(table.stiffness * (np.linalg.norm(d, axis=1) - table.rest) ** 2)
    assert np.sum(fields["energy"] * point_areas(sim.model)) == pytest.approx(total, rel=1e-12)


def test_force_is_the_mean_spring_force_at_the_point():
    # Uniaxial strain e: the two x springs at an inner point each pull with
    # k * e * hx = S hy e, the two y springs with nothing: mean S hy e / 2.
    sim = structural_sheet()
    e, modulus, hy = 0.02, 300.0, 0.5 / 8
    x = sim.model.rest_positions.copy()
    x[:, 0] *= 1.0 + e
    force = spring_fields(sim.model, x)["force"].reshape(9, 9)
    np.testing.assert_allclose(force[1:-1, 1:-1], modulus * hy * e / 2, rtol=1e-9)


def test_mesh_carries_every_field_with_its_unit_for_exports():
    sim = Simulation.from_file(SCENES / "hanging.toml")
    sim.advance(0.2)
    mesh = sim.mesh
    for name in ("speed", "stretch", "force", "energy"):
        assert mesh.point_data[name].shape == (mesh.n_points,)
        assert np.isfinite(mesh.point_data[name]).all()
    assert mesh.point_data["energy"].max() > 0


# -- colours --------------------------------------------------------------------


def project(plotter, points) -> np.ndarray:
    """Pixel (row, column) of world points, by VTK's own projection."""
    renderer, height = plotter.renderer, plotter.window_size[1]
    pixels = []
    for point in points:
        renderer.SetWorldPoint(*point, 1.0)
        renderer.WorldToDisplay()
        x, y, _ = renderer.GetDisplayPoint()
        pixels.append((height - 1 - round(y), round(x)))
    return np.array(pixels)


def test_a_point_shows_the_colour_of_its_field_value():
    """A flat sheet seen from above, stretched more and more along x: the
    pixel over each sampled point has the colour map's hue at that point's
    stretch (fixed range), so the colour follows the field."""
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    sim = structural_sheet(n=17, size=(1.0, 1.0))
    rest = sim.model.rest_positions
    x = rest.copy()
    u = rest[:, 0] - rest[:, 0].min()
    # x edges grow from 1 to 1.06 times their length; a point's stretch is
    # the mean over its x and y edges, so it grows from 1 to about 1.03
    x[:, 0] = rest[:, 0].min() + u + 0.03 * u**2
    sim.set_state(positions=x)
    plotter = pv.Plotter(off_screen=True, window_size=(400, 400))
    clim = (0.97, 1.03)
    view = ClothView(sim, plotter, color="stretch", clim=clim, camera="none", show_pins=False)
    centre = x.mean(axis=0)
    # from 45 degrees above: lit well short of saturation
    plotter.camera.position, plotter.camera.focal_point = centre + (0, -2.2, 2.2), centre
    plotter.camera.up = (0, 1, 1)
    plotter.renderer.ResetCameraClippingRange()
    plotter.renderer.SetUseFXAA(False)
    plotter.show(auto_close=False)
    image = plotter.screenshot(return_img=True).astype(float)
    stretch = view.surface.point_data["stretch"]
    cmap = matplotlib.colormaps["coolwarm"]
    inner = [i + 17 * 8 for i in range(2, 15, 3)]  # along the middle row
    for k, (row, col) in zip(inner, project(plotter, x[inner]), strict=True):
        seen = image[row - 1 : row + 2, col - 1 : col + 2, :3].reshape(-1, 3).mean(axis=0)
        expected = 255 * np.array(cmap((stretch[k] - clim[0]) / (clim[1] - clim[0]))[:3])
        # Light scales the colour (ambient, diffuse) and adds white (the
        # highlight): seen = a * expected + b, fitted; a wrong colour leaves
        # a large residual.
        basis = np.column_stack([expected, np.ones(3)])
        (a, b), *_ = np.linalg.lstsq(basis, seen, rcond=None)
        residual = np.abs(basis @ (a, b) - seen).max()
        assert a > 0.5 and residual < 4.0, (k, a, b, residual)
    assert stretch[inner].min() < 1.005 and stretch[inner].max() > 1.025  # across the map
    bars = list(plotter.scalar_bars.keys())
    plotter.close()
    assert bars == ["stretch\n(length / rest length)"]  # the unit under the name


def test_a_hanging_cloth_is_most_stretched_at_its_pins():
    sim = Simulation.from_file(SCENES / "hanging.toml")
    sim.advance(1.0)
    hottest = int(np.argmax(sim.mesh.point_data["stretch"]))
    pins = sim.positions[sim.pinned_indices]
    distance = np.linalg.norm(pins - sim.positions[hottest], axis=1).min()
    assert distance < 0.15 * max(sim.scene.cloth.size)


def test_front_and_back_of_the_cloth_look_different():
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    colours = []
    for side in (-1.0, 1.0):
        sim = Simulation(pvcloth.Scene())  # a vertical sheet in the x-z plane
        plotter = pv.Plotter(off_screen=True, window_size=(200, 200))
        ClothView(sim, plotter, camera="none", show_pins=False)
        centre = sim.positions.mean(axis=0)
        plotter.camera.position = centre + (0.0, side * 3.0, 0.0)
        plotter.camera.focal_point = centre
        plotter.camera.up = (0, 0, 1)
        plotter.renderer.ResetCameraClippingRange()
        plotter.show(auto_close=False)
        image = plotter.screenshot(return_img=True).astype(float)
        colours.append(image[90:110, 90:110, :3].reshape(-1, 3).mean(axis=0))
        plotter.close()
    front, back = (c / c.sum() for c in colours)
    assert np.abs(front - back).max() > 0.1  # a different hue, not a shade


def test_a_vertical_sheet_facing_the_default_camera_keeps_its_colour():
    # VTK's default light kit drew it at half its colour from this camera.
    import pyvista as pv

    from pvcloth.visual.colors import CLOTH_COLOR
    from pvcloth.visual.view import ClothView

    sim = Simulation(pvcloth.Scene())  # vertical, in the x-z plane
    plotter = pv.Plotter(off_screen=True, window_size=(240, 180))
    view = ClothView(sim, plotter, show_pins=False)
    plotter.show(auto_close=False)
    image = plotter.screenshot(return_img=True).astype(float)
    centre = project(plotter, [view.surface.center])[0]
    seen = image[centre[0] - 3 : centre[0] + 4, centre[1] - 3 : centre[1] + 4, :3]
    plotter.close()
    base = 255 * np.array(pv.Color(CLOTH_COLOR).float_rgb)
    assert 0.75 < seen.reshape(-1, 3).mean(axis=0)[0] / base[0] < 1.15


def test_the_ground_reads_as_a_floor_with_a_checker():
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    sim = Simulation.from_file(SCENES / "ground.toml")
    plotter = pv.Plotter(off_screen=True, window_size=(320, 240))
    ClothView(sim, plotter, show_pins=False)
    plotter.show(auto_close=False)
    image = plotter.screenshot(return_img=True).astype(int)
    plotter.close()
    bottom = image[-60:, :, :3].reshape(-1, 3)
    grey = bottom[(np.abs(bottom[:, 0] - bottom[:, 2]) < 40) & (bottom.sum(axis=1) > 300)]
    brightness = grey.sum(axis=1)
    # two tones, both light: a floor, not a dark slab
    assert np.percentile(brightness, 90) - np.percentile(brightness, 10) > 25
    assert np.median(brightness) > 450


def test_a_new_obstacle_shape_draws_its_own_surface_or_says_it_has_none():
    import pyvista as pv

    from pvcloth.physics.obstacles import Sphere
    from pvcloth.visual.scenery import obstacle_surface

    class Blob(Sphere):
        pass

    class Shapeless(Sphere):
        def surface(self, extent):
            return super(Sphere, self).surface(extent)  # the base class's: none

    common = dict(center=(0, 0, 0), thickness=0.0, friction=0.0, static_friction=0.0)
    mesh = obstacle_surface(Blob(0.5, **common), 1.0)
    assert isinstance(mesh, pv.PolyData) and mesh.n_cells > 100
    assert mesh.volume == pytest.approx(4 / 3 * np.pi * 0.125, rel=0.01)
    with pytest.raises(NotImplementedError, match="Shapeless has no surface"):
        obstacle_surface(Shapeless(0.5, **common), 1.0)


# -- camera ---------------------------------------------------------------------


def frame_by_frame(sim, frames, size, **view_options):
    """Per frame: the cloth's pixel box share, whether it left the frame,
    the share it is seen over (:func:`silhouette_share`); and the camera
    positions, its own and a camera refitted to every frame (a movie's
    loop, measured)."""
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    width, height = size
    plotter = pv.Plotter(off_screen=True, window_size=size)
    view = ClothView(sim, plotter, **view_options)
    plotter.show(auto_close=False)
    nx, ny = sim.resolution
    border = np.unique(
        np.r_[
            np.arange(nx),
            np.arange(nx * (ny - 1), nx * ny),
            np.arange(0, nx * ny, nx),
            np.arange(nx - 1, nx * ny, nx),
            np.arange(0, nx * ny, 7),
        ]
    )
    from pvcloth.visual.camera import VIEWS, FramingCamera

    # The same fit with no smoothing: what a camera refitted to every frame does.
    raw = FramingCamera(*VIEWS[sim.scene.camera.view], aspect=width / height, follow=1.0)
    shares, outside, cameras, raw_cameras = [], [], [], []
    seen = []
    for _ in sim.frames(frames, 30.0):
        view.update()
        raw_cameras.append(raw.frame(sim.positions)[0])
        plotter.render()
        pixels = project(plotter, sim.positions[border])
        span = pixels.max(axis=0) - pixels.min(axis=0)
        shares.append(span.max() / min(width, height))
        outside.append(bool(((pixels < 0) | (pixels >= [height, width])).any()))
        cameras.append(np.array(plotter.camera.position))
        seen.append(silhouette_share(plotter, sim.positions, sim.model.shape))
    plotter.close()
    return np.array(shares), outside, np.array(seen), np.array(cameras), np.array(raw_cameras)


def project_all(plotter, points) -> np.ndarray:
    """Pixel (column, row from the top) of world points, through the
    camera's composite projection (its window centre included), in NumPy."""
    renderer = plotter.renderer
    width, height = plotter.window_size
    matrix = renderer.GetActiveCamera().GetCompositeProjectionTransformMatrix(
        renderer.GetTiledAspectRatio(), -1.0, 1.0
    )
    m = np.array([[matrix.GetElement(i, j) for j in range(4)] for i in range(4)])
    clip = np.c_[points, np.ones(len(points))] @ m.T
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * width, height - 1 - (ndc[:, 1] + 1) / 2 * height]


def silhouette_share(plotter, points, shape) -> float:
    """How much of the frame the cloth is seen over: its triangles filled
    in at their projected pixels, then thinned by two pixels on every side
    (a cloth seen edge-on, a line, vanishes), as the larger of the pixel
    box's sides over the frame's smaller side."""
    from PIL import Image, ImageDraw
    from scipy.ndimage import binary_erosion

    from pvcloth.physics.topology import triangles

    width, height = plotter.window_size
    pixels = project_all(plotter, points)
    image = Image.new("1", (width, height), 0)
    draw = ImageDraw.Draw(image)
    for triangle in pixels[triangles(shape)]:
        draw.polygon([tuple(p) for p in triangle], fill=1)
    mask = binary_erosion(np.array(image), iterations=2)
    rows, columns = np.nonzero(mask)
    if rows.size == 0:
        return 0.0
    return max(np.ptp(rows), np.ptp(columns)) / min(width, height)


@pytest.mark.parametrize(
    "path",
    [  # the hanging cloth in the quick tier, every other scene in validation
        p if p.stem == "hanging" else pytest.param(p, marks=pytest.mark.validation)
        for p in sorted(SCENES.glob("*.toml"))
    ],
    ids=lambda p: p.stem,
)
def test_the_camera_keeps_every_bundled_scene_framed(path):
    """The cloth's box spans at least half the frame's smaller side in every
    frame from the first, and so does what is seen of it (its projected
    triangles, thinned by two pixels: a cloth seen edge-on counts for
    nothing), and it never leaves the frame; and the camera glides: it accelerates
    less than one refitted to every frame (measured as the RMS second
    difference of its position: 1.2 to 4.9 times less on these scenes) and
    never jumps by more than a seventh of its distance in a frame."""
    sim = Simulation.from_file(path)
    shares, outside, seen, cameras, raw = frame_by_frame(sim, 45, (320, 240))
    assert shares.min() >= 0.5, f"smallest share {shares.min():.2f}"
    assert seen.min() >= 0.5, f"seen over {seen.min():.2f} at frame {seen.argmin()}"
    assert not any(outside)

    def jerk(path):
        return np.sqrt(np.mean(np.sum(np.diff(path, n=2, axis=0) ** 2, axis=1)))

    assert jerk(cameras) < jerk(raw)
    distance = np.linalg.norm(cameras - sim.positions.mean(axis=0), axis=1).mean()
    assert np.linalg.norm(np.diff(cameras, axis=0), axis=1).max() < distance / 7


@pytest.mark.parametrize("camera", ["scene", "fixed"])
def test_the_scalar_bar_stands_clear_of_the_cloth_and_the_label(camera):
    """Coloured by a field, the cloth is framed left of the strip on the
    right where the scalar bar stands: in every frame of the flag coloured
    by speed (a following camera, and a fixed one), every cloth point
    projects left of the bar's box, and the label's box does not meet it."""
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    sim = Simulation.from_file(SCENES / "flag.toml")
    plotter = pv.Plotter(off_screen=True, window_size=(320, 240))
    view = ClothView(sim, plotter, color="speed", label=True, camera=camera)
    plotter.show(auto_close=False)
    renderer = plotter.renderer
    (bar,) = plotter.scalar_bars.values()
    height = plotter.window_size[1]
    for _ in sim.frames(30, 30.0):
        view.update()
        plotter.render()
        left, bottom = bar.GetPositionCoordinate().GetComputedDisplayValue(renderer)
        right, top = bar.GetPosition2Coordinate().GetComputedDisplayValue(renderer)
        assert 0 < left < right <= plotter.window_size[0] and 0 <= bottom < top <= height
        columns = project_all(plotter, sim.positions)[:, 0]
        assert columns.max() < left, f"cloth at column {columns.max():.0f}, bar from {left}"
        box = [0.0] * 4  # the label: x from, x to, y from, y to (pixels from the bottom)
        view.text.GetBoundingBox(renderer, box)
        apart = box[1] < left or box[0] > right or box[3] < bottom or box[2] > top
        assert apart, (box, (left, right, bottom, top))
    plotter.close()


def test_view_presets_and_an_explicit_camera():
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    scene = pvcloth.load_scene(SCENES / "hanging.toml")
    for view_name, axis in (("side", 0), ("front", 1), ("top", 2)):
        sim = Simulation(scene.with_overrides({"camera.view": view_name}))
        plotter = pv.Plotter(off_screen=True, window_size=(160, 120))
        ClothView(sim, plotter)
        direction = np.array(plotter.camera.position) - np.array(plotter.camera.focal_point)
        plotter.close()
        assert np.argmax(np.abs(direction)) == axis
    explicit = scene.with_overrides(
        {"camera.position": [2.0, -3.0, 1.0], "camera.focal_point": [0.0, 0.0, 0.5]}
    )
    sim = Simulation(explicit)
    plotter = pv.Plotter(off_screen=True, window_size=(160, 120))
    view = ClothView(sim, plotter)
    sim.advance(0.2)
    view.update()  # an explicit camera does not follow
    assert plotter.camera.position == pytest.approx((2.0, -3.0, 1.0))
    assert plotter.camera.focal_point == pytest.approx((0.0, 0.0, 0.5))
    plotter.close()


# -- commands -----------------------------------------------------------------------


def run_pvcloth(*arguments, cwd):
    return subprocess.run(
        [sys.executable, "-m", "pvcloth", *arguments],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["--color", "heat"], "color: 'heat' is not a field; choose one of stretch, speed"),
        (["--cmap", "Viridis"], "cmap: 'Viridis' is not a colour map (did you mean 'viridis'?)"),
        (["--clim", "1.01,0.99"], "clim: needs finite LOW < HIGH"),
        (["--clim", "low,high"], "clim: expected LOW,HIGH"),
    ],
)
def test_bad_colour_options_are_named(tmp_path, arguments, message):
    result = run_pvcloth(
        "render", str(SCENES / "hanging.toml"), "-o", "x.png", "--quiet", *arguments, cwd=tmp_path
    )
    assert result.returncode == 2
    assert message in result.stderr and "Traceback" not in result.stderr
    assert not list(tmp_path.iterdir())


def test_render_colours_by_a_field_from_the_command_line(tmp_path):
    result = run_pvcloth(
        "render",
        str(SCENES / "hanging.toml"),
        "-o",
        "speed.png",
        "--frames",
        "10",
        "--size",
        "240x180",
        "--color",
        "speed",
        "--view",
        "front",
        "--quiet",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    image = iio.imread(tmp_path / "speed.png")
    viridis = 255 * np.array(matplotlib.colormaps["viridis"](np.linspace(0, 1, 64))[:, :3])
    pixels = image[..., :3].reshape(-1, 1, 3).astype(float)
    near_map = (np.abs(pixels - viridis[None]).max(axis=2) < 40).any(axis=1)
    assert near_map.mean() > 0.05  # the cloth is drawn in the colour map


def test_compare_draws_one_labelled_panel_per_integrator(tmp_path):
    result = run_pvcloth(
        "compare",
        str(SCENES / "hanging.toml"),
        "--integrators",
        "symplectic_euler,fast_mass_spring,fast_bdf2+lbfgs",
        "--dts",
        "auto,1/60,1/60",
        "-o",
        "trade.gif",
        "--frames",
        "6",
        "--size",
        "600x200",
        "--quiet",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    frames = iio.imread(tmp_path / "trade.gif")
    assert frames.shape[:3] == (6, 200, 600)
    lines = result.stdout.splitlines()[1:]
    assert [line.split(",")[0].strip() for line in lines] == [
        "symplectic_euler",
        "fast_mass_spring",
        "fast_bdf2+lbfgs",  # an integrator with its solver.accelerator
    ]
    assert all("wall per simulated s" in line and "m RMS" in line for line in lines)
    # each third of the frame shows a cloth
    last = frames[-1][..., :3].astype(int)
    reddish = (last[..., 0] - last[..., 1] > 25) & (last[..., 0] - last[..., 2] > 15)
    for k in range(3):
        assert reddish[:, 200 * k : 200 * (k + 1)].mean() > 0.02


def test_compare_refuses_an_unknown_accelerator(tmp_path):
    result = run_pvcloth(
        "compare",
        str(SCENES / "hanging.toml"),
        "--integrators",
        "fast_bdf2,fast_bdf2+newton",
        "-o",
        "x.gif",
        cwd=tmp_path,
    )
    assert result.returncode == 2
    assert "solver.accelerator: 'newton' is not allowed" in result.stderr
    result = run_pvcloth(
        "compare",
        str(SCENES / "hanging.toml"),
        "--integrators",
        "rk4+lbfgs",
        "-o",
        "x.gif",
        cwd=tmp_path,
    )
    assert result.returncode == 2
    assert "'rk4+lbfgs': +ACCELERATOR (one of chebyshev, lbfgs) follows an integrator that" in (
        result.stderr
    )


def test_compare_refuses_a_mismatched_step_list(tmp_path):
    result = run_pvcloth(
        "compare",
        str(SCENES / "hanging.toml"),
        "--integrators",
        "symplectic_euler,rk4",
        "--dts",
        "1e-4,2e-4,3e-4",
        "-o",
        "x.gif",
        cwd=tmp_path,
    )
    assert result.returncode == 2
    assert "dts: give one step or one per integrator (2), got 3" in result.stderr


# -- reference pictures, one per feature ------------------------------------------


def feature_picture(name: str, tmp_path) -> np.ndarray:
    """A small picture of one feature, made through the public functions."""
    from pvcloth.visual.compare import compare
    from pvcloth.visual.movie import render

    out = tmp_path / f"{name}.png"
    small = pvcloth.ClothSpec(resolution=(16, 16), orientation="horizontal", center=(0, 0, 1.5))
    if name == "stretch_on_a_ball":
        scene = pvcloth.load_scene(SCENES / "drape_sphere.toml")
        scene = scene.replace(cloth=dataclasses_replace(scene.cloth, resolution=(16, 16)))
        render(
            Simulation(scene),
            out,
            frames=20,
            size=(200, 150),
            color="stretch",
            clim=(0.97, 1.03),
            progress=False,
        )
    elif name == "side_view":
        scene = pvcloth.load_scene(SCENES / "hanging.toml").replace(cloth=small)
        scene = scene.with_overrides({"camera.view": "side"})
        render(Simulation(scene, dt=5e-4), out, frames=10, size=(200, 150), progress=False)
    elif name == "compare_two_panels":
        scene = pvcloth.load_scene(SCENES / "hanging.toml").replace(cloth=small)
        compare(
            scene,
            out,
            ["symplectic_euler", "fast_mass_spring"],
            dts=[5e-4, 1 / 60],
            frames=8,
            size=(320, 160),
            progress=False,
        )
    return iio.imread(out)


def dataclasses_replace(obj, **changes):
    import dataclasses

    return dataclasses.replace(obj, **changes)


@pytest.mark.parametrize("name", ["stretch_on_a_ball", "side_view", "compare_two_panels"])
def test_feature_pictures_match_their_references(name, tmp_path):
    """Catches a broken colour map, back face, ground, camera or panel layout.
    To accept a deliberate change of look:
    PVCLOTH_UPDATE_REFERENCE=1 python -m pytest tests/test_view.py -k references."""
    import os

    from conftest import ROOT

    image = feature_picture(name, tmp_path)
    path = ROOT / "tests" / "reference" / f"{name}.png"
    if os.environ.get("PVCLOTH_UPDATE_REFERENCE"):
        iio.imwrite(path, image)
    expected = iio.imread(path)
    assert image.shape == expected.shape
    if name == "compare_two_panels":
        # The label band shows measured wall times, which differ run to run
        # (the command's test checks the labels): compare the cloth panels.
        band = image.shape[0] // 4
        image, expected = image[band:], expected[band:]
    difference = np.abs(image.astype(int) - expected.astype(int)).max(axis=-1)
    # software GL differs by a few levels between builds; a change of look by many
    assert difference.mean() < 1.5
    assert (difference > 40).mean() < 0.01


def test_the_overlay_says_an_adaptive_run_s_mean_step():
    """Its last step is often one cut short to land on the frame: the overlay
    gives the frame's mean step and how many there were."""
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    scene = pvcloth.load_scene(SCENES / "hanging.toml").with_resolution(8)
    sim = pvcloth.Simulation(
        scene.with_overrides({"solver.integrator": "rk23", "solver.tolerance": 1e-4})
    )
    plotter = pv.Plotter(off_screen=True, window_size=(320, 240))
    view = ClothView(sim, plotter, camera="none", label=True)
    steps, start = sim.steps, sim.time
    sim.advance(1 / 30)
    view.update()
    mean = (sim.time - start) / (sim.steps - steps)
    assert view.text.GetInput().endswith(
        f"rk23, dt = {mean:.3g} s (adaptive, mean of {sim.steps - steps})"
    )
    fixed = pvcloth.Simulation(scene)
    assert (
        ClothView(fixed, plotter, camera="none", label=True)
        .text.GetInput()
        .endswith(f"dt = {fixed.dt:.3g} s (as given)")
    )
    plotter.close()


@pytest.mark.usefixtures("rendering")
def test_sim_plot_draws_the_obstacles_and_ground_render_draws(tmp_path):
    ball = pvcloth.ObstacleSpec("sphere", center=(0.0, 0.0, 0.6), radius=0.25)
    floor = pvcloth.ObstacleSpec("ground")
    cloth = pvcloth.ClothSpec(resolution=(12, 12), orientation="horizontal", center=(0, 0, 1.0))
    scene = pvcloth.Scene(cloth=cloth, pins=pvcloth.PinSpec(corners=()))
    near = {}
    for name, obstacles in (("bare", ()), ("with", (ball, floor))):
        sim = Simulation(scene.replace(obstacles=obstacles))
        sim.advance(0.5)  # draped over the ball
        shot = tmp_path / f"{name}.png"
        sim.plot(off_screen=True, window_size=(320, 240), screenshot=str(shot))
        image = iio.imread(shot)[..., :3].astype(int)
        # pixels of the obstacles' blue-grey and of the ground's checker
        colours = [(0x8F, 0xA3, 0xB8), (0xDD, 0xD8, 0xCC), (0xC9, 0xC3, 0xB5)]
        near[name] = [int((np.abs(image - c).sum(axis=2) < 60).sum()) for c in colours]
    assert sum(near["with"]) > 10000 > 10 * sum(near["bare"]), near
