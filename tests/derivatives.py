"""Finite-difference checks of a penalty's force and Hessian, shared by the
tests of the obstacles' and the layers' penalties in Newton's solve
(``tests/test_contact_in_step.py``, ``tests/test_layers_in_solve.py``).

A penalty here has ``change(t, trial)`` (its energy's change, J),
``add_force(t, force)`` (adds its force, N, into an ``(N, 3)`` array) and
``hessian(t)`` (a ``(3N, 3N)`` sparse matrix, N/m)."""

from __future__ import annotations

import numpy as np
import pytest

#: The step of the central differences (m): the penalties' depths are
#: millimetres, their energies' changes far above rounding at this step.
STEP = 1e-9


def assert_force_is_minus_the_energy_slope(penalty, x, rng, tries: int = 5) -> None:
    """The force at ``x`` (m, ``(N, 3)``) is minus the slope of the energy
    along random directions, by central differences."""
    force = np.zeros_like(x)
    penalty.add_force(x, force)
    for _ in range(tries):
        move = rng.normal(size=x.shape)
        ahead, behind = penalty.change(x, x + STEP * move), penalty.change(x, x - STEP * move)
        assert (ahead - behind) / (2 * STEP) == pytest.approx(-np.vdot(force, move), rel=1e-5)


def assert_hessian_is_minus_the_force_derivative(
    penalty, x, rng, rows=slice(None), rtol: float = 1e-5, atol: float = 1e-9, tries: int = 5
) -> np.ndarray:
    """The Hessian at ``x`` times random small moves is minus the force's
    change, by central differences, on the coordinates ``rows`` (all by
    default). Returns the Hessian, dense."""
    hessian = penalty.hessian(x).toarray()
    for _ in range(tries):
        move = STEP * rng.normal(size=x.shape)
        ahead, behind = np.zeros_like(x), np.zeros_like(x)
        penalty.add_force(x + move, ahead)
        penalty.add_force(x - move, behind)
        np.testing.assert_allclose(
            (hessian @ move.ravel())[rows], -(ahead - behind).ravel()[rows] / 2, rtol=rtol,
            atol=atol,
        )  # fmt: skip
    return hessian
