"""The one protocol every output is written by (pvcloth.io.files.Staged):
published whole with the umask's mode, removed when never published, the
temporaries of dead writers cleaned up and those of live ones kept."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from pvcloth.io.files import Staged, atomic_write


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def dead_pid() -> int:
    """The id of a process that has exited (and been reaped)."""
    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], stdout=-1)
    return int(child.stdout)


def test_publish_replaces_the_file_whole_with_the_umask_mode(tmp_path, umask_022):
    target = tmp_path / "run.npz"
    target.write_text("old")
    with Staged(target) as staged:
        assert staged.temporary.parent == tmp_path
        assert staged.temporary.name.startswith(f".run.{os.getpid()}.")
        assert staged.temporary.suffix == ".npz"
        staged.temporary.write_text("new")
        assert target.read_text() == "old"  # nothing shows until published
        staged.publish()
    assert target.read_text() == "new"
    assert target.stat().st_mode & 0o777 == 0o644  # not mkstemp's 0600
    assert [p.name for p in tmp_path.iterdir()] == ["run.npz"]


def test_an_unpublished_temporary_is_removed_and_the_old_output_kept(tmp_path):
    target = tmp_path / "movie.gif"
    target.write_text("old")
    with pytest.raises(RuntimeError), Staged(target) as staged:
        staged.temporary.write_text("half")
        raise RuntimeError("the writer failed")
    with Staged(tmp_path / "frames", folder=True) as staged:
        (staged.temporary / "0.vtu").write_text("a frame")
    assert [p.name for p in tmp_path.iterdir()] == ["movie.gif"]
    assert target.read_text() == "old"

    def crash(temporary):
        raise OSError("disk full")

    with pytest.raises(OSError):
        atomic_write(target, crash)
    assert [p.name for p in tmp_path.iterdir()] == ["movie.gif"]


def test_orphans_of_dead_writers_are_removed_and_live_ones_kept(tmp_path):
    dead, alive = dead_pid(), os.getpid()
    orphans = [tmp_path / f".cloth.{dead}.abc123.pvd", tmp_path / f".cloth_vtu.{dead}.k2j3h4"]
    orphans[0].write_text("killed while writing")
    orphans[1].mkdir()
    (orphans[1] / "cloth_00000.vtu").write_text("a frame")
    live = tmp_path / f".cloth.{alive}.xyz789.pvd"
    live.write_text("still writing")
    other = tmp_path / f".other.{dead}.abc123.pvd"  # another output's: not ours to judge
    other.write_text("")
    with Staged(tmp_path / "cloth.pvd"), Staged(tmp_path / "cloth_vtu", folder=True):
        pass
    assert not any(orphan.exists() for orphan in orphans)
    assert live.exists() and other.exists()


def test_a_folder_publish_replaces_the_old_folder_wholly(tmp_path, umask_022):
    target = tmp_path / "cloth_obj"
    target.mkdir()
    for n in range(3):
        (target / f"cloth_{n:05d}.obj").write_text("old")
    with Staged(target, folder=True) as staged:
        (staged.temporary / "cloth_00000.obj").write_text("new")
        staged.publish()
    assert [p.name for p in target.iterdir()] == ["cloth_00000.obj"]  # no old frame left
    assert (target / "cloth_00000.obj").read_text() == "new"
    assert target.stat().st_mode & 0o777 == 0o755  # not mkdtemp's 0700
    assert [p.name for p in tmp_path.iterdir()] == ["cloth_obj"]  # nothing set aside remains
