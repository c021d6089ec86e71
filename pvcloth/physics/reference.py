"""The reference solution runs are measured against, and the measure.

A reference is the same scene run with :data:`REFERENCE_INTEGRATOR` at a
step far below the one compared (:func:`reference_dt`, the one rule every
user of a reference follows): the trade-off command and sweeps run one to
the end of a study (:func:`reference_run`), movies and ``pvcloth compare``
keep one beside the simulation for the ``error`` field
(:class:`FollowingReference`), and :func:`rms_distance` says how far a run
ended from it.
"""

from __future__ import annotations

import math

import numpy as np

from pvcloth.physics.simulation import Simulation
from pvcloth.scene.spec import Scene

#: The reference integrator: fourth order, so at a quarter of the smallest
#: step compared its own error is far below every run's.
REFERENCE_INTEGRATOR = "rk4"


def reference_dt(scene: Scene, smallest: float) -> float:
    """The reference's step for runs whose smallest step is ``smallest``
    (s): a quarter of it, and at most half the reference integrator's
    stable step on ``scene``.

    Examples
    --------
    >>> import pvcloth
    >>> scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    >>> reference_dt(scene, 1e-3)
    0.00025
    """
    limit = Simulation(scene, integrator=REFERENCE_INTEGRATOR, stability="ignore").stable_dt()
    return min(smallest / 4, 0.5 * limit)


def reference_step(scene: Scene, smallest: float, duration: float) -> float:
    """:func:`reference_dt`, shortened to divide ``duration`` into whole
    steps (a reference must end exactly where the runs end)."""
    return duration / math.ceil(duration / reference_dt(scene, smallest))


def reference_run(scene: Scene, duration: float, dt: float) -> Simulation:
    """The fine solution runs are compared with, advanced to ``duration``."""
    sim = Simulation(scene, integrator=REFERENCE_INTEGRATOR, dt=dt, stability="ignore")
    sim.advance(duration)
    return sim


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
    :data:`REFERENCE_INTEGRATOR` at :func:`reference_dt` of the followed
    step, from the followed simulation's state when it is made. A script
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
    >>> from pvcloth.physics.reference import FollowingReference
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
            dt = reference_dt(scene, sim.dt)
        self.sim = Simulation(scene, integrator=REFERENCE_INTEGRATOR, dt=dt, stability="ignore")
        if sim.time > 0:
            self.sim.set_state(sim.state.x, sim.state.v, sim.state.t)

    def error(self, sim: Simulation) -> np.ndarray:
        """Distance (m) of each of ``sim``'s points from the reference's at
        ``sim``'s time, shape (N,); the reference is advanced to that time."""
        behind = sim.time - self.sim.time
        if behind > 0:
            self.sim.advance(behind)
        return np.linalg.norm(sim.positions - self.sim.positions, axis=1)
