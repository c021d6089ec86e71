"""Time integrators, one file each, found by name through :data:`INTEGRATORS`.

To add one: write a subclass of :class:`Integrator` in its own module,
decorate it with :func:`register` and import the module here.
"""

from pvcloth.errors import InputError
from pvcloth.physics.integrators import (  # noqa: F401  (importing registers them)
    backward_euler,
    bdf2,
    explicit_euler,
    fast_bdf2,
    fast_mass_spring,
    implicit_euler,
    rk4,
    rk23,
    symplectic_euler,
    verlet,
)
from pvcloth.physics.integrators.base import INTEGRATORS, Integrator, register
from pvcloth.scene.validation import choice

__all__ = ["INTEGRATORS", "Integrator", "get_integrator", "register"]


def get_integrator(name: str, iterations: int | None = None) -> Integrator:
    """A new integrator instance by registry name, e.g. ``"symplectic_euler"``;
    ``iterations`` per step for those that iterate (``None``: their default;
    the others do not use it). Fewer than the integrator's
    ``min_iterations`` are refused, with its reason.

    >>> get_integrator("fast_bdf2", iterations=20).iterations
    20
    """
    cls = INTEGRATORS[choice("integrator", name, sorted(INTEGRATORS))]
    if not cls.iterative or iterations is None:
        return cls()
    if iterations < cls.min_iterations:
        raise InputError(
            "solver.iterations",
            f"{cls.name} needs at least {cls.min_iterations} iterations a step, got "
            f"{iterations}: {cls.too_few_iterations}",
        )
    return cls(iterations=iterations)
