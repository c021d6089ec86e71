"""Scene description: what the user asked for, validated.

A scene is a tree of frozen dataclasses (:class:`Scene` here, its parts in
:mod:`pvcloth.scene.parts`). It can be built in Python or read from a TOML
file (:func:`pvcloth.scene.files.load_scene`); both routes go through the
same constructors, so both give equal, validated objects. Every bad key or
value raises :class:`~pvcloth.errors.SceneError` naming the key, the value
and what is allowed.
"""

from __future__ import annotations

import dataclasses
import html
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from pvcloth.errors import SceneError
from pvcloth.scene.materials import expand_material, preset
from pvcloth.scene.overrides import assign, expand
from pvcloth.scene.parts import (
    MAX_AIR_DAMPING,
    MAX_GRAVITY,
    MAX_THICKNESS_SHARE,
    CameraSpec,
    ClothSpec,
    ObstacleSpec,
    PinSpec,
    SelfCollisionSpec,
    SolverSpec,
    SpringSpec,
    SpringsSpec,
    WindSpec,
    _set,
    flat_gap,
)
from pvcloth.scene.validation import check_keys, real, sequence, vector


@dataclass(frozen=True)
class Scene:
    """A complete, validated description of a cloth simulation.

    Parameters
    ----------
    name : str
        Label used in messages and output names.
    cloth : ClothSpec
        The sheet.
    springs : SpringsSpec
        Spring families; any can be ``None``.
    pins : PinSpec
        Pinned points (default: the two top corners).
    solver : SolverSpec
        Integrator and time step.
    gravity : (float, float, float)
        Acceleration of gravity in m/s^2; z is up. ``(0, 0, 0)`` builds no
        gravity term.
    air_damping : float
        Linear drag on each point's absolute velocity, in 1/s (force
        ``-air_damping * m * v``). Zero builds no drag term.
    wind : WindSpec, optional
        Wind; ``None`` (the default) builds no wind term.
    obstacles : tuple of ObstacleSpec
        Spheres, boxes and ground planes; none by default (and then no
        collision code runs).
    self_collision : SelfCollisionSpec, optional
        Contact of the cloth with itself; ``None`` (the default) runs no
        self-collision code.
    camera : CameraSpec
        How movies look at the scene (no effect on the physics).

    Examples
    --------
    >>> from pvcloth import Scene, ClothSpec
    >>> scene = Scene(cloth=ClothSpec(resolution=(8, 8)))
    >>> scene == Scene.from_dict({"cloth": {"resolution": [8, 8]}})
    True
    """

    name: str = "scene"
    cloth: ClothSpec = field(default_factory=ClothSpec)
    springs: SpringsSpec = field(default_factory=SpringsSpec)
    pins: PinSpec = field(default_factory=PinSpec)
    solver: SolverSpec = field(default_factory=SolverSpec)
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    air_damping: float = 0.0
    wind: WindSpec | None = None
    obstacles: tuple[ObstacleSpec, ...] = ()
    self_collision: SelfCollisionSpec | None = None
    camera: CameraSpec = field(default_factory=CameraSpec)

    def __post_init__(self):
        if not isinstance(self.name, str):
            raise SceneError("name", f"expected text, got {type(self.name).__name__}")
        for f in fields(self):
            expected = _NESTED.get(f.name)
            if expected and not isinstance(getattr(self, f.name), expected):
                raise SceneError(
                    f.name,
                    f"expected a {expected.__name__}, got {type(getattr(self, f.name)).__name__}",
                )
        _set(
            self,
            "gravity",
            vector("gravity", self.gravity, 3, minimum=-MAX_GRAVITY, maximum=MAX_GRAVITY),
        )
        _set(
            self,
            "air_damping",
            real("air_damping", self.air_damping, minimum=0.0, maximum=MAX_AIR_DAMPING),
        )
        if self.wind is not None and not isinstance(self.wind, WindSpec):
            raise SceneError("wind", f"expected a WindSpec or None, got {type(self.wind).__name__}")
        obstacles = sequence("obstacles", self.obstacles)
        for n, obstacle in enumerate(obstacles):
            if not isinstance(obstacle, ObstacleSpec):
                raise SceneError(
                    f"obstacles[{n}]",
                    f"expected an ObstacleSpec, got {type(obstacle).__name__}",
                )
        _set(self, "obstacles", tuple(obstacles))
        self._check_self_collision()
        self._check_pins_fit()

    def _check_self_collision(self) -> None:
        contact = self.self_collision
        if contact is None:
            return
        if not isinstance(contact, SelfCollisionSpec):
            raise SceneError(
                "self_collision",
                f"expected a SelfCollisionSpec or None, got {type(contact).__name__}",
            )
        gap = flat_gap(self.cloth.size, self.cloth.resolution)
        if contact.thickness is not None and contact.thickness > MAX_THICKNESS_SHARE * gap:
            nx, ny = self.cloth.resolution
            raise SceneError(
                "self_collision.thickness",
                f"{contact.thickness:g} m is more than half the {gap:.3g} m gap between "
                f"neighbouring parts of this flat {nx} x {ny} cloth of {self.cloth.size[0]:g} x "
                f"{self.cloth.size[1]:g} m, so the flat cloth would push itself apart; "
                f"use at most {MAX_THICKNESS_SHARE * gap:.3g} m here, or fewer points",
            )

    def _check_pins_fit(self) -> None:
        nx, ny = self.cloth.resolution
        for n, (i, j) in enumerate(self.pins.points):
            if i >= nx or j >= ny:
                raise SceneError(
                    f"pins.points[{n}]",
                    f"({i}, {j}) is outside the {nx}x{ny} grid; "
                    f"i must be below {nx} and j below {ny}",
                )
        for n, k in enumerate(self.pins.indices):
            if k >= nx * ny:
                raise SceneError(
                    f"pins.indices[{n}]",
                    f"{k} is outside the grid of {nx * ny} points (0 to {nx * ny - 1})",
                )

    # -- construction from plain data ---------------------------------------

    @classmethod
    def from_dict(cls, data: Any, name: str | None = None) -> Scene:
        """Build a scene from nested dictionaries (as TOML or JSON give).

        Parameters
        ----------
        data : dict
            Keys as in the scene files, nested tables or dotted keys
            (``{"solver.dt": 1e-3}``, see :mod:`pvcloth.scene.overrides`);
            missing keys take their defaults.
        name : str, optional
            Overrides ``data["name"]``.

        Returns
        -------
        Scene
            The validated scene.

        Raises
        ------
        SceneError
            For any unknown key or bad value.
        """
        if isinstance(data, Mapping) and any(isinstance(k, str) and "." in k for k in data):
            data = expand(data)  # dotted keys, as --set and sweeps write them
        if isinstance(data, Mapping):
            data = expand_material(dict(data))  # cloth.material: a fabric preset
        data = dict(check_keys("", data, [f.name for f in fields(cls)]))
        if name is not None:
            data["name"] = name
        kwargs: dict[str, Any] = {}
        for key, value in data.items():
            if key == "springs":
                kwargs[key] = _springs_from_dict(value)
            elif key == "wind":
                kwargs[key] = _spec_from_dict(WindSpec, value, key)
            elif key == "self_collision":
                kwargs[key] = _spec_from_dict(SelfCollisionSpec, value, key)
            elif key == "obstacles":
                kwargs[key] = tuple(
                    _spec_from_dict(ObstacleSpec, item, f"obstacles[{n}]")
                    for n, item in enumerate(sequence(key, value))
                )
            elif key in _NESTED:
                kwargs[key] = _spec_from_dict(_NESTED[key], value, key)
            else:
                kwargs[key] = value
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dictionaries that :meth:`from_dict` turns back into this scene."""
        return _plain(dataclasses.asdict(self))

    def with_resolution(self, nx: int, ny: int | None = None) -> Scene:
        """The same scene on an ``nx`` x ``ny`` grid (``ny`` defaults to ``nx``);
        the per-cloth material makes it the same cloth."""
        cloth = dataclasses.replace(self.cloth, resolution=(nx, nx if ny is None else ny))
        return dataclasses.replace(self, cloth=cloth)

    def replace(self, **changes) -> Scene:
        """A copy with top-level fields replaced (validated again)."""
        return dataclasses.replace(self, **changes)

    def with_overrides(self, changes: Mapping[str, Any]) -> Scene:
        """A copy with dotted keys set, validated like a scene file
        (the dialect of :mod:`pvcloth.scene.overrides`).

        Examples
        --------
        >>> from pvcloth import Scene
        >>> scene = Scene().with_overrides({"solver.dt": 1e-3, "springs.shear": 50.0})
        >>> scene.solver.dt, scene.springs.shear.stiffness
        (0.001, 50.0)
        """
        if not changes:
            return self
        if "cloth.material" in changes:  # the preset first, then what else is given
            size = changes.get("cloth.size", self.cloth.size)
            rest = {k: v for k, v in changes.items() if k != "cloth.material"}
            values = preset(changes["cloth.material"], tuple(size))
            # a family the preset leaves out stays when the changes give it
            values = {
                k: v
                for k, v in values.items()
                if v is not None or not any(key.startswith(f"{k}.") or key == k for key in rest)
            }
            changes = {**values, **rest}
        data = self.to_dict()
        for key, value in changes.items():
            assign(data, key, value)
        return Scene.from_dict(data)

    # -- how it reads in a terminal and a notebook ---------------------------

    def summary(self) -> list[tuple[str, str]]:
        """``(topic, text)`` rows that say what the scene asks for, in units.

        Examples
        --------
        >>> from pvcloth import Scene
        >>> dict(Scene().summary())["solver"]
        'symplectic_euler, dt automatic (at most half the stable step), stability refuse'
        """
        cloth, solver = self.cloth, self.solver
        springs = [
            f"{f.name} {spec.stiffness:g} N/m, damping {spec.damping:g} N s/m"
            for f in fields(self.springs)
            if (spec := getattr(self.springs, f.name)) is not None
        ]
        pins = [
            f"{label} {', '.join(str(v) for v in values)}"
            for label, values in (
                ("corners", self.pins.corners),
                ("edges", self.pins.edges),
                ("points", self.pins.points),
                ("indices", self.pins.indices),
            )
            if values
        ]
        step = (
            "automatic (at most half the stable step)" if solver.dt is None else f"{solver.dt:g} s"
        )
        wind = "none"
        if self.wind is not None:
            wind = f"{_vec(self.wind.velocity)} m/s, drag {self.wind.drag:g}"
            wind += f", lift {self.wind.lift:g}" if self.wind.lift else ""
            wind += f", gusts ±{self.wind.gust:.0%}" if self.wind.gust else ""
        return [
            (
                "cloth",
                f"{cloth.resolution[0]} x {cloth.resolution[1]} points, {cloth.size[0]:g} x "
                f"{cloth.size[1]:g} m, {cloth.mass:g} kg, {cloth.orientation} "
                f"at {_vec(cloth.center)} m",
            ),
            ("springs", "; ".join(springs) or "none"),
            ("pins", "; ".join(pins) or "none"),
            (
                "solver",
                f"{solver.method}, dt {step}, stability {solver.stability}"
                + (f", {solver.iterations} iterations" if solver.iterations else "")
                + (f", {solver.accelerator} accelerator" if solver.accelerator else ""),
            ),
            ("gravity", f"{_vec(self.gravity)} m/s^2, air damping {self.air_damping:g} 1/s"),
            ("wind", wind),
            ("obstacles", "; ".join(_obstacle_text(o) for o in self.obstacles) or "none"),
            ("self-contact", self._self_collision_text()),
        ]

    def _self_collision_text(self) -> str:
        contact = self.self_collision
        if contact is None:
            return "off"
        given = "" if contact.thickness is not None else " (0.3 of the grid's gap)"
        return (
            f"thickness {contact.thickness_for(self.cloth):.3g} m{given}, "
            f"friction {contact.friction:g}" + (", layers in the solve" if contact.in_solve else "")
        )

    def __repr__(self) -> str:
        rows = "".join(f"\n  {topic:<10} {text}" for topic, text in self.summary())
        return f"Scene({self.name!r}){rows}"

    def _repr_html_(self) -> str:
        return html_table(f"Scene {self.name!r}", self.summary())


def _obstacle_text(obstacle: ObstacleSpec) -> str:
    where = f"at {_vec(obstacle.center)} m" + (" (moving)" if obstacle.path else "")
    if obstacle.type == "sphere":
        return f"sphere of radius {obstacle.radius:g} m {where}"
    if obstacle.type == "box":
        return f"box {_vec(obstacle.size)} m {where}"
    return f"ground through {_vec(obstacle.center)} m, normal {_vec(obstacle.normal)}"


def _vec(values) -> str:
    return "(" + ", ".join(f"{v:g}" for v in values) + ")"


def html_table(title: str, rows) -> str:
    """A small HTML table for notebooks (the escaping is html.escape's)."""
    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
        f"<td style='text-align:left'>{html.escape(v)}</td></tr>"
        for k, v in rows
    )
    return f"<table><caption><b>{html.escape(title)}</b></caption>{body}</table>"


_NESTED = {
    "cloth": ClothSpec,
    "springs": SpringsSpec,
    "pins": PinSpec,
    "solver": SolverSpec,
    "camera": CameraSpec,
}


def _spec_from_dict(cls, data, path: str):
    check_keys(path, data, [f.name for f in fields(cls)])
    for f in fields(cls):
        required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        if required and f.name not in data:
            raise SceneError(f"{path}.{f.name}", "is required here")
    try:
        return cls(**data)
    except SceneError as error:
        raise error.under(path) from None


def _springs_from_dict(data) -> SpringsSpec:
    # A family missing from the table is not built; the table itself being
    # absent keeps the defaults (handled by the caller never getting here).
    check_keys("springs", data, [f.name for f in fields(SpringsSpec)])
    families = {}
    for f in fields(SpringsSpec):
        value = data.get(f.name)
        families[f.name] = (
            None if value is None else _spec_from_dict(SpringSpec, value, f"springs.{f.name}")
        )
    return SpringsSpec(**families)


def _plain(value):
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value
