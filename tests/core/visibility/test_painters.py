"""The painter's renderers: the BSP tree and Newell's depth sort give the
z-buffer's picture, including where no order of whole polygons exists (cycles, piercing), and
the BSP tree of the notes' worked example is built and walked as the lecture does it."""

from __future__ import annotations

import functools
from types import SimpleNamespace

import numpy as np
import pytest

from core.context import RenderContext
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings
from core.visibility import bsp
from tests.conftest import ROOT

SCENES = ROOT / "scenes"
BUNNY_SMALL = SCENES / "stanford-bunny" / "bun_zipper_res2.ply"     # shipped with the glass bunny


# ---------------------------------------------------------------- the notes' worked example

def _wall(x0, z0, x1, z1):
    """A vertical triangle standing on the top-view segment (x0, z0)–(x1, z1): the lecture's
    figure is drawn from above, each polygon a line."""
    return [(x0, -1.0, z0), (x1, -1.0, z1), ((x0 + x1) / 2, 1.0, (z0 + z1) / 2)]


# The figure's five polygons as top-view segments, placed as its text describes them: 3 is
# the root with 1, 2 and the part 5A of 5 in front of it (its normal, +z) and 4, 5B behind;
# the eye, at z = -5, is in 3's rear half-space, in 2's rear half-space and in 4's front one.
LECTURE = {3: _wall(-1, 0, 1, 0), 2: _wall(1.5, 1.5, 1.5, 0.5), 4: _wall(1, -2, -1, -2),
           1: _wall(-1, 3, 1, 3), 5: _wall(2, -1, 2, 1)}
EYE = SimpleNamespace(point=(0.0, 0.0, -5.0), direction=None)


def _lecture_tree():
    names = [3, 2, 4, 1, 5]        # "first" takes the head of each list: root 3, then 2 and 4
    positions = np.array([p for k in names for p in LECTURE[k]])
    return names, bsp.build(positions, np.arange(15).reshape(5, 3), "first")


def test_lecture_example_tree():
    names, tree = _lecture_tree()
    label = lambda f: names[tree.source[f]]                                  # noqa: E731
    node_polygon = [label(tree.node_fragments[tree.first[i]]) for i in range(tree.nodes)]
    root = 0
    assert node_polygon[root] == 3
    assert node_polygon[tree.front[root]] == 2 and node_polygon[tree.back[root]] == 4
    two, four = tree.front[root], tree.back[root]
    # 5 spans 3's plane: split once, 5A in front (under 2, on its front), 5B behind (under 4)
    assert tree.splits == 1 and len(tree.node_fragments) == 6     # 5 is now 5A and 5B
    assert node_polygon[tree.front[two]] == 5 and node_polygon[tree.back[two]] == 1
    assert tree.front[four] == -1 and node_polygon[tree.back[four]] == 5
    five_a = tree.node_fragments[tree.first[tree.front[two]]]
    five_b = tree.node_fragments[tree.first[tree.back[four]]]
    assert tree.points[tree.fragments[five_a], 2].min() >= 0.0      # z >= 0: 3's front side
    assert tree.points[tree.fragments[five_b], 2].max() <= 0.0
    assert (tree.nodes, tree.depth) == (6, 3)


def test_lecture_example_rendering_order():
    """The notes: "Rendering order is 5A, 2, 1 (F half-space), 3 (root), 5B, 4 (B half-space)"."""
    names, tree = _lecture_tree()
    order = bsp.back_to_front(tree, EYE)
    labels = [names[tree.source[f]] for f in order]
    assert labels == [5, 2, 1, 3, 5, 4]
    five_a, five_b = order[0], order[4]
    assert tree.points[tree.fragments[five_a], 2].min() >= 0.0
    assert tree.points[tree.fragments[five_b], 2].max() <= 0.0
    # from z = +9 the eye is in front of 3 (its rear half-space first: 4, then 5B, the eye
    # being behind 4 now) but still behind 2 (x = 0 < 1.5): 5A, 2, 1 as before
    far = SimpleNamespace(point=(0.0, 0.0, 9.0), direction=None)
    assert [names[tree.source[f]] for f in bsp.back_to_front(tree, far)] == [4, 5, 3, 5, 2, 1]
    # a parallel view looking along +z (towards the viewer: -z) walks like the eye at z = -5
    along = SimpleNamespace(point=None, direction=(0.0, 0.0, -1.0))
    assert [names[tree.source[f]] for f in bsp.back_to_front(tree, along)] == labels


@pytest.mark.parametrize("rule", ["first", "random", "fewest-splits"])
def test_every_root_rule_keeps_every_triangle(rule):
    """Whatever the roots, the fragments tile the input: areas per source triangle add up."""
    rng = np.random.default_rng(3)
    positions = rng.uniform(-1, 1, (60, 3))
    triangles = np.arange(60).reshape(20, 3)
    tree = bsp.build(positions, triangles, rule, seed=7)
    area = lambda p, t: 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]],   # noqa: E731
                                                      p[t[:, 2]] - p[t[:, 0]]), axis=1)
    kept = tree.node_fragments                      # a split fragment gives way to its pieces
    pieces = np.bincount(tree.source[kept], area(tree.points, tree.fragments[kept]), minlength=20)
    assert np.allclose(pieces, area(positions, triangles), rtol=1e-9)
    # each split turns one fragment into two or three
    assert tree.splits > 0 and tree.splits <= len(kept) - 20 <= 2 * tree.splits
    assert sorted(bsp.back_to_front(tree, EYE)) == sorted(kept)
    with pytest.raises(ValueError, match="BSP root rule must be one of"):
        bsp.build(positions, triangles, "best")


# ------------------------------------------------------------ the same picture as the z-buffer

def _compare(scene, renderer, projection, shading, view=0):
    """``(share of equal pixels, {"edge": n, "seam": n, "tie": n, "other": n, "rounding": n})``
    against the z-buffer.

    Equal means within one level (1/255) per channel, the project's golden tolerance: a split
    triangle's pixels interpolate from other barycentrics, equal up to rounding, and a colour
    on a half level may tip (counted as "rounding"). A differing pixel is at an edge when the z-buffer's visible triangle (or background)
    changes within its 3 x 3 neighbourhood, on a seam when only the painter's triangle does
    (a split's T-junction: the cut vertex, rounded to the rasterizer's 1/256 pixel, is off
    its neighbour's edge and a pixel centre in the sliver is missed), at a depth tie when both renderers see the same
    depth there (two surfaces at one depth: the z-buffer keeps the later), else "other"."""
    context = RenderContext()
    kept = {}

    def grab(stage, arrays):
        if stage in ("z-buffer", "paint"):
            kept[stage] = arrays["tri"].copy()

    settings = RenderSettings.for_scene(scene, projection=projection, shading=shading)
    ref = render(scene, scene.views[view], settings, context, inspect=grab)
    ref_color, ref_depth = ref.color.copy(), ref.depth.copy()
    frame = render(scene, scene.views[view], settings.replace(renderer=renderer), context,
                   inspect=grab)
    assert frame.message is None and frame.stats["renderer"] == renderer
    error = np.abs(frame.color.astype(np.int16) - ref_color).max(axis=2)
    differ = np.argwhere(error > 1)
    tri = np.pad(kept["z-buffer"], 1, mode="edge")
    painted = np.pad(kept["paint"], 1, mode="edge")
    kinds = {"edge": 0, "seam": 0, "tie": 0, "other": 0, "rounding": int(np.count_nonzero(error == 1))}
    for y, x in differ:
        block = tri[y:y + 3, x:x + 3]
        if (block != block[1, 1]).any():
            kinds["edge"] += 1
        elif (painted[y:y + 3, x:x + 3] != painted[y + 1, x + 1]).any():
            kinds["seam"] += 1
        elif np.isclose(frame.depth[y, x], ref_depth[y, x], rtol=0, atol=1e-12):
            kinds["tie"] += 1
        else:
            kinds["other"] += 1
    return 1.0 - len(differ) / ref_color[..., 0].size, kinds


CASES = [  # scene, projection, shading: each scene in both projections, all shadings met
    ("interpenetrating.tri", "perspective", "flat"),
    ("interpenetrating.tri", "parallel", "gouraud"),
    ("pierced_triangles.tri", "perspective", "phong"),
    ("pierced_triangles.tri", "parallel", "flat"),
    ("three_bars.toml", "perspective", "gouraud"),
    ("three_bars.toml", "parallel", "phong"),
    ("crossing_front_plane.tri", "perspective", "flat"),
    ("crossing_front_plane.tri", "parallel", "phong"),
    ("few_triangles.tri", "perspective", "gouraud"),
    ("cube.toml", "parallel", "flat"),
    ("house_solid.obj", "perspective", "phong"),
    ("torus.toml", "perspective", "gouraud"),
    ("torus.toml", "parallel", "flat"),
]


@functools.lru_cache(maxsize=None)
def _scene(name):
    return load_scene(SCENES / name)


@pytest.mark.parametrize("renderer", ["bsp", "depth-sort"])
@pytest.mark.parametrize("name, projection, shading", CASES)
def test_same_picture_as_the_zbuffer(name, projection, shading, renderer):
    same, kinds = _compare(_scene(name), renderer, projection, shading)
    assert same >= 0.999, (same, kinds)
    assert kinds["other"] == 0, kinds


@pytest.mark.slow
@pytest.mark.parametrize("renderer", ["bsp", "depth-sort"])
@pytest.mark.parametrize("projection, shading", [("perspective", "flat"), ("parallel", "phong")])
def test_same_picture_as_the_zbuffer_on_the_bunny(projection, shading, renderer):
    same, kinds = _compare(load_scene(BUNNY_SMALL), renderer, projection, shading)
    assert same >= 0.999, (same, kinds)
    assert kinds["other"] == 0, kinds


def _plain_sort(monkeypatch):
    """The depth-sort renderer with only step 1: sorted by farthest z, nothing tested."""
    from core.visibility import depth_sort
    monkeypatch.setattr(depth_sort, "depth_sort",
                        functools.partial(depth_sort.depth_sort, resolve=False))


@pytest.mark.parametrize("name", ["three_bars.toml", "pierced_triangles.tri"])
def test_no_order_of_whole_polygons_exists(name, monkeypatch):
    """The cycle and the piercing: both painters split and match the z-buffer; the plain sort
    by farthest z, which cannot split, paints a visible part of the picture wrong."""
    scene = _scene(name)
    for renderer in ("bsp", "depth-sort"):
        same, kinds = _compare(scene, renderer, "perspective", "flat")
        assert same >= 0.999 and kinds["other"] == 0, (renderer, same, kinds)
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, renderer="depth-sort"),
                   RenderContext())
    assert frame.stats["depth sort"]["splits"] > 0
    _plain_sort(monkeypatch)
    same, kinds = _compare(scene, "depth-sort", "perspective", "flat")
    assert kinds["other"] > 500, (same, kinds)       # a whole region, not a seam


# ------------------------------------------------------------- looking at the painting

def test_paint_first_overdraw_and_pixel_history():
    from core.inspect.buffers import buffer
    from core.renderers.painters.inspect import inspect_pixel, overdraw
    scene = _scene("interpenetrating.tri")
    view = scene.views[0]
    context = RenderContext()
    settings = RenderSettings.for_scene(scene, renderer="depth-sort")
    full = render(scene, view, settings, context)
    painted = full.stats["painted"]
    assert painted > len(scene.meshes[0].triangles)              # the cycle and the pierce split
    none = render(scene, view, settings.replace(paint_first=0), context)
    assert (none.color == none.color[0, 0]).all()                # nothing painted: background
    part = render(scene, view, settings.replace(paint_first=painted // 2), context)
    assert part.stats["painted"] == painted // 2
    assert 0 < (part.color != none.color).any(axis=2).sum() < (full.color != none.color).any(axis=2).sum()
    counts = overdraw(scene, view, settings, context)
    assert counts.shape == (500, 500) and counts.dtype == np.int32
    covered = (full.color != none.color).any(axis=2)
    assert (counts[covered] >= 1).all() and counts.max() >= 2
    zcounts, _ = buffer(scene, view, settings.replace(renderer="zbuffer"), "overdraw", context)
    zbuffer = render(scene, view, settings.replace(renderer="zbuffer"), context)
    assert (zcounts[(zbuffer.color != none.color).any(axis=2)] >= 1).all()
    y, x = np.argwhere(counts == counts.max())[0]
    for renderer in ("depth-sort", "bsp"):
        s = settings.replace(renderer=renderer)
        record = inspect_pixel(scene, view, s, int(x), int(y), context, render=render)
        frame = render(scene, view, s, context)
        assert record["renderer"] == renderer and record["pixel"] == [int(x), int(y)]
        assert record["color"] == [int(c) for c in frame.color[y, x]]
        writes = record["writes"]
        assert len(writes) == overdraw(scene, view, s, context)[y, x] >= 2
        assert [w["rank"] for w in writes] == sorted(w["rank"] for w in writes)
        assert writes[-1]["color"] == record["color"]           # the last write is what shows
        assert writes[-1]["depth"] >= max(w["depth"] for w in writes) - 1e-12   # and nearest


def test_cli_painter_options(tmp_path, capsys):
    from app.cli import main
    out = tmp_path / "bars.png"
    assert main(["render", str(SCENES / "three_bars.toml"), "--renderer", "bsp", "--bsp-root",
                 "first", "--paint-first", "10", "--out", str(out)]) == 0
    assert out.exists()
    assert main(["render", str(SCENES / "three_bars.toml"), "--renderer", "bsp",
                 "--paint-first", "-2", "--out", str(out), "--force"]) == 2
    assert "error: --paint-first must be 0 or more, not -2" in capsys.readouterr().err
    assert main(["plan", str(SCENES / "three_bars.toml"), "--renderer", "depth-sort"]) == 0
    import json
    report = json.loads(capsys.readouterr().out)
    assert report["depth-sort"]["depth sort"]["splits"] > 0
    assert any(s["stage"] == "depth sort" and "splits" in s["why"] for s in report["runs"])


def test_viewer_state_draw_order_and_toggles():
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES / "three_bars.toml")
    state.choices.set_renderer("depth-sort")
    state.choices.set_paint_first(7)
    assert state.choices.settings().options_of("depth-sort").paint_first == 7
    state.choices.set_renderer("zbuffer")
    # only the painters paint in order
    assert state.choices.settings().options_of("depth-sort").paint_first is None
    assert not state.choices.settings().depth_cue
    state.choices.set_depth_cue(True)
    assert state.choices.settings().depth_cue and state.dirty
    state.choices.set_transparency("screen-door")
    assert state.choices.settings().transparency == "screen-door"
    with pytest.raises(ValueError, match="transparency must be one of"):
        state.choices.set_transparency("glass")


def test_a_painter_under_a_new_name_is_treated_as_the_one_it_copies(capsys):
    """The BSP renderer's functions under a new name, with its capabilities: its transparent
    pane is laid in the entry's painting order, the command line's plan reports its tree, the
    pixel history reads its order, the window's draw-order slider reaches it and the render
    log names it. Nothing but the registry entry says it is a painter."""
    import json

    from app.cli import main
    from app.commands.scene_commands import _drawn_by
    from app.session.state import ViewerState
    from core.inspect import inspect_pixel
    from core.renderers import register_renderer, unregister_renderer
    from core.visibility.paint import bsp_painting
    painted = []          # the meshes of each scene painted through the entry's painting

    def counted(scene, *rest):
        painted.append(len(scene.meshes))
        return bsp_painting(scene, *rest)

    register_renderer("bsp-again", "core.renderers.painters.draw:draw_bsp",
                      inspector="core.renderers.painters.inspect:inspect_pixel",
                      plan_stages="core.renderers.painters.plan:bsp_stages",
                      options="core.renderers.painters.options:PainterOptions",
                      painting=counted, transparency=True, shaders=True, rasterizes=True)
    try:
        pane = load_scene(SCENES / "transparent_pane.toml")
        frames = [render(pane, pane.views[0],
                         RenderSettings.for_scene(pane, renderer=name, size=(96, 96)),
                         RenderContext()) for name in ("bsp", "bsp-again")]
        assert painted == [1]                    # the pane alone, in the entry's order
        assert frames[1].stats["transparent triangles"] == frames[0].stats[
            "transparent triangles"] > 0
        assert np.array_equal(frames[1].color, frames[0].color)
        reports = []
        for name in ("bsp", "bsp-again"):
            assert main(["plan", str(SCENES / "three_bars.toml"), "--renderer", name]) == 0
            reports.append(json.loads(capsys.readouterr().out))
        trees = [{k: v for k, v in r[name]["BSP tree"].items() if "ms" not in k}   # untimed
                 for r, name in zip(reports, ("bsp", "bsp-again"))]
        assert trees[1] == trees[0] and trees[1]["nodes"] > 0
        assert reports[1]["bsp-again"]["painted"] == reports[0]["bsp"]["painted"] > 0
        assert [s["stage"] for s in reports[1]["runs"]] == [s["stage"] for s in reports[0]["runs"]]
        bars = load_scene(SCENES / "three_bars.toml")
        settings = RenderSettings.for_scene(bars, renderer="bsp-again", size=(80, 60))
        shown = render(bars, bars.views[0], settings, RenderContext()).color
        y, x = (int(c) for c in np.argwhere((shown != shown[0, 0]).any(axis=2))[0])
        del painted[:]
        record = inspect_pixel(bars, bars.views[0], settings, x, y, RenderContext())
        same = inspect_pixel(bars, bars.views[0], settings.replace(renderer="bsp"), x, y,
                             RenderContext())
        assert painted == [len(bars.meshes)]
        assert record["writes"] and record["writes"] == same["writes"]
        assert _drawn_by(settings) == "bsp-again"
        state = ViewerState.open(SCENES / "three_bars.toml")
        state.choices.set_renderer("bsp-again")
        state.choices.set_paint_first(7)
        assert state.choices.settings().options_of("bsp-again").paint_first == 7
        assert state.choices.renderer_entry.status == "drawn by bsp-again"
    finally:
        unregister_renderer("bsp-again")


def test_bench_rows_for_the_painters(tmp_path):
    """``bench --renderer bsp,depth-sort,zbuffer``: a tree row per root rule, a frame row per
    renderer (tiny sizes: the numbers are the bench's business, the rows are this test's)."""
    import argparse
    import json
    from app.cli import main
    from app.bench.bench import _renderers
    with pytest.raises(argparse.ArgumentTypeError, match="not 'raytrace'"):
        _renderers("bsp,raytrace")
    assert main(["bench", "--renderer", "bsp,depth-sort,zbuffer", "--sizes", "300",
                 "--frames", "1", "--warmup", "0", "--size", "64x64", "--shading", "flat",
                 "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "painters.json").read_text())
    assert [t["rule"] for t in result["trees"]] == ["first", "random", "fewest-splits"]
    assert all(t["nodes"] > 0 and t["build cpu ms"] >= 0 for t in result["trees"])
    assert [r["renderer"] for r in result["frames"]] == ["bsp", "depth-sort", "zbuffer"]
    assert result["frames"][2]["memory_bytes"] == 64 * 64 * 28
    assert "| fewest-splits |" in (tmp_path / "painters.md").read_text()
