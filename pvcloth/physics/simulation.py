"""The simulation: owns the model, the state and the clock, and advances them.

:class:`Simulation` gathers parts that each do one job: the step size
(:mod:`~pvcloth.physics.step_policy`), what follows the integrator in a step
(:mod:`~pvcloth.physics.pipeline`), the clocks (:mod:`~pvcloth.physics.clocks`),
live edits (:mod:`~pvcloth.physics.live_edits`) and pins
(:mod:`~pvcloth.physics.pins`). Here are what ties them: the state's double
buffer, one step, and what a viewer or a checkpoint reads. The cloth as a
PyVista mesh is the layer above's (:class:`pvcloth.Simulation`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pvcloth.errors import DivergenceError, InputError
from pvcloth.physics import step_policy
from pvcloth.physics.adaptive import StepController
from pvcloth.physics.auto import Choice, choose_integrator
from pvcloth.physics.clocks import Clocks
from pvcloth.physics.integrators import get_integrator
from pvcloth.physics.live_edits import LiveEdits
from pvcloth.physics.memory import check_memory
from pvcloth.physics.model import build_model
from pvcloth.physics.pins import Pins
from pvcloth.physics.pipeline import Guard, PinVelocities, Step, build_pipeline
from pvcloth.physics.state import Control, Snapshot, State
from pvcloth.scene.files import load_scene
from pvcloth.scene.parts import AUTO, MAX_LENGTH
from pvcloth.scene.spec import Scene, html_table

#: No cloth point moves faster than this (m/s) unless the solver blew up.
SPEED_LIMIT = 1.0e4


class Simulation(Clocks, LiveEdits, Pins):
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
        time s, as read-only views: change them with :meth:`set_state`.
        The simulation owns two states and writes each step into the one not
        current, so a state read now is overwritten two steps later: copy
        what you keep (``state.copy()``, :meth:`snapshot`).
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
        check_memory(scene)
        self.model = build_model(scene, backend)
        #: What each step goes through after the integrator (obstacles, pins,
        #: self-collision, the divergence guard): only what the scene needs.
        self.pipeline = build_pipeline(self.model)
        solver = scene.solver
        self.integrator = get_integrator(solver.method, solver.iterations, solver.accelerator)
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
        stability policy. Infinite without ``[self_collision]``, and for an
        integrator whose solve holds the layers (``holds_layers``, when
        ``[self_collision] in_solve`` asks for it)."""
        contact = self.model.self_collision
        if contact is not None and contact.in_solve and self.integrator.holds_layers:
            return math.inf
        return step_policy.contact_step(self.model, self.scene)

    @classmethod
    def from_file(cls, path: str | Path, **overrides) -> Simulation:
        """Load a TOML scene and build its simulation."""
        return cls(load_scene(path), **overrides)

    def reset(self) -> None:
        """Back to the initial state, pins as the scene gives them."""
        x = self.model.rest_positions.copy()
        # The double buffer: each step reads the current state and writes the
        # spare one, then they swap. Reusing the memory saves fresh pages at
        # every step (2.6 ms of a 4.5 ms step at 256x256 went to page faults).
        self._state = State(x, np.zeros_like(x), 0.0)
        self._public: State | None = None  # read-only views of _state, made when asked
        self._spare = State(np.empty_like(x), np.empty_like(x))
        self.pin_velocities = PinVelocities(len(x))
        self.control = Control.from_model(self.model)
        #: Steps taken since the start.
        self.steps = 0
        #: Simulated seconds asked for (by advance) but not yet stepped: less than dt.
        self.owed = 0.0
        self.integrator.restart()  # a multistep method starts again
        self._state_changed()

    @property
    def state(self) -> State:
        """The current state, as read-only views (see the class's attributes).

        Views, not the arrays themselves: the simulation's own arrays stay
        writable for the compiled kernels, which take a read-only array by
        numba's slow typing path (60 us more per step at 64x64)."""
        if self._public is None:
            now = self._state
            self._public = State(_read_only(now.x), _read_only(now.v), now.t)
        return self._public

    def set_state(self, positions=None, velocities=None, time=None, *, steps=None) -> None:
        """Replace the current state: the way to edit it by hand.

        Parameters
        ----------
        positions, velocities : array_like, shape (N, 3), optional
            New positions (m, each coordinate within
            :data:`~pvcloth.scene.parts.MAX_LENGTH`) and velocities (m/s,
            each speed under :data:`SPEED_LIMIT`); copied. Left out: as now.
        time : float, optional
            The new time (s, finite and not negative); left out: as now.
        steps : int, optional
            The steps counted as taken (a restored run's); left out: as now.

        Examples
        --------
        >>> import numpy as np, pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> push = np.zeros((64, 3)); push[:, 1] = 1.5
        >>> sim.set_state(velocities=push)
        >>> float(sim.velocities[:, 1].mean())
        1.5
        >>> sim.set_state(velocities=np.zeros((3, 3)))
        Traceback (most recent call last):
        ...
        pvcloth.errors.InputError: velocities: expected shape (64, 3), got (3, 3)
        """
        now = self._state
        x = now.x if positions is None else _array("positions", positions, now.x.shape)
        v = now.v if velocities is None else _array("velocities", velocities, now.v.shape)
        if np.abs(x).max(initial=0.0) > MAX_LENGTH:
            raise InputError("positions", f"each coordinate must be within +-{MAX_LENGTH:g} m")
        # The guard's rule (and the checkpoint loader's): each component bounded.
        if np.abs(v).max(initial=0.0) > SPEED_LIMIT:
            raise InputError("velocities", f"each component must be within +-{SPEED_LIMIT:g} m/s")
        t = now.t
        if time is not None:
            t = float(time)
            if not (math.isfinite(t) and t >= 0.0):
                raise InputError("time", f"expected a finite time >= 0 s, got {time!r}")
        if steps is not None:
            if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
                raise InputError("steps", f"expected a whole number >= 0, got {steps!r}")
            self.steps = int(steps)
        # Into the spare buffer, then swapped in: the current arrays are never written.
        spare = self._spare
        np.copyto(spare.x, x)
        np.copyto(spare.v, v)
        spare.t = t
        self._spare, self._state, self._public = self._state, spare, None
        self.integrator.restart()  # an edited state has no past a multistep method may use
        self._state_changed()

    def _state_changed(self) -> None:
        """Called whenever the current state changed (steps, reset, set_state):
        the layer above refreshes its mesh here. Nothing to do in the physics."""

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
        return self._state.t

    @property
    def positions(self) -> np.ndarray:
        """Read-only ``(N, 3)`` positions in VTK point order (``i + nx * j``)."""
        return self.state.x

    @property
    def velocities(self) -> np.ndarray:
        """Read-only ``(N, 3)`` velocities in VTK point order."""
        return self.state.v

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
        state = self._state  # one state throughout, should a step replace it meanwhile
        return Snapshot(
            x=state.x.copy(),
            v=state.v.copy(),
            t=state.t,
            steps=self.steps,
            pinned=self.control.pinned_index.copy(),
            integrator=self.integrator_label,
            dt=self.dt,
            dt_source=self.dt_source,
            adaptive=self.controller is not None,
            wind=self.scene.wind,
        )

    @property
    def integrator_label(self) -> str:
        """The integrator's name, with ``+ACCELERATOR`` when the scene names
        one and the integrator iterates (``"fast_bdf2+lbfgs"``): what the
        window and the compared panels show."""
        accelerator = self.scene.solver.accelerator
        named = accelerator is not None and self.integrator.iterative
        return self.integrator.name + (f"+{accelerator}" if named else "")

    @property
    def resolution(self) -> tuple[int, int]:
        """``(nx, ny)``: points along the width and the height, as in
        ``scene.cloth.resolution`` and the mesh's dimensions (VTK's order;
        ``model.shape`` is NumPy's ``(ny, nx)``)."""
        return self.model.shape[1], self.model.shape[0]

    def energy(self) -> dict[str, float]:
        """Kinetic, potential and total energy in joules."""
        kinetic = self.model.kinetic_energy(self._state.v)
        potential = self.model.potential_energy(self._state.x)
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
        return self.integrator.stable_dt(self.model, self._state, self.control)

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
        sim.set_state(state.x, state.v, state.t, steps=steps)
        sim.owed = owed
        sim.control.set_state({"pinned": pinned, "targets": targets})
        sim.integrator.set_state(integrator_state)
        if sim.controller is not None and controller_state is not None:
            sim.controller.set_state(controller_state, step=dt)
            sim.dt = dt
        return sim

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
                self.integrator, self.model, self.control, self._state, tolerance
            ),
        )
        if self.controller is not None:
            self.dt = self.controller.step
        self.integrator.set_error_control(self.controller is not None)

    def _resolve_auto(self, scene: Scene) -> Scene:
        """``scene`` with ``solver.integrator = "auto"`` replaced by the
        integrator a probe chose (kept in :attr:`choice`), so what runs, and
        what a checkpoint saves, names it; other scenes as they are."""
        if scene.solver.method != AUTO:
            return scene
        self.choice = choose_integrator(scene, type(self))
        return scene.with_overrides({"solver.integrator": self.choice.name})

    def _substep(
        self, pinned: np.ndarray, pin_positions: np.ndarray, dt: float | None = None
    ) -> bool:
        """One step of ``dt`` (default: the fixed step) from the current state
        into the spare one, which becomes current; with a controller,
        ``False`` when its error estimate rejected it (nothing changed)."""
        dt = self.dt if dt is None else dt
        state, pin_velocity = self.pin_velocities(self._state, pinned, pin_positions, dt)
        model = self.model
        model.set_time(state.t)
        spare = self._spare
        with np.errstate(all="ignore"):
            try:
                new = self.integrator.step(model, state, self.control, dt, out=spare)
            except DivergenceError as error:
                if self.controller is None:
                    raise
                # A solver that did not converge (Newton's) is a rejected
                # step under error control: a shorter one converges in fewer
                # iterations, down to solver.min_dt (whose error quotes this).
                self.controller.step = dt
                self.controller.judge(math.inf)
                self.controller.failure = str(error)
                return False
            if self.controller is not None:
                self.controller.step = dt
                if not self.controller.judge(self.integrator.error):
                    return False
                new.t = state.t + dt
            else:
                new.t = (self.steps + 1) * dt if self._uniform_clock(state) else state.t + dt
        step = Step(
            state,
            new,
            self.control,
            dt,
            pinned,
            pin_positions,
            pin_velocity,
            integrator_check=self.integrator.check,
            held=self.integrator.held_contacts(new.x, new.t) if self.model.obstacles else [],
            held_layers=self.integrator.held_layers(new.x) if self.model.self_collision else None,
        )
        for operator in self.pipeline:
            operator(step)
        speed, finite = step.reports[Guard.name]
        if not speed <= SPEED_LIMIT or not finite:
            raise DivergenceError(self._divergence_message(speed))
        # The state replaced is the next step's spare (an integrator that
        # returned new arrays leaves the old spare to the collector).
        self._spare, self._state, self._public = self._state, new, None
        self.steps += 1
        return True

    def _divergence_message(self, speed: float) -> str:
        what = "became non-finite" if not np.isfinite(speed) else f"reached {speed:.3g} m/s"
        message = (
            f"simulation diverged at t = {self._state.t:.6g} s (step {self.steps + 1}) "
            f"with {self.integrator.name} at dt = {self.dt:.3g} s: point velocities {what}."
        )
        stable = None
        if np.isfinite(self._state.x).all() and np.isfinite(self._state.v).all():
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


def _read_only(array: np.ndarray) -> np.ndarray:
    """A view of ``array`` that cannot be written through."""
    view = array.view()
    view.flags.writeable = False
    return view


def _array(name: str, value, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a finite float array of ``shape``, or an :class:`InputError`."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InputError(
            name, f"expected numbers of shape {shape}, got {type(value).__name__}"
        ) from None
    if array.shape != shape:
        raise InputError(name, f"expected shape {shape}, got {array.shape}")
    if not np.isfinite(array).all():
        raise InputError(name, "every value must be finite")
    return array
