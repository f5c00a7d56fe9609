"""The ``"pathtrace"`` renderer: the scene packed for :mod:`core.pathtrace.kernel`, the film's
samples one pass each, averaged.

:func:`pack` turns a scene into the kernel's arrays (kept in the render context while the
scene lives): the ray tracer's BVH (:func:`core.raytrace.bvh.build`) over every triangle,
each triangle's corners, unit normal, area and material row, the emitting triangles with the
cumulative distribution that light sampling draws from (area x emitted luminance), and the
point and directional lights. :func:`render_passes` traces ``samples`` passes, each one ray
through every pixel at one of the film's sample offsets (jittered strata), and returns the
mean radiance ``(H, W, 3)``; :func:`draw` is the registered renderer. Its pixel inspector is
:mod:`core.renderers.pathtrace.inspect`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from core.camera.film import progressive_order, sample_offsets
from core.camera.rays import pack_camera
from core.pathtrace import kernel
from core.radiosity.mesh import check_scene, has_light, reflectance
from core.radiosity.tone import tone_map
from core.shading.illumination import pack_surfaces, to_uint8
from core.work import report

BAND = 1 << 17         # rays traced in one call (about 0.1-0.5 s): the unit of progress


@dataclass
class Packed:
    bvh: object
    corners: np.ndarray
    normal: np.ndarray
    material: np.ndarray
    materials: np.ndarray
    emit_tri: np.ndarray
    emit_cdf: np.ndarray
    area: np.ndarray
    emit_pdf: np.ndarray
    lights: np.ndarray
    scale: float
    background: np.ndarray


def _material_row(material) -> np.ndarray:
    row = np.zeros(kernel.MATERIAL_WIDTH)
    row[kernel.RHO:kernel.RHO + 3] = reflectance(material)
    row[kernel.KS] = material.ks
    row[kernel.SHINE] = material.n
    row[kernel.KR] = material.kr
    row[kernel.KT] = material.kt
    row[kernel.IOR] = material.ior
    row[kernel.EMIT:kernel.EMIT + 3] = material.emission
    row[kernel.TWO_SIDED] = 1.0 if material.two_sided else 0.0
    row[kernel.OS:kernel.OS + 3] = material.os
    row[kernel.SURFACE:] = pack_surfaces([material], [False])[0]   # its lighting model's row
    return row


def pack_lights(lights) -> np.ndarray:
    """(L, 10): position or direction, intensity, c1 c2 c3, 1 for a point light."""
    rows = []
    for light in lights:
        point = light.position is not None
        where = light.position if point else light.direction
        rows.append([*where, *light.intensity, *light.attenuation, 1.0 if point else 0.0])
    return np.array(rows, dtype=np.float64).reshape(-1, 10)


def pack(scene) -> Packed:
    """The kernel's arrays for ``scene``; raises RadiosityError for a material it cannot use."""
    from core.radiosity.mesh import RadiosityError
    from core.raytrace.bvh import build
    check_scene(scene)
    meshes = [m for m in scene.meshes if len(m.triangles)]
    if not meshes:
        from core.renderers import held_instead
        raise RadiosityError("; ".join(["it has no triangles, and the path tracer draws "
                                        "triangles only", *held_instead(scene)]))
    positions = np.concatenate([m.positions for m in meshes])
    offsets = np.cumsum([0] + [len(m.positions) for m in meshes])
    triangles = np.concatenate([m.triangles + offsets[i] for i, m in enumerate(meshes)])
    material = np.repeat(np.arange(len(meshes)), [len(m.triangles) for m in meshes])
    materials = np.array([_material_row(m.material) for m in meshes])
    corners = positions[triangles]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(cross, axis=1)
    normal = cross / np.where(length > 0, length, 1.0)[:, None]
    area = 0.5 * length
    emission = materials[material, kernel.EMIT:kernel.EMIT + 3]
    power = area * (0.2126 * emission[:, 0] + 0.7152 * emission[:, 1] + 0.0722 * emission[:, 2])
    emit_tri = np.flatnonzero(power > 0.0)
    emit_cdf = np.cumsum(power[emit_tri])
    emit_pdf = np.zeros(len(area))
    if len(emit_tri):
        emit_pdf[emit_tri] = power[emit_tri] / emit_cdf[-1]
    bvh, _ = build(positions, triangles)
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    return Packed(bvh, np.ascontiguousarray(corners), normal, material.astype(np.int64),
                  materials, emit_tri.astype(np.int64), emit_cdf, area, emit_pdf,
                  pack_lights(scene.lights), float(np.linalg.norm(hi - lo)) or 1.0,
                  np.asarray(scene.background, dtype=np.float64).reshape(3))


def packed_for(scene, context) -> Packed:
    cache = context.cache(scene)
    if "pathtrace packing" not in cache:
        cache["pathtrace packing"] = pack(scene)
    return cache["pathtrace packing"]


def trace(packed: Packed, cam, width: int, height: int, offset, seed: int,
          strata_seed: int = 0, sample: int = kernel.INDEPENDENT, first_pixel: int = 0,
          count: int | None = None) -> tuple[np.ndarray, int]:
    """Radiance ``(count, 3)`` of pixels ``first_pixel ..`` of one pass (film ``offset``;
    ``cam``: :func:`core.camera.rays.pack_camera` of the picture), and the bounces their
    paths made; ``sample``: which of their pixels' paths they are, for the stratified first
    bounce (``kernel.INDEPENDENT``: none). The kernel makes each pixel's ray itself."""
    n = width * height - first_pixel if count is None else count
    out = np.empty((n, 3))
    bounces = np.zeros((n + 255) // 256, np.int64)
    args = (packed.bvh, packed.corners, packed.normal, packed.material, packed.materials,
            packed.emit_tri, packed.emit_cdf, packed.area, packed.emit_pdf, packed.lights,
            packed.background, cam, int(width), int(height), float(offset[0]),
            float(offset[1]), kernel.EPS * packed.scale, int(seed), out, bounces,
            int(first_pixel), int(strata_seed), int(sample))
    kernel.trace_many(*args, kernel.trace_run_at(*args))
    return out, int(bounces.sum())


def pass_offsets(samples: int, seed: int) -> np.ndarray:
    """One film offset per pass: jittered strata (a single pass: the pixel centre), in an
    order whose every prefix covers the pixel (:func:`core.camera.film.progressive_order`),
    so that the window's running mean is antialiased across the whole pixel at every count,
    not along its top rows of strata first."""
    offsets = sample_offsets(samples, "jittered" if samples > 1 else "regular", seed)
    return offsets[progressive_order(samples)]


def sample_index(settings, k: int) -> int:
    """The kernel's ``sample`` for pass ``k``: k when the options stratify, else
    ``kernel.INDEPENDENT``."""
    return k if settings.options_of("pathtrace").sampler == "stratified" else kernel.INDEPENDENT


def render_passes(scene, view, settings, context, first: int = 0, count: int | None = None,
                  packed: Packed | None = None, samples: int | None = None
                  ) -> tuple[np.ndarray, dict]:
    """Mean radiance ``(H, W, 3)`` of passes ``first .. first + count`` of ``samples`` (default
    ``settings.samples``; more than its limit of 256 may be asked for here)."""
    packed = packed or packed_for(scene, context)
    width, height = settings.size
    offsets = pass_offsets(samples or settings.samples, settings.seed)
    count = len(offsets) - first if count is None else count
    total = np.zeros((height * width, 3))
    bounces, began = 0, time.perf_counter()
    n = width * height
    cam = pack_camera(view, settings.projection, width, height, settings.keep_aspect)
    for k in range(first, first + count):
        for start in range(0, n, BAND):       # a band at a time: progress, and Ctrl+C between
            end = min(n, start + BAND)
            radiance, b = trace(packed, cam, width, height, offsets[k],
                                seed=settings.seed * 1_000_003 + k, strata_seed=settings.seed,
                                sample=sample_index(settings, k), first_pixel=start,
                                count=end - start)
            total[start:end] += radiance
            bounces += b
            report("path tracing", (k - first) * n + end, count * n, "path")
    seconds = time.perf_counter() - began
    stats = {"paths": count * width * height, "bounces": bounces, "trace seconds": seconds}
    return (total / max(count, 1)).reshape(height, width, 3), stats


def draw(scene, view, settings, frame, context, timer=None) -> None:
    """The ``"pathtrace"`` renderer: ``settings.samples`` paths per pixel."""
    from core.radiosity.mesh import RadiosityError
    try:
        packed = packed_for(scene, context)
    except RadiosityError as error:
        frame.color[...] = 0
        frame.message = f"{scene.name}: cannot path trace: {error}"
        return
    if not has_light(scene):
        frame.color[...] = 0
        frame.stats.setdefault("warnings", []).append(
            f"{scene.name}: nothing emits light (no material with emission, no [[light]] "
            "of any intensity): the picture is black")
        return
    if timer is not None:
        timer.lap("pack scene, build BVH")
    radiance, stats = render_passes(scene, view, settings, context, packed=packed)
    frame.color[...] = to_uint8(tone_map(radiance, scene.tone))
    frame.stats["pathtrace"] = stats
    frame.stats["samples per pixel"] = settings.samples
    frame.stats["computed"].append("path tracing")
    if timer is not None:
        timer.lap("path trace")
