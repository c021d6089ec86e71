"""The window's physics thread: it owns the simulation, keeps wall-clock
time, and carries out the window's requests between chunks of steps.

Why a thread: the window must keep drawing and following the mouse while
the cloth computes, and some work takes longer than a frame (an implicit
step at 64x64 is a quarter second, a stable-step estimate up to 0.2 s). The
main thread, which VTK needs, draws only the :class:`~pvcloth.physics.state.Snapshot`
this thread publishes after every chunk and every request (``snapshot``):
copies, replaced whole, so no frame mixes two states.

Why a loop rather than one chunk per timer tick: a chunk that finished
between two ticks would leave the physics idle until the next one; the loop
starts the next chunk at once, so a cloth that cannot keep up with real
time runs as fast as the machine allows.
"""

from __future__ import annotations

import collections
import contextlib
import math
import os
import queue
import threading
import time
from concurrent.futures import Future

import numpy as np

from pvcloth.errors import DivergenceError
from pvcloth.physics.blas import one_blas_thread
from pvcloth.physics.kernels import use_threads

#: The state kept from before each of the last this many chunks: a
#: divergence goes back to the newest calm one.
KEPT_CHUNKS = 90
#: A kept state counts as calm while no point moves faster (m/s).
CALM_SPEED = 50.0
#: Longest wall time (s) one chunk catches up after a slow one; beyond it
#: time is dropped (slow motion) rather than owed.
MAX_CATCH_UP = 0.1
#: The real-time fraction is measured over about this much wall time (s).
MEASURE_WINDOW = 1.0


class RealTimeMeter:
    """Simulated seconds over wall seconds, measured over the last
    :data:`MEASURE_WINDOW` seconds of wall time.

    Examples
    --------
    >>> meter = RealTimeMeter()
    >>> for k in range(11):  # 0.5 s of cloth time in each wall second
    ...     meter.add(wall=0.1 * k, sim_time=0.05 * k)
    >>> round(meter.fraction, 3)
    0.5
    """

    def __init__(self):
        self.samples: collections.deque[tuple[float, float]] = collections.deque()

    def add(self, wall: float, sim_time: float) -> None:
        if self.samples and sim_time < self.samples[-1][1]:  # the cloth went back (a reset)
            self.samples.clear()
        self.samples.append((wall, sim_time))
        while len(self.samples) > 2 and wall - self.samples[1][0] >= MEASURE_WINDOW:
            self.samples.popleft()

    def restart(self) -> None:
        """Forget the samples (after a pause, a reset or a new step)."""
        self.samples.clear()

    @property
    def fraction(self) -> float | None:
        """Measured real-time fraction, or ``None`` before there is a span.

        The span is the last :data:`MEASURE_WINDOW` seconds exactly: when
        no sample falls at its start (the physics thread was held up there),
        the cloth time at the start is interpolated between the samples on
        either side. Taking the older sample instead stretched the span over
        the hold-up, and once showed x0.90 where the last second ran at x1.10.
        """
        samples = list(self.samples)  # the physics thread may append meanwhile
        if len(samples) < 2:
            return None
        (w0, t0), (w1, t1) = samples[0], samples[-1]
        start = w1 - MEASURE_WINDOW
        if w0 < start:  # add() keeps the second sample inside the span
            (wa, ta), (wb, tb) = samples[0], samples[1]
            t0 = ta + (tb - ta) * (start - wa) / (wb - wa)
            w0 = start
        return (t1 - t0) / (w1 - w0) if w1 - w0 >= 0.2 else None


class PhysicsThread:
    """Runs ``sim`` against the wall clock on a thread of its own.

    Parameters
    ----------
    sim : Simulation
        Owned by this thread once started: change it through :meth:`request`.
    chunk_seconds : float
        Longest wall time (s) one chunk of steps should take (at least one
        step runs, however long): requests wait at most about this long.

    Attributes
    ----------
    paused : bool
        Set to stop advancing (requests still run).
    drag : (int, DragPath) or None
        A point being dragged and its path, replayed in cloth time.
    step_cost : float or None
        Measured wall seconds per substep (an average).
    chunk_ms : float
        Wall time of the last chunk (ms).
    diverged : str or None
        Message of the last divergence (the thread pauses on one).
    snapshot : Snapshot
        The instant the window draws (:meth:`Simulation.snapshot
        <pvcloth.physics.simulation.Simulation.snapshot>`), published by this
        thread after every chunk and every request, before the request's
        caller hears that it ran; replaced whole, never changed.
    """

    def __init__(self, sim, chunk_seconds: float):
        self.sim = sim
        self.chunk_seconds = chunk_seconds
        self.paused = False
        self.drag = None
        self.step_cost: float | None = None
        self.chunk_ms = 0.0
        self._held = contextlib.ExitStack()  # the BLAS limit while running
        self.chunk_started: float | None = None
        self.diverged: str | None = None
        self.meter = RealTimeMeter()
        self.snapshot = sim.snapshot()
        self._kept = collections.deque(maxlen=KEPT_CHUNKS)
        self._requests: queue.Queue = queue.Queue()
        self._owed = 0.0
        self._last = None
        self._stop = False
        self._thread = threading.Thread(target=self._loop, name="pvcloth-physics", daemon=True)

    def start(self) -> None:
        """Start stepping, with BLAS held to one thread until :meth:`stop`
        (the drawing needs the other core; see :mod:`pvcloth.physics.blas`).
        The limit is taken here, on the calling thread: OpenBLAS ignored a
        thread count set from another thread once the main one had set one."""
        self._held.enter_context(one_blas_thread())
        self._thread.start()

    def stop(self) -> None:
        """Finish the current chunk, end the thread and give BLAS back its
        threads."""
        self._stop = True
        self._wake()
        if self._thread.is_alive():
            self._thread.join()
        self._held.close()

    def request(self, change, *args) -> Future:
        """Run ``change(*args)`` on this thread after what is queued."""
        future: Future = Future()
        self._requests.put((future, change, args))
        return future

    def wait(self, timeout: float | None = 60.0) -> None:
        """Block until every request made so far has run."""
        if self._thread.is_alive():
            self.request(lambda: None).result(timeout)
        else:  # not started (tests driving it by hand): run them here
            self._run_requests()

    def forget_pace(self) -> None:
        """Start measuring cost and pace afresh (new step, integrator...)."""
        self.step_cost = None
        self.meter.restart()

    # -- on the thread ---------------------------------------------------------

    def _wake(self):
        self._requests.put(None)

    def _loop(self):
        # The drawing needs a core: leave it one (see use_threads).
        use_threads((os.cpu_count() or 1) - 1)
        while not self._stop:
            self._run_requests(block=self.paused)
            if self.paused or self._stop:
                self._last = None
                continue
            now = time.perf_counter()
            if self._last is None:
                self.meter.add(now, self.sim.time)
            self._owed = min(self._owed + (now - self._last if self._last else 0.0), MAX_CATCH_UP)
            self._last = now
            steps = self.steps_for(self._owed)
            if steps == 0:  # less than a step owed: wait for the clock
                time.sleep(max(self.sim.dt - self._owed, 0.0005))
                continue
            self._owed = max(self._owed - steps * self.sim.dt, 0.0)
            self.run_chunk(steps)

    def _run_requests(self, block: bool = False) -> None:
        while True:
            try:
                item = self._requests.get(timeout=0.05) if block else self._requests.get_nowait()
            except queue.Empty:
                return
            block = False
            if item is None:
                continue
            future, change, args = item
            try:
                result = change(*args)
            except DivergenceError as error:
                self._on_divergence(error)
                self.snapshot = self.sim.snapshot()
                future.set_exception(error)
            except Exception as error:  # shown by the window, never lost
                self.snapshot = self.sim.snapshot()
                future.set_exception(error)
            else:
                # Published before the caller hears: what it draws next shows the change.
                self.snapshot = self.sim.snapshot()
                future.set_result(result)

    def steps_for(self, seconds: float) -> int:
        """Substeps of ``seconds`` that fit :attr:`chunk_seconds` of wall
        time at the measured cost; one while the cost is unknown."""
        wanted = math.floor(seconds / self.sim.dt + 1e-9)
        if self.step_cost is None:
            return min(wanted, 1)
        return min(wanted, max(1, math.floor(self.chunk_seconds / self.step_cost)))

    def run_chunk(self, steps: int) -> None:
        """``steps`` substeps, the dragged pin moved along its path in cloth
        time; a divergence pauses on the newest calm kept state."""
        sim = self.sim
        self._kept.append((sim.state.copy(), sim.steps, float(np.abs(sim.state.v).max())))
        seconds = steps * sim.dt
        drag = self.drag
        if drag is not None and sim.control.pinned[drag[0]]:
            k, path = drag
            sim.move_pin(k, path.target(sim.state.x[k], sim.time + seconds, seconds))
        start = self.chunk_started = time.perf_counter()
        try:
            sim.advance(seconds)
        except DivergenceError as error:
            self._on_divergence(error)
            return
        finally:
            self.chunk_started = None
            self.snapshot = sim.snapshot()
        spent = time.perf_counter() - start
        self.chunk_ms = 1e3 * spent
        cost = spent / steps
        known = self.step_cost
        self.step_cost = cost if known is None else 0.7 * known + 0.3 * cost
        self.meter.add(time.perf_counter(), sim.time)

    def _on_divergence(self, error: DivergenceError) -> None:
        sim = self.sim
        calm = [kept for kept in self._kept if kept[2] <= CALM_SPEED]
        if calm or self._kept:
            state, steps, _ = (calm or list(self._kept))[0 if not calm else -1]
            sim.set_state(state.x, state.v, state.t, steps=steps)
        self._kept.clear()
        self.paused = True
        self.drag = None
        self.meter.restart()
        try:
            step = f"a for the automatic step, dt = {sim.automatic_dt():.3g} s"
        except Exception:  # no stable step to be found: the scene needs changing
            step = "[ to halve the step"
        self.diverged = (
            f"DIVERGED ({error}) Showing t = {sim.time:.3f} s, the last calm state kept. "
            f"Press {step}, then space to go on or b to restart."
        )
