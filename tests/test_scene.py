"""Scenes: TOML and Python give the same validated object; bad input gets a
clear SceneError naming the key, the value and what is allowed."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pvcloth
from pvcloth import ClothSpec, PinSpec, Scene, SceneError, SolverSpec, SpringSpec, SpringsSpec

TOML = """
name = "demo"
gravity = [0.0, 0.0, -9.81]
air_damping = 0.1

[cloth]
size = [2.0, 1.0]
resolution = [21, 11]
mass = 0.3
orientation = "horizontal"
center = [0.0, 0.0, 2.0]

[springs.structural]
stiffness = 300.0
damping = 0.2

[springs.shear]
stiffness = 30.0

[pins]
corners = []
edges = ["top"]

[solver]
integrator = "explicit_euler"
dt = 0.0005
"""


def test_toml_and_python_give_the_same_scene(tmp_path):
    path = tmp_path / "demo.toml"
    path.write_text(TOML)
    from_file = pvcloth.load_scene(path)
    in_code = Scene(
        name="demo",
        cloth=ClothSpec(
            size=(2, 1), resolution=(21, 11), mass=0.3, orientation="horizontal", center=(0, 0, 2)
        ),
        springs=SpringsSpec(structural=SpringSpec(300, 0.2), shear=SpringSpec(30), bending=None),
        pins=PinSpec(corners=(), edges=("top",)),
        solver=SolverSpec("explicit_euler", 0.0005),
        air_damping=0.1,
    )
    assert from_file == in_code
    # and the plain-data form goes back to the same scene
    assert Scene.from_dict(in_code.to_dict()) == in_code


def test_bundled_scenes_load(scenes_dir):
    paths = sorted(scenes_dir.glob("*.toml"))
    assert paths, "no bundled scenes"
    for path in paths:
        scene = pvcloth.load_scene(path)
        assert scene.name == path.stem


def test_defaults_pin_the_two_top_corners():
    assert Scene().pins.corners == ("top-left", "top-right")


@pytest.mark.parametrize(
    ("data", "key", "words"),
    [
        ({"clth": {}}, "clth", "did you mean 'cloth'"),
        ({"cloth": {"resolutoin": [4, 4]}}, "cloth.resolutoin", "did you mean 'resolution'"),
        ({"cloth": {"mass": -1.0}}, "cloth.mass", "at least 1e-09"),
        ({"cloth": {"mass": 0}}, "cloth.mass", "at least 1e-09"),
        ({"cloth": {"mass": 10**400}}, "cloth.mass", "finite number"),
        ({"cloth": {"size": [1e-320, 1.0]}}, "cloth.size[0]", "at least 0.0001"),
        ({"cloth": {"center": [0, 0, 1e308]}}, "cloth.center[2]", "at most 10000"),
        ({"wind": {"velocity": [1e308, 0, 0]}}, "wind.velocity[0]", "at most 340"),
        (
            {"springs": {"structural": {"stiffness": 1e308}}},
            "springs.structural.stiffness",
            "at most",
        ),
        ({"cloth": {"mass": "heavy"}}, "cloth.mass", "expected a number"),
        ({"cloth": {"resolution": [1, 8]}}, "cloth.resolution[0]", "between 2 and"),
        ({"cloth": {"resolution": [8.5, 8]}}, "cloth.resolution[0]", "whole number"),
        ({"cloth": {"resolution": 8}}, "cloth.resolution", "expected a list"),
        ({"cloth": {"size": [1.0, math.inf]}}, "cloth.size[1]", "finite"),
        ({"cloth": {"center": [0.0, math.nan, 0.0]}}, "cloth.center[1]", "finite"),
        ({"cloth": {"orientation": "vertcal"}}, "cloth.orientation", "did you mean 'vertical'"),
        ({"springs": {"shear": {"damping": 1.0}}}, "springs.shear.stiffness", "required"),
        ({"springs": {"bending": {"stiffness": -4}}}, "springs.bending.stiffness", "at least 0"),
        ({"solver": {"dt": 0.0}}, "solver.dt", "greater than 0"),
        ({"solver": {"dt": -1e-3}}, "solver.dt", "greater than 0"),
        ({"solver": {"integrator": "rk5"}}, "solver.integrator", "Choose one of"),
        (
            {"pins": {"points": [[8, 0]]}, "cloth": {"resolution": [8, 8]}},
            "pins.points[0]",
            "outside the 8x8 grid",
        ),
        (
            {"pins": {"indices": [64]}, "cloth": {"resolution": [8, 8]}},
            "pins.indices[0]",
            "outside the grid",
        ),
        ({"pins": {"edges": ["middle"]}}, "pins.edges[0]", "Choose one of"),
        ({"gravity": [0, 0]}, "gravity", "expected 3 items"),
        ({"air_damping": True}, "air_damping", "expected a number"),
    ],
)
def test_bad_values_name_key_value_and_what_is_allowed(data, key, words):
    with pytest.raises(SceneError) as caught:
        Scene.from_dict(data)
    assert caught.value.key == key
    assert words in str(caught.value)


def test_python_construction_is_validated_too():
    with pytest.raises(SceneError, match="between 2 and 4096"):
        ClothSpec(resolution=(0, 4))
    with pytest.raises(SceneError, match="expected a ClothSpec"):
        Scene(cloth={"resolution": (4, 4)})


def test_file_errors_are_scene_errors(tmp_path):
    with pytest.raises(SceneError, match="cannot read scene file"):
        pvcloth.load_scene(tmp_path / "missing.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[cloth\nmass = 1")
    with pytest.raises(SceneError, match="not valid TOML"):
        pvcloth.load_scene(broken)


@pytest.mark.parametrize("text", ["", "\n# only a comment\n"], ids=["empty", "comment"])
def test_a_scene_file_that_sets_nothing_is_refused(tmp_path, text):
    path = tmp_path / "blank.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"blank\.toml sets nothing: .*cloth\.resolution"):
        pvcloth.load_scene(path)


@pytest.mark.parametrize(
    "text, key, line",
    [
        ("cloth.resolutoin = [8, 8]\n", "cloth.resolutoin", 1),
        ('name = "x"\n\n[cloth]\nmass = 0.3\nresolution = -3\n', "cloth.resolution", 5),
        ("[solver]\ndt = 0.01\n[cloth]\ndt = 1\n", "cloth.dt", 4),
        ("solver = { dt = -1 }\n", "solver.dt", 1),
        (
            '[[obstacles]]\ntype = "sphere"\nradius = 1\ncentre = [0, 0, 0]\n',
            "obstacles[0].centre",
            4,
        ),
        (  # a list over several lines: its rows are not table headers
            '[cloth]\nsize = [\n  1.0,\n  1.0]\n[[obstacles]]\ntype = "sphere"\npath = [\n'
            "  [0, 0, 0, 1],\n  [1, 0, 0, 1]]\nradius = -1\n",
            "obstacles[0].radius",
            10,
        ),
        (  # two obstacles set a radius: the line is ambiguous, the file is named
            '[[obstacles]]\ntype = "sphere"\nradius = 1\n[[obstacles]]\ntype = "sphere"\n'
            "radius = -1\n",
            "obstacles[1].radius",
            None,
        ),
    ],
)
def test_a_scene_file_error_names_the_file_and_line(tmp_path, text, key, line):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as caught:
        pvcloth.load_scene(path)
    assert caught.value.key == key
    where = f"{path}, line {line}" if line else f"{path}"
    assert str(caught.value).startswith(f"{where}: {key}: "), str(caught.value)


# -- property-based: malformed dictionaries raise SceneError and nothing else --

KEYS = [
    "name",
    "cloth",
    "springs",
    "pins",
    "solver",
    "gravity",
    "air_damping",
    "size",
    "resolution",
    "mass",
    "orientation",
    "center",
    "structural",
    "shear",
    "bending",
    "stiffness",
    "damping",
    "corners",
    "edges",
    "points",
    "indices",
    "integrator",
    "dt",
    "top",
    "vertical",
    "symplectic_euler",
    "top-left",
]
leaves = (
    st.none()
    | st.booleans()
    | st.integers(-(10**12), 10**12)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.sampled_from(KEYS)
    | st.text(max_size=5)
)
values = st.recursive(
    leaves,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(st.sampled_from(KEYS) | st.text(max_size=4), inner, max_size=4)
    ),
    max_leaves=20,
)
scene_dicts = st.dictionaries(st.sampled_from(KEYS), values, max_size=6)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene_dicts)
def test_malformed_scene_dicts_raise_only_scene_errors(data):
    try:
        scene = Scene.from_dict(data)
    except SceneError as error:
        assert str(error)
    else:
        assert isinstance(scene, Scene)
