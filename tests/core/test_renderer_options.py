"""A renderer's own options: registered with it, carried by RenderSettings, shown in the panel.

The ray tracer's, radiosity's and the painters' options are frozen dataclasses each renderer
registers (core.registry); these tests hold the routing, the validation messages, the panel's
controls (app.session.options) and the command line's flags against hand-written values, and
show that a new renderer's options reach all of them through its one registration.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.session.options import Control, controls
from core.registry import option_classes, option_owner, register_renderer, unregister_renderer
from core.settings import SHADOW_MODES, RenderSettings

from tests.conftest import ROOT

SCENES = ROOT / "scenes"


def test_a_field_is_routed_to_its_renderers_options_and_defaults_are_not_stored():
    s = RenderSettings().replace(max_depth=3, bsp_root="first", shading="phong")
    assert s.shading == "phong"
    assert s.options_of("raytrace").max_depth == 3
    assert s.options_of("bsp").bsp_root == "first" == s.options_of("depth-sort").bsp_root
    assert s.options_of("radiosity").max_elements == 2000          # untouched: the default
    assert s.options_of("zbuffer") is None                          # it registered none
    assert RenderSettings().replace(max_depth=7) == RenderSettings()   # the default again
    assert s.replace(max_depth=7, bsp_root="fewest-splits").options == ()
    from core.renderers.raytrace.options import RaytraceOptions
    given = RenderSettings().replace(options=(RaytraceOptions(max_depth=2),), shading="phong")
    assert given.options_of("raytrace").max_depth == 2 and given.shading == "phong"
    assert RenderSettings().replace(options=(RaytraceOptions(),)) == RenderSettings()


def test_unknown_and_refused_values_say_what_and_why():
    with pytest.raises(TypeError, match="RenderSettings has no setting 'depth_max', and no "
                                        "renderer's options have one"):
        RenderSettings().replace(depth_max=3)
    with pytest.raises(ValueError, match=r"max_depth must be a whole number from 1 to 64, "
                                         r"not 0"):
        RenderSettings().replace(max_depth=0)
    with pytest.raises(ValueError, match="shadows must be one of off, background, object, "
                                         "transmit, not 'sometimes'"):
        RenderSettings.for_scene(_scene(), shadows="sometimes")
    with pytest.raises(ValueError, match="hemicube resolution must be an even whole number"):
        RenderSettings().replace(hemicube_resolution=33)


def test_the_panel_shows_each_option_by_its_type_and_metadata():
    found = {c.name: c for c in controls(RenderSettings().options_of("raytrace"))}
    assert list(found) == ["max_depth", "adaptive_epsilon", "shadows", "fresnel",
                           "fresnel_form", "secondary_attenuation", "adaptive_threshold"]
    assert found["max_depth"] == Control("max_depth", "int", 7, (), "the ray tree's depth limit")
    assert found["shadows"].kind == "choice" and found["shadows"].choices == SHADOW_MODES
    assert found["fresnel"].kind == "bool" and found["secondary_attenuation"].kind == "pair"
    painters = [c.name for c in controls(RenderSettings().options_of("bsp"))]
    assert painters == ["bsp_root"]              # paint_first has the draw-order slider
    assert controls(None) == []


@dataclasses.dataclass(frozen=True)
class KnobOptions:
    """A toy renderer's options: one number, one choice."""
    knob: int = dataclasses.field(default=2, metadata={"help": "how far to turn it"})
    tint: str = dataclasses.field(default="red", metadata={"choices": ("red", "blue")})

    def __post_init__(self):
        if not 0 <= self.knob <= 9:
            raise ValueError(f"knob must be from 0 to 9, not {self.knob!r}")

    @staticmethod
    def add_arguments(parser):
        parser.add_argument("--knob", type=int, default=None, help="toy: how far to turn it")

    @staticmethod
    def overrides(args):
        return {"knob": getattr(args, "knob", None)}


@pytest.fixture
def toy():
    from core.renderers.zbuffer.draw import draw
    register_renderer("toy-knob", draw, options=KnobOptions, label="Toy")
    yield
    unregister_renderer("toy-knob")


def test_a_new_renderers_options_reach_settings_panel_and_command_line(toy):
    assert KnobOptions in option_classes() and option_owner("knob") is KnobOptions
    s = RenderSettings(renderer="toy-knob").replace(knob=5)
    assert s.options_of("toy-knob") == KnobOptions(knob=5)
    assert [c.name for c in controls(s.options_of("toy-knob"))] == ["knob", "tint"]
    from app.cli_arguments import command_parser, option_overrides
    args = command_parser("render").parse_args(["render", "scenes/torus.toml", "--knob", "4"])
    assert option_overrides(args)["knob"] == 4
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES / "torus.toml", size=(32, 24))
    state.choices.set_renderer("toy-knob")
    assert not state.choices.set_option("knob", 12)
    assert state.option_message == "knob must be from 0 to 9, not 12; knob stays 2"
    assert state.choices.set_option("knob", 7)
    assert state.choices.renderer_options() == KnobOptions(knob=7)


def test_the_panels_depth_limit_changes_the_ray_traced_mirror():
    """house_mirror.toml: one bounce shows the mirror's reflection; a depth limit of 1 stops
    at the mirror's own colour, so the pictures differ, and only where secondary rays go."""
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES / "house_mirror.toml", size=(48, 36))
    state.choices.set_renderer("raytrace")
    deep = _frame(state)
    assert state.choices.set_option("max_depth", 1)
    shallow = _frame(state)
    differs = np.any(deep != shallow, axis=2)
    assert 0 < differs.sum() < differs.size
    assert state.choices.set_option("max_depth", 7)
    assert np.array_equal(_frame(state), deep)


def _frame(state):
    from core.render import render
    return render(state.scene, state.views.current, state.choices.settings()).color


def _scene():
    from core.scene.formats import load_scene
    return load_scene(SCENES / "torus.toml")
