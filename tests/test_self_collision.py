"""Self-collision (``[self_collision]``): the cloth never passes through
itself, checked after every step by the brute-force counter of
``tests/intersections.py`` (independent of the code under test); the
closest-point routines against dense sampling; bad input named by key; and
a scene without the table runs none of it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from intersections import count_self_intersections

from conftest import ROOT
from pvcloth import Scene, SceneError, SelfCollisionSpec, Simulation, load_scene
from pvcloth.errors import DivergenceError
from pvcloth.info import describe
from pvcloth.physics import self_collision, topology
from pvcloth.physics.integrators import INTEGRATORS

RNG = np.random.default_rng(7)


def test_closest_point_on_a_triangle_is_no_farther_than_any_sampled_point():
    grid = np.linspace(0.0, 1.0, 121)
    u, v = np.meshgrid(grid, grid)
    inside = u + v <= 1.0
    for _ in range(100):
        p, a, b, c = RNG.normal(size=(4, 3))
        weights = self_collision.point_triangle(tuple(p), tuple(a), tuple(b), tuple(c))
        assert min(weights) >= 0.0 and sum(weights) == pytest.approx(1.0)
        found = np.linalg.norm(p - np.dot(weights, [a, b, c]))
        samples = a + u[inside, None] * (b - a) + v[inside, None] * (c - a)
        nearest = np.linalg.norm(samples - p, axis=1).min()
        assert nearest - 1e-3 <= found <= nearest + 1e-12


@pytest.mark.parametrize("parallel", [False, True])
def test_closest_points_of_two_segments_are_no_farther_than_any_sampled_pair(parallel):
    grid = np.linspace(0.0, 1.0, 301)[:, None]
    for _ in range(60):
        p1, q1, p2, q2 = RNG.normal(size=(4, 3))
        if parallel:
            q2 = p2 + (q1 - p1) * RNG.uniform(-2.0, 2.0)
        s, t = self_collision.segment_segment(tuple(p1), tuple(q1), tuple(p2), tuple(q2))
        found = np.linalg.norm(p1 + s * (q1 - p1) - p2 - t * (q2 - p2))
        first, second = p1 + grid * (q1 - p1), p2 + grid * (q2 - p2)
        nearest = np.linalg.norm(first[:, None] - second[None], axis=2).min()
        assert nearest - 1e-2 <= found <= nearest + 1e-12


def test_the_grid_triangles_match_the_counters():
    from intersections import grid_triangles

    ours = {tuple(t) for t in topology.triangles((5, 7)).tolist()}
    assert ours == {tuple(t) for t in grid_triangles(7, 5).tolist()} and len(ours) == 48
    edges = topology.edges((5, 7))
    from_triangles = {
        tuple(sorted(e))
        for t in grid_triangles(7, 5)
        for e in ((t[0], t[1]), (t[1], t[2]), (t[0], t[2]))
    }
    assert {tuple(sorted(e)) for e in edges} == from_triangles and len(edges) == len(from_triangles)


def _fold(integrator: str, n: int, contact: bool) -> Scene:
    scene = load_scene(ROOT / "data" / "scenes" / "fold.toml").with_resolution(n)
    changes = {"solver.integrator": integrator}
    scene = scene.with_overrides(changes)
    return scene if contact else scene.replace(self_collision=None)


def _worst_after_every_step(sim: Simulation, seconds: float) -> int:
    nx, ny = sim.resolution
    worst = 0
    end = sim.state.t + seconds
    while sim.state.t < end - 1e-9:
        sim.advance(sim.dt)  # one step
        worst = max(worst, count_self_intersections(sim.state.x, (nx, ny)))
    return worst


def test_the_fold_scene_passes_through_itself_without_self_collision():
    # What the tests below guard against really happens in this scene.
    sim = Simulation(_fold("fast_mass_spring", 32, contact=False))
    sim.advance(1.2)
    assert count_self_intersections(sim.state.x, sim.resolution) > 100


def test_the_fold_never_intersects_with_self_collision():
    sim = Simulation(_fold("fast_mass_spring", 32, contact=True))
    assert _worst_after_every_step(sim, 1.2) == 0
    assert sim.model.self_collision.report.contacts > 0  # the halves did meet


@pytest.mark.validation
@pytest.mark.parametrize("integrator", ["symplectic_euler", "verlet", "implicit_euler"])
def test_the_fold_never_intersects_with_other_integrators(integrator):
    # From the folded cloth (halves in contact), each integrator at its own
    # step, checked after every step.
    sim = Simulation(_fold("fast_mass_spring", 32, contact=True))
    sim.advance(0.9)
    sim.update({"solver.integrator": integrator, "solver.dt": None})
    assert count_self_intersections(sim.state.x, sim.resolution) == 0
    seconds = 0.3 if integrator == "implicit_euler" else 0.015
    assert _worst_after_every_step(sim, seconds) == 0
    assert sim.model.self_collision.report.contacts > 0


def test_without_the_table_no_self_collision_code_runs(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("self-collision ran in a scene without it")

    monkeypatch.setattr(self_collision.SelfCollision, "resolve", refuse)
    sim = Simulation(Scene.from_dict({"cloth": {"resolution": [8, 8]}}))
    sim.advance(0.05)
    assert sim.model.self_collision is None
    assert dict(sim.scene.summary())["self-contact"] == "off"
    assert "contact     no self-collision" in describe(sim)  # what pvcloth info prints


def test_the_scene_file_turns_it_on_with_its_thickness():
    scene = load_scene(ROOT / "data" / "scenes" / "fold.toml")
    sim = Simulation(scene)
    gap = (1.6 / 31) * (0.6 / 31) / np.hypot(1.6 / 31, 0.6 / 31)
    assert sim.model.self_collision.thickness == pytest.approx(0.3 * gap)
    assert "friction 0.3" in dict(scene.summary())["self-contact"]
    # pvcloth info says so, with the thickness, the friction and the step limit
    said = f"self-collision on: layers kept {1e3 * 0.3 * gap:.3g} mm apart, friction 0.3; "
    said += f"steps are split to at most {sim.contact_step():.3g} s"
    assert said in describe(sim)
    # in_solve: bdf2 holds the layers in its solve and takes no split
    held = scene.with_overrides({"self_collision.in_solve": True, "solver.integrator": "bdf2"})
    sim = Simulation(held)
    assert sim.model.self_collision.in_solve and sim.contact_step() == math.inf
    assert "layers in the solve" in dict(held.summary())["self-contact"]
    assert "bdf2 holds the layers in its solve: no limit on the step" in describe(sim)


@pytest.mark.parametrize(
    "table, key, words",
    [
        ({"thickness": 0.0}, "self_collision.thickness", "greater than 0"),
        ({"thickness": -0.01}, "self_collision.thickness", "greater than 0"),
        ({"thickness": 0.05}, "self_collision.thickness", "at most 0.0177 m here"),
        ({"thickness": "thin"}, "self_collision.thickness", "expected a number"),
        ({"friction": -0.1}, "self_collision.friction", "at least 0"),
        ({"friction": 12}, "self_collision.friction", "at most 5"),
        ({"in_solve": "yes"}, "self_collision.in_solve", "expected true or false"),
        ({"thick": 0.01}, "self_collision.thick", ""),
    ],
)
def test_bad_input_names_the_key(table, key, words):
    with pytest.raises(SceneError) as caught:
        Scene.from_dict({"cloth": {"resolution": [21, 21]}, "self_collision": table})
    assert caught.value.key == key
    assert words in str(caught.value)


def test_a_direct_spec_is_checked_against_the_grid_too():
    with pytest.raises(SceneError, match="self_collision.thickness"):
        Scene(self_collision=SelfCollisionSpec(thickness=0.5))


# -- the response and the zones, on a few points ----------------------------------


#: Grid cells (column, row) for the four points of :func:`_one_triangle`,
#: far apart: no pair of them is two sides of one crease.
APART = np.array([[0, 0], [10, 0], [20, 0], [30, 0]])


def _one_triangle(p):
    """Points 0-2 a triangle in z = 0, point 3 at ``p``; rows of the pair
    list for the point against the triangle."""
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], p])
    triangles = np.array([[0, 1, 2]])
    edges = np.empty((0, 2), np.int64)
    return x, triangles, edges


def test_a_zone_its_own_pairs_meet_twice_in_one_pass_moves_and_is_not_held():
    # A point falls through a still triangle. Two listed pairs name the same
    # four points: the second is met in the pass that made the zone, before
    # the zone moved. It must wait for the zone to move, not hold it (held,
    # the cloth would freeze where it started, its velocity kept).
    x0, triangles, edges = _one_triangle([0.2, 0.2, 1.0])
    x1 = x0.copy()
    x1[3, 2] = -1.0
    v1 = (x1 - x0) / 0.1
    rows = np.array([[0, 3, 0], [0, 3, 0]])
    inv_mass = np.ones(4)
    zones = self_collision.new_zones(x0, x1, v1)
    everywhere = np.full((4, 3), -10.0), np.full((4, 3), 10.0)  # boxes: no list is needed
    zoned, unresolved, done = self_collision.impact_zones(
        rows, np.arange(2), self_collision.pair_distances(rows, triangles, edges, x0), triangles,
        edges, x0, x1, v1, inv_mass, 0.01, zones, *everywhere,
    )  # fmt: skip
    assert zoned == 4 and unresolved == 0 and done
    # All four move by their mean motion (2 m down shared by four): a
    # translation, so no distance changed, and the mean velocity.
    assert np.allclose(x1 - x0, [0.0, 0.0, -0.5])
    assert np.allclose(v1, [0.0, 0.0, -5.0])


def test_a_corner_with_a_small_weight_is_not_flung_when_the_others_are_pinned():
    # The point touches the triangle next to its pinned edge 1-2, where
    # corner 0 carries a weight of 0.02: moving the contact point by the
    # whole push through that corner alone would move it 50 times as much.
    x0, triangles, edges = _one_triangle([0.49, 0.49, 0.05])
    x, v = x0.copy(), np.zeros((4, 3))
    v[3] = [0.0, 0.0, -1.0]  # the point comes down at 1 m/s
    inv_mass = np.array([1.0, 0.0, 0.0, 0.0])  # only corner 0 may move
    rows, floor = np.array([[0, 3, 0]]), np.zeros((4, 3))
    self_collision.respond(
        rows, np.arange(1), self_collision.pair_distances(rows, triangles, edges, x0), APART,
        triangles, edges, x0, x, v, x0.copy(), inv_mass, floor,
        0.1, 0.0, 0.01, 0.05, 1,
    )  # fmt: skip
    assert np.linalg.norm(v[0]) <= 1.0 + 1e-12  # no more than the approach removed
    assert np.linalg.norm(x[0] - x0[0]) <= 0.05 + 1e-12  # the push, at most
    assert np.array_equal(x[1:], x0[1:]) and np.array_equal(v[1:], [[0, 0, 0]] * 2 + [[0, 0, -1]])


def test_a_point_resting_on_an_obstacle_is_not_pushed_into_it():
    # The triangle lies on the ground (its normal +z): the point above is
    # pushed up by the whole gap instead of sharing it with the triangle.
    x0, triangles, edges = _one_triangle([0.2, 0.2, 0.04])
    x, v = x0.copy(), np.zeros((4, 3))
    v[3] = [0.0, 0.0, -0.5]
    floor = np.zeros((4, 3))
    floor[:3] = [0.0, 0.0, 1.0]
    rows = np.array([[0, 3, 0]])
    self_collision.respond(
        rows, np.arange(1), self_collision.pair_distances(rows, triangles, edges, x0), APART,
        triangles, edges, x0, x, v, x0.copy(), np.ones(4), floor,
        0.1, 0.0, 0.01, 0.5, 1,
    )  # fmt: skip
    assert np.array_equal(x[:3], x0[:3]) and np.array_equal(v[:3], np.zeros((3, 3)))
    assert x[3, 2] == pytest.approx(0.1) and v[3, 2] == pytest.approx(0.0)


def test_an_impulse_does_not_drive_a_point_resting_on_an_obstacle_into_it():
    # The triangle lies on the ground; the point above falls through it in
    # one step. The impulse stops the point and leaves the triangle where it
    # is (shared, it would push the triangle into the ground).
    x0, triangles, edges = _one_triangle([0.2, 0.2, 0.5])
    x1 = x0.copy()
    x1[3, 2] = -0.5
    v1 = (x1 - x0) / 0.1
    floor = np.zeros((4, 3))
    floor[:3] = [0.0, 0.0, 1.0]
    rows = np.array([[0, 3, 0]])
    gaps = self_collision.pair_distances(rows, triangles, edges, x0)
    count, moved, _ = self_collision.impulses(
        rows, np.arange(1), gaps, triangles, edges, x0, x1, v1, np.ones(4), floor,
        0.01, np.ones(4, bool),
    )  # fmt: skip
    assert count == 1 and moved.tolist() == [False, False, False, True]
    assert np.array_equal(x1[:3], x0[:3]) and np.array_equal(v1[:3], np.zeros((3, 3)))
    assert not self_collision.approaches(0, 3, 0, 1, 2, x0, x1, 0.01)
    assert v1[3, 2] == pytest.approx(0.0)


def test_a_run_with_self_collision_resumes_bit_for_bit(tmp_path):
    # The pair list is not saved: a resumed run builds its own, and the
    # response goes through pairs in one fixed order, so nothing changes.
    import pvcloth

    sim = Simulation(_fold("fast_mass_spring", 16, contact=True))
    sim.advance(1.0)  # the halves meet from 1.1 s on
    pvcloth.save_checkpoint(sim, tmp_path / "run.npz")
    resumed = pvcloth.load_checkpoint(tmp_path / "run.npz")
    contacts = 0
    for _ in range(18):
        sim.advance(sim.dt)
        resumed.advance(resumed.dt)
        contacts += sim.model.self_collision.report.contacts
    assert contacts > 0  # the layers were touching
    assert np.array_equal(sim.positions, resumed.positions)


def test_a_kept_wider_pair_list_changes_nothing(monkeypatch):
    # The pair list is taken from a kept, wider one while the boxes stay
    # inside it. The result must be the one of a list built afresh every
    # step: same pairs, same order, so the same run bit for bit.
    from contact_scenes import towel_fold

    runs = []
    for skin in (0.0, 3.0):
        monkeypatch.setattr(self_collision, "SKIN", skin)
        sim, drive = towel_fold(16, "fast_mass_spring")
        reused = 0
        while sim.state.t < 1.4:  # folded over, let go, landing
            drive(sim)
            sim.advance(sim.dt)
            reused += sim.model.self_collision._served > 1
        runs.append((sim.positions.copy(), reused))
    (fresh, reused_fresh), (kept, reused_kept) = runs
    assert reused_kept > 20 and reused_kept > reused_fresh  # the wider list was used
    assert np.array_equal(fresh, kept)


@pytest.mark.parametrize("kind", [0, 1], ids=["point-triangle", "edge-edge"])
def test_the_hash_grid_lists_exactly_the_overlapping_boxes(kind):
    # Against every pair compared with every other (O(N^2), fine for 8x8):
    # the same pairs, each once, none sharing a point. Boxes of random
    # sizes, some spanning many cells, on a crumpled grid.
    shape = (8, 8)
    x = RNG.normal(scale=0.05, size=(64, 3))
    size = RNG.uniform(0.0, 0.03, size=(64, 1)) * (1 + 9 * (RNG.random((64, 1)) < 0.1))
    lo, hi = x - size, x + size
    items = topology.triangles(shape) if kind == 0 else topology.edges(shape)
    ilo = lo[items].min(axis=1)
    ihi = hi[items].max(axis=1)
    qlo, qhi = (lo, hi) if kind == 0 else (ilo, ihi)
    overlap = np.all((qlo[:, None] <= ihi[None]) & (qhi[:, None] >= ilo[None]), axis=2)
    queries = np.arange(len(qlo))[:, None, None] if kind == 0 else items[:, None, :]
    shares = (queries[..., None] == items[None, :, None, :]).any(axis=(2, 3))
    if kind == 1:
        overlap &= np.triu(np.ones_like(overlap), 1)  # each pair once
    expected = {tuple(p) for p in np.argwhere(overlap & ~shares)}
    out = np.empty((len(qlo) * len(ilo), 2), np.int64)  # room for every pair
    for cell in (0.004, 0.02, 0.5):  # boxes spanning many cells, a few, or one
        n = self_collision.box_pairs(qlo, qhi, ilo, ihi, items, kind, cell, out)
        found = [tuple(p) for p in out[:n]]
        assert len(found) == len(set(found))  # each once
        assert set(found) == expected
    assert len(expected) > 50


# -- more scenes that fold onto themselves (tests/contact_scenes.py) ----------------
#
# In three tiers, each asserting the same things at its own size: every
# scene played by fast_mass_spring never intersects (and does pass through
# itself with nothing to stop it), and every other integrator, taking over
# at the moment a scene's layers press hardest, keeps it so.
# - quick: every scene at QUICK_N points a side, each integrator from one
#   scene (PAIRED);
# - validation: the same pairs at 64x64 (backward Euler at 32x32), but the
#   runs of EXHAUSTIVE_ONLY;
# - exhaustive: every scene with every integrator at 32x32 and 64x64.

#: Points a side of the quick tier's scenes: each of the five passes
#: through itself at this size when nothing stops it (240 to 1,300
#: intersecting pairs at 24x24, 86 to 325 at 16x16).
QUICK_N = 24
#: How long each scene is played (s).
SECONDS = {"crumple": 1.5, "corner drag": 1.0, "twist": 1.5, "towel fold": 2.0, "sphere drape": 2.0}
#: When each scene's layers press hardest on each other (s): the contacts
#: of a fast_mass_spring run at 32x32, summed over each 0.1 s, peak there
#: (crumple 21,000 at 0.6 s; the dragged corner lands at 0.7 s; twist
#: 11,000 at 0.9 s; towel 42,000 at 0.9 s; drape 13,000 at 0.7 s).
PRESSING = {
    "crumple": 0.6,
    "corner drag": 0.7,
    "twist": 0.9,
    "towel fold": 0.9,
    "sphere drape": 0.7,
}
#: The scene each integrator takes over in the quick and validation tiers:
#: every scene once at least. backward_euler's Newton iterations stall on
#: the crushed pile of the drag (see NEWTON_STALLS), so it takes the towel.
PAIRED = {
    "explicit_euler": "twist",
    "symplectic_euler": "crumple",
    "verlet": "corner drag",
    "rk4": "sphere drape",
    "rk23": "towel fold",
    "implicit_euler": "crumple",
    "backward_euler": "towel fold",
    "bdf2": "towel fold",
    "fast_bdf2": "corner drag",
}
#: Steps each explicit integrator takes from the pressed state (its step is
#: 35 to 650 times shorter than fast_mass_spring's, chosen anew at that
#: state, so it keeps half the stable step there); implicit ones run this
#: long (s): backward Euler, the reference solved to convergence, takes up
#: to 13 s a step in these scenes at 32x32, so it runs 0.1 s, and not at
#: 64x64 (a minute a step or more).
EXPLICIT_STEPS = 150
IMPLICIT_SECONDS = {"implicit_euler": 0.3, "backward_euler": 0.1, "bdf2": 0.1, "fast_bdf2": 0.3}
#: The references solved by Newton: too slow for 64x64 here.
NEWTON = ("backward_euler", "bdf2")
#: backward_euler's Newton iterations stall here at its 1/60 s step, 0.007
#: m/s^2 short of its 0.001 m/s^2 tolerance after 200 iterations (the
#: drag at 0.7 s, springs crushed in the pile): a limit of that solver, which raises
#: rather than return an unconverged step; self-collision never ran wrong.
NEWTON_STALLS = pytest.mark.xfail(
    raises=DivergenceError, strict=True, reason="backward_euler's Newton stalls on a crushed pile"
)
#: bdf2's Newton stalls in the twist at 32x32: 2.45 m/s^2 left after 200
#: iterations at 0.98 s (the same solver as backward_euler's, on BDF2's
#: equation); self-collision never ran wrong.
BDF2_STALLS = pytest.mark.xfail(
    raises=DivergenceError, strict=True, reason="bdf2's Newton stalls in the twist at 32x32"
)


def _first_intersection(sim, drive, seconds: float, stop_at_first: bool):
    """``(worst count, pairs the report calls unresolved)`` over the run,
    counted after every step."""
    worst = unresolved = 0
    while sim.state.t < seconds - 1e-9:
        if drive is not None:
            drive(sim)
        sim.advance(sim.dt)
        worst = max(worst, count_self_intersections(sim.state.x, sim.resolution))
        if sim.model.self_collision is not None:
            unresolved += sim.model.self_collision.report.unresolved
        if worst and stop_at_first:
            break
    return worst, unresolved


#: Runs too long for the README's test command (its 25 minutes), measured
#: in a fresh clone on 2 cores: the twist played whole at 64x64 took 10.6
#: min, explicit Euler's take-over of it 7.8, the crumple played whole 6.2.
#: They run in the exhaustive tier; their 24x24 twins stay in the quick one.
EXHAUSTIVE_ONLY = {
    ("twist", 64, "whole"),
    ("crumple", 64, "whole"),
    ("twist", 64, "explicit_euler"),
}


def _played(n: int, mark=None):
    """Every scene at ``n`` points a side (the drape not at 64x64: its finer
    skirt folds without passing through itself even with nothing to stop it,
    none in 2 s, so it would prove nothing)."""
    params = []
    for name in SECONDS:
        if (name, n) == ("sphere drape", 64):
            continue
        heavy = (name, n, "whole") in EXHAUSTIVE_ONLY
        marks = [pytest.mark.exhaustive] if heavy else [mark] if mark else []
        params.append(pytest.param(name, n, id=f"{name}-{n}", marks=marks))
    return params


@pytest.mark.parametrize(
    "name, n",
    _played(QUICK_N) + _played(64, pytest.mark.validation) + _played(32, pytest.mark.exhaustive),
)
def test_a_cloth_piled_dragged_twisted_or_folded_onto_itself_never_intersects(name, n):
    from contact_scenes import ALL

    without, _ = _first_intersection(*ALL[name](n, "fast_mass_spring", False), SECONDS[name], True)
    assert without > 0  # the scene does pass through itself when nothing stops it
    sim, drive = ALL[name](n, "fast_mass_spring", True)
    assert _first_intersection(sim, drive, SECONDS[name], False) == (0, 0)


@pytest.fixture(scope="session")
def pressed_state(tmp_path_factory, worker_id):
    """``pressed_state(name, n) -> (x, v, t)``: the scene with self-collision,
    played by fast_mass_spring to ``PRESSING[name]``. Built once per run
    and kept in a file of the run's temporary folder, which pytest-xdist's
    processes share (a lock lets one of them build it)."""
    import fcntl

    from contact_scenes import ALL

    folder = tmp_path_factory.getbasetemp()
    if worker_id != "master":  # each xdist process has a folder of its own in the run's
        folder = folder.parent
    folder = folder / "pressed-states"
    folder.mkdir(exist_ok=True)

    def pressed(name: str, n: int):
        path = folder / f"{name.replace(' ', '-')}-{n}.npz"
        with open(path.with_suffix(".lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.exists():
                sim, drive = ALL[name](n, "fast_mass_spring", True)
                while sim.state.t < PRESSING[name] - 1e-9:
                    if drive is not None:
                        drive(sim)
                    sim.advance(sim.dt)
                np.savez(path, x=sim.state.x, v=sim.state.v, t=sim.state.t)
        with np.load(path) as kept:
            return kept["x"], kept["v"], float(kept["t"])

    return pressed


def _integrators():
    """The quick and validation pairs, then the exhaustive product."""
    for integrator, name in sorted(PAIRED.items()):
        sizes = [(QUICK_N, None), (32 if integrator in NEWTON else 64, "validation")]
        for n, tier in sizes:
            if (name, n, integrator) in EXHAUSTIVE_ONLY:
                tier = "exhaustive"
            yield pytest.param(
                name, n, integrator, id=f"{name}-{n}-{integrator}",
                marks=[getattr(pytest.mark, tier)] if tier else [],
            )  # fmt: skip
    for n in (32, 64):
        for name in SECONDS:
            for integrator in sorted(INTEGRATORS):
                if integrator == "fast_mass_spring":  # it plays each whole scene above
                    continue
                if (integrator in NEWTON and n > 32) or (name, n) == ("sphere drape", 64):
                    continue
                if PAIRED[integrator] == name and (n == 64 or integrator in NEWTON):
                    continue  # a validation pair already
                marks = [pytest.mark.exhaustive]
                if integrator == "backward_euler" and name == "corner drag":
                    marks.append(NEWTON_STALLS)
                if integrator == "bdf2" and name == "twist":
                    marks.append(BDF2_STALLS)
                yield pytest.param(
                    name, n, integrator, id=f"{name}-{n}-{integrator}", marks=marks
                )  # fmt: skip


@pytest.mark.parametrize("name, n, integrator", list(_integrators()))
def test_every_integrator_keeps_each_scene_from_passing_through_itself(
    name, n, integrator, pressed_state
):
    # Each integrator takes over from the moment the scene's layers press
    # hardest, as fast_mass_spring brought it there, at its own automatic
    # step chosen anew at that state (half the stable step there, split for
    # contact), as a user switching integrators at that moment gets it; pins
    # keep being driven; counted after every step.
    from contact_scenes import ALL

    x, v, t = pressed_state(name, n)
    sim, drive = ALL[name](n, "fast_mass_spring", True)
    sim.set_state(x, v, t)
    if drive is not None:
        drive(sim)
    assert count_self_intersections(sim.state.x, sim.resolution) == 0
    sim.update({"solver.integrator": integrator, "solver.dt": None})
    if integrator not in IMPLICIT_SECONDS:  # the step keeps its margin at this state
        assert sim.dt <= 0.5 * sim.stable_dt() * (1 + 1e-12)
    implicit = integrator in IMPLICIT_SECONDS
    end = t + IMPLICIT_SECONDS[integrator] if implicit else math.inf
    worst = contacts = steps = 0
    while sim.state.t < end - 1e-9 and (implicit or steps < EXPLICIT_STEPS):
        if drive is not None:
            drive(sim)
        sim.advance(sim.dt)
        steps += 1
        worst = max(worst, count_self_intersections(sim.state.x, sim.resolution))
        contacts += sim.model.self_collision.report.contacts
    assert worst == 0
    assert contacts > 100  # the layers did press on each other


def test_an_impulse_stops_a_point_falling_through_a_triangle_without_a_zone():
    x0, triangles, edges = _one_triangle([0.2, 0.2, 1.0])
    x1 = x0.copy()
    x1[3, 2] = -1.0  # straight through the triangle in one step
    v1 = (x1 - x0) / 0.1
    rows, inv_mass = np.array([[0, 3, 0]]), np.ones(4)
    assert self_collision.approaches(0, 3, 0, 1, 2, x0, x1, 0.01)
    count, moved, found = self_collision.impulses(
        rows,
        np.arange(1),
        self_collision.pair_distances(rows, triangles, edges, x0),
        triangles,
        edges,
        x0,
        x1,
        v1,
        inv_mass,
        np.zeros_like(x0),
        0.01,
        np.ones(4, bool),
    )
    assert count == found == 1 and moved.all()
    assert not self_collision.approaches(0, 3, 0, 1, 2, x0, x1, 0.01)
    # Inelastic, momentum kept: the point ends moving with the triangle's
    # point below it (weights 0.6, 0.2, 0.2), and no momentum was made.
    below = np.dot([0.6, 0.2, 0.2], v1[:3, 2])
    assert v1[3, 2] == pytest.approx(below) and v1[:, 2].sum() == pytest.approx(-20.0)


def test_a_step_that_would_list_too_many_pairs_is_refused_with_a_clear_error(monkeypatch):
    # Every point of a small cloth flung through one spot in one step: the
    # pair list would hold nearly every pair. Past MAX_PAIRS the step is
    # refused by name instead of the memory running out.
    from pvcloth.errors import DivergenceError

    monkeypatch.setattr(self_collision, "MAX_PAIRS", 1000)
    contact = self_collision.SelfCollision((8, 8), 0.01, 0.0)
    x0 = np.stack(np.meshgrid(np.linspace(0, 1, 8), np.linspace(0, 1, 8), [0.0]), -1).reshape(-1, 3)
    x1 = x0[::-1].copy()  # each point to its mirror: every path crosses the middle
    with pytest.raises(DivergenceError, match=r"candidate pairs in one step .*lower solver\.dt"):
        contact.resolve(x0, x1, (x1 - x0) / 0.01, np.ones(64), 0.01)


@pytest.mark.parametrize("n", [32, pytest.param(64, marks=pytest.mark.validation)])
def test_a_folded_towel_at_rest_does_not_chatter(n):
    # The towel of examples/03_self_collision/towel_helpers.py, let go at 1 s, over its third
    # second. Layers that chatter gain about one step of gravity every step:
    # the bound is a hundredth of that, the kinetic energy of the whole cloth
    # after one step of free fall, (1/2) M (g dt)^2. (Pushing the two sides
    # of the crease a whole thickness apart gave ~5e-5 J here, twice over;
    # at 64x64, steps of 1/60 s, longer than the contact step, never let
    # it rest.)
    from contact_scenes import towel_fold

    sim, drive = towel_fold(n, "fast_mass_spring")
    mass = sim.scene.cloth.mass
    bound = 0.01 * 0.5 * mass * (9.81 * sim.dt) ** 2
    worst = 0.0
    while sim.state.t < 3.0 - 1e-9:
        drive(sim)
        sim.advance(sim.dt)
        if sim.state.t > 2.0:
            worst = max(worst, sim.energy()["kinetic"])
    assert sim.model.self_collision.report.contacts > 100  # the top half lies on the bottom one
    assert sim.positions[:, 2].max() > 1.5 * sim.model.self_collision.thickness  # still folded
    assert worst < bound, f"kinetic energy {worst:.2e} J at rest, bound {bound:.2e} J"


def test_friction_between_layers_holds_a_fold_on_a_slope():
    # The folded towel at rest, then the floor tilted by 14 degrees along the
    # fold line (gravity turned instead). tan 14 = 0.25: friction 0.3 between
    # the layers holds the top half. With none, the whole towel slides, its
    # bottom half too, though the floor's static friction (0.7) holds the
    # same cloth lying flat in one layer: the top half then pulls the bottom
    # one only at the crease, and the floor's friction after the step, point
    # by point, gives way there (a limit the guide states).
    import sys

    sys.path.insert(0, str(ROOT / "examples" / "03_self_collision"))
    from towel_helpers import fold_a_towel

    slid = {}
    for case in ("flat", 0.3, 0.0):
        sim, drive = fold_a_towel(32, friction=0.0 if case == "flat" else case)
        if case == "flat":  # let go at once: it lies in one layer
            for j in range(sim.resolution[1]):
                sim.unpin((0, j))
            drive = None
        while sim.state.t < 2.0 - 1e-9:
            if drive is not None:
                drive(sim)
            sim.advance(sim.dt)
        top = sim.positions[:, 2] > sim.model.self_collision.thickness
        if case != "flat":
            assert 200 < top.sum() < 800  # about half the cloth is the top layer
        angle = np.radians(14.0)
        sim.update({"gravity": [0.0, 9.81 * np.sin(angle), -9.81 * np.cos(angle)]})
        layers = (top, ~top) if top.any() else (~top,)  # the two halves, or the one layer
        before = [sim.positions[layer, 1].mean() for layer in layers]
        sim.advance(1.0)
        slid[case] = [
            sim.positions[layer, 1].mean() - start
            for layer, start in zip(layers, before, strict=True)
        ]
    assert len(slid["flat"]) == 1 and abs(slid["flat"][0]) < 0.001  # one layer, held
    assert max(map(abs, slid[0.3])) < 0.01  # held: under a centimetre in a second
    assert min(slid[0.0]) > 0.1  # without friction both halves slide down the slope


@pytest.mark.parametrize("n, steps_per_frame", [(32, 1), (64, 2), (128, 2)])
def test_steps_are_split_so_one_step_of_gravity_stays_within_the_reach(n, steps_per_frame):
    # A 1 m cloth: thickness 0.3 of the grid's closest gap, the response's
    # reach half of that; a layer falls g dt^2 in a step from rest.
    scene = load_scene(ROOT / "data" / "scenes" / "ground.toml").with_resolution(n)
    scene = scene.with_overrides({"solver.integrator": "fast_mass_spring", "solver.dt": None})
    sim = Simulation(scene.replace(self_collision=SelfCollisionSpec()))
    reach = 0.5 * 0.3 * (1.0 / (n - 1)) / np.sqrt(2.0)
    assert sim.model.self_collision.reach == pytest.approx(reach)
    assert 9.81 * sim.dt**2 <= reach
    assert sim.dt == pytest.approx(1.0 / 60.0 / steps_per_frame)
    # A given step is split the same way; without the table nothing is.
    given = Simulation(scene.replace(self_collision=SelfCollisionSpec()), dt=1.0 / 60.0)
    assert given.dt == sim.dt and given.dt_source == ("given" if n == 32 else "substep")
    assert Simulation(scene).dt == pytest.approx(1.0 / 60.0)
