"""The scan-line renderer's stages in the plan (:func:`core.plan.plan` calls :func:`add_stages`
through the renderer's registry entry).

Watkins' algorithm decides visibility span by span: the z-buffer's scan conversion is replaced
by the scan-line visible-surface stage, and the depth buffer is written but never tested.
Imports nothing heavy: ``python -m app plan`` loads this module, not the renderer.
"""

from __future__ import annotations

STAGE = "scan-line visible surface"


def add_stages(stages: list, triangle_stage, scene=None) -> None:
    """Watkins' algorithm decides visibility span by span: no depth test per pixel."""
    for i, s in enumerate(stages):
        if s.name == "depth buffer":
            stages[i] = triangle_stage(s.name, s.runs, "not read to decide visibility: each "
                                       "pixel gets its visible polygon's depth, for what is "
                                       "drawn after (transparency, depth cueing)")
        if s.name == "z-buffer scan conversion":
            stages[i] = triangle_stage(
                STAGE, s.runs,
                "Watkins (FvDFH 15.6): edge table by first scan line, polygon table with "
                "in/out flags, active edge table sorted in x; one polygon in a span needs no "
                "depth, several are compared at the span's ends, and penetrating ones cut the "
                "span where their depths cross; the z-buffer's fill rule")
