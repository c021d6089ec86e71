"""The package's layers, as its folders show them: the scene describes, the
physics computes, and neither reaches for what draws, plots, reports
progress or schedules."""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import pvcloth
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.scene.parts import INTEGRATOR_NAMES, MEASURING_INTEGRATORS

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
from pvcloth.scene.parts import ClothSpec, ObstacleSpec, WindSpec
from pvcloth.scene.spec import Scene
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
print(json.dumps(sorted(m for m in sys.modules if m.startswith("pvcloth."))))
print(json.dumps(sorted(m.split(".")[0] for m in sys.modules)))
"""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    loaded = set(json.loads(done.stdout.splitlines()[-1]))
    assert not loaded & set(OUTSIDE), f"physics loaded {sorted(loaded & set(OUTSIDE))}"
    ours = json.loads(done.stdout.splitlines()[-2])
    above = [m for m in ours if m.split(".")[1] in ("visual", "io", "studies", "cli")]
    assert not above, f"physics loaded the layers above it: {above}"


def _imports(path: Path, annotations: bool = True, names: bool = False) -> set[str]:
    """Modules ``path`` imports, inside functions too; ``annotations``
    False leaves out those under ``if TYPE_CHECKING:`` (never run), and
    ``names`` adds ``module.name`` for each ``from module import name`` (the
    name may be a module)."""
    tree = ast.parse(path.read_text())
    skipped = set()
    if not annotations:
        for node in ast.walk(tree):
            if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
                skipped.update(id(inner) for inner in ast.walk(node))
    found = set()
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
            if names:
                found.update(f"{node.module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


def _module_graph() -> dict[str, set[str]]:
    """pvcloth's modules and the pvcloth modules each imports when it runs."""
    paths = {
        ".".join(("pvcloth", *path.relative_to(PACKAGE).with_suffix("").parts)).removesuffix(
            ".__init__"
        ): path
        for path in PACKAGE.rglob("*.py")
    }
    return {
        name: {m for m in _imports(path, annotations=False, names=True) if m in paths and m != name}
        for name, path in paths.items()
    }


def test_no_module_imports_one_that_imports_it_back():
    # A cycle, however long, through imports that run (lazy ones included).
    graph = _module_graph()
    done, path = set(), []

    def visit(name: str) -> None:
        if name in path:
            cycle = path[path.index(name) :] + [name]
            raise AssertionError("import cycle: " + " -> ".join(cycle))
        if name in done:
            return
        path.append(name)
        for other in sorted(graph[name]):
            if other != "pvcloth":  # the package's __init__ gathers the public names
                visit(other)
        path.pop()
        done.add(name)

    for name in sorted(graph):
        visit(name)


def test_the_visual_layer_does_not_reach_into_the_studies():
    for path in (PACKAGE / "visual").rglob("*.py"):
        reached = sorted(m for m in _imports(path) if m.startswith("pvcloth.studies"))
        assert not reached, f"{path.name} imports {reached}"


def test_imports_point_down_the_layers_only():
    # scene -> physics -> visual / io / studies: a lower layer never imports
    # a higher one (checked on the source, including imports inside functions).
    below = {
        "scene": ("pvcloth.errors", "pvcloth.scene"),
        "physics": ("pvcloth.errors", "pvcloth.scene", "pvcloth.signals", "pvcloth.physics"),
    }
    # The cloth as a mesh is added above both, in pvcloth/simulation.py.
    for folder, allowed in below.items():
        for path in (PACKAGE / folder).rglob("*.py"):
            for module in _imports(path):
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


def test_the_architecture_page_names_every_module():
    # docs/architecture.md is the map a newcomer reads the package by: a
    # module it does not name is a module nobody will find.
    # (Integrators are "one file per method", named by the registry.)
    page = (PACKAGE.parent / "docs" / "architecture.md").read_text()
    named = set(re.findall(r"[\w.]+\.py\b", page))
    missing = sorted(
        str(path.relative_to(PACKAGE))
        for path in PACKAGE.rglob("*.py")
        if path.name not in named
        and path.name != "__init__.py"
        and not (path.parent.name == "integrators" and path.stem in INTEGRATORS)
    )
    assert not missing, f"docs/architecture.md does not name {missing}"
