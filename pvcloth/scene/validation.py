"""Small checkers that turn user values into validated Python values.

Each checker names the key it was given, the bad value and what is allowed,
and raises :class:`~pvcloth.errors.SceneError` (or, for arguments that are
not scene keys, the error class given as ``error``, e.g.
:class:`~pvcloth.errors.InputError`). They never let a NumPy or
``TypeError`` traceback through.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable, Mapping, Sequence
from numbers import Integral, Real

from pvcloth.errors import InputError, SceneError


def describe(value: object) -> str:
    """Short ``repr`` of ``value`` with its type, cut if it is long."""
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def check_keys(key: str, data: object, allowed: Iterable[str]) -> Mapping:
    """Check that ``data`` is a mapping whose keys are all in ``allowed``."""
    allowed = list(allowed)
    if not isinstance(data, Mapping):
        raise SceneError(key, f"expected a table of settings, got {describe(data)}")
    for name in data:
        if not isinstance(name, str) or name not in allowed:
            hint = ""
            if isinstance(name, str):
                close = difflib.get_close_matches(name, allowed, n=1)
                if close:
                    hint = f" (did you mean {close[0]!r}?)"
            where = f"{key}.{name}" if key else str(name)
            raise SceneError(
                where, f"unknown key{hint}. Allowed here: {', '.join(sorted(allowed))}"
            )
    return data


def real(
    key: str,
    value: object,
    *,
    minimum: float | None = None,
    exclusive: bool = False,
    maximum: float | None = None,
    error: type[InputError] = SceneError,
) -> float:
    """A finite real number, optionally bounded below (and above)."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise error(key, f"expected a number, got {describe(value)}")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond any float, e.g. 10**400
        raise error(key, f"expected a finite number, got {describe(value)}") from None
    if not math.isfinite(number):
        raise error(key, f"expected a finite number, got {value!r}")
    if minimum is not None:
        if exclusive and not number > minimum:
            raise error(key, f"must be greater than {minimum:g}, got {value!r}")
        if not exclusive and not number >= minimum:
            raise error(key, f"must be at least {minimum:g}, got {value!r}")
    if maximum is not None and number > maximum:
        raise error(key, f"must be at most {maximum:g}, got {value!r}")
    return number


def integer(
    key: str, value: object, *, minimum: int, maximum: int, error: type[InputError] = SceneError
) -> int:
    """An integer within ``[minimum, maximum]``."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise error(key, f"expected a whole number, got {describe(value)}")
    number = int(value)
    if not minimum <= number <= maximum:
        raise error(key, f"must be between {minimum} and {maximum}, got {number}")
    return number


def sequence(key: str, value: object, length: int | None = None) -> Sequence:
    """A list or tuple (not a string), of ``length`` items if given."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
        raise SceneError(key, f"expected a list, got {describe(value)}")
    if length is not None and len(value) != length:
        raise SceneError(key, f"expected {length} items, got {len(value)}")
    return value


def vector(key: str, value: object, length: int, **bounds) -> tuple[float, ...]:
    """A list of ``length`` finite numbers, each checked by :func:`real`."""
    items = sequence(key, value, length)
    return tuple(real(f"{key}[{n}]", item, **bounds) for n, item in enumerate(items))


def choice(
    key: str, value: object, allowed: Sequence[str], *, error: type[InputError] = SceneError
) -> str:
    """One of the strings in ``allowed``, with a did-you-mean hint."""
    if not isinstance(value, str):
        raise error(key, f"expected one of {', '.join(allowed)}; got {describe(value)}")
    if value not in allowed:
        close = difflib.get_close_matches(value, allowed, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise error(key, f"{value!r} is not allowed{hint}. Choose one of: {', '.join(allowed)}")
    return value
