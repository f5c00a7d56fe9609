"""Buffer views (render passes, AOVs): what the renderer kept at every pixel, shown
as a picture with a colour map, and the raw values for whoever wants the numbers.

The module of a renderer's inspector (its registry entry's ``inspector``) may define
``buffers(scene, view, settings, context, names) -> {name: array}``: the z-buffer's
(:func:`core.renderers.zbuffer.inspect.buffers`, the scan-line renderer's the same), the
painters' overdraw (:func:`core.renderers.painters.inspect.buffers`) and the ray tracer's
(:func:`core.renderers.raytrace.inspect.buffers`) do.

=============  =====================================  ===========================================
name           values                                 colour map
=============  =====================================  ===========================================
depth          canonical depth (z-buffer: NPC z,      near bright, far dark; empty black
               larger nearer; ray tracer: -t)
normal         unit world normal (H, W, 3)            (N + 1) / 2 as RGB
triangle       visible triangle (scene order), -1     a colour per id
barycentrics   weights of the 3 vertices (H, W, 3)    the weights as RGB
uv             (u, v) the texture was read at         frac(u), frac(v) as red, green
mip            MIP level read (λ, clamped)            a palette over 0 .. the last level
overdraw       fragments per pixel (depth ignored)    a palette over 0 .. the most
ray-depth      depth of the pixel's ray tree          a palette over 0 .. the deepest
=============  =====================================  ===========================================
"""

from __future__ import annotations

import importlib

import numpy as np

from core.inspect import NotInspectable
from core.renderers import get_renderer

BUFFERS = ("depth", "normal", "triangle", "barycentrics", "uv", "mip", "overdraw", "ray-depth")

# A palette from cold to hot (blue, cyan, green, yellow, red) for counts and levels.
_PALETTE = np.array([[0, 0, 160], [0, 170, 255], [0, 200, 60], [255, 230, 0], [230, 0, 0]],
                    dtype=np.float64)


def _provider(renderer: str):
    """The ``buffers`` of the module of ``renderer``'s inspector (None: it has none)."""
    inspector = get_renderer(renderer).inspector
    if inspector is None:
        return None
    return getattr(importlib.import_module(inspector.partition(":")[0]), "buffers", None)


def buffer(scene, view, settings, name: str, context=None) -> tuple[np.ndarray, np.ndarray]:
    """``(values, picture)``: the raw buffer ``name`` and its colour-mapped ``(H, W, 3)``
    uint8 picture. Raises :class:`NotInspectable` when the renderer keeps no such buffer."""
    if name not in BUFFERS:
        raise NotInspectable(f"buffer must be one of {', '.join(BUFFERS)}, not {name!r}")
    values = None
    try:
        provider = _provider(settings.renderer)
    except ValueError as error:                  # not a registered renderer
        raise NotInspectable(str(error)) from None
    if provider is not None:
        try:
            values = provider(scene, view, settings, context, (name,)).get(name)
        except ValueError as error:
            raise NotInspectable(f"{settings.renderer}: {error}") from None
    if values is None:
        raise NotInspectable(f"the {settings.renderer} renderer keeps no {name} buffer for "
                             f"this frame ({settings.shading} shading)")
    return values, colour_map(name, values)


def colour_map(name: str, values: np.ndarray) -> np.ndarray:
    """The picture of a buffer (see the table above)."""
    if name == "depth":
        return _ramp(values, grey=True)
    if name in ("normal", "barycentrics", "uv"):
        v = np.nan_to_num(np.asarray(values, dtype=np.float64), nan=0.0)
        if name == "normal":
            v = (v + 1) / 2
        elif name == "uv":
            v = np.concatenate([v - np.floor(v), np.zeros(v.shape[:2] + (1,))], axis=2)
        empty = np.isnan(np.asarray(values, dtype=np.float64)).any(axis=2)
        out = np.floor(np.clip(v, 0, 1) * 255 + 0.5).astype(np.uint8)
        out[empty] = 0
        return out
    if name == "triangle":
        ids = np.asarray(values, dtype=np.int64)
        h = (ids * 2654435761) & 0xFFFFFF
        out = np.stack([(h >> 16) & 255, (h >> 8) & 255, h & 255], axis=2)
        out = 64 + out * 191 // 255
        out[ids < 0] = 0
        return out.astype(np.uint8)
    return _ramp(values, grey=False)            # mip, overdraw, ray-depth


def _ramp(values, grey: bool) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64)
    empty = ~np.isfinite(v)
    out = np.zeros(v.shape + (3,), np.uint8)
    if empty.all():
        return out
    lo, hi = float(v[~empty].min()), float(v[~empty].max())
    if grey:
        t = np.zeros_like(v) if hi == lo else (v - lo) / (hi - lo)
        level = np.floor(48 + t * 207 + 0.5)
        out[...] = np.where(empty, 0, level)[..., None].astype(np.uint8)
        return out
    t = np.zeros_like(v) if hi <= 0 else np.clip(v, 0, None) / hi
    stops = np.linspace(0, 1, len(_PALETTE))
    for c in range(3):
        out[..., c] = np.floor(np.interp(np.where(empty, 0, t), stops, _PALETTE[:, c]) + 0.5)
    out[empty] = 0
    if not grey:
        out[np.isfinite(v) & (v == 0)] = 0          # nothing there: black
    return out
