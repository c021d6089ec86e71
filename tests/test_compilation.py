"""The first run says that it compiles, and its speed figures leave the
compilation out."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT
from pvcloth.compilation import NOTICE, CompileClock

PVCLOTH = str(Path(sys.executable).with_name("pvcloth"))


def test_the_clock_counts_outermost_compiles_and_announces_once(capsys):
    clock = CompileClock(announce=True)
    for _ in range(2):
        clock.started()
        clock.started()  # a kernel compiling the one it calls
        clock.ended()
        clock.ended()
    assert capsys.readouterr().err.count(NOTICE) == 1
    assert 0.0 < clock.seconds < 1.0


@pytest.mark.validation  # a cold compile: seconds
def test_a_first_run_says_it_compiles_and_a_second_does_not(tmp_path):
    command = [PVCLOTH, "simulate", "data/scenes/hanging.toml", "--seconds", "0.05"]
    command += ["--set", "cloth.resolution=8", "--quiet"]
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    first, second = (
        subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
        for _ in range(2)
    )
    assert first.returncode == second.returncode == 0, first.stderr + second.stderr
    assert first.stderr.count(NOTICE) == 1 and "compiling the kernels" in first.stdout
    assert NOTICE not in second.stderr and "compiling" not in second.stdout
