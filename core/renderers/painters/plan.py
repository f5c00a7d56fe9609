"""The painter's renderers' stages in the plan (:func:`core.plan.plan` calls
:func:`bsp_stages` or :func:`depth_sort_stages` through the renderer's registry entry).

They find an order instead of testing depth per pixel: the ordering stage goes in its place in
the pipeline, and the depth buffer holds each triangle's paint rank. Imports nothing heavy:
``python -m app plan`` loads this module, not the renderers.
"""

from __future__ import annotations

from core.plan import Stage


def bsp_stages(stages: list, triangle_stage, scene=None) -> None:
    """The BSP tree: its order is known before clipping."""
    _painter_stages(stages, triangle_stage, "BSP tree", before="clip triangles",
                    why="built once per scene in world space (spanning triangles split), "
                        "walked back to front from the eye")


def depth_sort_stages(stages: list, triangle_stage, scene=None) -> None:
    """Newell's depth sort: it orders the projected triangles."""
    _painter_stages(stages, triangle_stage, "depth sort", after="project",
                    why="Newell, Newell and Sancha: sorted by farthest z, overlap tests in "
                        "order, moves and splits until no polygon hides one painted before it")


def _painter_stages(stages: list, triangle_stage, name: str, why: str, before: str = "",
                    after: str = "") -> None:
    """Put the painter's ordering stage in place and say how it paints."""
    at = next(i for i, s in enumerate(stages) if s.name == (before or after))
    at += 1 if after else 0
    stages.insert(at, triangle_stage(name, True, why))
    for i, s in enumerate(stages):
        if s.name == "depth buffer" and s.runs:
            stages[i] = Stage(s.name, True, "the rasterizer's depth holds each triangle's paint "
                                            "rank: the later painted covers the earlier")
