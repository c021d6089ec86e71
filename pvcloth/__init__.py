"""pvcloth: mass-spring cloth for the Python scientific stack.

Scene -> model and state -> integrator -> simulation -> view, movie,
interaction, export, analysis. See ``docs/architecture.md``.
"""

from importlib import metadata as _metadata

from pvcloth.errors import (
    CheckpointError,
    DisplayError,
    DivergenceError,
    ExportInterrupted,
    InputError,
    MovieInterrupted,
    PvclothError,
    SceneError,
    SweepError,
)

try:  # one source for the version: the installed package's metadata (pyproject.toml)
    __version__ = _metadata.version("pvcloth")
except _metadata.PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

#: Everything but the errors is imported on first use (PEP 562 module
#: ``__getattr__``): ``import pvcloth`` is quick and loads no NumPy, numba or
#: drawing library until asked, so ``pvcloth --help`` answers at once and a
#: Ctrl-C during start-up reaches the command's own handler.
_LAZY = {
    **{
        name: ("physics.integrators", name)
        for name in ("INTEGRATORS", "Integrator", "get_integrator")
    },
    **{name: ("physics.model", name) for name in ("Model", "build_model")},
    **{
        name: ("scene.parts", name)
        for name in ("CameraSpec", "ClothSpec", "ObstacleSpec", "PinSpec", "SolverSpec")
        + ("SelfCollisionSpec", "SpringSpec", "SpringsSpec", "WindSpec")
    },
    "Scene": ("scene.spec", "Scene"),
    "load_scene": ("scene.files", "load_scene"),
    "Simulation": ("simulation", "Simulation"),
    **{name: ("physics.state", name) for name in ("Control", "State")},
    "render": ("visual.movie", "render"),
    "compare": ("visual.compare", "compare"),
    "export": ("io.timeseries", "export"),
    "save_checkpoint": ("io.checkpoint", "save_checkpoint"),
    "load_checkpoint": ("io.checkpoint", "load_checkpoint"),
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        value = getattr(importlib.import_module(f".{module}", __name__), attribute)
        globals()[name] = value  # looked up once
        return value
    raise AttributeError(f"module 'pvcloth' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "INTEGRATORS",
    "CameraSpec",
    "CheckpointError",
    "ClothSpec",
    "Control",
    "DisplayError",
    "DivergenceError",
    "ExportInterrupted",
    "InputError",
    "Integrator",
    "Model",
    "MovieInterrupted",
    "ObstacleSpec",
    "PinSpec",
    "PvclothError",
    "Scene",
    "SceneError",
    "SelfCollisionSpec",
    "Simulation",
    "SolverSpec",
    "SpringSpec",
    "SpringsSpec",
    "State",
    "SweepError",
    "WindSpec",
    "__version__",
    "build_model",
    "compare",
    "export",
    "get_integrator",
    "load_checkpoint",
    "load_scene",
    "render",
    "save_checkpoint",
]
