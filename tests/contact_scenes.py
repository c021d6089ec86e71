"""Scenes where a cloth meets itself, for the self-collision tests: each is
a scene and, where the scene alone cannot say it, a driver that moves pins
before every step (the way a script or the window's mouse does)."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np

from conftest import ROOT
from pvcloth import SelfCollisionSpec, Simulation, load_scene

SCENES = ROOT / "data" / "scenes"
# The towel is the gallery's (examples/03_self_collision/towel_helpers.py).
sys.path.insert(0, str(ROOT / "examples" / "03_self_collision"))
from towel_helpers import fold_a_towel  # noqa: E402


def _with_contact(scene, n: int, integrator: str, contact: bool):
    scene = scene.with_resolution(n).with_overrides(
        {"solver.integrator": integrator, "solver.dt": None}
    )
    return scene.replace(self_collision=SelfCollisionSpec() if contact else None)


def crumple(n: int, integrator: str, contact: bool = True):
    """The bundled crumple: a long cloth dropped edge-on from 0.3 m buckles
    and piles onto itself on the ground."""
    scene = load_scene(SCENES / "crumple.toml")
    return Simulation(_with_contact(scene, n, integrator, contact)), None


def sphere_drape(n: int, integrator: str, contact: bool = True):
    """A soft cloth (bending 0.2 N/m) dropped onto a ball 1 m above the
    floor, the ball narrow for the cloth (radius 0.25 m, cloth 1.6 m): the
    skirt hangs free and gathers into folds that press on each other."""
    scene = load_scene(SCENES / "drape_sphere.toml")
    ball, floor = scene.obstacles
    scene = scene.replace(
        obstacles=(dataclasses.replace(ball, center=(0.0, 0.0, 1.0), radius=0.25), floor)
    ).with_overrides(
        {"cloth.size": [1.6, 1.6], "cloth.center": [0.0, 0.0, 1.3], "springs.bending": 0.2}
    )
    return Simulation(_with_contact(scene, n, integrator, contact)), None


def corner_drag(n: int, integrator: str, contact: bool = True):
    """A cloth lying on the floor; one corner is grabbed and dragged over
    the cloth to the opposite corner at about 3 m/s, 5 cm up."""
    scene = load_scene(SCENES / "ground.toml").with_overrides(
        {"cloth.center": [0.0, 0.0, 0.01], "pins.corners": []}
    )
    sim = Simulation(_with_contact(scene, n, integrator, contact))
    # The floor's contact after the step only, as the scene was made with:
    # with it inside the solve (fast_mass_spring's default) the dragged cloth
    # slides along the floor further (median 0.99 m against 0.69 m in 0.8 s
    # at 24x24) and its corner never comes down onto it, so no layers press.
    sim.integrator.contact_in_step = False
    nx, ny = sim.resolution
    corner = (0, 0)
    start = sim.positions[sim.point_index(corner)].copy()
    end = sim.positions[sim.point_index((nx - 1, ny - 1))] + [0.0, 0.0, 0.05]
    sim.pin(corner)

    def drive(sim):
        share = min(sim.state.t / 0.5, 1.0)
        lift = 0.05 * min(share / 0.2, 1.0)
        sim.move_pin(corner, start + share * (end - start) + [0.0, 0.0, lift])

    return sim, drive


def twist(n: int, integrator: str, contact: bool = True):
    """A hanging cloth held by its four corners; the top two turn about the
    vertical axis through its middle, one turn in 1.5 s, so the cloth
    winds onto itself."""
    scene = load_scene(SCENES / "hanging.toml").with_overrides(
        {
            "cloth.orientation": "vertical",
            "cloth.center": [0.0, 0.0, 1.0],
            "pins.corners": ["top-left", "top-right", "bottom-left", "bottom-right"],
        }
    )
    sim = Simulation(_with_contact(scene, n, integrator, contact))
    nx, ny = sim.resolution
    tops = [(0, ny - 1), (nx - 1, ny - 1)]
    starts = [sim.positions[sim.point_index(p)].copy() for p in tops]
    axis = 0.5 * (starts[0] + starts[1])

    def drive(sim):
        angle = 2.0 * np.pi * min(sim.state.t / 1.5, 1.0)
        c, s = np.cos(angle), np.sin(angle)
        for point, start in zip(tops, starts, strict=True):
            r = start - axis
            sim.move_pin(point, axis + [c * r[0] - s * r[1], s * r[0] + c * r[1], r[2]])

    return sim, drive


def towel_fold(n: int, integrator: str, contact: bool = True):
    """The towel of ``examples/03_self_collision/towel_helpers.py``: a cloth on the floor folded
    in half by its left edge in 1 s, then let go to settle on itself."""
    return fold_a_towel(n, integrator, contact)


ALL = {
    "crumple": crumple,
    "sphere drape": sphere_drape,
    "corner drag": corner_drag,
    "twist": twist,
    "towel fold": towel_fold,
}
