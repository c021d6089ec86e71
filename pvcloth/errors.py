"""The exceptions pvcloth raises on purpose.

Every error a user can cause by what they ask for is a :class:`PvclothError`,
so a caller can catch the project's errors without catching NumPy's. All of
them live here and are importable from ``pvcloth``.
"""

from __future__ import annotations

from pathlib import Path


class PvclothError(Exception):
    """Base class of every error pvcloth raises on purpose."""


class InputError(PvclothError, ValueError):
    """An argument that is not allowed: a value passed to a function or
    given on the command line (a frame count, a picture size, a point
    index...). Bad scene keys are the subclass :class:`SceneError`.

    Parameters
    ----------
    key : str
        Name of the offending argument or option, e.g. ``"frames"``.
    message : str
        What is wrong and what is allowed.
    """

    def __init__(self, key: str, message: str):
        self.key = key
        self.message = message
        super().__init__(f"{key}: {message}" if key else message)


class SceneError(InputError):
    """A scene description holds a key or value that is not allowed.

    Parameters
    ----------
    key : str
        Dotted path of the offending key, e.g. ``"cloth.resolution"``.
    message : str
        What is wrong and what is allowed.
    where : str, optional
        The file (and line) the key was read from, put in front of the
        message, e.g. ``"scene.toml, line 3"``.
    """

    def __init__(self, key: str, message: str, where: str = ""):
        super().__init__(key, message)
        self.where = where
        if where:
            self.args = (f"{where}: {self.args[0]}",)

    def under(self, prefix: str) -> SceneError:
        """Return the same error with ``prefix`` put in front of its key."""
        key = f"{prefix}.{self.key}" if self.key else prefix
        return SceneError(key, self.message, self.where)


class DivergenceError(PvclothError, FloatingPointError):
    """The simulation produced non-finite or exploding values.

    The simulation's state is left at the last good step, so whatever was
    written from it so far stays valid.
    """


class MovieInterrupted(PvclothError):
    """A movie stopped early. ``path`` is the valid partial movie, or ``None``
    if no frame was finished and nothing was written."""

    def __init__(self, message: str, path: Path | None, frames: int):
        super().__init__(message)
        self.path = path
        self.frames = frames


class ExportInterrupted(PvclothError):
    """An export stopped early; ``frames`` were written and stay readable."""

    def __init__(self, message: str, frames: int):
        super().__init__(message)
        self.frames = frames


class CheckpointError(PvclothError):
    """A checkpoint file is missing, damaged, foreign or inconsistent."""


class SweepError(PvclothError):
    """A sweep that cannot run as asked (a setting with no values, a bad
    range, Dask missing...)."""


class DisplayError(PvclothError):
    """There is no screen to open the interactive window on."""
