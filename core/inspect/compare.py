"""A picture held against the reference, pixel by pixel (for grading: is ours the
expected picture, and where not).

:func:`compare` measures, per pixel, the largest channel difference (in levels of 1/255)
between a picture and the reference of the same size, and counts the pixels beyond the
tolerance, beyond 1/255 and beyond 8/255; :func:`heat_map` shows where they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_HEAT = np.array([[40, 0, 90], [200, 0, 120], [255, 120, 0], [255, 255, 80]], np.float64)


@dataclass
class Comparison:
    diff: np.ndarray          # (H, W) int: the largest channel difference, 0..255
    tolerance: float          # on 0..1
    beyond_tolerance: int
    beyond_1: int             # pixels more than 1/255 apart
    beyond_8: int             # pixels more than 8/255 apart
    worst: tuple[int, int]    # (x, y) of the largest difference (the first, row by row)
    worst_levels: int

    @property
    def same(self) -> bool:
        return self.beyond_tolerance == 0

    def verdict(self) -> str:
        h, w = self.diff.shape
        total = h * w
        head = ("same" if self.same else "DIFFERENT") + f" within {self.tolerance * 255:g}/255"
        text = (f"{head}: {self.beyond_tolerance} of {total} pixels beyond the tolerance, "
                f"{self.beyond_1} beyond 1/255 ({100 * self.beyond_1 / total:.2f} %), "
                f"{self.beyond_8} beyond 8/255")
        if self.worst_levels:
            x, y = self.worst
            text += f"; worst pixel ({x}, {y}) by {self.worst_levels}/255"
        return text


def compare(picture: np.ndarray, reference: np.ndarray, tolerance: float = 1 / 255) -> Comparison:
    """``picture`` and ``reference`` ``(H, W, 3)`` uint8 of the same shape."""
    if picture.shape != reference.shape:
        raise ValueError(f"the picture is {picture.shape[1]} x {picture.shape[0]}, the "
                         f"reference {reference.shape[1]} x {reference.shape[0]}")
    diff = np.abs(picture.astype(np.int16) - reference.astype(np.int16)).max(axis=2)
    levels = tolerance * 255
    worst = int(np.argmax(diff))
    return Comparison(diff=diff, tolerance=tolerance,
                      beyond_tolerance=int((diff > levels + 1e-9).sum()),
                      beyond_1=int((diff > 1).sum()), beyond_8=int((diff > 8).sum()),
                      worst=(worst % diff.shape[1], worst // diff.shape[1]),
                      worst_levels=int(diff.flat[worst]))


def heat_map(comparison: Comparison, reference: np.ndarray) -> np.ndarray:
    """``(H, W, 3)`` uint8: the reference, dimmed to a quarter, where the pixels agree within
    the tolerance; elsewhere a heat colour from purple (just beyond) to yellow (≥ 64/255)."""
    diff = comparison.diff
    out = (reference.astype(np.uint16) // 4).astype(np.uint8)
    beyond = diff > comparison.tolerance * 255 + 1e-9
    if beyond.any():
        t = np.clip(np.log2(np.maximum(diff[beyond], 1)) / 6, 0, 1)     # 1 → 0, 64 → 1
        stops = np.linspace(0, 1, len(_HEAT))
        out[beyond] = np.stack([np.interp(t, stops, _HEAT[:, c]) for c in range(3)],
                               axis=1).astype(np.uint8)
    return out
