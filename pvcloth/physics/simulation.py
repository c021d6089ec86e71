"""The simulation: owns model, state and clock, and advances them."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pvcloth.errors import DivergenceError, InputError, SceneError
from pvcloth.physics import step_policy
from pvcloth.physics.adaptive import StepController, steady_step
from pvcloth.physics.auto import Choice, choose_integrator
from pvcloth.physics.blas import one_blas_thread
from pvcloth.physics.integrators import get_integrator
from pvcloth.physics.model import build_model
from pvcloth.physics.pipeline import Guard, Step, build_pipeline
from pvcloth.physics.state import Control, Snapshot, State
from pvcloth.scene.files import load_scene
from pvcloth.scene.parts import AUTO, MAX_LENGTH, STABILITY_POLICIES, WindSpec
from pvcloth.scene.spec import Scene, html_table
from pvcloth.scene.validation import choice, integer, real

#: No cloth point moves faster than this (m/s) unless the solver blew up.
SPEED_LIMIT = 1.0e4
#: How far ``Simulation.scale_stiffness`` may take the springs from the scene's.
MIN_STIFFNESS_SCALE, MAX_STIFFNESS_SCALE = 1e-6, 1e6
#: Top-level scene keys that may change during a run (:meth:`Simulation.update`).
LIVE_KEYS = ("springs", "gravity", "air_damping", "wind", "solver")
#: Most steps one call may take: hours of wall time even for a tiny cloth.
MAX_STEPS = 10**7
#: Peak bytes per cloth point while a simulation is built: the stable-step
#: estimate's sparse Jacobians dominate (9.2 kB at 256x256, falling with size,
#: from `python benchmarks/memory.py`; stepping needs a tenth of it).
PEAK_BYTES_PER_POINT = 9200


class Simulation:
    """A cloth that moves.

    Parameters
    ----------
    scene : Scene
        What to simulate.
    integrator : str, optional
        Overrides ``scene.solver.integrator``; ``"auto"`` (with
        ``solver.tolerance``) lets a short probe choose
        (:mod:`pvcloth.physics.auto`).
    dt : float, optional
        Overrides ``scene.solver.dt`` (seconds per substep). When neither
        gives a step, the simulation takes the largest step that is at most
        half the integrator's stable step and divides a 1/60 s frame evenly
        (the frame itself for an integrator stable at any step).
    stability : {"refuse", "substep", "ignore"}, optional
        Overrides ``scene.solver.stability``: what to do with a step above
        the integrator's stable step.
    backend : {"auto", "numba", "numpy"}, optional
        Compiled kernels or pure NumPy for the spring forces (default:
        ``PVCLOTH_BACKEND`` or ``"auto"``: numba when installed). Both give
        the same results to round-off.

    Attributes
    ----------
    scene : Scene
        What runs, live edits included (:meth:`update`): the one source of
        truth, saved by checkpoints.
    model : Model
        The constants: grid, masses, force terms, obstacles.
    state : State
        The current positions ``(N, 3)`` m, velocities ``(N, 3)`` m/s and
        time s. Each step makes a new current state (in the memory of the
        one before last, when nobody else holds that): a state you hold is
        never written again, so another thread may read it.
    control : Control
        Pins and their targets.
    integrator : Integrator
    dt : float
        The step taken, seconds (``scene.solver.dt`` or a substep of it, or
        the automatic step); with a tolerance, the next step the controller
        will try (:attr:`last_step` is the one last taken).
    controller : StepController or None
        Chooses each step when the scene gives ``solver.tolerance``.
    choice : Choice or None
        What ``solver.integrator = "auto"`` chose, and why.
    steps : int
        Steps taken since the start.
    owed : float
        Seconds asked for but not yet stepped (less than ``dt``).
    stiffness_scale : float
        Springs relative to the scene's at the start.

    Raises
    ------
    SceneError
        If the step is above 0.8 of the stable step
        (:data:`~pvcloth.physics.step_policy.STABLE_SHARE`)
        and the policy is ``"refuse"``, or if no step is stable.

    Examples
    --------
    >>> import pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> sim.dt_source
    'auto'
    >>> sim.advance(1 / 60)
    >>> sim.positions.shape, round(sim.time, 4)
    ((64, 3), 0.0167)
    """

    def __init__(
        self,
        scene: Scene,
        *,
        integrator: str | None = None,
        dt: float | None = None,
        stability: str | None = None,
        backend: str | None = None,
    ):
        if not isinstance(scene, Scene):
            raise InputError("scene", f"expected a pvcloth.Scene, got {type(scene).__name__}")
        # The overrides become part of the scene: sim.scene is what runs.
        given = {"solver.integrator": integrator, "solver.dt": dt, "solver.stability": stability}
        scene = scene.with_overrides({k: v for k, v in given.items() if v is not None})
        #: How ``solver.integrator = "auto"`` chose (``None`` if the scene named one).
        self.choice: Choice | None = None
        scene = self._resolve_auto(scene)
        #: The scene being simulated, live edits (:meth:`update`) included:
        #: its ``solver.dt`` is the step asked for (``None``: automatic),
        #: ``dt`` the step taken (a substep of it, perhaps).
        self.scene = scene
        #: Springs' stiffness and damping relative to the scene's at the start
        #: (changed by :meth:`scale_stiffness`).
        self.stiffness_scale = 1.0
        _check_memory(scene)
        self.model = build_model(scene, backend)
        #: What each step goes through after the integrator (obstacles, pins,
        #: self-collision, the divergence guard): only what the scene needs.
        self.pipeline = build_pipeline(self.model)
        self.integrator = get_integrator(scene.solver.method, scene.solver.iterations)
        self.reset()
        #: Chooses every step when the scene gives ``solver.tolerance``
        #: (:mod:`pvcloth.physics.adaptive`); ``None`` for fixed steps.
        self.controller: StepController | None = None
        self.dt = self._checked_step(scene.solver.dt, scene.solver.stability)
        self._start_controller()

    @property
    def requested_dt(self) -> float | None:
        """The step asked for (``scene.solver.dt``), or ``None`` for an automatic one."""
        return self.scene.solver.dt

    @property
    def dt_source(self) -> str:
        """Where ``dt`` comes from: ``"auto"`` (at most half the stable step),
        ``"given"`` (the scene or an override) or ``"substep"`` (the given
        step split into equal substeps for stability, or for
        self-collision: :meth:`contact_step`)."""
        if self.controller is not None:
            return "adaptive"
        if self.requested_dt is None:
            return "auto"
        return "given" if self.dt == self.requested_dt else "substep"

    def _checked_step(self, dt: float | None, policy: str) -> float:
        """The step to take (:func:`~pvcloth.physics.step_policy.checked_step`)."""
        return step_policy.checked_step(
            self.scene, dt, policy, self.integrator.name, self.stable_dt, self.contact_step()
        )

    def automatic_dt(self) -> float:
        """The step ``solver.dt`` left out gives: the largest that is at most
        half the stable step (and the :meth:`contact_step`) and divides a
        1/60 s frame (whole steps per frame, so that advancing by frames
        lands exactly on them)."""
        stable = step_policy.positive(self.stable_dt(), self.integrator.name)
        return step_policy.automatic_step(stable, self.contact_step())

    def contact_step(self) -> float:
        """The longest step (s) self-collision can hold one layer up on
        another in (:meth:`SelfCollision.longest_step
        <pvcloth.physics.self_collision.SelfCollision.longest_step>`); a
        longer step is split into equal substeps under it, whatever the
        stability policy. Infinite without ``[self_collision]``."""
        return step_policy.contact_step(self.model, self.scene)

    @classmethod
    def from_file(cls, path: str | Path, **overrides) -> Simulation:
        """Load a TOML scene and build its simulation."""
        return cls(load_scene(path), **overrides)

    def reset(self) -> None:
        """Back to the initial state, pins as the scene gives them."""
        x = self.model.rest_positions.copy()
        self.state = State(x, np.zeros_like(x), 0.0)
        self.control = Control.from_model(self.model)
        #: Steps taken since the start.
        self.steps = 0
        #: Simulated seconds asked for (by advance) but not yet stepped: less than dt.
        self.owed = 0.0
        self._spare = None  # a replaced state the next step may reuse
        self.update_mesh()

    # -- the cloth as a PyVista mesh -------------------------------------------

    _mesh = None  # built on first use of ``mesh``: physics runs without PyVista

    @property
    def mesh(self):
        """The cloth as a ``pyvista.StructuredGrid`` of dimensions ``(nx, ny, 1)``.

        The same object for the life of the simulation, its points and point
        data updated in place after every :meth:`advance`, :meth:`step` and
        :meth:`reset`, so a plotter showing it or a script holding it sees the
        current cloth. Point ``k`` is solver point ``k``. Point data (colour
        by any of them, e.g. ``sim.plot(scalars="speed")``):

        - ``velocity`` (N, 3), m/s
        - ``speed`` (N,), m/s
        - ``stretch`` (N,), local length over rest length (1 at rest)
        - ``force`` (N,), N, mean elastic force of the springs at the point
        - ``energy`` (N,), J/m^2, elastic energy density
          (:mod:`pvcloth.physics.fields`)
        - ``pinned`` (N,), 1 where the point is pinned, else 0

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> mesh = sim.mesh
        >>> mesh.dimensions, mesh.n_points
        ((8, 8, 1), 64)
        >>> sim.advance(0.1)
        >>> sim.mesh is mesh, bool(mesh.points[:, 2].min() < sim.model.rest_positions[:, 2].min())
        (True, True)
        >>> sorted(mesh.point_data.keys())
        ['energy', 'force', 'pinned', 'speed', 'stretch', 'velocity']
        """
        if self._mesh is None:
            from pvcloth.visual.view import (
                cloth_mesh,  # the view layer, imported only when asked for
            )

            self._mesh = cloth_mesh(self)
        return self._mesh

    def update_mesh(self) -> None:
        """Copy the current state into :attr:`mesh` (done after every advance;
        call it after editing ``sim.state`` by hand). Costs nothing until the
        mesh is first used."""
        if self._mesh is not None:
            from pvcloth.visual.view import update_cloth_mesh

            update_cloth_mesh(self._mesh, self)

    def plot(self, **kwargs):
        """Show the cloth as ``mesh.plot()`` does (keywords go to
        :func:`pyvista.plot`); the cloth's colour unless ``scalars`` is given.

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> sim.advance(0.2)
        >>> sim.plot(scalars="stretch", off_screen=True, screenshot="stretch.png")
        """
        from pvcloth.visual.view import plot_cloth

        return plot_cloth(self, **kwargs)

    # -- how it reads in a terminal and a notebook -------------------------------

    def summary(self) -> list[tuple[str, str]]:
        """``(topic, text)`` rows: scene, size, clock, integrator and step, pins."""
        nx, ny = self.resolution
        origin = step_policy.STEP_SOURCES[self.dt_source]
        if self.controller is not None:
            origin += (
                f", tolerance {self.controller.tolerance:g} m, {self.controller.rejected} rejected"
            )
        return [
            ("scene", self.scene.name),
            ("cloth", f"{nx} x {ny} points, backend {self.model.backend}"),
            ("time", f"{self.time:.6g} s after {self.steps} steps"),
            ("integrator", f"{self.integrator.name}, dt {self.dt:.4g} s ({origin})"),
            ("pins", f"{self.control.pinned_index.size} point(s)"),
        ]

    def __repr__(self) -> str:
        nx, ny = self.resolution
        return (
            f"<Simulation {self.scene.name!r}: {nx} x {ny} points, t = {self.time:.6g} s "
            f"({self.steps} steps), {self.integrator.name} at "
            + ("adaptive " if self.controller is not None else "")
            + f"dt = {self.dt:.4g} s>"
        )

    def _repr_html_(self) -> str:
        return html_table(f"Simulation {self.scene.name!r}", self.summary())

    # -- what viewers read -----------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time in seconds."""
        return self.state.t

    @property
    def positions(self) -> np.ndarray:
        """Read-only ``(N, 3)`` positions in VTK point order (``i + nx * j``)."""
        view = self.state.x.view()
        view.flags.writeable = False
        return view

    @property
    def velocities(self) -> np.ndarray:
        """Read-only ``(N, 3)`` velocities in VTK point order."""
        view = self.state.v.view()
        view.flags.writeable = False
        return view

    def snapshot(self) -> Snapshot:
        """This instant, copied whole for a viewer on another thread
        (:class:`~pvcloth.physics.state.Snapshot`).

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> sim.advance(0.1)
        >>> now = sim.snapshot()
        >>> sim.advance(0.1)
        >>> round(now.t, 3), bool((now.x != sim.positions).any()), now.pinned.tolist()
        (0.1, True, [56, 63])
        """
        state = self.state  # one state throughout, should a step replace it meanwhile
        return Snapshot(
            x=state.x.copy(),
            v=state.v.copy(),
            t=state.t,
            steps=self.steps,
            pinned=self.control.pinned_index.copy(),
            integrator=self.integrator.name,
            dt=self.dt,
            dt_source=self.dt_source,
            adaptive=self.controller is not None,
            wind=self.scene.wind,
        )

    @property
    def resolution(self) -> tuple[int, int]:
        """``(nx, ny)``: points along the width and the height, as in
        ``scene.cloth.resolution`` and the mesh's dimensions (VTK's order;
        ``model.shape`` is NumPy's ``(ny, nx)``)."""
        return self.model.shape[1], self.model.shape[0]

    def energy(self) -> dict[str, float]:
        """Kinetic, potential and total energy in joules."""
        kinetic = self.model.kinetic_energy(self.state.v)
        potential = self.model.potential_energy(self.state.x)
        return {"kinetic": kinetic, "potential": potential, "total": kinetic + potential}

    @property
    def last_step(self) -> float:
        """The step last taken (s): ``dt``, or an adaptive run's last
        accepted step (``dt`` is then the next one it will try)."""
        if self.controller is not None and self.controller.taken > 0.0:
            return self.controller.taken
        return self.dt

    @property
    def stats(self) -> dict[str, float | int]:
        """What the steps have been: ``steps`` taken, and for an adaptive
        run also ``rejected``, the ``shortest``, ``longest`` and ``last``
        accepted steps (s) and the ``mean`` step, simulated time over steps
        (all since the run began, a resumed run's since its resume except
        ``steps`` and ``rejected``).

        Examples
        --------
        >>> import pvcloth
        >>> scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
        >>> sim = pvcloth.Simulation(scene.with_overrides({"solver.integrator": "rk23",
        ...                                                "solver.tolerance": 1e-4}))
        >>> sim.advance(0.1)
        >>> stats = sim.stats
        >>> stats["shortest"] <= stats["mean"] <= stats["longest"], stats["rejected"] >= 0
        (True, True)
        """
        stats: dict[str, float | int] = {"steps": self.steps}
        control = self.controller
        if control is not None:
            stats.update(
                rejected=control.rejected,
                shortest=control.shortest,
                longest=control.longest,
                last=self.last_step,
                mean=self.time / self.steps if self.steps else math.nan,
            )
        return stats

    def stable_dt(self) -> float:
        """The integrator's largest stable step near the current state.

        It accounts for the springs, their dashpots and air damping (the
        linearised cloth), not for the wind or contact: a strong wind on a
        light cloth can need a smaller step than this, which neither the
        ``refuse`` check nor ``substep`` will know (the divergence guard
        still stops such a run, and its message says so)."""
        return self.integrator.stable_dt(self.model, self.state, self.control)

    # -- pins ------------------------------------------------------------------

    def point_index(self, point) -> int:
        """Flat index of a point given as an index or an ``(i, j)`` pair."""
        nx, ny = self.resolution
        if isinstance(point, (tuple, list)) and len(point) == 2:
            i = integer("point[0] (i)", point[0], minimum=0, maximum=nx - 1, error=InputError)
            j = integer("point[1] (j)", point[1], minimum=0, maximum=ny - 1, error=InputError)
            return i + nx * j
        if isinstance(point, (int, np.integer)) and not isinstance(point, bool):
            return integer("point", point, minimum=0, maximum=nx * ny - 1, error=InputError)
        raise InputError(
            "point",
            f"expected an index 0..{nx * ny - 1} or an (i, j) pair of whole numbers, got {point!r}",
        )

    @staticmethod
    def _target(position) -> np.ndarray:
        """A pin target: three finite coordinates in metres, within
        ``MAX_LENGTH`` of the origin (like every position in a scene)."""
        try:
            target = np.asarray(position, dtype=float)
        except (TypeError, ValueError, OverflowError):
            target = None
        if target is None or target.shape != (3,) or not np.isfinite(target).all():
            raise InputError(
                "position",
                f"expected three finite coordinates (x, y, z) in metres, got {position!r}",
            )
        if np.abs(target).max() > MAX_LENGTH:
            raise InputError(
                "position", f"each coordinate must be within +-{MAX_LENGTH:g} m, got {position!r}"
            )
        return target

    def pin(self, point, position=None) -> None:
        """Hold a point at ``position`` (default: where it is now)."""
        k = self.point_index(point)
        target = self.state.x[k] if position is None else self._target(position)
        self.control.pin(k, target)

    def move_pin(self, point, position) -> None:
        """Set a pinned point's target; it gets there over the next advance."""
        k = self.point_index(point)
        if not self.control.pinned[k]:
            raise InputError("point", f"point {k} is not pinned; pin it first")
        self.control.targets[k] = self._target(position)

    def unpin(self, point) -> None:
        """Let a pinned point move freely."""
        self.control.unpin(self.point_index(point))

    def restore_scene_pins(self) -> None:
        """Drop every pin added since the start; keep the scene's own."""
        self.control.pinned = self.model.pinned

    @property
    def pinned_indices(self) -> np.ndarray:
        return self.control.pinned_index

    # -- live edits ------------------------------------------------------------

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
        self.model.apply(scene)
        solver, was = scene.solver, self.scene.solver
        if (solver.method, solver.iterations) != (self.integrator.name, was.iterations):
            self.integrator = get_integrator(solver.method, solver.iterations)
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

    @classmethod
    def resumed(
        cls,
        scene: Scene,
        *,
        dt: float,
        stiffness_scale: float,
        state: State,
        steps: int,
        owed: float,
        pinned: np.ndarray,
        targets: np.ndarray,
        integrator_state: dict[str, np.ndarray],
        backend: str | None = None,
        controller_state: np.ndarray | None = None,
    ) -> Simulation:
        """A simulation that continues a saved one exactly (what
        :func:`pvcloth.load_checkpoint` builds from checked entries): the
        scene as edited, the step that was being taken (not re-derived), the
        state, the clock, the pins, the integrator's own state, an adaptive
        run's controller memory and the backend (the two sum forces in
        different orders)."""
        sim = cls(scene, dt=dt, stability="ignore", backend=backend)
        sim.scene = scene  # the saved solver settings, not the override above
        sim.stiffness_scale = stiffness_scale
        sim.state = State(state.x.copy(), state.v.copy(), state.t)
        sim.steps, sim.owed = steps, owed
        sim.control.targets[:] = targets
        sim.control.pinned = pinned
        sim.integrator.set_state(integrator_state)
        if sim.controller is not None and controller_state is not None:
            sim.controller.set_state(controller_state, step=dt)
            sim.dt = dt
        sim.update_mesh()
        return sim

    # -- time stepping ---------------------------------------------------------

    def advance(self, seconds: float) -> None:
        """Simulate ``seconds`` more, in fixed substeps of ``dt``.

        Time not covered by whole substeps is carried over to the next call,
        so many short advances add up to the same run as one long one. Pinned
        points move in a straight line to their targets over the substeps.

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
            self._advance_adaptive(seconds)
            return
        self.check_run_length(self.owed + seconds)
        self.owed += seconds
        n = math.floor(self.owed / self.dt + 1e-9)
        self.owed = max(self.owed - n * self.dt, 0.0)
        if n == 0:
            return
        pinned = self.control.pinned_index
        start = self.state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        try:
            with self._one_pool():
                for s in range(1, n + 1):
                    self._substep(pinned, start + (goal - start) * (s / n))
        finally:  # after a divergence too: the mesh shows the last good state
            self.update_mesh()

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
            self.update_mesh()

    def _one_pool(self):
        """On the compiled kernels, BLAS on one thread while an integrator
        that calls it steps: the kernels' OpenMP threads take the cores (see
        :mod:`pvcloth.physics.blas`)."""
        if self.model.backend == "numba" and self.integrator.uses_blas:
            return one_blas_thread()
        return contextlib.nullcontext()

    def _start_controller(self) -> None:
        """A step controller when the scene gives a tolerance (and an
        integrator that measures its error), else none
        (:func:`~pvcloth.physics.step_policy.step_controller`)."""
        self.controller = step_policy.step_controller(
            self.scene,
            self.integrator,
            self.dt,
            self.stable_dt,
            self.contact_step(),
            lambda tolerance: step_policy.starting_step(
                self.integrator, self.model, self.control, self.state, tolerance
            ),
        )
        if self.controller is not None:
            self.dt = self.controller.step

    def _resolve_auto(self, scene: Scene) -> Scene:
        """``scene`` with ``solver.integrator = "auto"`` replaced by the
        integrator a probe chose (kept in :attr:`choice`), so what runs, and
        what a checkpoint saves, names it; other scenes as they are."""
        if scene.solver.method != AUTO:
            return scene
        self.choice = choose_integrator(scene, type(self))
        return scene.with_overrides({"solver.integrator": self.choice.name})

    def _advance_adaptive(self, seconds: float) -> None:
        """Steps chosen by the controller until exactly ``seconds`` later;
        rejected ones are retried shorter and leave no trace."""
        control = self.controller
        steady = self.integrator.steady_steps
        end = self.state.t + seconds
        pinned = self.control.pinned_index
        start_time = self.state.t
        start = self.state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        try:
            while self.state.t < end - 1e-12 * max(1.0, end):
                if control.step < control.min_step:
                    raise DivergenceError(
                        f"simulation stopped at t = {self.state.t:.6g} s: {self.integrator.name}"
                        f" needed steps under {control.min_step:g} s (solver.min_dt) to keep "
                        f"its error under {control.tolerance:g} m per second; the step had "
                        f"fallen to {control.step:.3g} s. A blow-up, or a tolerance too tight "
                        f"for this cloth: loosen solver.tolerance, lower solver.min_dt, or "
                        f"try an implicit integrator"
                    )
                natural = control.step
                remaining = end - self.state.t
                if steady and control.taken > 0.0:
                    # Keep the step (and its factorisation) unless worth changing.
                    h = steady_step(natural, control.taken, remaining)
                else:
                    h = min(natural, remaining)
                    if remaining - h < 1e-9 * h:  # no sliver of a step left over
                        h = remaining
                share = (self.state.t + h - start_time) / seconds
                if self._substep(pinned, start + (goal - start) * share, dt=h):
                    if h < natural:
                        # Cut short to land on the end, not for its error:
                        # the next advance starts from the step the controller
                        # wanted (else every frame's end restarted it small).
                        control.step = max(control.step, natural)
                    self.dt = control.step
        finally:  # after a divergence too: the mesh shows the last good state
            self.update_mesh()

    def _substep(
        self, pinned: np.ndarray, pin_positions: np.ndarray, dt: float | None = None
    ) -> bool:
        """One step of ``dt`` (default: the fixed step); with a controller,
        ``False`` when its error estimate rejected it (nothing changed)."""
        dt = self.dt if dt is None else dt
        state = self.state
        # Pinned points have zero inverse mass, so integrators move them at
        # their velocity: the one that lands them on their target.
        pin_velocity = (pin_positions - state.x[pinned]) / dt
        state.v[pinned] = pin_velocity
        model = self.model
        model.set_time(state.t)
        spare = self._take_spare()
        with np.errstate(all="ignore"):
            new = self.integrator.step(model, state, self.control, dt, out=spare)
            if self.controller is not None:
                self.controller.step = dt
                if not self.controller.judge(self.integrator.error):
                    self._spare = spare
                    return False
                new.t = state.t + dt
            else:
                new.t = (self.steps + 1) * dt if self._uniform_clock(state) else state.t + dt
        step = Step(state, new, self.control, dt, pinned, pin_positions, pin_velocity)
        for operator in self.pipeline:
            operator(step)
        speed, finite = step.reports[Guard.name]
        if not speed <= SPEED_LIMIT or not finite:
            self._spare = spare
            raise DivergenceError(self._divergence_message(speed))
        self._spare = state
        self.state = new
        self.steps += 1
        return True

    def _take_spare(self) -> State | None:
        """The state the last step replaced, for the next step to write over,
        if nothing outside the simulation still holds it or its arrays (a
        ``before = sim.state``, a kept ``sim.positions`` view); else ``None``
        and the integrator takes new memory. Reusing it saves fresh pages at
        every step: 2.6 ms of a 4.5 ms step at 256x256 went to page faults."""
        spare, self._spare = self._spare, None
        if spare is None or _reference_counts(spare) != _UNSHARED:
            return None
        return spare

    def _uniform_clock(self, state) -> bool:
        # Time as steps * dt avoids summing round-off, while dt never changed.
        return abs(state.t - self.steps * self.dt) <= 1e-9 * max(1.0, state.t)

    def _divergence_message(self, speed: float) -> str:
        what = "became non-finite" if not np.isfinite(speed) else f"reached {speed:.3g} m/s"
        message = (
            f"simulation diverged at t = {self.state.t:.6g} s (step {self.steps + 1}) "
            f"with {self.integrator.name} at dt = {self.dt:.3g} s: point velocities {what}."
        )
        stable = None
        if np.isfinite(self.state.x).all() and np.isfinite(self.state.v).all():
            try:
                stable = self.stable_dt()
            except Exception:  # the last good state may be too wild to linearise
                stable = None
        if stable and 0 < stable < math.inf:
            message += (
                f" The largest stable step of the springs here is about {stable:.3g} s; "
                f"try dt = {0.5 * stable:.3g} s."
            )
        else:
            message += " Try a smaller dt or the symplectic_euler integrator with damping."
        if any(term.name == "wind" for term in self.model.forces):
            message += (
                " That estimate leaves the wind out, which can make a step unstable on its own "
                "(strong wind on a light cloth): a smaller step or weaker wind may be needed."
            )
        return message


def _reference_counts(state: State) -> tuple[int, int, int]:
    return sys.getrefcount(state), sys.getrefcount(state.x), sys.getrefcount(state.v)


def _unshared_counts() -> tuple[int, int, int]:
    # What _reference_counts gives for a state held only by a local name,
    # called the way _take_spare calls it (the interpreter decides the
    # numbers; measured here rather than assumed).
    spare = State(np.empty((1, 3)), np.empty((1, 3)))
    return _reference_counts(spare)


_UNSHARED = _unshared_counts()


def available_memory() -> float | None:
    """Bytes of memory available to a new allocation (Linux's MemAvailable),
    or None where that cannot be read."""
    try:
        with open("/proc/meminfo", encoding="ascii") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return 1024.0 * float(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return None


def _check_memory(scene: Scene) -> None:
    """Refuse, before any allocation, a cloth the machine cannot hold."""
    nx, ny = scene.cloth.resolution
    need = float(nx * ny * PEAK_BYTES_PER_POINT)
    have = available_memory()
    if have is not None and need > 0.9 * have:
        raise SceneError(
            "cloth.resolution",
            f"{nx} x {ny} = {nx * ny:,} points need about {need / 1e9:.3g} GB while the "
            f"simulation is built ({PEAK_BYTES_PER_POINT / 1e3:.1f} kB per point), and "
            f"{have / 1e9:.3g} GB are available. Use fewer points: about "
            f"{int((0.9 * have / PEAK_BYTES_PER_POINT) ** 0.5)} per side would fit.",
        )
