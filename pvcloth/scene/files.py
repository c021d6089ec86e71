"""Scene files: TOML read into a :class:`~pvcloth.scene.spec.Scene`, and
every error named with the file and the line that set the key."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from pvcloth.errors import SceneError
from pvcloth.scene.spec import Scene


def load_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file.

    Parameters
    ----------
    path : str or Path
        A ``.toml`` file; the scene's name defaults to the file's stem.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        If the file cannot be read, is not valid TOML, or describes a bad scene.

    Examples
    --------
    >>> import pvcloth
    >>> from pathlib import Path
    >>> _ = Path("small.toml").write_text("cloth.resolution = [8, 8]")
    >>> scene = pvcloth.load_scene("small.toml")
    >>> scene.name, scene.cloth.resolution
    ('small', (8, 8))

    The bundled scenes are in the repository's ``data/scenes`` folder, e.g.
    ``pvcloth.load_scene("data/scenes/hanging.toml")``.
    """
    try:
        path = Path(path)
        text = path.read_text(encoding="utf-8")
    except TypeError:
        raise SceneError("", f"expected a file path, got {path!r}") from None
    except UnicodeDecodeError as error:
        raise SceneError(
            "", f"{path} is not a text file in UTF-8 (byte {error.start}): a scene is TOML text"
        ) from None
    except ValueError as error:  # e.g. a NUL character in the path
        raise SceneError("", f"cannot read scene file {str(path)!r}: {error}") from None
    except OSError as error:
        raise SceneError("", f"cannot read scene file {str(path)!r}: {error.strerror}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError("", f"{path}: not valid TOML: {error}") from None
    except RecursionError:
        raise SceneError("", f"{path}: its tables or lists are nested too deeply") from None
    if not data:
        raise SceneError(
            "",
            f"{path} sets nothing: a scene file needs at least one key, e.g. "
            f"cloth.resolution = [16, 16] (the bundled scenes are examples)",
        )
    data.setdefault("name", path.stem)
    try:
        return Scene.from_dict(data)
    except SceneError as error:
        line = _line_setting(text, error.key)
        where = f"{path}, line {line}" if line else str(path)
        raise SceneError(error.key, error.message, where) from None


def _line_setting(text: str, key: str) -> int | None:
    """The line (from 1) of a TOML text that sets the dotted ``key`` (list
    indices dropped), or ``None`` unless exactly one line does. Tables are
    followed by their ``[headers]``; an inline table counts as the line of
    the key it is assigned to."""
    wanted = re.sub(r"\[\d+\]", "", key)
    if not wanted:
        return None
    table, lines = "", []
    for number, line in enumerate(text.splitlines(), 1):
        code = line.split("#", 1)[0].strip()  # a '#' inside a string ends the search early
        # A table name starts with a letter, _ or a quote: a row of a list
        # written over several lines ("[1, 0, 0, 1]") is not a header.
        header = re.fullmatch(r"\[\[?\s*([A-Za-z_\"][\w.\-\" ]*)\]\]?", code)
        if header:
            table = header.group(1).replace('"', "").replace(" ", "")
            lines += [number] if table == wanted else []
            continue
        assigned = re.match(r"([\w.\-\" ]+?)\s*=", code)
        if assigned:
            name = assigned.group(1).replace('"', "").replace(" ", "")
            full = f"{table}.{name}" if table else name
            if full == wanted or wanted.startswith(full + "."):
                lines.append(number)
    return lines[0] if len(lines) == 1 else None
