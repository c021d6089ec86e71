"""Files that stay valid whatever happens: one way to write every output.

An output (a checkpoint, a screenshot, a movie, an export's files and
frames folders) is written under a hidden temporary name beside its
destination and moved into place whole (:class:`Staged`), so a reader never
sees half of it and a writer killed midway leaves the earlier output as it
was. A temporary is named ``.STEM.PID.xxxxxxxxSUFFIX`` after its
destination and its writer's process id: the next writer of that
destination removes the ones whose writer died
(:func:`remove_orphaned_temporaries`), so they do not pile up.
"""

from __future__ import annotations

import glob
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path


class Staged:
    """An output written under a hidden temporary name beside ``path`` and
    moved into place whole by :meth:`publish`.

    Making one first removes the temporaries of ``path`` left by writers
    that died. Used as a context manager, it removes its temporary on
    leaving unless it was published: an output that fails leaves nothing.

    Parameters
    ----------
    path : path
        Where the output goes.
    folder : bool
        Stage a folder, to be filled with files, instead of a file.

    Attributes
    ----------
    path : Path
        The destination.
    temporary : Path
        Where to write: an empty file (or folder) named
        ``.STEM.PID.xxxxxxxxSUFFIX`` beside ``path``, with the suffix of
        ``path`` so that writers choosing a format by it choose the right
        one.
    published : bool
        Whether :meth:`publish` has moved it into place.

    Examples
    --------
    >>> from pathlib import Path
    >>> from pvcloth.io.files import Staged
    >>> with Staged(Path("notes.txt")) as staged:
    ...     _ = staged.temporary.write_text("all or nothing")
    ...     staged.publish()
    >>> Path("notes.txt").read_text()
    'all or nothing'
    >>> with Staged(Path("frames"), folder=True) as staged:
    ...     _ = (staged.temporary / "0.txt").write_text("a frame")  # never published
    >>> sorted(p.name for p in Path().iterdir())
    ['notes.txt']
    """

    def __init__(self, path: str | os.PathLike, *, folder: bool = False):
        self.path = Path(path)
        self.folder = folder
        self.published = False
        remove_orphaned_temporaries(self.path)
        where = dict(dir=self.path.parent, prefix=f".{self.path.stem}.{os.getpid()}.")
        if folder:
            self.temporary = Path(tempfile.mkdtemp(suffix=self.path.suffix, **where))
        else:
            handle, name = tempfile.mkstemp(suffix=self.path.suffix, **where)
            os.close(handle)
            self.temporary = Path(name)

    def publish(self) -> None:
        """Move the temporary onto ``path``, replacing what is there.

        A file is renamed over the old one in one step: ``path`` is always
        the old file or the new one, never neither. A folder cannot be
        renamed over a folder with files in it, so the old one is renamed
        aside first and removed after; a writer killed between the two
        renames leaves no folder at ``path`` and the old one hidden, which
        the next writer removes. Either way nothing of the old output stays
        mixed with the new (a re-export with fewer frames keeps none of the
        old frames).
        """
        # Give the output the mode a plain open() or mkdir() would (the
        # umask's), so others can read what a user writes for them.
        os.chmod(self.temporary, (0o777 if self.folder else 0o666) & ~_umask())
        if self.folder and os.path.lexists(self.path):
            aside = self.temporary.with_name(_aside_name(self.temporary, self.path.suffix))
            os.replace(self.path, aside)
            os.replace(self.temporary, self.path)
            _remove(aside)
        else:
            os.replace(self.temporary, self.path)
        self.published = True

    def discard(self) -> None:
        """Remove the temporary unless it was published."""
        if not self.published:
            _remove(self.temporary)

    def __enter__(self) -> Staged:
        return self

    def __exit__(self, *exc) -> None:
        self.discard()


def atomic_write(path: Path, write: Callable[[str], None]) -> None:
    """Call ``write(temporary_path)`` and move the result onto ``path``
    (:class:`Staged`); if ``write`` fails, ``path`` is left as it was."""
    with Staged(path) as staged:
        write(str(staged.temporary))
        staged.publish()


def remove_orphaned_temporaries(path: Path) -> list[Path]:
    """Delete the hidden temporaries of ``path`` (``.STEM.PID.*SUFFIX``,
    files or folders) whose writing process no longer runs; return what was
    deleted. Those of running processes are kept: they may be writing."""
    removed = []
    for candidate in path.parent.glob(f".{glob.escape(path.stem)}.*{glob.escape(path.suffix)}"):
        pid = candidate.name[len(path.stem) + 2 :].split(".", 1)[0]
        if pid.isdigit() and not _running(int(pid)):
            _remove(candidate)
            removed.append(candidate)
    return removed


def _aside_name(temporary: Path, suffix: str) -> str:
    """Where a replaced folder waits to be removed: the temporary's name
    with ``.aside`` before the suffix. It is free (mkstemp's random part
    has no dot) and, should the writer die, an orphan of the same
    destination."""
    stem = temporary.name[: len(temporary.name) - len(suffix)]
    return f"{stem}.aside{suffix}"


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def _umask() -> int:
    """The process's file-creation mask (read by setting it and back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True
