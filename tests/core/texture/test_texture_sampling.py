"""Texture samplers, MIP chain, image files and procedural textures.

The samplers are held to hand values and to an independent numpy statement of GL's rules
(4.6 core, 8.14); the GL oracle itself (llvmpipe) is in test_texture_gl.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from core.texture import Texture, TextureError, load_image, procedural
from core.texture import sample as S
from core.texture.image import linear_to_srgb, mip_chain, srgb_to_linear

RNG = np.random.default_rng(11)


def _texture(h=4, w=8, wrap="repeat"):
    return Texture.from_array(RNG.random((h, w, 4)), wrap=wrap)


def _run(tex, filter_name, uv, duv=None):
    texels, levels = tex.packed()
    uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
    duv = np.zeros((len(uv), 4)) if duv is None else np.ascontiguousarray(duv, float).reshape(-1, 4)
    out = np.zeros((len(uv), 4))
    S.sample_many(texels, levels, tex.wrap_code, S.FILTERS[filter_name], uv, duv, out)
    return out


# ---------------------------------------------------------------- GL's rules in numpy

def _wrap_np(i, size, mode):
    if mode == "repeat":
        return np.mod(i, size)
    if mode == "clamp":
        return np.clip(i, 0, size - 1)
    a = np.mod(i, 2 * size) - size
    return (size - 1) - np.where(a >= 0, a, -(1 + a))


def _nearest_np(img, u, v, mode):
    h, w = img.shape[:2]
    i = _wrap_np(np.floor(u * w).astype(int), w, mode)
    j = _wrap_np(np.floor(v * h).astype(int), h, mode)
    return img[j, i]


def _bilinear_np(img, u, v, mode):
    h, w = img.shape[:2]
    x, y = u * w - 0.5, v * h - 0.5
    i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
    a, b = (x - i0)[:, None], (y - j0)[:, None]
    I0, I1 = _wrap_np(i0, w, mode), _wrap_np(i0 + 1, w, mode)
    J0, J1 = _wrap_np(j0, h, mode), _wrap_np(j0 + 1, h, mode)
    return ((1 - a) * (1 - b) * img[J0, I0] + a * (1 - b) * img[J0, I1]
            + (1 - a) * b * img[J1, I0] + a * b * img[J1, I1])


@pytest.mark.parametrize("mode", ["repeat", "clamp", "mirror"])
def test_wrap_hand_values(mode):
    expected = {  # size 4, indices -5 … 8
        "repeat": [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0],
        "clamp": [0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3],
        "mirror": [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0],
    }[mode]
    got = [S.wrap_index(i, 4, S.WRAPS[mode]) for i in range(-5, 9)]
    assert got == expected


@pytest.mark.parametrize("mode", ["repeat", "clamp", "mirror"])
def test_nearest_and_bilinear_match_gl_rules(mode):
    tex = _texture(5, 7, mode)
    img = tex.levels[0].astype(np.float64)
    uv = RNG.uniform(-2.5, 3.5, (2000, 2))
    np.testing.assert_allclose(_run(tex, "nearest", uv), _nearest_np(img, uv[:, 0], uv[:, 1], mode),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(_run(tex, "bilinear", uv),
                               _bilinear_np(img, uv[:, 0], uv[:, 1], mode), rtol=0, atol=1e-6)


def test_bilinear_hand_values():
    img = np.zeros((2, 2, 4))
    img[0, 0, 0], img[0, 1, 0], img[1, 0, 0], img[1, 1, 0] = 0.0, 1.0, 0.5, 0.25
    tex = Texture.from_array(img, wrap="clamp")
    centres = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
    assert _run(tex, "bilinear", centres)[:, 0].tolist() == [0.0, 1.0, 0.5, 0.25]
    # halfway between all four texel centres: the mean
    assert _run(tex, "bilinear", [(0.5, 0.5)])[0, 0] == pytest.approx(0.4375, abs=1e-12)
    # a quarter of the way from texel (0,0) towards (1,0)
    assert _run(tex, "bilinear", [(0.375, 0.25)])[0, 0] == pytest.approx(0.25, abs=1e-12)


def test_mip_chain_is_the_box_filter():
    img = RNG.random((8, 16, 4))
    levels = mip_chain(img)
    assert [lv.shape[:2] for lv in levels] == [(8, 16), (4, 8), (2, 4), (1, 2), (1, 1)]
    box = img.reshape(4, 2, 8, 2, 4).mean(axis=(1, 3))
    np.testing.assert_allclose(levels[1], box, atol=1e-6)
    np.testing.assert_allclose(levels[-1][0, 0], img.mean(axis=(0, 1)), atol=1e-6)


def test_mip_chain_odd_sizes_keep_the_mean():
    img = RNG.random((5, 3, 4))
    levels = mip_chain(img)
    assert [lv.shape[:2] for lv in levels] == [(5, 3), (2, 1), (1, 1)]
    for level in levels:
        np.testing.assert_allclose(level.mean(axis=(0, 1)), img.mean(axis=(0, 1)), atol=1e-6)


def test_trilinear_picks_the_level_of_the_footprint():
    tex = _texture(16, 16)
    texels, levels = tex.packed()
    uv = RNG.random((50, 2))
    # 4 texels a pixel along x, 1 along y: rho = 4, lambda = 2 exactly -> level 2 bilinear
    duv = np.tile([4 / 16, 0.0, 0.0, 1 / 16], (50, 1))
    level2 = np.array([S.bilinear(texels, levels, 0, 2, u, v) for u, v in uv])
    np.testing.assert_allclose(_run(tex, "trilinear", uv, duv), level2, atol=1e-12)
    # rho = 2^1.5: halfway between levels 1 and 2
    duv[:, 0] = 2 ** 1.5 / 16
    mid = 0.5 * (np.array([S.bilinear(texels, levels, 0, 1, u, v) for u, v in uv]) + level2)
    np.testing.assert_allclose(_run(tex, "trilinear", uv, duv), mid, atol=1e-12)
    # magnification: level 0, bilinear
    duv[:] = [0.1 / 16, 0, 0, 0.1 / 16]
    np.testing.assert_allclose(_run(tex, "trilinear", uv, duv), _run(tex, "bilinear", uv),
                               atol=1e-12)
    assert S.level_of_detail(levels, 3 / 16, 4 / 16, 0.0, 1 / 16) == pytest.approx(np.log2(5))


def test_anisotropic_probes_along_the_major_axis():
    tex = _texture(64, 64)
    texels, levels = tex.packed()
    u, v = 0.3, 0.6
    # isotropic footprint: one probe, the trilinear value
    iso = [2 / 64, 0, 0, 2 / 64]
    np.testing.assert_allclose(_run(tex, "anisotropic", [(u, v)], iso),
                               _run(tex, "trilinear", [(u, v)], iso), atol=1e-12)
    # 8 texels along x, 2 along y: 4 probes at the level of 8 / 4 = 2 texels (lambda = 1)
    d = [8 / 64, 0, 0, 2 / 64]
    probes = [S.mip_at(texels, levels, 0, 1.0, u + ((k + 0.5) / 4 - 0.5) * d[0], v)
              for k in range(4)]
    np.testing.assert_allclose(_run(tex, "anisotropic", [(u, v)], d)[0], np.mean(probes, axis=0),
                               atol=1e-12)


def test_constant_texture_is_constant_under_every_filter():
    tex = Texture.from_array(np.full((32, 32, 3), 0.3))
    uv = RNG.uniform(-3, 3, (200, 2))
    duv = RNG.uniform(-1, 1, (200, 4)) * 10 ** RNG.uniform(-4, 1, (200, 1))
    for name in S.FILTERS:
        np.testing.assert_allclose(_run(tex, name, uv, duv)[:, :3], 0.3, atol=1e-6)


def test_far_and_non_finite_coordinates_do_not_crash():
    tex = _texture()
    uv = np.array([[1e300, -1e300], [np.inf, 0.0], [np.nan, 0.5]])
    duv = np.array([[np.inf, 0, 0, 0], [np.nan, 0, 0, 0], [0, 0, 0, 0]])
    for name in S.FILTERS:
        _run(tex, name, uv, duv)         # any texel; no exception, no out-of-range read


def test_srgb_round_trip_and_hand_value():
    c = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(linear_to_srgb(srgb_to_linear(c)), c, atol=1e-12)
    assert srgb_to_linear(0.5) == pytest.approx(0.2140, abs=1e-4)
    assert srgb_to_linear(0.04) == pytest.approx(0.04 / 12.92)


# ---------------------------------------------------------------- files

def test_png_reads_with_v_up_and_srgb_decoded(tmp_path):
    img = np.zeros((2, 3, 3), np.uint8)
    img[0, 0] = (255, 0, 0)             # the picture's top-left
    img[1, 2] = (0, 128, 0)             # its bottom-right
    Image.fromarray(img).save(tmp_path / "t.png")
    tex = load_image(tmp_path / "t.png", "geometry[1].material.texture")
    assert tex.size == (3, 2) and tex.srgb
    assert tex.levels[0][1, 0, 0] == pytest.approx(1.0)                    # top row is v = 1
    assert tex.levels[0][0, 2, 1] == pytest.approx(srgb_to_linear(128 / 255), abs=1e-6)


def test_jpeg_reads(tmp_path):
    Image.fromarray(np.full((8, 8, 3), 200, np.uint8)).save(tmp_path / "t.jpg")
    tex = load_image(tmp_path / "t.jpg", "k")
    assert tex.levels[0][..., :3].mean() == pytest.approx(srgb_to_linear(200 / 255), abs=0.01)


def _bad_files(tmp_path):
    good = tmp_path / "good.png"
    Image.fromarray(np.zeros((64, 64, 3), np.uint8)).save(good)
    (tmp_path / "corrupt.png").write_bytes(good.read_bytes()[:60])
    (tmp_path / "notes.png").write_text("not an image at all\n")
    Image.new("1", (17000, 1)).save(tmp_path / "huge.png")
    return {"missing.png": "no such file", "corrupt.png": "corrupt",
            "notes.png": "not an image", "huge.png": "17000 x 1"}


def test_bad_texture_files_give_a_message_naming_file_and_key(tmp_path):
    for name, reason in _bad_files(tmp_path).items():
        with pytest.raises(TextureError) as info:
            load_image(tmp_path / name, "geometry[2].material.texture", shown=f"scenes/{name}")
        message = str(info.value)
        assert f"scenes/{name}" in message and "geometry[2].material.texture" in message
        assert reason in message


# ---------------------------------------------------------------- procedural

def test_checker_hand_values():
    tex = procedural.make("checker", scale=2, resolution=4, a=[1, 1, 1], b=[0, 0, 0])
    grey = tex.levels[0][..., 0]
    assert grey.tolist() == [[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 1], [0, 0, 1, 1]]


@pytest.mark.parametrize("name", ["value_noise", "perlin", "perlin_height", "bricks"])
def test_procedural_textures_tile(name):
    """Repeated, a procedural texture has no seam: the step across the wrap (last column to
    the first, last row to the first) is no larger than the steps inside, at the 99th
    percentile and on average. A texture that merely stops at its border is caught (the
    control below)."""
    img = procedural.make(name, resolution=128).levels[0][..., 0].astype(np.float64)
    _assert_seamless(img)


def test_the_checker_tiles():
    """Rolled by one square, across the wrap, the checker is its own negative: every square
    is whole, including those that the texture's border cuts."""
    for scale, resolution in [(8, 128), (4, 96), (10, 200)]:
        img = procedural.make("checker", scale=scale, resolution=resolution, a=[1, 1, 1],
                              b=[0, 0, 0]).levels[0][..., 0]
        _assert_checker_tiles(img, resolution // scale)
    with pytest.raises(ValueError, match="scale must be even"):
        procedural.make("checker", scale=5)          # would put two squares of a colour together


def _assert_checker_tiles(img, square):
    for axis in (0, 1):
        assert np.array_equal(np.roll(img, square, axis=axis), 1 - img)


def _assert_seamless(img):
    for axis in (0, 1):
        wrapped = np.concatenate([img, img.take([0], axis=axis)], axis=axis)
        steps = np.abs(np.diff(wrapped, axis=axis))
        inner, seam = np.delete(steps, -1, axis=axis), steps.take(-1, axis=axis)
        assert np.percentile(seam, 99) <= np.percentile(inner, 99) + 1e-6
        assert seam.mean() <= 2 * inner.mean() + 1e-6


def test_the_seam_checks_catch_a_texture_that_does_not_tile():
    """The controls: a wave whose period does not divide the texture; a checker whose border
    squares are cut short."""
    x = np.arange(128) / 128
    not_periodic = 0.5 + 0.5 * np.sin(2 * np.pi * 1.37 * x)[None, :] * np.ones((128, 1))
    with pytest.raises(AssertionError):
        _assert_seamless(not_periodic)
    cut = ((np.arange(128)[:, None] // 24 + np.arange(128)[None, :] // 24) % 2).astype(float)
    with pytest.raises(AssertionError):
        _assert_checker_tiles(cut, 24)


def test_noise_is_in_range_and_not_constant():
    for name in ("value_noise", "perlin"):
        img = procedural.make(name, resolution=64, scale=4).levels[0][..., 0]
        assert 0.0 <= img.min() and img.max() <= 1.0 and img.std() > 0.01


def test_demo_height_is_the_demo_function():
    from core.texture.bump_demo import demo_bump
    tex = procedural.make("demo_height", resolution=50, map=3)
    u, v = (7 + 0.5) / 50, (20 + 0.5) / 50
    expected = (demo_bump(3, 100 * u, -100 * (1 - v)) + 2) / 4
    assert tex.levels[0][20, 7, 0] == pytest.approx(expected, abs=1e-6)


def test_procedural_refuses_bad_parameters():
    with pytest.raises(ValueError, match="unknown procedural"):
        procedural.make("marble")
    with pytest.raises(ValueError, match="scale"):
        procedural.make("checker", scale=2.5)
    with pytest.raises(ValueError, match="resolution"):
        procedural.make("checker", resolution=10**6)
    with pytest.raises(ValueError, match="checker"):
        procedural.make("checker", colour=1)
