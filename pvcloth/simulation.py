"""The simulation: owns model, state and clock, and advances them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .errors import DivergenceError, SceneError
from .integrators import get_integrator
from .model import build_model
from .scene import STABILITY_POLICIES, Scene, load_scene
from .state import Control, State
from .validation import choice, real

#: No cloth point moves faster than this (m/s) unless the solver blew up.
SPEED_LIMIT = 1.0e4


class Simulation:
    """A cloth that moves.

    Parameters
    ----------
    scene : Scene
        What to simulate.
    integrator : str, optional
        Overrides ``scene.solver.integrator``.
    dt : float, optional
        Overrides ``scene.solver.dt`` (seconds per substep).
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
        If the step is above the stable step and the policy is ``"refuse"``.

    Examples
    --------
    >>> import pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
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
        self.model = build_model(scene, backend)
        self.integrator = get_integrator(integrator or scene.solver.integrator)
        #: The step asked for (scene or override); ``dt`` may be a substep of it.
        self.requested_dt = (
            scene.solver.dt if dt is None else real("dt", dt, minimum=0.0, exclusive=True)
        )
        self.reset()
        policy = scene.solver.stability if stability is None else stability
        policy = choice("stability", policy, STABILITY_POLICIES)
        self.dt = self._checked_step(self.requested_dt, policy)

    def _checked_step(self, dt: float, policy: str) -> float:
        """Apply the scene's stability policy to the requested step."""
        if policy == "ignore":
            return dt
        limit = self.stable_dt()
        if dt <= limit:
            return dt
        if policy == "substep":
            return dt / math.ceil(dt / (0.5 * limit))
        raise SceneError(
            "solver.dt",
            f"{dt:.4g} s is above the largest stable step of {self.integrator.name} for this "
            f"cloth, about {limit:.3g} s. Use dt <= {0.5 * limit:.3g}, the implicit_euler "
            f"integrator (stable at any step), or solver.stability = 'substep' to split "
            f"each step automatically ('ignore' runs it anyway).",
        )

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
        """The integrator's largest stable step near the current state."""
        return self.integrator.stable_dt(self.model, self.state, self.control)

    # -- pins ------------------------------------------------------------------

    def point_index(self, point) -> int:
        """Flat index of a point given as an index or an ``(i, j)`` pair."""
        nx, ny = self.shape
        if isinstance(point, (tuple, list)) and len(point) == 2:
            i, j = (int(p) for p in point)
            if not (0 <= i < nx and 0 <= j < ny):
                raise SceneError("point", f"({i}, {j}) is outside the {nx}x{ny} grid")
            return i + nx * j
        if isinstance(point, (int, np.integer)) and 0 <= point < nx * ny:
            return int(point)
        raise SceneError(
            "point", f"expected an index 0..{nx * ny - 1} or an (i, j) pair, got {point!r}"
        )

    def pin(self, point, position=None) -> None:
        """Hold a point at ``position`` (default: where it is now)."""
        k = self.point_index(point)
        target = self.state.x[k] if position is None else np.asarray(position, dtype=float)
        self.control.targets[k] = target
        self.control.pinned[k] = True
        self.control.refresh(self.model)

    def move_pin(self, point, position) -> None:
        """Set a pinned point's target; it gets there over the next advance."""
        k = self.point_index(point)
        if not self.control.pinned[k]:
            raise SceneError("point", f"point {k} is not pinned; pin it first")
        self.control.targets[k] = np.asarray(position, dtype=float)

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
        split into substeps if it became unstable."""
        factor = real("factor", factor, minimum=0.0, exclusive=True)
        for springs in self.model.springs:
            for group in springs.groups:
                group.stiffness *= factor
                group.damping *= factor
        self.model.refresh()
        if self.dt > self.stable_dt():
            self.dt = self._checked_step(self.dt, "substep")

    def set_wind(self, wind) -> None:
        """Replace the scene's wind mid-run (``None`` removes the term).

        Parameters
        ----------
        wind : WindSpec or None
        """
        from .forces import Wind
        from .scene import WindSpec

        if wind is not None and not isinstance(wind, WindSpec):
            raise SceneError("wind", f"expected a WindSpec or None, got {type(wind).__name__}")
        forces = [term for term in self.model.forces if not isinstance(term, Wind)]
        if wind is not None and (wind.drag > 0 or wind.lift > 0):
            forces.append(Wind.from_spec(wind, self.model.shape))
        self.model.forces = forces
        self.scene = self.scene.replace(wind=wind)

    def set_integrator(self, name: str) -> None:
        """Switch integrator mid-run; the step asked for is kept if stable,
        else split into substeps."""
        self.integrator = get_integrator(name)
        self.dt = self._checked_step(self.requested_dt, "substep")

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
        """
        seconds = real("seconds", seconds, minimum=0.0)
        self._owed += seconds
        n = math.floor(self._owed / self.dt + 1e-9)
        self._owed = max(self._owed - n * self.dt, 0.0)
        if n == 0:
            return
        pinned = self.control.pinned_index
        start = self.state.x[pinned].copy()
        goal = self.control.targets[pinned].copy()
        for s in range(1, n + 1):
            self._substep(pinned, start + (goal - start) * (s / n))

    def step(self) -> None:
        """One substep of ``dt``."""
        self._owed = 0.0
        pinned = self.control.pinned_index
        self._substep(pinned, self.control.targets[pinned])

    def _substep(self, pinned: np.ndarray, pin_positions: np.ndarray) -> None:
        dt = self.dt
        state = self.state
        # Pinned points have zero inverse mass, so integrators move them at
        # their velocity: the one that lands them on their target.
        pin_velocity = (pin_positions - state.x[pinned]) / dt
        state.v[pinned] = pin_velocity
        model = self.model
        model.set_time(state.t)
        with np.errstate(all="ignore"):
            new = self.integrator.step(model, state, self.control, dt)
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
            raise DivergenceError(self._divergence_message(speed))
        self.state = new
        self.steps += 1

    def _uniform_clock(self, state) -> bool:
        # Time as steps * dt avoids summing round-off, while dt never changed.
        return abs(state.t - self.steps * self.dt) <= 1e-9 * max(1.0, state.t)

    def _divergence_message(self, speed: float) -> str:
        what = "became non-finite" if not np.isfinite(speed) else f"reached {speed:.3g} m/s"
        message = (
            f"simulation diverged at t = {self.state.t:.6g} s (step {self.steps + 1}) "
            f"with {self.integrator.name} at dt = {self.dt:.3g} s: point velocities {what}."
        )
        try:
            stable = self.stable_dt()
        except Exception:  # the last good state may be too wild to linearise
            stable = None
        if stable and 0 < stable < math.inf:
            message += (
                f" The largest stable step here is about {stable:.3g} s; "
                f"try dt = {0.5 * stable:.3g} s."
            )
        else:
            message += " Try a smaller dt or the symplectic_euler integrator with damping."
        return message
