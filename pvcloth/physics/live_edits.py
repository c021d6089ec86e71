"""Live edits: changing a running simulation's scene by the keys scene
files use, checked whole before anything changes.

:class:`LiveEdits` is one part of :class:`~pvcloth.physics.simulation.Simulation`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from pvcloth.errors import InputError
from pvcloth.physics.integrators import get_integrator
from pvcloth.scene.parts import STABILITY_POLICIES, WindSpec
from pvcloth.scene.spec import Scene
from pvcloth.scene.validation import choice, real

#: How far ``Simulation.scale_stiffness`` may take the springs from the scene's.
MIN_STIFFNESS_SCALE, MAX_STIFFNESS_SCALE = 1e-6, 1e6
#: Top-level scene keys that may change during a run (:meth:`LiveEdits.update`).
LIVE_KEYS = ("springs", "gravity", "air_damping", "wind", "solver")


class LiveEdits:
    """The live-edit methods of :class:`~pvcloth.physics.simulation.Simulation`
    (they change its ``scene``, ``model``, ``integrator``, ``dt`` and
    ``controller`` together, or none of them)."""

    def update(self, changes: Mapping[str, Any], *, stability: str | None = None) -> None:
        """Change the running simulation's scene by dotted keys, the same keys
        scene files, ``--set`` and sweeps use (:mod:`pvcloth.scene.overrides`).

        The new scene is validated first; then the model's constants, the
        integrator and the step follow it, and ``sim.scene`` becomes it, so
        a checkpoint taken afterwards resumes the edited run. Nothing
        changes if any part is refused.

        Parameters
        ----------
        changes : mapping
            ``{"springs.structural.stiffness": 1200, "wind.velocity": [3, 0, 0],
            "solver.integrator": "rk4", "solver.dt": None, ...}``. Live keys
            are under ``springs`` (constants of the families the scene has),
            ``gravity``, ``air_damping``, ``wind`` and ``solver``.
        stability : {"refuse", "substep", "ignore"}, optional
            How the step is checked against the new stable step (default:
            the new scene's ``solver.stability``).

        Raises
        ------
        SceneError
            A bad key or value, or a step the policy refuses.
        InputError
            A key that cannot change during a run (the grid, the pins of the
            scene, the obstacles): build a new simulation for those.

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> sim.update({"springs.structural.stiffness": 800, "solver.integrator": "verlet"})
        >>> sim.scene.springs.structural.stiffness, sim.integrator.name
        (800.0, 'verlet')
        """
        self._apply(self.scene.with_overrides(changes), stability)

    def _apply(self, scene: Scene, stability: str | None) -> None:
        """Run ``scene`` from here on (see :meth:`update`)."""
        fixed = [
            f.name
            for f in dataclasses.fields(Scene)
            if f.name not in LIVE_KEYS and getattr(scene, f.name) != getattr(self.scene, f.name)
        ]

        def built(springs) -> list[bool]:  # which families exist: fixed by the build
            return [getattr(springs, f) is not None for f in ("structural", "shear", "bending")]

        if built(scene.springs) != built(self.scene.springs):
            fixed.append("springs (a family added or removed)")
        if fixed:
            raise InputError(
                "changes",
                f"{', '.join(fixed)} cannot change during a run; build a new Simulation for "
                f"that (live: {', '.join(LIVE_KEYS)})",
            )
        policy = scene.solver.stability if stability is None else stability
        policy = choice("stability", policy, STABILITY_POLICIES, error=InputError)
        scene = self._resolve_auto(scene)
        before = (self.scene, self.integrator, self.dt)
        solver, was = scene.solver, self.scene.solver
        integrator = self.integrator
        if (solver.method, solver.iterations, solver.accelerator) != (
            self.integrator.name,
            was.iterations,
            was.accelerator,
        ):
            # made first: one that refuses its settings leaves the run as it was
            integrator = get_integrator(solver.method, solver.iterations, solver.accelerator)
        self.model.apply(scene)
        self.integrator = integrator
        # The stable step depends on the springs, air damping and the
        # integrator, not on wind; gravity sets the contact step.
        step_depends = ("springs", "air_damping", "solver")
        if scene.self_collision is not None:
            step_depends += ("gravity",)
        if any(getattr(scene, name) != getattr(self.scene, name) for name in step_depends):
            try:
                current, self.scene = self.scene, scene  # the step rule reads the new solver
                try:
                    self.dt = self._checked_step(scene.solver.dt, policy)
                    self._start_controller()
                finally:
                    self.scene = current
            except BaseException:
                self.model.apply(before[0])
                self.integrator, self.dt = before[1], before[2]
                self._start_controller()
                raise
        self.scene = scene

    def scale_stiffness(self, factor: float) -> None:
        """Multiply every spring's stiffness and damping by ``factor`` (> 0),
        e.g. from a slider; the step is re-checked against the new limit and
        split into substeps if it became unstable (softer springs give back a
        step that stiffer ones split).

        The springs may end up between :data:`MIN_STIFFNESS_SCALE` and
        :data:`MAX_STIFFNESS_SCALE` times the scene's at the start (beyond
        that the stable-step arithmetic under- or overflows);
        ``stiffness_scale`` says where they are."""
        factor = real("factor", factor, minimum=0.0, exclusive=True, error=InputError)
        scale = self.stiffness_scale * factor
        if not MIN_STIFFNESS_SCALE <= scale <= MAX_STIFFNESS_SCALE:
            raise InputError(
                "factor",
                f"{factor:g} would make the springs {scale:.3g} times the scene's; allowed "
                f"is {MIN_STIFFNESS_SCALE:g} to {MAX_STIFFNESS_SCALE:g} times",
            )
        changes = {}
        for family in ("structural", "shear", "bending"):
            spec = getattr(self.scene.springs, family)
            if spec is not None:
                changes[f"springs.{family}.stiffness"] = spec.stiffness * factor
                changes[f"springs.{family}.damping"] = spec.damping * factor
        self.update(changes, stability="substep")
        self.stiffness_scale = scale

    def set_wind(self, wind) -> None:
        """Replace the scene's wind mid-run (``None`` removes the term).

        Parameters
        ----------
        wind : WindSpec or None
        """
        if wind is not None and not isinstance(wind, WindSpec):
            raise InputError("wind", f"expected a WindSpec or None, got {type(wind).__name__}")
        self._apply(self.scene.replace(wind=wind), "substep")

    def set_integrator(self, name: str) -> None:
        """Switch integrator mid-run; the step asked for is kept if stable,
        else split into substeps (an automatic step is chosen anew)."""
        self.update({"solver.integrator": name}, stability="substep")

    def set_step(self, dt: float | None, stability: str = "refuse") -> None:
        """Ask for a new step mid-run: ``None`` for the automatic one (half
        the stable step for explicit integrators, 1/60 s for implicit
        ones), else ``dt`` in seconds, checked as ``stability`` says
        (``"refuse"`` raises :class:`SceneError` above the stable share and
        leaves the step as it was).

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(), integrator="implicit_euler")
        >>> sim.set_step(None); round(1 / sim.dt)
        60
        >>> sim.set_step(0.01); sim.dt, sim.dt_source
        (0.01, 'given')
        """
        self.update({"solver.dt": dt}, stability=stability)
