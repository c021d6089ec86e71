"""Progress bars for long work, with one look everywhere: tqdm's, which
draws in a terminal and as a widget in a notebook (``tqdm.auto``)."""

from __future__ import annotations

from collections.abc import Iterable

from tqdm.auto import tqdm


def frame_bar(frames: Iterable[int], total: int, what: str, *, enabled: bool = True) -> tqdm:
    """A bar over a frame loop (``sim.frames(...)``): ``what`` on the left,
    frames per second and the time left on the right; nothing when not
    ``enabled``."""
    return tqdm(frames, total=total, desc=what, unit="frame", disable=not enabled)
