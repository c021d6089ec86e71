"""What to simulate: validated, frozen scene descriptions (``spec``), the
value checks they use (``validation``) and TOML loading.

The scene layer depends on nothing else in pvcloth but :mod:`pvcloth.errors`.
"""

from pvcloth.scene.spec import (
    CORNERS,
    EDGES,
    INTEGRATOR_NAMES,
    MAX_LENGTH,
    OBSTACLE_TYPES,
    ORIENTATIONS,
    STABILITY_POLICIES,
    ClothSpec,
    ObstacleSpec,
    PinSpec,
    Scene,
    SolverSpec,
    SpringSpec,
    SpringsSpec,
    WindSpec,
    load_scene,
)

__all__ = [
    "CORNERS",
    "EDGES",
    "INTEGRATOR_NAMES",
    "MAX_LENGTH",
    "OBSTACLE_TYPES",
    "ORIENTATIONS",
    "STABILITY_POLICIES",
    "ClothSpec",
    "ObstacleSpec",
    "PinSpec",
    "Scene",
    "SolverSpec",
    "SpringSpec",
    "SpringsSpec",
    "WindSpec",
    "load_scene",
]
