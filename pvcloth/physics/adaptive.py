"""Step-size control: the user sets the error, the controller the step.

With ``solver.tolerance`` (metres) a scene runs an integrator that measures
its own error (``Integrator.embedded``) at a step chosen anew for every step.
Two kinds of estimate exist:

- ``rk23``: the distance between the Bogacki–Shampine pair's second- and
  third-order positions (order ``k = 2``).
- ``implicit_euler``, ``fast_mass_spring`` and ``backward_euler``: backward
  Euler against the trapezoidal rule from the same velocities,
  ``h |v' - v| / 2`` (:func:`~pvcloth.physics.integrators.base.drift_error`;
  ``k = 1``), free from the one solve. It measures the time discretisation;
  not what stopping a solver early costs (the studies measure that part).

The loop:

- A step whose error estimate (the largest distance over the points)
  exceeds its share of the tolerance is rejected and retried shorter;
  nothing of it is kept.
- An accepted step sets the next by a PI controller (Gustafsson 1991, "Control
  theoretic techniques for stepsize selection in explicit Runge-Kutta
  methods", ACM TOMS 17(4); the form of Hairer and Wanner, *Solving ODEs II*,
  IV.2): ``h_next = h * safety * (tol / err)^(0.7/k) * (err_prev / tol)^(0.4/k)``
  with ``k`` the kept solution's order (the error per unit step scales as
  ``h^k``). The integral part reacts to this
  step's error, the proportional part damps the oscillation a plain
  ``(tol / err)^(1/k)`` rule shows on problems near their stability limit.
- Each change is held within :data:`SHRINK` and :data:`GROW` times the step
  (BDF2's within twice: see ``Integrator.max_step_growth``); after a
  rejection the next step may not grow. Steps lie between
  ``solver.min_dt`` (default :data:`MIN_STEP`; below it the run stops with a
  DivergenceError: the problem is too stiff or singular for this tolerance)
  and ``solver.max_dt`` (default :data:`MAX_STEP`), lowered for an explicit
  method to 0.8 of its estimated stable step: a longer step would only be
  rejected (rk23 at 1e-2 m on the hanging cloth: 69 rejections in 535
  steps without that bound, 2 in 667 with it).
- A method that factorises a matrix of the step (``fast_mass_spring``)
  keeps its step while the controller asks for 0.9 to 1.25 times it, and
  divides each frame into equal steps (:func:`steady_step`): 31
  factorisations in 978 steps at 1e-2 m on the 8x8 hanging cloth, against
  800 with the step changed whenever asked, a tenth of the wall time.
- With no ``solver.dt`` the first step is the one whose drift under the
  largest acceleration would spend the tolerance's share (``a h^2 / 2`` for
  order 1, ``a h^3 / 6`` for order 2): a first step far too long costs a
  chain of rejections, each a full step (for implicit Euler, a linear
  solve at a frame's step each).

How the tolerance relates to the error a run ends with: each step may spend
``tolerance * h / 1 s`` (error per unit step), so the errors made during a
second of simulated time add up to at most the tolerance; what the run ends
with is those errors as the motion carries them on. Measured against RK4 at
a tiny step (``benchmarks/results/adaptive.md``; ``tests/test_adaptive.py``
asserts the first two):

- 16x16 hanging cloth with rk23, after 0.5 s: 0.4 to 0.5 of ``tolerance * t``
  at every tolerance from 1e-3 to 1e-6 m; over 1 s, 0.9 to 10 times it (the
  swing grows earlier errors): within a factor of 10, shrinking with it.
- 16x16 hanging cloth with implicit Euler over 1 s: 1.2 and 2.5 times
  ``tolerance * t`` at 1e-1 and 1e-2 m (and under it after 0.5 s on the 8x8
  one, asserted). Its steps shrink in proportion to the tolerance (first
  order): 1e-2 m took 4315 steps for the second.
- A 16x16 swing that air damping calms within 3 s: 0.2 of ``tolerance * t``
  from 1e-4 to 1e-6 m, at half the cost of the fixed step that reaches the
  same error (the steps grow as the motion dies out).
- A cloth dropped on the ground: the error stops shrinking below a few mm
  (and so does that of fixed steps): contact is resolved after each step,
  outside the error estimate, and its error is not smooth in the step. The
  controller does not collapse there (a few rejections in thousands of
  steps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pvcloth.scene.parts import DEFAULT_MAX_DT, DEFAULT_MIN_DT

#: Safety factor on every new step (the estimate is an estimate).
SAFETY = 0.9
#: Largest and smallest factor between one step and the next.
GROW, SHRINK = 5.0, 0.2
#: Default bounds of the step in seconds (``solver.min_dt`` and ``max_dt`` change them).
MIN_STEP, MAX_STEP = DEFAULT_MIN_DT, DEFAULT_MAX_DT
#: The time (s) over which the errors of the steps may add up to the tolerance.
UNIT_TIME = 1.0


@dataclass
class StepController:
    """PI control of the step (see the module's description).

    Parameters
    ----------
    tolerance : float
        Largest error estimate (m) an accepted step may have.
    order : int
        Order of the solution kept (2 for ``rk23``): its error per step, and
        so the estimate, scale as ``h^(order + 1)``.
    step : float
        The next step to try (s).
    min_step, max_step : float
        Bounds of the step (s; ``solver.min_dt`` and ``solver.max_dt``, by
        default :data:`MIN_STEP` and :data:`MAX_STEP`). The simulation lowers
        ``max_step`` to 0.8 of an explicit method's estimated stable step: a
        longer step is rejected by its error anyway.
    grow : float
        Largest factor from one accepted step to the next: :data:`GROW`, or
        less for a method that cannot build on a shorter last step
        (``Integrator.max_step_growth``: BDF2 restarts with a first-order
        step beyond 2.4 times its last, whose error is then rejected).

    Attributes
    ----------
    previous : float or None
        Error over tolerance of the last accepted step (the P part's memory).
    rejected : int
        Steps rejected so far.
    taken : float
        Length of the last accepted step (s; 0 before the first).
    shortest, longest : float
        Shortest and longest accepted step (s) since the controller started
        (a resumed run's since its resume; ``inf`` and 0 before the first).

    Examples
    --------
    >>> from pvcloth.physics.adaptive import StepController
    >>> control = StepController(tolerance=1e-4, order=2, step=1e-3)
    >>> control.judge(error=4e-7)  # a 1 ms step may spend 1e-7 m: rejected, shorter
    False
    >>> round(control.step, 6)
    0.00045
    >>> control.judge(error=1e-8)  # inside: accepted (no growth just after a rejection)
    True
    >>> round(control.step, 6)
    0.00045
    >>> control.judge(error=1e-8)  # inside again: longer, by less than (tol/err)^(1/k) (the P part)
    True
    >>> round(control.step, 6)
    0.000508
    """

    tolerance: float
    order: int
    step: float
    min_step: float = MIN_STEP
    max_step: float = MAX_STEP
    grow: float = GROW
    previous: float | None = None
    rejected: int = 0
    taken: float = 0.0
    shortest: float = math.inf
    longest: float = 0.0
    _after_rejection: bool = False
    #: The integrator's own error on the last step it could not take (a
    #: Newton solve that did not converge), or empty.
    failure: str = ""

    def judge(self, error: float) -> bool:
        """Whether a step of :attr:`step` with this error estimate is
        accepted; sets the next step to try either way."""
        # Error per unit step: a step of h may spend h / (1 s) of the
        # tolerance, so a second's steps add up to at most the tolerance. The
        # estimate then scales as h^order, hence the exponents' k.
        k = self.order
        allowed = self.tolerance * self.step / UNIT_TIME
        ratio = error / allowed if math.isfinite(error) else math.inf
        if ratio <= 1.0:
            factor = SAFETY * max(ratio, 1e-10) ** (-0.7 / k)
            if self.previous is not None:
                factor *= max(self.previous, 1e-10) ** (0.4 / k)
            factor = min(self.grow, max(SHRINK, factor))
            if self._after_rejection:
                factor = min(factor, 1.0)
            self.previous, self._after_rejection = ratio, False
            self.taken = self.step
            self.shortest = min(self.shortest, self.step)
            self.longest = max(self.longest, self.step)
            self.step = min(self.max_step, self.step * factor)
            return True
        factor = SHRINK if not math.isfinite(ratio) else max(SHRINK, SAFETY * ratio ** (-1.0 / k))
        self.step *= factor
        self.rejected += 1
        self._after_rejection = True
        return False

    def get_state(self) -> np.ndarray:
        """The memory a resumed run needs to choose the same steps, as the
        six numbers a checkpoint keeps: the last error ratio (-1 for none),
        whether the last step was rejected, the rejections, the last
        accepted step and the bounds (s)."""
        return np.array(
            [
                -1.0 if self.previous is None else self.previous,
                float(self._after_rejection),
                float(self.rejected),
                self.taken,
                self.min_step,
                self.max_step,
            ]
        )

    def set_state(self, values: np.ndarray, step: float) -> None:
        """Continue from :meth:`get_state`'s numbers (or the first three,
        which checkpoints held before the bounds were kept; the bounds then
        stay as estimated now), the next step to try being ``step``."""
        previous, after_rejection, rejected, *rest = (float(v) for v in values)
        self.previous = None if previous < 0 else previous
        self._after_rejection = bool(after_rejection)
        self.rejected = int(rejected)
        if rest:  # the bounds as they were (the stable step was estimated then)
            self.taken, self.min_step, self.max_step = rest
        self.step = step


#: A step that factorises (``Integrator.steady_steps``) is lengthened only
#: when the controller would make it at least this many times longer.
STEADY_GAIN = 1.25


def steady_step(wanted: float, last: float, remaining: float) -> float:
    """The step a method that factorises takes (s): the last one again
    while the controller wants between :data:`SAFETY` and
    :data:`STEADY_GAIN` times it (the safety factor is margin a repeated
    step may use; a step over its error is still rejected), else the one
    wanted; then shortened to divide ``remaining`` (the time left of the
    advance) into whole steps, so every frame of a run takes the same steps
    and reuses their factorisation.

    Examples
    --------
    >>> from pvcloth.physics.adaptive import steady_step
    >>> steady_step(wanted=0.011, last=0.01, remaining=0.05)  # 10 % longer: not worth a new factor
    0.01
    >>> round(steady_step(wanted=0.02, last=0.01, remaining=0.05), 6)  # 3 steps of 1/60 s
    0.016667
    """
    step = last if SAFETY * last <= wanted <= STEADY_GAIN * last else wanted
    whole = remaining / math.ceil(remaining / step * (1.0 - 1e-12))
    # The time left is a difference of clock readings: the same step again
    # comes out a few ulps off, and any change of the step refactorises.
    return last if abs(whole - last) <= 1e-9 * last else whole
