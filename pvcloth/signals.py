"""Ctrl-C and SIGTERM that always stop a run, even inside VTK.

A signal handler's exception raised while VTK runs a Python callback (as it
does while rendering a frame) is printed and swallowed by VTK, so the run
went on to the end as if nothing had happened. The handlers here record the
signal; around calls into VTK (:func:`deferred`) they raise it only when the
call returns, and the frame loops call :func:`check` between frames.

A signal that arrives while a module is being imported is held until that
import ends: raised inside a compiled extension's set-up (cholespy's
nanobind enums, VTK's modules), it turned into a C++ exception that
aborted the process (SIGABRT, a C++ traceback) instead of a short message.
"""

from __future__ import annotations

import builtins
import contextlib
import signal
import sys
import threading


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every writer keeps what is valid."""


_pending: type[KeyboardInterrupt] | None = None
_deferring = 0


def _handler(signum, frame):
    global _pending
    _pending = Terminated if signum == signal.SIGTERM else KeyboardInterrupt
    if not _deferring:
        raise _pending()


@contextlib.contextmanager
def deferred(*, then_raise: bool = True):
    """Within the block a signal is only recorded; it is raised when the
    block ends (unless ``then_raise`` is false: for clean-up while a run is
    already stopping). For calls into VTK, which would swallow it and log an
    error, and for steps that must finish once begun (closing a file)."""
    global _deferring
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
    if then_raise and not _deferring:
        check()


def check() -> None:
    """Raise the Ctrl-C or SIGTERM received since :func:`handled` began, if
    one was swallowed on its way."""
    global _pending
    if _pending is not None:
        pending, _pending = _pending, None
        raise pending()


@contextlib.contextmanager
def handled():
    """Within the block, SIGINT raises KeyboardInterrupt and SIGTERM
    :class:`Terminated`, and both are remembered for :func:`check`."""
    global _pending
    _pending = None
    previous = {s: signal.signal(s, _handler) for s in (signal.SIGINT, signal.SIGTERM)}
    hook = sys.unraisablehook

    def quiet(unraisable):
        # A signal that lands in a callback Python cannot raise from (an
        # import lock's weakref callback) is swallowed with a printed
        # traceback; it stays recorded in _pending and check() raises it.
        if not isinstance(unraisable.exc_value, KeyboardInterrupt):
            hook(unraisable)

    sys.unraisablehook = quiet
    importer = builtins.__import__
    builtins.__import__ = _held_during(importer)
    try:
        yield
    finally:
        builtins.__import__ = importer
        sys.unraisablehook = hook
        for s, old in previous.items():
            signal.signal(s, old)
        _pending = None


def _held_during(importer):
    """``importer`` (``builtins.__import__``) with signals held until the
    outermost import of the main thread ends, where :func:`deferred` raises
    them. Signal handlers run only in the main thread, so other threads'
    imports (dask's) are left alone."""
    main = threading.main_thread()

    def held_import(*args, **kwargs):
        if threading.current_thread() is not main:
            return importer(*args, **kwargs)
        with deferred():
            return importer(*args, **kwargs)

    return held_import
