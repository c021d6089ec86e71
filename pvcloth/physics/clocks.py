"""The clocks: fixed steps (with time owed between calls), the adaptive
controller's steps, and the frame loop movies, exports and studies share.

:class:`Clocks` is one part of :class:`~pvcloth.physics.simulation.Simulation`;
each step itself is its ``_substep``.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator

import numpy as np

from pvcloth.errors import DivergenceError, InputError, SceneError
from pvcloth.physics.adaptive import steady_step
from pvcloth.physics.blas import one_blas_thread
from pvcloth.scene.validation import integer, real

#: Most steps one call may take: hours of wall time even for a tiny cloth.
MAX_STEPS = 10**7


class Clocks:
    """The time-stepping methods of :class:`~pvcloth.physics.simulation.Simulation`
    (they read its ``dt``, ``controller``, ``owed``, ``state`` and ``control``
    and call its ``_substep`` and ``_state_changed``)."""

    def clock_state(self) -> dict[str, np.ndarray]:
        """What the clock carries from call to call, as a checkpoint saves
        it: the steps taken and the time owed to the next call (s, less
        than one step)."""
        return {"steps": np.array(self.steps), "owed": np.array(self.owed)}

    def advance(self, seconds: float, on_step=None) -> None:
        """Simulate ``seconds`` more, in fixed substeps of ``dt``.

        Time not covered by whole substeps is carried over to the next call,
        so many short advances add up to the same run as one long one. Pinned
        points move in a straight line to their targets over the substeps.
        ``on_step(done)``, if given, is called after every step with the
        simulated seconds done of this call (how a progress bar follows it;
        the physics draws none).

        Raises
        ------
        DivergenceError
            If the state stops being finite or bounded; the state is left at
            the last good step.
        SceneError
            If ``seconds`` would take more than :data:`MAX_STEPS` steps (the
            run is refused before it starts).
        """
        seconds = real("seconds", seconds, minimum=0.0, error=InputError)
        if self.controller is not None:
            self._advance_adaptive(seconds, on_step)
            return
        self.check_run_length(self.owed + seconds)
        self.owed += seconds
        n = math.floor(self.owed / self.dt + 1e-9)
        self.owed = max(self.owed - n * self.dt, 0.0)
        if n == 0:
            return
        pinned = self.control.pinned_index
        start = self._state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        try:
            with self._one_pool():
                for s in range(1, n + 1):
                    self._substep(pinned, start + (goal - start) * (s / n))
                    if on_step is not None:
                        on_step(s * self.dt)
        finally:  # after a divergence too: viewers show the last good state
            self._state_changed()

    def frames(self, count: int, fps: float, before_frame=None) -> Iterator[int]:
        """The frame loop movies, exports and studies share: yields ``0, 1,
        ..., count - 1``, frame 0 at the current state and every later one
        ``1 / fps`` simulated seconds after the one before.

        The whole run's length is checked before the first frame (a run of
        more than :data:`MAX_STEPS` steps is refused, not found out after
        hours).

        Parameters
        ----------
        count : int
            Frames, at least 1.
        fps : float
            Frames per simulated second, in (0, 1000].
        before_frame : callable, optional
            ``before_frame(sim, n)`` runs before frame ``n`` is advanced
            to (e.g. to move a pin along a scripted path).

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> [round(sim.time, 3) for n in sim.frames(4, fps=10)]
        [0.0, 0.1, 0.2, 0.3]
        """
        count = integer("frames", count, minimum=1, maximum=MAX_STEPS, error=InputError)
        fps = real("fps", fps, minimum=0.0, exclusive=True, maximum=1000.0, error=InputError)
        self.check_run_length((count - 1) / fps)
        return self._frames(count, fps, before_frame)

    def _frames(self, count: int, fps: float, before_frame) -> Iterator[int]:
        for n in range(count):
            if before_frame is not None:
                before_frame(self, n)
            if n:
                self.advance(1.0 / fps)
            yield n

    def check_run_length(self, seconds: float) -> int:
        """The number of steps ``seconds`` of simulation take; a
        :class:`SceneError` if that is more than :data:`MAX_STEPS` (a step
        far below what the run needs would otherwise look like a hang)."""
        steps = seconds / self.dt
        if not steps <= MAX_STEPS:
            raise SceneError(
                "solver.dt",
                f"{seconds:.4g} s of simulation at dt = {self.dt:.3g} s is {steps:.3g} steps, "
                f"more than the {MAX_STEPS:.0e} pvcloth runs in one go. Use a larger step "
                f"(leave solver.dt out for one chosen from the stable step) or simulate less "
                f"time per call.",
            )
        return math.floor(steps + 1e-9)

    def step(self) -> None:
        """One substep of ``dt``."""
        self.owed = 0.0
        pinned = self.control.pinned_index
        try:
            with self._one_pool():
                self._substep(pinned, self.control.targets[pinned])
        finally:
            self._state_changed()

    def _one_pool(self):
        """On the compiled kernels, BLAS on one thread while an integrator
        that calls it steps: the kernels' OpenMP threads take the cores (see
        :mod:`pvcloth.physics.blas`)."""
        if self.model.backend == "numba" and self.integrator.uses_blas:
            return one_blas_thread()
        return contextlib.nullcontext()

    def _advance_adaptive(self, seconds: float, on_step=None) -> None:
        """Steps chosen by the controller until exactly ``seconds`` later;
        rejected ones are retried shorter and leave no trace."""
        control = self.controller
        steady = self.integrator.steady_steps
        end = self._state.t + seconds
        pinned = self.control.pinned_index
        start_time = self._state.t
        start = self._state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        try:
            while self._state.t < end - 1e-12 * max(1.0, end):
                if control.step < control.min_step:
                    raise DivergenceError(
                        f"simulation stopped at t = {self._state.t:.6g} s: {self.integrator.name}"
                        f" needed steps under {control.min_step:g} s (solver.min_dt) to keep "
                        f"its error under {control.tolerance:g} m per second; the step had "
                        f"fallen to {control.step:.3g} s. A blow-up, or a tolerance too tight "
                        f"for this cloth: loosen solver.tolerance, lower solver.min_dt, or "
                        f"try an implicit integrator"
                        + (f" (its last failure: {control.failure})" if control.failure else "")
                    )
                natural = control.step
                remaining = end - self._state.t
                if steady and control.taken > 0.0:
                    # Keep the step (and its factorisation) unless worth changing.
                    h = steady_step(natural, control.taken, remaining)
                else:
                    h = min(natural, remaining)
                    if remaining - h < 1e-9 * h:  # no sliver of a step left over
                        h = remaining
                share = (self._state.t + h - start_time) / seconds
                if self._substep(pinned, start + (goal - start) * share, dt=h):
                    if h < natural:
                        # Cut short to land on the end, not for its error:
                        # the next advance starts from the step the controller
                        # wanted (else every frame's end restarted it small);
                        # for a method whose growth is bounded, no longer than
                        # that allows (BDF2 restarts beyond 2.4 times its last).
                        restored = natural
                        if math.isfinite(self.integrator.max_step_growth):
                            restored = min(natural, control.grow * h)
                        control.step = max(control.step, restored)
                    self.dt = control.step
                    if on_step is not None:
                        on_step(self._state.t - start_time)
        finally:  # after a divergence too: viewers show the last good state
            self._state_changed()

    def _uniform_clock(self, state) -> bool:
        # Time as steps * dt avoids summing round-off, while dt never changed.
        return abs(state.t - self.steps * self.dt) <= 1e-9 * max(1.0, state.t)
