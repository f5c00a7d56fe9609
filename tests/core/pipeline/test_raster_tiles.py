"""The tiled rasterizer's hierarchical z (core/pipeline/raster.py) changes no pixel.

Hierarchical z skips triangles and 8 x 8 blocks it proves hidden, and a tile whose later
triangles look nearer is drawn last to first with ``z > zbuffer``. Each must give exactly the
buffers of the plain z-buffer (the same kernels with hierarchical z off) and the depth and
winning triangle of the course's scan-line rasterizer, an independent algorithm. Large
frames go in batches, the later ones set up against the earlier ones' coarse z: every test
runs both ways.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.pipeline.layers import depth_layers
from core.pipeline import raster, raster_scanline


@pytest.fixture(autouse=True, params=["one batch", "batches"])
def batching(request, monkeypatch):
    """Every test twice: as one batch, and in the two batches of a large frame (whose second
    setup drops triangles behind the first batch's coarse z), by lowering the threshold."""
    if request.param == "batches":
        monkeypatch.setattr(raster, "BATCH_FROM", 64)
    return request.param


def _plain(xy_z, inv_w, tris, w, h, monkeypatch):
    with monkeypatch.context() as m:
        m.setattr(raster, "HIERARCHICAL_Z", False)
        return raster.rasterize(xy_z, inv_w, tris, w, h)


def _checked_against_both(xy_z, inv_w, tris, w, h, monkeypatch):
    """The tiled rasterizer's buffer, asserted equal to the plain z-buffer's (every array) and
    to the scan-line oracle's (ids and depths)."""
    fast = raster.rasterize(xy_z, inv_w, tris, w, h)
    plain = _plain(xy_z, inv_w, tris, w, h, monkeypatch)
    for name in ("depth", "tri", "b1", "b2"):
        assert np.array_equal(getattr(fast, name), getattr(plain, name)), name
    oracle = raster_scanline.rasterize(xy_z, inv_w, tris, w, h)
    assert np.array_equal(fast.tri, oracle.tri) and np.array_equal(fast.depth, oracle.depth)
    return fast


@pytest.mark.parametrize("front_to_back", [True, False])
def test_layer_stacks_equal_the_plain_zbuffer_and_the_scanline_oracle(front_to_back, monkeypatch):
    w, h = 150, 100                               # 3 x 2 tiles, the last ones partial
    xy_z, inv_w, tris = depth_layers(12, 300, w, h, front_to_back)
    fast = _checked_against_both(xy_z, inv_w, tris, w, h, monkeypatch)
    # every pixel shows the nearest layer: the first drawn front to back, the last otherwise
    layer = fast.tri // (len(tris) // 12)
    assert np.all(layer == (0 if front_to_back else 11))
    assert np.all(fast.depth == np.float64(-0.1))


def test_ties_go_to_the_later_triangle_in_either_drawing_order(monkeypatch):
    # Three equal-depth copies of each layer, nearest layer last (so tiles run last to first):
    # the winner at every pixel must still be the last copy of the nearest layer.
    w, h = 130, 70
    xy_z, inv_w, tris = depth_layers(6, 200, w, h, front_to_back=False)
    n = len(tris) // 6
    stack = np.concatenate([np.concatenate([tris[k * n:(k + 1) * n]] * 3) for k in range(6)])
    fast = raster.rasterize(xy_z, inv_w, stack, w, h)
    plain = _plain(xy_z, inv_w, stack, w, h, monkeypatch)
    assert np.array_equal(fast.tri, plain.tri) and np.array_equal(fast.b1, plain.b1)
    assert np.all(fast.tri >= 5 * 3 * n + 2 * n)   # the third copy of the nearest layer


def test_hidden_triangles_cut_through_visible_ones(monkeypatch):
    # Random overlapping triangles at random slopes over a full-frame background, in a random
    # order: the coarse z must never hide a pixel that a triangle wins.
    rng = np.random.default_rng(5)
    w, h = 200, 140
    bg, bg_w, bg_t = depth_layers(1, 50, w, h)
    n = 4000
    centres = rng.uniform([0, 0], [w, h], size=(n, 1, 2))
    pts = (centres + rng.normal(scale=12, size=(n, 3, 2))).reshape(-1, 2)
    xy_z = np.concatenate([bg, np.column_stack([pts, rng.uniform(-1, 0, 3 * n)])])
    tris = np.concatenate([bg_t, len(bg) + np.arange(3 * n).reshape(n, 3)])
    inv_w = rng.uniform(0.3, 3.0, len(xy_z))
    for order in (np.arange(len(tris)), rng.permutation(len(tris))):
        fast = raster.rasterize(xy_z, inv_w, tris[order], w, h)
        plain = _plain(xy_z, inv_w, tris[order], w, h, monkeypatch)
        for name in ("depth", "tri", "b1", "b2"):
            assert np.array_equal(getattr(fast, name), getattr(plain, name)), name
        serial = raster.rasterize(xy_z, inv_w, tris[order], w, h, parallel=False)
        assert np.array_equal(fast.tri, serial.tri) and np.array_equal(fast.b2, serial.b2)


def test_batches_drop_hidden_triangles_in_setup(monkeypatch):
    """The point of the batches: deep in a stack, triangles never reach a bin. Counted by the
    scene slots the last batch used (front to back: its layers are all hidden)."""
    monkeypatch.setattr(raster, "BATCH_FROM", 64)
    w, h = 128, 128
    xy_z, inv_w, tris = depth_layers(64, 200, w, h, front_to_back=True)
    buffer = raster.rasterize(xy_z, inv_w, tris, w, h)
    assert np.all(buffer.tri < len(tris) // 64)          # the nearest layer, drawn first
    # the last batch (triangles n/64 .. n) was set up in chunks; chunk c's slots start at
    # c m / chunks and end at chunk_end[c]: nothing was kept
    ends = buffer._scene.chunk_end
    m = len(tris) - len(tris) // 64
    starts = np.arange(len(ends)) * m // len(ends)
    assert np.array_equal(ends, starts)


def _screen_winding(xy_z, tris) -> np.ndarray:
    """+1 for a triangle counter-clockwise on the screen (y up: a front face), -1 clockwise."""
    p = xy_z[tris]
    area = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) \
        - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1])
    return np.sign(area)


def _wound(tris, winding, xy_z, want) -> np.ndarray:
    """``tris`` turned so that each has screen winding ``want``."""
    return np.where((winding == want)[:, None], tris, tris[:, ::-1])


def test_an_open_mesh_draws_its_front_faces_first_and_changes_no_pixel(monkeypatch):
    # A sphere with its cap cut off, seen through the hole: back faces show. Each bin lists
    # its front faces first; the buffers are still those of the plain z-buffer in triangle
    # order and of the scan-line oracle.
    import trimesh
    w, h = 160, 120
    mesh = trimesh.creation.uv_sphere(radius=1.0, count=[24, 32])
    keep = mesh.triangles_center[:, 2] < 0.6            # the cap off, facing the viewer
    positions, tris = mesh.vertices, mesh.faces[keep]
    tilt = np.array([[1, 0, 0], [0, np.cos(0.5), -np.sin(0.5)], [0, np.sin(0.5), np.cos(0.5)]])
    p = positions @ tilt.T
    xy_z = np.column_stack([w / 2 + 45 * p[:, 0], h / 2 + 45 * p[:, 1], p[:, 2] / 4 - 0.5])
    inv_w = np.ones(len(xy_z))
    winding = _screen_winding(xy_z, tris)
    assert (winding > 0).any() and (winding < 0).any()
    fast = _checked_against_both(xy_z, inv_w, tris, w, h, monkeypatch)
    assert (winding[fast.tri[fast.tri >= 0]] < 0).any()  # a back face is seen, through the hole
    # the (last batch's) bins: front faces before the split, back faces after it
    scene = fast._scene
    n_tiles = -(-w // raster.TILE) * -(-h // raster.TILE)
    start, split = scene.tile_start[:n_tiles + 1], scene.tile_split[:n_tiles]
    for k in range(n_tiles):
        ids = scene.tri[scene.bins[start[k]:start[k + 1]]]
        sides = winding[ids]
        assert np.all(sides[:split[k] - start[k]] > 0) and np.all(sides[split[k] - start[k]:] < 0)
        front, back = ids[:split[k] - start[k]], ids[split[k] - start[k]:]
        assert np.all(np.diff(front) > 0) and np.all(np.diff(back) > 0)   # triangle order
    assert (split > start[:-1]).any() and (split < start[1:]).any()


def test_a_tie_between_a_front_and_a_back_face_goes_to_the_later_one(monkeypatch):
    # A near layer drawn twice at one depth, first as back faces and then as front faces,
    # over a far layer of back faces (so the front faces lie nearer: the bins draw them
    # first). The later copy, the front faces, must win every pixel of the near layer,
    # though the earlier copy is drawn after it.
    w, h = 130, 90
    xy_z, inv_w, tris = depth_layers(2, 200, w, h, front_to_back=True)
    n = len(tris) // 2
    winding = _screen_winding(xy_z, tris)
    near, far = tris[:n], tris[n:]
    stack = np.concatenate([_wound(near, winding[:n], xy_z, -1),
                            _wound(near, winding[:n], xy_z, +1),
                            _wound(far, winding[n:], xy_z, -1)])
    assert raster._fronts_nearer(np.array([[3.0 * -0.1 * n, n, 3.0 * -0.5 * n, 2 * n]]))
    fast = raster.rasterize(xy_z, inv_w, stack, w, h)
    plain = _plain(xy_z, inv_w, stack, w, h, monkeypatch)
    assert np.array_equal(fast.tri, plain.tri) and np.array_equal(fast.b1, plain.b1)
    assert np.all((fast.tri >= n) & (fast.tri < 2 * n))   # the second copy, a front face
    serial = raster.rasterize(xy_z, inv_w, stack, w, h, parallel=False)
    assert np.array_equal(fast.tri, serial.tri)
