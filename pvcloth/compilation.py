"""The first run's kernel compilation, said and timed.

numba compiles pvcloth's kernels the first time they run on a machine (a few
seconds; half a minute with self-collision) and loads them from its on-disk
cache afterwards. :func:`watch_compilation` listens to numba's compile
events: the first one prints a one-line notice (so a progress bar sitting at
zero is explained), and :class:`CompileClock` adds up the seconds spent
compiling, which speed figures (``pvcloth simulate``, the panels of
``pvcloth compare``) leave out. Loading from the cache sends no such event.
"""

from __future__ import annotations

import sys
import threading
import time

#: What the notice says, once per process.
NOTICE = "pvcloth: compiling the kernels (first run only: numba caches them on disk)..."


class CompileClock:
    """Seconds spent compiling since :func:`watch_compilation` was called:
    the outermost compile events only (a kernel compiles the ones it calls
    inside its own event)."""

    def __init__(self, announce: bool):
        self.seconds = 0.0
        self.announce = announce
        self.announced = False
        self._depth = threading.local()
        self._lock = threading.Lock()

    def started(self) -> None:
        depth = getattr(self._depth, "value", 0)
        self._depth.value = depth + 1
        if depth == 0:
            self._depth.since = time.perf_counter()
            with self._lock:
                if self.announce and not self.announced:
                    self.announced = True
                    from tqdm.auto import tqdm  # writes above a running bar

                    tqdm.write(NOTICE, file=sys.stderr)

    def ended(self) -> None:
        self._depth.value -= 1
        if self._depth.value == 0:
            with self._lock:
                self.seconds += time.perf_counter() - self._depth.since


_clock: CompileClock | None = None


def watch_compilation(announce: bool = True) -> CompileClock:
    """Listen to numba's compile events from now on (once per process;
    later calls return the same clock). Without numba, the clock stays at
    zero: nothing compiles."""
    global _clock
    if _clock is not None:
        return _clock
    _clock = CompileClock(announce)
    try:
        from numba.core import event
    except ImportError:
        return _clock

    class _Listener(event.Listener):
        def on_start(self, _event) -> None:
            _clock.started()

        def on_end(self, _event) -> None:
            _clock.ended()

    event.register("numba:compile", _Listener())
    return _clock


def compile_seconds() -> float:
    """Seconds compiled so far (0 when nobody watches)."""
    return 0.0 if _clock is None else _clock.seconds
