"""What the studies share: the reference run, the step rule, timed runs and
the error measure.

The trade-off command, sweeps and ``benchmarks/implicit_crossover.py``
compare runs with a reference of the same scene, so they must agree on how
the reference is made and how far a run is from it; this module is that one
definition.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from pvcloth.errors import DivergenceError
from pvcloth.physics.simulation import Simulation
from pvcloth.scene.spec import Scene

#: The reference integrator: fourth order, so at a quarter of the smallest
#: step compared its own error is far below every run's.
REFERENCE_INTEGRATOR = "rk4"


def dividing_step(duration: float, dt: float) -> float:
    """The step nearest ``dt`` that divides ``duration`` into whole steps.

    Every run of a study must end exactly at ``duration``: a run that stops
    short by a fraction of a step is off by an error of first order in dt,
    which would hide every method's true order.

    Examples
    --------
    >>> dividing_step(0.25, 0.003)
    0.0030120481927710845
    """
    return duration / max(1, round(duration / dt))


def scene_step(scene: Scene) -> float:
    """The scene's step, or the automatic one it gets when it gives none."""
    if scene.solver.dt is not None:
        return scene.solver.dt
    return Simulation(scene, stability="ignore").dt


def reference_step(scene: Scene, smallest: float, duration: float) -> float:
    """The reference's step: a quarter of the smallest step compared, at
    most half the reference integrator's stable step, dividing ``duration``."""
    limit = Simulation(scene, integrator=REFERENCE_INTEGRATOR, stability="ignore").stable_dt()
    dt = min(smallest / 4, 0.5 * limit)
    return duration / math.ceil(duration / dt)


def reference_run(scene: Scene, duration: float, dt: float) -> Simulation:
    """The fine solution runs are compared with, advanced to ``duration``."""
    sim = Simulation(scene, integrator=REFERENCE_INTEGRATOR, dt=dt, stability="ignore")
    sim.advance(duration)
    return sim


@dataclass
class TimedRun:
    """One run of a study and what it cost.

    Attributes
    ----------
    sim : Simulation
        Where it ended (the last good state if it diverged).
    stable : bool
        Whether it reached the end without diverging.
    message : str
        The divergence message, or ``""``.
    wall : float
        Wall-clock seconds of the run (building the simulation excluded).
    """

    sim: Simulation
    stable: bool
    message: str
    wall: float

    @property
    def wall_per_sim_second(self) -> float:
        """Wall seconds per simulated second."""
        return self.wall / max(self.sim.time, self.sim.dt)


def timed_run(
    scene: Scene,
    duration: float,
    *,
    integrator: str | None = None,
    dt: float | None = None,
    tolerance: float | None = None,
) -> TimedRun:
    """Run ``scene`` for ``duration`` simulated seconds at exactly the step
    given (``stability="ignore"``: an unstable step really runs and shows as
    unstable), or with steps chosen for ``tolerance`` (m), timing it by the
    wall clock."""
    if tolerance is not None:
        scene = scene.with_overrides({"solver.tolerance": tolerance, "solver.dt": None})
    sim = Simulation(scene, integrator=integrator, dt=dt, stability="ignore")
    start = time.perf_counter()
    try:
        sim.advance(duration)
        stable, message = True, ""
    except DivergenceError as error:
        stable, message = False, str(error)
    return TimedRun(sim, stable, message, time.perf_counter() - start)


def rms_distance(x: np.ndarray, reference: np.ndarray) -> float:
    """Root mean square distance in metres between two ``(N, 3)`` position
    arrays, point by point.

    Examples
    --------
    >>> import numpy as np
    >>> rms_distance(np.zeros((2, 3)), np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]))
    0.7071067811865476
    """
    return float(np.sqrt(np.mean(np.sum((x - reference) ** 2, axis=1))))


class FollowingReference:
    """A fine reference run kept at the time of the simulation it follows,
    for the ``error`` field of movies and ``pvcloth compare``.

    It runs the followed simulation's scene (its edits included) with
    :data:`REFERENCE_INTEGRATOR` at a quarter of the followed step, at most
    half its own stable step, from the followed simulation's state when it
    is made. A script
    that moves pins between frames must move the reference's too (the movie
    does: it hands ``before_frame`` both).

    Parameters
    ----------
    sim : Simulation
        The simulation to follow, at its start.
    dt : float, optional
        The reference's step instead of the rule above.

    Examples
    --------
    >>> import pvcloth
    >>> from pvcloth.studies.runs import FollowingReference
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> reference = FollowingReference(sim)
    >>> sim.advance(0.1)
    >>> error = reference.error(sim)  # metres, per point
    >>> error.shape, bool(error.max() < 1e-3)
    ((64,), True)
    """

    def __init__(self, sim: Simulation, dt: float | None = None):
        scene = sim.scene
        if dt is None:
            limit = Simulation(scene, integrator=REFERENCE_INTEGRATOR, stability="ignore")
            dt = min(sim.dt / 4, 0.5 * limit.stable_dt())
        self.sim = Simulation(scene, integrator=REFERENCE_INTEGRATOR, dt=dt, stability="ignore")
        self.sim.state = sim.state.copy() if sim.time > 0 else self.sim.state

    def error(self, sim: Simulation) -> np.ndarray:
        """Distance (m) of each of ``sim``'s points from the reference's at
        ``sim``'s time, shape (N,); the reference is advanced to that time."""
        behind = sim.time - self.sim.time
        if behind > 0:
            self.sim.advance(behind)
        return np.linalg.norm(sim.positions - self.sim.positions, axis=1)
