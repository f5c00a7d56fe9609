"""The path tracer's samplers: the stratified first bounce (the default) against independent
random numbers on the Cornell box's back wall, the window bench's measure of noise (the median
absolute Laplacian). Both are unbiased, so their means agree; the stratified one's noise falls
faster than plain Monte Carlo's k^-1/2. (Both are our own code: a consistency check; the
Mitsuba oracle in test_pathtrace.py holds the default's picture to an independent program.)"""

from __future__ import annotations

import numpy as np
import pytest

from core.context import RenderContext
from core.renderers.pathtrace.draw import render_passes
from core.scene.formats import load_scene
from core.settings import RenderSettings

from tests.conftest import ROOT

SIZE = 128
WALL = [int(v * SIZE / 400) for v in (130, 95, 300, 160)]   # the window bench's box, scaled


def _wall(image: np.ndarray) -> np.ndarray:
    x0, y0, x1, y1 = WALL
    return image[y0:y1, x0:x1].mean(axis=2)


def _noise(image: np.ndarray) -> float:
    a = _wall(image)
    lap = 4 * a[1:-1, 1:-1] - a[:-2, 1:-1] - a[2:, 1:-1] - a[1:-1, :-2] - a[1:-1, 2:]
    return float(np.median(np.abs(lap)))


@pytest.fixture(scope="module")
def accumulated():
    """Per sampler: the running mean after 8 and after 64 passes, as the window accumulates."""
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    view = scene.views[0]
    base = RenderSettings.for_scene(scene, renderer="pathtrace", size=(SIZE, SIZE), samples=256)
    out = {}
    for sampler in ("independent", "stratified"):
        settings, context, total = base.replace(sampler=sampler), RenderContext(), 0.0
        for k in range(64):
            radiance, _ = render_passes(scene, view, settings, context, first=k, count=1)
            total = total + radiance
            if k + 1 in (8, 64):
                out[sampler, k + 1] = total / (k + 1)
    return out


def test_the_default_is_stratified():
    assert RenderSettings().options_of("pathtrace").sampler == "stratified"


def test_both_samplers_agree_on_the_mean(accumulated):
    # 64 paths over ~1,900 wall pixels: the mean's own noise is well under 1 % (measured
    # 0.1 %); a biased sampler (a shift shared by every pixel, say) would miss by more.
    ours = _wall(accumulated["stratified", 64]).mean()
    plain = _wall(accumulated["independent", 64]).mean()
    assert ours == pytest.approx(plain, rel=0.01)


def test_stratified_noise_falls_faster_than_monte_carlo(accumulated):
    plain = _noise(accumulated["independent", 8]) / _noise(accumulated["independent", 64])
    ours = _noise(accumulated["stratified", 8]) / _noise(accumulated["stratified", 64])
    # plain Monte Carlo's noise falls as k^-1/2: about sqrt(8) = 2.83 from 8 to 64 paths
    assert 2.3 < plain < 3.2
    assert ours > 3.0 and ours > plain * 1.1
    assert _noise(accumulated["stratified", 64]) < 0.9 * _noise(accumulated["independent", 64])


def test_an_unknown_sampler_is_refused_with_the_choices():
    with pytest.raises(ValueError, match="path sampler must be one of stratified, independent"):
        RenderSettings().replace(sampler="sobol")
