"""Kajiya's rendering equation (1986) by path tracing, one numba loop per camera ray.

    L(x, ω_o) = L_e(x, ω_o) + ∫ f(x, ω_i, ω_o) L(x', −ω_i) cos θ_i dω_i

Units match :mod:`core.radiosity`: an emitter's ``emission`` is its radiance, a diffuse surface
reflects with the BRDF ρ/π (ρ = k_d O_d), so a lit wall's pixel is its radiosity B. The
glossy lobe is the material's lighting model's (:mod:`core.shading.models`, reached through
its seam ``glossy`` / ``sample_glossy``): for Phong, the normalised modified Phong BRDF
k_s O_s (n + 2)/(2π) cos^n α (α between the mirror direction and ω_o); mirrors (k_r) and
glass (k_t, index ``ior``) are delta lobes.

At each hit along a path (``throughput`` the product of f cos / pdf so far):

1. emission seen directly (first hit, after a delta bounce) counts whole; seen after a
   diffuse or glossy bounce, it is weighted by multiple importance sampling (Veach's power
   heuristic) against the light sampling of step 2;
2. next-event estimation: a point chosen on the emitting triangles (by area x emitted power)
   and a shadow ray, MIS-weighted against BSDF sampling; every point and directional light
   of the scene, with its shadow ray (a delta light: no MIS, the Phong model's units
   π I f_att cos θ as irradiance);
3. the next direction sampled from the BSDF: a lobe chosen in proportion to its weight
   (diffuse: cosine-weighted; Phong: the cos^n lobe about the mirror direction; mirror;
   glass: Snell's refraction, total internal reflection reflects);
4. Russian roulette from the fourth bounce on (survive with the throughput's largest channel,
   at most 0.95), and a hard limit of ``MAX_BOUNCES``.

Random numbers: splitmix64 per (ray, pass, seed), so a picture is reproducible. With a
``sample`` index (the pass: the pixel's k-th path), the first hit's six numbers (the light
sample's triangle and point, the BSDF's lobe and direction) are stratified instead: point k of
the R3 sequence (Roberts 2018: k α mod 1, α the powers of 1/φ₃, φ₃ the root of x⁴ = x + 1),
shifted by a random vector per pixel (Cranley and Patterson 1976). Each path stays an unbiased
estimate, and a pixel's first k paths spread over its light and its hemisphere evenly for every
k, so its noise falls faster than k^-1/2 where the first bounce carries it (the diffuse walls
of a Cornell box). Deeper bounces draw from splitmix64 as before.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import call_compiled, compiled_at, njit, prange
from core.camera.rays import clipped_ray, pixel_point
from core.raytrace.bvh import closest, new_stack, occluded, spread
from core.shading.illumination import SURFACE_COLUMNS
from core.shading.models.dispatch import glossy, sample_glossy
from core.vectors import around, reflect

MAX_BOUNCES = 64
# materials columns
RHO, KS, SHINE, KR, KT, IOR, EMIT, TWO_SIDED, OS, SURFACE = 0, 3, 4, 5, 6, 7, 8, 11, 12, 15
# SURFACE: the material's row of core.shading.illumination.pack_surfaces, which its lighting
# model's glossy lobe reads (core.shading.models).
MATERIAL_WIDTH = SURFACE + SURFACE_COLUMNS
EPS = 1e-7          # ray offset, times the scene's size
PHI3 = 1.2207440845731146                     # x**4 = x + 1: the R3 sequence's generator
R3 = (1.0 / PHI3, 1.0 / PHI3 ** 2, 1.0 / PHI3 ** 3)
INDEPENDENT = -1    # the sample index that asks for independent random numbers everywhere


@njit(cache=True, inline="always")
def _next(state):
    """splitmix64: (new state, uniform in [0, 1))."""
    state = (state + np.uint64(0x9E3779B97F4A7C15)) & np.uint64(0xFFFFFFFFFFFFFFFF)
    z = state
    z = ((z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)) & np.uint64(0xFFFFFFFFFFFFFFFF)
    z = ((z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)) & np.uint64(0xFFFFFFFFFFFFFFFF)
    z = z ^ (z >> np.uint64(31))
    return state, (z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@njit(cache=True)
def _lum(r, g, b):
    return 0.2126 * r + 0.7152 * g + 0.0722 * b


@njit(cache=True)
def _lobe_weights(m):
    """Probabilities of choosing diffuse, Phong, mirror, glass at a hit of material ``m``."""
    wd = _lum(m[RHO], m[RHO + 1], m[RHO + 2])
    ws = m[KS] * _lum(m[OS], m[OS + 1], m[OS + 2])
    wr, wt = m[KR], m[KT]
    total = wd + ws + wr + wt
    if total <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    return wd / total, ws / total, wr / total, wt / total


@njit(cache=True)
def _bsdf(m, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, pd, ps):
    """f (r, g, b) of the diffuse and glossy lobes and the pdf of sampling ω_i (solid angle);
    ω_o points away from the surface, n on its side."""
    cos_i = nx * wix + ny * wiy + nz * wiz
    if cos_i <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    fr = m[RHO] / math.pi
    fg = m[RHO + 1] / math.pi
    fb = m[RHO + 2] / math.pi
    pdf = pd * cos_i / math.pi
    if ps > 0.0:                          # the material's lighting model's glossy lobe
        gr, gg, gb, gp = glossy(m, SURFACE, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, ps)
        fr += gr
        fg += gg
        fb += gb
        pdf += gp
    return fr, fg, fb, pdf


@njit(cache=True)
def _emitted(m, front):
    if front or m[TWO_SIDED] > 0.0:
        return m[EMIT], m[EMIT + 1], m[EMIT + 2]
    return 0.0, 0.0, 0.0


@njit(cache=True)
def _light_pdf(emit_pdf, area, cos_l, dist2):
    """Solid-angle pdf of having chosen this point by light sampling."""
    if cos_l <= 0.0:
        return 0.0
    return emit_pdf / area * dist2 / cos_l


@njit(cache=True)
def _point_on(corners, e, u1, u2):
    """A uniform point on triangle ``e`` (Shirley's square-root warp)."""
    su = math.sqrt(u1)
    b0, b1 = 1.0 - su, u2 * su
    b2 = 1.0 - b0 - b1
    c = corners[e]
    return (b0 * c[0, 0] + b1 * c[1, 0] + b2 * c[2, 0], b0 * c[0, 1] + b1 * c[1, 1] + b2 * c[2, 1],
            b0 * c[0, 2] + b1 * c[1, 2] + b2 * c[2, 2])


@njit(cache=True)
def _sample_lobe(m, nx, ny, nz, wox, woy, woz, pd, ps, u0, u1, u2):
    """A direction from the diffuse or glossy lobe (chosen with pd : ps by ``u0``)."""
    if u0 * (pd + ps) < pd:               # cosine-weighted hemisphere
        r = math.sqrt(u1)
        phi = 2.0 * math.pi * u2
        return around(nx, ny, nz, r * math.cos(phi), r * math.sin(phi), math.sqrt(1.0 - u1))
    return sample_glossy(m, SURFACE, nx, ny, nz, wox, woy, woz, u1, u2)


# The kinds of ray a path is made of, and a recorded ray's columns.
CAMERA, DIFFUSE, MIRROR, GLASS = 0, 1, 2, 3
RAY_KINDS = ("camera", "diffuse or glossy (BSDF sample)", "mirror", "glass")
RECORD_WIDTH = 15     # origin 3, direction 3, kind, throughput 3, t, triangle, radiance so far 3


@njit(cache=True)
def _strata(seed, pixel, sample):
    """The six numbers of a pixel's ``sample``-th first hit: two points of the R3 sequence,
    each shifted by the pixel's own random vector (the same in every pass)."""
    state = np.uint64(seed) * np.uint64(0xD1B54A32D192ED03) + np.uint64(pixel)
    state, a = _next(state)
    state, b = _next(state)
    state, c = _next(state)
    state, d = _next(state)
    state, e = _next(state)
    state, f = _next(state)
    return (_shifted(a, sample, R3[0]), _shifted(b, sample, R3[1]), _shifted(c, sample, R3[2]),
            _shifted(d, sample, R3[0]), _shifted(e, sample, R3[1]), _shifted(f, sample, R3[2]))


@njit(cache=True)
def _shifted(shift, sample, alpha):
    """Point ``sample`` of the sequence k α mod 1, moved by ``shift`` (mod 1)."""
    v = shift + sample * alpha
    return v - math.floor(v)


@njit(cache=True)
def _record(row, ox, oy, oz, dx, dy, dz, kind, tr, tg, tb, t, tri, lr, lg, lb):
    row[0], row[1], row[2], row[3], row[4], row[5] = ox, oy, oz, dx, dy, dz
    row[6], row[7], row[8], row[9] = kind, tr, tg, tb
    row[10], row[11], row[12], row[13], row[14] = t, tri, lr, lg, lb


@njit(cache=True, inline="always")
def trace_path(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf,
               tri_area, tri_emit_pdf, lights, background, ox, oy, oz, dx, dy, dz, t_min, t_max,
               offset, state, strata, stratified, stack, record):
    """The radiance along one camera ray: ``(r, g, b, state, bounces)``; a camera ray that
    hits nothing sees the background colour (a path that leaves the scene later, nothing).
    ``record`` (R, RECORD_WIDTH): the first R rays of the path, for the pixel inspector
    (R = 0 when rendering). ``strata``: the first hit's six numbers when ``stratified``
    (:func:`_strata`)."""
    lr, lg, lb = 0.0, 0.0, 0.0
    tr, tg, tb = 1.0, 1.0, 1.0
    last_pdf = 0.0            # solid-angle pdf of the BSDF sample that made this ray
    delta = True              # a camera ray, or one after a mirror or glass bounce: no MIS
    kind = CAMERA
    for bounce in range(MAX_BOUNCES):
        k, t, _, _ = closest(bvh, ox, oy, oz, dx, dy, dz, t_min, t_max, stack)
        if bounce < record.shape[0]:
            _record(record[bounce], ox, oy, oz, dx, dy, dz, kind, tr, tg, tb,
                    t if k >= 0 else np.inf, bvh.prim[k] if k >= 0 else -1, lr, lg, lb)
        if k < 0:
            if bounce == 0:
                return background[0], background[1], background[2], state, 0
            return lr, lg, lb, state, bounce
        tri = bvh.prim[k]
        m = materials[tri_material[tri]]
        px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
        gx, gy, gz = tri_normal[tri, 0], tri_normal[tri, 1], tri_normal[tri, 2]
        cos_o = -(dx * gx + dy * gy + dz * gz)
        front = cos_o > 0.0
        nx, ny, nz = (gx, gy, gz) if front else (-gx, -gy, -gz)
        # 1. emission seen along the ray
        er, eg, eb = _emitted(m, front)
        if er + eg + eb > 0.0:
            w = 1.0
            if not delta:
                lp = _light_pdf(tri_emit_pdf[tri], tri_area[tri], abs(cos_o), t * t)
                w = last_pdf * last_pdf / (last_pdf * last_pdf + lp * lp)
            lr += tr * er * w
            lg += tg * eg * w
            lb += tb * eb * w
        pd, ps, pr, pt = _lobe_weights(m)
        if pd + ps + pr + pt <= 0.0:
            return lr, lg, lb, state, bounce
        wox, woy, woz = -dx, -dy, -dz
        sx, sy, sz = px + offset * nx, py + offset * ny, pz + offset * nz
        # 2. next-event estimation, for the diffuse and Phong lobes
        if pd + ps > 0.0:
            if emit_tri.shape[0] > 0:
                if stratified and bounce == 0:
                    u0, u1, u2 = strata[0], strata[1], strata[2]
                else:
                    state, u0 = _next(state)
                    state, u1 = _next(state)
                    state, u2 = _next(state)
                j = min(np.searchsorted(emit_cdf, u0 * emit_cdf[-1], side="right"),
                        emit_tri.shape[0] - 1)
                e = emit_tri[j]
                qx, qy, qz = _point_on(corners, e, u1, u2)
                lx, ly, lz = qx - sx, qy - sy, qz - sz
                dist2 = lx * lx + ly * ly + lz * lz
                dist = math.sqrt(dist2)
                if dist > 0.0:
                    lx, ly, lz = lx / dist, ly / dist, lz / dist
                    en = tri_normal[e]
                    cos_l = -(lx * en[0] + ly * en[1] + lz * en[2])
                    me = materials[tri_material[e]]
                    er, eg, eb = _emitted(me, cos_l > 0.0)
                    fr, fg, fb, bp = _bsdf(m, nx, ny, nz, wox, woy, woz, lx, ly, lz, pd, ps)
                    if er + eg + eb > 0.0 and fr + fg + fb > 0.0 and \
                            occluded(bvh, sx, sy, sz, lx, ly, lz, 0.0, dist * (1.0 - 1e-6),
                                     stack) < 0:
                        lp = _light_pdf(tri_emit_pdf[e], tri_area[e], abs(cos_l), dist2)
                        cos_s = nx * lx + ny * ly + nz * lz
                        w = lp * lp / (lp * lp + bp * bp)
                        g = w * cos_s / lp
                        lr += tr * fr * er * g
                        lg += tg * fg * eg * g
                        lb += tb * fb * eb * g
            for li in range(lights.shape[0]):
                light = lights[li]
                if light[9] > 0.0:                       # a point light
                    lx, ly, lz = light[0] - sx, light[1] - sy, light[2] - sz
                    dist = math.sqrt(lx * lx + ly * ly + lz * lz)
                    if dist == 0.0:
                        continue
                    lx, ly, lz = lx / dist, ly / dist, lz / dist
                    f_att = min(1.0, 1.0 / max(light[6] + light[7] * dist
                                               + light[8] * dist * dist, 1e-300))
                    reach = dist * (1.0 - 1e-9)
                else:                                    # directional: towards the light
                    lx, ly, lz = light[0], light[1], light[2]
                    f_att, reach = 1.0, np.inf
                cos_s = nx * lx + ny * ly + nz * lz
                if cos_s <= 0.0:
                    continue
                fr, fg, fb, _ = _bsdf(m, nx, ny, nz, wox, woy, woz, lx, ly, lz, pd, ps)
                if occluded(bvh, sx, sy, sz, lx, ly, lz, 0.0, reach, stack) >= 0:
                    continue
                g = math.pi * f_att * cos_s
                lr += tr * fr * light[3] * g
                lg += tg * fg * light[4] * g
                lb += tb * fb * light[5] * g
        # 3. the next direction, from a lobe chosen by its weight
        if stratified and bounce == 0:
            u0, u1, u2 = strata[3], strata[4], strata[5]
        else:
            state, u0 = _next(state)
            state, u1 = _next(state)
            state, u2 = _next(state)
        if u0 < pd + ps:
            wx, wy, wz = _sample_lobe(m, nx, ny, nz, wox, woy, woz, pd, ps, u0 / (pd + ps),
                                      u1, u2)
            fr, fg, fb, bp = _bsdf(m, nx, ny, nz, wox, woy, woz, wx, wy, wz, pd, ps)
            if bp <= 0.0:
                return lr, lg, lb, state, bounce
            cos_i = nx * wx + ny * wy + nz * wz
            tr, tg, tb = tr * fr * cos_i / bp, tg * fg * cos_i / bp, tb * fb * cos_i / bp
            last_pdf, delta, kind = bp, False, DIFFUSE
            ox, oy, oz = sx, sy, sz
        elif u0 < pd + ps + pr:                       # mirror: k_r, chosen with pr
            wx, wy, wz = reflect(dx, dy, dz, nx, ny, nz)
            scale = m[KR] / pr
            tr, tg, tb = tr * scale, tg * scale, tb * scale
            delta, kind = True, MIRROR
            ox, oy, oz = sx, sy, sz
        else:                                         # glass: k_t, Snell's law
            eta = 1.0 / m[IOR] if front else m[IOR]
            c = -(dx * nx + dy * ny + dz * nz)
            k2 = 1.0 - eta * eta * (1.0 - c * c)
            if k2 < 0.0:                              # total internal reflection
                wx, wy, wz = reflect(dx, dy, dz, nx, ny, nz)
                ox, oy, oz = sx, sy, sz
            else:
                a = eta * c - math.sqrt(k2)
                wx, wy, wz = eta * dx + a * nx, eta * dy + a * ny, eta * dz + a * nz
                ox, oy, oz = px - offset * nx, py - offset * ny, pz - offset * nz
            scale = m[KT] / pt
            tr, tg, tb = tr * scale, tg * scale, tb * scale
            delta, kind = True, GLASS
        dx, dy, dz = wx, wy, wz
        t_min, t_max = 0.0, np.inf
        # 4. Russian roulette
        if bounce >= 3:
            q = min(0.95, max(tr, tg, tb))
            state, u = _next(state)
            if u >= q:
                return lr, lg, lb, state, bounce + 1
            tr, tg, tb = tr / q, tg / q, tb / q
    return lr, lg, lb, state, MAX_BOUNCES


# No reference counts (numba's _nrt): the run makes no array, and the counts of the views
# and tuples of arrays a path passes around took a fifth of its time, atomically, per bounce.
@njit(cache=True, _nrt=False)
def trace_run(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf, tri_area,
              tri_emit_pdf, lights, background, cam, width, height, offset_x, offset_y, offset,
              seed, first_pixel, strata_seed, sample, start, end, out, stack, record):
    """Pixels ``first_pixel + start .. first_pixel + end − 1`` of a pass, each one's camera ray
    made here (:func:`core.camera.rays.clipped_ray` at the pass's film offset), their
    radiance into ``out[start:end]``; returns their bounces. One call per run of pixels,
    with :func:`trace_path` inlined in its loop: a numba call hands over each of its ~15
    arrays (reference counts) and cost about a tenth of a path when made once per ray.
    ``record``: the path of a run of one pixel, or (0, …)."""
    total = 0
    for i in range(start, end):
        pixel = first_pixel + i
        state = np.uint64(seed) * np.uint64(0x632BE59BD9B4E019) + np.uint64(pixel)
        state, _ = _next(state)
        x, y = pixel_point(width, height, pixel, offset_x, offset_y)
        ox, oy, oz, dx, dy, dz, t_min, t_max = clipped_ray(cam, x, y)
        if not t_min < t_max:                # outside the viewport (letterbox)
            out[i, 0], out[i, 1], out[i, 2] = background[0], background[1], background[2]
            continue
        strata = _strata(strata_seed, pixel, max(sample, 0))
        r, g, b, state, depth = trace_path(
            bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf,
            tri_area, tri_emit_pdf, lights, background, ox, oy, oz, dx, dy, dz, t_min, t_max,
            offset, state, strata, sample >= 0, stack, record)
        out[i, 0], out[i, 1], out[i, 2] = r, g, b
        total += depth
    return total


@njit(cache=True, parallel=True, nogil=True)
def trace_many(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf, tri_area,
               tri_emit_pdf, lights, background, cam, width, height, offset_x, offset_y, offset,
               seed, out, bounces, first_pixel, strata_seed, sample, at):
    """Radiance of pixels ``first_pixel .. first_pixel + N − 1`` of one pass into ``out``
    (N, 3): rays from the packed camera ``cam`` (:func:`core.camera.rays.pack_camera`) of a
    ``width`` x ``height`` picture at film offset (``offset_x``, ``offset_y``); ``bounces``
    (chunks,) the path lengths. A pixel draws its random numbers from (seed, its index in the
    frame), so it can be traced again alone (the inspector). ``sample`` >= 0: the paths are
    their pixels' ``sample``-th, whose first hits are stratified (:func:`_strata` with
    ``strata_seed``); ``INDEPENDENT``: they are not. ``at``: :func:`trace_run`'s machine
    code for these arguments (:func:`trace_run_at`), called by its address."""
    n = out.shape[0]
    no_record = np.empty((0, RECORD_WIDTH))
    chunks = (n + 255) // 256
    for j in prange(chunks):
        chunk = spread(j, chunks)
        bounces[chunk] = call_compiled(
            at, trace_run, bvh, corners, tri_normal, tri_material, materials, emit_tri,
            emit_cdf, tri_area, tri_emit_pdf, lights, background, cam, width, height,
            offset_x, offset_y, offset, seed, first_pixel, strata_seed, sample, chunk * 256,
            min(n, (chunk + 1) * 256), out, new_stack(), no_record)


def trace_run_at(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf,
                 tri_area, tri_emit_pdf, lights, background, cam, width, height, offset_x,
                 offset_y, offset, seed, out, bounces, first_pixel, strata_seed,
                 sample) -> tuple[int, int]:
    """:func:`trace_run`'s machine code for the arguments :func:`trace_many` gives it."""
    return compiled_at(trace_run, (
        bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf, tri_area,
        tri_emit_pdf, lights, background, cam, width, height, offset_x, offset_y, offset, seed,
        first_pixel, strata_seed, sample, 0, 0, out, new_stack(), np.empty((0, RECORD_WIDTH))))


@njit(cache=True)
def trace_recorded(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf,
                   tri_area, tri_emit_pdf, lights, background, cam, width, height, offset_x,
                   offset_y, offset, seed, pixel, strata_seed, sample, record):
    """Pixel ``pixel`` of a pass, as :func:`trace_many` traces it, with its path in
    ``record``: ``(r, g, b, bounces)``."""
    out = np.empty((1, 3))
    depth = trace_run(bvh, corners, tri_normal, tri_material, materials, emit_tri, emit_cdf,
                      tri_area, tri_emit_pdf, lights, background, cam, width, height,
                      offset_x, offset_y, offset, seed, pixel, strata_seed, sample, 0, 1, out,
                      new_stack(), record)
    return out[0, 0], out[0, 1], out[0, 2], depth
