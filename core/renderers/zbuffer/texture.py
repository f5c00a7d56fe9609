"""The textured pixel's record, for the pixel inspector: (u, v), its derivatives, the MIP level,
the texels the filter read, the normal after the bump or normal map, and the Phong terms with the
texture's colour as O_d.

The colour is :func:`core.texture.surface.textured_pixel` itself, called on the pixel's
numbers (the kernel's function, so it is the pixel the frame shows); the breakdown beside it
follows the same steps with the same compiled helpers.
"""

from __future__ import annotations

import math

import numpy as np

from core.shading.illumination import OD, TWO_SIDED, quantize
from core.shading.models.dispatch import lighting_terms
from core.texture import sample as sampling
from core.texture.surface import (BUMP_SCALE, COLOR, COLOR_SRGB, DPDU, DPDV, ENVIRONMENT, HEIGHT,
                                  NORMAL, NORMAL_MAP, POSITION, REFLECTIVITY, UV, lookup,
                                  bumped_normal, encode_srgb, environment, mapped_normal,
                                  textured_pixel, unit3)
from core.texture.tutorial import plane_constants, uv_at

FILTER_NAMES = {sampling.NEAREST: "nearest", sampling.BILINEAR: "bilinear",
                sampling.TRILINEAR: "trilinear", sampling.ANISOTROPIC: "anisotropic"}


def textured_record(cap, x, y, corners, weights, face, mesh) -> dict:
    from core.texture.shaders import demo_shade
    s, attrs = cap.shade, cap.arrays["clipped_attrs"]
    i0, i1, i2 = corners
    w0, w1, w2 = weights
    texels, levels, textures, maps = s.texture_maps
    settings = cap.settings
    filter_ = sampling.FILTERS.get(settings.texture_filter, sampling.TRILINEAR)
    bump = bool(settings.bump)
    if s.demo[mesh, 0] > 0.5:                       # the course's bump demo: its own model
        from core.texture.bump_demo import DEMO_LIGHT, java_color_byte
        light = (s.lights[0, 1:4].copy() if len(s.lights) and s.lights[0, 0] == 0.0
                 else np.array(DEMO_LIGHT))
        blue = demo_shade(attrs, i0, i1, i2, w0, w1, w2, s.demo, mesh, light)
        return {"bump demo": {"blue": float(blue)}, "color": [0, 0, int(java_color_byte(blue))]}
    constants = np.zeros((1, 3, 3))
    if cap.device_h.shape[0]:
        plane_constants(cap.device_h, i0, i1, i2, attrs[i0, UV], attrs[i0, UV + 1],
                        attrs[i1, UV], attrs[i1, UV + 1], attrs[i2, UV], attrs[i2, UV + 1],
                        float(cap.height), constants, 0)
    surf = s.surfaces.copy()
    r, g, b = textured_pixel(attrs, i0, i1, i2, w0, w1, w2, 0, x, y, constants, mesh, maps,
                             texels, levels, textures, filter_, bump, surf, s.lights, s.ambient,
                             s.eye, s.halfway)
    record = {"color": [int(quantize(c)) for c in (r, g, b)],
              "texture filter": FILTER_NAMES.get(filter_, str(filter_))}
    record.update(_breakdown(cap, x, y, corners, weights, mesh, constants, filter_, bump))
    return record


def _lerp(attrs, c, corners, weights):
    (i0, i1, i2), (w0, w1, w2) = corners, weights
    return w0 * attrs[i0, c] + w1 * attrs[i1, c] + w2 * attrs[i2, c]


def _breakdown(cap, x, y, corners, weights, mesh, constants, filter_, bump) -> dict:
    """textured_pixel's steps, kept: (u, v), the maps, the normal, O_d, Phong, environment."""
    s, attrs = cap.shade, cap.arrays["clipped_attrs"]
    texels, levels, textures, maps = s.texture_maps
    lerp = lambda c: _lerp(attrs, c, corners, weights)      # noqa: E731
    nx, ny, nz, _ = unit3(lerp(NORMAL), lerp(NORMAL + 1), lerp(NORMAL + 2))
    p = [lerp(POSITION + c) for c in range(3)]
    u, v, dudx, dvdx, dudy, dvdy = uv_at(constants, 0, x, y)
    if not (math.isfinite(u) and math.isfinite(v)):
        u, v = lerp(UV), lerp(UV + 1)
        dudx = dvdx = dudy = dvdy = 0.0
    derivs = (dudx, dvdx, dudy, dvdy)
    out = {"uv": [u, v], "uv derivatives": {"du/dx": dudx, "dv/dx": dvdx, "du/dy": dudy,
                                             "dv/dy": dvdy},
           "interpolated normal": [nx, ny, nz]}
    if bump and (maps[mesh, HEIGHT] >= 0 or maps[mesh, NORMAL_MAP] >= 0):
        pu = [lerp(DPDU + c) for c in range(3)]
        pv = [lerp(DPDV + c) for c in range(3)]
        if maps[mesh, HEIGHT] >= 0:
            nx, ny, nz = bumped_normal(nx, ny, nz, *pu, *pv, texels, levels, textures,
                                       int(maps[mesh, HEIGHT]), maps[mesh, BUMP_SCALE], filter_,
                                       u, v, *derivs)
            out["normal map"] = "height (Blinn's bump mapping)"
        else:
            nx, ny, nz = mapped_normal(nx, ny, nz, *pu, *pv, texels, levels, textures,
                                       int(maps[mesh, NORMAL_MAP]), filter_, u, v, *derivs)
            out["normal map"] = "tangent-space normal map"
        out["perturbed normal"] = [nx, ny, nz]
    surf = s.surfaces.copy()
    if maps[mesh, COLOR] >= 0:
        k = int(maps[mesh, COLOR])
        r, g, b, _ = lookup(texels, levels, textures, k, filter_, u, v, *derivs)
        out["texture"] = _texels_read(texels, levels, textures, k, filter_, u, v, derivs)
        out["texture"]["filtered (linear)"] = [r, g, b]
        if maps[mesh, COLOR_SRGB] > 0.5:
            r, g, b = encode_srgb(r), encode_srgb(g), encode_srgb(b)
        out["texture"]["O_d"] = [r, g, b]
        surf[mesh, OD], surf[mesh, OD + 1], surf[mesh, OD + 2] = r, g, b
    terms = lighting_terms(p, (nx, ny, nz), mesh, surf, s.lights, s.ambient, s.eye, s.halfway)
    out["phong"] = terms
    rgb = list(terms["clamped"])
    if maps[mesh, ENVIRONMENT] >= 0 and maps[mesh, REFLECTIVITY] > 0.0:
        from core.texture.surface import view_direction
        vx, vy, vz = view_direction(s.eye, *p)
        d = nx * vx + ny * vy + nz * vz
        if d < 0.0 and surf[mesh, TWO_SIDED] != 0.0:
            nx, ny, nz, d = -nx, -ny, -nz, -d
        er, eg, eb = environment(texels, levels, textures, int(maps[mesh, ENVIRONMENT]),
                                 2 * d * nx - vx, 2 * d * ny - vy, 2 * d * nz - vz)
        k = maps[mesh, REFLECTIVITY]
        env = [encode_srgb(er), encode_srgb(eg), encode_srgb(eb)]
        rgb = [(1 - k) * rgb[c] + k * env[c] for c in range(3)]
        out["environment"] = {"reflectivity": float(k), "colour": env}
    out["sum"] = rgb
    return out


def _texels_read(texels, levels, textures, k, filter_, u, v, derivs) -> dict:
    """Which texels ``sample`` read for this pixel, with their weights (levels of texture k)."""
    first, count, wrap = (int(c) for c in textures[k])
    lam = float(sampling.level_of_detail(levels, *derivs, first))
    out = {"texture": k, "size": [int(levels[first, 1]), int(levels[first, 2])],
           "levels": count, "lambda": lam}
    if filter_ == sampling.NEAREST:
        out["mip level"] = 0
        out["texels"] = [_nearest(texels, levels, wrap, first, u, v)]
        return out
    if filter_ == sampling.BILINEAR:
        out["mip level"] = 0
        out["texels"] = _bilinear(texels, levels, wrap, first, 0, u, v, 1.0)
        return out
    probes = [(u, v, lam, 1.0)]
    if filter_ == sampling.ANISOTROPIC:
        probes = _probes(levels, first, u, v, derivs, lam)
    read = []
    for pu, pv, plam, weight in probes:
        read += _mip(texels, levels, wrap, first, count, plam, pu, pv, weight)
    out["mip level"] = (0.0 if not lam > 0.0 else min(lam, count - 1))
    out["texels"] = read
    return out


def _texel(texels, levels, level, i, j):
    row = levels[level, 0] + j * levels[level, 1] + i
    return [float(c) for c in texels[row]]


def _nearest(texels, levels, wrap, level, u, v) -> dict:
    w, h = int(levels[level, 1]), int(levels[level, 2])
    i = int(sampling.wrap_index(sampling.floor_index(u * w), w, wrap))
    j = int(sampling.wrap_index(sampling.floor_index(v * h), h, wrap))
    return {"level": 0, "i": i, "j": j, "weight": 1.0,
            "rgba": _texel(texels, levels, level, i, j)}


def _bilinear(texels, levels, wrap, level, index, u, v, weight) -> list:
    w, h = int(levels[level, 1]), int(levels[level, 2])
    x, y = u * w - 0.5, v * h - 0.5
    i0, j0 = sampling.floor_index(x), sampling.floor_index(y)
    alpha, beta = x - math.floor(x), y - math.floor(y)
    if not (math.isfinite(alpha) and math.isfinite(beta)):
        alpha, beta = 0.0, 0.0
    out = []
    for di, dj, wt in ((0, 0, (1 - alpha) * (1 - beta)), (1, 0, alpha * (1 - beta)),
                       (0, 1, (1 - alpha) * beta), (1, 1, alpha * beta)):
        i = int(sampling.wrap_index(i0 + di, w, wrap))
        j = int(sampling.wrap_index(j0 + dj, h, wrap))
        out.append({"level": index, "i": i, "j": j, "weight": weight * wt,
                    "rgba": _texel(texels, levels, level, i, j)})
    return out


def _mip(texels, levels, wrap, first, count, lam, u, v, weight) -> list:
    """mip_at's texels: bilinear on the two levels around λ (or level 0 / the last)."""
    last = count - 1
    if not lam > 0.0:
        return _bilinear(texels, levels, wrap, first, 0, u, v, weight)
    if lam >= last:
        return _bilinear(texels, levels, wrap, first + last, last, u, v, weight)
    d1 = int(math.floor(lam))
    f = lam - d1
    return (_bilinear(texels, levels, wrap, first + d1, d1, u, v, weight * (1 - f))
            + _bilinear(texels, levels, wrap, first + d1 + 1, d1 + 1, u, v, weight * f))


def _probes(levels, first, u, v, derivs, lam) -> list:
    """anisotropic's probes along the major axis: (u, v, λ, weight)."""
    dudx, dvdx, dudy, dvdy = derivs
    rho_x, rho_y = sampling.footprint(levels, dudx, dvdx, dudy, dvdy, first)
    if rho_x >= rho_y:
        major, minor, du, dv = rho_x, rho_y, dudx, dvdx
    else:
        major, minor, du, dv = rho_y, rho_x, dudy, dvdy
    if not (major > 0.0 and math.isfinite(major)):
        return [(u, v, lam, 1.0)]
    n = (sampling.MAX_ANISOTROPY if not minor > 0.0
         else int(min(math.ceil(major / minor), sampling.MAX_ANISOTROPY)))
    n = max(n, 1)
    level = math.log2(major / n)
    return [(u + ((k + 0.5) / n - 0.5) * du, v + ((k + 0.5) / n - 0.5) * dv, level, 1.0 / n)
            for k in range(n)]
