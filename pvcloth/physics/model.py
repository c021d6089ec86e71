"""The model: everything about a cloth that does not change while it moves.

:func:`build_model` turns a :class:`~pvcloth.Scene` into a
:class:`Model` holding the grid, the masses, the default pins and exactly the
force terms the scene asks for, nothing more.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from pvcloth.physics.bending import PlateBending
from pvcloth.physics.forces import AirDamping, ForceTerm, Gravity, Wind
from pvcloth.physics.grid import initial_positions, lumped_masses
from pvcloth.physics.kernels import (
    SpringPlan,
    body_forces,
    kick_drift,
    resolve_backend,
    spring_forces,
    spring_projection,
    spring_projection_numpy,
    subtract_product,
    wind_forces,
)
from pvcloth.physics.obstacles import Contacts, build_obstacle
from pvcloth.physics.self_collision import SelfCollision
from pvcloth.physics.springs import Springs, SpringTable
from pvcloth.physics.state import REVISIONS


@dataclass
class Model:
    """Constants of a cloth simulation.

    Attributes
    ----------
    shape : (int, int)
        ``(ny, nx)``: rows along the height, points per row (NumPy's order;
        :attr:`pvcloth.Simulation.resolution` and the mesh give ``(nx, ny)``).
    rest_positions : ndarray, shape (N, 3)
        Initial positions in metres, in VTK point order (index ``i + nx * j``).
    mass : ndarray, shape (N,)
        Point masses in kg.
    pinned : ndarray of bool, shape (N,)
        Points pinned by the scene.
    springs : list of Springs
        The spring families the scene asks for (see :mod:`pvcloth.physics.springs`).
    bending : PlateBending or None
        The sheet's plate bending (:mod:`pvcloth.physics.bending`), ``None``
        unless the cloth has a bending rigidity.
    gravity : Gravity or None
    air : AirDamping or None
    wind : Wind or None
        The other force terms (:mod:`pvcloth.physics.forces`), each ``None``
        when the scene has none of it.
    obstacles : list
        Rigid obstacles (see :mod:`pvcloth.physics.obstacles`); empty if the
        scene has none, and then no collision code runs.
    self_collision : SelfCollision or None
        Contact of the cloth with itself (:mod:`pvcloth.physics.self_collision`);
        ``None`` unless the scene asks, and then no self-collision code runs.
    backend : {"numba", "numpy"}
        Where spring forces and the semi-implicit update are computed.
    revision : int
        A number new with every change of constants (:meth:`apply`) and never
        used by another model (:data:`~pvcloth.physics.state.REVISIONS`):
        integrators that cache factorisations key them by it.
    serial : int
        The model's own number, fixed for its life (what depends only on the
        grid, such as a sparsity pattern, is keyed by it).
    """

    shape: tuple[int, int]
    rest_positions: np.ndarray
    mass: np.ndarray
    pinned: np.ndarray
    springs: list[Springs] = field(default_factory=list)
    gravity: Gravity | None = None
    air: AirDamping | None = None
    wind: Wind | None = None
    obstacles: list = field(default_factory=list)
    backend: str = "numpy"
    self_collision: SelfCollision | None = None
    bending: PlateBending | None = None

    def __post_init__(self):
        self.serial = self.revision = next(REVISIONS)
        self._table: SpringTable | None = None
        self._plan = SpringPlan(self.springs, self.shape) if self.backend == "numba" else None
        if self._plan is not None and self.bending is not None:
            self._plan.set_plate(self.bending.matrix)

    @property
    def n_points(self) -> int:
        return self.mass.size

    @property
    def forces(self) -> list[ForceTerm]:
        """Every force term: springs, plate bending, then the other forces."""
        bending = [self.bending] if self.bending is not None else []
        return [*self.springs, *bending, *self.other_forces]

    @property
    def other_forces(self) -> list[ForceTerm]:
        """The force terms that are not springs (gravity, air damping, wind)."""
        return [term for term in (self.gravity, self.air, self.wind) if term is not None]

    # What the implicit integrators ask of the terms besides the springs
    # (they hold springs and plate bending in their matrices and the rest as
    # loads): these questions, so that no integrator reads a term's fields.

    @property
    def bending_matrix(self) -> sp.csr_matrix | None:
        """Plate bending's constant ``Q`` (N/m, ``(N, N)``): energy
        ``x_c^T Q x_c / 2`` per coordinate; ``None`` without plate bending."""
        return self.bending.matrix if self.bending is not None else None

    def bending_hessian(self) -> sp.csr_matrix | None:
        """``Q`` for every coordinate, ``(3N, 3N)`` in the point-major order
        of the other Jacobians (made once); ``None`` without plate bending."""
        return self.bending.hessian() if self.bending is not None else None

    @property
    def air_rate(self) -> float:
        """Air damping's rate (1/s): its force is ``-rate * m * v``; 0 without."""
        return self.air.rate if self.air is not None else 0.0

    def add_gravity(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Add the weights (N, shape (N, 3)) to ``out``; nothing without gravity."""
        if self.gravity is not None:
            self.gravity.accumulate(x, v, out)

    def add_wind(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> bool:
        """Add the wind's force (N, shape (N, 3)) at positions ``x`` (m) and
        velocities ``v`` (m/s) to ``out``; ``False`` (nothing added) without wind."""
        if self.wind is None:
            return False
        if self._plan is not None:
            wind_forces(self.wind, x, v, out, self.shape)
        else:
            self.wind.accumulate(x, v, out)
        return True

    def add_other_forces(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Add every force but the springs' (gravity, air damping, wind; N,
        shape (N, 3)) at ``x`` (m) and ``v`` (m/s) to ``out``."""
        for term in (self.gravity, self.air):
            if term is not None:
                term.accumulate(x, v, out)
        self.add_wind(x, v, out)

    def spring_table(self) -> SpringTable:
        """Every spring of every family as one flat table (kept until the
        constants change)."""
        if self._table is None:
            self._table = SpringTable.join([family.table() for family in self.springs])
        return self._table

    def spring_projection(self, x: np.ndarray, weight: np.ndarray, out: np.ndarray) -> float:
        """Liu et al.'s local step summed onto the points, into ``out``
        ``(N, 3)``: every spring of :meth:`spring_table` projected to its rest
        length along its current direction at ``x`` (m), times ``weight``
        (one per spring), added at its end a and taken from its end b.
        Returns ``sum(weight * rest * length)`` over the springs (the term of
        their weighted energy that is not quadratic in ``x``)."""
        table = self.spring_table()
        project = spring_projection if self._plan is not None else spring_projection_numpy
        return project(x, table.a, table.b, table.rest, weight, out)

    @property
    def compiled(self) -> bool:
        """Whether springs run in the compiled kernels (:mod:`pvcloth.physics.kernels`)."""
        return self._plan is not None

    def compute_forces(self, x: np.ndarray, v: np.ndarray, out: np.ndarray | None = None):
        """Total force ``(N, 3)`` in newtons on every point (pins included)
        at positions ``x`` (m) and velocities ``v`` (m/s)."""
        if self._plan is not None:
            f = np.empty_like(x) if out is None else out
            # Gravity and air damping are written over f, the springs and the
            # plate bending and the wind add on, all in compiled kernels.
            gravity = self.gravity.acceleration if self.gravity is not None else _NO_GRAVITY
            air = self.air.rate if self.air is not None else 0.0
            body_forces(v, f, self.mass, gravity, air, self.shape)
            spring_forces(self._plan, x, v, f)
            if self.bending is not None:
                if self._plan.empty:  # no spring pass to ride on: the whole product
                    subtract_product(self.bending.matrix, x, f, self.shape[0])
            self.add_wind(x, v, f)
            return f
        f = np.zeros_like(x) if out is None else out
        if out is not None:
            f.fill(0.0)
        for term in self.forces:
            term.accumulate(x, v, f)
        return f

    def kick_drift(self, x, v, f, inv_mass, dt: float, x_out, v_out) -> tuple[float, bool] | None:
        """The semi-implicit Euler update ``v' = v + dt f / m``, ``x' = x +
        dt v'`` into ``x_out, v_out`` (all ``(N, 3)``; ``inv_mass`` ``(N,)``
        in 1/kg). Compiled, it also returns the largest speed and whether
        every new value is finite (found on the way); NumPy returns None
        and leaves ``f`` scaled to accelerations."""
        if self._plan is not None:
            return kick_drift(x, v, f, inv_mass, dt, x_out, v_out, self.shape)
        f *= inv_mass[:, None]
        np.multiply(f, dt, out=v_out)
        v_out += v
        np.multiply(v_out, dt, out=x_out)
        x_out += x
        return None

    def apply(self, scene) -> None:
        """Take the constants a (live-edited) scene gives: spring stiffness
        and damping, gravity, air damping, wind. The terms are derived as
        :func:`build_model` derives them, so this model and one built from
        ``scene`` hold the same numbers. The grid, the masses and which
        spring families exist do not change (the caller checks)."""
        for springs in self.springs:
            spec = getattr(scene.springs, springs.family)
            springs.set_constants(spec.stiffness, spec.damping)
        self.gravity, self.air, self.wind = _body_terms(scene, self.mass, self.shape)
        if self._plan is not None:
            self._plan.refresh()
        self._table = None
        self.revision = next(REVISIONS)

    def set_time(self, t: float) -> None:
        """Tell time-dependent terms (gusty wind) the time of the coming step."""
        if self.wind is not None:
            self.wind.set_time(t)

    def collide(self, x0, x1, v1, movable, t0: float, t1: float, held=()) -> list[Contacts]:
        """Resolve collisions of the step ``t0 -> t1`` in place on ``x1``, ``v1``
        for the ``movable`` point indices; returns the points that touched
        and their obstacle's normals, one :class:`Contacts` per obstacle that
        may have been reached. ``held`` (one :class:`Contacts` per obstacle,
        or empty) are the points the integrator's solve pushed on, whose
        friction is applied here when it left it (a penalty's impulse)."""
        touched = []
        for obstacle, contacts in zip(self.obstacles, held, strict=False):
            if contacts.impulse is not None and contacts.index.size:
                obstacle._hold(x1, v1, contacts, t0, t1)
        # A cube around everything that moved: flat reductions are ten times
        # cheaper than per-axis ones, and this only has to be conservative.
        low = np.full(3, min(x0.min(), x1.min()))
        high = np.full(3, max(x0.max(), x1.max()))
        for obstacle in self.obstacles:
            if obstacle.may_touch(low, high, t0, t1):
                touched.append(obstacle.collide(x0, x1, v1, movable, t0, t1))
        return touched

    def potential_energy(self, x: np.ndarray) -> float:
        """Stored energy in joules (springs, plate bending and gravity)."""
        return sum(term.potential_energy(x) for term in self.forces)

    def kinetic_energy(self, v: np.ndarray) -> float:
        """Kinetic energy in joules."""
        return 0.5 * float(self.mass @ np.einsum("ij,ij->i", v, v))

    def jacobians(self, x: np.ndarray, v: np.ndarray):
        """Sum of the terms' ``(dF/dx, dF/dv)`` as sparse ``(3N, 3N)``
        matrices (the springs' clamped: see
        :meth:`~pvcloth.physics.springs.Springs.jacobians`)."""
        size = 3 * self.n_points
        dfdx = sp.csr_matrix((size, size))
        dfdv = sp.csr_matrix((size, size))
        for term in self.forces:
            jx, jv = term.jacobians(x, v)
            if jx is not None:
                dfdx = dfdx + jx
            if jv is not None:
                dfdv = dfdv + jv
        return dfdx, dfdv


_NO_GRAVITY = np.zeros(3)


def _body_terms(scene, mass: np.ndarray, shape: tuple[int, int]):
    """``(gravity, air damping, wind)`` terms for ``scene``, ``None`` where
    it has none."""
    gravity = Gravity(np.asarray(scene.gravity, dtype=float), mass) if any(scene.gravity) else None
    air = AirDamping(scene.air_damping, mass) if scene.air_damping > 0 else None
    wind = scene.wind
    blows = wind is not None and (wind.drag > 0 or wind.lift > 0)
    return gravity, air, Wind.from_spec(wind, shape) if blows else None


def pinned_mask(scene) -> np.ndarray:
    """Boolean mask ``(N,)`` of the points the scene pins."""
    nx, ny = scene.cloth.resolution
    mask = np.zeros((ny, nx), dtype=bool)
    pins = scene.pins
    top, right = ny - 1, nx - 1
    corner = {
        "top-left": (top, 0),
        "top-right": (top, right),
        "bottom-left": (0, 0),
        "bottom-right": (0, right),
    }
    for name in pins.corners:
        mask[corner[name]] = True
    edge = {
        "top": (top, slice(None)),
        "bottom": (0, slice(None)),
        "left": (slice(None), 0),
        "right": (slice(None), right),
    }
    for name in pins.edges:
        mask[edge[name]] = True
    for i, j in pins.points:
        mask[j, i] = True
    flat = mask.ravel()
    flat[list(pins.indices)] = True
    return flat


def build_model(scene, backend: str | None = None) -> Model:
    """Build the model a scene describes, with only the terms it needs.

    Parameters
    ----------
    scene : Scene
    backend : {"auto", "numba", "numpy"}, optional
        Where spring forces are computed: compiled kernels or pure NumPy
        (default: ``PVCLOTH_BACKEND`` or ``"auto"``, numba when installed).

    Returns
    -------
    Model

    Examples
    --------
    >>> import pvcloth
    >>> scene = pvcloth.Scene(springs=pvcloth.SpringsSpec(bending=None))
    >>> [term.name for term in pvcloth.build_model(scene).forces]
    ['structural springs', 'shear springs', 'gravity']
    """
    cloth = scene.cloth
    nx, ny = cloth.resolution
    x = initial_positions(cloth)
    mass = lumped_masses(cloth).ravel()
    spacing = (cloth.size[0] / (nx - 1), cloth.size[1] / (ny - 1))
    springs = []
    for family in ("structural", "shear", "bending"):
        spec = getattr(scene.springs, family)
        if spec is None:
            continue
        term = Springs.build(family, x, spec.stiffness, spec.damping, spacing)
        if term.count:
            springs.append(term)
    gravity, air, wind = _body_terms(scene, mass, (ny, nx))
    rigidity = cloth.bending_rigidity
    bending = PlateBending((ny, nx), spacing, rigidity) if rigidity > 0 else None
    return Model(
        (ny, nx),
        x.reshape(-1, 3).copy(),
        mass,
        pinned_mask(scene),
        springs,
        gravity,
        air,
        wind,
        [build_obstacle(spec) for spec in scene.obstacles],
        resolve_backend(backend),
        _self_collision(scene),
        bending,
    )


def _self_collision(scene) -> SelfCollision | None:
    contact = scene.self_collision
    if contact is None:
        return None
    nx, ny = scene.cloth.resolution
    return SelfCollision(
        (ny, nx), contact.thickness_for(scene.cloth), contact.friction, contact.in_solve
    )
