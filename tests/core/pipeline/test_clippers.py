"""The three line clippers (``--clipper``) against each other: Cohen–Sutherland (the course's),
Liang–Barsky and clipping in homogeneous coordinates, on 100,000 random segments in each
canonical volume, and the pictures they give."""

from __future__ import annotations

import numpy as np
import pytest

from core import RenderSettings, render
from core.pipeline import clip
from core.scene.formats import load_scene
from core.pipeline.project import project_lines


@pytest.mark.parametrize("projection, z_min", [("parallel", 0.0), ("perspective", -0.1)])
def test_the_clippers_keep_the_same_segments_to_1e12_in_npc(projection, z_min):
    rng = np.random.default_rng(35)
    p0, p1 = rng.uniform(-2, 1, (100_000, 3)), rng.uniform(-2, 1, (100_000, 3))
    vp = (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)         # the unit viewport: device = NPC
    cs = clip.clip_lines(p0, p1, projection, z_min)
    assert 20_000 < len(cs[0]) < 90_000            # accepted, rejected and cut ones
    for other in ("liang-barsky", "homogeneous"):
        q = clip.clip_lines_with(other, p0, p1, projection, z_min)
        assert len(q[0]) == len(cs[0])
        for a, b in zip(cs, q):
            npc_a, npc_b = project_lines(a, projection, vp), project_lines(b, projection, vp)
            assert np.abs(npc_a - npc_b).max() <= 1e-12


def test_a_segment_clipped_by_hand():
    # parallel: from (-3, 0, -0.5) to (3, 0.5, -0.5) enters x = -1 at t = 1/3, leaves x = 1 at 2/3
    for clipper in clip.CLIPPERS:
        q0, q1 = clip.clip_lines_with(clipper, [[-3, 0, -0.5]], [[3, 0.5, -0.5]], "parallel")
        np.testing.assert_allclose(q0, [[-1, 1 / 6, -0.5]], atol=1e-15)
        np.testing.assert_allclose(q1, [[1, 2 / 6, -0.5]], atol=1e-15)


@pytest.mark.parametrize("name", ["house.toml", "house_projections.toml"])
def test_every_clipper_draws_the_same_house(name):
    scene = load_scene(f"scenes/{name}")
    for view in scene.views[:13]:
        for projection in ("perspective", "parallel"):
            settings = RenderSettings.for_scene(scene, size=(120, 120), projection=projection)
            today = render(scene, view, settings).color
            for clipper in ("liang-barsky", "homogeneous"):
                assert np.array_equal(render(scene, view, settings.replace(clipper=clipper)).color,
                                      today), (view.label, projection, clipper)


def test_an_unknown_clipper_is_one_message():
    with pytest.raises(ValueError, match="clipper must be one of cohen-sutherland, liang-barsky, "
                                         "homogeneous, not 'cyrus'"):
        RenderSettings(clipper="cyrus")


def test_the_command_line_takes_a_clipper(tmp_path):
    import subprocess
    import sys
    from PIL import Image
    from core.paths import ROOT
    out = tmp_path / "homogeneous.png"
    done = subprocess.run([sys.executable, "-m", "app", "render", "scenes/house.toml",
                           "--view", "9", "--size", "64x64", "--clipper", "homogeneous",
                           "--out", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    scene = load_scene("scenes/house.toml")
    view = next(v for v in scene.views if "view 9 (" in v.label)
    today = render(scene, view, RenderSettings.for_scene(scene, size=(64, 64))).color
    assert today.any() and np.array_equal(np.asarray(Image.open(out))[:, :, :3], today)
