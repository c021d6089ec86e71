"""Dotted scene keys: the one way to change a scene by name.

``solver.dt = 1e-3`` means ``{"solver": {"dt": 1e-3}}``. The same keys and
values work everywhere a scene is changed by name: ``pvcloth ... --set
KEY=VALUE`` on the command line, sweeps (``pvcloth sweep --set
KEY=VALUES``), :meth:`Scene.from_dict` (which accepts dotted keys beside
nested tables), :meth:`Scene.with_overrides` and live edits
(:meth:`pvcloth.Simulation.update`).

Two shorthands, for the settings changed most often:

- a spring family's name sets its stiffness: ``springs.structural = 1e3``
  is ``springs.structural.stiffness = 1e3``;
- ``cloth.resolution = 32`` is ``cloth.resolution = [32, 32]``.

Values given as text (from a command line) are read as TOML values:
``1e-3``, ``true``, ``[0.0, 0.0, -9.81]``, ``"rk4"``; a bare word such as
``rk4`` is text, and ``.5`` a number.
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping
from typing import Any

from pvcloth.errors import InputError, SceneError


def parse_value(text: str) -> Any:
    """A value written on a command line, read as TOML reads a value.

    Examples
    --------
    >>> parse_value("1e-3"), parse_value("true"), parse_value("[1, 2]"), parse_value("rk4")
    (0.001, True, [1, 2], 'rk4')
    """
    text = text.strip()
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        pass
    try:
        return float(text)  # what TOML does not take but Python does: .5, 1.
    except ValueError:
        return text  # a bare word: text


def parse_assignment(item: str, option: str = "--set") -> tuple[str, str]:
    """``"KEY=VALUE"`` split into the key and the (unparsed) value text.

    Raises
    ------
    InputError
        If there is no ``=`` or no key.
    """
    key, sep, value = item.partition("=")
    if not sep or not key.strip():
        raise InputError(option, f"expected KEY=VALUE like solver.dt=1e-3, got {item!r}")
    return key.strip(), value


def assign(data: dict, key: str, value: Any) -> None:
    """Set the dotted ``key`` to ``value`` in nested scene data, in place
    (with the two shorthands of this module's docstring).

    Examples
    --------
    >>> data = {"springs": {"shear": {"stiffness": 1.0, "damping": 0.1}}}
    >>> assign(data, "springs.shear", 5.0); assign(data, "solver.dt", 1e-3)
    >>> data
    {'springs': {'shear': {'stiffness': 5.0, 'damping': 0.1}}, 'solver': {'dt': 0.001}}
    """
    parts = key.split(".")
    if not all(parts):
        raise SceneError(key, "a dotted key needs a name between every two dots")
    node = data
    for depth, part in enumerate(parts[:-1]):
        child = node.setdefault(part, {})
        if not isinstance(child, dict):
            raise SceneError(".".join(parts[: depth + 1]), "is a value, not a table")
        node = child
    last = parts[-1]
    if parts[0] == "springs" and len(parts) == 2 and not isinstance(value, (dict, type(None))):
        family = node.get(last)
        node[last] = {**(family if isinstance(family, dict) else {}), "stiffness": value}
    elif key == "cloth.resolution" and not isinstance(value, (list, tuple)):
        node[last] = [value, value]
    else:
        node[last] = value


def expand(data: Mapping[str, Any]) -> dict[str, Any]:
    """Nested scene data with every dotted top-level key of ``data`` set by
    :func:`assign` (nested tables are taken as they are, first)."""
    nested = {key: copy.deepcopy(value) for key, value in data.items() if "." not in key}
    for key, value in data.items():
        if "." in key:
            assign(nested, key, value)
    return nested
