"""A teacher's picture beside ours: ``python -m app view SCENE --reference PNG``.

Takes the reference PNG (read once, at start) and each new frame; ``h`` cycles what the
picture area shows: our picture, the reference, and the difference heat map of
:func:`core.inspect.compare.heat_map`, with the numbers ``python -m app compare`` prints
(:meth:`core.inspect.compare.Comparison.verdict`). A reference of another size than the frame
says so and shows nothing in its place. No GL here: the window uploads what
:attr:`ReferenceView.shown` holds.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

log = logging.getLogger("fvd")

MODES = ("picture", "reference", "difference")
MAX_PIXELS = 64 << 20            # a reference larger than any window's picture is refused


def load_reference(path: str | Path) -> np.ndarray:
    """The PNG at ``path`` as ``(H, W, 3)`` uint8; ValueError with the reason otherwise."""
    import warnings
    from PIL import Image
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"--reference {path}: no such file" if not path.exists()
                         else f"--reference {path}: not a regular file")
    try:
        with warnings.catch_warnings():      # its size is judged below, in one line
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = Image.open(path)
        with image:
            if image.format != "PNG":
                raise ValueError(f"--reference {path}: a {image.format} image, not a PNG")
            if image.width * image.height > MAX_PIXELS:
                raise ValueError(f"--reference {path}: {image.width} x {image.height} pixels "
                                 f"is larger than any picture the window shows")
            return np.asarray(image.convert("RGB"))
    except (OSError, Image.DecompressionBombError) as error:
        raise ValueError(f"--reference {path}: cannot read it as a PNG ({error})") from None


class ReferenceView:
    """What ``h`` shows, and the comparison's verdict."""

    def __init__(self, image: np.ndarray, name: str):
        self.image, self.name = image, name
        self.mode = "picture"
        self.shown: np.ndarray | None = None       # (H, W, 4) in the picture's place, or None
        self.verdict = ""

    def cycle(self, frame, how: str) -> str:
        """The next of picture, reference, difference; returns the mode shown."""
        self.mode = MODES[(MODES.index(self.mode) + 1) % len(MODES)]
        self.refresh(frame)
        log.info("action: %s -> showing the %s%s", how, self.mode,
                 f" ({self.verdict})" if self.verdict else "")
        return self.mode

    def refresh(self, frame) -> None:
        """Rebuild what is shown for ``frame`` (a new frame, or a new mode)."""
        from core.inspect.compare import compare, heat_map
        self.shown = None
        if frame is None:
            return
        ours = frame.color
        if ours.shape != self.image.shape:
            h, w = self.image.shape[:2]
            self.verdict = (f"the reference {self.name} is {w} x {h}, the picture "
                            f"{ours.shape[1]} x {ours.shape[0]}: open the window at --size "
                            f"{w}x{h} to compare")
            self.mode = "picture"
            return
        result = compare(ours, self.image)
        self.verdict = f"against {self.name}: {result.verdict()}"
        if self.mode == "picture":
            return
        picture = self.image if self.mode == "reference" else heat_map(result, self.image)
        self.shown = np.zeros(ours.shape[:2] + (4,), np.uint8)
        self.shown[..., :3] = picture
