"""Which stages a scene needs: the renderer runs these and skips the rest.

``plan(scene, projection, shading)`` returns the stages in pipeline order, each with whether it
runs and why (or why not), by asking the stage objects of :mod:`core.stages`, which the
z-buffer's draw asks too before it runs a stage. ``python -m app plan`` prints it and the
window shows it; the renderer names the stages it ran in ``Frame.stats["stages run"]`` (and
records what it allocated and computed) so that tests can hold the two against each other
(``tests/core/test_plan_stages.py``).
"""

from __future__ import annotations

from core.registry import Renderer, get_renderer, get_shading, load
from core.scene.model import Scene
from core.stages import PIPELINE, TRANSPARENCY, Facts, Stage, triangle_stage_for  # noqa: F401


def plan(scene: Scene, projection: str, shading: str, keep_aspect: bool = False,
         rasterizer: str = "edge", texture_filter: str = "trilinear",
         renderer: str = "zbuffer", transparency: str | None = None) -> list[Stage]:
    """The stages for ``scene`` drawn with ``projection`` and ``shading``, in the order the
    renderer runs them (``core/render.py``, ``core/renderers/zbuffer/draw.py``); ``keep_aspect``,
    ``rasterizer`` and ``transparency`` as in :class:`core.settings.RenderSettings`
    (``transparency`` None: what the scene asks for, else what it needs)."""
    get_shading(shading)                        # ValueError naming the modes there are
    facts = Facts(scene, projection, shading, keep_aspect, rasterizer, texture_filter,
                  renderer, transparency)
    # Each stage object decides for itself: the z-buffer's draw asks the same ones.
    stages = [stage.planned(facts) for stage in PIPELINE if stage.listed(facts)]
    entry = _entry(renderer)
    if entry is not None and entry.plan_stages:      # the renderer's own stages, in place
        load(entry.plan_stages)(stages, triangle_stage_for(facts), scene)
    stages.append(TRANSPARENCY.planned(facts))
    return stages


def _entry(renderer: str) -> Renderer | None:
    """The registry's entry of ``renderer`` (None for a name not registered: the plan of
    the z-buffer's stages alone)."""
    try:
        return get_renderer(renderer)
    except ValueError:
        return None


def plan_as_dict(stages: list[Stage]) -> dict:
    """The JSON shape of ``python -m app plan``: the stages that run, and those left out with why."""
    return {
        "runs": [{"stage": s.name, "why": s.reason} for s in stages if s.runs],
        "left_out": [{"stage": s.name, "why": s.reason} for s in stages if not s.runs],
    }
