"""Colours: the palette everything is drawn in, and the fields a cloth can
be coloured by (:data:`FIELDS`, per point, with units) with the colour range
a field is shown over (:class:`ColorRange`, one that only grows). The
``error`` field needs a reference run beside the simulation
(:class:`pvcloth.physics.reference.FollowingReference`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pvcloth.errors import InputError

#: Front of the cloth (the side its grid normal points to) and back.
CLOTH_COLOR = "#c8553d"
CLOTH_BACK_COLOR = "#4f7fae"
BACK_COLOR = "#b7bfc9"
OBSTACLE_COLOR = "#8fa3b8"
#: The ground's checker: two close tones, so motion over it reads.
GROUND_COLORS = ("#ddd8cc", "#c9c3b5")


@dataclass(frozen=True)
class FieldStyle:
    """How a field is shown: scalar-bar title (with unit) and colour map."""

    title: str
    cmap: str
    #: Values the colour range always includes (1 for stretch: at rest).
    anchor: float = 0.0
    #: Colour range symmetric about the anchor (a diverging map).
    symmetric: bool = False


#: The fields a cloth can be coloured by (``--color``), all per point.
FIELDS = {
    "stretch": FieldStyle("stretch (length / rest length)", "coolwarm", 1.0, True),
    "speed": FieldStyle("speed (m/s)", "viridis"),
    "force": FieldStyle("spring force (N)", "magma"),
    "energy": FieldStyle("elastic energy (J/m^2)", "inferno"),
    "error": FieldStyle("distance from the reference (m)", "plasma"),
}


def check_field(name: str | None) -> str | None:
    """``name`` if it is a field of :data:`FIELDS` (or ``None``), else a
    clear :class:`~pvcloth.errors.InputError`."""
    if name is not None and name not in FIELDS:
        raise InputError("color", f"{name!r} is not a field; choose one of {', '.join(FIELDS)}")
    return name


def check_cmap(name: str | None) -> str | None:
    """``name`` if matplotlib knows the colour map (or ``None``), else a clear
    :class:`~pvcloth.errors.InputError`."""
    if name is None:
        return None
    import matplotlib

    if name not in matplotlib.colormaps:
        close = [known for known in sorted(matplotlib.colormaps) if known.lower() == name.lower()]
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(
            "cmap", f"{name!r} is not a colour map{hint}; e.g. viridis, coolwarm, magma, plasma"
        )
    return name


#: Scalar-bar titles of the point data on ``Simulation.mesh``.
FIELD_TITLES = {
    "velocity": "velocity (m/s)",
    "pinned": "pinned (1 = yes)",
    **{name: style.title for name, style in FIELDS.items()},
}


def nice_ceiling(value: float) -> float:
    """The smallest of 1, 2, 2.5, 5 times a power of ten that is at least
    ``value`` (> 0): colour-range ends that read well and change rarely (the
    ground's checker squares are sized by it too).

    Examples
    --------
    >>> from pvcloth.visual.colors import nice_ceiling
    >>> nice_ceiling(0.0123), nice_ceiling(3.0), nice_ceiling(7.0)
    (0.02, 5.0, 10.0)
    """
    power = 10.0 ** math.floor(math.log10(value))
    for step in (1.0, 2.0, 2.5, 5.0, 10.0):
        if value <= step * power * (1 + 1e-12):
            return step * power
    return 10.0 * power


#: The percentile of a frame's values (their distance from the field's
#: anchor) a colour range grows to: 5 % of the points must reach further
#: before the range grows.
RANGE_PERCENTILE = 95.0


class ColorRange:
    """A colour range that only grows: a colour means the same value from
    the frame it first appears on (a range refitted to every frame would
    let colours drift while the values stand still).

    The range is the anchor to a rounded-up reach of everything seen (for
    stretch, symmetric about 1); a fixed ``clim`` never changes. A frame's
    reach is the :data:`RANGE_PERCENTILE` th percentile of the points'
    distances from the anchor, not the farthest point's: one point's spike
    (a flag's corner whipping at 19 m/s while the rest moves under 3.4 m/s)
    would otherwise set the range for the whole movie and darken everything
    else. Values beyond the range take the colour map's end colour.

    Examples
    --------
    >>> from pvcloth.visual.colors import ColorRange
    >>> scale = ColorRange("stretch")
    >>> scale.update([0.999, 1.004])
    (0.995, 1.005)
    >>> scale.update([1.001])  # a calmer frame keeps the range
    (0.995, 1.005)
    >>> speeds = ColorRange("speed")
    >>> speeds.update([0.5] * 60 + [2.9] * 39 + [19.0])  # one point whips: not 20
    (0.0, 5.0)
    """

    def __init__(self, field: str, clim=None):
        self.style = FIELDS[field]
        self.fixed = None if clim is None else (float(clim[0]), float(clim[1]))
        self.span = 0.0

    def update(self, values) -> tuple[float, float]:
        if self.fixed is not None:
            return self.fixed
        values = np.asarray(values, dtype=float)
        finite = values[np.isfinite(values)]
        anchor = self.style.anchor
        distances = np.abs(finite - anchor)
        reach = float(np.percentile(distances, RANGE_PERCENTILE)) if distances.size else 0.0
        if reach > self.span:
            self.span = nice_ceiling(reach) if reach > 0 else 0.0
        span = self.span or (1e-3 if self.style.symmetric else 1e-6)
        if self.style.symmetric:
            return anchor - span, anchor + span
        low = min(anchor, float(finite.min(initial=anchor)))
        return low, low + span


def parse_clim(text: str) -> tuple[float, float]:
    """``"LOW,HIGH"`` -> ``(LOW, HIGH)`` with ``LOW < HIGH``, or a clear error."""
    try:
        low, high = (float(part) for part in text.split(","))
    except ValueError:
        raise InputError("clim", f"expected LOW,HIGH like 0.99,1.01, got {text!r}") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise InputError("clim", f"needs finite LOW < HIGH, got {text!r}")
    return low, high
