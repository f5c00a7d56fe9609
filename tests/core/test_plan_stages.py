"""The plan against the draw: the stages the plan says run are the stages the draw ran.

The plan (:func:`core.plan.plan`) and the z-buffer family's draws ask the same stage objects
(:mod:`core.stages`); each draw names the stages it ran in ``frame.stats["stages run"]``.
Every shipped scene is drawn small with every shading mode by every renderer that
scan-converts triangles (the z-buffer, Watkins' scan line, the painters).
"""

from __future__ import annotations

import pytest

from core.context import RenderContext
from core.paths import SCENES_DIR
from core.plan import plan
from core.registry import names_that, shading_names
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings
from core.stages import PIPELINE, Facts

SCENES = sorted(p.name for p in SCENES_DIR.iterdir()
                if p.suffix in (".toml", ".tri", ".obj"))
SIZE = (24, 18)


def _disagreements(scene, renderer: str) -> list[str]:
    """Each (shading, rasterizer) frame whose plan and draw disagree, with what differs."""
    found = []
    context = RenderContext()                   # one BSP tree for all the modes
    for shading in shading_names():
        for rasterizer in ("edge", "scanline") if renderer == "zbuffer" else ("edge",):
            settings = RenderSettings.for_scene(scene, size=SIZE, renderer=renderer,
                                                shading=shading, rasterizer=rasterizer,
                                                samples=1)
            frame = render(scene, scene.views[0], settings, context)
            planned = {s.name for s in frame.plan if s.runs}
            ran = set(frame.stats["stages run"])
            if planned != ran:
                found.append(f"{shading}, {rasterizer}: planned only {sorted(planned - ran)}, "
                             f"ran only {sorted(ran - planned)}")
    return found


@pytest.mark.parametrize("renderer", names_that("rasterizes"))
@pytest.mark.parametrize("name", SCENES)
def test_the_draw_runs_the_stages_the_plan_says(name, renderer):
    scene = load_scene(SCENES_DIR / name, size=SIZE)
    if not scene.views:
        pytest.skip(f"{name} has no valid view")
    assert _disagreements(scene, renderer) == []


def test_the_plan_is_the_stage_objects_answers():
    """The z-buffer's plan, in order, is what its stage objects decide (transparency after)."""
    scene = load_scene(SCENES_DIR / "torus.toml")
    facts = Facts(scene, "perspective", "phong")
    stages = plan(scene, "perspective", "phong")
    assert stages[:-1] == [s.planned(facts) for s in PIPELINE if s.listed(facts)]
    assert stages[-1].name == "transparency"


def test_a_painter_plans_no_order_for_a_wireframe():
    """The painters' ordering stage is a triangle stage: a wireframe paints nothing."""
    scene = load_scene(SCENES_DIR / "cube.toml")
    stages = {s.name: s for s in plan(scene, "perspective", "wireframe", renderer="bsp")}
    assert not stages["BSP tree"].runs
    assert stages["BSP tree"].reason == "wireframe draws edges only"
