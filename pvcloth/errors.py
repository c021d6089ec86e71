"""The exceptions pvcloth raises on purpose.

Every error a user can cause by what they ask for is a :class:`PvclothError`,
so a caller can catch the project's errors without catching NumPy's.
"""

from __future__ import annotations


class PvclothError(Exception):
    """Base class of every error pvcloth raises on purpose."""


class SceneError(PvclothError, ValueError):
    """A scene description holds a key or value that is not allowed.

    Parameters
    ----------
    key : str
        Dotted path of the offending key, e.g. ``"cloth.resolution"``.
    message : str
        What is wrong and what is allowed.
    """

    def __init__(self, key: str, message: str):
        self.key = key
        self.message = message
        super().__init__(f"{key}: {message}" if key else message)

    def under(self, prefix: str) -> SceneError:
        """Return the same error with ``prefix`` put in front of its key."""
        key = f"{prefix}.{self.key}" if self.key else prefix
        return SceneError(key, self.message)


class DivergenceError(PvclothError, FloatingPointError):
    """The simulation produced non-finite or exploding values.

    The simulation's state is left at the last good step, so whatever was
    written from it so far stays valid.
    """
