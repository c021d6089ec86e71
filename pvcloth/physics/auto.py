"""``solver.integrator = "auto"``: the method a short probe finds cheapest
for the scene's tolerance.

With a tolerance the question is not "which method is most accurate" but
"which reaches this error in the least wall time", and the answer depends
on the cloth: an explicit pair (``rk23``) is held below its stable step,
which shrinks as the springs stiffen and the cloth lightens
(``h < 2 / omega``), while an implicit one (``implicit_euler``) may take
whatever step the tolerance allows but pays a linear solve for each. So
each candidate is run for a short probe on the scene itself, with the
tolerance and its adaptive steps, and the one with the least wall time per
simulated second is kept. The stable step enters as the explicit pair's
largest step (:func:`pvcloth.physics.step_policy.step_controller`), the
stiffness through it and through the implicit solves' iteration counts.

Candidates are the methods whose error estimate bounds their error as the
step shrinks: ``rk23`` and ``implicit_euler``. ``fast_mass_spring`` is
left out, because its estimate sees the time discretisation but not its
iterations stopped early (measured at 1 to 7 cm on the bundled scenes,
``benchmarks/results/tradeoff_hanging16.md``), so it could not keep a
tolerance's promise; ``backward_euler`` is a measuring instrument (seconds
per step). Name an integrator to override the choice.

The probe measures wall time, so two runs near the crossover may choose
differently; the choice is written into ``sim.scene`` (what runs, and what
a checkpoint resumes) and :attr:`pvcloth.Simulation.choice` says why.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pvcloth.errors import DivergenceError
from pvcloth.scene.spec import Scene

#: Methods ``auto`` chooses between (see the module's description).
CANDIDATES = ("rk23", "implicit_euler")
#: Simulated seconds each candidate is probed for, at most ...
PROBE_TIME = 0.05
#: ... and wall seconds, at most (a slow candidate stops early: its
#: cost per simulated second is already known to be high).
PROBE_WALL = 0.5


@dataclass(frozen=True)
class Choice:
    """What ``auto`` chose, and the probe that chose it.

    Attributes
    ----------
    name : str
        The integrator chosen.
    costs : dict of str to float
        Wall seconds per simulated second each candidate took in the probe
        (``inf``: it diverged or could not keep the tolerance).
    probed : dict of str to float
        Simulated seconds each probe covered.
    """

    name: str
    costs: dict[str, float] = field(default_factory=dict)
    probed: dict[str, float] = field(default_factory=dict)

    @property
    def reason(self) -> str:
        """One line for ``pvcloth info``: the measured costs, cheapest first."""
        ranked = sorted(self.costs, key=self.costs.get)
        parts = [
            f"{name} {cost:.3g} s" if math.isfinite(cost) else f"{name} failed"
            for name, cost in ((name, self.costs[name]) for name in ranked)
        ]
        return (
            f"cheapest in a {max(self.probed.values(), default=0.0):.2g} s probe, wall time "
            f"per simulated second: {', '.join(parts)}"
        )


def choose_integrator(scene: Scene, simulation: Callable[[Scene], Any]) -> Choice:
    """Probe every candidate on ``scene`` (which has a tolerance) and return
    the cheapest (see the module's description).

    Parameters
    ----------
    scene : Scene
        With ``solver.tolerance``; its integrator is replaced by each
        candidate in turn.
    simulation : callable
        Builds the simulation that runs a probe from a scene:
        :class:`~pvcloth.physics.simulation.Simulation`, which calls this
        function (passed in, so this module does not import it back).

    Examples
    --------
    >>> import pvcloth
    >>> from pvcloth.physics.auto import choose_integrator
    >>> scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    >>> tolerant = scene.with_overrides({"solver.tolerance": 1e-3})
    >>> choice = choose_integrator(tolerant, pvcloth.Simulation)
    >>> choice.name in ("rk23", "implicit_euler"), sorted(choice.costs)
    (True, ['implicit_euler', 'rk23'])
    """
    costs, probed = {}, {}
    for name in CANDIDATES:
        candidate = scene.with_overrides({"solver.integrator": name})
        costs[name], probed[name] = _probe(simulation, candidate)
    best = min(CANDIDATES, key=costs.get)
    return Choice(best, costs, probed)


def _probe(simulation: Callable[[Scene], Any], scene: Scene) -> tuple[float, float]:
    """Wall seconds per simulated second of ``scene`` over a short run, and
    the simulated seconds run. The first step is not timed (it compiles
    kernels and factorises); then one step at a time, so that a slow
    candidate stops soon after :data:`PROBE_WALL`."""
    try:
        sim = simulation(scene)
        sim.advance(sim.controller.step)
        begun, start = sim.time, time.perf_counter()
        while sim.time - begun < PROBE_TIME and time.perf_counter() - start < PROBE_WALL:
            sim.advance(sim.controller.step)
    except DivergenceError:
        return math.inf, 0.0
    covered = sim.time - begun
    return (time.perf_counter() - start) / covered, covered
