"""Parameter sweeps: many short simulations over a product of settings, on Dask.

A sweep is the Cartesian product of ``--set KEY=VALUES`` settings applied to
one scene. Every combination is an independent *unit*: a short simulation
that records whether it stayed stable (or the divergence message), its RMS
error against a reference of the same physical settings (RK4 at a quarter of
the smallest step swept for those settings, as in the trade-off command),
wall time per simulated second and final energy.

Units run on Dask (``dask.distributed``): a local cluster on this machine's
cores by default, or an existing cluster given by its scheduler address.
References are Dask tasks too, shared by the units that need them. Dask
retries the tasks of a worker that dies, so losing a worker loses only the
work it had in hand. Rows are appended to ``sweep.csv`` as units finish (one
``write`` and ``flush`` per row), so an interrupted sweep keeps every finished
row, and running the same command again skips the rows already there.

Value syntax (validated like scene files, through :class:`~pvcloth.Scene`):

- a list: ``springs.structural=1e2,1e3,1e4`` or ``solver.integrator=rk4,verlet``
- a linear range: ``cloth.mass=0.1:0.5:5lin`` (5 values from 0.1 to 0.5)
- a logarithmic range: ``solver.dt=1e-4:1e-2:8log``

Keys are dotted scene keys, in the dialect every scene change uses
(:mod:`pvcloth.scene.overrides`, with its two shorthands: a spring family
``springs.structural`` sets its stiffness, and ``cloth.resolution=N`` means
N x N points); each value is read as there.
"""

from __future__ import annotations

import csv
import hashlib
import itertools
import json
import logging
import math
import re
import signal
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from pvcloth.errors import SceneError, SweepError
from pvcloth.io.files import atomic_write
from pvcloth.physics.reference import reference_run, reference_step, rms_distance
from pvcloth.scene.overrides import parse_value
from pvcloth.scene.spec import Scene
from pvcloth.signals import deferred
from pvcloth.studies import runs

FIELDS = [
    "id",
    "settings",
    "integrator",
    "dt",
    "stable",
    "error",
    "rms_error",
    "wall_per_sim_second",
    "final_energy",
]

_RANGE = re.compile(r"^([^:]+):([^:]+):(\d+)(lin|log)$")


# -- settings -------------------------------------------------------------------


def parse_values(key: str, spec: str) -> list:
    """The values one ``--set KEY=SPEC`` asks for.

    Examples
    --------
    >>> parse_values("solver.dt", "1e-4:1e-2:3log")
    [0.0001, 0.001, 0.01]
    >>> parse_values("solver.integrator", "rk4,verlet")
    ['rk4', 'verlet']
    """
    spec = spec.strip()
    match = _RANGE.match(spec)
    if match:
        start, stop, count, kind = match.groups()
        try:
            low, high = float(start), float(stop)
        except ValueError:
            raise SweepError(f"{key}: range ends must be numbers, got {spec!r}") from None
        count = int(count)
        if count < 1:
            raise SweepError(f"{key}: a range needs at least 1 value, got {count}")
        if kind == "log":
            if low <= 0 or high <= 0:
                raise SweepError(f"{key}: a log range needs positive ends, got {spec!r}")
            values = np.geomspace(low, high, count)
        else:
            values = np.linspace(low, high, count)
        return [float(f"{v:.12g}") for v in values]
    values = [parse_value(item) for item in spec.split(",") if item.strip()]
    if not values:
        raise SweepError(f"{key}: no values given")
    return values


def parse_sets(items: list[str]) -> dict[str, list]:
    """``["KEY=SPEC", ...]`` to ``{key: values}`` (in the order given)."""
    sets: dict[str, list] = {}
    for item in items:
        key, sep, spec = item.partition("=")
        if not sep or not key.strip():
            raise SweepError(f"expected KEY=VALUES, got {item!r}")
        key = key.strip()
        if key in sets:
            raise SweepError(f"{key} is given twice")
        sets[key] = parse_values(key, spec)
    return sets


@dataclass(frozen=True)
class Unit:
    """One combination of settings."""

    settings: dict
    scene: Scene

    @property
    def label(self) -> str:
        return json.dumps(self.settings, sort_keys=True)

    @property
    def id(self) -> str:
        return hashlib.sha1(self.label.encode()).hexdigest()[:12]

    @property
    def physics(self) -> str:
        """What the reference depends on: the scene without its solver."""
        data = self.scene.to_dict()
        data.pop("solver", None)
        data.pop("name", None)
        return hashlib.sha1(json.dumps(data, sort_keys=True).encode()).hexdigest()[:12]


def expand(scene: Scene, sets: dict[str, list]) -> list[Unit]:
    """Every combination of ``sets`` applied to ``scene``, validated.

    Raises
    ------
    SceneError
        Naming the ``--set`` key and value that make a bad scene.
    """
    units = []
    keys = list(sets)
    for values in itertools.product(*(sets[k] for k in keys)):
        settings = dict(zip(keys, values, strict=True))
        try:
            units.append(Unit(settings, scene.with_overrides(settings)))
        except SceneError as error:
            raise SceneError(
                error.key, f"{error.message} (from the settings {', '.join(keys)} = {values})"
            ) from None
    return units


# -- work -------------------------------------------------------------------------


def shared_reference_step(scenes: list[Scene], duration: float) -> float:
    """The step of the reference shared by ``scenes`` (one physics, several
    solver settings): see :func:`pvcloth.physics.reference.reference_step`."""
    return reference_step(scenes[0], min(runs.scene_step(s) for s in scenes), duration)


def run_reference(scene: Scene, dt: float, duration: float) -> dict:
    """Positions and energy of the fine solution (a Dask task)."""
    sim = reference_run(scene, duration, dt)
    return {"x": np.array(sim.positions), "energy": sim.energy()["total"], "dt": dt}


def run_unit(unit: Unit, reference: dict, duration: float) -> dict:
    """One short simulation, compared with its reference (a Dask task)."""
    scene = unit.scene
    dt = runs.dividing_step(duration, runs.scene_step(scene))
    run = runs.timed_run(scene, duration, dt=dt)
    rms = energy = math.nan
    if run.stable:
        rms = rms_distance(run.sim.positions, reference["x"])
        energy = float(run.sim.energy()["total"])
    return {
        "id": unit.id,
        "settings": unit.label,
        "integrator": scene.solver.method,
        "dt": dt,
        "stable": run.stable,
        "error": run.message,
        "rms_error": rms,
        "wall_per_sim_second": run.wall_per_sim_second,
        "final_energy": energy,
    }


# -- results file -------------------------------------------------------------------


def read_rows(path: Path) -> list[dict]:
    """Rows of a sweep CSV; a line cut short by an interruption is ignored."""
    if not path.exists():
        return []
    rows = []
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            if None in row or any(row.get(f) is None for f in FIELDS):
                continue  # an incomplete last line
            row["dt"] = float(row["dt"])
            row["stable"] = row["stable"] == "True"
            for name in ("rms_error", "wall_per_sim_second", "final_energy"):
                row[name] = float(row[name])
            rows.append(row)
    return rows


class RowWriter:
    """Appends one CSV row per finished unit, flushed at once.

    The one output not staged whole (:mod:`pvcloth.io.files`): a sweep
    resumes from the rows already there, so each finished run must reach
    the file as it ends. A row cut short by a kill is dropped on reading
    and on reopening."""

    def __init__(self, path: Path):
        if path.exists():
            _drop_partial_line(path)
        new = not path.exists() or path.stat().st_size == 0
        self.handle = open(path, "a", newline="")  # noqa: SIM115 (closed in close())
        self.writer = csv.DictWriter(self.handle, fieldnames=FIELDS)
        if new:
            self.writer.writeheader()
            self.handle.flush()

    def write(self, row: dict) -> None:
        self.writer.writerow(row)
        self.handle.flush()

    def close(self) -> None:
        self.handle.close()


def _drop_partial_line(path: Path) -> None:
    """Cut a row that an interruption left without its newline (its open
    quote would swallow the rows appended after it)."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as handle:
            handle.truncate(data.rfind(b"\n") + 1)


# -- driver -----------------------------------------------------------------------


def _client(scheduler: str | None, workers: int | None):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise SweepError(
            "sweeps run on Dask: pip install 'dask[distributed]' (or pvcloth[sweep])"
        ) from None
    if scheduler:
        try:
            return Client(scheduler, timeout="10s"), None
        except OSError as error:
            raise SweepError(f"cannot reach the Dask scheduler at {scheduler}: {error}") from None
    # The worker processes start with Ctrl-C ignored (an ignored signal stays
    # ignored in a child): it is this process that stops the sweep and closes
    # them, instead of each printing the traceback of its interrupted loop.
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            # A task's error reaches this process through its future; what
            # the workers log besides is news of their own shutdown (a
            # cancelled task, a heartbeat to a scheduler already closed by
            # Ctrl-C), printed with a traceback at ERROR level.
            silence_logs=logging.CRITICAL,
        )
    finally:
        signal.signal(signal.SIGINT, previous)
    return Client(cluster), cluster


def run_sweep(
    scene: Scene,
    sets: dict[str, list],
    out: Path,
    *,
    duration: float = 0.25,
    scheduler: str | None = None,
    workers: int | None = None,
    client=None,
    progress: bool = True,
) -> list[dict]:
    """Run every unit not yet in ``out/sweep.csv`` and append its row.

    Parameters
    ----------
    scene : Scene
    sets : dict
        ``{key: values}`` from :func:`parse_sets`.
    out : Path
        Folder for ``sweep.csv`` (created).
    duration : float
        Simulated seconds per unit.
    scheduler : str, optional
        Address of an existing Dask scheduler; default a local cluster.
    workers : int, optional
        Workers of the local cluster (default: one per core).
    client : dask.distributed.Client, optional
        Use this client instead of making one.

    Returns
    -------
    list of dict
        All rows of the sweep, old and new, in unit order.
    """
    units = expand(scene, sets)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "sweep.csv"
    done = {row["id"] for row in read_rows(path)}
    todo = [u for u in units if u.id not in done]
    if todo:
        own = client is None
        cluster = None
        if own:
            client, cluster = _client(scheduler, workers)
        from dask.distributed import as_completed

        references, futures = {}, []
        try:
            groups: dict[str, list[Unit]] = {}
            for unit in units:  # references see every step swept, done or not
                groups.setdefault(unit.physics, []).append(unit)
            references = {}
            for key, members in groups.items():
                if any(u in todo for u in members):
                    dt = shared_reference_step([u.scene for u in members], duration)
                    references[key] = client.submit(
                        run_reference, members[0].scene, dt, duration, key=f"reference-{key}"
                    )
            futures = [
                client.submit(
                    run_unit, u, references[u.physics], duration, key=f"unit-{u.id}", retries=2
                )
                for u in todo
            ]
            writer = RowWriter(path)
            try:
                bar = tqdm(
                    total=len(units),
                    initial=len(units) - len(todo),
                    desc="sweep",
                    unit="run",
                    disable=not progress,
                )
                for future in as_completed(futures):
                    writer.write(future.result())
                    bar.update()
                bar.close()
            finally:
                writer.close()
        except KeyboardInterrupt:
            # Stop the work before the workers go, so that they end quietly
            # instead of printing the tracebacks of their cancelled tasks.
            with deferred(then_raise=False):
                client.cancel(list(references.values()) + futures, force=True)
            raise
        finally:
            if own:
                with deferred(then_raise=False):  # a second Ctrl-C must not break the shutdown
                    client.close()
                    if cluster is not None:
                        cluster.close()
    order = {u.id: n for n, u in enumerate(units)}
    rows = [row for row in read_rows(path) if row["id"] in order]
    return sorted(rows, key=lambda row: order[row["id"]])


# -- report -------------------------------------------------------------------------


def summary(rows: list[dict]) -> str:
    """A short table per integrator: runs, stable, best error, median cost."""
    lines = [
        f"{'integrator':<18}{'runs':>6}{'stable':>8}{'best RMS error':>16}{'median wall/sim s':>19}"
    ]
    for name in sorted({r["integrator"] for r in rows}):
        mine = [r for r in rows if r["integrator"] == name]
        ok = [r for r in mine if r["stable"]]
        best = f"{min(r['rms_error'] for r in ok):.3e}" if ok else "-"
        cost = np.median([r["wall_per_sim_second"] for r in mine])
        lines.append(f"{name:<18}{len(mine):>6}{len(ok):>8}{best:>16}{cost:>19.3g}")
    return "\n".join(lines)


def plot(rows: list[dict], sets: dict[str, list], path: Path, axes: list[str] | None = None):
    """Stability maps over two swept keys (one panel per integrator; a cell's
    colour is the share of its runs that stayed stable) and the accuracy-cost
    points of every stable run."""
    # A Figure of its own, drawn by Agg when saved: no pyplot, so the
    # caller's matplotlib backend (a notebook's) is left as it was.
    from matplotlib.figure import Figure

    if not axes:  # the swept keys with several values; the step across if swept
        keys = [k for k in sets if k != "solver.integrator" and len(sets[k]) > 1]
        keys.sort(key=lambda k: k != "solver.dt")
        axes = keys[:2] or [next(iter(sets))]
    for key in axes:
        if key not in sets:
            raise SweepError(f"axes: {key} is not a swept key (swept: {', '.join(sets)})")
    integrators = sorted({r["integrator"] for r in rows})
    fig = Figure(figsize=(3.6 * (len(integrators) + 1), 3.6), dpi=100)
    panels = fig.subplots(1, len(integrators) + 1, squeeze=False)
    panels = panels[0]
    for panel, name in zip(panels, integrators, strict=False):
        mine = [r for r in rows if r["integrator"] == name]
        _stability_panel(panel, mine, sets, axes)
        panel.set_title(name, fontsize=9)
    cost = panels[-1]
    for n, name in enumerate(integrators):
        ok = [r for r in rows if r["integrator"] == name and r["stable"]]
        cost.loglog(
            [r["wall_per_sim_second"] for r in ok],
            [r["rms_error"] for r in ok],
            "o",
            color=f"C{n}",
            label=name,
            alpha=0.8,
        )
    cost.set_xlabel("wall s per simulated s")
    cost.set_ylabel("RMS error vs reference (m)")
    cost.set_title("accuracy against cost (stable runs)", fontsize=9)
    cost.legend(fontsize=7)
    cost.grid(True, which="both", alpha=0.2)
    fig.tight_layout()
    atomic_write(path, fig.savefig)


def _stability_panel(panel, rows, sets, axes) -> None:
    def settings(row):
        return json.loads(row["settings"])

    if len(axes) == 1:
        axes = [axes[0], None]
    xs = sets[axes[0]]
    ys = sets[axes[1]] if axes[1] else [None]
    share = np.full((len(ys), len(xs)), np.nan)
    for j, y in enumerate(ys):
        for i, x in enumerate(xs):
            cell = [
                r
                for r in rows
                if settings(r)[axes[0]] == x and (axes[1] is None or settings(r)[axes[1]] == y)
            ]
            if cell:
                share[j, i] = np.mean([r["stable"] for r in cell])
    panel.imshow(share, origin="lower", cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    panel.set_xticks(
        range(len(xs)),
        [f"{x:.3g}" if isinstance(x, float) else str(x) for x in xs],
        rotation=60,
        fontsize=7,
    )
    panel.set_xlabel(axes[0], fontsize=8)
    if axes[1]:
        panel.set_yticks(
            range(len(ys)), [f"{y:.3g}" if isinstance(y, float) else str(y) for y in ys], fontsize=7
        )
        panel.set_ylabel(axes[1], fontsize=8)
    else:
        panel.set_yticks([])
    for j in range(len(ys)):
        for i in range(len(xs)):
            if not np.isnan(share[j, i]):
                panel.text(
                    i,
                    j,
                    "ok"
                    if share[j, i] == 1
                    else ("x" if share[j, i] == 0 else f"{share[j, i]:.0%}"),
                    ha="center",
                    va="center",
                    fontsize=7,
                )
