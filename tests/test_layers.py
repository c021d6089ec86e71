"""The package's layers, as its folders show them: the scene describes, the
physics computes, and neither reaches for what draws, plots, reports
progress or schedules."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pvcloth
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.scene.spec import INTEGRATOR_NAMES, MEASURING_INTEGRATORS

PACKAGE = Path(pvcloth.__file__).parent
#: What the physics and scene layers must never import.
OUTSIDE = ("pyvista", "vtk", "vtkmodules", "matplotlib", "dask", "distributed", "tqdm", "meshio")


def _modules(folder: str) -> list[str]:
    return sorted(
        ".".join(("pvcloth", *path.relative_to(PACKAGE).with_suffix("").parts)).removesuffix(
            ".__init__"
        )
        for path in (PACKAGE / folder).rglob("*.py")
    )


def test_physics_and_scene_run_without_drawing_plotting_progress_or_scheduling_libraries():
    # A fresh interpreter imports every physics and scene module and runs
    # steps with every integrator, an obstacle, wind and pins: nothing in
    # OUTSIDE may have been loaded.
    modules = _modules("physics") + _modules("scene")
    code = f"""
import importlib, json, sys
for name in {modules!r}:
    importlib.import_module(name)
from pvcloth.physics.simulation import Simulation
from pvcloth.scene.spec import ClothSpec, ObstacleSpec, Scene, WindSpec
from pvcloth.physics.integrators import INTEGRATORS
scene = Scene(
    cloth=ClothSpec(resolution=(6, 6)),
    wind=WindSpec(velocity=(2.0, 0.0, 0.0)),
    obstacles=(ObstacleSpec("sphere", center=(0.0, 0.0, -0.5), radius=0.2),),
)
for name in sorted(INTEGRATORS):
    sim = Simulation(scene, integrator=name)
    sim.pin(3)
    sim.advance(0.02)
print(json.dumps(sorted(m.split(".")[0] for m in sys.modules)))
"""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    loaded = set(json.loads(done.stdout.splitlines()[-1]))
    assert not loaded & set(OUTSIDE), f"physics loaded {sorted(loaded & set(OUTSIDE))}"


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


def test_imports_point_down_the_layers_only():
    # scene -> physics -> visual / io / studies: a lower layer never imports
    # a higher one (checked on the source, including imports inside functions).
    below = {
        "scene": ("pvcloth.errors", "pvcloth.scene"),
        "physics": ("pvcloth.errors", "pvcloth.scene", "pvcloth.signals", "pvcloth.physics"),
    }
    # The one way up: Simulation.mesh and Simulation.plot hand the user the
    # view layer's mesh, imported inside those two methods, when asked for.
    asked_for = {("simulation.py", "pvcloth.visual.view")}
    for folder, allowed in below.items():
        for path in (PACKAGE / folder).rglob("*.py"):
            for module in _imports(path):
                if (path.name, module) in asked_for:
                    continue
                if module.startswith("pvcloth"):
                    assert module.startswith(allowed), f"{path.name} imports {module}"
                else:
                    assert module.split(".")[0] not in OUTSIDE, f"{path.name} imports {module}"


def test_every_registered_integrator_is_a_name_scenes_accept():
    assert sorted(INTEGRATORS) == sorted(INTEGRATOR_NAMES)
    measuring = sorted(name for name, method in INTEGRATORS.items() if method.embedded)
    assert measuring == sorted(MEASURING_INTEGRATORS)


def test_every_error_class_lives_in_errors_and_is_exported():
    # An exception class defined anywhere but errors.py is a defect: callers
    # could not catch pvcloth's errors from one place.
    for path in PACKAGE.rglob("*.py"):
        if path.name == "errors.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                bases = {getattr(b, "id", getattr(b, "attr", "")) for b in node.bases}
                assert not bases & {"Exception", "PvclothError", "ValueError", "RuntimeError"}, (
                    f"{path.relative_to(PACKAGE)} defines the exception {node.name}"
                )
    import pvcloth.errors as errors

    for name in dir(errors):
        value = getattr(errors, name)
        if (
            isinstance(value, type)
            and issubclass(value, Exception)
            and value.__module__ == errors.__name__
        ):
            assert getattr(pvcloth, name) is value, f"{name} is not exported from pvcloth"
