"""The path tracer's pixel record, for the pixel inspector: :func:`inspect_pixel` traces one
pixel's paths again, as :func:`core.renderers.pathtrace.draw.draw` traced them (the same random
numbers), and reports the first pass's rays.
"""

from __future__ import annotations

import numpy as np

from core.camera.rays import pack_camera
from core.pathtrace import kernel
from core.renderers.pathtrace.draw import packed_for, pass_offsets, sample_index
from core.radiosity.mesh import has_light, reflectance
from core.radiosity.tone import tone_map
from core.shading.illumination import to_uint8


def inspect_pixel(scene, view, settings, x, y, context) -> dict:
    """The pixel (x, y) traced again, pass by pass, as :func:`draw` traced it: its colour
    (equal to the picture's), and the first pass's path: each ray's kind, origin, direction,
    hit (point, mesh, material), weight (the path throughput it carries) and contribution
    (the radiance it added at its hit)."""
    from core.radiosity.mesh import RadiosityError
    record = {"renderer": "pathtrace", "pixel": [int(x), int(y)]}
    try:
        packed = packed_for(scene, context)
    except RadiosityError as error:
        return {**record, "color": [0, 0, 0], "message": str(error)}
    if not has_light(scene):
        return {**record, "color": [0, 0, 0], "message": "nothing emits light"}
    width, height = settings.size
    offsets = pass_offsets(settings.samples, settings.seed)
    total = np.zeros(3)
    path = []
    cam = pack_camera(view, settings.projection, width, height, settings.keep_aspect)
    for k, offset in enumerate(offsets):
        rays = np.zeros((16, kernel.RECORD_WIDTH))
        r, g, b, depth = kernel.trace_recorded(
            packed.bvh, packed.corners, packed.normal, packed.material, packed.materials,
            packed.emit_tri, packed.emit_cdf, packed.area, packed.emit_pdf, packed.lights,
            packed.background, cam, int(width), int(height), float(offset[0]),
            float(offset[1]), kernel.EPS * packed.scale, settings.seed * 1_000_003 + k,
            y * width + x, settings.seed, sample_index(settings, k), rays)
        total += (r, g, b)
        if k == 0:
            recorded = int(np.count_nonzero(np.abs(rays[:, 3:6]).sum(axis=1)))   # direction set
            path = _path_record(scene, packed, rays[:recorded], (r, g, b))
    radiance = total / len(offsets)
    color = to_uint8(tone_map(radiance[None, None], scene.tone))[0, 0]
    return {**record, "color": [int(c) for c in color], "radiance": radiance.tolist(),
            "samples": len(offsets), "path (first sample)": path}


def _path_record(scene, packed, rays, final) -> list[dict]:
    meshes = [m for m in scene.meshes if len(m.triangles)]
    out = []
    for i, row in enumerate(rays):
        after = rays[i + 1, 12:15] if i + 1 < len(rays) else np.asarray(final)
        tri = int(row[11])
        entry = {"kind": kernel.RAY_KINDS[int(row[6])], "origin": row[0:3].tolist(),
                 "direction": row[3:6].tolist(), "weight": row[7:10].tolist(),
                 "contribution": (after - row[12:15]).tolist()}
        if tri < 0:
            entry["hit"] = None
        else:
            m = meshes[int(packed.material[tri])]
            entry["hit"] = (row[0:3] + row[10] * row[3:6]).tolist()
            entry["mesh"] = m.name
            entry["material"] = {"rho": reflectance(m.material).tolist(), "ks": m.material.ks,
                                 "kr": m.material.kr, "kt": m.material.kt,
                                 "emission": list(m.material.emission)}
        out.append(entry)
    return out
