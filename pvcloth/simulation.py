"""The simulation a user holds: the physics
(:class:`pvcloth.physics.simulation.Simulation`) plus the cloth as a PyVista
mesh that follows it, and a plot.

This is the one place where the physics meets the drawing libraries, above
both: the physics imports nothing that draws, and PyVista is imported only
when the mesh or a plot is first asked for.
"""

from __future__ import annotations

import time

from pvcloth.errors import InputError
from pvcloth.physics import simulation as physics


class Simulation(physics.Simulation):
    """A cloth that moves, and its mesh: what ``pvcloth.Simulation``,
    :meth:`from_file` and :func:`pvcloth.load_checkpoint` give.

    Everything of :class:`pvcloth.physics.simulation.Simulation` (its
    parameters, attributes and methods), plus :attr:`mesh`,
    :meth:`update_mesh` and :meth:`plot`.

    Examples
    --------
    >>> import pvcloth
    >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
    >>> sim.advance(1 / 60)
    >>> sim.mesh.n_points, round(sim.time, 4)
    (64, 0.0167)
    """

    _mesh = None  # built on first use of ``mesh``: physics runs without PyVista

    @property
    def mesh(self):
        """The cloth as a ``pyvista.StructuredGrid`` of dimensions ``(nx, ny, 1)``.

        The same object for the life of the simulation, its points and point
        data updated in place after every :meth:`advance`, :meth:`step` and
        :meth:`reset`, so a plotter showing it or a script holding it sees the
        current cloth. Point ``k`` is solver point ``k``. Point data (colour
        by any of them, e.g. ``sim.plot(scalars="speed")``):

        - ``velocity`` (N, 3), m/s
        - ``speed`` (N,), m/s
        - ``stretch`` (N,), local length over rest length (1 at rest)
        - ``force`` (N,), N, mean elastic force of the springs at the point
        - ``energy`` (N,), J/m^2, elastic energy density
          (:mod:`pvcloth.physics.fields`)
        - ``pinned`` (N,), 1 where the point is pinned, else 0

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> mesh = sim.mesh
        >>> mesh.dimensions, mesh.n_points
        ((8, 8, 1), 64)
        >>> sim.advance(0.1)
        >>> sim.mesh is mesh, bool(mesh.points[:, 2].min() < sim.model.rest_positions[:, 2].min())
        (True, True)
        >>> sorted(mesh.point_data.keys())
        ['energy', 'force', 'pinned', 'speed', 'stretch', 'velocity']
        """
        if self._mesh is None:
            from pvcloth.visual.cloth_grid import cloth_mesh

            self._mesh = cloth_mesh(self)
        return self._mesh

    def update_mesh(self) -> None:
        """Copy the current state into :attr:`mesh` (done whenever the state
        changes). Costs nothing until the mesh is first used."""
        if self._mesh is not None:
            from pvcloth.visual.cloth_grid import update_cloth_mesh

            update_cloth_mesh(self._mesh, self)

    def plot(self, **kwargs):
        """Show the cloth as ``mesh.plot()`` does (keywords go to
        :func:`pyvista.plot`); the cloth's colour unless ``scalars`` is given.

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> sim.advance(0.2)
        >>> sim.plot(scalars="stretch", off_screen=True, screenshot="stretch.png")
        """
        from pvcloth.visual.view import plot_cloth

        return plot_cloth(self, **kwargs)

    def advance(self, seconds: float, progress: bool | str = False) -> None:
        """Simulate ``seconds`` more (see
        :meth:`pvcloth.physics.simulation.Simulation.advance`), with a
        progress bar over the simulated seconds if ``progress`` is true, or
        with ``"auto"`` once the first steps predict more than
        :data:`PROGRESS_AFTER` seconds of wall time for the call (a terminal
        bar, or a widget in a notebook).

        Examples
        --------
        >>> import pvcloth
        >>> sim = pvcloth.Simulation(pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8))))
        >>> sim.advance(0.05, progress="auto")  # a bar only if this were slow
        >>> round(sim.time, 3)
        0.05
        """
        if progress not in (False, True, "auto"):
            raise InputError("progress", f"expected True, False or 'auto', got {progress!r}")
        if progress is False:
            return super().advance(seconds)
        bar = _ProgressBar(seconds, always=progress is True)
        try:
            super().advance(seconds, on_step=bar.update)
        finally:
            bar.close()

    def _state_changed(self) -> None:
        self.update_mesh()


#: Wall seconds an advance must be expected to take before its bar shows by default.
PROGRESS_AFTER = 3.0


class _ProgressBar:
    """A tqdm bar over an advance's simulated seconds, opened at once when
    asked for, else only once the steps so far predict more than
    :data:`PROGRESS_AFTER` seconds for the whole call."""

    def __init__(self, seconds: float, always: bool):
        self.seconds, self.always = seconds, always
        self.started = time.perf_counter()
        self.bar = None
        self.shown = 0  # simulated milliseconds on the bar
        if always:
            self._open()

    def _open(self) -> None:
        from tqdm.auto import tqdm

        # In whole simulated milliseconds: float counts can pass the total by a rounding.
        total = max(1, round(1000 * self.seconds))
        self.bar = tqdm(total=total, desc="advancing", unit="ms simulated")

    def update(self, done: float) -> None:
        done = min(done, self.seconds)  # time owed from the call before adds steps
        if self.bar is None:
            spent = time.perf_counter() - self.started
            if done <= 0.0 or spent * self.seconds / done <= PROGRESS_AFTER:
                return
            self._open()
        now = min(round(1000 * done), self.bar.total)
        self.bar.update(now - self.shown)
        self.shown = now

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
