"""How long the user waits: from an input that changed the picture to the first picture on
screen that shows it, and the window's own time to draw that picture.

The window notes the time of the first input event of each batch it handles
(:meth:`InputLatency.input`), which request carried the change (:meth:`requested`, by the
worker's generation), and when a picture of a request is swapped onto the screen
(:meth:`shown`). A picture of request ``g`` shows every change asked for up to ``g``: the
latency is the time from the oldest of those inputs to the swap. A tracer's coarse picture
counts (it is what the user sees first); its refinements, showing nothing newer, do not.
``python -m app -v view`` logs each one ("on screen: ..."), and ``python -m app bench
--window`` reports their median and worst during a drag.
"""

from __future__ import annotations


class InputLatency:
    """Input times per request, waiting for their first picture."""

    def __init__(self):
        self._batch: float | None = None          # the first input since the last draw
        self._changed: float | None = None        # the first input not yet requested
        self._waiting: list[tuple[int, float]] = []   # (generation, input time), oldest first

    def input(self, at: float) -> None:
        """An input event at ``at`` (perf_counter seconds); only the first of a batch counts."""
        if self._batch is None:
            self._batch = at

    def drawn(self, dirty: bool) -> None:
        """A turn of the loop ended: its inputs asked for a new picture (``dirty``) or not."""
        if dirty and self._changed is None and self._batch is not None:
            self._changed = self._batch
        self._batch = None

    def requested(self, generation: int) -> bool:
        """The picture was asked for as request ``generation``: the pending inputs ride on it.
        Returns whether any did (an input now waits for this picture)."""
        if self._changed is None:
            self._changed = self._batch
        answers = self._changed is not None
        if answers:
            self._waiting.append((generation, self._changed))
        self._changed = None
        return answers

    def shown(self, generation: int, at: float) -> float | None:
        """A picture of request ``generation`` reached the screen at ``at``: seconds since the
        oldest input it answers, or None when it answers none (a refinement, a redraw)."""
        answered = [t for g, t in self._waiting if g <= generation]
        if not answered:
            return None
        self._waiting = [(g, t) for g, t in self._waiting if g > generation]
        return at - min(answered)
