"""Save a simulation to one file and resume it exactly.

A checkpoint is a NumPy ``.npz`` archive (zip with CRC checks) holding a
format tag, the scene as it runs (live edits included: stiffness, wind,
integrator, the step asked for and the stability policy) as JSON, the step
being taken, the stiffness scale, the backend, positions, velocities, the clock, pins and
their targets, and the integrator's own state (implicit Euler's warm start),
so a resumed run repeats the uninterrupted one bit for bit. Writing goes to
a temporary file renamed into place, so a crash mid-write leaves the
previous checkpoint intact.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from pvcloth.errors import CheckpointError, PvclothError
from pvcloth.io.files import atomic_write
from pvcloth.physics.clocks import MAX_STEPS
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.physics.live_edits import MAX_STIFFNESS_SCALE, MIN_STIFFNESS_SCALE
from pvcloth.physics.simulation import SPEED_LIMIT
from pvcloth.physics.state import State
from pvcloth.scene.parts import MAX_LENGTH
from pvcloth.scene.spec import Scene
from pvcloth.simulation import Simulation

TAG = "pvcloth-checkpoint"
VERSION = 2
#: Versions this pvcloth reads (1 had no stiffness scale).
READABLE = (1, 2)


def save_checkpoint(sim: Simulation, path: str | os.PathLike) -> Path:
    """Write the whole simulation state to ``path`` (``.npz``), atomically.

    Examples
    --------
    >>> import numpy as np, pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> sim.advance(0.1)
    >>> pvcloth.save_checkpoint(sim, "run.npz")
    PosixPath('run.npz')
    >>> resumed = pvcloth.load_checkpoint("run.npz")
    >>> sim.advance(0.1); resumed.advance(0.1)
    >>> bool(np.array_equal(sim.positions, resumed.positions))  # bit for bit
    True
    """
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz")
    path.parent.mkdir(parents=True, exist_ok=True)
    extra = {f"integrator_{k}": v for k, v in sim.integrator.get_state().items()}
    if sim.controller is not None:  # an adaptive run resumes with its controller's memory
        extra["controller"] = sim.controller.get_state()
    arrays = dict(
        tag=np.array(TAG),
        version=np.array(VERSION),
        scene=np.array(json.dumps(sim.scene.to_dict())),
        integrator=np.array(sim.integrator.name),
        dt=np.array(sim.dt),
        stiffness_scale=np.array(sim.stiffness_scale),
        backend=np.array(sim.model.backend),
        x=sim.state.x,
        v=sim.state.v,
        t=np.array(sim.state.t),
        **sim.clock_state(),  # steps, owed
        **sim.control.get_state(),  # pinned, targets
        **extra,
    )

    def write(temporary):
        with open(temporary, "wb") as handle:
            np.savez(handle, **arrays)

    atomic_write(path, write)
    return path


def load_checkpoint(path: str | os.PathLike) -> Simulation:
    """Rebuild the simulation saved in ``path``.

    Every entry is checked before use: its type, shape and range, and that
    its numbers are finite, so a damaged or edited file cannot start a run
    that hangs or returns NaN.

    Raises
    ------
    CheckpointError
        If the file cannot be read, is not a pvcloth checkpoint, or any entry
        is missing, of the wrong kind or out of range. Nothing is changed in
        that case.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            data = {key: archive[key] for key in archive.files}
    except FileNotFoundError:
        raise CheckpointError(f"no checkpoint at {path}") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, RuntimeError) as error:
        raise CheckpointError(f"{path} is not a readable checkpoint: {error}") from None
    except Exception as error:  # numpy's readers raise more kinds on damaged archives
        raise CheckpointError(f"{path} is not a readable checkpoint: {error!r}") from None
    try:
        return _rebuild(data, path)
    except CheckpointError:
        raise
    except PvclothError as error:
        raise CheckpointError(f"{path}: its contents are invalid: {error}") from None


def _entry(data: dict, key: str, path: Path, kind: str, shape=None) -> np.ndarray:
    """``data[key]``, checked to be of numpy kind ``kind`` (and ``shape``)
    and, for numbers, finite."""
    if key not in data:
        raise CheckpointError(f"{path} lacks the entry {key!r}")
    value = data[key]
    if value.dtype.kind not in kind or (shape is not None and value.shape != shape):
        raise CheckpointError(
            f"{path}: {key!r} is {value.dtype} of shape {value.shape}; expected "
            f"{ {'U': 'text', 'f': 'floats', 'iu': 'integers', 'b': 'booleans'}[kind] } "
            f"of shape {shape if shape is not None else 'any'}"
        )
    if kind == "f" and not np.isfinite(value).all():
        raise CheckpointError(f"{path}: {key!r} holds values that are not finite")
    return value


def _scalar(data, key, path, kind, low, high):
    value = _entry(data, key, path, kind, ()).item()
    if not low <= value <= high:
        raise CheckpointError(f"{path}: {key!r} is {value!r}; expected {low} to {high}")
    return value


def _rebuild(data: dict, path: Path) -> Simulation:
    if str(data.get("tag", "")) != TAG:
        raise CheckpointError(f"{path} is not a pvcloth checkpoint (no {TAG!r} tag)")
    version = _entry(data, "version", path, "iu", ()).item()
    if version not in READABLE:
        raise CheckpointError(
            f"{path} has checkpoint version {version}; this pvcloth reads versions "
            f"{', '.join(map(str, READABLE))}"
        )
    try:
        scene = Scene.from_dict(json.loads(str(_entry(data, "scene", path, "U", ()))))
    except (ValueError, RecursionError) as error:  # JSONDecodeError is a ValueError
        raise CheckpointError(f"{path}: its scene is not readable JSON: {error}") from None
    integrator = str(_entry(data, "integrator", path, "U", ()))
    if integrator not in INTEGRATORS:
        raise CheckpointError(f"{path}: unknown integrator {integrator!r}")
    # Version 1 saved the integrator beside the scene, not in it.
    scene = scene.with_overrides({"solver.integrator": integrator})
    dt = _scalar(data, "dt", path, "f", 1e-300, 10.0)
    scale, backend = 1.0, None  # version 1 resumed on the default backend
    if version >= 2:
        backend = str(_entry(data, "backend", path, "U", ()))
        scale = _scalar(
            data, "stiffness_scale", path, "f", MIN_STIFFNESS_SCALE, MAX_STIFFNESS_SCALE
        )
    nx, ny = scene.cloth.resolution
    n = nx * ny
    x = _entry(data, "x", path, "f", (n, 3))
    v = _entry(data, "v", path, "f", (n, 3))
    targets = _entry(data, "targets", path, "f", (n, 3))
    pinned = _entry(data, "pinned", path, "b", (n,))
    for key, values, bound in (("x", x, MAX_LENGTH), ("targets", targets, MAX_LENGTH)):
        if np.abs(values).max() > bound:
            raise CheckpointError(f"{path}: {key!r} has a coordinate beyond +-{bound:g} m")
    if np.abs(v).max() > SPEED_LIMIT:
        raise CheckpointError(f"{path}: 'v' has a speed beyond {SPEED_LIMIT:g} m/s")
    t = _scalar(data, "t", path, "f", 0.0, MAX_STEPS * dt)
    steps = _scalar(data, "steps", path, "iu", 0, 2**62)
    owed = _scalar(data, "owed", path, "f", 0.0, dt)  # never a whole step is owed
    prefix = "integrator_"
    extra = {}
    for key in data:
        if key.startswith(prefix):
            values = _entry(data, key, path, "f")
            if values.ndim != 1 or values.size > 3 * n:  # one value per free coordinate
                raise CheckpointError(f"{path}: {key!r} has shape {values.shape}")
            extra[key[len(prefix) :]] = values
    controller = None
    if "controller" in data:
        values = _entry(data, "controller", path, "f")
        if values.shape not in ((3,), (6,)) or values[2] < 0:  # 3: saved before the bounds
            raise CheckpointError(f"{path}: 'controller' holds {values.tolist()}")
        controller = values
    return Simulation.resumed(
        scene,
        controller_state=controller,
        dt=float(dt),
        stiffness_scale=float(scale),
        backend=backend,
        state=State(x, v, float(t)),
        steps=int(steps),
        owed=float(owed),
        pinned=pinned,
        targets=targets,
        integrator_state=extra,
    )
