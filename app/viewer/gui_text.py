"""Text for the panel: ImGui's built-in font covers Latin-1 only, and the core's messages use a
few typographic marks."""

from __future__ import annotations

_TYPOGRAPHY = str.maketrans({"\u2013": "-", "\u2014": "-", "\u2212": "-", "\u2018": "'",
                             "\u2019": "'", "\u201c": '"', "\u201d": '"', "\u2026": "...",
                             "\u00b7": ".", "\u203a": ">"})


def displayable(text: str) -> str:
    """``text`` in the characters the GUI font has (others become '?')."""
    return text.translate(_TYPOGRAPHY).encode("latin-1", "replace").decode("latin-1")
