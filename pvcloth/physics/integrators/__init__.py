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


def get_integrator(
    name: str, iterations: int | None = None, accelerator: str | None = None
) -> Integrator:
    """A new integrator instance by registry name, e.g. ``"symplectic_euler"``;
    ``iterations`` per step and their ``accelerator`` (one of
    :data:`~pvcloth.scene.parts.ACCELERATORS`) for those that iterate
    (``None``: their default; the others do not use them). Fewer than the
    integrator's ``fewest_iterations(accelerator)`` are refused, with its
    reason.

    >>> get_integrator("fast_bdf2", iterations=20).iterations
    20
    >>> get_integrator("fast_bdf2", accelerator="lbfgs").accelerator
    'lbfgs'
    """
    cls = INTEGRATORS[choice("integrator", name, sorted(INTEGRATORS))]
    if not cls.iterative:
        return cls()
    options = {} if accelerator is None else {"accelerator": accelerator}
    if iterations is None:
        return cls(**options)
    fewest = cls.fewest_iterations(accelerator)
    if iterations < fewest:
        raise InputError(
            "solver.iterations",
            f"{cls.name} needs at least {fewest} iterations a step"
            + (f" with the {accelerator} accelerator" if accelerator else "")
            + f", got {iterations}: {cls.too_few_iterations}",
        )
    return cls(iterations=iterations, **options)
