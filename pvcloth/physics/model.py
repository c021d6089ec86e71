"""The model: everything about a cloth that does not change while it moves.

:func:`build_model` turns a :class:`~pvcloth.scene.Scene` into a
:class:`Model` holding the grid, the masses, the default pins and exactly the
force terms the scene asks for, nothing more.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pvcloth.physics.forces import AirDamping, Gravity, Springs, Wind
from pvcloth.physics.grid import initial_positions, lumped_masses
from pvcloth.physics.kernels import resolve_backend
from pvcloth.physics.obstacles import build_obstacle


@dataclass
class Model:
    """Constants of a cloth simulation.

    Attributes
    ----------
    shape : (int, int)
        ``(ny, nx)``: rows along the height, points per row.
    rest_positions : ndarray, shape (N, 3)
        Initial positions, in VTK point order (index ``i + nx * j``).
    mass : ndarray, shape (N,)
        Point masses in kg.
    pinned : ndarray of bool, shape (N,)
        Points pinned by the scene.
    forces : list
        Force terms (see :mod:`pvcloth.physics.forces`), only those the scene needs.
    obstacles : list
        Rigid obstacles (see :mod:`pvcloth.physics.obstacles`); empty if the scene
        has none, and then no collision code runs.
    """

    shape: tuple[int, int]
    rest_positions: np.ndarray
    mass: np.ndarray
    pinned: np.ndarray
    forces: list = field(default_factory=list)
    obstacles: list = field(default_factory=list)
    backend: str = "numpy"

    def __post_init__(self):
        self._plan = None
        if self.backend == "numba":
            from pvcloth.physics.kernels import SpringPlan

            self._plan = SpringPlan(self.springs, self.shape)

    @property
    def n_points(self) -> int:
        return self.mass.size

    @property
    def springs(self) -> list[Springs]:
        """The spring families that were built."""
        return [term for term in self.forces if isinstance(term, Springs)]

    @property
    def compiled(self) -> bool:
        """Whether springs run in the compiled kernels (:mod:`pvcloth.physics.kernels`)."""
        return self._plan is not None

    def compute_forces(self, x: np.ndarray, v: np.ndarray, out: np.ndarray | None = None):
        """Total force ``(N, 3)`` on every point (pins included)."""
        if self._plan is not None:
            f = np.empty_like(x) if out is None else out
            self._compiled_forces(x, v, f)
            return f
        f = np.zeros_like(x) if out is None else out
        if out is not None:
            f.fill(0.0)
        for term in self.forces:
            term.accumulate(x, v, f)
        return f

    def _compiled_forces(self, x, v, f) -> None:
        """Gravity and air damping (written over ``f``) and springs in
        compiled kernels; any other term (wind) adds on in NumPy."""
        from pvcloth.physics.kernels import body_forces, spring_forces

        gravity, air = np.zeros(3), 0.0
        for term in self.forces:
            if isinstance(term, Gravity):
                gravity = gravity + term.acceleration
            elif isinstance(term, AirDamping):
                air += term.rate
        body_forces(v, f, self.mass, gravity, air, self.shape)
        spring_forces(self._plan, x, v, f)
        for term in self.forces:
            if not isinstance(term, (Springs, Gravity, AirDamping)):
                term.accumulate(x, v, f)

    def refresh(self) -> None:
        """Call after changing spring constants in place (the compiled
        kernels hold copies)."""
        if self._plan is not None:
            self._plan.refresh()

    def set_time(self, t: float) -> None:
        """Tell time-dependent terms (gusty wind) the time of the coming step."""
        for term in self.forces:
            if hasattr(term, "set_time"):
                term.set_time(t)

    def collide(self, x0, x1, v1, movable, t0: float, t1: float) -> int:
        """Resolve collisions of the step ``t0 -> t1`` in place on ``x1``, ``v1``
        for the ``movable`` point indices; returns how many points touched."""
        touched = 0
        # A cube around everything that moved: flat reductions are ten times
        # cheaper than per-axis ones, and this only has to be conservative.
        low = np.full(3, min(x0.min(), x1.min()))
        high = np.full(3, max(x0.max(), x1.max()))
        for obstacle in self.obstacles:
            if obstacle.may_touch(low, high, t0, t1):
                touched += obstacle.collide(x0, x1, v1, movable, t0, t1).index.size
        return touched

    def potential_energy(self, x: np.ndarray) -> float:
        return sum(term.potential_energy(x) for term in self.forces)

    def kinetic_energy(self, v: np.ndarray) -> float:
        return 0.5 * float(self.mass @ np.einsum("ij,ij->i", v, v))

    def jacobians(self, x: np.ndarray, v: np.ndarray):
        """Sum of the terms' ``(dF/dx, dF/dv)`` as sparse ``(3N, 3N)`` matrices."""
        import scipy.sparse as sp

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
    forces: list = []
    for family in ("structural", "shear", "bending"):
        spec = getattr(scene.springs, family)
        if spec is None:
            continue
        term = Springs.build(family, x, spec.stiffness, spec.damping, spacing)
        if term.count:
            forces.append(term)
    if any(scene.gravity):
        forces.append(Gravity(np.asarray(scene.gravity, dtype=float), mass))
    if scene.air_damping > 0:
        forces.append(AirDamping(scene.air_damping, mass))
    if scene.wind is not None and (scene.wind.drag > 0 or scene.wind.lift > 0):
        w = scene.wind
        forces.append(Wind.from_spec(w, (ny, nx)))
    obstacles = [build_obstacle(spec) for spec in scene.obstacles]
    return Model(
        (ny, nx),
        x.reshape(-1, 3).copy(),
        mass,
        pinned_mask(scene),
        forces,
        obstacles,
        resolve_backend(backend),
    )
