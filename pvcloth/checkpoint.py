"""Save a simulation to one file and resume it exactly.

A checkpoint is a NumPy ``.npz`` archive (zip with CRC checks) holding a
format tag, the scene as JSON, the integrator and step, positions,
velocities, the clock, pins and their targets, and the integrator's own
state (implicit Euler's warm start), so a resumed run repeats the
uninterrupted one bit for bit. Writing goes to a temporary file renamed into
place, so a crash mid-write leaves the previous checkpoint intact.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from .errors import CheckpointError, PvclothError
from .timeseries import atomic_write

TAG = "pvcloth-checkpoint"
VERSION = 1


def save_checkpoint(sim, path) -> Path:
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
    arrays = dict(
        tag=np.array(TAG),
        version=np.array(VERSION),
        scene=np.array(json.dumps(sim.scene.to_dict())),
        integrator=np.array(sim.integrator.name),
        dt=np.array(sim.dt),
        x=sim.state.x,
        v=sim.state.v,
        t=np.array(sim.state.t),
        steps=np.array(sim.steps),
        owed=np.array(sim._owed),
        pinned=sim.control.pinned,
        targets=sim.control.targets,
        **extra,
    )

    def write(temporary):
        with open(temporary, "wb") as handle:
            np.savez(handle, **arrays)

    atomic_write(path, write)
    return path


def load_checkpoint(path):
    """Rebuild the simulation saved in ``path``.

    Raises
    ------
    CheckpointError
        If the file cannot be read, is not a pvcloth checkpoint, or its
        arrays do not fit its scene. Nothing is changed in that case.
    """
    from .scene import Scene
    from .simulation import Simulation

    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            data = {key: archive[key] for key in archive.files}
    except FileNotFoundError:
        raise CheckpointError(f"no checkpoint at {path}") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise CheckpointError(f"{path} is not a readable checkpoint: {error}") from None
    if str(data.get("tag", "")) != TAG:
        raise CheckpointError(f"{path} is not a pvcloth checkpoint (no {TAG!r} tag)")
    if int(data["version"]) != VERSION:
        raise CheckpointError(
            f"{path} has checkpoint version {int(data['version'])}; "
            f"this pvcloth reads version {VERSION}"
        )
    try:
        scene = Scene.from_dict(json.loads(str(data["scene"])))
        sim = Simulation(
            scene, integrator=str(data["integrator"]), dt=float(data["dt"]), stability="ignore"
        )
        n = sim.model.n_points
        for key, shape in (("x", (n, 3)), ("v", (n, 3)), ("targets", (n, 3)), ("pinned", (n,))):
            if data[key].shape != shape:
                raise CheckpointError(
                    f"{path}: {key} has shape {data[key].shape}, the scene needs {shape}"
                )
    except PvclothError as error:
        if isinstance(error, CheckpointError):
            raise
        raise CheckpointError(f"{path}: its scene is invalid: {error}") from None
    except KeyError as error:
        raise CheckpointError(f"{path} lacks the entry {error}") from None
    sim.state.x[:] = data["x"]
    sim.state.v[:] = data["v"]
    sim.state.t = float(data["t"])
    sim.steps = int(data["steps"])
    sim._owed = float(data["owed"])
    sim.control.pinned[:] = data["pinned"]
    sim.control.targets[:] = data["targets"]
    sim.control.refresh(sim.model)
    prefix = "integrator_"
    sim.integrator.set_state({k[len(prefix) :]: v for k, v in data.items() if k.startswith(prefix)})
    return sim
