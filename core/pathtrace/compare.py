"""Comparing two renderings of one view away from edges (the oracle tests, the report).

:func:`surface_ids` names, per pixel, the planar surface its centre sees (mesh and face
plane, through the BVH); :func:`interior_mask` keeps the pixels whose whole 3 x 3
neighbourhood sees the same surface (no silhouette, crease or shadow-free edge in reach of
the box filter). :func:`block_relative_error` is the mean relative error of ``b x b`` block
means over blocks wholly inside, so that a converged bias shows and the sampling noise of
single pixels averages out.
"""

from __future__ import annotations

import numpy as np


def surface_ids(scene, view, projection: str, width: int, height: int,
                with_meshes: bool = False):
    """(H, W) int64: the planar surface seen at each pixel centre (-1: nothing); with
    ``with_meshes`` also (H, W) the index of its mesh among those with triangles."""
    from core.camera.rays import camera_rays
    from core.renderers.pathtrace.draw import pack
    from core.raytrace.bvh import intersect_rays
    packed = pack(scene)
    origins, directions, t_min, t_max = camera_rays(view, projection, width, height)
    prim, _, _, _ = intersect_rays(packed.bvh, origins, directions, t_min, t_max)
    normal = np.round(packed.normal, 6)
    plane = np.round(np.einsum("ij,ij->i", normal, packed.corners[:, 0]) / packed.scale, 6)
    key = np.concatenate([packed.material[:, None], normal, plane[:, None]], axis=1)
    _, surface = np.unique(key, axis=0, return_inverse=True)
    ids = np.where(prim >= 0, surface.reshape(-1)[np.maximum(prim, 0)], -1)
    if with_meshes:
        mesh = np.where(prim >= 0, packed.material[np.maximum(prim, 0)], -1)
        return ids.reshape(height, width), mesh.reshape(height, width)
    return ids.reshape(height, width)


def interior_mask(ids: np.ndarray) -> np.ndarray:
    """Pixels whose 3 x 3 neighbourhood all see the same surface (and something)."""
    h, w = ids.shape
    mask = np.zeros((h, w), bool)
    core = ids[1:-1, 1:-1]
    same = core >= 0
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same &= ids[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] == core
    mask[1:-1, 1:-1] = same
    return mask


def block_relative_error(ours: np.ndarray, reference: np.ndarray, mask: np.ndarray,
                         block: int = 4) -> tuple[float, int]:
    """``(mean relative error, blocks compared)`` of block means over wholly masked blocks,
    all three channels, where the reference is not black."""
    h, w = mask.shape
    h, w = h - h % block, w - w % block
    shape = (h // block, block, w // block, block)
    inside = mask[:h, :w].reshape(shape).all(axis=(1, 3))
    a = ours[:h, :w].reshape(*shape, 3).mean(axis=(1, 3))[inside]
    b = reference[:h, :w].reshape(*shape, 3).mean(axis=(1, 3))[inside]
    if not len(b):
        return float("nan"), 0
    lit = b > 1e-3 * b.max()
    return float(np.mean(np.abs(a[lit] - b[lit]) / b[lit])), int(inside.sum())
