"""BDF2, the second-order backward differentiation formula, solved to convergence."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pvcloth.errors import InputError
from pvcloth.physics.integrators.backward_euler import BackwardEuler
from pvcloth.physics.integrators.base import drift_error, register
from pvcloth.physics.state import Control, State

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model


@dataclass
class Step:
    """One step as BDF2 remembers it: where it started and how long it was.

    Attributes
    ----------
    x, v : numpy.ndarray
        Positions (m) and velocities (m/s) at its start, shape (N, 3) (copies).
    dt : float
        Its length (s).
    end : float
        The time (s) it ended at: the next step may use it as history only
        if it starts from there.
    """

    x: np.ndarray
    v: np.ndarray
    dt: float
    end: float


def bdf2_start(last: Step, x: np.ndarray, v: np.ndarray, dt: float):
    """BDF2's step as a backward Euler step: ``(x_hat, v_hat, h)`` such that
    ``x' = x_hat + h v'`` and ``v' = v_hat + h a(x', v')``.

    With ``w = dt / last.dt`` (1 at a constant step), variable-step BDF2
    (Hairer, Norsett and Wanner, *Solving ODEs I*, III.5) reads ``y' -
    (1 + w)^2 / (1 + 2w) y + w^2 / (1 + 2w) y_prev = (1 + w) / (1 + 2w) dt
    y''``, for ``y = x`` and ``y = v`` alike: at a constant step ``x_hat =
    (4 x - x_prev) / 3`` and ``h = 2 dt / 3``. ``x``, ``v`` are the state at
    the step's start (m, m/s, shape (N, 3)), ``last`` the step that led to it.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.integrators.bdf2 import Step, bdf2_start
    >>> last = Step(np.zeros((1, 3)), np.zeros((1, 3)), dt=0.1, end=0.1)
    >>> x_hat, v_hat, h = bdf2_start(last, np.ones((1, 3)), np.ones((1, 3)), 0.1)
    >>> float(x_hat[0, 0]), round(h, 6)  # (4 * 1 - 0) / 3 and 2/3 of the step
    (1.3333333333333333, 0.066667)
    """
    w = dt / last.dt
    ahead, back = (1 + w) ** 2 / (1 + 2 * w), w * w / (1 + 2 * w)
    return ahead * x - back * last.x, ahead * v - back * last.v, dt * (1 + w) / (1 + 2 * w)


def bdf2_error(last: Step, v: np.ndarray, v_new: np.ndarray, dt: float) -> float:
    """The error estimate of a BDF2 step (m): BDF2's local error ``C dt^3
    x'''`` with ``x'''`` from the second divided difference of the last
    three velocities (``last.v``, ``v`` and ``v_new``, m/s, shape (N, 3));
    the largest over the points. ``C = (1 + w)^2 / (6 w (1 + 2 w))`` for the
    ratio ``w = dt / last.dt`` of the two steps, 2/9 at a constant step
    (Hairer, Norsett and Wanner III.5). It scales as ``dt^3`` (second order)
    and comes from the one solve.

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.integrators.bdf2 import Step, bdf2_error
    >>> last = Step(np.zeros((1, 3)), np.zeros((1, 3)), dt=0.1, end=0.1)
    >>> # v = t^2: x''' = 2 m/s^3, so 2/9 * 0.001 * 2
    >>> round(bdf2_error(last, np.full((1, 3), 0.01), np.full((1, 3), 0.04), 0.1), 9)
    0.000769800
    """
    jerk = 2 * ((v_new - v) / dt - (v - last.v) / last.dt) / (dt + last.dt)  # (N, 3) m/s^3
    w = dt / last.dt
    constant = (1 + w) ** 2 / (6 * w * (1 + 2 * w))
    return constant * dt**3 * float(np.sqrt(np.einsum("ij,ij->i", jerk, jerk).max(initial=0.0)))


#: The longest step BDF2 takes on its history, as a multiple of the last
#: one: below 1 + sqrt(2) = 2.414, where its variable-step form stops being
#: zero-stable (Grigorieff 1983); a longer one starts again with backward Euler.
MAX_RATIO = 2.4


def _ends_at(step: Step, t: float) -> bool:
    """Whether ``step`` ended at time ``t`` (s): to a millionth of its length,
    since the simulation's clock counts ``t`` as steps times ``dt`` where
    the step added ``dt`` to its start (they differ in the last bits)."""
    return abs(step.end - t) <= 1e-6 * step.dt


class History:
    """The step BDF2 may build on: the last step taken (``pending``) becomes
    the history of the next one if that starts where it ended; a step that
    was rejected and is taken again from the same start keeps the history it
    had. Anything else (a state from elsewhere; the simulation also calls
    :meth:`clear` on a reset or an edit of the state) starts again with one
    backward Euler step."""

    def __init__(self):
        self.pending: Step | None = None
        self.current: Step | None = None

    def before(self, state: State, dt: float) -> Step | None:
        """The step that led to ``state``, or ``None`` (start again), for a
        next step of ``dt``: also ``None`` when ``dt`` is more than
        :data:`MAX_RATIO` times that step's length (variable-step BDF2 is
        zero-stable only below ``1 + sqrt(2)``; after a step cut short at a
        frame's end the next is often far longer)."""
        if self.pending is not None and _ends_at(self.pending, state.t):
            self.current, self.pending = self.pending, None
        if self.current is not None and (
            not _ends_at(self.current, state.t) or self.current.x.shape != state.x.shape
        ):
            self.current = None
        if self.current is not None and dt > MAX_RATIO * self.current.dt:
            return None  # kept: a shorter retry from this state may use it
        return self.current

    def after(self, state: State, dt: float) -> None:
        """Remember a step of ``dt`` from ``state`` (copied: the simulation
        reuses its arrays)."""
        self.pending = Step(state.x.copy(), state.v.copy(), dt, state.t + dt)

    def clear(self) -> None:
        self.pending = self.current = None

    def get_state(self) -> dict[str, np.ndarray]:
        """The last step, as flat arrays (a checkpoint's), or nothing."""
        if self.pending is None:
            return {}
        last = self.pending
        return {
            "history_x": last.x.ravel().copy(),
            "history_v": last.v.ravel().copy(),
            "history_time": np.array([last.dt, last.end]),
        }

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`get_state` gave; a history that cannot be one
        (a damaged checkpoint's) is refused with what is wrong."""
        self.clear()
        if "history_x" not in state:
            return
        x, v = (np.array(state.get(f"history_{key}", ()), float) for key in "xv")
        times = np.array(state.get("history_time", ()), float)
        if not (
            x.size == v.size > 0
            and x.size % 3 == 0
            and times.shape == (2,)
            and np.isfinite(times).all()
            and times[0] > 0
            and np.isfinite(x).all()
            and np.isfinite(v).all()
        ):
            raise InputError(
                "history",
                "expected finite positions and velocities of one shape and a step > 0 s "
                f"(history_time = {times.tolist()})",
            )
        self.pending = Step(x.reshape(-1, 3), v.reshape(-1, 3), float(times[0]), float(times[1]))


class KeepsLastStep:
    """What the two BDF2 integrators share: the last step, kept in
    :attr:`history`, saved in checkpoints and dropped on a restart."""

    history: History
    #: Adaptive steps grow at most this much, below :data:`MAX_RATIO`: a
    #: longer step restarts with backward Euler, whose first-order error
    #: estimate is then far over a tolerance BDF2 meets. Growth of 5 (the
    #: controller's own) made a limit cycle on the 16x16 hanging cloth at
    #: 1e-5 m: every attempt to grow restarted, was rejected and refactorised,
    #: and the step sat near 5e-6 s with errors 1e4 times under the tolerance.
    max_step_growth = 2.0

    def restart(self) -> None:
        self.history.clear()

    def get_state(self) -> dict[str, np.ndarray]:
        return self.history.get_state()

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        self.history.set_state(state)


@register
class BDF2(KeepsLastStep, BackwardEuler):
    """BDF2, the second-order backward differentiation formula, by Newton to
    the same residual as :class:`~pvcloth.physics.integrators.backward_euler.BackwardEuler`.

    At a constant step ``dt`` it reads ``x' = (4 x - x_prev) / 3 + 2/3 dt
    v'`` and ``v' = (4 v - v_prev) / 3 + 2/3 dt a(x', v')``: backward
    Euler's equation with the combinations of the last two states in place
    of the start and two thirds of the step (:func:`bdf2_start`), so the
    same incremental potential and the same Newton solve take it, with
    every force implicit: springs, their dashpots, plate bending, air
    damping, gravity and the wind. The dashpots act on the change of each
    spring's length from ``x_hat``'s, like backward Euler's from ``x``'s:
    the length of the combined start is not the combination of the two
    lengths where a spring turns, so their rate is first order there (the
    dashpots move the 64x64 cotton cloth by 0.48 cm in its first second,
    ``benchmarks/results/frame_step.md``).

    Like backward Euler it is A-stable and L-stable (it damps the stiffest
    modes of a cloth to nothing at any step), but its error is second
    order: ``2/9 dt^3 x'''`` per step against backward Euler's ``dt^2 a /
    2``, so a swing loses far less energy to the method. The first step,
    and every step after a reset or an edit of the state, is one backward
    Euler step (its ``dt^2`` local error, taken once,
    keeps the method second order). A varied step is taken by the
    variable-step formula, so adaptive runs need no restart. Pinned points
    go where the simulation sends them. Each step leaves its error estimate
    in :attr:`error` (:func:`bdf2_error`; the start-up step's is
    :func:`~pvcloth.physics.integrators.base.drift_error`).

    Several factorisations per step (seconds at 64x64): like backward
    Euler, the reference its fast twin is measured against.

    Parameters
    ----------
    iterations : int
        The most Newton iterations per step.
    """

    name, order = "bdf2", 2  # registry key; global order of accuracy
    description = "BDF2 (second order), Newton to 1e-3 m/s^2 unbalanced; a reference"

    def __init__(self, iterations: int = 200):
        super().__init__(iterations)
        self.history = History()
        #: Whether the last step was the backward Euler start-up.
        self.started_up = False

    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        x, v = state.x, state.v
        last = self.history.before(state, dt)
        if last is None:
            x_hat, v_hat, h = x, v, dt
        else:
            x_hat, v_hat, h = bdf2_start(last, x, v, dt)
        # Start from the explicit drift; pinned points at their targets (the
        # simulation set their velocity so that x + dt v is the target).
        end = self.solve(
            model, control, x_hat, v_hat, h, x + dt * v, state.t, state.t + dt, positions=x
        )
        v_new = (end - x_hat) / h
        v_new[control.pinned] = v[control.pinned]
        self.started_up = last is None
        self.error = drift_error(dt, v, v_new) if last is None else bdf2_error(last, v, v_new, dt)
        self.history.after(state, dt)
        return State(end, v_new, state.t + dt)
