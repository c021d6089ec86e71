"""``.. scene-keys::``: the reference of every scene key, made from the spec
classes' own docstrings, so that it is written once (in the code).

Each TOML table of a scene file becomes a section with one row per key: its
name, default and meaning, read from the class's numpydoc ``Parameters``.
"""

from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.statemachine import StringList
from numpydoc.docscrape import NumpyDocString
from sphinx.util.docutils import SphinxDirective

#: (TOML table, spec class name, a sentence on the table).
TABLES = [
    ("[cloth]", "ClothSpec", "The sheet: size, resolution, mass, material and where it starts."),
    (
        "[springs.structural], [springs.shear], [springs.bending]",
        "SpringSpec",
        "One family of springs each; leave a table out to keep the family's default, "
        "set ``springs.bending = false`` (or ``None`` from Python) to build none.",
    ),
    ("[pins]", "PinSpec", "Which points are held."),
    ("[solver]", "SolverSpec", "Integrator, step and how the step is checked."),
    ("[wind]", "WindSpec", "Air moving past the cloth (left out: no wind term is built)."),
    ("[camera]", "CameraSpec", "How movies and the window look at the cloth."),
    ("[[obstacles]]", "ObstacleSpec", "Spheres, boxes and ground planes, one table each."),
    (
        "[self_collision]",
        "SelfCollisionSpec",
        "The cloth kept from passing through itself (left out: no such code runs).",
    ),
]


#: The head of every key table: a three-column list table.
TABLE_HEAD = [
    ".. list-table::",
    "   :header-rows: 1",
    "   :widths: 20 20 60",
    "",
    "   * - key",
    "     - default",
    "     - meaning",
]


def _default(field: dataclasses.Field) -> str:
    if field.default is not dataclasses.MISSING:
        return repr(field.default)
    if field.default_factory is not dataclasses.MISSING:
        return repr(field.default_factory())
    return "(required)"


def _flat(lines: list[str]) -> str:
    return " ".join(line.strip() for line in lines if line.strip())


def scene_keys_rst() -> list[str]:
    """The reference as reStructuredText lines."""
    import pvcloth
    from pvcloth.scene import parts, spec

    lines: list[str] = []
    top = NumpyDocString(spec.Scene.__doc__ or "")
    top_fields = {f.name: f for f in dataclasses.fields(spec.Scene)}
    lines += ["Top-level keys", "--------------", "", *TABLE_HEAD]
    for parameter in top["Parameters"]:
        field = top_fields.get(parameter.name)
        if field is None or "Spec" in parameter.type:
            continue
        lines += [
            f"   * - ``{parameter.name}``",
            f"     - ``{_default(field)}``",
            f"     - {_flat(parameter.desc)}",
        ]
    lines.append("")
    for table, name, about in TABLES:
        cls = getattr(parts, name)
        doc = NumpyDocString(cls.__doc__ or "")
        defaults = {f.name: f for f in dataclasses.fields(cls)}
        lines += [table, "-" * len(table), "", about, "", f"(:class:`pvcloth.{name}`)", ""]
        lines += TABLE_HEAD
        for parameter in doc["Parameters"]:
            for key in parameter.name.split(","):
                key = key.strip()
                field = defaults.get(key)
                default = _default(field) if field is not None else ""
                lines += [
                    f"   * - ``{key}``",
                    f"     - ``{default}``" if default else "     -",
                    f"     - {_flat(parameter.desc)}",
                ]
        lines.append("")
    del pvcloth
    return lines


class SceneKeys(SphinxDirective):
    has_content = False

    def run(self) -> list[nodes.Node]:
        container = nodes.section()
        container.document = self.state.document
        self.state.nested_parse(StringList(scene_keys_rst(), "scene-keys"), 0, container)
        return container.children


def setup(app):
    app.add_directive("scene-keys", SceneKeys)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
