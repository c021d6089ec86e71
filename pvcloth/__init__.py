"""pvcloth: mass-spring cloth for the Python scientific stack.

Scene -> model and state -> integrator -> simulation -> view, movie,
interaction, export, analysis. See ``docs/architecture.md``.
"""

from .errors import DivergenceError, PvclothError, SceneError
from .integrators import INTEGRATORS, Integrator, get_integrator
from .model import Model, build_model
from .scene import (
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
from .simulation import Simulation
from .state import Control, State

__version__ = "0.1.0"


__all__ = [
    "INTEGRATORS",
    "ClothSpec",
    "Control",
    "DivergenceError",
    "Integrator",
    "Model",
    "ObstacleSpec",
    "PinSpec",
    "PvclothError",
    "Scene",
    "SceneError",
    "Simulation",
    "SolverSpec",
    "SpringSpec",
    "SpringsSpec",
    "State",
    "WindSpec",
    "build_model",
    "get_integrator",
    "load_scene",
]
