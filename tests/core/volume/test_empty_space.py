"""Empty-space skipping (core.volume.raymarch): the blocks a ray jumps add nothing, so the
marched numbers are those of the march that takes every sample, to the bit; the blocks' σ = 0
test against σ sampled densely; a constant volume whose blocks are all empty or all full; a
transfer function of one point; blocks of one value composited in closed form, against the
march of every sample."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.rays import camera_rays
from core.camera.view import View
from core.scene.model import Light
from core.shading.illumination import pack_ambient, pack_eye, pack_lights
from core.camera.view import eye_from_view
from core.volume import generators
from core.volume.data import Volume
from core.volume.raymarch import (BLOCK, COARSE, EARLY_TERMINATION, block_constants,
                                  block_ranges, coarse_blocks, empty_blocks, march_volume)
from core.renderers.volume.draw import step_of

TRANSFER = np.array([[0.0, 0, 0, 0, 0], [0.15, 0.2, 0.3, 0.6, 0], [0.2, 0.45, 0.6, 0.9, 0.9],
                     [0.25, 0.9, 0.7, 0.3, 1.5], [0.3, 1, 0.55, 0.2, 12], [1, 1, 1, 1, 1.5]])


def _rays(view, size, projection="perspective"):
    origins, directions, t_lo, t_hi = camera_rays(view, projection, size, size, ((0.5, 0.5),),
                                                  True)
    return origins, directions, t_lo, t_hi, eye_from_view(view, projection)


def _march(volume, rays, skip_empty=True, skip_constant=False):
    origins, directions, t_lo, t_hi, eye = rays
    return march_volume(volume, origins, directions, t_lo, t_hi, step_of(volume),
                        pack_lights([Light(position=(4, 5, 6))]), pack_ambient((0.2,) * 3),
                        pack_eye(eye), skip_empty=skip_empty, skip_constant=skip_constant)


def _phantom(side, mode, lighting, transfer=TRANSFER):
    values, spacing = generators.shepp_logan(side)
    return Volume(values=values, spacing=spacing, mode=mode, lighting=lighting,
                  transfer=transfer)


VIEW = View(vrp=(0, 0, 0), vpn=(0.5, 0.35, 1), vup=(0, 1, 0),
            window=(-1.25, 1.25, -1.25, 1.25), prp=(0, 0, 6), front=2, back=-2)
MODES = [("emission-absorption", "gradient"), ("emission-absorption", "none"), ("mip", "none")]


@pytest.mark.parametrize("mode, lighting", [("emission-absorption", "gradient"),
                                            ("emission-absorption", "none"), ("mip", "none")])
def test_skipping_empty_blocks_gives_the_march_of_every_sample_to_the_bit(mode, lighting):
    values, spacing = generators.shepp_logan(48)
    values = np.pad(values, 24)                      # room round the head: empty coarse blocks
    volume = Volume(values=values, spacing=spacing, mode=mode, lighting=lighting,
                    transfer=TRANSFER)
    view = View(vrp=(0, 0, 0), vpn=(0.5, 0.35, 1), vup=(0, 1, 0),
                window=(-1.25, 1.25, -1.25, 1.25), prp=(0, 0, 6), front=2, back=-2)
    rays = _rays(view, 40)
    skipped, every = _march(volume, rays), _march(volume, rays, skip_empty=False)
    lows, highs = block_ranges(volume)
    empty = empty_blocks(TRANSFER, lows, highs)
    assert 0 < empty.sum() < empty.size              # some blocks are jumped, some are not
    assert coarse_blocks(empty, highs)[0].any()      # and some coarse blocks
    for got, want in zip(skipped, every):
        assert np.array_equal(got, want)
    if mode == "mip":
        assert np.isfinite(skipped[2]).sum() > 100    # rays that met the grid
    else:
        assert (skipped[1] < 0.9).sum() > 100         # rays that met the medium


def test_block_ranges_hold_every_sample_a_blocks_cells_read():
    values = np.random.default_rng(1).random((19, 17, 9)).astype(np.float32)
    lows, highs = block_ranges(Volume(values=values))
    assert lows.shape == (3, 2, 1)                   # ceil(cells / BLOCK) a side
    for b in np.ndindex(lows.shape):
        cells = values[tuple(slice(BLOCK * i, BLOCK * (i + 1) + 1) for i in b)]
        assert lows[b] == cells.min() and highs[b] == cells.max()


def test_a_block_is_empty_exactly_where_dense_samples_of_sigma_are_all_zero():
    rng = np.random.default_rng(7)
    transfers = [TRANSFER, np.array([[0.5, 1, 1, 1, 0.0]]), np.array([[0.5, 1, 1, 1, 2.0]]),
                 np.array([[0.2, 1, 1, 1, 0.0], [0.4, 1, 1, 1, 3.0], [0.6, 1, 1, 1, 0.0]]),
                 np.array([[0.2, 1, 1, 1, 1.0], [0.4, 1, 1, 1, 0.0]])]
    ends = np.sort(rng.choice(np.linspace(-0.2, 1.2, 57), (400, 2)), axis=1)
    lows, highs = ends[:, 0], ends[:, 1]
    for transfer in transfers:
        got = empty_blocks(transfer, lows, highs)
        for lo, hi, empty in zip(lows, highs, got):
            values = np.concatenate([np.linspace(lo, hi, 301),
                                     transfer[(transfer[:, 0] >= lo) & (transfer[:, 0] <= hi), 0]])
            assert empty == (np.interp(values, transfer[:, 0], transfer[:, 4]).max() == 0.0)


def _slab_rays(n):
    """Rays along −z through an n x n grid of points over [−0.9, 0.9]², from z = 5."""
    c = np.linspace(-0.9, 0.9, n)
    x, y = np.meshgrid(c, c)
    origins = np.stack([x.ravel(), y.ravel(), np.full(n * n, 5.0)], 1)
    directions = np.tile([0.0, 0.0, -1.0], (n * n, 1))
    eye = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
               prp=(0, 0, 6), front=3, back=-3)
    return origins, directions, np.zeros(n * n), np.full(n * n, np.inf), \
        eye_from_view(eye, "parallel")


@pytest.mark.parametrize("transfer", [np.array([[0.0, 0.5, 0.5, 0.5, 0.0],
                                                [1.0, 0.5, 0.5, 0.5, 2.0]]),
                                      np.array([[0.7, 0.5, 0.5, 0.5, 1.0]])],
                         ids=["ramp", "one point"])
def test_a_constant_volume_every_block_full_is_the_closed_form(transfer):
    # the cube [−1, 1]³ of constant value 0.5: σ = 1 (the ramp's middle; the one point's
    # everywhere), so each ray along z through it leaves c (1 − e^{−2σ}) and T = e^{−2σ}
    volume = Volume(values=np.full((33, 33, 33), 0.5, np.float32), spacing=(1 / 16,) * 3,
                    lighting="none", transfer=transfer)
    assert not empty_blocks(transfer, *block_ranges(volume)).any()
    color, through, _ = _march(volume, _slab_rays(7))
    assert np.allclose(through, np.exp(-2.0), rtol=1e-12, atol=0)
    assert np.allclose(color, 0.5 * (1 - np.exp(-2.0)), rtol=1e-12, atol=0)


def test_a_constant_volume_every_block_empty_lets_all_light_through():
    transfer = np.array([[0.0, 1, 1, 1, 0.0], [0.6, 1, 1, 1, 0.0], [1.0, 1, 1, 1, 4.0]])
    volume = Volume(values=np.full((33, 33, 33), 0.5, np.float32), spacing=(1 / 16,) * 3,
                    lighting="gradient", transfer=transfer)
    assert empty_blocks(transfer, *block_ranges(volume)).all()
    color, through, _ = _march(volume, _slab_rays(7))
    assert np.all(color == 0.0) and np.all(through == 1.0)
    mip = Volume(values=volume.values, spacing=volume.spacing, mode="mip")
    assert np.all(_march(mip, _slab_rays(7))[2] == np.float32(0.5))


def test_the_kept_gradients_are_central_differences_one_sided_at_the_border():
    from core.volume.raymarch import sample_gradients
    values = np.random.default_rng(3).random((6, 7, 5)).astype(np.float32)
    got = sample_gradients(Volume(values=values, lighting="gradient"))
    want = np.stack(np.gradient(values.astype(np.float64)), -1)      # numpy's edge_order=1
    assert got.shape == (6, 7, 5, 3)
    assert np.allclose(got, want, rtol=0, atol=1e-6)


@pytest.mark.parametrize("mode, lighting", MODES)
def test_blocks_of_one_value_in_closed_form_give_the_march_of_every_sample(mode, lighting):
    volume = _phantom(96, mode, lighting)
    rays = _rays(VIEW, 40)
    closed, every = _march(volume, rays, skip_constant=True), _march(volume, rays, False)
    lows, highs = block_ranges(volume)
    constant = ~np.isnan(block_constants(volume, 1 if lighting == "gradient" else 0))
    assert (constant & ~empty_blocks(TRANSFER, lows, highs)).sum() > 50   # blocks it sums
    for got, want in zip(closed, every):
        if mode == "mip":
            assert np.array_equal(got, want)      # the same value, taken once
        else:                                     # the same sum, regrouped
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    if mode != "mip":
        assert (closed[1] < 0.9).sum() > 100


def test_a_block_is_one_value_exactly_where_its_samples_and_margin_are():
    rng = np.random.default_rng(3)
    values = np.zeros((27, 19, 12), np.float32)
    values[rng.random(values.shape) < 0.002] = 1.0        # a few lone samples
    values[20:, :, :] = 0.5
    volume = Volume(values=values)
    for margin in (0, 1):
        got = block_constants(volume, margin)
        assert got.shape == (4, 3, 2)
        for b in np.ndindex(got.shape):
            reads = values[tuple(slice(max(BLOCK * i - margin, 0), BLOCK * (i + 1) + 1 + margin)
                                 for i in b)]
            if (reads == reads.flat[0]).all():
                assert got[b] == reads.flat[0]
            else:
                assert np.isnan(got[b])
        assert np.isfinite(got).sum() > 3 and np.isnan(got).sum() > 3


def test_a_ray_ending_early_inside_a_block_of_one_value_ends_where_every_sample_does():
    values = np.full((33, 33, 33), 0.8, np.float32)        # every block one value, dense
    transfer = np.array([[0.0, 1, 0.5, 0.25, 40.0], [1.0, 1, 0.5, 0.25, 40.0]])
    volume = Volume(values=values, spacing=(1 / 16,) * 3, transfer=transfer)
    rays = _rays(VIEW, 24)
    closed, every = _march(volume, rays, skip_constant=True), _march(volume, rays, False)
    assert (every[1] < EARLY_TERMINATION).sum() > 100       # rays that ended early
    np.testing.assert_allclose(closed[0], every[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(closed[1], every[1], rtol=0, atol=1e-15)


def test_a_coarse_block_is_empty_where_all_its_blocks_are_and_holds_their_largest_sample():
    rng = np.random.default_rng(5)
    empty = rng.random((9, 5, 4)) < 0.9
    highs = rng.random((9, 5, 4)).astype(np.float32)
    coarse_empty, coarse_highs = coarse_blocks(empty, highs)
    assert coarse_empty.shape == coarse_highs.shape == (3, 2, 1)   # ceil(blocks / COARSE)
    for c in np.ndindex(coarse_empty.shape):
        part = tuple(slice(COARSE * i, COARSE * (i + 1)) for i in c)
        assert coarse_empty[c] == empty[part].all()
        assert coarse_highs[c] == highs[part].max()
    assert coarse_empty.any() and not coarse_empty.all()
