"""The simulation: owns model, state and clock, and advances them."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from pvcloth.errors import DivergenceError, SceneError
from pvcloth.physics.integrators import get_integrator
from pvcloth.physics.model import build_model
from pvcloth.physics.state import Control, State
from pvcloth.scene.spec import MAX_LENGTH, STABILITY_POLICIES, Scene, load_scene
from pvcloth.scene.validation import choice, integer, real

#: No cloth point moves faster than this (m/s) unless the solver blew up.
SPEED_LIMIT = 1.0e4
#: A step counts as stable up to this share of the estimated limit. The
#: estimate is exact only for the linearised cloth at rest; far from rest,
#: nonlinear coupling has destabilised steps above about 0.8 of it (and
#: explicit Euler at 0.9995 of it diverged), so a step just under it is refused.
STABLE_SHARE = 0.8
#: Automatic steps and substeps aim at this share of the estimated limit.
SAFE_SHARE = 0.5
#: Automatic step of an integrator that is stable at any step: a 60 fps frame.
FRAME_DT = 1.0 / 60.0
#: How far ``Simulation.scale_stiffness`` may take the springs from the scene's.
MIN_STIFFNESS_SCALE, MAX_STIFFNESS_SCALE = 1e-6, 1e6
#: Most steps one call may take: hours of wall time even for a tiny cloth.
MAX_STEPS = 10**7
#: Peak bytes per cloth point while a simulation is built: the stable-step
#: estimate's sparse Jacobians dominate (8.7 kB at 256x256, falling with size,
#: from `python benchmarks/memory.py`; stepping needs a tenth of it).
PEAK_BYTES_PER_POINT = 8700


class Simulation:
    """A cloth that moves.

    Parameters
    ----------
    scene : Scene
        What to simulate.
    integrator : str, optional
        Overrides ``scene.solver.integrator``.
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

    Raises
    ------
    SceneError
        If the step is above 0.8 of the stable step (:data:`STABLE_SHARE`)
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
            raise SceneError("scene", f"expected a pvcloth.Scene, got {type(scene).__name__}")
        self.scene = scene
        #: Springs' stiffness and damping relative to the scene's (scale_stiffness).
        self.stiffness_scale = 1.0
        _check_memory(scene)
        self.model = build_model(scene, backend)
        self.integrator = get_integrator(integrator or scene.solver.integrator)
        #: The step asked for (scene or override), or ``None`` for an automatic
        #: one; ``dt`` is the step actually taken (a substep of it, perhaps).
        self.requested_dt = (
            scene.solver.dt if dt is None else real("dt", dt, minimum=0.0, exclusive=True)
        )
        self.reset()
        policy = scene.solver.stability if stability is None else stability
        policy = choice("stability", policy, STABILITY_POLICIES)
        self.dt = self._checked_step(self.requested_dt, policy)

    @property
    def dt_source(self) -> str:
        """Where ``dt`` comes from: ``"auto"`` (at most half the stable step),
        ``"given"`` (the scene or an override) or ``"substep"`` (the given
        step split into equal substeps for stability)."""
        if self.requested_dt is None:
            return "auto"
        return "given" if self.dt == self.requested_dt else "substep"

    def _checked_step(self, dt: float | None, policy: str) -> float:
        """The step to take: automatic when ``dt`` is None, else ``dt`` checked
        against the stable step as ``policy`` says."""
        if dt is None:
            return self.automatic_dt()
        if policy == "ignore":
            return dt
        limit = self._positive_stable_dt()
        if dt <= STABLE_SHARE * limit:
            return dt
        if policy == "substep":
            return dt / math.ceil(dt / (SAFE_SHARE * limit))
        raise SceneError(
            "solver.dt",
            f"{dt:.4g} s is above the largest stable step allowed for {self.integrator.name} "
            f"on this cloth, {STABLE_SHARE:g} of its estimated limit of {limit:.3g} s (the "
            f"estimate is exact only near rest). Use dt <= {SAFE_SHARE * limit:.3g} (or leave "
            f"solver.dt out to get that step automatically), the implicit_euler integrator "
            f"(stable at any step), or solver.stability = 'substep' to split each step "
            f"automatically ('ignore' runs it anyway).",
        )

    def automatic_dt(self) -> float:
        """The step ``solver.dt`` left out gives: the largest that is at most
        half the stable step and divides a 1/60 s frame (whole steps per
        frame, so that advancing by frames lands exactly on them)."""
        limit = self._positive_stable_dt()
        return FRAME_DT / max(1, math.ceil(FRAME_DT / (SAFE_SHARE * limit)))

    def _positive_stable_dt(self) -> float:
        limit = self.stable_dt()
        if not limit > 0.0:
            raise SceneError(
                "solver.integrator",
                f"{self.integrator.name} is unstable at every step on this cloth (its stiffest "
                f"mode is undamped and grows at any dt). Give the springs some damping, or use "
                f"symplectic_euler, verlet, rk4 or implicit_euler.",
            )
        return limit

    @classmethod
    def from_file(cls, path: str | Path, **overrides) -> Simulation:
        """Load a TOML scene and build its simulation."""
        return cls(load_scene(path), **overrides)

    def reset(self) -> None:
        """Back to the initial state, pins as the scene gives them."""
        x = self.model.rest_positions.copy()
        self.state = State(x, np.zeros_like(x), 0.0)
        self.control = Control.from_model(self.model)
        self.steps = 0
        self._owed = 0.0  # simulated time asked for but not yet stepped
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
        ['pinned', 'speed', 'stretch', 'velocity']
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
        nx, ny = self.shape
        origin = {"auto": "automatic", "given": "as given", "substep": "substep"}[self.dt_source]
        return [
            ("scene", self.scene.name),
            ("cloth", f"{nx} x {ny} points, backend {self.model.backend}"),
            ("time", f"{self.time:.6g} s after {self.steps} steps"),
            ("integrator", f"{self.integrator.name}, dt {self.dt:.4g} s ({origin})"),
            ("pins", f"{self.control.pinned_index.size} point(s)"),
        ]

    def __repr__(self) -> str:
        nx, ny = self.shape
        return (
            f"<Simulation {self.scene.name!r}: {nx} x {ny} points, t = {self.time:.6g} s "
            f"({self.steps} steps), {self.integrator.name} at dt = {self.dt:.4g} s>"
        )

    def _repr_html_(self) -> str:
        from pvcloth.scene.spec import _html_table

        return _html_table(f"Simulation {self.scene.name!r}", self.summary())

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

    @property
    def shape(self) -> tuple[int, int]:
        """``(nx, ny)``: points along the width and the height."""
        return self.model.shape[1], self.model.shape[0]

    def energy(self) -> dict[str, float]:
        """Kinetic, potential and total energy in joules."""
        kinetic = self.model.kinetic_energy(self.state.v)
        potential = self.model.potential_energy(self.state.x)
        return {"kinetic": kinetic, "potential": potential, "total": kinetic + potential}

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
        nx, ny = self.shape
        if isinstance(point, (tuple, list)) and len(point) == 2:
            i = integer("point[0] (i)", point[0], minimum=0, maximum=nx - 1)
            j = integer("point[1] (j)", point[1], minimum=0, maximum=ny - 1)
            return i + nx * j
        if isinstance(point, (int, np.integer)) and not isinstance(point, bool):
            return integer("point", point, minimum=0, maximum=nx * ny - 1)
        raise SceneError(
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
            raise SceneError(
                "position",
                f"expected three finite coordinates (x, y, z) in metres, got {position!r}",
            )
        if np.abs(target).max() > MAX_LENGTH:
            raise SceneError(
                "position", f"each coordinate must be within +-{MAX_LENGTH:g} m, got {position!r}"
            )
        return target

    def pin(self, point, position=None) -> None:
        """Hold a point at ``position`` (default: where it is now)."""
        k = self.point_index(point)
        target = self.state.x[k] if position is None else self._target(position)
        self.control.targets[k] = target
        self.control.pinned[k] = True
        self.control.refresh(self.model)

    def move_pin(self, point, position) -> None:
        """Set a pinned point's target; it gets there over the next advance."""
        k = self.point_index(point)
        if not self.control.pinned[k]:
            raise SceneError("point", f"point {k} is not pinned; pin it first")
        self.control.targets[k] = self._target(position)

    def unpin(self, point) -> None:
        """Let a pinned point move freely."""
        k = self.point_index(point)
        self.control.pinned[k] = False
        self.control.refresh(self.model)

    def restore_scene_pins(self) -> None:
        """Drop every pin added since the start; keep the scene's own."""
        self.control.pinned[:] = self.model.pinned
        self.control.refresh(self.model)

    @property
    def pinned_indices(self) -> np.ndarray:
        return self.control.pinned_index

    def scale_stiffness(self, factor: float) -> None:
        """Multiply every spring's stiffness and damping by ``factor`` (> 0),
        e.g. from a slider; the step is re-checked against the new limit and
        split into substeps if it became unstable.

        The springs may end up between :data:`MIN_STIFFNESS_SCALE` and
        :data:`MAX_STIFFNESS_SCALE` times the scene's (beyond that the
        stable-step arithmetic under- or overflows); ``stiffness_scale`` says
        where they are."""
        factor = real("factor", factor, minimum=0.0, exclusive=True)
        scale = self.stiffness_scale * factor
        if not MIN_STIFFNESS_SCALE <= scale <= MAX_STIFFNESS_SCALE:
            raise SceneError(
                "factor",
                f"{factor:g} would make the springs {scale:.3g} times the scene's; allowed "
                f"is {MIN_STIFFNESS_SCALE:g} to {MAX_STIFFNESS_SCALE:g} times",
            )
        self.stiffness_scale = scale
        for springs in self.model.springs:
            for group in springs.groups:
                group.stiffness *= factor
                group.damping *= factor
        self.model.refresh()
        # Re-derived from the step asked for, so that softer springs give
        # back a step that stiffer ones had split.
        self.dt = self._checked_step(self.requested_dt, "substep")

    def set_wind(self, wind) -> None:
        """Replace the scene's wind mid-run (``None`` removes the term).

        Parameters
        ----------
        wind : WindSpec or None
        """
        from pvcloth.physics.forces import Wind
        from pvcloth.scene.spec import WindSpec

        if wind is not None and not isinstance(wind, WindSpec):
            raise SceneError("wind", f"expected a WindSpec or None, got {type(wind).__name__}")
        forces = [term for term in self.model.forces if not isinstance(term, Wind)]
        if wind is not None and (wind.drag > 0 or wind.lift > 0):
            forces.append(Wind.from_spec(wind, self.model.shape))
        self.model.forces = forces
        self.scene = self.scene.replace(wind=wind)

    def set_integrator(self, name: str) -> None:
        """Switch integrator mid-run; the step asked for is kept if stable,
        else split into substeps (an automatic step is chosen anew)."""
        self.integrator = get_integrator(name)
        self.dt = self._checked_step(self.requested_dt, "substep")

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
        if dt is not None:
            dt = real("dt", dt, minimum=0.0, exclusive=True)
        stability = choice("stability", stability, STABILITY_POLICIES)
        self.dt = self._checked_step(dt, stability)
        self.requested_dt = dt

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
        seconds = real("seconds", seconds, minimum=0.0)
        self.check_run_length(self._owed + seconds)
        self._owed += seconds
        n = math.floor(self._owed / self.dt + 1e-9)
        self._owed = max(self._owed - n * self.dt, 0.0)
        if n == 0:
            return
        pinned = self.control.pinned_index
        start = self.state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        try:
            for s in range(1, n + 1):
                self._substep(pinned, start + (goal - start) * (s / n))
        finally:  # after a divergence too: the mesh shows the last good state
            self.update_mesh()

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
        self._owed = 0.0
        pinned = self.control.pinned_index
        try:
            self._substep(pinned, self.control.targets[pinned])
        finally:
            self.update_mesh()

    def _substep(self, pinned: np.ndarray, pin_positions: np.ndarray) -> None:
        dt = self.dt
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
            new.t = (self.steps + 1) * dt if self._uniform_clock(state) else state.t + dt
            if model.obstacles:
                model.collide(state.x, new.x, new.v, self.control.movable_index, state.t, new.t)
        new.x[pinned] = pin_positions
        new.v[pinned] = pin_velocity
        if new.checked is not None and not model.obstacles:
            speed, finite = new.checked  # pinned points included (their v is set above)
            speed = speed if finite else math.inf
        else:
            speed = np.abs(new.v).max(initial=0.0)
            finite = np.isfinite(new.x).all()
        if not speed <= SPEED_LIMIT or not finite:
            self._spare = spare
            raise DivergenceError(self._divergence_message(speed))
        self._spare = state
        self.state = new
        self.steps += 1

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
