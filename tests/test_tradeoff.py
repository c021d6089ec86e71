"""The speed/accuracy measurement: orders on a damped cloth, unstable runs
flagged, and the CSV and plot written by the command."""

from __future__ import annotations

import csv

import imageio.v3 as iio
import numpy as np
import pytest

from conftest import SCENES, small_scene
from pvcloth import INTEGRATORS, Simulation
from pvcloth.cli import main
from pvcloth.studies.tradeoff import measure, pareto_front, table


@pytest.fixture(scope="module")
def damped_runs():
    scene = small_scene(6, stiffness=100.0, damping=0.2, air_damping=0.5)
    limit = Simulation(scene).stable_dt()
    steps = [limit / 2, limit / 4, limit / 8, 4 * limit]
    runs = measure(
        scene,
        integrators=["symplectic_euler", "verlet", "rk4"],
        steps=steps,
        duration=0.3,
        progress=False,
    )
    return runs, limit


@pytest.mark.parametrize("integrator", ["symplectic_euler", "verlet", "rk4"])
def test_orders_hold_on_a_damped_cloth(damped_runs, integrator):
    runs, _ = damped_runs
    ok = [r for r in runs if r.integrator == integrator and r.stable]
    assert len(ok) == 3
    dts = np.array([r.dt for r in ok])
    errors = np.array([r.rms_error for r in ok])
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert slope == pytest.approx(INTEGRATORS[integrator].order, abs=0.3)


def test_steps_far_above_the_limit_are_reported_unstable(damped_runs):
    runs, limit = damped_runs
    for run in runs:
        if run.dt > 3 * limit:
            assert not run.stable and np.isnan(run.rms_error)
    front = pareto_front(runs)
    assert front and all(r.stable for r in front)
    costs = [r.wall_per_sim_second for r in front]
    assert costs == sorted(costs)


def test_command_writes_csv_plot_and_table(tmp_path, capsys):
    code = main(
        [
            "tradeoff",
            str(SCENES / "hanging.toml"),
            "-o",
            str(tmp_path),
            "--resolution",
            "5",
            "--duration",
            "0.05",
            "--integrators",
            "symplectic_euler,implicit_euler",
            "--steps",
            "0.001,0.01",
            "--quiet",
        ]
    )
    assert code == 0
    rows = list(csv.DictReader(open(tmp_path / "tradeoff.csv")))
    # two fixed steps each, and implicit Euler (it measures its error) at
    # the first-order default tolerances
    assert len(rows) == 6
    assert {r["integrator"] for r in rows} == {"symplectic_euler", "implicit_euler"}
    adaptive = sorted(float(r["tolerance"]) for r in rows if r["tolerance"] != "nan")
    assert adaptive == [1e-2, 1e-1]
    assert iio.imread(tmp_path / "tradeoff.png").ndim == 3
    said = capsys.readouterr()
    assert "Pareto front" in said.out and "tol: an adaptive run's tolerance" in said.out
    # how long it would take, said before it starts; a few seconds here
    assert "pvcloth: about " in said.err and "to make it shorter" not in said.err


def test_the_estimate_grows_with_the_work_and_says_it_in_a_persons_units():
    from pvcloth.cli import _duration
    from pvcloth.studies.tradeoff import estimate_seconds

    scene = small_scene(6)
    one = estimate_seconds(scene, ["verlet"], [1e-3], duration=0.05, tolerances=[])
    more = estimate_seconds(scene, ["verlet"], [1e-4, 1e-3], duration=0.05, tolerances=[])
    assert 0 < one < more  # ten times the steps in the second run
    assert [_duration(s) for s in (0.2, 42, 600, 3 * 3600)] == ["1 s", "42 s", "10 min", "3.0 h"]


def test_adaptive_runs_join_the_fixed_ones():
    """rk23 at three tolerances beside its fixed steps: its error shrinks
    with the tolerance and stays under ``tolerance * t`` (the relation
    :mod:`pvcloth.physics.adaptive` states, for the largest point error; the
    RMS one is smaller)."""
    scene = small_scene(6, stiffness=100.0, damping=0.2, air_damping=0.5)
    duration = 0.3
    runs = measure(
        scene,
        integrators=["rk23"],
        steps=[2e-3],
        duration=duration,
        tolerances=[1e-2, 1e-3, 1e-4],
        progress=False,
    )
    adaptive = sorted((r for r in runs if r.adaptive), key=lambda r: -r.tolerance)
    assert [r.tolerance for r in adaptive] == [1e-2, 1e-3, 1e-4]
    errors = [r.rms_error for r in adaptive]
    assert errors == sorted(errors, reverse=True)
    assert all(r.rms_error < r.tolerance * duration for r in adaptive)
    assert all(r.dt == pytest.approx(duration / r.steps) for r in adaptive)
    assert "1e-04" in table(runs)
    fixed = [r for r in runs if not r.adaptive]
    assert len(fixed) == 1 and fixed[0].dt == pytest.approx(2e-3)


def test_implicit_errors_split_into_time_and_solver_parts():
    """The implicit methods' error is split against converged backward Euler
    at the same step: RMS distances obey the triangle inequality, and more
    local/global iterations shrink only the solver part."""
    scene = small_scene(6, stiffness=800.0, damping=0.5, orientation="horizontal")
    scene = scene.with_overrides({"pins.corners": ["top-left", "top-right"]})

    def split(iterations):
        runs = measure(
            scene.with_overrides({"solver.iterations": iterations}),
            integrators=["fast_mass_spring", "implicit_euler", "rk4"],
            steps=[1 / 60, 1 / 240],
            duration=0.25,
            tolerances=[],  # fixed steps only: the split is made at a step
            progress=False,
        )
        return {(r.integrator, round(r.dt, 6)): r for r in runs}

    few, many = split(3), split(300)
    assert ("backward_euler", round(1 / 60, 6)) not in few  # measured, not listed
    for (name, dt), run in few.items():
        if name == "rk4":
            assert np.isnan(run.solver_error) and np.isnan(run.discretisation_error)
            continue
        time, solver = run.discretisation_error, run.solver_error
        assert time > 0 and solver > 0
        assert abs(run.rms_error - time) <= solver * (1 + 1e-9)
        assert solver <= (run.rms_error + time) * (1 + 1e-9)
        assert many[name, dt].discretisation_error == pytest.approx(time, rel=1e-9)
    for dt in (round(1 / 60, 6), round(1 / 240, 6)):
        assert many["fast_mass_spring", dt].solver_error < few["fast_mass_spring", dt].solver_error
    assert "of which: time (m)" in table(list(few.values()))


def test_the_plot_tells_every_integrator_apart_labels_steps_and_marks_the_front():
    from matplotlib.colors import to_rgb

    from pvcloth.studies.tradeoff import Run, draw

    names = sorted(INTEGRATORS)
    runs = [
        Run(name, dt, True, 1e-3 * (n + 1) * dt * 60, 0.0, 0.1 * (n + 1) / (dt * 60), 60)
        for n, name in enumerate(names)
        for dt in (1 / 60, 1 / 120, 1 / 240)
    ]
    ax = draw(runs, "test").axes[0]
    lines = {line.get_label(): line for line in ax.lines}
    looks = [(to_rgb(lines[name].get_color()), lines[name].get_marker()) for name in names]
    assert len(set(looks)) == len(names)  # no two integrators alike
    assert len({colour for colour, _ in looks}) == len(names)  # not even by colour alone
    greys = [c for c, _ in looks if max(c) - min(c) < 0.05]
    assert not greys  # grey is the front's and the guides' colour
    labels = {text.get_text() for text in ax.texts}
    assert {"1/60 s", "1/240 s"} <= labels
    assert any("Pareto front" in label for label in lines)
