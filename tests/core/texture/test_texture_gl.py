"""The texture oracle: our samplers against Mesa's llvmpipe on the same textured floor.

The floor is a quad seen at a grazing angle under perspective, (u, v) repeating 4 x 5 times,
a 64 x 64 texture of random texels (the hardest case: neighbours differ by anything) with
its MIP chain uploaded level by level. Our side runs the project's own stages (N_per, clipping,
the z-buffer) and the renderers' sampler over the tutorial's plane constants (``unlit_texture``
below); llvmpipe draws the same triangles through the same world-to-clip matrix. Compared
away from the floor's edges (two pixels in):

- GL_NEAREST: equal, except where a pixel centre maps within 1e-4 texel of a texel boundary
  (there the choice is float32 rounding in llvmpipe: 13 of ~49,000 pixels here);
- GL_LINEAR: within 1/255 (measured: at most 1/255);
- GL_LINEAR_MIPMAP_LINEAR: GL leaves the level of detail to the implementation. A texture
  whose level k is the constant k/8 makes each side show its λ: llvmpipe's stays within 0.09 of
  ours (GL's formula ρ = max(|∂(u,v)/∂x|, |∂(u,v)/∂y|) evaluated exactly at the pixel centre;
  llvmpipe differences 2 x 2 quads and approximates log2), and the colours of the random
  texture then differ by at most 9/255 (mean 0.22/255).
"""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import View, normalizing_transform
from core.pipeline.clip_polygon import clip_triangles
from core.pipeline.project import triangle_matrix, viewport
from core.pipeline.raster import rasterize
from core.pipeline.vertex_kernels import transform_affine, transform_projective
from core.texture import Texture
from core.texture.sample import FILTERS
from tools import llvmpipe_context
from core.jit import njit, prange
from core.texture.sample import sample
from core.texture.tutorial import triangle_constants, uv_at

SIZE = 256


@njit(cache=True, parallel=True, nogil=True)
def unlit_texture(tri, constants, texels, levels, wrap, filter_, background, out):
    """``out (H, W, 4)`` float: the filtered texel at each covered pixel (the tutorial's
    plane constants, :func:`core.texture.tutorial.uv_at`, and the sampler the renderers use),
    ``background`` elsewhere: the texture alone, no light, as the GL oracle draws it."""
    height, width = tri.shape
    for j in prange(height):
        for i in range(width):
            t = tri[j, i]
            if t < 0:
                for k in range(4):
                    out[j, i, k] = background[k]
                continue
            u, v, dudx, dvdx, dudy, dvdy = uv_at(constants, t, i, j)
            r, g, b, a = sample(texels, levels, wrap, filter_, u, v, dudx, dvdx, dudy, dvdy)
            out[j, i, 0], out[j, i, 1], out[j, i, 2], out[j, i, 3] = r, g, b, a

TEXELS = 64
FLOOR = np.array([[-4, 0, -8], [4, 0, -8], [4, 0, 2], [-4, 0, 2]], float)
# an offset keeps pixel centres off exact texel boundaries (the quad is symmetric)
FLOOR_UV = np.array([[0, 0], [4, 0], [4, 5], [0, 5]], float) + [0.01234567, 0.0456789]
FLOOR_TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])
GRAZING = View(vrp=(0, 0, 0), vpn=(0, 0.25, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
               prp=(0, 0, 3), front=2.5, back=-30, label="grazing floor")


@pytest.fixture(scope="module")
def gl():
    from app.oracles.texture_gl import TextureGL
    oracle = TextureGL((SIZE, SIZE), ctx=llvmpipe_context())   # only the context may be missing
    assert "llvmpipe" in oracle.renderer_name
    yield oracle
    oracle.release()


def _ours(texture: Texture, filter_name: str):
    """The floor through our stages; returns the picture, the coverage and the uv frame."""
    n, z_min = normalizing_transform(GRAZING, "perspective")
    m = triangle_matrix("perspective", z_min, viewport(GRAZING.window, SIZE, SIZE))
    clipped = clip_triangles(transform_affine(n, FLOOR), FLOOR_TRIANGLES, FLOOR_UV,
                             "perspective", z_min)
    device, inv_w = transform_projective(m, clipped.points)
    device_h = np.column_stack([clipped.points, np.ones(len(clipped.points))]) @ m.T
    vis = rasterize(device, inv_w, clipped.triangles, SIZE, SIZE)
    constants = triangle_constants(device_h, clipped.triangles, clipped.attrs, SIZE)
    texels, levels = texture.packed()
    out = np.zeros((SIZE, SIZE, 4))
    tri = vis.tri.astype(np.int64)
    unlit_texture(tri, constants, texels, levels, texture.wrap_code, FILTERS[filter_name],
                  np.full(4, -1.0), out)
    return out, tri, constants


def _inner(mask, pixels=2):
    for _ in range(pixels):
        mask = (mask & np.roll(mask, 1, 0) & np.roll(mask, -1, 0)
                & np.roll(mask, 1, 1) & np.roll(mask, -1, 1))
    return mask


def _compare(gl, texture, filter_name):
    ours, tri, constants = _ours(texture, filter_name)
    theirs = gl.render(FLOOR, FLOOR_TRIANGLES, FLOOR_UV, GRAZING, "perspective", texture,
                       filter_name)
    inner = _inner((tri >= 0) & (theirs[..., 0] >= 0))
    assert inner.sum() > 40_000
    diff = np.abs(np.round(ours[..., :3] * 255) - np.round(theirs[..., :3] * 255)).max(axis=2)
    return diff, inner, tri, constants, ours, theirs


def _random_texture(wrap="repeat"):
    return Texture.from_array(np.random.default_rng(0).random((TEXELS, TEXELS, 4)), wrap=wrap)


def test_nearest_matches_llvmpipe(gl):
    diff, inner, tri, constants, *_ = _compare(gl, _random_texture(), "nearest")
    on_boundary = np.zeros_like(inner)
    for j, i in zip(*np.nonzero(inner)):
        u, v, *_ = uv_at(constants, tri[j, i], i, j)
        x, y = u * TEXELS, v * TEXELS
        on_boundary[j, i] = min(abs(x - round(x)), abs(y - round(y))) < 1e-4
    assert on_boundary.sum() < 0.001 * inner.sum()
    assert diff[inner & ~on_boundary].max() == 0       # measured: 0 (README: equal)


@pytest.mark.parametrize("wrap", ["repeat", "clamp"])
def test_bilinear_matches_llvmpipe(gl, wrap):
    diff, inner, *_ = _compare(gl, _random_texture(wrap), "bilinear")
    assert diff[inner].max() <= 1                     # measured: 1 (README: at most 1/255)


def test_trilinear_level_of_detail_against_llvmpipe(gl):
    base = _random_texture()
    levels = [np.full(lv.shape, k / 8.0, np.float32) for k, lv in enumerate(base.levels)]
    marked = Texture(levels=levels)
    ours, tri, *_ = _ours(marked, "trilinear")
    theirs = gl.render(FLOOR, FLOOR_TRIANGLES, FLOOR_UV, GRAZING, "perspective", marked,
                       "trilinear")
    inner = _inner((tri >= 0) & (theirs[..., 0] >= 0))
    ours_lambda, gl_lambda = ours[..., 0][inner] * 8, theirs[..., 0][inner] * 8
    minified = (ours_lambda > 0.05) & (ours_lambda < len(levels) - 1.1)
    assert minified.sum() > 10_000                  # the floor spans many levels
    assert np.abs(gl_lambda - ours_lambda)[minified].max() < 0.095   # measured 0.0885 (README: 0.09)
    diff, inner, *_ = _compare(gl, base, "trilinear")
    assert diff[inner].max() <= 9 and diff[inner].mean() < 0.45   # measured 9, mean 0.39


FLOOR_SCENE = """
name = "oracle floor"
shading = "phong"
ambient = [1, 1, 1]
background = [0, 0, 0]
[[geometry]]
generator = "plane"
params = {{ size = 10, subdivisions = 3 }}
transform = {{ translate = [0.0123, -1, 0.0456] }}
material = {{ ka = 1, kd = 0, ks = 0, od = [1, 1, 1], texture = "noise.png", uv_scale = [3, 3] }}
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0.3, 1]
vup = [0, 1, 0]
window = [-1, 1, -1, 1]
prp = [0, 0, 2.5]
front = 2
back = -40
[[light]]
direction = [0, 1, 0]
"""


@pytest.mark.parametrize("filter_name,tolerance", [("nearest", 0), ("bilinear", 1),
                                                   ("trilinear", 11)])
def test_the_renderer_against_llvmpipe_on_a_textured_floor(gl, tmp_path, filter_name, tolerance):
    """The whole path: a PNG (sRGB) read by the scene reader, the plane generator's (u, v),
    the textured shader in the z-buffer renderer (unlit: ambient 1, k_a 1, so the pixel is the
    filtered texture encoded back to sRGB) against llvmpipe drawing the same mesh and MIP chain
    and encoding the same way."""
    from core import render
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    from core.texture.material import maps_of
    rng = np.random.default_rng(5)
    from PIL import Image
    Image.fromarray(rng.integers(0, 256, (64, 64, 3), dtype=np.uint8)).save(tmp_path / "noise.png")
    (tmp_path / "floor.toml").write_text(FLOOR_SCENE.format())
    scene = load_scene(tmp_path / "floor.toml")
    assert not scene.view_messages
    frame = render(scene, scene.views[0], RenderSettings.for_scene(
        scene, size=(SIZE, SIZE), texture_filter=filter_name))
    mesh = scene.meshes[0]
    maps = maps_of(mesh.material)
    theirs = gl.render(mesh.positions, mesh.triangles, mesh.uv * np.asarray(maps.uv_scale),
                       scene.views[0], "perspective", maps.color, filter_name, encode_srgb=True)
    covered = (frame.depth > -np.inf) & (theirs[..., 0] >= 0)
    inner = _inner(covered)
    assert inner.sum() > 20_000
    gl8 = np.floor(np.clip(theirs[..., :3], 0, 1) * 255 + 0.5)
    diff = np.abs(frame.color.astype(int) - gl8).max(axis=2)[inner]
    assert diff.max() <= tolerance, (diff.max(), diff.mean())
    assert diff.mean() < 0.6            # measured: nearest 0, bilinear 0.003, trilinear 0.34


def _bilinear_reduce(fine: np.ndarray, h2: int, w2: int) -> np.ndarray:
    """llvmpipe's glGenerateMipmap, written here from its description (gallium's
    util_gen_mipmap blits each level from the one above with GL_LINEAR): the fine level
    sampled bilinearly, edges clamped, at each coarse texel's centre."""
    def weights(n, n2):
        w = np.zeros((n2, n))
        for i in range(n2):
            x = (i + 0.5) * n / n2 - 0.5
            x0 = int(np.floor(x))
            for k, t in ((x0, 1 - (x - x0)), (x0 + 1, x - x0)):
                w[i, min(max(k, 0), n - 1)] += t
        return w
    coarse = np.tensordot(weights(fine.shape[0], h2), fine, axes=(1, 0))
    return np.tensordot(weights(fine.shape[1], w2), coarse, axes=(1, 1)).transpose(1, 0, 2)


@pytest.mark.parametrize("height,width", [(64, 64), (64, 32), (16, 128), (37, 23), (5, 7)])
def test_the_mip_chain_against_gl_generate_mipmap(gl, height, width):
    """Our MIP chain (core.texture.image.mip_chain) against the levels llvmpipe's
    glGenerateMipmap makes from the same base level, read back level by level.

    Even sizes: the same 2 x 2 box, equal to float32 rounding (measured 6e-8). Odd sizes: GL
    leaves the filter to the implementation; llvmpipe's levels equal the bilinear blit model
    above (measured 2e-6), and ours differ from them on purpose: our coarse texel averages
    exactly its footprint, so every level keeps the base level's mean, which GL's does not.
    """
    from core.texture.image import mip_chain
    image = np.random.default_rng(height * width).random((height, width, 4)).astype(np.float32)
    tex = gl.ctx.texture((width, height), 4, image.tobytes(), dtype="f4")
    tex.build_mipmaps()
    ours = mip_chain(image.astype(np.float64))
    levels = [np.frombuffer(tex.read(level=k), np.float32).reshape(lv.shape).astype(np.float64)
              for k, lv in enumerate(ours)]
    tex.release()
    assert ours[-1].shape[:2] == (1, 1)
    even = all(lv.shape[0] in (1, 2 * nxt.shape[0]) and lv.shape[1] in (1, 2 * nxt.shape[1])
               for lv, nxt in zip(ours, ours[1:]))
    for k in range(1, len(ours)):
        assert abs(ours[k].mean(dtype=np.float64) - ours[0].mean(dtype=np.float64)) < 1e-6  # keeps the mean
        if even:
            assert np.abs(levels[k] - ours[k]).max() < 1e-6
        else:
            model = _bilinear_reduce(levels[k - 1], *ours[k].shape[:2])
            assert np.abs(levels[k] - model).max() < 1e-5
    if not even:
        assert max(np.abs(levels[k] - ours[k]).max() for k in range(1, len(ours))) > 0.01
