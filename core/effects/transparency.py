"""Transparency in the z-buffer family (FvDFH 16.5.1; the notes' "interpolated" and "screen
door" transparency), for the z-buffer and the painter's renderers.

A mesh whose material has ``k_t > 0`` (the transmission coefficient; the same
``Material.kt`` the ray tracer refracts with) is transparent. The opaque meshes are drawn
first, as usual, leaving colours and depths. The transparent triangles are then put in back
to front order (Newell's depth sort, or a painter's own order: the BSP renderer's tree) and
laid over the frame where they lie in front of the opaque surface:

- ``interpolated``: ``I = (1 - k_t) I_1 + k_t I_2``, ``I_1`` the transparent surface's own
  colour, ``I_2`` what was there (the opaque surface, or transparent ones painted before);
- ``interpolated-specular``: the notes' "more realistic effect": the near surface's ambient and
  diffuse interpolated with the far colour, then its specular added,
  ``I = (1 - k_t) I_1,ad + k_t I_2 + I_1,s``, so a highlight on glass stays as bright as on
  an opaque surface instead of being dimmed by ``1 - k_t``. The near surface is shaded twice,
  as it is and with ``k_s = 0``: its specular is the difference;
- ``screen-door``: the surface is drawn, with the depth test, only on the pixels of an
  ordered-dither mask (4 x 4 Bayer) whose share is its opacity ``1 - k_t``; the eye averages
  the mesh of pixels. Order-independent in principle; drawn in the same order here.

Painting order matters only where transparent triangles overlap: they are grouped into layers
that share no pixel (a triangle's layer is one above the highest layer among the pixels it
covers), and each layer is rasterized and shaded at once, in order.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from core.arrays import rgb_picture
from core.jit import njit
from core.pipeline.raster import (INVALID, PIXEL_CENTRE, SUBPIXEL_ONE, pixel_box,
                                  snap_vertices, triangle_edges)
from core.settings import TRANSPARENCIES
from core.shading.illumination import to_uint8

MODES = tuple(TRANSPARENCIES)
# The 4 x 4 ordered-dither (Bayer) matrix: a pixel shows the surface where
# (B + 0.5) / 16 < opacity, so any 16 pixels of a tile show round(16 opacity) of them.
BAYER = np.array([[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]])


def split_scene(scene, context):
    """``(opaque scene, transparent scene)``, kept in the context while ``scene`` lives; the
    transparent meshes are open (both faces drawn: one sees the back of a glass through it)."""
    cache = context.cache(scene)
    held = cache.get("transparency split")
    meshes = tuple(scene.meshes)
    if held is None or held[0] != meshes:
        clear = [m for m in meshes if m.material.kt > 0 and len(m.triangles)]
        opaque = [m for m in meshes if not (m.material.kt > 0 and len(m.triangles))]
        held = (meshes, dataclasses.replace(scene, meshes=opaque),
                dataclasses.replace(scene, meshes=[dataclasses.replace(m, closed=False)
                                                   for m in clear]))
        cache["transparency split"] = held
    return held[1], held[2]


def without_specular(clear, context):
    """``clear`` with every material's ``k_s`` 0 (its ambient and diffuse alone), kept in the
    context while ``clear`` lives."""
    cache = context.cache(clear)
    held = cache.get("without specular")
    if held is None:
        held = dataclasses.replace(clear, meshes=[
            dataclasses.replace(m, material=dataclasses.replace(m.material, ks=0.0))
            for m in clear.meshes])
        cache["without specular"] = held
    return held


def with_transparency(draw):
    """``draw`` (a z-buffer family renderer) on the opaque meshes, then the transparent ones
    laid over (``settings.transparency``)."""
    def draw_transparent(scene, view, settings, frame, context, timer):
        opaque, clear = split_scene(scene, context)
        draw(opaque, view, settings, frame, context, timer)
        if frame.message is None and settings.shading not in ("wireframe",):
            composite(clear, view, settings, frame, context)
            timer.lap("transparency")
    return draw_transparent


@njit(cache=True, nogil=True)
def coverage_layers(xy_z, inv_w, triangles, width, height):
    """Each triangle's layer, in order: one above the highest layer among the pixel centres
    it covers. Coverage is the rasterizer's own (its fixed point, edge functions and fill
    rule), so no two triangles of a layer share a pixel and a pixel meets its triangles in
    rising layers: as many layers as the most triangles over one pixel, where layers by
    pixel box were nearly one per triangle (boxes of neighbours overlap; 32,259 layers for
    the glass bunny's BSP fragments at 64 x 48)."""
    fixed = np.empty((xy_z.shape[0], 2), np.int32)
    snap_vertices(xy_z, inv_w, fixed, 0, xy_z.shape[0])
    top = np.zeros((height, width), np.int32)
    layer = np.zeros(triangles.shape[0], np.int32)
    for t in range(triangles.shape[0]):
        v0, v1, v2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        x0, y0 = np.int64(fixed[v0, 0]), np.int64(fixed[v0, 1])
        x1, y1 = np.int64(fixed[v1, 0]), np.int64(fixed[v1, 1])
        x2, y2 = np.int64(fixed[v2, 0]), np.int64(fixed[v2, 1])
        if x0 == INVALID or x1 == INVALID or x2 == INVALID:
            continue                               # the rasterizer draws nothing of it
        area2, edge0, edge1, edge2 = triangle_edges(x0, y0, x1, y1, x2, y2)
        if area2 == 0:
            continue
        i_min, i_max, j_min, j_max = pixel_box(x0, y0, x1, y1, x2, y2, width, height)
        for step in range(2):                      # the highest layer under it, then above
            m = layer[t]
            for j in range(j_min, j_max + 1):
                py = j * SUBPIXEL_ONE + PIXEL_CENTRE
                row = height - 1 - j
                for i in range(i_min, i_max + 1):
                    px = i * SUBPIXEL_ONE + PIXEL_CENTRE
                    if edge0[0] * px + edge0[1] * py + edge0[2] >= 0 \
                            and edge1[0] * px + edge1[1] * py + edge1[2] >= 0 \
                            and edge2[0] * px + edge2[1] * py + edge2[2] >= 0:
                        if step == 0:
                            m = max(m, top[row, i])
                        else:
                            top[row, i] = m + 1
            layer[t] = m
    return layer


def _layer_box(device, triangles, width, height):
    """The rows and columns (a pair of slices) holding every pixel of ``triangles``, or None:
    the union of their pixel boxes, one pixel wider."""
    if len(triangles) == 0:
        return None
    xy = device[triangles][..., :2]
    c0 = max(int(np.floor(xy[..., 0].min())) - 1, 0)
    c1 = min(int(np.ceil(xy[..., 0].max())) + 1, width - 1)
    r0 = max(height - 1 - int(np.ceil(xy[..., 1].max())) - 1, 0)
    r1 = min(height - 1 - int(np.floor(xy[..., 1].min())) + 1, height - 1)
    if c0 > c1 or r0 > r1:
        return None
    return slice(r0, r1 + 1), slice(c0, c1 + 1)


def composite(clear, view, settings, frame, context) -> None:
    """Lay the transparent meshes of ``clear`` over ``frame`` (its colour and depth)."""
    from core.registry import get_renderer
    from core.visibility.paint import (Painting, SimpleFrame, depth_sorted_painting, paint,
                                       painting, resolve, true_depth)
    if not clear.meshes:
        return
    height, width = frame.color.shape[:2]
    # a painter lays them in its own order, the others in Newell's depth sort
    order = get_renderer(settings.renderer).painting or depth_sorted_painting
    drawn = settings.replace(paint_first=None, samples=1)
    p = painting(clear, view, drawn, context, order=order)
    specular_added = settings.transparency == "interpolated-specular"
    p_ad = (painting(without_specular(clear, context), view, drawn, context, order=order)
            if specular_added and p is not None else None)
    frame.stats["transparent triangles"] = 0 if p is None else int(len(p.triangles))
    if p is None or len(p.triangles) == 0:
        return
    kt_of_face = np.array([m.material.kt for m in clear.meshes])[p.inputs.face_surface]
    depth = frame.depth if frame.depth is not None else np.full((height, width), -np.inf)
    depth = depth.copy()
    layers = coverage_layers(p.device, p.inv_w, np.ascontiguousarray(p.triangles), width,
                             height)
    frame.stats["transparency layers"] = int(layers.max()) + 1
    opacity_mask = (BAYER[np.arange(height)[:, None] % 4, np.arange(width)[None, :] % 4] + 0.5) / 16
    colour, colour_ad = rgb_picture(height, width), rgb_picture(height, width)
    for layer in range(int(layers.max()) + 1):
        chosen = np.flatnonzero(layers == layer)
        one = Painting(p.device, p.inv_w, p.triangles[chosen], p.attrs, p.source[chosen],
                       p.inputs, {})
        vis = paint(one, width, height, context)
        resolve(one, vis, clear, settings, SimpleFrame(colour))
        if p_ad is not None:               # the same triangles, shaded with k_s = 0
            one_ad = Painting(p_ad.device, p_ad.inv_w, p_ad.triangles[chosen], p_ad.attrs,
                              p_ad.source[chosen], p_ad.inputs, {})
            resolve(one_ad, vis, without_specular(clear, context), settings,
                    SimpleFrame(colour_ad))
        z = true_depth(vis, one)
        # the layer's pixels lie in its triangles' boxes: the masks are made there alone
        # (over the whole picture they cost 2 of a frame's 2.7 s, 624 layers at 800 x 600)
        box = _layer_box(p.device, one.triangles, width, height)
        if box is None:
            continue
        tri, colour_s, colour_ad_s = vis.tri[box], colour[box], colour_ad[box]
        shown, below = frame.color[box], depth[box]          # views: written in place
        covered = tri >= 0
        kt = np.zeros(covered.shape)
        kt[covered] = kt_of_face[one.source[tri[covered]]]
        front = covered & (z[box] >= below)
        if settings.transparency == "screen-door":
            front &= opacity_mask[box] < 1.0 - kt
            shown[front] = colour_s[front]
            below[front] = z[box][front]
        elif p_ad is not None:
            k = kt[front][:, None]
            ad = colour_ad_s[front] / 255.0
            specular = np.maximum(colour_s[front] / 255.0 - ad, 0.0)
            blend = (1.0 - k) * ad + k * shown[front] / 255.0 + specular
            shown[front] = to_uint8(blend)
        else:
            k = kt[front][:, None]
            blend = (1.0 - k) * colour_s[front] / 255.0 + k * shown[front] / 255.0
            shown[front] = to_uint8(blend)
    if settings.transparency == "screen-door":
        frame.depth = depth
