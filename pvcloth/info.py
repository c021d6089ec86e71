"""Plain-text description of a simulation's model, for ``pvcloth info``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from pvcloth.physics.step_policy import STABLE_SHARE, step_origin

if TYPE_CHECKING:  # for annotations only
    from pvcloth.physics.simulation import Simulation


def describe(sim: Simulation) -> str:
    """A few lines that say what the model built and how it will be stepped.

    Parameters
    ----------
    sim : Simulation

    Returns
    -------
    str
    """
    model, scene = sim.model, sim.scene
    nx, ny = sim.resolution
    lines = [
        f"scene       {scene.name}",
        f"particles   {model.n_points} ({nx} x {ny}), cloth {scene.cloth.size[0]:g} x "
        f"{scene.cloth.size[1]:g} m, {scene.cloth.orientation}",
        f"mass        {model.mass.sum():.6g} kg total, {model.mass.min():.3g} to "
        f"{model.mass.max():.3g} kg per point",
    ]
    springs = model.springs
    lines.append(
        "springs     "
        + (", ".join(f"{s.family} {s.count}" for s in springs) if springs else "none")
        + f" ({sum(s.count for s in springs)} in all)"
    )
    lines.append("forces      " + ("; ".join(t.describe() for t in model.forces) or "none"))
    lines.append(
        "obstacles   "
        + ("; ".join(o.describe() for o in model.obstacles) or "none (no collision code runs)")
    )
    contact = sim.contact_step()  # infinite without self-collision
    layers = model.self_collision
    if layers is None:
        lines.append("contact     no self-collision (add a [self_collision] table to turn it on)")
    else:
        if math.isfinite(contact):
            held = (
                f"steps are split to at most {contact:.3g} s (one step's fall under gravity "
                f"within what the contact response may move a point)"
            )
        elif layers.in_solve and sim.integrator.holds_layers:
            held = f"{sim.integrator.name} holds the layers in its solve: no limit on the step"
        else:
            held = "no limit on the step without gravity"
        lines.append(
            f"contact     self-collision on: layers kept {1e3 * layers.thickness:.3g} mm apart, "
            f"friction {layers.friction:g}; {held}"
        )
    pinned = np.flatnonzero(sim.control.pinned)
    shown = ", ".join(f"({k % nx}, {k // nx})" for k in pinned[:6])
    more = f" and {pinned.size - 6} more" if pinned.size > 6 else ""
    lines.append(f"pins        {pinned.size} point(s): {shown or 'none'}{more}")
    lines.append(
        "backend     "
        + (
            "numba (compiled spring kernels)"
            if model.compiled
            else "numpy (set PVCLOTH_BACKEND=numba or install numba for compiled kernels)"
        )
    )
    stable = sim.stable_dt()
    origin = step_origin(
        sim.dt_source,
        stable=stable,
        contact=contact,
        requested=sim.requested_dt,
        controller=sim.controller,
    )
    lines.append(
        f"integrator  {sim.integrator.name} (order {sim.integrator.order}: "
        f"{sim.integrator.description}), dt = {sim.dt:.4g} s ({origin})"
    )
    if sim.choice is not None:
        lines.append(f"chosen by   solver.integrator = 'auto': {sim.choice.reason}")
    if sim.controller is not None and sim.integrator.converges_to is not None:
        lines.append(
            f"error       the tolerance bounds {sim.integrator.converges_to}'s time "
            f"discretisation, not what {sim.integrator.name} leaves out of it (a linearised "
            f"or early-stopped solve; pvcloth tradeoff measures that part)"
        )
    if stable == 0.0:
        lines.append("stable dt   none: the stiffest mode is undamped and grows at any step")
    elif math.isinf(stable):
        lines.append("stable dt   unlimited (stable at any step on the linearised cloth)")
    else:
        verdict = "ok" if sim.dt <= STABLE_SHARE * stable else "TOO LARGE: expect divergence"
        if sim.controller is not None:
            verdict = f"adaptive steps are held under {STABLE_SHARE:g} of it"
        share = sim.dt / stable
        lines.append(
            f"stable dt   about {stable:.4g} s at rest (dt is {share:.2f} of it: {verdict})"
        )
    return "\n".join(lines)
