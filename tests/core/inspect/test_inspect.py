"""The pixel inspector: each renderer's record sums to the pixel the frame shows,
on 10,000 random pixels per renderer; the notes' worked example gives its hand values."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core import RenderContext, RenderSettings, View, render
from core.inspect import NotInspectable, inspect_pixel
from core.paths import SCENES_DIR
from core.scene.formats import load_scene
from core.shading.illumination import quantize

PIXELS_PER_RENDERER = 10_000

# The notes' worked example: VRP (0, 0, 54), PRP (8, 6, 30), window -1..17, F = 10, B = -50.
WORKED = View(vrp=(0.0, 0.0, 54.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
              window=(-1.0, 17.0, -1.0, 17.0), prp=(8.0, 6.0, 30.0), front=10.0, back=-50.0,
              label="worked example")


def _bytes(rgb) -> list[int]:
    return [int(quantize(c)) for c in rgb]


def _check_sum(record) -> None:
    """The record's own terms add up to its colour (to 1/255)."""
    if "samples" in record:
        for sample in record["samples"]:
            _check_sum(sample)
        return
    if "phong" in record and "sum" not in record:            # flat, Phong: the model's terms
        terms = record["phong"]
        total = [terms["ambient"][c] + sum(light.get("sum", [0, 0, 0])[c]
                                           for light in terms["lights"]) for c in range(3)]
        assert np.abs(np.subtract(_bytes(total), record["color"])).max() <= 1
    if "sum" in record:                                       # textured: the maps, then Phong
        assert np.abs(np.subtract(_bytes(record["sum"]), record["color"])).max() <= 1
    if "vertices" in record:                                  # Gouraud: each vertex lit
        for vertex in record["vertices"]:
            if "phong" in vertex:
                assert _bytes(vertex["phong"]["clamped"]) == _bytes(vertex["colour"])
        w = record["weights"]["used"]
        mixed = sum(w[k] * np.array(v["colour"]) for k, v in enumerate(record["vertices"]))
        assert _bytes(mixed) == record["color"]
    nodes = record.get("ray tree") or []
    if "raw" in record and nodes and all("contribution" in n for n in nodes):   # the tree
        total = np.sum([node["contribution"] for node in nodes], axis=0)
        assert np.abs(total - record["raw"]).max() <= 1e-12


# (scene, settings overrides, share of the renderer's pixels)
ZBUFFER_CASES = [
    ("cube.toml", {"shading": "flat"}, 0.1),
    ("cube.toml", {"shading": "gouraud"}, 0.1),
    ("crossing_front_plane.tri", {"shading": "gouraud"}, 0.05),      # the clipper's vertices
    ("interpenetrating.tri", {"shading": "phong", "projection": "parallel"}, 0.05),
    ("torus.toml", {"shading": "phong"}, 0.15),
    ("torus.toml", {"shading": "gouraud", "rasterizer": "scanline"}, 0.1),
    ("texture_floor.toml", {"shading": "phong"}, 0.15),
    ("texture_sphere_torus.toml", {"shading": "phong", "texture_filter": "anisotropic"}, 0.1),
    ("texture_bump_sphere.toml", {"shading": "phong"}, 0.1),
    ("cube.toml", {"shading": "phong", "samples": 4}, 0.05),
    ("house.toml", {"shading": "wireframe"}, 0.05),
]
RAYTRACE_CASES = [
    ("whitted.toml", {}, 0.5),
    ("refraction.toml", {"fresnel": True}, 0.3),
    ("house_mirror.toml", {"shadows": "object"}, 0.2),
]


def _torus_scene():
    """An analytic torus (the ray caster's quartic) beside a sphere."""
    from core.scene.model import Light, Material, Scene
    from core.scene.primitives import Sphere, Torus
    view = View(vrp=(0, 0, 0), vpn=(0, 1, 2), vup=(0, 1, 0), window=(-2, 2, -2, 2),
                prp=(0, 0, 8), front=3, back=-3, label="above")
    return Scene(name="torus", meshes=[], views=[view], lights=[Light(position=(3.0, 4.0, 5.0))],
                 primitives=[Torus((0.0, 0.0, 0.0), 1.2, 0.4, (0.0, 1.0, 0.0),
                                   Material(od=(0.2, 0.6, 0.9))),
                             Sphere((1.2, 0.6, 0.4), 0.5, Material(od=(0.9, 0.3, 0.2)))])


RAYCAST_CASES = [("whitted.toml", {}, 0.5), (_torus_scene, {"samples": 4}, 0.5)]


def _run(cases, renderer, size=(96, 72)) -> tuple[int, dict]:
    rng = np.random.default_rng(22)
    checked, layers = 0, {}
    for name, overrides, share in cases:
        scene = name() if callable(name) else load_scene(SCENES_DIR / name)
        settings = RenderSettings.for_scene(scene, renderer=renderer, size=size, **overrides)
        view = scene.views[0]
        shown = render(scene, view, settings, RenderContext()).color
        context = RenderContext()
        for _ in range(int(round(share * PIXELS_PER_RENDERER))):
            x, y = int(rng.integers(size[0])), int(rng.integers(size[1]))
            record = inspect_pixel(scene, view, settings, x, y, context)
            assert record["renderer"] == renderer and record["pixel"] == [x, y]
            assert np.abs(np.subtract(record["color"], shown[y, x], dtype=int)).max() <= 1, \
                (name, overrides, x, y)
            _check_sum(record)
            layer = record.get("layer", "ray tree" if record.get("ray tree") else "other")
            layers[layer] = layers.get(layer, 0) + 1
            checked += 1
    return checked, layers


@pytest.mark.slow
def test_zbuffer_records_sum_to_the_shown_pixel_on_10000_random_pixels():
    checked, layers = _run(ZBUFFER_CASES, "zbuffer")
    assert checked >= PIXELS_PER_RENDERER
    assert layers["triangle"] > 3000 and layers["line"] > 5 and layers["background"] > 100


@pytest.mark.slow
def test_raytrace_records_sum_to_the_shown_pixel_on_10000_random_pixels():
    checked, layers = _run(RAYTRACE_CASES, "raytrace", size=(64, 48))
    assert checked >= PIXELS_PER_RENDERER


@pytest.mark.slow
def test_raycast_records_sum_to_the_shown_pixel_on_10000_random_pixels():
    checked, _ = _run(RAYCAST_CASES, "raycast", size=(64, 48))
    assert checked >= PIXELS_PER_RENDERER


def test_the_worked_example_depth_and_matrices_are_the_hand_values():
    scene = load_scene(SCENES_DIR / "house_solid.obj")
    scene = dataclasses.replace(scene, views=[WORKED])
    settings = RenderSettings.for_scene(scene, shading="flat", size=(500, 500))
    x, y = 250, 250
    record = inspect_pixel(scene, WORKED, settings, x, y, RenderContext())
    # The pixel centre on the view plane (the front wall, z = 54): u from the window.
    u = -1 + 18 * (x + 0.5) / 500
    v = 17 - 18 * (y + 0.5) / 500
    assert record["layer"] == "triangle" and record["mesh name"] is not None
    # The rasterizer snaps vertices to 1/256 pixel (its weights are those of the snapped
    # triangle): x and y within 1/256 pixel = 18/500/256 world units; z is exact on the wall.
    snap = 18 / 500 / 256
    assert record["depth"]["world point"][:2] == pytest.approx([u, v], abs=snap)
    assert record["depth"]["world point"][2] == pytest.approx(54.0, abs=1e-12)
    assert record["depth"]["vrc"] == pytest.approx([u, v, 0.0], abs=snap)
    # n = -30 after T(-PRP): canonical z = -30/80; z_min = -(-30 + 10)/(-30 - 50) = -1/4;
    # after M and the divide by W = 3/8: (-3/8 + 1/4)/(3/4) / (3/8) = -4/9.
    assert record["depth"]["npc"] == pytest.approx(-4 / 9, abs=1e-12)
    assert record["depth"]["distance from the eye"] == pytest.approx(
        np.linalg.norm([u - 8, v - 6, 54 - 84]), abs=snap)
    m = record["matrices"]
    assert np.allclose(m["S_per"], np.diag([1 / 24, 1 / 24, 1 / 80, 1]))
    assert np.allclose(m["SH_par"], [[1, 0, 0, 0], [0, 1, 1 / 15, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    assert np.allclose(m["T_prp"], [[1, 0, 0, -8], [0, 1, 0, -6], [0, 0, 1, -30], [0, 0, 0, 1]])
    assert np.allclose(m["T_vrp"], [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -54], [0, 0, 0, 1]])
    assert np.allclose(m["R"], np.eye(4))
    assert m["z_min"] == pytest.approx(-0.25)
    assert np.allclose(m["M"], [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 4 / 3, 1 / 3], [0, 0, -1, 0]])
    # the front wall faces +z: its normal, and the pixel's colour from its terms
    assert record["normal"] == pytest.approx([0, 0, 1])
    _check_sum(record)


def _plain(scene, view, settings, frame, context, timer):
    """A renderer registered without an inspector."""
    frame.color[...] = 0


def test_a_renderer_without_an_inspector_is_refused_in_words():
    from core.renderers import register_renderer, unregister_renderer
    register_renderer("plain", _plain)
    scene = load_scene(SCENES_DIR / "sphere.toml")
    try:                 # (left registered, it would show up in later tests' listings)
        settings = RenderSettings.for_scene(scene, renderer="plain", size=(20, 20))
        with pytest.raises(NotInspectable, match="the plain renderer has no pixel inspector"):
            inspect_pixel(scene, scene.views[0], settings, 3, 3)
    finally:
        unregister_renderer("plain")
    settings = settings.replace(renderer="zbuffer")
    with pytest.raises(NotInspectable, match=r"pixel \(20, 3\) is outside the 20 x 20 frame"):
        inspect_pixel(scene, scene.views[0], settings, 20, 3)
    bad = dataclasses.replace(scene.views[0], vup=scene.views[0].vpn, label="tilted")
    with pytest.raises(NotInspectable, match="tilted: invalid"):
        inspect_pixel(scene, bad, settings, 3, 3)


def test_a_renderer_is_planned_and_inspected_through_its_registry_entry():
    """A new name with the scan-line renderer's functions gets its plan stage and its record:
    nothing but the entry knows which renderer has which."""
    from core.plan import plan
    from core.renderers import register_renderer, unregister_renderer
    scene = load_scene(SCENES_DIR / "interpenetrating.tri")
    register_renderer("watkins-again", "core.renderers.scanline.draw:draw",
                      inspector="core.renderers.scanline.inspect:inspect_pixel",
                      plan_stages="core.renderers.scanline.plan:add_stages", shaders=True)
    try:
        settings = RenderSettings.for_scene(scene, renderer="watkins-again", size=(40, 30),
                                            shading="gouraud")
        names = [s.name for s in plan(scene, settings.projection, settings.shading,
                                      renderer="watkins-again")]
        assert "scan-line visible surface" in names and "z-buffer scan conversion" not in names
        assert "scan-line visible surface" not in [
            s.name for s in plan(scene, settings.projection, settings.shading)]
        frame = render(scene, scene.views[0], settings, RenderContext())
        covered = np.argwhere((frame.color != frame.color[0, 0]).any(axis=2))
        y, x = (int(c) for c in covered[len(covered) // 2])
        record = inspect_pixel(scene, scene.views[0], settings, x, y, RenderContext())
        assert record["color"] == frame.color[y, x].tolist()
        assert record["layer"] == "triangle" and record["scan line"]["spans"]
    finally:
        unregister_renderer("watkins-again")


@pytest.mark.parametrize("name, extra", [
    ("bsp", {}), ("depth-sort", {}),
    ("radiosity", {"max_elements": 100, "hemicube_resolution": 16})])
def test_the_front_door_hands_itself_to_the_inspectors_that_show_its_frame(name, extra):
    """The painters' and radiosity's records read the frame the front door draws (effects laid
    over): their packages sit below core.render, so it is handed to them as ``render``."""
    from core.inspect import inspector_of, takes_render
    assert takes_render(inspector_of(name)) and not takes_render(inspector_of("zbuffer"))
    scene = load_scene(SCENES_DIR / ("cornell_box.toml" if name == "radiosity"
                                     else "interpenetrating.tri"))
    settings = RenderSettings.for_scene(scene, renderer=name, size=(48, 48), **extra)
    context = RenderContext()
    frame = render(scene, scene.views[0], settings, context)
    for x, y in ((24, 24), (10, 40)):
        record = inspect_pixel(scene, scene.views[0], settings, x, y, context)
        assert record["renderer"] == name and record["color"] == frame.color[y, x].tolist()


def test_a_frame_drawn_without_the_inspector_loads_none_of_it():
    """Off costs nothing: rendering (and the window's module) import no inspector code."""
    import subprocess
    import sys
    code = ("import sys\n"
            "from core import render, RenderSettings\n"
            "from core.scene.formats import load_scene\n"
            "from core.paths import SCENES_DIR\n"
            "import app.viewer.inspector_tools\n"
            "scene = load_scene(SCENES_DIR / 'cube.toml')\n"
            "render(scene, scene.views[0], RenderSettings.for_scene(scene, shading='phong',"
            " size=(32, 24)))\n"
            "print(sorted(m for m in sys.modules if 'inspect' in m and m.startswith(('core',"
            " 'app'))))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=str(SCENES_DIR.parent))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "['app.viewer.inspector_tools']"


def test_a_record_of_another_shape_is_listed_key_by_key():
    from core.inspect.text import describe
    record = {"renderer": "bsp", "pixel": [4, 2], "color": [9, 8, 7],
              "history": [{"polygon": 3, "color": [1, 2, 3]}], "ray tree": [{"odd": 1}]}
    assert describe(record) == ["pixel (4, 2)  bsp  colour (9, 8, 7)",
                                "history: [{'polygon': 3, 'color': [1, 2, 3]}]",
                                "ray tree: [{'odd': 1}]"]
