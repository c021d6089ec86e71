"""One thread pool at a time: BLAS is held to one thread while pvcloth steps.

Two pools share this machine's cores when a step runs on the compiled
kernels: numba's OpenMP threads (the spring loop) and OpenBLAS's (the dot
products of the conjugate gradients in ``implicit_euler``, SuperLU's dense
blocks in ``backward_euler``), which NumPy and SciPy each bundle. Each pool
keeps its threads spinning for a while after a call, so one pool's spinning
threads hold the cores the other's wait for. Inside :func:`one_blas_thread`
OpenBLAS runs on the calling thread alone; the cores belong to the kernels,
and in the window to the kernels and the drawing. Measured side by side in
``benchmarks/results/blas_threads.md``.

The limit is taken with threadpoolctl and the user's own setting is put
back on the way out, so code around a simulation keeps its BLAS threads.
OpenBLAS's thread count is one per process, but here a count set from a
second thread was ignored once the main thread had set one (OpenBLAS
0.3.30-0.3.31, seen in ``tests/test_blas_threads.py``): the window's
physics thread therefore takes its limit on the main thread, when it starts.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

_controller = None


def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries, made once (making
    it inspects every loaded library, about 1 ms; limiting through it after
    that costs about 20 us)."""
    global _controller
    if _controller is None:
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController().select(user_api="blas")
    return _controller


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with every loaded BLAS library on one thread.

    Examples
    --------
    >>> import scipy.linalg  # loads SciPy's OpenBLAS beside NumPy's
    >>> from threadpoolctl import threadpool_info
    >>> from pvcloth.physics.blas import one_blas_thread
    >>> with one_blas_thread():
    ...     {info["num_threads"] for info in threadpool_info() if info["user_api"] == "blas"}
    {1}
    """
    controller = _blas_controller()
    if not controller.lib_controllers:  # no BLAS loaded yet (a NumPy without one)
        yield
        return
    with controller.limit(limits=1):
        yield
