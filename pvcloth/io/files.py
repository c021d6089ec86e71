"""Files that stay valid whatever happens: written under a temporary name
and renamed into place, with the temporaries of killed writers cleaned up."""

from __future__ import annotations

import glob
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path


def atomic_write(path: Path, write: Callable[[str], None]) -> None:
    """Call ``write(temporary_path)`` and rename the result onto ``path``.

    The temporary file is hidden beside ``path`` and named with this
    process's id; temporaries left there by a process that died (a killed
    save) are removed first, so they do not pile up."""
    remove_orphaned_temporaries(path)
    handle, temporary = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.stem}.{os.getpid()}.", suffix=path.suffix
    )
    os.close(handle)
    try:
        write(temporary)
        # mkstemp makes the file 0600; give it the mode a plain open() would
        # (the umask's), so others can read what a user writes for them.
        os.chmod(temporary, 0o666 & ~current_umask())
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def current_umask() -> int:
    """The process's file-creation mask (read by setting it and back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def remove_orphaned_temporaries(path: Path) -> list[Path]:
    """Delete the hidden temporaries of ``path`` (``.STEM.PID.*SUFFIX``) whose
    writing process no longer runs; return what was deleted."""
    removed = []
    for candidate in path.parent.glob(f".{glob.escape(path.stem)}.*{glob.escape(path.suffix)}"):
        pid = candidate.name[len(path.stem) + 2 :].split(".", 1)[0]
        if pid.isdigit() and not _running(int(pid)):
            if candidate.is_dir():  # an export's staging folder
                shutil.rmtree(candidate, ignore_errors=True)
            else:
                candidate.unlink(missing_ok=True)
            removed.append(candidate)
    return removed


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        return True
    return True
