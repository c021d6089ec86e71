"""pvcloth: mass-spring cloth for the Python scientific stack.

Scene -> model and state -> integrator -> simulation -> view, movie,
interaction, export, analysis. See ``docs/architecture.md``.
"""

from importlib import metadata as _metadata

from .errors import (
    CheckpointError,
    DisplayError,
    DivergenceError,
    ExportInterrupted,
    MovieInterrupted,
    PvclothError,
    SceneError,
    SweepError,
)
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

try:  # one source for the version: the installed package's metadata (pyproject.toml)
    __version__ = _metadata.version("pvcloth")
except _metadata.PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

#: Output functions, imported on first use so that ``import pvcloth`` loads no
#: drawing or file-format library (PEP 562 module ``__getattr__``).
_LAZY = {
    "render": ("movie", "render"),
    "export": ("timeseries", "export"),
    "save_checkpoint": ("checkpoint", "save_checkpoint"),
    "load_checkpoint": ("checkpoint", "load_checkpoint"),
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        return getattr(importlib.import_module(f".{module}", __name__), attribute)
    raise AttributeError(f"module 'pvcloth' has no attribute {name!r}")


__all__ = [
    "INTEGRATORS",
    "CheckpointError",
    "ClothSpec",
    "Control",
    "DisplayError",
    "DivergenceError",
    "ExportInterrupted",
    "Integrator",
    "Model",
    "MovieInterrupted",
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
    "SweepError",
    "WindSpec",
    "__version__",
    "build_model",
    "export",
    "get_integrator",
    "load_checkpoint",
    "load_scene",
    "render",
    "save_checkpoint",
]
