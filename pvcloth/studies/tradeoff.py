"""Speed against accuracy: every integrator over a range of time steps.

Each run simulates the same scene for the same time and is compared with a
reference run (RK4 at a quarter of the smallest step asked for, see
:mod:`pvcloth.physics.reference`): the RMS
distance of the points at the end, the relative difference of total energy
at the end (the numerical energy drift, since the reference loses only what
damping takes), the wall time per simulated second, and whether it stayed
stable. Runs go through :class:`~pvcloth.physics.simulation.Simulation` with
``stability="ignore"``, so steps above the limit really run and show as
unstable.

The implicit methods that approximate a converged one (``implicit_euler``:
one linearised Newton step, and ``fast_mass_spring``: a few local/global
iterations, no dashpots, approximate ``backward_euler``; ``fast_bdf2``
approximates ``bdf2`` the same way) have their error split in two with the
converged run at the same step: the **time discretisation** error (the
converged method's own distance from the reference: only a smaller step
lowers it) and the **solver** error (the method's distance from it at that
step: what stopping early, or leaving terms out, costs; more iterations
lower it).

The methods that measure their own error (``rk23``, ``implicit_euler``,
``fast_mass_spring``, ``fast_bdf2``) also run with ``solver.tolerance`` at a few
tolerances, their steps chosen by the controller
(:mod:`pvcloth.physics.adaptive`): these join the plot as dashed lines,
their step the mean one (simulated time over steps), so a glance shows what
letting the controller choose costs against the best fixed step.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from pvcloth.errors import DivergenceError
from pvcloth.io.files import atomic_write
from pvcloth.physics.integrators import INTEGRATORS
from pvcloth.physics.reference import (
    REFERENCE_INTEGRATOR,
    reference_run,
    reference_step,
    rms_distance,
)
from pvcloth.physics.simulation import Simulation
from pvcloth.studies.runs import dividing_step, timed_run


@dataclass
class Run:
    """One integrator at one step: its error, cost and stability."""

    integrator: str
    dt: float
    stable: bool
    rms_error: float  # m; nan if unstable
    energy_drift: float  # relative; nan if unstable
    wall_per_sim_second: float  # s of wall time per s of simulated time
    steps: int
    #: For methods that approximate a converged one (``converges_to``): the
    #: converged run's RMS distance from the reference at this step (m) ...
    discretisation_error: float = math.nan
    #: ... and this run's RMS distance from that converged run (m).
    solver_error: float = math.nan
    #: The tolerance (m) an adaptive run's steps were chosen for (``dt`` is
    #: then its mean step); nan for a fixed step.
    tolerance: float = math.nan

    @property
    def adaptive(self) -> bool:
        return not math.isnan(self.tolerance)


#: Tolerances (m) adaptive runs take by default, by the method's order: a
#: first-order method's step shrinks in proportion to the tolerance (1e-3 m
#: costs implicit Euler minutes per simulated second at 32x32), a
#: second-order one's as its square root.
DEFAULT_TOLERANCES = {1: (1e-1, 1e-2), 2: (1e-2, 1e-3, 1e-4, 1e-5)}


def default_steps(scene, count: int = 8) -> list[float]:
    """Steps from 1/16 of symplectic Euler's limit up to a 1/30 s frame."""
    limit = Simulation(scene, integrator="symplectic_euler", stability="ignore").stable_dt()
    return [float(dt) for dt in np.geomspace(limit / 16, 1 / 30, count)]


def plan(scene, integrators=None, steps=None, duration=0.25, tolerances=None):
    """The runs :func:`measure` makes: ``(names, steps, jobs)``, each job
    ``(integrator, step or None, tolerance or None)``, the converged methods
    the others approximate first."""
    integrators = sorted(INTEGRATORS) if integrators is None else list(integrators)
    steps = default_steps(scene) if steps is None else sorted(steps)
    # Every run ends exactly at `duration` (see dividing_step).
    steps = sorted({dividing_step(duration, dt) for dt in steps})
    converged = converged_references(integrators)
    names = converged + [n for n in integrators if n not in converged]
    jobs = [(name, dt, None) for name in names for dt in steps]
    for name in integrators:
        method = INTEGRATORS[name]
        if method.embedded and method.interactive:
            chosen = DEFAULT_TOLERANCES.get(method.order, ()) if tolerances is None else tolerances
            jobs += [(name, None, tolerance) for tolerance in chosen]
    return names, steps, jobs


def converged_references(integrators) -> list[str]:
    """The converged methods (``backward_euler``, ``bdf2``) that ``integrators``
    approximate or name, each once, sorted: they run first so that the
    approximate ones can be split against them."""
    wanted = {INTEGRATORS[n].converges_to for n in integrators} - {None}
    wanted |= {n for n in integrators if n in {m.converges_to for m in INTEGRATORS.values()}}
    return sorted(wanted)


def estimate_seconds(scene, integrators=None, steps=None, duration=0.25, tolerances=None) -> float:
    """Roughly how long :func:`measure` takes (wall seconds): each method's
    cost per step, from a few steps of it here, times the steps of its fixed
    runs and of the reference; an adaptive run counted as its method at the
    middle step. For saying it before the minutes start."""
    names, steps, jobs = plan(scene, integrators, steps, duration, tolerances)
    middle = steps[len(steps) // 2]
    cost = {}
    for name in {job[0] for job in jobs} | {REFERENCE_INTEGRATOR}:
        sim = Simulation(scene, integrator=name, dt=middle, stability="ignore")
        start, taken = time.perf_counter(), 0
        try:
            sim.step()  # compiled, factorised
            start = time.perf_counter()
            while taken < 2:
                sim.step()
                taken += 1
        except DivergenceError:  # too long a step for it: costs what it took
            pass
        cost[name] = (time.perf_counter() - start) / max(taken, 1)
    total = duration / reference_step(scene, min(steps), duration) * cost[REFERENCE_INTEGRATOR]
    for name, dt, _ in jobs:
        total += duration / (dt or middle) * cost[name]
    return total


def measure(
    scene, *, integrators=None, steps=None, duration=0.25, tolerances=None, progress=True
) -> list[Run]:
    """Run every integrator at every step, and those that measure their
    error at every tolerance, and compare with the reference.

    Parameters
    ----------
    scene : Scene
    integrators : list of str, optional
        Default: all registered integrators.
    steps : list of float, optional
        Time steps in seconds; default :func:`default_steps`.
    duration : float
        Simulated seconds of each run.
    tolerances : list of float, optional
        Tolerances (m) of the adaptive runs, for every method among
        ``integrators`` that measures its error (and is interactive:
        ``backward_euler`` is left out); default :data:`DEFAULT_TOLERANCES`
        by order; ``[]`` for none.
    progress : bool
        Show a progress bar.

    Returns
    -------
    list of Run
    """
    integrators = sorted(INTEGRATORS) if integrators is None else list(integrators)
    _, steps, jobs = plan(scene, integrators, steps, duration, tolerances)
    truth = reference_run(scene, duration, reference_step(scene, min(steps), duration))
    x_ref, e_ref = truth.positions, truth.energy()["total"]
    scale = max(abs(e_ref), truth.model.kinetic_energy(truth.velocities), 1e-12)
    runs = []
    # The converged runs come first, so that the methods approximating
    # them can be split against them.
    references = set(converged_references(integrators))
    converged: dict[tuple[str, float], np.ndarray] = {}  # (name, step) -> its positions
    for name, dt, tolerance in tqdm(jobs, desc="trade-off runs", unit="run", disable=not progress):
        run = timed_run(scene, duration, integrator=name, dt=dt, tolerance=tolerance)
        if tolerance is not None:
            dt = duration / max(run.sim.steps, 1)  # the mean step
        split = (math.nan, math.nan)
        if run.stable:
            error = rms_distance(run.sim.positions, x_ref)
            drift = (run.sim.energy()["total"] - e_ref) / scale
            target = (INTEGRATORS[name].converges_to, dt)
            if name in references and tolerance is None:
                converged[(name, dt)] = run.sim.positions
            elif tolerance is None and target in converged:
                split = (
                    rms_distance(converged[target], x_ref),
                    rms_distance(run.sim.positions, converged[target]),
                )
        else:
            error = drift = math.nan
        if name in integrators:
            runs.append(
                Run(
                    name,
                    dt,
                    run.stable,
                    error,
                    drift,
                    run.wall_per_sim_second,
                    run.sim.steps,
                    *split,
                    math.nan if tolerance is None else tolerance,
                )
            )
    return runs


def pareto_front(runs: list[Run]) -> list[Run]:
    """Stable runs that no other stable run beats in both cost and error."""
    stable = sorted(
        (r for r in runs if r.stable), key=lambda r: (r.wall_per_sim_second, r.rms_error)
    )
    front, best = [], math.inf
    for run in stable:
        if run.rms_error < best:
            front.append(run)
            best = run.rms_error
    return front


def write_csv(runs: list[Run], path: Path) -> None:
    """One row per run, written whole (:func:`~pvcloth.io.files.atomic_write`):
    an interrupted study leaves the previous table."""

    def write(temporary: str) -> None:
        with open(temporary, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(asdict(runs[0])))
            writer.writeheader()
            for run in runs:
                writer.writerow(asdict(run))

    atomic_write(path, write)


#: One colour and one marker per integrator, in the order of their names:
#: matplotlib's ten colours without its grey (C7), which the Pareto front and
#: the guide lines use, so no integrator reads as one of them, and navy.
PLOT_COLORS = ("C0", "C1", "C2", "C3", "C4", "C5", "C6", "C8", "C9", "navy")
PLOT_MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*", "h", "p")


def step_label(dt: float) -> str:
    """A step as a student reads it: ``1/60`` for a fraction of a second with a
    whole denominator, else seconds in short form.

    Examples
    --------
    >>> step_label(1 / 60), step_label(3e-4), step_label(0.01)
    ('1/60 s', '3.0e-04 s', '1/100 s')
    """
    denominator = 1.0 / dt
    if abs(denominator - round(denominator)) < 1e-6 * denominator and denominator <= 10000:
        return f"1/{round(denominator)} s"
    return f"{dt:.1e} s"


def plot(runs: list[Run], path: Path, title: str) -> None:
    """Save :func:`draw`'s figure to ``path`` (PNG, SVG, PDF: by its suffix),
    whole or not at all (:func:`~pvcloth.io.files.atomic_write`)."""
    atomic_write(path, draw(runs, title).savefig)


def draw(runs: list[Run], title: str):
    """The trade-off figure (a ``matplotlib.figure.Figure``). Error against
    cost: each integrator in its own colour and marker, its
    fixed steps joined and the largest and smallest labelled, adaptive runs
    dashed with open markers, unstable runs as crosses along the top, and the
    Pareto front as a thick grey band with its runs ringed."""
    # A Figure of its own, drawn by Agg when saved: no pyplot, so the
    # caller's matplotlib backend (a notebook's) is left as it was.
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.8, 4.8), dpi=110)
    ax = fig.subplots()
    stable = [r for r in runs if r.stable]
    ceiling = 3 * max((r.rms_error for r in stable), default=1.0)
    front = pareto_front(runs)
    ax.step(
        [r.wall_per_sim_second for r in front],
        [r.rms_error for r in front],
        where="post",
        color="0.55",
        lw=7,
        alpha=0.35,
        solid_capstyle="round",
        label="Pareto front (best error for the cost)",
        zorder=1,
    )
    ax.plot(
        [r.wall_per_sim_second for r in front],
        [r.rms_error for r in front],
        "o",
        markersize=14,
        markerfacecolor="none",
        markeredgecolor="0.35",
        markeredgewidth=1.2,
        zorder=2,
    )
    for n, name in enumerate(sorted({r.integrator for r in runs})):
        color = PLOT_COLORS[n % len(PLOT_COLORS)]
        marker = PLOT_MARKERS[n % len(PLOT_MARKERS)]
        ok = sorted(
            (r for r in stable if r.integrator == name and not r.adaptive), key=lambda r: r.dt
        )
        bad = [r for r in runs if r.integrator == name and not r.stable]
        ax.plot(
            [r.wall_per_sim_second for r in ok],
            [r.rms_error for r in ok],
            marker=marker,
            ls="-",
            color=color,
            label=name,
            alpha=0.9,
            zorder=3,
        )
        for run in {id(r): r for r in (ok[:1] + ok[-1:])}.values():  # the largest and smallest step
            ax.annotate(
                step_label(run.dt),
                (run.wall_per_sim_second, run.rms_error),
                xytext=(5, 4),
                textcoords="offset points",
                fontsize=7,
                color=color,
            )
        chosen = sorted(
            (r for r in stable if r.integrator == name and r.adaptive), key=lambda r: r.tolerance
        )
        if chosen:
            ax.plot(
                [r.wall_per_sim_second for r in chosen],
                [r.rms_error for r in chosen],
                marker=marker,
                ls="--",
                color=color,
                markerfacecolor="white",
                label=f"{name}, adaptive",
                alpha=0.9,
                zorder=3,
            )
        if bad:
            ax.plot(
                [r.wall_per_sim_second for r in bad],
                [ceiling] * len(bad),
                "x",
                color=color,
                markersize=9,
                zorder=3,
            )
    ax.axhline(ceiling, color="grey", lw=0.5, ls=":")
    ax.text(
        min(r.wall_per_sim_second for r in runs),
        ceiling,
        " x = unstable (diverged); labels: the step",
        va="bottom",
        fontsize=8,
        color="grey",
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall seconds per simulated second (lower is faster)")
    ax.set_ylabel("RMS point error vs reference (m)")
    ax.set_title(title, fontsize=10)
    # Beside the axes: inside, it covered the most accurate runs.
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(True, which="both", alpha=0.2)
    fig.tight_layout()
    return fig


def table(runs: list[Run]) -> str:
    """Plain-text table of the runs, Pareto-optimal ones starred."""
    front = {id(r) for r in pareto_front(runs)}
    split = any(not math.isnan(r.solver_error) for r in runs)
    adaptive = any(r.adaptive for r in runs)
    lines = [
        f"{'integrator':<17}{'dt (s)':>10}"
        + (f"{'tol (m)':>9}" if adaptive else "")
        + f"{'stable':>8}{'RMS error (m)':>15}{'energy drift':>14}{'wall/sim s':>12}"
        + (f"{'of which: time (m)':>20}{'solver (m)':>12}" if split else "")
    ]
    for r in runs:
        star = " *" if id(r) in front else ""
        error = f"{r.rms_error:.3e}" if r.stable else "-"
        drift = f"{r.energy_drift:+.2e}" if r.stable else "-"
        parts = ""
        if split:
            parts = "".join(
                f"{'-' if math.isnan(value) else f'{value:.3e}':>{width}}"
                for value, width in ((r.discretisation_error, 20), (r.solver_error, 12))
            )
        tolerance = (f"{r.tolerance:>9.0e}" if r.adaptive else f"{'-':>9}") if adaptive else ""
        lines.append(
            f"{r.integrator:<17}{r.dt:>10.3g}{tolerance}{'yes' if r.stable else 'NO':>8}"
            f"{error:>15}{drift:>14}{r.wall_per_sim_second:>12.3g}{parts}{star}"
        )
    lines.append("* on the Pareto front (no run is both faster and more accurate)")
    if adaptive:
        lines.append("tol: an adaptive run's tolerance; its dt is the mean step it took")
    if split:
        lines.append(
            "time: the converged method's error at that step (backward_euler's, or bdf2's "
            "for fast_bdf2); solver: the run's distance from it (stopping early, terms left out)"
        )
    return "\n".join(lines)
