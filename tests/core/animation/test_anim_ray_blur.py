"""Motion blur in the ray tracer, a time per primary ray (core.animation.ray_blur): the moving
square of test_anim_blur against its exact box-filtered coverage, a still scene, the same
bytes on every run, and fast motion spread as noise rather than the accumulation's copies."""

from __future__ import annotations

import numpy as np
import pytest

from core.animation import ray_blur
from core.animation.frames import Shutter, render_at
from core.animation.keys import animation_of
from core.scene.formats import read_scene_file
from core.settings import RenderSettings
from tests.core.animation.test_anim_blur import coverage, moving, SQUARE


def frame(text, t, shutter=None, renderer="raytrace", **options):
    scene = read_scene_file(text, "square.toml")
    anim = animation_of(scene)
    settings = RenderSettings.for_scene(scene, size=(64, 8), shading="flat",
                                        projection="parallel", renderer=renderer, **options)
    return render_at(anim, t, settings, shutter=shutter)


def row(f):
    return f.color[4, :, 0].astype(float) / 255


def test_the_ray_tracer_blurs_per_ray_by_default_and_accumulates_when_asked():
    assert frame(moving(0.0), 0.5, Shutter(8)).stats["motion blur"].startswith("per ray")
    assert frame(moving(0.0), 0.5, Shutter(8, method="accumulate")).stats["motion blur"] \
        == "accumulated"
    assert frame(moving(0.0), 0.5, Shutter(8), renderer="zbuffer").stats["motion blur"] \
        == "accumulated"
    with pytest.raises(ValueError, match="the motion blur's method is one of auto"):
        Shutter(4, method="sideways")


@pytest.mark.parametrize("left0", [0.0, 0.3, 0.71])
def test_64_times_a_ray_give_the_box_filtered_coverage_within_two_strata(left0):
    """One time in each of 64 strata of the shutter (0.5 px of the edge's sweep each): only
    the strata holding the two ends of a pixel centre's [c - 8, c] can miscount, each by at
    most 1/64, so |error| <= 2/64 (+ half a byte's rounding); on average far less."""
    got = frame(moving(left0), 0.5, Shutter(64))
    assert got.stats["motion blur"] == "per ray, 256 time buckets"
    error = np.abs(row(got) - coverage(left0))
    assert error.max() <= 2 / 64 + 0.5 / 255, error.max()
    assert error.mean() < 1 / 128, error.mean()
    assert np.all(row(got)[coverage(left0) > 2 / 64] > 0)  # every pixel swept is blurred


def test_a_still_scene_blurred_per_ray_is_its_sharp_frame():
    """Each pixel's rays all pass through the same film samples, whatever their times: the
    mean of equal colours is that colour (to the last bit here, so the bytes agree; in
    general the summation order could move a colour by an ulp, 1/255 at a rounding tie)."""
    still = SQUARE.split("[animation]")[0] + "[animation]\nduration = 1\nfps = 1\n"
    for options in ({}, {"samples": 4}):
        sharp = frame(still, 0.5, **options).color
        assert np.array_equal(frame(still, 0.5, Shutter(16), **options).color, sharp)
        assert np.array_equal(frame(still, 0.5, Shutter(7, 0.0, 1.0), **options).color, sharp)


def test_the_blurred_frame_is_the_same_bytes_on_every_run():
    one = frame(moving(0.3), 0.5, Shutter(16), samples=4).color
    two = frame(moving(0.3), 0.5, Shutter(16), samples=4).color
    assert np.array_equal(one, two)
    other = frame(moving(0.3), 0.5, Shutter(16), samples=4, seed=5).color
    assert not np.array_equal(one, other)                   # the seed is the pattern's



def test_fast_motion_is_noise_not_copies():
    """A bar one pixel wide sweeping 32 px in the shutter with 4 samples. Accumulated, the 4
    sub-frames share their times: 4 sharp copies, the same in every row. Per ray, each
    pixel's 4 times are its own (one a stratum, the bucket drawn per pixel): the hits fall
    all along the sweep and differ row by row, with the same light on average (each of the
    8 rows x 4 strata lights about one pixel at 1/4: 8 in all, give or take 1.3)."""
    text = moving(0.0).replace('transform = { rotate = [90, 0, 0] }',
                               'transform = { rotate = [90, 0, 0], scale = [0.125, 1, 1] }')
    copies = frame(text, 0.5, Shutter(4, method="accumulate")).color[..., 0] / 255
    assert np.all(copies == copies[0]) and np.count_nonzero(copies[0]) == 4
    assert sorted(set(np.round(copies[0] * 4, 2))) == [0.0, 1.0]
    spread = frame(text, 0.5, Shutter(4)).color[..., 0] / 255
    lit = np.nonzero(spread.any(axis=0))[0]
    assert len(lit) >= 12 and lit.max() - lit.min() >= 24, lit
    assert not np.all(spread == spread[0])
    assert abs(spread.sum() - copies.sum()) <= 4, (spread.sum(), copies.sum())


def test_the_time_plan_is_stratified():
    """Stratum k's rays pick buckets k·m … k·m + m - 1, whose times lie in [k/S, (k+1)/S)."""
    fractions, picks = ray_blur.time_plan((1, 3, 5), 16, 0, 0.5)
    m = ray_blur.buckets_per_stratum(16)
    assert len(fractions) == 16 * m == 64
    assert np.all(np.diff(fractions) > 0) and 0 <= fractions[0] and fractions[-1] < 1
    for k in range(16):
        assert np.all(picks[k] // m == k)
        assert np.all((fractions[picks[k]] >= k / 16) & (fractions[picks[k]] < (k + 1) / 16))


def test_the_blur_method_is_refused_where_it_cannot_be(tmp_path, capsys):
    from app.cli import main
    path = tmp_path / "square.toml"
    path.write_text(moving(0.0))
    assert main(["animate", str(path), "--out", str(tmp_path / "f"), "--motion-blur", "4",
                 "--blur-method", "per-ray"]) == 2
    assert "--blur-method per-ray is the ray tracer's: give --renderer raytrace" \
        in capsys.readouterr().err
    assert main(["animate", str(path), "--out", str(tmp_path / "f"),
                 "--blur-method", "accumulate"]) == 2
    assert "--blur-method is the motion blur's: give --motion-blur SAMPLES too" \
        in capsys.readouterr().err


def panning(left0: float) -> str:
    """The square still, left edge at ``left0``, and the keyed camera moving the other way at
    64 px/s: the picture of :func:`moving` (``left0``), seen by a moving eye."""
    still = SQUARE.split("[animation]")[0]
    view = 'vpn = [0, 0, 1], vup = [0, 1, 0], prp = [32, 0, 10], window = [0, 64, -4, 4]'
    return (still + '[animation]\nduration = 1\nfps = 1\n'
            'interpolation = "linear"\n'
            f'[[key]]\ntime = 0\nview = {{ vrp = [0, 0, 0], {view} }}\n'
            f'object.square = {{ translate = [{4 + left0}, 0, 0] }}\n'
            f'[[key]]\ntime = 1\nview = {{ vrp = [-64, 0, 0], {view} }}\n'
            f'object.square = {{ translate = [{4 + left0}, 0, 0] }}\n')


def test_a_moving_camera_blurs_per_ray_as_the_moving_square_does():
    """Each ray's primary ray comes from the keyed view at its time: the still square seen
    by a panning eye gets the same box-filtered coverage, within the same 2/64."""
    got = frame(panning(0.3), 0.5, Shutter(64))
    assert got.stats["motion blur"].startswith("per ray")
    assert np.array_equal(row(frame(panning(0.3), 0.5)),
                          (np.abs(np.arange(64) + 0.5 - 36.3) < 4).astype(float))
    error = np.abs(row(got) - coverage(0.3))
    assert error.max() <= 2 / 64 + 0.5 / 255, error.max()
    assert error.mean() < 1 / 128, error.mean()


def test_a_restored_simulation_starts_at_the_shutters_opening():
    """A ray's time may lie anywhere in its part of the shutter, before the accumulation's
    first midpoint: the state handed to a worker is the one at the opening."""
    assert Shutter(4).opens(1.0, 30.0) == pytest.approx(1.0 - 0.25 / 30.0)
    assert Shutter(4, 0.0, 0.5).opens(1.0, 30.0) == 1.0
    assert Shutter(1).opens(1.0, 30.0) == 1.0
    fractions, _ = ray_blur.time_plan((1, 2, 2), 4, 0, 1.0)
    assert fractions.min() < 0.5 / 4                   # before the first midpoint, here


def test_what_the_tracer_cannot_take_per_ray_is_accumulated_and_says_why():
    from core.paths import ROOT
    from core.scene.formats import load_scene
    scene = load_scene(str(ROOT / "scenes" / "fountain.toml"))
    anim = animation_of(scene)
    settings = RenderSettings.for_scene(scene, size=(40, 30), renderer="raytrace")
    got = render_at(anim, 0.5, settings, shutter=Shutter(2))
    assert got.stats["motion blur"] == ("accumulated (particles are drawn over the picture, "
                                        "not traced)")
    square = frame(moving(0.0), 0.5, Shutter(4), samples=4, pixel_filter="gaussian")
    assert square.stats["motion blur"] == "accumulated (per-ray blur box-filters its samples)"


def test_a_frame_traced_in_bands_keeps_the_bound(monkeypatch):
    """Past MAX_BAND_RAYS the plan is drawn band by band (here one row a band: 8 bands),
    each bucket's scene still made once: the same bound, the same bytes run to run, and a
    still scene still its sharp frame."""
    monkeypatch.setattr(ray_blur, "MAX_BAND_RAYS", 64 * 64)
    got = frame(moving(0.3), 0.5, Shutter(64)).color
    assert np.array_equal(got, frame(moving(0.3), 0.5, Shutter(64)).color)
    error = np.abs(got[..., 0] / 255 - coverage(0.3))
    assert error.max() <= 2 / 64 + 0.5 / 255 and error.mean() < 1 / 128
    assert not np.all(got == got[0])                        # each row its own draws
    still = SQUARE.split("[animation]")[0] + "[animation]\nduration = 1\nfps = 1\n"
    assert np.array_equal(frame(still, 0.5, Shutter(16)).color, frame(still, 0.5).color)
