"""Pictures, not just files: frame counts and sizes, moving frames, cloth
pixels where the camera projects the cloth, and safe interrupted movies."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

import pvcloth
from conftest import SCENES, small_scene
from pvcloth import Simulation

pytestmark = pytest.mark.usefixtures("rendering")


def cloth_pixels(image: np.ndarray) -> np.ndarray:
    """Mask of the cloth's red-brown against the grey-blue background."""
    r, g, b = (image[..., c].astype(int) for c in range(3))
    return (r - g > 25) & (r - b > 15)


def test_grid_point_k_is_solver_point_k():
    from pvcloth.visual.cloth_grid import cloth_grid

    sim = Simulation(small_scene(5).replace(cloth=pvcloth.ClothSpec(resolution=(5, 3))))
    grid = cloth_grid(sim.positions, sim.resolution)
    np.testing.assert_array_equal(grid.points, sim.positions)
    # structured (i, j) indexing agrees with the flat order i + nx * j
    assert grid.dimensions == (5, 3, 1)
    assert grid.x[3, 2, 0] == sim.positions[3 + 5 * 2, 0]
    assert grid.z[1, 2, 0] == sim.positions[1 + 5 * 2, 2]


def test_gif_has_the_frames_and_size_asked_and_the_cloth_moves(tmp_path):
    from pvcloth.visual.movie import render

    sim = Simulation.from_file(SCENES / "hanging.toml")
    out = tmp_path / "hanging.gif"
    stats = render(sim, out, frames=6, fps=10, size=(200, 150), progress=False)
    frames = iio.imread(out)
    assert frames.shape[:3] == (6, 150, 200)
    assert stats.frames == 6 and len(stats.physics) == 6
    assert sim.time == pytest.approx(0.5)
    differences = [np.abs(frames[n + 1].astype(int) - frames[n]).mean() for n in range(5)]
    assert min(differences) > 0.5  # every frame shows motion
    assert not list(tmp_path.glob(".*"))  # no hidden temporary left


def test_cloth_pixels_are_where_the_camera_projects_the_cloth(tmp_path):
    import pyvista as pv

    from pvcloth.visual.view import ClothView

    sim = Simulation.from_file(SCENES / "hanging.toml")
    sim.advance(0.3)
    plotter = pv.Plotter(off_screen=True, window_size=(320, 240))
    ClothView(sim, plotter, show_pins=False)
    plotter.show(auto_close=False)
    image = plotter.screenshot(return_img=True)
    renderer = plotter.renderer
    mask = cloth_pixels(image)
    nx, ny = sim.resolution
    hits = 0
    for i, j in [(nx // 2, ny // 2), (nx // 4, ny // 3), (3 * nx // 4, 2 * ny // 3)]:
        renderer.SetWorldPoint(*sim.positions[i + nx * j], 1.0)
        renderer.WorldToDisplay()
        px, py, _ = renderer.GetDisplayPoint()
        row, col = 240 - 1 - round(py), round(px)
        hits += mask[row - 1 : row + 2, col - 1 : col + 2].any()
    plotter.close()
    assert hits == 3
    # and the cloth is a modest part of the picture, not all of it
    assert 0.02 < mask.mean() < 0.6


def test_png_and_mp4(tmp_path):
    from pvcloth.visual.movie import render

    for name in ("last.png", "clip.mp4"):
        sim = Simulation(small_scene(8, damping=0.1, dt=5e-4))
        render(sim, tmp_path / name, frames=4, fps=20, size=(160, 120), progress=False)
    assert iio.imread(tmp_path / "last.png").shape == (120, 160, 3)
    assert len(iio.imread(tmp_path / "clip.mp4")) == 4


def test_divergence_mid_movie_keeps_a_valid_shorter_gif(tmp_path):
    from pvcloth.visual.movie import MovieInterrupted, render

    # dt far above the stable step: the first frame draws, then it blows up
    sim = Simulation(small_scene(8, stiffness=2000.0), dt=2e-3, stability="ignore")
    out = tmp_path / "broken.gif"
    with pytest.raises(MovieInterrupted) as caught:
        render(sim, out, frames=50, fps=30, size=(120, 90), progress=False)
    assert caught.value.path == out and caught.value.frames >= 1
    assert "kept a valid GIF" in str(caught.value)
    assert len(iio.imread(out)) == caught.value.frames
    assert not list(tmp_path.glob(".*"))  # no hidden temporary left


def test_interruption_before_any_frame_leaves_no_file(tmp_path, monkeypatch):
    from pvcloth.visual import view
    from pvcloth.visual.movie import MovieInterrupted, render

    def interrupt(self):
        raise KeyboardInterrupt

    monkeypatch.setattr(view.ClothView, "update", interrupt)
    out = tmp_path / "none.gif"
    with pytest.raises(MovieInterrupted, match="no file written"):
        render(Simulation(small_scene(4)), out, frames=5, progress=False)
    assert list(tmp_path.iterdir()) == []


REFERENCE = "tests/reference/hanging_16_t0.4.png"


def reference_frame(tmp_path) -> np.ndarray:
    """The hanging scene at 16x16 after 0.4 s, 200x150 pixels."""
    from pvcloth.visual.movie import render

    scene = pvcloth.load_scene(SCENES / "hanging.toml")
    cloth = pvcloth.ClothSpec(
        resolution=(16, 16), mass=0.2, orientation="horizontal", center=(0, 0, 1.5)
    )
    sim = Simulation(scene.replace(cloth=cloth), dt=5e-4)
    sim.advance(0.4)
    render(sim, tmp_path / "ref.png", frames=1, size=(200, 150), progress=False)
    return iio.imread(tmp_path / "ref.png")


def test_image_matches_stored_reference(tmp_path):
    """Catches a broken camera, lighting or shading. To accept a deliberate
    change of look: PVCLOTH_UPDATE_REFERENCE=1 python -m pytest -k reference."""
    import os

    from conftest import ROOT

    image = reference_frame(tmp_path)
    path = ROOT / REFERENCE
    if os.environ.get("PVCLOTH_UPDATE_REFERENCE"):
        iio.imwrite(path, image)
    expected = iio.imread(path)
    assert image.shape == expected.shape
    difference = np.abs(image.astype(int) - expected.astype(int)).max(axis=-1)
    # software GL differs by a few levels between builds; shape changes by many
    assert difference.mean() < 1.0
    assert (difference > 40).mean() < 0.005


@pytest.mark.parametrize("name", ["drape_sphere", "drape_cube", "ground", "flag"])
def test_environment_scenes_render_with_their_obstacles(name, tmp_path):
    """Each wind or obstacle scene renders a GIF in which the obstacles show:
    blue-grey solid pixels for a sphere or box, beige pixels for the ground."""
    from pvcloth.visual.movie import render

    sim = Simulation.from_file(SCENES / f"{name}.toml")
    out = tmp_path / f"{name}.gif"
    render(sim, out, frames=3, fps=30, size=(200, 150), progress=False)
    frames = iio.imread(out)
    assert frames.shape[:3] == (3, 150, 200)
    r, g, b = (frames[0][..., c].astype(int) for c in range(3))
    # Blue-grey and darker than the sky gradient (whose blue is above 200).
    solid = ((b - r > 15) & (b < 170)).mean()
    floor = ((r - b > 10) & (np.abs(r - g) < 12)).mean()
    kinds = {o.name for o in sim.model.obstacles}
    assert (solid > 0.01) == bool(kinds & {"sphere", "box"})
    assert (floor > 0.05) == ("ground" in kinds)
    assert cloth_pixels(frames[-1]).mean() > 0.005


def gif_delays_in_file(path) -> list[int]:
    """Every frame's delay in centiseconds, read from the GIF's bytes: the
    Graphic Control Extension blocks (0x21 0xF9 0x04, flags, delay as a
    little-endian 16-bit number), found by walking the file's blocks."""
    data = path.read_bytes()
    assert data[:6] in (b"GIF87a", b"GIF89a")
    flags = data[10]
    at = 13 + (3 * 2 ** ((flags & 7) + 1) if flags & 0x80 else 0)  # global colour table
    delays = []
    while data[at] != 0x3B:  # trailer
        if data[at] == 0x21:  # extension: label, then sub-blocks
            if data[at + 1] == 0xF9:
                delays.append(int.from_bytes(data[at + 4 : at + 6], "little"))
            at += 2
            while data[at]:
                at += data[at] + 1
            at += 1
        else:  # image descriptor, optional local colour table, LZW sub-blocks
            local = data[at + 9]
            at += 10 + (3 * 2 ** ((local & 7) + 1) if local & 0x80 else 0) + 1
            while data[at]:
                at += data[at] + 1
            at += 1
    return delays


def test_gif_frame_delays_add_up_to_the_movie_length(tmp_path):
    from pvcloth.visual.movie import render

    sim = Simulation.from_file(SCENES / "hanging.toml")
    out = tmp_path / "timed.gif"
    render(sim, out, frames=9, fps=30, size=(120, 90), progress=False)
    delays = gif_delays_in_file(out)
    assert len(delays) == 9 and set(delays) == {3, 4}  # a constant 3 cs would be 11 % fast
    assert sum(delays) == 30  # 9 frames at 30 fps: 0.3 s
    assert len(iio.imread(out)) == 9


def test_gif_refuses_a_frame_rate_it_cannot_show(tmp_path):
    from pvcloth import InputError
    from pvcloth.visual.movie import render

    with pytest.raises(InputError, match=r"fps.*at most 50"):
        render(Simulation(small_scene(4)), tmp_path / "fast.gif", frames=3, fps=60, progress=False)
    assert list(tmp_path.iterdir()) == []


def mp4_boxes(path) -> list[str]:
    """The top-level box types of an MP4, in file order."""
    data, at, boxes = path.read_bytes(), 0, []
    while at < len(data):
        size = int.from_bytes(data[at : at + 4], "big")
        boxes.append(data[at + 4 : at + 8].decode("latin-1"))
        if size == 1:  # 64-bit size follows
            size = int.from_bytes(data[at + 8 : at + 16], "big")
        at += size
    return boxes


def test_mp4_of_an_odd_size_is_padded_not_stretched_and_starts_fast(tmp_path):
    import subprocess

    import imageio_ffmpeg

    from pvcloth.visual.movie import render

    sim = Simulation(small_scene(8, damping=0.1, dt=5e-4))
    out = tmp_path / "odd.mp4"
    stats = render(sim, out, frames=3, fps=20, size=(161, 121), progress=False)
    assert stats.notes == ["MP4 frames padded from 161x121 to 162x122 (H.264 needs even sides)"]
    probe = subprocess.run(
        [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(out)],
        capture_output=True,
        text=True,
    ).stderr
    assert "162x122" in probe and "h264" in probe
    boxes = mp4_boxes(out)
    assert boxes.index("moov") < boxes.index("mdat")  # fast start: index first
    # Padded with the edge pixels: the added column repeats the last one
    # (a stretch would have resampled every column).
    frame = iio.imread(out)[0].astype(int)
    assert frame.shape == (122, 162, 3)
    assert np.abs(frame[:, -1] - frame[:, -2]).mean() < 3
