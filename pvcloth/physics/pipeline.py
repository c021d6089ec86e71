"""What happens to a step after the integrator made it: an ordered list of
operators, built once from what the scene asks for.

Before the integrator, :class:`PinVelocities` (always) gives the pinned
points the velocity that lands them on their targets. The integrator moves
every point as if nothing were in the way. Then, in this order:

1. :class:`ObstacleContacts` (only with obstacles): swept collision with
   each obstacle, points pushed out with friction;
2. :class:`PinLanding` (always): pinned points put exactly on their targets
   at the velocity that took them there;
3. :class:`SelfContact` (only with ``[self_collision]``): the cloth kept
   from passing through itself, after the pins land (they move as told, the
   rest keeps clear), with the points an obstacle touched held;
4. :class:`Guard` (always): the largest speed and whether every value is
   finite, which the simulation turns into a :class:`~pvcloth.DivergenceError`.

Each operator writes its report into :attr:`Step.reports` under its name. A
scene without obstacles or self-collision runs none of their code (a test
checks that).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from pvcloth.physics.state import Control, State


@dataclass
class Step:
    """One step passing through the pipeline.

    Attributes
    ----------
    before, after : State
        The state the step started from and the one it makes (changed in place).
    control : Control
        Pins and inverse masses.
    dt : float
        The step (s).
    pinned : numpy.ndarray
        Indices of the pinned points, shape (P,).
    pin_positions, pin_velocity : numpy.ndarray
        Where the pinned points end the step (m) and the velocity that takes
        them there (m/s), shape (P, 3).
    reports : dict
        What each operator reported, by its name.
    integrator_check : tuple of (float, bool) or None
        The integrator's own ``(largest speed, all finite)`` of ``after``
        (``Integrator.check``), if it made one.
    held : list of Contacts
        The points the integrator's own solve held against obstacles
        (``Integrator.held_contacts``), which the obstacle contacts add to
        their report.
    held_layers : HeldPairs or None
        The pairs of layers the integrator's solve held apart
        (``Integrator.held_layers``), which the self-contact gives friction.
    """

    before: State
    after: State
    control: Control
    dt: float
    pinned: np.ndarray
    pin_positions: np.ndarray
    pin_velocity: np.ndarray
    reports: dict[str, Any] = field(default_factory=dict)
    integrator_check: tuple[float, bool] | None = None
    held: list = field(default_factory=list)
    held_layers: Any = None


class Operator(Protocol):
    """A stage after the integrator: changes ``step.after`` in place and
    reports into ``step.reports[name]``."""

    name: str

    def __call__(self, step: Step) -> None: ...


class PinVelocities:
    """The state a step starts from, its pinned points at the velocity that
    lands them on their targets in ``dt``.

    Pinned points have zero inverse mass, so integrators move them at their
    velocity. The current state is returned as it is when it holds that
    velocity already (pins standing still: the last step landed them at
    rest), else a state sharing its positions and holding a copy of its
    velocities with the pinned rows changed: the current state is never
    written.

    Parameters
    ----------
    n : int
        Number of points.
    """

    name = "pin velocities"

    def __init__(self, n: int):
        self._velocities = np.empty((n, 3))

    def __call__(
        self, state: State, pinned: np.ndarray, pin_positions: np.ndarray, dt: float
    ) -> tuple[State, np.ndarray]:
        """``(state to step from, pin velocity (m/s) of shape (P, 3))``."""
        pin_velocity = (pin_positions - state.x[pinned]) / dt
        if np.array_equal(state.v[pinned], pin_velocity):
            return state, pin_velocity
        np.copyto(self._velocities, state.v)
        self._velocities[pinned] = pin_velocity
        return State(state.x, self._velocities, state.t), pin_velocity


class ObstacleContacts:
    """Swept collision with the model's obstacles; reports the points each
    touched (a list of :class:`~pvcloth.physics.obstacles.Contacts`), with
    those the integrator's solve held (:attr:`Step.held`)."""

    name = "obstacles"

    def __init__(self, model):
        self.model = model

    def __call__(self, step: Step) -> None:
        with np.errstate(all="ignore"):  # a diverging step is the guard's to report
            step.reports[self.name] = step.held + self.model.collide(
                step.before.x,
                step.after.x,
                step.after.v,
                step.control.movable_index,
                step.before.t,
                step.after.t,
                step.held,
            )


class PinLanding:
    """Pinned points exactly on their targets, at the velocity that took
    them there (the integrators moved them at it already; this removes
    their round-off and anything an obstacle did to them)."""

    name = "pins"

    def __call__(self, step: Step) -> None:
        step.after.x[step.pinned] = step.pin_positions
        step.after.v[step.pinned] = step.pin_velocity


class SelfContact:
    """Friction on the pairs of layers the integrator's solve held apart,
    then the cloth kept from passing through itself; reports the
    self-collision's :class:`~pvcloth.physics.self_collision.Report`."""

    name = "self-collision"

    def __init__(self, contact):
        self.contact = contact

    def __call__(self, step: Step) -> None:
        touched = step.reports.get(ObstacleContacts.name, ())
        if step.held_layers is not None:
            self.contact.rub(step.held_layers, step.after.x, step.after.v, step.control.inv_mass)
        self.contact.resolve(
            step.before.x, step.after.x, step.after.v, step.control.inv_mass, step.dt, touched
        )
        step.reports[self.name] = self.contact.report


class Guard:
    """Reports ``(largest speed in m/s, every value finite)``. Without an
    operator that changes velocities after the integrator (obstacles,
    self-collision), the compiled step's own check is taken when it made one
    (:attr:`Step.integrator_check`: pinned points included, their velocity being the one
    it used)."""

    name = "guard"

    def __init__(self, trust_integrator: bool):
        self.trust_integrator = trust_integrator

    def __call__(self, step: Step) -> None:
        after = step.after
        if self.trust_integrator and step.integrator_check is not None:
            speed, finite = step.integrator_check
            speed = speed if finite else np.inf
        else:
            speed = np.abs(after.v).max(initial=0.0)
            finite = bool(np.isfinite(after.x).all())
        step.reports[self.name] = (float(speed), finite)


def build_pipeline(model) -> list[Operator]:
    """The operators ``model``'s scene needs, in order (see the module's
    description).

    Examples
    --------
    >>> import pvcloth
    >>> from pvcloth.physics.model import build_model
    >>> from pvcloth.physics.pipeline import build_pipeline
    >>> plain = build_model(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(6, 6))))
    >>> [operator.name for operator in build_pipeline(plain)]
    ['pins', 'guard']
    """
    operators: list[Operator] = []
    if model.obstacles:
        operators.append(ObstacleContacts(model))
    operators.append(PinLanding())
    if model.self_collision is not None:
        operators.append(SelfContact(model.self_collision))
    operators.append(Guard(trust_integrator=len(operators) == 1))
    return operators
