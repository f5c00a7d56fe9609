"""The scan-line rasterizer's Gouraud against llvmpipe with ``noperspective`` varyings.

The course's scan-line algorithm interpolates intensities linearly in screen space; OpenGL
does the same when the varying is declared ``noperspective`` (``gouraud_linear`` in
``app/oracles/reference_gl.py``). Away from triangle edges the two must agree to 2/255; and,
as a control, the perspective-correct Gouraud of the edge rasterizer must not agree with it
everywhere on a perspective view (nor the scan line's with GL's perspective-correct one).
"""

from __future__ import annotations

import numpy as np
import pytest

from tools import need_module                                          # noqa: E402

need_module("moderngl", "the OpenGL oracle needs moderngl")

from core.render import render                                        # noqa: E402
from core.settings import RenderSettings                              # noqa: E402
from tests.app.oracles.test_gl_oracle import (  # noqa: E402,F401
    SIZE, _lit, _save_failure, edge_mask, gl, scene_file, valid_views)


def _scanline(scene, view_index, projection, rasterizer="scanline"):
    settings = RenderSettings.for_scene(scene, projection=projection, shading="gouraud",
                                        size=SIZE, rasterizer=rasterizer)
    frame = render(scene, scene.views[view_index], settings)
    assert frame.message is None, frame.message
    return frame.color.astype(np.int16)


@pytest.mark.parametrize("variant", ["own lights", "halfway, attenuated"])
@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("name", ["sphere.toml", "torus.toml", "interpenetrating.tri"])
def test_scanline_gouraud_matches_noperspective_llvmpipe(gl, name, projection, variant):
    scene = _lit(scene_file(name), variant)
    gl.load(scene, modes=("gouraud_linear", "coverage"))
    for view_index in valid_views(scene, projection):
        ours = _scanline(scene, view_index, projection)
        theirs = gl.render(gl.scene.views[view_index], projection, "gouraud_linear").astype(np.int16)
        covered = gl.render(gl.scene.views[view_index], projection, "coverage")[:, :, 0] > 127
        away = covered & ~edge_mask(scene, view_index, projection)
        label = f"scanline-{name}-{projection}-{variant}-view{view_index + 1}"
        assert away.sum() >= 2000, f"{label}: only {away.sum()} pixels away from edges"
        diff = np.abs(ours - theirs).max(axis=2)
        worst = int(diff[away].max())
        if worst > 2:
            where = _save_failure(label, ours=ours.astype(np.uint8),
                                  llvmpipe=theirs.astype(np.uint8), differ=(diff > 2) & away)
            pytest.fail(f"{label}: {np.count_nonzero((diff > 2) & away)} pixels away from edges "
                        f"differ by more than 2/255 (worst {worst}); {where}")


def test_the_comparison_tells_screen_linear_from_perspective_correct(gl):
    # interpenetrating.tri: big triangles in depth, seen in perspective
    scene = scene_file("interpenetrating.tri")
    gl.load(scene, modes=("gouraud", "gouraud_linear", "coverage"))
    covered = gl.render(gl.scene.views[0], "perspective", "coverage")[:, :, 0] > 127
    away = covered & ~edge_mask(scene, 0, "perspective")
    linear = gl.render(gl.scene.views[0], "perspective", "gouraud_linear").astype(np.int16)
    correct = gl.render(gl.scene.views[0], "perspective", "gouraud").astype(np.int16)
    assert np.abs(_scanline(scene, 0, "perspective") - correct).max(axis=2)[away].max() > 2
    assert np.abs(_scanline(scene, 0, "perspective", "edge") - linear).max(axis=2)[away].max() > 2
