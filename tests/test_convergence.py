"""Refining the grid approximates the same cloth.

The test pins the whole top edge. Pinning single points would not converge
under any parameterisation: a point load on a membrane has a logarithmically
infinite displacement (2D elasticity), so the sag of a corner-pinned cloth
grows by a nearly constant amount each time the grid is refined.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla

from pvcloth import ClothSpec, PinSpec, Scene, SpringSpec, SpringsSpec, build_model


def in_plane_equilibrium(model, tolerance=1e-10):
    """Newton's method on the free in-plane (x, z) coordinates of a vertical
    cloth; gravity lies in its plane, so the equilibrium does too."""
    x = model.rest_positions.copy()
    dofs = (~model.pinned[:, None] & np.array([True, False, True])).ravel()
    zero = np.zeros_like(x)
    for _ in range(30):
        residual = model.compute_forces(x, zero).ravel()[dofs]
        if np.abs(residual).max() < tolerance:
            return x
        stiffness = -model.jacobians(x, zero)[0]
        x.ravel()[dofs] += spla.spsolve(stiffness[dofs][:, dofs].tocsc(), residual)
    raise AssertionError("Newton did not converge")


def sag(n: int) -> float:
    scene = Scene(
        cloth=ClothSpec(size=(1.0, 1.0), resolution=(n, n), mass=0.2),
        springs=SpringsSpec(SpringSpec(20.0), SpringSpec(5.0), SpringSpec(0.5)),
        pins=PinSpec(corners=(), edges=("top",)),
    )
    model = build_model(scene)
    x = in_plane_equilibrium(model)
    return model.mass @ (model.rest_positions[:, 2] - x[:, 2]) / model.mass.sum()


def test_hanging_sag_converges_as_resolution_doubles():
    s16, s32, s64 = sag(16), sag(32), sag(64)
    assert s64 > 0.02  # soft enough for a 2 % stretch: a real sag
    assert abs(s64 - s32) < abs(s32 - s16)
    assert abs(s64 - s32) < 0.005 * s64
