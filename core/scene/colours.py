"""Colour models (FvDFH 13.3): the RGB a scene file's colour names, from RGB, CMY, HSV or HLS.

A colour in a scene file is a list ``[r, g, b]`` or one of the tables ``{ rgb = [...] }``,
``{ cmy = [c, m, y] }``, ``{ hsv = [h, s, v] }``, ``{ hls = [h, l, s] }``, with the hue in
degrees (0 to 360, red at 0) and the rest from 0 to 1. The conversions are the book's
algorithms (Figs. 13.34 and 13.37), written out here; the tests hold them against Python's
``colorsys``.
"""

from __future__ import annotations

import math

MODELS = ("rgb", "cmy", "hsv", "hls")


def cmy_to_rgb(c: float, m: float, y: float) -> tuple[float, float, float]:
    """[R G B] = [1 1 1] − [C M Y] (FvDFH eq. 13.11)."""
    return 1.0 - c, 1.0 - m, 1.0 - y


def hsv_to_rgb(h: float, s: float, v: float) -> tuple[float, float, float]:
    """The hexcone (FvDFH Fig. 13.34): h in degrees, s and v in [0, 1]."""
    if s == 0.0:
        return v, v, v                       # achromatic: the hue does not matter
    h = (h % 360.0) / 60.0                   # the sector 0..5 of the hexagon
    i = math.floor(h)
    f = h - i
    p, q, t = v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f))
    return ((v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q))[int(i) % 6]


def hls_to_rgb(h: float, l: float, s: float) -> tuple[float, float, float]:  # noqa: E741
    """The double hexcone (FvDFH Fig. 13.37): h in degrees, l and s in [0, 1]."""
    if s == 0.0:
        return l, l, l
    m2 = l * (1.0 + s) if l <= 0.5 else l + s - l * s
    m1 = 2.0 * l - m2
    return _value(m1, m2, h + 120.0), _value(m1, m2, h), _value(m1, m2, h - 120.0)


def _value(n1: float, n2: float, hue: float) -> float:
    hue %= 360.0
    if hue < 60.0:
        return n1 + (n2 - n1) * hue / 60.0
    if hue < 180.0:
        return n2
    if hue < 240.0:
        return n1 + (n2 - n1) * (240.0 - hue) / 60.0
    return n1


def to_rgb(model: str, values) -> tuple[float, float, float]:
    """``values`` of ``model`` as RGB; raises ValueError naming what is out of range."""
    if model not in MODELS:
        raise ValueError(f"the colour model must be one of {', '.join(MODELS)}, not {model!r}")
    a, b, c = (float(x) for x in values)
    if model in ("hsv", "hls"):
        if not 0.0 <= a <= 360.0:
            raise ValueError(f"the hue must be from 0 to 360 degrees, not {a!r}")
        names = ("saturation", "value") if model == "hsv" else ("lightness", "saturation")
        for name, x in zip(names, (b, c)):
            if not 0.0 <= x <= 1.0:
                raise ValueError(f"the {name} must be from 0 to 1, not {x!r}")
        rgb = hsv_to_rgb(a, b, c) if model == "hsv" else hls_to_rgb(a, b, c)
    else:
        for x in (a, b, c):
            if not 0.0 <= x <= 1.0:
                raise ValueError(f"each {model.upper()} component must be from 0 to 1, "
                                 f"not {x!r}")
        rgb = cmy_to_rgb(a, b, c) if model == "cmy" else (a, b, c)
    return tuple(min(max(x, 0.0), 1.0) for x in rgb)
