"""Whitespace-separated numbers with their line numbers, read without trusting any count.

Takes the text of a numeric file (``.tri``; the OFF pre-check) and returns every number as one
float64 array plus the means to name the line of any of them. ``#`` starts a comment that runs
to the end of the line. The numbers are converted a chunk at a time, so the memory used is
proportional to the data actually present, never to a count written in the file.
"""

from __future__ import annotations

import numpy as np

from core.scene.formats.errors import ReaderError, short

_CHUNK = 1 << 16          # tokens converted to float64 per numpy call


class Numbers:
    """All numbers of ``text``; ``values[k]`` is the k-th number, ``line(k)`` its line (1-based).

    ``tokens[k]`` keeps the text of the first ``keep`` numbers (a reader may need to see how a
    count was written). A token that is not a number raises :class:`ReaderError` with its line.
    """

    def __init__(self, text: str, file: str, keep: int = 0) -> None:
        self.file = file
        lines = text.split("\n")
        self.counts = np.zeros(len(lines), dtype=np.int64)      # numbers on each line
        self.tokens: list[str] = []
        parts, chunk, seen = [], [], 0
        for i, line in enumerate(lines):
            toks = line.split("#", 1)[0].split()
            if not toks:
                continue
            self.counts[i] = len(toks)
            if len(self.tokens) < keep:
                self.tokens.extend(toks[:keep - len(self.tokens)])
            chunk.extend(toks)
            if len(chunk) >= _CHUNK:
                parts.append(self._convert(chunk, seen))
                seen += len(chunk)
                chunk = []
        if chunk:
            parts.append(self._convert(chunk, seen))
        self.values = np.concatenate(parts) if parts else np.zeros(0)
        self._ends = np.cumsum(self.counts)                     # numbers up to each line

    def line(self, k: int) -> int:
        """The line that holds number ``k`` (or the last line with a number if k is past the end)."""
        if len(self.values) == 0:
            return 1
        k = min(k, len(self.values) - 1)
        return int(np.searchsorted(self._ends, k, side="right")) + 1

    def _convert(self, chunk: list[str], first: int) -> np.ndarray:
        try:
            return np.array(chunk, dtype=np.float64)
        except ValueError:
            pass
        for j, token in enumerate(chunk):                       # find the culprit (error path)
            try:
                float(token)
            except ValueError:
                self._ends = np.cumsum(self.counts)
                raise ReaderError(self.file, f"{short(token)} is not a number",
                                  self.line_of_token(first + j)) from None
        raise AssertionError("numpy refused a chunk that float() accepts")

    def line_of_token(self, k: int) -> int:
        """Like :meth:`line` but usable while the numbers are still being read."""
        return int(np.searchsorted(self._ends, k, side="right")) + 1
