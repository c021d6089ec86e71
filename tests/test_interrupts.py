"""Interrupted at a random moment, as a user or a scheduler would: Ctrl-C
(SIGINT), SIGTERM or SIGKILL sent to ``pvcloth render`` and ``pvcloth export``
while they write. Afterwards every output is valid: Ctrl-C and SIGTERM exit
130 and 143 with a short message (no traceback) and keep the finished frames;
SIGKILL leaves the earlier complete output at that path as it was; no hidden
partial file stays behind once the next run has started."""

from __future__ import annotations

import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import imageio.v3 as iio
import meshio
import pytest

from conftest import SCENES

PVCLOTH = str(Path(sys.executable).with_name("pvcloth"))
SCENE = str(SCENES / "hanging.toml")
FORMATS = ["gif", "mp4", "png", "pvd", "xdmf", "obj"]
SIGNALS = [signal.SIGINT, signal.SIGTERM, signal.SIGKILL]


def _command(output: Path, frames: int) -> list[str]:
    verb = "render" if output.suffix in (".gif", ".mp4", ".png") else "export"
    args = [PVCLOTH, verb, SCENE, "-o", str(output), "--frames", str(frames), "--quiet"]
    return args + (["--size", "160x120"] if verb == "render" else [])


def frames_in(output: Path) -> int:
    """Frames a reader finds in an output (each one read, so each is valid)."""
    if output.suffix in (".gif", ".mp4"):
        return len(list(iio.imiter(output)))
    if output.suffix == ".png":
        return 1 if iio.imread(output).size else 0
    if output.suffix == ".xdmf":
        with meshio.xdmf.TimeSeriesReader(output) as reader:
            reader.read_points_cells()
            for k in range(reader.num_steps):
                reader.read_data(k)
            return reader.num_steps
    folder = output.with_name(f"{output.stem}_obj")
    if output.suffix == ".pvd":
        import pyvista as pv

        reader = pv.get_reader(output)
        for t in reader.time_values:
            reader.set_active_time_value(t)
            assert reader.read()[0].n_points > 0
        return len(reader.time_values)
    files = sorted(folder.glob("*.obj"))
    for file in files:
        assert meshio.read(file).points.shape[0] > 0
    return len(files)


def hidden_leftovers(folder: Path) -> list[Path]:
    return [p for p in folder.rglob(".*") if p.is_file() or p.is_dir()]


@pytest.mark.usefixtures("rendering")
@pytest.mark.parametrize("kind", FORMATS)
def test_signals_at_random_moments_leave_valid_outputs(kind, tmp_path):
    rng = random.Random(f"pvcloth-{kind}")  # seeded: the same moments every run
    output = tmp_path / f"cloth.{kind}"
    subprocess.run(_command(output, 4), check=True, capture_output=True, timeout=300)
    complete = frames_in(output)  # the earlier, complete output
    for sig in SIGNALS:
        run = subprocess.Popen(_command(output, 400), stderr=subprocess.PIPE, text=True)
        time.sleep(rng.uniform(1.5, 4.0))  # start-up takes about 1.5 s
        run.send_signal(sig)
        _, err = run.communicate(timeout=120)
        assert "Traceback" not in err, err
        if sig == signal.SIGKILL:
            assert run.returncode == -signal.SIGKILL
            # the earlier output is untouched, whole and readable
            assert frames_in(output) == complete
            continue
        expected = 130 if sig == signal.SIGINT else 143
        assert run.returncode == expected, err
        assert err.startswith("pvcloth: interrupted" if expected == 130 else "pvcloth: terminated")
        if "no file written" not in err and "after 0 frame" not in err:
            complete = frames_in(output)  # the kept frames are readable
            assert complete >= 1
            said = re.search(r"stopped after (\d+) frame", err)
            if said and kind != "png":  # as many frames as the message says
                assert complete == int(said.group(1)), err
        assert hidden_leftovers(tmp_path) == [], err
    # a new run clears what the killed one left hidden, and completes
    subprocess.run(_command(output, 3), check=True, capture_output=True, timeout=300)
    assert frames_in(output) == (1 if kind == "png" else 3)
    assert hidden_leftovers(tmp_path) == []


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_a_signal_during_start_up_gives_a_short_message(sig):
    """Start-up (imports, compiling, the stable-step estimate) is interrupted
    cleanly too. A SIGTERM that comes before the command's handlers are in
    place (the interpreter still importing: on a loaded machine that took
    over 0.3 s, seen in a fresh clone's run) ends the process silently, as
    its default action does, which is as clean: what must never show is a
    traceback or more than a short message."""
    rng = random.Random(f"start-up-{sig}")
    for _ in range(4):
        run = subprocess.Popen(
            [PVCLOTH, "simulate", SCENE, "--seconds", "30", "--quiet"],
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(rng.uniform(0.3, 2.0))
        run.send_signal(sig)
        _, err = run.communicate(timeout=120)
        if sig == signal.SIGTERM and run.returncode == -signal.SIGTERM:
            assert err == "", err  # killed before the handlers: nothing said
            continue
        assert run.returncode == (130 if sig == signal.SIGINT else 143), err
        assert "Traceback" not in err and len(err.splitlines()) <= 2, err


def test_ctrl_c_stops_a_sweep_quietly_and_the_rerun_finishes_it(tmp_path):
    pytest.importorskip("dask.distributed")
    command = [PVCLOTH, "sweep", SCENE, "--set", "cloth.resolution=6",
               "--set", "solver.dt=1e-4:1e-3:24log", "--duration", "1.5", "--workers", "2",
               "-o", str(tmp_path), "--quiet"]  # fmt: skip
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # Signal once the first row is in: the cluster is up and about six
    # seconds of runs remain, so the signal does not race the sweep's end.
    table = tmp_path / "sweep.csv"
    deadline = time.monotonic() + 120
    while run.poll() is None and time.monotonic() < deadline:
        if table.exists() and len(table.read_text().splitlines()) >= 2:
            break
        time.sleep(0.05)
    run.send_signal(signal.SIGINT)
    out, err = run.communicate(timeout=120)
    if "wrote" in out:
        pytest.skip("the sweep finished before the signal came")
    assert run.returncode == 130 and err.strip() == "pvcloth: interrupted", err
    rows_kept = len(table.read_text().splitlines()) - 1
    assert 1 <= rows_kept < 24
    rerun = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert "wrote" in rerun.stdout and "(24 runs)" in rerun.stdout


def test_a_signal_python_cannot_raise_is_kept_quietly_for_check(capsys):
    # As when SIGTERM lands in an import lock's weakref callback: Python hands
    # the exception to sys.unraisablehook instead of raising it.
    import sys
    import types

    from pvcloth import signals

    with signals.handled():
        try:
            signals._handler(signal.SIGTERM, None)
        except signals.Terminated as error:
            sys.unraisablehook(
                types.SimpleNamespace(
                    exc_type=type(error), exc_value=error, exc_traceback=None,
                    err_msg=None, object=None,
                )
            )  # fmt: skip
        assert capsys.readouterr().err == ""
        with pytest.raises(signals.Terminated):
            signals.check()


def test_a_signal_during_an_import_is_held_until_the_import_ends(tmp_path, monkeypatch):
    # As when SIGTERM lands inside a compiled extension's set-up (cholespy's
    # nanobind enums): raised there, it aborted the process with a C++ error.
    from pvcloth import signals

    (tmp_path / "signalled_module.py").write_text(
        "import signal\nsignal.raise_signal(signal.SIGTERM)\nFINISHED = True\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    with signals.handled():
        with pytest.raises(signals.Terminated):
            import signalled_module  # noqa: F401
    assert sys.modules["signalled_module"].FINISHED  # the module's body ran to its end
    del sys.modules["signalled_module"]
