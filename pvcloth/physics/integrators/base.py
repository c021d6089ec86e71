"""The interface every integrator follows, and the registry that finds them."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.stability import stiffest_mode
from pvcloth.physics.state import Control, State
from pvcloth.scene.parts import INTEGRATOR_NAMES

if TYPE_CHECKING:  # for annotations only: the model module imports no integrator
    from pvcloth.physics.model import Model

#: Name -> integrator class. Filled by :func:`register`.
INTEGRATORS: dict[str, type[Integrator]] = {}


def register(cls: type[Integrator]) -> type[Integrator]:
    """Class decorator that makes an integrator available by its ``name``,
    which must be one of the names scenes accept
    (:data:`pvcloth.scene.parts.INTEGRATOR_NAMES`)."""
    if cls.name not in INTEGRATOR_NAMES:
        raise ValueError(
            f"integrator {cls.name!r} is not in pvcloth.scene.parts.INTEGRATOR_NAMES; "
            f"add it there so scenes can ask for it"
        )
    INTEGRATORS[cls.name] = cls
    return cls


class Integrator(ABC):
    """Advances a cloth by one step.

    An integrator knows nothing about wind, spheres or pins: it asks the model
    for forces (and, if implicit, Jacobians) and treats points whose inverse
    mass is zero as immovable. The simulation sets pinned points' velocities
    and positions around each step.

    Attributes
    ----------
    name : str
        Registry key, as written in scene files.
    order : int
        Global order of accuracy.
    iterative : bool
        Whether it takes a fixed count of iterations per step, ``iterations``
        when made (``solver.iterations`` in a scene); ``backward_euler``
        iterates to a tolerance instead and is not one.
    interactive : bool
        Whether the window offers it when cycling integrators (a method
        that takes seconds per step is a measuring instrument, not one).
    converges_to : str or None
        The integrator this one approximates and whose answer it would give
        solved exactly (``"backward_euler"`` for the implicit ones), which
        studies measure its solver error against; ``None`` if exact.
    embedded : bool
        Whether each step measures its own error (an embedded pair, whose
        estimate it leaves in ``error``, metres): only these take
        ``solver.tolerance``.
    steady_steps : bool
        Whether a step costs more when its length differs from the last
        (it factorises a matrix that depends on the step): adaptive runs then
        change its step only when worth it (:mod:`pvcloth.physics.adaptive`).
    check : tuple of (float, bool) or None
        ``(largest speed in m/s, every value finite)`` of the state the
        last step made, when the step found them on its way (the compiled
        symplectic step does), so the divergence guard need not look again;
        ``None`` otherwise.
    min_iterations : int
        The fewest iterations a step of an ``iterative`` one may take with
        its default accelerator; :meth:`fewest_iterations` gives it per
        accelerator (:func:`~pvcloth.physics.integrators.get_integrator`
        refuses fewer, saying :attr:`too_few_iterations`; the window's
        ``i`` key passes over it when a scene gives fewer).
    too_few_iterations : str
        Why fewer than :meth:`fewest_iterations` are refused.
    max_step_growth : float
        The longest step it takes as a continuation of its last, as a
        multiple of that one (``inf``: any); adaptive runs grow the step by
        at most this factor (:class:`~pvcloth.physics.adaptive.StepController`).
    uses_blas : bool
        Whether its step calls BLAS (linear solves, long dot products): the
        simulation then holds BLAS to one thread around it
        (:mod:`pvcloth.physics.blas`); the explicit steps skip that cost
        (about 20 us, a sixth of a 32x32 step).
    holds_layers : bool
        Whether its own solve can hold one layer of the cloth up on another
        (:class:`~pvcloth.physics.integrators.penalties.LayerPenalty`), as
        it does when the scene asks (``[self_collision] in_solve``): then no
        step is split for self-collision
        (:meth:`~pvcloth.physics.simulation.Simulation.contact_step`).
    """

    name: str = ""
    order: int = 1
    description: str = ""
    iterative: bool = False
    min_iterations: int = 1
    too_few_iterations: str = ""
    converges_to: str | None = None
    interactive: bool = True
    max_step_growth: float = float("inf")
    uses_blas: bool = False
    holds_layers: bool = False
    embedded: bool = False
    steady_steps: bool = False
    check: tuple[float, bool] | None = None
    _forces: np.ndarray | None = None  # reused (N, 3) force buffer, newtons

    @classmethod
    def fewest_iterations(cls, accelerator: str | None = None) -> int:
        """The fewest iterations a step may take with ``accelerator`` (one
        of :data:`~pvcloth.scene.parts.ACCELERATORS`, ``None`` for the
        default): :attr:`min_iterations` unless a subclass says otherwise."""
        return cls.min_iterations

    @staticmethod
    def acceleration(model: Model, control: Control, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Acceleration (m/s^2, shape (N, 3)) at positions ``x`` (m) and
        velocities ``v`` (m/s): force over mass, zero for pinned points. The
        stages of the Runge-Kutta methods evaluate this."""
        return control.inv_mass[:, None] * model.compute_forces(x, v)

    def forces(self, model: Model, state: State) -> np.ndarray:
        """The total force at ``state``, in a buffer this integrator reuses
        from step to step (valid until its next call)."""
        if self._forces is None or self._forces.shape != state.x.shape:
            self._forces = np.empty_like(state.x)
        return model.compute_forces(state.x, state.v, out=self._forces)

    @abstractmethod
    def step(
        self, model: Model, state: State, control: Control, dt: float, out: State | None = None
    ) -> State:
        """Return the :class:`~pvcloth.physics.state.State` one step ``dt`` later.

        ``out``, if given, is a state of the same shape whose arrays the
        integrator may overwrite and return (the simulation keeps a spare
        one so that big grids do not get fresh memory at every step); an
        integrator may also ignore it and return new arrays. ``state`` is
        never changed."""

    def stable_dt(self, model: Model, state: State, control: Control) -> float:
        """Largest stable time step near ``state``: this integrator's own step
        applied to the cloth's stiffest mode (see :func:`largest_stable_step`).
        ``inf`` if no step is too large, 0 if none is small enough."""
        mode = stiffest_mode(model, state.x, state.v, control.inv_mass)
        return largest_stable_step(type(self), mode.omega, mode.alpha)

    def restart(self) -> None:
        """Forget what the integrator carries between steps (the simulation
        calls it when the state is reset or replaced by hand): a multistep
        method starts again from the new state alone. Nothing, by default."""
        return None

    def set_error_control(self, on: bool) -> None:
        """Told whether a step controller chooses its steps (``solver.tolerance``:
        :class:`~pvcloth.physics.adaptive.StepController`); nothing changes
        here."""
        return None

    def held_contacts(self, x: np.ndarray, t: float) -> list:
        """The points its last step's own solve held against obstacles, as
        :class:`~pvcloth.physics.obstacles.Contacts` with the normals at
        positions ``x`` (m, ``(N, 3)``) and time ``t`` (s); none unless the
        obstacles enter its solve (:mod:`pvcloth.physics.contact`)."""
        return []

    def held_layers(self, x: np.ndarray):
        """The pairs of layers its last step's own solve held apart
        (:class:`~pvcloth.physics.integrators.penalties.HeldPairs`: those
        pressed at positions ``x``, m, ``(N, 3)``, with the weights and
        normals the solve fixed at the step's start), for friction after the
        step; None unless the layers enter its solve (:attr:`holds_layers`
        and the scene's ``[self_collision] in_solve``)."""
        return None

    def get_state(self) -> dict[str, np.ndarray]:
        """Arrays the integrator carries between steps (saved in checkpoints)."""
        return {}

    def set_state(self, state: dict[str, np.ndarray]) -> None:
        """Restore what :meth:`get_state` returned (nothing, by default)."""
        return None

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def drift_error(dt: float, v_before: np.ndarray, v_after: np.ndarray) -> float:
    """The error estimate of a backward Euler step (metres): the largest
    distance between its position ``x + h v'`` and the trapezoidal rule's
    ``x + h (v + v') / 2`` from the same velocities, ``h |v' - v| / 2``.

    Both come from the one solve, so the estimate is free. It is the
    leading term of backward Euler's local error, ``h^2 a / 2`` (the
    trapezoidal rule's is a power of ``h`` smaller), and scales as ``h^2``.
    Velocities in m/s, shape (N, 3).

    Examples
    --------
    >>> import numpy as np
    >>> from pvcloth.physics.integrators.base import drift_error
    >>> drift_error(0.01, np.zeros((2, 3)), np.array([[0.0, 0, -0.1], [0.3, 0.4, 0]]))
    0.0025
    """
    change = v_after - v_before
    return 0.5 * dt * float(np.sqrt(np.einsum("ij,ij->i", change, change).max(initial=0.0)))


def reuse_or_allocate(out, state):
    """``out`` if there is one, else a new state shaped like ``state``."""
    if out is None:
        return State(np.empty_like(state.x), np.empty_like(state.v), state.t)
    return out


class _ModalOscillator:
    """A model of one unit-mass point whose every axis is a damped oscillator
    ``x'' = -omega^2 x - 2 alpha x'``: the stiffest mode, seen by an integrator."""

    n_points = 1
    mass = np.ones(1)

    def __init__(self, omega: float, alpha: float):
        self.stiffness, self.damping = omega * omega, 2.0 * alpha

    def compute_forces(self, x, v, out=None):
        f = -self.stiffness * x - self.damping * v
        if out is None:
            return f
        out[...] = f
        return out

    def jacobians(self, x, v):
        return -self.stiffness * sp.identity(3, format="csr"), -self.damping * sp.identity(
            3, format="csr"
        )

    def kick_drift(self, x, v, f, inv_mass, dt, x_out, v_out):
        np.multiply(f, inv_mass[:, None], out=f)
        np.multiply(f, dt, out=v_out)
        v_out += v
        np.multiply(v_out, dt, out=x_out)
        x_out += x


def step_matrix(integrator_class, omega: float, alpha: float, dt: float) -> np.ndarray:
    """The 2x2 matrix that maps ``(x, v)`` to the next step's ``(x, v)`` for
    one integrator on one damped mode."""
    model = _ModalOscillator(omega, alpha)
    control = Control(np.ones(1), np.zeros(1, bool), np.zeros((1, 3)))
    integrator = integrator_class()  # fresh: no warm start carried into the probe
    columns = []
    for x0, v0 in ((1.0, 0.0), (0.0, 1.0)):
        state = State(np.full((1, 3), x0), np.full((1, 3), v0))
        after = integrator.step(model, state, control, dt)
        columns.append((after.x[0, 0], after.v[0, 0]))
    return np.array(columns).T


def largest_stable_step(integrator_class, omega: float, alpha: float) -> float:
    """Largest ``dt`` at which the integrator's step matrix on the mode
    ``(omega, alpha)`` has spectral radius at most 1, found by bisection.

    Returns ``inf`` when no step up to ``10^4 / omega`` is unstable and 0 when
    every step is (explicit Euler on an undamped mode).
    """
    if omega == 0.0:
        return float("inf")

    def stable(dt):
        radius = np.abs(np.linalg.eigvals(step_matrix(integrator_class, omega, alpha, dt)))
        return bool(radius.max() <= 1.0 + 1e-9)

    low, high = 0.0, 1.0 / omega
    while stable(high):
        low, high = high, 2.0 * high
        if high > 1e4 / omega:
            return float("inf")
    for _ in range(50):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if stable(mid) else (low, mid)
    # Below a thousandth of the mode's period the "limit" is only round-off
    # letting a mode that grows at every step pass the test.
    return low if low * omega > 1e-3 else 0.0
