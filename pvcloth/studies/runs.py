"""What the studies share besides the reference (which is
:mod:`pvcloth.physics.reference`): steps that end a run exactly on time,
the scene's own step, and runs timed by the wall clock."""

from __future__ import annotations

import time
from dataclasses import dataclass

from pvcloth.errors import DivergenceError
from pvcloth.physics.simulation import Simulation
from pvcloth.scene.spec import Scene


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
