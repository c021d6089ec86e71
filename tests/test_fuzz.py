"""Fuzzing as a hostile user: generated scene files through ``pvcloth info``
and ``pvcloth simulate``, and generated API calls on a live simulation. The
rule: every case ends in success or in the project's own error (exit code 2
with a message on the command line, a ``PvclothError`` in Python), never a
traceback, a hang or a silent NaN.

Seeded and bounded: ``PVCLOTH_FUZZ_EXAMPLES`` sets the number of cases per
test (default 150 here; ``python benchmarks/fuzz.py`` runs 10,000 or more and
records the count). The step bound :data:`pvcloth.physics.clocks.MAX_STEPS` is
lowered to 20,000 for the run, so a case that would take too long is refused
by the same check a user meets, just sooner.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

import pvcloth
import pvcloth.physics.clocks
from pvcloth.cli import main

EXAMPLES = int(os.environ.get("PVCLOTH_FUZZ_EXAMPLES", "150"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=False,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)


@pytest.fixture(autouse=True)
def _few_steps(monkeypatch):
    monkeypatch.setattr(pvcloth.physics.clocks, "MAX_STEPS", 20_000)


# -- values a hostile user writes -----------------------------------------------

EXTREME_FLOATS = st.sampled_from(
    [0.0, -0.0, 1.0, -1.0, 1e-320, 5e-324, 1e-30, 1e-9, 1e9, 1e30, 1e308, -1e308,
     math.inf, -math.inf, math.nan, 0.5, 2.5e-4, 400.0]
)  # fmt: skip
NUMBERS = st.one_of(
    EXTREME_FLOATS,
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.sampled_from([10**400, -(10**400), 4096, 4097, 2, 1, 0, -1]),
)
SCALARS = st.one_of(NUMBERS, st.booleans(), st.text(max_size=8))
VALUES = st.recursive(
    SCALARS, lambda inner: st.lists(inner, max_size=4), max_leaves=8
)  # lists, nested lists

#: The keys a scene table can hold, with a few misspellings among them.
KEYS = {
    "cloth": ["size", "resolution", "mass", "orientation", "center", "sise"],
    "springs.structural": ["stiffness", "damping", "stifness"],
    "springs.shear": ["stiffness", "damping"],
    "springs.bending": ["stiffness", "damping"],
    "pins": ["corners", "edges", "points", "indices", "corner"],
    "solver": ["integrator", "dt", "stability"],
    "wind": ["velocity", "drag", "lift", "density", "gust", "gust_period", "seed"],
    "": ["name", "gravity", "air_damping", "wind", "unknown"],
}
GOOD = {
    "cloth.resolution": st.lists(st.integers(2, 10), min_size=2, max_size=2),
    "cloth.orientation": st.sampled_from(["vertical", "horizontal", "diagonal"]),
    "pins.corners": st.lists(
        st.sampled_from(["top-left", "top-right", "bottom-left", "bottom-right", "middle"]),
        max_size=3,
    ),
    "pins.edges": st.lists(st.sampled_from(["top", "bottom", "left", "right", "up"]), max_size=2),
    "solver.integrator": st.sampled_from(sorted(pvcloth.INTEGRATORS) + ["euler", ""]),
    "solver.stability": st.sampled_from(["refuse", "substep", "ignore", "never"]),
    "solver.dt": st.one_of(EXTREME_FLOATS, st.floats(1e-5, 1e-2)),
}
OBSTACLE = st.fixed_dictionaries(
    {"type": st.sampled_from(["sphere", "box", "ground", "cone"])},
    optional={
        "center": st.one_of(st.lists(NUMBERS, min_size=3, max_size=3), VALUES),
        "radius": NUMBERS,
        "size": st.lists(NUMBERS, min_size=3, max_size=3),
        "rotation": st.lists(NUMBERS, min_size=3, max_size=3),
        "normal": st.lists(NUMBERS, min_size=3, max_size=3),
        "thickness": NUMBERS,
        "friction": NUMBERS,
        "static_friction": NUMBERS,
        "path": st.lists(st.lists(NUMBERS, min_size=4, max_size=4), max_size=3),
    },
)


@st.composite
def scene_tables(draw) -> dict:
    """A nested dict shaped like a scene file: real keys (mostly), small
    grids (mostly), and any value anywhere."""
    data: dict = {"cloth": {"resolution": [6, 6]}}
    for table, keys in KEYS.items():
        for key in draw(st.lists(st.sampled_from(keys), max_size=3, unique=True)):
            dotted = f"{table}.{key}" if table else key
            good = GOOD.get(dotted)
            value = draw(good if good is not None and draw(st.booleans()) else VALUES)
            where = data
            for part in table.split(".") if table else []:
                where = where.setdefault(part, {}) if isinstance(where.get(part, {}), dict) else {}
            where[key] = value
    if draw(st.booleans()):
        data["obstacles"] = draw(st.lists(OBSTACLE, max_size=2))
    return data


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, dict):
        return "{" + ", ".join(f'"{k}" = {toml_value(v)}' for k, v in value.items()) + "}"
    return "[" + ", ".join(toml_value(v) for v in value) + "]"


def toml_text(data: dict) -> str:
    """Every value as an inline ``key = value`` line (TOML's dotted keys)."""
    lines = []

    def walk(prefix, table):
        for key, value in table.items():
            name = f'{prefix}"{key}"'
            if isinstance(value, dict):
                walk(name + ".", value)
            elif key == "obstacles" and isinstance(value, list):
                for item in value:
                    lines.append(f"[[obstacles]]\n{toml_value(item)[1:-1].replace(', ', chr(10))}")
            else:
                lines.insert(0, f"{name} = {toml_value(value)}")

    walk("", data)
    return "\n".join(lines) + "\n"


MUTATIONS = st.lists(
    st.tuples(st.integers(0, 400), st.sampled_from(["", "[", "]", "=", '"', "\x00", "\xff", "\n",
                                                     "nan", "1e999", "[[", "{", ".", "#"])),
    max_size=3,
)  # fmt: skip


def _assert_no_nan_reported(text: str) -> None:
    assert "nan" not in text.lower().replace("nanosecond", "")


def _run_cli(args, capsys) -> int:
    code = main(args)
    out, err = capsys.readouterr()
    assert code in (0, 2), (code, err)
    if code == 2:
        assert err.startswith("pvcloth: error: ") and "Traceback" not in err
    else:
        _assert_no_nan_reported(out)
    return code


@seed(20261201)
@FUZZ
@given(data=scene_tables(), mutations=MUTATIONS)
def test_generated_scene_files_through_info_and_simulate(tmp_path, capsys, data, mutations):
    text = toml_text(data)
    for position, piece in mutations:
        position = min(position, len(text))
        text = text[:position] + piece + text[position:]
    path = tmp_path / "fuzz.toml"
    path.write_bytes(text.encode("utf-8", errors="surrogatepass").replace(b"\xc3\xbf", b"\xff"))
    if _run_cli(["info", str(path)], capsys) == 0:
        _run_cli(["simulate", str(path), "--seconds", "0.02", "--quiet"], capsys)


# -- API calls ------------------------------------------------------------------

POINTS = st.one_of(
    st.integers(-3, 40),
    st.tuples(st.integers(-2, 8), st.integers(-2, 8)),
    st.sampled_from([True, 1.5, (1.9, 0), ("a", 0), "0", None, [1, 2, 3], np.int64(3)]),
)
POSITIONS = st.one_of(
    st.lists(NUMBERS, min_size=3, max_size=3),
    st.lists(NUMBERS, max_size=5),
    st.sampled_from([None, "up", (0.0, 0.0, 1.0), np.array([0.1, 0.2, 1.3])]),
)
CALLS = st.one_of(
    st.tuples(st.just("pin"), POINTS, POSITIONS),
    st.tuples(st.just("pin"), POINTS),
    st.tuples(st.just("move_pin"), POINTS, POSITIONS),
    st.tuples(st.just("unpin"), POINTS),
    st.tuples(st.just("advance"), NUMBERS),
    st.tuples(st.just("advance"), st.floats(0.0, 0.05)),
    st.tuples(st.just("step")),
    st.tuples(st.just("reset")),
    st.tuples(st.just("restore_scene_pins")),
    st.tuples(st.just("scale_stiffness"), NUMBERS),
    st.tuples(st.just("set_integrator"), st.sampled_from(sorted(pvcloth.INTEGRATORS) + ["x", 3])),
    st.tuples(
        st.just("set_wind"),
        st.one_of(st.none(), st.just("wind"), st.just(pvcloth.WindSpec((3.0, 1.0, 0.0)))),
    ),
)  # fmt: skip


@seed(20261202)
@FUZZ
@given(calls=st.lists(CALLS, min_size=1, max_size=8), integrator=GOOD["solver.integrator"])
def test_generated_api_calls_end_in_success_or_our_error(calls, integrator):
    try:
        scene = pvcloth.Scene(
            cloth=pvcloth.ClothSpec(resolution=(6, 6)),
            solver=pvcloth.SolverSpec(integrator, stability="substep"),
            air_damping=0.2,
        )
    except pvcloth.SceneError:
        return  # a bad integrator name: refused, as it should be
    sim = pvcloth.Simulation(scene)
    for name, *args in calls:
        try:
            getattr(sim, name)(*args)
        except pvcloth.PvclothError:
            pass
        assert np.isfinite(sim.positions).all() and np.isfinite(sim.velocities).all(), name


# -- damaged and tampered checkpoints -------------------------------------------


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory):
    """A real checkpoint's path (implicit Euler, so it has integrator state)."""
    scene = pvcloth.Scene(
        cloth=pvcloth.ClothSpec(resolution=(5, 5)), solver=pvcloth.SolverSpec("implicit_euler")
    )
    sim = pvcloth.Simulation(scene)
    sim.advance(0.05)
    return pvcloth.save_checkpoint(sim, tmp_path_factory.mktemp("ck") / "run.npz")


TAMPERED = st.one_of(
    st.just(np.nan),
    st.just(np.inf),
    st.just(1e9),
    st.just(-1),
    st.just(np.array([1, 2, 3], dtype=np.int8)),
    st.just(np.array("not json {")),
    st.just(np.array('{"cloth": {"mass": -1}}')),
    st.just(np.array("[" * 5000)),
    st.just(np.zeros((2, 2))),
    st.just(np.array(True)),
    st.just(np.array(2**40)),
    st.just(None),  # the entry removed
)


def _load_and_run(path) -> None:
    try:
        sim = pvcloth.load_checkpoint(path)
    except pvcloth.CheckpointError:
        return
    try:
        sim.advance(0.02)
    except pvcloth.PvclothError:
        return
    assert np.isfinite(sim.positions).all()


@seed(20261203)
@FUZZ
@given(cuts=st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), min_size=1, max_size=4),
       truncate=st.booleans())  # fmt: skip
def test_damaged_checkpoint_files_raise_checkpoint_error(tmp_path, checkpoint, cuts, truncate):
    content = bytearray(checkpoint.read_bytes())
    for where, byte in cuts:
        content[where % len(content)] = byte
    if truncate:
        content = content[: cuts[0][0] % len(content)]
    path = tmp_path / "damaged.npz"
    path.write_bytes(bytes(content))
    _load_and_run(path)


@seed(20261204)
@FUZZ
@given(changes=st.dictionaries(st.sampled_from(["x", "v", "t", "steps", "owed", "dt", "pinned",
                                                "targets", "scene", "integrator", "version",
                                                "integrator_last_dv", "tag"]),
                               TAMPERED, min_size=1, max_size=3))  # fmt: skip
def test_tampered_checkpoint_entries_raise_checkpoint_error(tmp_path, checkpoint, changes):
    with np.load(checkpoint) as archive:
        entries = {k: archive[k] for k in archive.files}
    for key, value in changes.items():
        if value is None:
            entries.pop(key, None)
        elif isinstance(value, float) and entries[key].dtype.kind in "fiub":
            changed = np.array(entries[key], dtype=float, copy=True)
            changed.flat[0] = value
            entries[key] = changed
        else:
            entries[key] = value
    path = tmp_path / "tampered.npz"
    np.savez(path, **entries)
    _load_and_run(path)


#: Cases per fuzz test in the exhaustive tier: about 10,000 in all.
EXHAUSTIVE_EXAMPLES = 2500


@pytest.mark.exhaustive
def test_every_fuzz_test_at_thousands_of_cases():
    # The four tests above with EXHAUSTIVE_EXAMPLES cases each (they run
    # 150 in the quick tier), in a process of their own so the count is
    # read when this module is imported.
    import subprocess
    import sys
    from pathlib import Path

    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "not exhaustive",
         "-p", "no:randomly", "--timeout=0", __file__],
        cwd=Path(__file__).resolve().parent.parent,
        env=dict(os.environ, PVCLOTH_FUZZ_EXAMPLES=str(EXHAUSTIVE_EXAMPLES)),
        capture_output=True,
        text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "4 passed" in done.stdout
