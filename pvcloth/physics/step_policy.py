"""Which step a simulation takes: the rules, as functions of the scene,
the model and the integrator, with no simulation of their own.

- A **given** step (``solver.dt``) is checked against the integrator's
  estimated stable step: kept up to :data:`STABLE_SHARE` of it, else
  refused, split into substeps of :data:`SAFE_SHARE` of it, or run anyway,
  as ``solver.stability`` says (:func:`checked_step`).
- An **automatic** step (``solver.dt`` left out) is the largest that is at
  most :data:`SAFE_SHARE` of the stable step and divides a 1/60 s frame
  (:func:`automatic_step`).
- With self-collision every step is also split under the **contact step**,
  the longest in which a resting layer is held up (:func:`contact_step`).
- With ``solver.tolerance`` a :class:`~pvcloth.physics.adaptive.StepController`
  chooses every step between bounds set here (:func:`step_controller`).

The stable step is an eigenvalue estimate that costs a sparse solve, so it
is passed as a function and asked for only when a rule needs it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pvcloth.errors import SceneError
from pvcloth.physics.adaptive import GROW, MAX_STEP, MIN_STEP, UNIT_TIME, StepController
from pvcloth.scene.parts import MEASURING_INTEGRATORS
from pvcloth.scene.spec import Scene

#: A step counts as stable up to this share of the estimated limit. The
#: estimate is exact only for the linearised cloth at rest; far from rest,
#: nonlinear coupling has destabilised steps above about 0.8 of it (and
#: explicit Euler at 0.9995 of it diverged), so a step just under it is refused.
STABLE_SHARE = 0.8
#: Automatic steps and substeps aim at this share of the estimated limit.
SAFE_SHARE = 0.5
#: Automatic step of an integrator that is stable at any step: a 60 fps frame.
FRAME_DT = 1.0 / 60.0


def contact_step(model, scene: Scene) -> float:
    """The longest step (s) self-collision can hold one layer up on another
    in (:meth:`SelfCollision.longest_step
    <pvcloth.physics.self_collision.SelfCollision.longest_step>`); infinite
    without ``[self_collision]``."""
    contact = model.self_collision
    if contact is None:
        return math.inf
    return contact.longest_step(math.hypot(*scene.gravity))


def split_for_contact(dt: float, contact: float) -> float:
    """``dt`` split into equal substeps no longer than ``contact``.

    Examples
    --------
    >>> split_for_contact(0.01, 0.004), split_for_contact(0.01, math.inf)
    (0.0033333333333333335, 0.01)
    """
    return dt / max(1, math.ceil(dt / contact - 1e-9))


def positive(stable: float, integrator: str) -> float:
    """``stable`` (s), or the error that says no step is stable."""
    if not stable > 0.0:
        raise SceneError(
            "solver.integrator",
            f"{integrator} is unstable at every step on this cloth (its stiffest "
            f"mode is undamped and grows at any dt). Give the springs some damping, or use "
            f"symplectic_euler, verlet, rk4 or implicit_euler.",
        )
    return stable


def automatic_step(stable: float, contact: float) -> float:
    """The largest step at most :data:`SAFE_SHARE` of ``stable`` and at most
    ``contact`` that divides a 1/60 s frame (whole steps per frame, so that
    advancing by frames lands exactly on them).

    Examples
    --------
    >>> round(1 / automatic_step(math.inf, math.inf))  # stable at any step: the frame
    60
    >>> automatic_step(0.001, math.inf) == (1 / 60) / 34  # 34 steps of at most 0.5 ms
    True
    """
    limit = min(SAFE_SHARE * stable, contact)
    return FRAME_DT / max(1, math.ceil(FRAME_DT / limit))


def checked_step(
    scene: Scene,
    dt: float | None,
    policy: str,
    integrator: str,
    stable: Callable[[], float],
    contact: float,
) -> float:
    """The step to take: automatic when ``dt`` is None, else ``dt`` checked
    against the stable step as ``policy`` says (with a tolerance, ``dt`` is
    only the first step the controller tries: not checked).

    Parameters
    ----------
    scene : Scene
        Its ``solver`` (tolerance, max_dt) is read.
    dt : float or None
        The step asked for (s).
    policy : {"refuse", "substep", "ignore"}
    integrator : str
        The integrator's name, for messages.
    stable : callable
        ``stable()`` gives the integrator's estimated stable step (s).
    contact : float
        :func:`contact_step`.
    """
    if scene.solver.tolerance is not None and dt is not None:
        return min(dt, scene.solver.max_dt or MAX_STEP, contact)
    if dt is None:
        return automatic_step(positive(stable(), integrator), contact)
    if policy == "ignore":
        return split_for_contact(dt, contact)
    limit = positive(stable(), integrator)
    if dt <= STABLE_SHARE * limit:
        return split_for_contact(dt, contact)
    if policy == "substep":
        return split_for_contact(dt / math.ceil(dt / (SAFE_SHARE * limit)), contact)
    raise SceneError(
        "solver.dt",
        f"{dt:.4g} s is above the largest stable step allowed for {integrator} "
        f"on this cloth, {STABLE_SHARE:g} of its estimated limit of {limit:.3g} s (the "
        f"estimate is exact only near rest). Use dt <= {SAFE_SHARE * limit:.3g} (or leave "
        f"solver.dt out to get that step automatically), the implicit_euler integrator "
        f"(stable at any step), or solver.stability = 'substep' to split each step "
        f"automatically ('ignore' runs it anyway).",
    )


def starting_step(integrator, model, control, state, tolerance: float) -> float:
    """A first step for a tolerance when none is given: the one whose
    error estimate would be about the tolerance's share if the error
    were the drift of the largest acceleration ``a`` over the step,
    ``a h^2 / 2 <= tolerance h / 1 s`` for a first-order method and
    ``a h^3 / 6 <= tolerance h`` for a second-order one (a start, in the
    manner of Hairer, Norsett and Wanner's, *Solving ODEs I*, II.4: too
    long a first step costs rejections, each a full step; too short a
    few steps while it grows fivefold each)."""
    acceleration = integrator.acceleration(model, control, state.x, state.v)
    largest = float(np.sqrt(np.einsum("ij,ij->i", acceleration, acceleration).max(initial=0.0)))
    if not largest > 0.0:
        return math.inf
    share = tolerance / UNIT_TIME
    if integrator.order == 1:
        return 2.0 * share / largest
    return math.sqrt(6.0 * share / largest)


def step_controller(
    scene: Scene,
    integrator,
    dt: float,
    stable: Callable[[], float],
    contact: float,
    starting: Callable[[float], float],
) -> StepController | None:
    """The controller of an adaptive run when the scene gives a tolerance
    (and an integrator that measures its error), else ``None``.

    Parameters
    ----------
    scene : Scene
    integrator : Integrator
    dt : float
        The step so far (from :func:`checked_step`), the most the first may be.
    stable : callable
        ``stable()`` gives the integrator's estimated stable step (s).
    contact : float
        :func:`contact_step`.
    starting : callable
        ``starting(tolerance)`` gives :func:`starting_step` at the current state.
    """
    solver = scene.solver
    tolerance = solver.tolerance
    if tolerance is None:
        return None
    if not integrator.embedded:
        raise SceneError(
            "solver.tolerance",
            f"{integrator.name} does not measure its own error, so no step can be "
            f"chosen for a tolerance; use solver.integrator = {', '.join(MEASURING_INTEGRATORS)!r}"
            f" with it, or leave solver.tolerance out for fixed steps",
        )
    largest = min(solver.max_dt or MAX_STEP, contact)
    limit = stable()
    if math.isfinite(limit) and limit > 0.0:
        # An explicit step beyond its stable one would only be rejected
        # (measured: 69 rejections in 535 steps at 1e-2 m without this).
        largest = min(largest, STABLE_SHARE * limit)
    if solver.min_dt is not None and solver.min_dt > 0.5 * largest:
        raise SceneError(
            "solver.min_dt",
            f"{solver.min_dt:g} s leaves no room under the largest step "
            f"{integrator.name} may take here, {largest:.3g} s (0.8 of its stable "
            f"step, solver.max_dt or the self-collision step); give at most "
            f"{0.5 * largest:.3g} s or leave it out",
        )
    smallest = min(solver.min_dt or MIN_STEP, 0.5 * largest)
    first = min(dt, largest)
    if solver.dt is None:
        first = min(first, max(starting(tolerance), smallest))
    return StepController(
        tolerance,
        integrator.order,
        first,
        min_step=smallest,
        max_step=largest,
        grow=min(GROW, integrator.max_step_growth),
    )


#: Where a simulation's step came from (``Simulation.dt_source``), in the
#: word the summary, the movie overlay and the window's status use.
STEP_SOURCES = {
    "auto": "automatic",
    "given": "as given",
    "substep": "substep",
    "adaptive": "adaptive",
}


def step_origin(
    source: str,
    *,
    stable: float,
    contact: float,
    requested: float | None = None,
    controller: StepController | None = None,
) -> str:
    """Where the step came from, in a sentence (what ``pvcloth info``
    prints; :data:`STEP_SOURCES` has it in a word).

    Parameters
    ----------
    source : {"auto", "given", "substep", "adaptive"}
        ``Simulation.dt_source``.
    stable, contact : float
        The integrator's estimated stable step and :func:`contact_step` (s).
    requested : float, optional
        The step asked for (``solver.dt``), for ``"substep"``.
    controller : StepController, optional
        An adaptive run's, for ``"adaptive"``.

    Examples
    --------
    >>> step_origin("auto", stable=0.001, contact=math.inf)
    'automatic: at most half the stable step, dividing 1/60 s'
    """
    if source == "auto":
        if contact < min(FRAME_DT, SAFE_SHARE * stable):
            return "automatic: under the self-collision step, dividing 1/60 s"
        if math.isinf(stable):
            return "automatic: one 1/60 s frame"
        return "automatic: at most half the stable step, dividing 1/60 s"
    if source == "substep":
        return f"substeps of the given {requested:.4g} s"
    if source == "adaptive" and controller is not None:
        return (
            f"adaptive: chosen every step to keep the error under {controller.tolerance:g} m per "
            f"simulated second, between {controller.min_step:.3g} and {controller.max_step:.3g} s;"
            f" this is the next step tried"
        )
    return STEP_SOURCES[source]
