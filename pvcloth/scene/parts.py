"""The parts of a scene: cloth, springs, pins, solver, wind, camera,
obstacles and self-collision, each a frozen, validated dataclass, with the
limits they are checked against. :class:`~pvcloth.scene.spec.Scene` puts
them together.

Material parameterisation (why these units): stiffness is given per cloth,
not per spring, so refining the grid approximates the same cloth.

- ``stretch`` (N/m) is the membrane stiffness of the sheet: the tension per
  unit width that doubles its length. A spring along x of rest length ``hx``
  that stands for a strip ``hy`` wide gets ``k = stretch * hy / hx``.
- ``shear`` (N/m) plays the same role for the diagonal springs, each of which
  gets ``k = shear`` (independent of the cell size, as for a square cell).
- ``bending`` (N/m) is scaled like ``stretch`` over springs two cells long.
  Bending springs resist folding only through second-order length change, so
  they are a regulariser, not a converging plate model: for a fabric's
  bending, give the cloth's ``bending_rigidity`` (N m) instead
  (:mod:`pvcloth.physics.bending`).
- Springs that lie on the cloth's border stand for half a strip and get half
  the stiffness and damping (the trapezoid rule), as do the border masses.
- ``damping`` (N s/m) of each family is scaled like its stiffness.
- ``mass`` is the total mass, lumped to points by area (trapezoid rule).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from pvcloth.errors import SceneError
from pvcloth.scene.validation import choice, integer, real, sequence, vector

#: Largest number of points along one side of the cloth.
MAX_RESOLUTION = 4096
#: Sizes in metres pvcloth accepts (a tenth of a millimetre to ten kilometres),
#: and the largest distance of any position from the origin. Beyond them a
#: step's arithmetic under- or overflows (a 1e-320 m cloth divides by zero,
#: a 1e308 m sphere overflows) instead of describing a cloth.
MIN_LENGTH, MAX_LENGTH = 1e-4, 1e4
#: Largest speed (m/s) of the wind, and acceleration (m/s^2) of gravity, per
#: component: the drag model is for air well below the speed of sound.
MAX_WIND, MAX_GRAVITY = 340.0, 1e4
#: Largest stiffness (N/m), damping (N s/m), mass (kg) and air damping (1/s).
MAX_STIFFNESS, MAX_DAMPING, MAX_MASS, MAX_AIR_DAMPING = 1e12, 1e9, 1e6, 1e6
#: Largest bending rigidity (N m): a steel sheet a millimetre thick has 19.
MAX_BENDING_RIGIDITY = 1e3
#: Smallest cloth mass (kg): below it the stable step of any stiffness is
#: too small to simulate a frame.
MIN_MASS = 1e-9
#: Most a surface's thickness (the gap the cloth keeps) may be, in metres.
MAX_THICKNESS = 1.0

_LENGTH = {"minimum": MIN_LENGTH, "maximum": MAX_LENGTH}
_POSITION = {"minimum": -MAX_LENGTH, "maximum": MAX_LENGTH}
ORIENTATIONS = ("vertical", "horizontal")
CORNERS = ("top-left", "top-right", "bottom-left", "bottom-right")
EDGES = ("top", "bottom", "left", "right")


def _set(obj, name: str, value) -> None:
    object.__setattr__(obj, name, value)


@dataclass(frozen=True)
class ClothSpec:
    """The sheet of cloth: size, resolution, mass and where it starts.

    Parameters
    ----------
    size : (float, float)
        Width and height in metres (along the point index i and j), each
        1e-4 to 1e4 m (:data:`MIN_LENGTH`, :data:`MAX_LENGTH`).
    resolution : (int, int)
        Points along the width (``nx``) and the height (``ny``), each 2 to 4096.
    mass : float
        Total mass in kilograms, 1e-9 to 1e6.
    orientation : {"vertical", "horizontal"}
        ``"vertical"`` hangs the cloth in the x-z plane (j runs up along z);
        ``"horizontal"`` lays it flat in the x-y plane (j runs along y).
    center : (float, float, float)
        Position of the cloth's centre in metres (each within +-1e4).
    bending_rigidity : float
        The sheet's resistance to bending, in N m (0 to 1e3; cotton is about
        1.7e-4): the moment per metre of width that bends it to a curvature
        of 1/m. 0 (the default) builds no plate bending
        (:mod:`pvcloth.physics.bending`); the fabric presets set it.

    Examples
    --------
    >>> from pvcloth import ClothSpec
    >>> ClothSpec(size=(2.0, 1.0), resolution=(41, 21)).resolution
    (41, 21)
    """

    size: tuple[float, float] = (1.0, 1.0)
    resolution: tuple[int, int] = (20, 20)
    mass: float = 0.2
    orientation: str = "vertical"
    center: tuple[float, float, float] = (0.0, 0.0, 1.0)
    bending_rigidity: float = 0.0

    def __post_init__(self):
        _set(self, "size", vector("size", self.size, 2, **_LENGTH))
        res = sequence("resolution", self.resolution, 2)
        _set(
            self,
            "resolution",
            tuple(
                integer(f"resolution[{n}]", r, minimum=2, maximum=MAX_RESOLUTION)
                for n, r in enumerate(res)
            ),
        )
        _set(self, "mass", real("mass", self.mass, minimum=MIN_MASS, maximum=MAX_MASS))
        _set(self, "orientation", choice("orientation", self.orientation, ORIENTATIONS))
        _set(self, "center", vector("center", self.center, 3, **_POSITION))
        _set(
            self,
            "bending_rigidity",
            real(
                "bending_rigidity", self.bending_rigidity, minimum=0.0, maximum=MAX_BENDING_RIGIDITY
            ),
        )


@dataclass(frozen=True)
class SpringSpec:
    """Stiffness (N/m) and damping (N s/m) of one spring family.

    See the module docstring for how these per-cloth values become per-spring
    constants.
    """

    stiffness: float
    damping: float = 0.0

    def __post_init__(self):
        _set(
            self, "stiffness", real("stiffness", self.stiffness, minimum=0.0, maximum=MAX_STIFFNESS)
        )
        _set(self, "damping", real("damping", self.damping, minimum=0.0, maximum=MAX_DAMPING))


@dataclass(frozen=True)
class SpringsSpec:
    """The three spring families; leave one out (``None``) to build none of it.

    Examples
    --------
    >>> from pvcloth import SpringSpec, SpringsSpec
    >>> SpringsSpec(bending=None).bending is None
    True
    """

    structural: SpringSpec | None = SpringSpec(400.0, 0.5)
    shear: SpringSpec | None = SpringSpec(40.0, 0.05)
    bending: SpringSpec | None = SpringSpec(4.0, 0.005)

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None and not isinstance(value, SpringSpec):
                raise SceneError(
                    f.name, f"expected a SpringSpec or None, got {type(value).__name__}"
                )


@dataclass(frozen=True)
class PinSpec:
    """Which points are held in place.

    The default pins the two top corners. Any combination of corners, whole
    edges, ``(i, j)`` grid points and flat point indices (``i + nx * j``, the
    VTK point order) may be given; their union is pinned.

    Examples
    --------
    >>> from pvcloth import PinSpec
    >>> PinSpec(corners=(), edges=("top",)).edges
    ('top',)
    """

    corners: tuple[str, ...] = ("top-left", "top-right")
    edges: tuple[str, ...] = ()
    points: tuple[tuple[int, int], ...] = ()
    indices: tuple[int, ...] = ()

    def __post_init__(self):
        corners = sequence("corners", self.corners)
        _set(
            self,
            "corners",
            tuple(choice(f"corners[{n}]", c, CORNERS) for n, c in enumerate(corners)),
        )
        edges = sequence("edges", self.edges)
        _set(self, "edges", tuple(choice(f"edges[{n}]", e, EDGES) for n, e in enumerate(edges)))
        points = []
        for n, p in enumerate(sequence("points", self.points)):
            pair = sequence(f"points[{n}]", p, 2)
            points.append(
                tuple(
                    integer(f"points[{n}][{m}]", q, minimum=0, maximum=MAX_RESOLUTION - 1)
                    for m, q in enumerate(pair)
                )
            )
        _set(self, "points", tuple(points))
        _set(
            self,
            "indices",
            tuple(
                integer(f"indices[{n}]", k, minimum=0, maximum=MAX_RESOLUTION**2 - 1)
                for n, k in enumerate(sequence("indices", self.indices))
            ),
        )


STABILITY_POLICIES = ("refuse", "substep", "ignore")
#: The integrator names a scene may give. The scene layer knows the names
#: only, so that describing a scene needs none of the solvers; every
#: integrator the registry holds must be one of them (``register`` checks).
#: ``solver.integrator`` that lets a probe choose (with ``solver.tolerance``).
AUTO = "auto"
#: Bounds of an adaptive step (s) when ``solver.min_dt`` / ``max_dt`` are left out.
DEFAULT_MIN_DT, DEFAULT_MAX_DT = 1e-9, 0.05
INTEGRATOR_NAMES = (
    "backward_euler",
    "bdf2",
    "explicit_euler",
    "fast_bdf2",
    "fast_mass_spring",
    "implicit_euler",
    "rk23",
    "rk4",
    "symplectic_euler",
    "verlet",
)
#: How ``fast_mass_spring`` and ``fast_bdf2`` speed up their local/global
#: iterations (``solver.accelerator``): Chebyshev's semi-iterative method
#: (the default) or L-BFGS on the global matrix (see
#: :class:`~pvcloth.physics.integrators.fast_mass_spring.FastMassSpring`).
ACCELERATORS = ("chebyshev", "lbfgs")
#: The integrators that measure their own error, so ``solver.tolerance`` can
#: choose their steps (``embedded`` in :mod:`pvcloth.physics.integrators`;
#: a test keeps the two equal, so the command line can say so without
#: importing the physics).
MEASURING_INTEGRATORS = (
    "backward_euler",
    "bdf2",
    "fast_bdf2",
    "fast_mass_spring",
    "implicit_euler",
    "rk23",
)


@dataclass(frozen=True)
class SolverSpec:
    """Time integration: which integrator, its fixed step, and what to do
    when that step is above the integrator's estimated stable step.

    Parameters
    ----------
    integrator : str, optional
        A name from :data:`pvcloth.INTEGRATORS`, or ``"auto"`` (with a
        tolerance). Left out: ``"auto"`` when a tolerance is given, else
        ``"symplectic_euler"``.
    dt : float, optional
        Step in seconds (0 < dt <= 10). Left out (``None``), the simulation
        takes the largest step that is at most half the integrator's estimated
        stable step for this cloth and divides a 1/60 s frame evenly (the
        frame itself for an integrator stable at any step).
    stability : {"refuse", "substep", "ignore"}
        What to do with a given step above 0.8 of the estimated stable step:
        ``"refuse"`` raises a SceneError naming a stable step; ``"substep"``
        splits each step into equal substeps at most half the stable step;
        ``"ignore"`` runs as asked (the divergence guard still stops a blow-up).
    iterations : int, optional
        ``fast_mass_spring``'s local/global iterations per step (1 to 10000;
        default 10): more are closer to backward Euler, and cost more. The
        other integrators leave it unused (``backward_euler`` iterates to its
        residual tolerance).
    accelerator : {"chebyshev", "lbfgs"}, optional
        How ``fast_mass_spring`` and ``fast_bdf2`` speed up those
        iterations (default ``"chebyshev"``): ``"lbfgs"`` costs more per
        iteration and, from about ten a step, ends closer to the converged
        step for the same count; every iteration lowers the step's energy
        (the other integrators leave it unused).
    tolerance : float, optional
        Position error in metres (1e-12 to 1) a second of simulation may
        add: the step is then chosen for every step from the integrator's
        own error estimate, rejected and retried when over its share
        (:mod:`pvcloth.physics.adaptive`); ``dt``, if given, is the first
        step tried, and ``stability`` is not used. Needs an integrator that
        measures its error (``rk23``, ``implicit_euler``,
        ``fast_mass_spring``, ``backward_euler``) or ``"auto"``, which picks
        the one a short probe finds cheapest (:mod:`pvcloth.physics.auto`).
    min_dt, max_dt : float, optional
        Bounds of an adaptive run's step in seconds (default 1e-9 and 0.05;
        ``min_dt < max_dt <= 10``); only with ``tolerance``.

    Examples
    --------
    >>> from pvcloth import SolverSpec
    >>> SolverSpec("rk23", tolerance=1e-5).tolerance
    1e-05
    >>> SolverSpec("verlet").dt is None  # chosen from the stable step
    True
    >>> SolverSpec("rk4", dt=1e-4).dt
    0.0001
    >>> SolverSpec("fast_mass_spring", iterations=6).iterations
    6
    >>> SolverSpec("fast_bdf2", accelerator="lbfgs").accelerator
    'lbfgs'
    >>> SolverSpec("auto", tolerance=1e-3, max_dt=0.01).max_dt
    0.01
    >>> SolverSpec(tolerance=1e-3).method  # a tolerance alone lets a probe choose
    'auto'
    >>> SolverSpec().method
    'symplectic_euler'
    """

    integrator: str | None = None
    dt: float | None = None
    stability: str = "refuse"
    iterations: int | None = None
    accelerator: str | None = None
    tolerance: float | None = None
    min_dt: float | None = None
    max_dt: float | None = None

    def __post_init__(self):
        _set(self, "stability", choice("stability", self.stability, STABILITY_POLICIES))
        if self.tolerance is not None:
            _set(self, "tolerance", real("tolerance", self.tolerance, minimum=1e-12, maximum=1.0))
        for key in ("min_dt", "max_dt"):
            value = getattr(self, key)
            if value is None:
                continue
            if self.tolerance is None:
                raise SceneError(key, "bounds an adaptive step: give solver.tolerance with it")
            _set(self, key, real(key, value, minimum=0.0, exclusive=True, maximum=10.0))
        low = DEFAULT_MIN_DT if self.min_dt is None else self.min_dt
        high = DEFAULT_MAX_DT if self.max_dt is None else self.max_dt
        if not low < high:
            raise SceneError(
                "min_dt" if self.min_dt is not None else "max_dt",
                f"the smallest step ({low:g} s) must be below the largest ({high:g} s)",
            )
        if self.integrator == AUTO and self.tolerance is None:
            raise SceneError(
                "integrator",
                "'auto' chooses the cheapest method for an error tolerance: give "
                "solver.tolerance (metres) with it, or name an integrator",
            )
        if self.iterations is not None:
            _set(
                self, "iterations", integer("iterations", self.iterations, minimum=1, maximum=10000)
            )
        if self.accelerator is not None:
            _set(self, "accelerator", choice("accelerator", self.accelerator, ACCELERATORS))
        if self.integrator is not None:
            _set(
                self,
                "integrator",
                choice("integrator", self.integrator, (*INTEGRATOR_NAMES, AUTO)),
            )
        if self.dt is not None:
            _set(self, "dt", real("dt", self.dt, minimum=0.0, exclusive=True, maximum=10.0))

    @property
    def method(self) -> str:
        """The integrator that runs: the one named, else ``"auto"`` with a
        tolerance and ``"symplectic_euler"`` without (so a tolerance given
        later, by ``--tolerance`` or an override, also lets a probe choose)."""
        if self.integrator is not None:
            return self.integrator
        return AUTO if self.tolerance is not None else "symplectic_euler"


@dataclass(frozen=True)
class WindSpec:
    """Wind: air velocity (m/s), drag and lift coefficients, air density, and
    optional gusts.

    Parameters
    ----------
    velocity : (float, float, float)
        Mean air velocity in m/s.
    drag : float
        Drag coefficient ``C_d`` (>= 0): force along the triangle's normal.
    lift : float
        Lift coefficient ``C_l`` (>= 0): force across the relative wind, in
        the plane of wind and normal; zero (the default) builds no lift.
    density : float
        Air density in kg/m^3.
    gust : float
        Relative gust strength (0 to 1): the wind speed varies between
        ``1 - gust`` and ``1 + gust`` times the mean. Zero means steady.
    gust_period : float
        Seconds between independent gust values (smoothly interpolated).
    seed : int
        Seed of the gust sequence: the same seed gives the same gusts.

    Examples
    --------
    >>> from pvcloth import WindSpec
    >>> WindSpec(velocity=(8.0, 2.0, 0.0)).drag
    1.0
    """

    velocity: tuple[float, float, float] = (5.0, 0.0, 0.0)
    drag: float = 1.0
    lift: float = 0.0
    density: float = 1.2
    gust: float = 0.0
    gust_period: float = 0.5
    seed: int = 0

    def __post_init__(self):
        _set(
            self,
            "velocity",
            vector("velocity", self.velocity, 3, minimum=-MAX_WIND, maximum=MAX_WIND),
        )
        _set(self, "drag", real("drag", self.drag, minimum=0.0))
        _set(self, "lift", real("lift", self.lift, minimum=0.0))
        _set(self, "density", real("density", self.density, minimum=0.0, exclusive=True))
        _set(self, "gust", real("gust", self.gust, minimum=0.0, maximum=1.0))
        _set(
            self, "gust_period", real("gust_period", self.gust_period, minimum=0.0, exclusive=True)
        )
        _set(self, "seed", integer("seed", self.seed, minimum=0, maximum=2**63 - 1))


#: Directions a camera preset looks from (see :mod:`pvcloth.visual.camera`).
CAMERA_VIEWS = ("iso", "front", "side", "top")


@dataclass(frozen=True)
class CameraSpec:
    """How movies look at the scene; the window starts from it too.

    Parameters
    ----------
    view : {"iso", "front", "side", "top"}
        The direction looked from: ``iso`` from the front, right and above;
        ``front`` along +y; ``side`` along -x; ``top`` down -z.
    follow : bool
        Move with the cloth so it fills the frame through the motion (the
        default); ``False`` fixes the camera on the region the cloth can
        reach.
    position, focal_point : (float, float, float), optional
        An explicit, fixed camera in metres: both or neither. When given,
        ``view`` and ``follow`` are not used.
    up : (float, float, float)
        View-up vector of an explicit camera.

    Examples
    --------
    >>> from pvcloth import Scene
    >>> Scene.from_dict({"camera": {"view": "side"}}).camera.view
    'side'
    >>> Scene.from_dict({"camera": {"position": [0, -3, 1], "focal_point": [0, 0, 0]}}).camera.up
    (0.0, 0.0, 1.0)
    """

    view: str = "iso"
    follow: bool = True
    position: tuple[float, float, float] | None = None
    focal_point: tuple[float, float, float] | None = None
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self):
        _set(self, "view", choice("view", self.view, CAMERA_VIEWS))
        if not isinstance(self.follow, bool):
            raise SceneError("follow", f"expected true or false, got {self.follow!r}")
        if (self.position is None) != (self.focal_point is None):
            raise SceneError(
                "position" if self.position is None else "focal_point",
                "an explicit camera needs both position and focal_point",
            )
        _set(self, "up", vector("up", self.up, 3, **_POSITION))
        if math.hypot(*self.up) == 0.0:
            raise SceneError("up", "must not be the zero vector")
        if self.position is not None:
            _set(self, "position", vector("position", self.position, 3, **_POSITION))
            _set(self, "focal_point", vector("focal_point", self.focal_point, 3, **_POSITION))
            sight = [a - b for a, b in zip(self.position, self.focal_point, strict=True)]
            if math.hypot(*sight) == 0.0:
                raise SceneError("position", "must differ from focal_point")
            cross = (
                sight[1] * self.up[2] - sight[2] * self.up[1],
                sight[2] * self.up[0] - sight[0] * self.up[2],
                sight[0] * self.up[1] - sight[1] * self.up[0],
            )
            if math.hypot(*cross) <= 1e-9 * math.hypot(*sight) * math.hypot(*self.up):
                raise SceneError("up", f"{self.up} is along the line of sight; give another")

    @property
    def explicit(self) -> bool:
        """Whether a fixed position and focal point are given."""
        return self.position is not None


OBSTACLE_TYPES = ("sphere", "box", "ground")
#: Keys each obstacle type uses besides the common ones.
_OBSTACLE_KEYS = {"sphere": ("radius",), "box": ("size", "rotation"), "ground": ("normal",)}


@dataclass(frozen=True)
class ObstacleSpec:
    """A rigid obstacle the cloth collides with: sphere, box or ground plane.

    Parameters
    ----------
    type : {"sphere", "box", "ground"}
    center : (float, float, float)
        Sphere or box centre; for the ground, a point on the plane.
    radius : float
        Sphere radius in metres (> 0). Sphere only.
    size : (float, float, float)
        Box edge lengths along its own axes (each > 0). Box only.
    rotation : (float, float, float)
        Box orientation: rotations in degrees about the fixed x, y and z
        axes, applied in that order. Box only.
    normal : (float, float, float)
        Ground plane normal (any length but zero), pointing to the free side.
        Ground only; default straight up.
    thickness : float
        Distance (m) the cloth keeps from the surface (>= 0).
    friction : float
        Kinetic Coulomb friction coefficient (>= 0).
    static_friction : float, optional
        Static coefficient (>= ``friction``); defaults to ``friction``.
    path : list of (t, x, y, z)
        Optional key frames of the centre, in increasing time; the obstacle
        moves in straight lines between them and rests before the first and
        after the last.

    Examples
    --------
    >>> from pvcloth import ObstacleSpec
    >>> ObstacleSpec("sphere", center=(0, 0, 0.5), radius=0.3).friction
    0.3
    """

    type: str
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float | None = None
    size: tuple[float, float, float] | None = None
    rotation: tuple[float, float, float] | None = None
    normal: tuple[float, float, float] | None = None
    thickness: float = 0.005
    friction: float = 0.3
    static_friction: float | None = None
    path: tuple[tuple[float, float, float, float], ...] = ()

    def __post_init__(self):
        kind = choice("type", self.type, OBSTACLE_TYPES)
        for other, keys in _OBSTACLE_KEYS.items():
            for key in keys:
                if other != kind and getattr(self, key) is not None:
                    raise SceneError(key, f"is not used by a {kind}; it belongs to a {other}")
        _set(self, "center", vector("center", self.center, 3, **_POSITION))
        if kind == "sphere":
            if self.radius is None:
                raise SceneError("radius", "a sphere needs a radius (metres, > 0)")
            _set(self, "radius", real("radius", self.radius, **_LENGTH))
        elif kind == "box":
            if self.size is None:
                raise SceneError("size", "a box needs size = [x, y, z] (metres, each > 0)")
            _set(self, "size", vector("size", self.size, 3, **_LENGTH))
            rotation = (0.0, 0.0, 0.0) if self.rotation is None else self.rotation
            _set(self, "rotation", vector("rotation", rotation, 3))
        else:
            normal = vector("normal", (0.0, 0.0, 1.0) if self.normal is None else self.normal, 3)
            length = math.hypot(*normal)
            if not length >= 1e-9:  # a subnormal normal would normalise to inf and NaN
                raise SceneError(
                    "normal",
                    f"must not be (nearly) zero, got {normal}; give the direction of the free side",
                )
            _set(self, "normal", normal)
        _set(
            self, "thickness", real("thickness", self.thickness, minimum=0.0, maximum=MAX_THICKNESS)
        )
        _set(self, "friction", real("friction", self.friction, minimum=0.0))
        static = self.friction if self.static_friction is None else self.static_friction
        static = real("static_friction", static, minimum=0.0)
        if static < self.friction:
            raise SceneError(
                "static_friction",
                f"{static:g} is below the kinetic friction {self.friction:g}; "
                "static friction must be at least the kinetic one",
            )
        _set(self, "static_friction", static)
        frames = []
        for n, frame in enumerate(sequence("path", self.path)):
            frames.append(vector(f"path[{n}]", frame, 4, **_POSITION))
            if n and frames[-1][0] <= frames[-2][0]:
                raise SceneError(
                    f"path[{n}]",
                    f"time {frames[-1][0]:g} s does not come after {frames[-2][0]:g} s; "
                    "key frames must be in increasing time",
                )
        _set(self, "path", tuple(frames))


#: Friction between layers: cloth on cloth measures 0.2 to 0.8; above this
#: the value is a typing error, not a fabric.
MAX_CLOTH_FRICTION = 5.0
#: A thickness may be at most this share of the flat grid's gap
#: (:func:`flat_gap`), or the flat cloth would push itself apart.
MAX_THICKNESS_SHARE = 0.5
#: The thickness a ``[self_collision]`` table without one gets, as a share
#: of the flat gap.
DEFAULT_THICKNESS_SHARE = 0.3


def flat_gap(size: tuple[float, float], resolution: tuple[int, int]) -> float:
    """The closest two parts of a flat grid cloth that share no point come
    (a cell's diagonal from the next cell's corner), in metres.

    Examples
    --------
    >>> round(flat_gap((1.0, 1.0), (11, 11)), 4)
    0.0707
    """
    hx = size[0] / (resolution[0] - 1)
    hy = size[1] / (resolution[1] - 1)
    return hx * hy / math.hypot(hx, hy)


@dataclass(frozen=True)
class SelfCollisionSpec:
    """Contact of the cloth with itself (off unless a scene has one).

    Parameters
    ----------
    thickness : float, optional
        Distance (m) the cloth's layers keep apart, > 0 and at most half the
        gap between neighbouring parts of the flat grid (:func:`flat_gap`:
        11.2 mm for a 1 m cloth of 64 x 64 points, so 5.6 mm). ``None`` (the
        default) takes 0.3 of that gap.
    friction : float
        Coulomb friction coefficient between layers, 0 to 5 (cloth on cloth
        is about 0.2 to 0.8).
    in_solve : bool
        Hold the layers apart inside the solve of ``backward_euler`` and
        ``bdf2`` too, with a penalty (no step is then split for
        self-collision); ``False`` (the default) meets them after the step
        only, as every other integrator does. Newton's iterations stall in
        some violent scenes with it.

    Examples
    --------
    >>> from pvcloth import Scene, SelfCollisionSpec
    >>> scene = Scene(self_collision=SelfCollisionSpec(thickness=0.004))
    >>> scene.self_collision.friction
    0.3
    """

    thickness: float | None = None
    friction: float = 0.3
    in_solve: bool = False

    def __post_init__(self):
        if self.thickness is not None:
            _set(
                self,
                "thickness",
                real(
                    "thickness",
                    self.thickness,
                    minimum=0.0,
                    exclusive=True,
                    maximum=MAX_THICKNESS,
                ),
            )
        _set(
            self,
            "friction",
            real("friction", self.friction, minimum=0.0, maximum=MAX_CLOTH_FRICTION),
        )
        if not isinstance(self.in_solve, bool):
            raise SceneError("in_solve", f"expected true or false, got {self.in_solve!r}")

    def thickness_for(self, cloth: ClothSpec) -> float:
        """The thickness in metres on ``cloth``'s grid (the default's share
        of its gap when none was given)."""
        if self.thickness is not None:
            return self.thickness
        return DEFAULT_THICKNESS_SHARE * flat_gap(cloth.size, cloth.resolution)
