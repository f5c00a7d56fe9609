"""The progress line of a long command on stderr, and the line that says it was stopped.

Long work reports between its chunks (:func:`core.work.report`); :class:`ProgressLine` is the
command line's watcher of it (``render``, ``animate``):

- nothing until the command has run SHOW_AFTER seconds, so a short command prints no line;
- on a terminal, one line rewritten in place, at most every REDRAW seconds (cut to the
  terminal's width: a line that wrapped could not be rewritten);
- elsewhere (a file, a pipe, a CI log), a plain line every PLAIN_EVERY seconds;
- with ``-q``, nothing.

Works nested in one another share the line, outer first (a movie's frames, then the frame's
simulation): ``frame 3 of 90 (3 %); simulating the rigid bodies: step 120 of 240 (50 %); 12 s,
about 5 min left``. A report of an outer work ends the inner ones, and a work that reaches its
total leaves the line. The time left is the outermost work's, at its rate since it began.

Ctrl+C: the command prints :meth:`ProgressLine.stopped` (what was running, for how long, and
what it keeps) and exits with 130, the shell's status for a process ended by SIGINT.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from dataclasses import dataclass

from core.work import describe

SHOW_AFTER = 1.5          # seconds before the first line
REDRAW = 0.25             # seconds between two redraws on a terminal
PLAIN_EVERY = 10.0        # seconds between two plain lines (not a terminal)
INTERRUPTED = 130         # the exit status of a command stopped by Ctrl+C (128 + SIGINT)


@dataclass
class _Work:
    what: str
    unit: str
    done: float
    total: float
    first: float          # done when its rate began to be measured
    began: float          # ... and when

    def text(self) -> str:
        share = f" ({100 * self.done / self.total:.0f} %)" if self.total > 0 else ""
        return describe(self.what, self.done, self.total, self.unit) + share


def duration(seconds: float) -> str:
    """``45 s``, ``12 min``, ``2.5 h``."""
    if seconds < 100:
        return f"{seconds:.0f} s"
    if seconds < 6000:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class ProgressLine:
    """A :data:`core.work.Watcher` that draws the progress line; also called directly (from
    any thread) by a command for its own outer work."""

    def __init__(self, stream=None, quiet: bool = False, clock=time.monotonic):
        self.stream = stream or sys.stderr
        self.quiet, self.clock = quiet, clock
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = clock()
        self.works: list[_Work] = []
        self.drawn: float | None = None       # when the line was last drawn
        self.open = False                     # a line in place that the next one replaces
        self.lock = threading.Lock()

    def __call__(self, what: str, done: float, total: float, unit: str = "") -> None:
        with self.lock:
            self._note(what, done, total, unit)
            now = self.clock()
            every = REDRAW if self.tty else PLAIN_EVERY
            if self.quiet or now - self.start < SHOW_AFTER or not self.works \
                    or (self.drawn is not None and now - self.drawn < every):
                return
            self.drawn = now
            self._write(self.text(now))

    def _note(self, what, done, total, unit) -> None:
        now = self.clock()
        for i, work in enumerate(self.works):
            if work.what == what:
                del self.works[i + 1:]                  # its inner works are over
                if done < work.done:                    # begun again
                    work.first, work.began = done, now
                work.done, work.total, work.unit = done, total, unit
                break
        else:
            self.works.append(_Work(what, unit, done, total, done, now))
        if done >= total:
            self.works = [w for w in self.works if w.what != what]

    def text(self, now: float) -> str:
        """The works, outer first, the time since the command started and the time left."""
        parts = "; ".join(w.text() for w in self.works)
        line = f"{parts}; {duration(now - self.start)}"
        outer = self.works[0]
        rate = (outer.done - outer.first) / max(now - outer.began, 1e-9)
        if rate > 0 and outer.total > outer.done:
            line += f", about {duration((outer.total - outer.done) / rate)} left"
        return line

    def doing(self) -> str:
        """What runs now, without the times ('' when nothing reported)."""
        with self.lock:
            return "; ".join(describe(w.what, w.done, w.total, w.unit) for w in self.works)

    def say(self, line: str) -> None:
        """A line that stays (a note, the stop line), below no half-drawn progress line."""
        with self.lock:
            self._end_line()
            print(line, file=self.stream, flush=True)

    def finish(self) -> None:
        """Clear the line in place (the command's own last lines follow)."""
        with self.lock:
            self._end_line()
            self.works = []

    def stopped(self, kept: str = "") -> str:
        """``stopped by Ctrl+C after 12 s (simulating ...: step 1,200 of 9,600): KEPT``."""
        doing = self.doing()
        return (f"stopped by Ctrl+C after {duration(self.clock() - self.start)}"
                f"{f' ({doing})' if doing else ''}{f': {kept}' if kept else ''}")

    def _write(self, line: str) -> None:
        if self.tty:                  # cut to the width: a wrapped line is not rewritten
            width = shutil.get_terminal_size().columns - 1
            if len(line) > width:
                line = line[:max(width - 3, 0)] + "..."
            self.stream.write("\r\033[K" + line)
            self.open = True
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def _end_line(self) -> None:
        if self.open:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self.open = False
