"""The ray tracer's pixel records, for the pixel inspector: the ray tree, ray by ray.

:func:`inspect_pixel` (the registered inspector) traces the pixel's samples again through the
kernel's own :func:`core.raytrace.whitted.trace`, which records each sample's tree: every
ray's kind, origin, direction, hit, material, ``I_local``, weight and contribution.

:func:`ray_tree_record` is the same tree told independently, node by node:
:func:`ray_tree` walks :func:`core.raytrace.whitted.trace`'s loop in Python, in its order
(an explicit stack, depth first), calling the tracer's own compiled pieces for each step
(``nearest``, ``surface_at``, ``checker_colour``, ``shadow_term``, ``refract``, ``reflect``,
``schlick``) and :func:`core.shading.models.dispatch.lighting_terms` (the material's lighting
model term by term) for the local colour with each light's shadow factor. Every node keeps its kind, origin, direction, hit, material, local
colour, weight and contribution (weight x local colour); their sum is the sample's colour,
and the samples' mean the pixel's, to the last bit.
"""

from __future__ import annotations

import numpy as np

from core.camera.view import View
from core.raytrace import bvh, geometry, whitted
from core.renderers.raytrace.draw import (Setup, TraceOptions, differentials, frame_offsets,
                                          prepare, primary)
from core.shading.illumination import EYE_POINT, POINT_LIGHT, TWO_SIDED, to_uint8
from core.shading.models.dispatch import lighting_terms

KINDS = ("primary", "shadow", "reflected", "refracted")
HITS = {0: "triangle", 1: "sphere", 2: "plane"}


def ray_tree_record(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The pixel's ray tree walked in Python, node by node (see the module)."""
    from core.camera.film import sample_offsets
    from core.renderers.raytrace import draw
    options = draw.TraceOptions.from_settings(settings)
    offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
               if settings.samples > 1 else np.array([settings.pixel_offset], dtype=np.float64))
    setup, (origins, directions, t_min, t_max) = _setup(scene, view, settings, options, offsets,
                                                         context)
    width, height = settings.size
    samples, colours = [], []
    for k in ((s * height + y) * width + x for s in range(len(offsets))):
        if not t_min[k] < t_max[k]:
            colour = [float(c) for c in setup.background]
            samples.append({"nodes": [], "note": "outside the viewport or the F..B slab",
                            "sum": colour})
        else:
            nodes, colour = ray_tree(setup, origins[k], directions[k], t_min[k], t_max[k])
            samples.append({"nodes": nodes, "sum": colour})
        colours.append(colour)
    raw = np.mean(np.array(colours), axis=0)
    record = {"renderer": "raytrace", "pixel": [int(x), int(y)],
              "color": to_uint8(raw).tolist(), "raw": raw.tolist(),
              "shadows": options.shadows, "max depth": options.max_depth}
    if len(samples) == 1:
        record.update({"ray tree": samples[0]["nodes"], "ray-tree depth": _depth(samples[0])})
    else:
        record["samples"] = samples
        record["ray-tree depth"] = max(_depth(s) for s in samples)
    return record


def _setup(scene, view, settings, options, offsets, context):
    """The tracer's prepared frame and its primary rays (all of them at once: one pixel's
    alone costs as much), kept per scene for the last view and settings asked."""
    from core.context import DEFAULT_CONTEXT
    from core.renderers.raytrace import draw
    cache = (context or DEFAULT_CONTEXT).cache(scene)
    held = cache.get("pixel inspector: raytrace")
    try:
        if held is not None and held[0] == (view, settings):
            return held[1]
    except (TypeError, ValueError):
        pass
    setup = draw.prepare(scene, view, settings.projection, settings.size, options, offsets,
                         settings.keep_aspect)
    held = (setup, draw.primary(setup, 0, setup.height, 0, setup.width))
    cache["pixel inspector: raytrace"] = ((view, settings), held)
    return held


def _depth(sample) -> int:
    return max((n["depth"] for n in sample["nodes"]), default=0)


def ray_tree(setup, origin, direction, t_min, t_max) -> tuple[list, list]:
    """The nodes of one primary ray's tree and their summed colour (unclamped RGB)."""
    packed = setup.packing.packed
    # What every node's trace reuses: the shadow mode, the offset off a surface, the BVH's
    # stack, the ray counters, a surface row and the eye (point or direction).
    work = (whitted.SHADOW_MODES.index(setup.options.shadows), 1e-9 * setup.packing.scale,
            bvh.new_stack(), np.zeros(len(whitted.COUNTERS), dtype=np.int64),
            np.empty((1, packed.surfaces.shape[1])), np.empty(4))
    total = [0.0, 0.0, 0.0]
    nodes = []
    pending = [(*origin, *direction, float(t_min), float(t_max), 1.0, 1, whitted.PRIMARY, -1)]
    while pending:
        ray = pending.pop()
        ox, oy, oz, dx, dy, dz, t0, t1, weight, depth, ray_kind, parent = ray
        node = {"id": len(nodes), "parent": parent, "kind": KINDS[ray_kind], "depth": depth,
                "origin": [ox, oy, oz], "direction": [dx, dy, dz], "weight": weight}
        nodes.append(node)
        contribution = _trace_node(setup, node, ray, work, pending)
        total = [total[c] + contribution[c] for c in range(3)]
    return nodes, total


def _trace_node(setup, node: dict, ray: tuple, work: tuple, pending: list) -> list:
    """Fill in ``node`` for ``ray`` (what it hit, the local terms), queue its reflected and
    refracted rays on ``pending``; returns its weighted contribution to the pixel."""
    packed = setup.packing.packed
    shadows, offset, stack, counts, surface_row, eye = work
    ox, oy, oz, dx, dy, dz, t0, t1, weight, depth, ray_kind, parent = ray
    kind, index, t, u, v = whitted.nearest(packed, ox, oy, oz, dx, dy, dz, t0, t1, stack)
    if kind == whitted.NOTHING:
        node.update({"hit": None, "local colour": [float(c) for c in setup.background]})
        contribution = [weight * float(setup.background[c]) for c in range(3)]
        node["contribution"] = contribution
        return contribution
    px, py, pz, nx, ny, nz, gx, gy, gz, s = whitted.surface_at(packed, kind, index, u, v,
                                                               ox, oy, oz, dx, dy, dz, t)
    whitted.hit_viewer(ray_kind, setup.eye, dx, dy, dz, eye)
    entering, lnx, lny, lnz = whitted.lit_normal(packed.surfaces, s, nx, ny, nz, gx, gy, gz,
                                                 dx, dy, dz)
    terms = _local(setup, packed, kind, index, s, (px, py, pz), (lnx, lny, lnz),
                   (gx, gy, gz), eye, shadows, offset, surface_row, stack, counts)
    local = terms["clamped"]
    contribution = [weight * local[c] for c in range(3)]
    k_r, k_t, ior = (float(c) for c in packed.optics[s])
    node.update({"hit": {"kind": HITS.get(int(kind), str(kind)), "index": int(index),
                         "t": float(t), "point": [px, py, pz], "normal": [nx, ny, nz],
                         "entering": bool(entering)},
                 "material": {"surface": int(s), "k_r": k_r, "k_t": k_t, "ior": ior},
                 "phong": terms, "local colour": local, "contribution": contribution})
    if k_r == 0.0 and k_t == 0.0:
        return contribution
    if depth >= setup.options.max_depth:
        node["children"] = "cut: the depth limit"
        return contribution
    _queue_children(setup.options, node, ray, ((px, py, pz), (nx, ny, nz), (gx, gy, gz)),
                    entering, (k_r, k_t, ior), offset, pending)
    return contribution


def _queue_children(o, node: dict, ray: tuple, hit: tuple, entering: bool, optics_of: tuple,
                    offset: float, pending: list) -> None:
    """The refracted ray (or total internal reflection) and the reflected ray of a hit, each
    queued unless adaptive depth control cuts it; Fresnel moves weight between the two."""
    from core.raytrace import optics
    dx, dy, dz, weight, depth = ray[3], ray[4], ray[5], ray[8], ray[9]
    (px, py, pz), (nx, ny, nz), (gx, gy, gz) = hit
    k_r, k_t, ior = optics_of
    fx, fy, fz, gx, gy, gz = optics.facing_normals(dx, dy, dz, nx, ny, nz, gx, gy, gz,
                                                   entering)
    me = node["id"]
    if k_t > 0.0:
        n_i, n_t = (o.medium, ior) if entering else (ior, o.medium)
        ok, tx, ty, tz = optics.refract(dx, dy, dz, fx, fy, fz, n_i, n_t)
        if not ok:
            node["total internal reflection"] = True
            k_r, k_t = k_r + k_t, 0.0
        elif o.fresnel:
            cos_i = -(fx * dx + fy * dy + fz * dz)
            cos_t = -(fx * tx + fy * ty + fz * tz)
            share = optics.schlick(cos_i, cos_t, n_i, n_t)
            k_r, k_t = k_r + share * k_t, (1.0 - share) * k_t
        if k_t > 0.0:
            if weight * k_t >= o.adaptive_epsilon:
                pending.append((px - offset * gx, py - offset * gy, pz - offset * gz,
                                tx, ty, tz, 0.0, np.inf, weight * k_t, depth + 1,
                                whitted.REFRACTED, me))
            else:
                node["refracted"] = "cut by adaptive control"
    if k_r > 0.0:
        if weight * k_r >= o.adaptive_epsilon:
            rx, ry, rz = optics.reflect(dx, dy, dz, fx, fy, fz)
            pending.append((px + offset * gx, py + offset * gy, pz + offset * gz,
                            rx, ry, rz, 0.0, np.inf, weight * k_r, depth + 1,
                            whitted.REFLECTED, me))
        else:
            node["reflected"] = "cut by adaptive control"


def _local(setup, packed, kind, index, s, p, n, g, eye, shadows, offset, surface_row, stack,
           counts) -> dict:
    """The terms of ``I_local`` as :func:`whitted.trace` finds them: the checker's O_d, each
    light's shadow factor, Phong."""
    from core.shading.illumination import unit3
    px, py, pz = p
    nx, ny, nz = n
    gx, gy, gz = g
    whitted.checker_colour(packed, kind, index, s, px, py, pz, surface_row)
    lights = setup.lights
    factors = [(1.0, 1.0, 1.0)] * len(lights)
    if shadows != whitted.SHADOW_OFF and len(lights):
        if eye[0] == EYE_POINT:
            vx, vy, vz, _ = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
        else:
            vx, vy, vz = eye[1], eye[2], eye[3]
        lit = (nx, ny, nz)
        if surface_row[0, TWO_SIDED] != 0.0 and nx * vx + ny * vy + nz * vz < 0.0:
            lit = (-nx, -ny, -nz)
        side = 1.0 if gx * vx + gy * vy + gz * vz >= 0.0 else -1.0
        sx, sy, sz = px + side * offset * gx, py + side * offset * gy, pz + side * offset * gz
        for k in range(len(lights)):
            if lights[k, 0] == POINT_LIGHT:
                lx, ly, lz, _ = unit3(lights[k, 1] - px, lights[k, 2] - py, lights[k, 3] - pz)
            else:
                lx, ly, lz = lights[k, 1], lights[k, 2], lights[k, 3]
            if lit[0] * lx + lit[1] * ly + lit[2] * lz <= 0.0:
                continue
            factors[k] = whitted.shadow_term(packed, shadows, lights[k], sx, sy, sz,
                                             setup.background, offset, stack, counts)
    return lighting_terms(p, n, 0, surface_row, lights, setup.ambient, eye, setup.halfway,
                          shadow=factors)


def buffers(scene, view, settings, context, names) -> dict:
    """The ray tracer's buffer views: ``depth`` (−t of the primary hit, so larger
    is nearer, as the z-buffer's), ``triangle`` (the scene triangle a primary ray hits first;
    -1 for spheres, planes and nothing) and ``ray-depth`` (per pixel, the smallest depth
    limit from which the traced colour no longer changes: the depth of the tree that
    matters). One sample per pixel, at the pixel centre."""
    from core.renderers.raytrace.draw import render_raw
    options_settings = settings.replace(samples=1)
    setup, (origins, directions, t_min, t_max) = _setup(
        scene, view, options_settings, _options(options_settings),
        np.array([options_settings.pixel_offset]), context)
    width, height = settings.size
    out = {}
    if "depth" in names or "triangle" in names:
        n = len(origins)
        kind, index, t_hit = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
        whitted.visible_many(setup.packing.packed, origins, directions, t_min, t_max, kind,
                             index, t_hit)
        hit = kind != whitted.NOTHING
        out["depth"] = np.where(hit, -t_hit, np.nan).reshape(height, width)
        out["triangle"] = np.where(kind == whitted.TRIANGLE, index, -1).reshape(height, width)
    if "ray-depth" in names:
        import dataclasses
        limit = setup.options.max_depth
        final = render_raw(setup)
        depth = np.full((height, width), limit, np.int64)
        still = np.ones((height, width), bool)      # the same colour at every limit so far
        for d in range(limit - 1, 0, -1):
            trial = dataclasses.replace(setup, options=dataclasses.replace(setup.options,
                                                                          max_depth=d))
            still &= (render_raw(trial) == final).all(axis=2)
            depth[still] = d
        out["ray-depth"] = depth
    return out


def _options(settings):
    from core.renderers.raytrace import draw
    return draw.TraceOptions.from_settings(settings)


# ------------------------------------------------------ the tree the kernel records

RAY_KINDS = ("primary", "shadow", "reflected", "refracted")
HIT_KINDS = {whitted.NOTHING: "nothing", whitted.TRIANGLE: "triangle", whitted.SPHERE: "sphere",
             whitted.PLANE: "plane"}
MAX_TREE = 4096            # rays recorded per sample at most


def inspect_pixel(scene, view: View, settings, x: int, y: int, context=None) -> dict:
    """The ray tree of pixel ``(x, y)`` (x right, y down, row 0 at the top), sample by sample:
    each ray's kind, origin, direction, what it hit, the material, ``I_local``, its weight and
    its contribution ``weight · I_local``; the contributions of a sample's tree sum to that
    sample's colour, and the samples' mean is the pixel (``color``, 0–255, as ``draw`` writes
    it). Raises ValueError for a pixel outside the picture."""
    width, height = settings.size
    if not (0 <= x < width and 0 <= y < height):
        raise ValueError(f"pixel ({x}, {y}) is outside the {width} x {height} picture")
    options = TraceOptions.from_settings(settings)
    setup = prepare(scene, view, settings.projection, settings.size, options,
                    frame_offsets(settings), settings.keep_aspect)
    origins, directions, t_min, t_max = primary(setup, y, y + 1, x, x + 1)
    diffs = differentials(setup, y, y + 1, x, x + 1)
    samples, total = [], np.zeros(3)
    for k in range(len(origins)):
        tree = np.zeros((MAX_TREE, whitted.TREE_COLUMNS))
        colour, recorded = _trace_one(setup, origins[k], directions[k], t_min[k], t_max[k],
                                      diffs[k], tree)
        total += colour
        samples.append({"offset": [float(c) for c in setup.offsets[k]],
                        "color": [float(c) for c in colour],
                        "rays": [_ray_record(scene, setup, row) for row in tree[:recorded]]})
    mean = total / len(origins)
    return {"renderer": "raytrace", "pixel": [int(x), int(y)],
            "color": [int(c) for c in to_uint8(mean)], "raw": [float(c) for c in mean],
            "samples": samples, "counts": {n: int(c) for n, c in zip(whitted.COUNTERS,
                                                                      setup.counts)}}


def _trace_one(setup: Setup, origin, direction, t_min, t_max, diff, tree):
    """One primary ray through the kernel's own :func:`whitted.trace`, recording its tree."""
    from core.texture.sample import FILTERS
    o, packed = setup.options, setup.packing.packed
    if not t_min < t_max:
        return np.array(setup.background), 0
    rays = np.empty((2 * o.max_depth + 2, whitted.STACK_COLUMNS))
    counts = np.zeros(len(whitted.COUNTERS), dtype=np.int64)
    raw = np.empty((1, 3))
    recorded = whitted.trace(
        packed, np.array([origin], dtype=np.float64), np.array([direction], dtype=np.float64),
        np.array([t_min], dtype=np.float64), np.array([t_max], dtype=np.float64), 0, 1,
        setup.eye, setup.lights, setup.ambient, setup.halfway, setup.background,
        whitted.SHADOW_MODES.index(o.shadows), o.max_depth, float(o.adaptive_epsilon),
        o.fresnel_code, o.medium, 1e-9 * setup.packing.scale, rays, np.empty(setup.lights.shape),
        np.empty((1, packed.surfaces.shape[1])), np.empty(4), bvh.new_stack(),
        counts, setup.packing.texturing, setup.packing.textured, FILTERS[o.texture_filter],
        bool(o.bump), whitted.colour_at(packed, setup.lights, setup.ambient, setup.halfway,
                                        setup.packing.texturing, setup.packing.textured,
                                        FILTERS[o.texture_filter], bool(o.bump)),
        np.array([diff], dtype=np.float64),
        whitted.scratch(packed, setup.packing.textured), tree, np.array(o.secondary_attenuation, dtype=np.float64), raw)
    r, g, b = raw[0]
    setup.counts += counts
    return np.array([r, g, b]), recorded


def _ray_record(scene, setup: Setup, row) -> dict:
    w = whitted
    hit = int(row[w.TREE_HIT])
    local = row[w.TREE_LOCAL:w.TREE_LOCAL + 3]
    weight = float(row[w.TREE_WEIGHT])
    record = {"kind": RAY_KINDS[int(row[w.TREE_KIND])], "depth": int(row[w.TREE_DEPTH]),
              "parent": int(row[w.TREE_PARENT]),
              "origin": row[w.TREE_ORIGIN:w.TREE_ORIGIN + 3].tolist(),
              "direction": row[w.TREE_DIRECTION:w.TREE_DIRECTION + 3].tolist(),
              "hit": HIT_KINDS[hit], "weight": weight, "local": local.tolist(),
              "contribution": (weight * local).tolist()}
    if hit != w.NOTHING:
        s = int(row[w.TREE_SURFACE])
        record.update({"t": float(row[w.TREE_T]), "material": _material_name(scene, s),
                       "point": row[w.TREE_POINT:w.TREE_POINT + 3].tolist(),
                       "normal": row[w.TREE_NORMAL:w.TREE_NORMAL + 3].tolist(),
                       "geometric normal": row[w.TREE_GEOMETRIC:w.TREE_GEOMETRIC + 3].tolist(),
                       "kr kt ior": setup.packing.packed.optics[s].tolist()})
    return record


def _material_name(scene, s: int) -> str:
    """The name of surface row ``s`` (meshes, then spheres, then planes, as packed)."""
    meshes = geometry.traced_meshes(scene)
    if s < len(meshes):
        return f"mesh {meshes[s].name!r}"
    spheres, planes = geometry.traced_primitives(scene)
    if s < len(meshes) + len(spheres):
        return f"sphere {s - len(meshes) + 1}"
    return f"plane {s - len(meshes) - len(spheres) + 1}"
