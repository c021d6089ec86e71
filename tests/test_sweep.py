"""Parameter sweeps on a real dask.distributed cluster: every row exactly once,
equal to a serial run, even when a worker is killed halfway."""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

from conftest import small_scene
from pvcloth import SceneError
from pvcloth.studies.sweep import (
    SweepError,
    expand,
    parse_sets,
    parse_values,
    read_rows,
    run_reference,
    run_sweep,
    run_unit,
    shared_reference_step,
    summary,
)

distributed = pytest.importorskip("dask.distributed")

DURATION = 0.1


def test_value_syntax():
    assert parse_values("k", "1,2.5,abc,true") == [1, 2.5, "abc", True]
    assert parse_values("k", "0:1:3lin") == [0.0, 0.5, 1.0]
    np.testing.assert_allclose(parse_values("k", "1e-4:1e-2:5log"), np.geomspace(1e-4, 1e-2, 5))
    assert parse_values("k", "1:2:3cubic") == ["1:2:3cubic"]  # text: the scene rejects it
    for bad, words in (("a:b:3lin", "numbers"), ("-1:1:3log", "positive"), ("0:1:0lin", "least")):
        with pytest.raises(SweepError, match=words):
            parse_values("k", bad)
    with pytest.raises(SweepError, match="no values"):
        parse_values("k", " , ")
    with pytest.raises(SweepError, match="KEY=VALUES"):
        parse_sets(["solver.dt"])
    with pytest.raises(SweepError, match="twice"):
        parse_sets(["solver.dt=1", "solver.dt=2"])


def test_settings_are_validated_like_scene_files():
    scene = small_scene(4)
    units = expand(scene, parse_sets(["springs.structural=10,20", "cloth.resolution=5"]))
    assert [u.scene.springs.structural.stiffness for u in units] == [10, 20]
    assert units[0].scene.cloth.resolution == (5, 5)
    with pytest.raises(SceneError) as caught:
        expand(scene, parse_sets(["springs.structural=10,-5"]))
    assert caught.value.key == "springs.structural.stiffness"
    assert "-5" in str(caught.value)
    with pytest.raises(SceneError, match="did you mean 'mass'"):
        expand(scene, parse_sets(["cloth.mas=1"]))
    with pytest.raises(SceneError, match="solver.integrator"):
        expand(scene, parse_sets(["solver.integrator=leapfrog"]))


SETS = [
    "springs.structural=50,200",
    "solver.dt=5e-4:4e-3:3log",
    "solver.integrator=symplectic_euler,verlet",
]


def serial_rows(scene, sets):
    """The same units run one after the other in this process."""
    units = expand(scene, sets)
    groups = {}
    for unit in units:
        groups.setdefault(unit.physics, []).append(unit)
    rows = {}
    for members in groups.values():
        dt = shared_reference_step([u.scene for u in members], DURATION)
        reference = run_reference(members[0].scene, dt, DURATION)
        for unit in members:
            rows[unit.id] = run_unit(unit, reference, DURATION)
    return rows


def assert_same(rows, expected):
    assert sorted(r["id"] for r in rows) == sorted(expected)  # every row exactly once
    for row in rows:
        want = expected[row["id"]]
        assert row["stable"] == want["stable"]
        assert row["settings"] == want["settings"]
        if want["stable"]:
            np.testing.assert_allclose(row["rms_error"], want["rms_error"], rtol=1e-9, atol=1e-15)
            np.testing.assert_allclose(row["final_energy"], want["final_energy"], rtol=1e-9)


@pytest.fixture
def cluster():
    with (
        distributed.LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        ) as local,
        distributed.Client(local) as client,
    ):
        yield client


def test_a_sweep_survives_a_killed_worker_and_equals_a_serial_run(cluster, tmp_path):
    scene = small_scene(10, stiffness=100.0, damping=0.1, stability="ignore")
    sets = parse_sets(SETS)
    expected = serial_rows(scene, sets)
    results = {}

    def sweep():
        results["rows"] = run_sweep(
            scene, sets, tmp_path, duration=DURATION, client=cluster, progress=False
        )

    worker = threading.Thread(target=sweep)
    worker.start()
    # Kill one worker process as soon as the first row is on disk.
    deadline = time.time() + 120
    while not read_rows(tmp_path / "sweep.csv") and time.time() < deadline:
        time.sleep(0.05)
    pids = cluster.run(os.getpid)
    victim = sorted(pids)[0]
    os.kill(pids[victim], signal.SIGKILL)
    worker.join(timeout=300)
    assert not worker.is_alive()
    rows = read_rows(tmp_path / "sweep.csv")
    assert len(rows) < len(expected) + 1
    assert_same(rows, expected)
    assert_same(results["rows"], expected)
    assert "symplectic_euler" in summary(rows)


def test_an_interrupted_sweep_resumes_without_redoing_rows(cluster, tmp_path):
    scene = small_scene(8, stiffness=100.0, stability="ignore")
    sets = parse_sets(SETS[:2])
    run_sweep(scene, sets, tmp_path, duration=DURATION, client=cluster, progress=False)
    path = tmp_path / "sweep.csv"
    lines = path.read_text().splitlines(keepends=True)
    # An interruption: the last two rows lost, the one before cut mid-line.
    path.write_text("".join(lines[:-3]) + lines[-3][:25])
    kept = {r["id"] for r in read_rows(path)}
    assert len(kept) == len(lines) - 4
    rows = run_sweep(scene, sets, tmp_path, duration=DURATION, client=cluster, progress=False)
    assert len(rows) == 6 and len({r["id"] for r in rows}) == 6
    before = path.read_text()
    run_sweep(scene, sets, tmp_path, duration=DURATION, client=cluster, progress=False)
    assert path.read_text() == before  # nothing left to do: nothing written
