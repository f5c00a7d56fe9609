"""The media a material may be made of: indices of refraction, by number or by name (the notes).

The scene reader checks a material's ``ior`` with :func:`index_of_refraction`; the ray tracer
(``core/raytrace/optics.py``) bends rays by it.
"""

from __future__ import annotations

import math

AIR, WATER, GLASS = 1.0003, 1.33, 1.52
INDICES = {"air": AIR, "water": WATER, "glass": GLASS, "vacuum": 1.0}


def index_of_refraction(value, where: str = "ior") -> float:
    """A positive finite index, from a number or one of the names in :data:`INDICES`.

    Raises ValueError naming ``where`` otherwise (an index <= 0 or NaN has no physical meaning
    and would make Snell's law divide by zero or return NaN directions).
    """
    if isinstance(value, str):
        if value.lower() not in INDICES:
            raise ValueError(f"{where}: unknown medium {value!r}; use a number or one of "
                             f"{', '.join(INDICES)}")
        return INDICES[value.lower()]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where}: expected a number or a medium name, got {value!r}")
    try:
        value = float(value)
    except OverflowError:                  # an integer of hundreds of digits (the fuzzers')
        raise ValueError(f"{where}: the index of refraction must be a positive finite number, "
                         f"not an integer of {len(str(abs(value)))} digits") from None
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{where}: the index of refraction must be a positive finite number, "
                         f"not {value!r}")
    return value
