"""numba's ``njit`` and ``prange``, or stand-ins that run the same code as
plain Python where numba is missing (the NumPy path must work without it)."""

from __future__ import annotations

try:
    from numba import njit, prange
except ImportError:  # pragma: no cover - exercised only where numba is missing
    prange = range

    def njit(*args, **kwargs):
        if args and callable(args[0]):
            return args[0]
        return lambda function: function


__all__ = ["njit", "prange"]
