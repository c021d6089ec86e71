"""The pvcloth command: info, simulate, and clear errors with exit code 2."""

from __future__ import annotations

import subprocess
import sys

from conftest import SCENES
from pvcloth.cli import main


def test_info_prints_the_model(capsys):
    assert main(["info", str(SCENES / "hanging.toml")]) == 0
    out = capsys.readouterr().out
    assert "particles   1024 (32 x 32)" in out
    assert "structural 1984, shear 1922, bending 1920" in out
    assert "pins        2 point(s)" in out
    assert "stable dt   about" in out and ": ok)" in out


def test_info_without_bending_lists_no_bending(tmp_path, capsys):
    scene = tmp_path / "plain.toml"
    scene.write_text("[springs.structural]\nstiffness = 100.0\n")
    assert main(["info", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "bending" not in out and "shear" not in out


def test_bad_scene_exits_2_with_the_key(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text("[cloth]\nmas = 1.0\n")
    assert main(["info", str(scene)]) == 2
    err = capsys.readouterr().err
    assert "cloth.mas" in err and "did you mean 'mass'" in err


def test_unstable_step_is_refused_substepped_or_run(capsys):
    scene = str(SCENES / "hanging.toml")
    assert main(["info", scene, "--dt", "0.01"]) == 2
    err = capsys.readouterr().err
    assert "solver.dt: 0.01 s is above the largest stable step" in err and "Use dt <=" in err
    assert main(["info", scene, "--dt", "0.01", "--stability", "substep"]) == 0
    assert "dt = 0.0002" in capsys.readouterr().out  # 0.01 split into 50 substeps
    code = main(["simulate", scene, "--dt", "0.01", "--stability", "ignore", "--quiet"])
    assert code == 2
    assert "diverged at t =" in capsys.readouterr().err


def test_console_module_runs():
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "pvcloth",
            "simulate",
            str(SCENES / "hanging.toml"),
            "--seconds",
            "0.05",
            "--quiet",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "simulated 0.05 s in 200 steps" in result.stdout


def _help(capsys, *command: str) -> str:
    try:
        main([*command, "--help"])
    except SystemExit as done:
        assert done.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps lines


def test_help_says_which_integrators_a_tolerance_needs(capsys):
    from pvcloth.physics.integrators import INTEGRATORS

    text = _help(capsys, "simulate")
    measuring = sorted(name for name, method in INTEGRATORS.items() if method.embedded)
    for name in sorted(INTEGRATORS):
        assert (name in text.split("--tolerance METRES", 2)[2].split("--stability")[0]) == (
            name in measuring
        ), name


def test_compare_takes_integrators_only_in_the_plural(capsys):
    import re

    text = _help(capsys, "compare")
    assert "--integrators" in text
    assert not re.search(r"--integrator\b(?!s)", text)
