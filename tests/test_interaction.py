"""The interactive window, driven with no person: synthetic VTK mouse and key
events on a real interactor with our drag style."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import SCENES
from pvcloth import Simulation

pytestmark = [
    pytest.mark.usefixtures("rendering"),
    pytest.mark.filterwarnings("error"),
]  # callback errors surface as warnings


@pytest.fixture
def app():
    from pvcloth.app import ClothApp

    sim = Simulation.from_file(SCENES / "hanging.toml")
    sim.advance(0.6)  # let it fall so it faces the camera
    # PVCLOTH_REAL_WINDOW=1 (set by the Xvfb test below) opens a real X window
    real = os.environ.get("PVCLOTH_REAL_WINDOW") == "1"
    application = ClothApp(sim, off_screen=not real, window_size=(480, 360))
    # a real window's show() would block in its event loop; this returns
    application.plotter.show(auto_close=False, interactive_update=real)
    yield application
    application.plotter.close()


def screen_of(app, k):
    from pvcloth.interaction import world_to_display

    return world_to_display(app.plotter.renderer, app.sim.positions[k : k + 1])[0]


def press_key(app, key):
    interactor = app.plotter.iren.interactor
    interactor.SetKeySym(key)
    interactor.SetKeyCode(key if len(key) == 1 else " ")
    interactor.KeyPressEvent()


def test_projection_matches_vtk(app):
    renderer = app.plotter.renderer
    k = 300
    renderer.SetWorldPoint(*app.sim.positions[k], 1.0)
    renderer.WorldToDisplay()
    np.testing.assert_allclose(screen_of(app, k), renderer.GetDisplayPoint(), atol=1e-6)


def test_drag_moves_the_point_and_its_neighbours_not_the_camera(app):
    from pvcloth.interaction import display_to_world

    nx, _ = app.sim.shape
    k = 16 + nx * 8  # a free point in the lower half
    x, y, depth = screen_of(app, k)
    camera = app.plotter.camera_position
    neighbour = k + 1
    before = app.sim.positions[[k, neighbour]].copy()
    iren = app.plotter.iren
    iren._mouse_left_button_press(int(round(x)), int(round(y)))
    assert app.style.grabbed is not None
    grabbed = app.style.grabbed
    assert np.linalg.norm(screen_of(app, grabbed)[:2] - [x, y]) <= 12
    target_px = (int(round(x)) + 60, int(round(y)) + 40)
    for step in range(1, 11):  # move in small steps, simulating frames between
        iren._mouse_move(int(round(x)) + 6 * step, int(round(y)) + 4 * step)
        app.frame()
    expected = display_to_world(app.plotter.renderer, *target_px, screen_of(app, grabbed)[2])
    for _ in range(5):
        app.frame()
    np.testing.assert_allclose(app.sim.positions[grabbed], expected, atol=1e-9)
    iren._mouse_left_button_release(*target_px)
    assert app.plotter.camera_position == camera
    moved = np.linalg.norm(app.sim.positions[[grabbed, neighbour]] - before, axis=1)
    assert moved[0] > 0.05 and moved[1] > 0.01  # the neighbour followed
    assert not app.sim.control.pinned[grabbed]  # released: free again


def test_shift_release_leaves_the_point_pinned_and_u_unpins(app):
    nx, _ = app.sim.shape
    k = 10 + nx * 10
    x, y, _ = screen_of(app, k)
    iren = app.plotter.iren
    iren._mouse_left_button_press(int(round(x)), int(round(y)))
    grabbed = app.style.grabbed
    iren._mouse_move(int(round(x)) + 20, int(round(y)))
    iren._shift_key_press()
    iren._mouse_left_button_release()
    iren._shift_key_release()
    assert app.sim.control.pinned[grabbed]
    press_key(app, "u")
    assert not app.sim.control.pinned[grabbed]
    assert app.sim.control.pinned.sum() == 2


def test_press_on_empty_space_grabs_nothing_and_rotates(app):
    camera = app.plotter.camera_position
    iren = app.plotter.iren
    iren._mouse_left_button_press(5, 5)  # a corner of the window, far from the cloth
    assert app.style.grabbed is None
    iren._mouse_move(60, 40)
    iren._mouse_left_button_release(60, 40)
    assert app.sim.control.pinned.sum() == 2
    assert app.plotter.camera_position != camera  # the usual trackball rotation


def test_keys_pause_step_reset_and_cycle(app):
    press_key(app, "space")
    assert app.paused
    t = app.sim.time
    app.frame()
    assert app.sim.time == t  # paused: no physics
    press_key(app, "n")
    assert app.sim.time == pytest.approx(t + 1 / 30, abs=app.sim.dt)  # whole substeps
    first = app.sim.integrator.name
    press_key(app, "i")
    assert app.sim.integrator.name != first
    press_key(app, "b")
    assert app.sim.time == 0.0


def test_slow_physics_slows_the_animation_instead_of_spiralling(app):
    app.physics_share = app.budget = 1e-6  # physics can never keep up
    for _ in range(6):
        app.frame()
    assert app.speed < 0.1
    assert "SLOW MOTION" in app.status.GetText(2)


def test_stiffness_slider_scales_springs(app):
    k0 = app.sim.model.springs[0].groups[0].stiffness.max()
    app._set_stiffness(4.0)
    assert app.sim.model.springs[0].groups[0].stiffness.max() == pytest.approx(4 * k0)
    assert app.sim.dt <= app.sim.stable_dt()


@pytest.mark.skipif(os.environ.get("PVCLOTH_REAL_WINDOW") == "1", reason="already inside")
def test_the_same_checks_in_a_real_window_under_xvfb():
    """Re-run this file with a real interactive window on a virtual X screen."""
    if shutil.which("xvfb-run") is None:
        if os.environ.get("CI"):
            pytest.fail("xvfb-run missing: .ci/run installs xvfb xauth")
        pytest.skip("xvfb-run not installed (apt-get install xvfb xauth)")
    env = dict(os.environ, PVCLOTH_REAL_WINDOW="1")
    env.pop("VTK_DEFAULT_OPENGL_WINDOW", None)  # an X window this time
    result = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 1280x1024x24",
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:randomly",
            __file__,
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert "9 passed" in result.stdout


def test_w_toggles_wind_and_the_slider_sets_its_speed(app):
    def wind_terms():
        return [t for t in app.sim.model.forces if t.name == "wind"]

    assert not wind_terms()  # the hanging scene has no wind
    press_key(app, "w")
    (wind,) = wind_terms()
    assert np.linalg.norm(wind.velocity) == pytest.approx(6.0)
    app._set_wind_speed(12.5)
    (wind,) = wind_terms()
    assert np.linalg.norm(wind.velocity) == pytest.approx(12.5)
    t = app.sim.time
    app.frame()
    assert app.sim.time > t and "wind 12.5 m/s" in app.status.GetText(2)
    press_key(app, "w")
    assert not wind_terms() and app.sim.scene.wind is None


def test_a_diverging_run_pauses_with_a_message_instead_of_crashing(app):
    app.sim.dt = 0.05  # far above the stable step
    for _ in range(40):
        app.frame()
        if app.paused:
            break
    assert app.paused and "DIVERGED" in app.status.GetText(2)
    assert np.isfinite(app.sim.positions).all()
    press_key(app, "b")
    assert app.sim.time == 0.0 and "DIVERGED" not in app.status.GetText(2)
