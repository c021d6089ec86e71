"""Export an animation for ParaView or Blender through meshio.

Formats, by extension:

``.pvd``
    one VTU file per frame in ``OUT_vtu/`` plus a ParaView Data index with
    each frame's simulated time; ParaView plays it as a moving cloth.

VTU and XDMF frames carry the point data of ``Simulation.mesh``
(:data:`pvcloth.physics.fields.MESH_FIELDS`: velocity m/s, speed m/s,
stretch, force N, energy J/m^2, pinned), so ParaView colours by any of them.
``.xdmf``
    an XDMF time series (with its HDF5 file). meshio writes the geometry
    once, so each frame stores ``displacement`` (from the rest positions) as
    point data besides the fields: in ParaView apply *Warp By Vector* with
    ``displacement`` to see the cloth move.
``.pc2``
    a point cache for Blender's built-in *Mesh Cache* modifier (no add-on):
    ``OUT.pc2`` holds every frame's positions, ``OUT.obj`` the cloth at the
    first frame with texture coordinates and normals, in the same vertex
    order. In Blender: *File → Import → Wavefront (.obj)* ``OUT.obj`` with
    *Forward* Y and *Up* Z, then *Add Modifier → Mesh Cache*, format PC2,
    file ``OUT.pc2``, axes *Forward* +Y and *Up* +Z (its defaults), *Frame
    Start* 1 (so that Blender's first frame, 1, shows the first exported
    one), and the scene's frame rate set to the export's ``fps``.
``.obj``
    one OBJ file per frame in ``OUT_obj/`` for Blender, with texture
    coordinates (the grid's, 0 to 1) and vertex normals, the same vertex
    order in every frame, and nothing that changes from run to run (meshio's
    writer stamps the time and cannot give faces texture coordinates, so
    pvcloth writes these itself). The data is z-up in metres: in Blender's
    OBJ importer set *Forward* to Y and *Up* to Z. Blender has no built-in
    sequence importer; an add-on (e.g. Stop-motion-OBJ) plays the folder,
    or export ``.pc2`` instead.

Every file and frames folder is written under a hidden temporary name beside
it and moved into place when the writing stops, finished or interrupted
(Ctrl-C, SIGTERM, an error; :class:`pvcloth.io.files.Staged`): the frames
done then form a readable series, and a run killed outright (SIGKILL) leaves
an earlier export at that path as it was.
A re-export replaces the whole frames folder, old frames and all; each
format has a folder of its own. Nothing here changes the working directory.
"""

from __future__ import annotations

import os
import struct
from contextlib import ExitStack
from pathlib import Path
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np

from pvcloth.errors import ExportInterrupted, InputError
from pvcloth.io.files import Staged
from pvcloth.physics import topology
from pvcloth.physics.fields import MESH_FIELDS, point_fields
from pvcloth.progress import frame_bar
from pvcloth.signals import deferred

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation

FORMATS = (".pvd", ".xdmf", ".obj", ".pc2")
#: The PC2 header (Blender's Mesh Cache reads it): signature, version, points,
#: start frame, samples per frame, samples; then float32 x, y, z per point per
#: sample, all little-endian.
PC2_HEADER = struct.Struct("<12siiffi")


def write_pc2_header(out, points: int, samples: int) -> None:
    """Write (or rewrite, at the start of ``out``) a PC2 header for
    ``points`` points and ``samples`` frames, one sample per frame, the
    first at frame 0 (where Blender's Mesh Cache puts it, whatever the
    header says)."""
    out.seek(0)
    out.write(PC2_HEADER.pack(b"POINTCACHE2\0", 1, points, 0.0, 1.0, samples))


def grid_texture_coordinates(resolution: tuple[int, int]) -> np.ndarray:
    """``(N, 2)`` texture coordinates of a grid's points, 0 to 1 along each
    side, in point order."""
    nx, ny = resolution
    u, v = np.meshgrid(np.linspace(0.0, 1.0, nx), np.linspace(0.0, 1.0, ny))
    return np.column_stack([u.ravel(), v.ravel()])


def write_obj(path: Path, points: np.ndarray, shape: tuple[int, int], texture: np.ndarray) -> None:
    """One Wavefront OBJ of a ``shape = (ny, nx)`` grid: vertices (m), texture
    coordinates, vertex normals (those the view draws with) and quads
    indexing all three alike; the same bytes for the same cloth."""
    faces = topology.quads(shape)
    normals = topology.normals(points, shape)
    index = faces + 1
    corners = np.repeat(index, 3, axis=1).reshape(-1, 4, 3)
    with open(path, "w") as out:
        out.write("# pvcloth cloth frame: metres, z up\n")
        np.savetxt(out, points, fmt="v %.17g %.17g %.17g")
        np.savetxt(out, texture, fmt="vt %.17g %.17g")
        np.savetxt(out, normals, fmt="vn %.17g %.17g %.17g")
        np.savetxt(out, corners.reshape(len(faces), 12), fmt="f" + " %d/%d/%d" * 4)


def _pvd_index(entries: list[tuple[float, str]]) -> str:
    rows = "\n".join(
        f'    <DataSet timestep="{t!r}" group="" part="0" file={quoteattr(name)}/>'
        for t, name in entries
    )
    return (
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
        f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n"
    )


def export(
    sim: Simulation,
    output: str | os.PathLike,
    *,
    frames: int = 60,
    fps: float = 30.0,
    progress: bool = True,
) -> Path:
    """Simulate ``frames`` frames and write them as a time series.

    Parameters
    ----------
    sim : Simulation
        Advanced by ``1 / fps`` between frames; the first frame is its
        current state.
    output : path
        ``OUT.pvd``, ``OUT.xdmf``, ``OUT.pc2`` (with ``OUT.obj``) or
        ``OUT.obj`` (see the module docstring).
    frames : int
        Number of frames, at least 1.
    fps : float
        Frames per simulated second.
    progress : bool
        Show a progress bar.

    Returns
    -------
    Path
        The index file (``.pvd``, ``.xdmf``), the point cache (``.pc2``) or
        the frames folder (``.obj``).

    Raises
    ------
    ExportInterrupted
        If the run stopped early; the frames done are kept, readable.

    Examples
    --------
    >>> import pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> pvcloth.export(sim, "cloth.pvd", frames=10, progress=False)
    PosixPath('cloth.pvd')
    >>> import pyvista as pv
    >>> reader = pv.get_reader("cloth.pvd")
    >>> len(reader.time_values), round(reader.time_values[-1], 3)
    (10, 0.3)
    """
    path = Path(output)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise InputError("output", f"unknown extension {path.suffix!r}; use one of {FORMATS}")
    frame_numbers = sim.frames(frames, fps)  # checked now, before any file is touched
    path.parent.mkdir(parents=True, exist_ok=True)
    cells = [("quad", topology.quads(sim.model.shape))]
    rest = sim.model.rest_positions
    done = 0
    bar = frame_bar(frame_numbers, frames, f"exporting {path.name}", enabled=progress)
    folder = path.with_name(f"{path.stem}_{'vtu' if suffix == '.pvd' else 'obj'}")
    entries: list[tuple[float, str]] = []  # PVD index: (time, frame file)
    # Every file and frames folder is written under a hidden temporary name
    # beside it and published when the writing stops (finished or
    # interrupted) with a frame written, so a run killed midway leaves an
    # earlier export at this path as it was. The data goes before the index
    # that names it.
    with ExitStack() as temporaries:  # what is not published is removed
        if suffix in (".xdmf", ".pc2"):
            extra = ".h5" if suffix == ".xdmf" else ".obj"
            names = [path.with_suffix(extra), path]
            outputs = [temporaries.enter_context(Staged(name)) for name in names]
        else:
            outputs = [temporaries.enter_context(Staged(folder, folder=True))]
            if suffix == ".pvd":
                outputs.append(temporaries.enter_context(Staged(path)))
        try:
            if suffix == ".xdmf":
                # meshio writes the .h5 as it goes and the .xdmf when closed.
                # meshio 5.3's __enter__ opens the HDF5 file in the working
                # directory (its name without the folder); opening it here by
                # its full path instead, as __enter__ would, keeps the working
                # directory alone (a chdir is process-wide: unsafe under
                # threads). The .xdmf names the HDF5 file by h5_filename's
                # name: the published one, not the temporary's.
                import h5py

                h5, xdmf = outputs
                writer = meshio.xdmf.TimeSeriesWriter(xdmf.temporary)
                writer.h5_filename = str(h5.path)
                writer.h5_file = h5py.File(h5.temporary, "w")
                try:
                    writer.write_points_cells(rest, cells)
                    for _ in bar:
                        with deferred():  # a frame is written whole
                            writer.write_data(
                                sim.time,
                                point_data={
                                    "displacement": sim.positions - rest,
                                    **_fields(sim),
                                },
                            )
                            done += 1
                finally:
                    with deferred(then_raise=False):  # closing writes the .xdmf itself
                        writer.__exit__(None, None, None)
                return path
            if suffix == ".pc2":
                obj, pc2 = outputs
                texture = grid_texture_coordinates(sim.resolution)
                with open(pc2.temporary, "wb") as cache:
                    try:
                        write_pc2_header(cache, sim.model.n_points, 0)
                        for n in bar:
                            with deferred():  # a frame is written whole
                                if n == 0:  # the base mesh: the first frame
                                    write_obj(
                                        obj.temporary, sim.positions, sim.model.shape, texture
                                    )
                                cache.write(np.asarray(sim.positions, dtype="<f4").tobytes())
                                done += 1
                    finally:
                        with deferred(then_raise=False):  # the header counts what is there
                            write_pc2_header(cache, sim.model.n_points, done)
                return path
            staged = outputs[0].temporary
            texture = grid_texture_coordinates(sim.resolution)
            for n in bar:
                name = f"{path.stem}_{n:05d}" + (".vtu" if suffix == ".pvd" else ".obj")
                with deferred():  # a frame is written whole
                    if suffix == ".pvd":
                        mesh = meshio.Mesh(
                            np.array(sim.positions),
                            cells,
                            point_data=_fields(sim),
                        )
                        meshio.write(staged / name, mesh)
                        entries.append((sim.time, f"{folder.name}/{name}"))
                    else:
                        write_obj(staged / name, sim.positions, sim.model.shape, texture)
                    done += 1
            return path if suffix == ".pvd" else folder
        except (Exception, KeyboardInterrupt) as error:
            reason = "interrupted" if isinstance(error, KeyboardInterrupt) else str(error)
            raise ExportInterrupted(
                f"export stopped after {done} frame(s): {reason}\n"
                f"the {done} frame(s) written in {path} stay readable",
                done,
            ) from error
        finally:
            if done:  # the frames written form a valid series
                with deferred(then_raise=False):  # once begun, publishing must finish
                    if suffix == ".pvd":
                        outputs[1].temporary.write_text(_pvd_index(entries))
                    for output in outputs:
                        output.publish()


def _fields(sim) -> dict[str, np.ndarray]:
    """The point data every exported frame carries, as ``sim.mesh`` does
    (``pinned`` as 0/1 floats: XDMF's writer takes numbers)."""
    fields = point_fields(sim, MESH_FIELDS)
    fields["pinned"] = fields["pinned"].astype(float)
    return fields
