"""Whitted's recursive ray tracer (the notes of April 2–9; Whitted 1980), in numba.

At each intersection the notes evaluate four things — the shadow rays, ``I_local`` (Phong),
the reflected ``I_r`` and the transmitted ``I_t`` — and sum them (Whitted's formula, with the
halfway or the reflection form of the specular term as the scene says)::

    I = I_a k_a O_d + Σ_i S_i f_att,i I_p,i [k_d O_d (N·L_i) + k_s O_s (·)^n]  +  k_r I_r  +  k_t I_t

- ``I_local`` is :func:`core.shading.illumination.phong_point`, the project's one Phong model,
  with each light's ``I_p`` multiplied by its shadow term ``S_i`` (one shadow ray per light).
  ``S_i``, the notes' three options for an object in the way (``shadows``):
  ``"background"``: the light arriving is the background colour (black: a hard shadow);
  ``"object"``: a fraction :data:`OBJECT_FRACTION` of the first occluder's colour ``O_d``;
  ``"transmit"`` (default): keep tracing through, multiplying by each surface's ``k_t``
  (opaque surfaces have ``k_t = 0``); ``"off"``: no shadow rays (``S_i = 1``).
- ``I_r``: the ray mirrored about the shading normal (:func:`core.raytrace.optics.reflect`).
- ``I_t``: the ray refracted by Snell's law, ``T = αI + βN``
  (:func:`core.raytrace.optics.refract`), from the medium (``medium``, air by default) into the
  surface's ``ior`` when the ray enters (it meets the front of the geometric normal) and back
  out when it leaves. Total internal reflection: no ``T``; its ``k_t`` goes to the reflected
  ray (the light is reflected, not lost). ``fresnel``: Schlick's weight
  (:func:`core.raytrace.optics.schlick`) or the exact Fresnel equations
  (:func:`core.raytrace.optics.fresnel_exact`) move ``F k_t`` from transmission to reflection.
- Sides: both children keep to the side the geometric normal says; a direction made about the
  shading normal that would cross the face is made about the face's normal instead.
- The ray tree: a primary ray is depth 1; a ray of depth ``max_depth`` spawns no children
  (the notes' "N ≤ 7"). A total internal reflection does not split the ray, so it does not
  deepen the tree (up to :data:`MAX_INTERNAL` in a row): light trapped in glass is followed
  instead of being cut to black (cutting it left black speckles in the glass bunny).
  Adaptive depth control (the notes' "k_1 · k_2 · … · k_n ≤ ε"): a child whose weight, the
  product of the k's on its path, is below ``epsilon`` is not cast; with ``attenuation``
  (C1, C2) a secondary ray's weight is also divided by ``1 + C1 R + C2 R²`` over its length R.
- Textures: a textured triangle is shaded by the z-buffer's pixel step
  (:func:`core.texture.surface.textured_at`), its footprint from the ray's differentials
  (:func:`transfer`, :func:`uv_derivatives`), which every child ray carries on.

The recursion is written as a loop over an explicit stack of pending rays, each carrying its
weight: ``I`` is linear in ``I_r`` and ``I_t``, so ``Σ weight · I_local`` over the tree's nodes
is the recursive sum exactly, and numba needs no recursive function. Colours are summed
unclamped (``raw``; clamped only when turned into bytes) so that energy can be checked.

Secondary rays start ``offset`` (a tiny fraction of the scene's size) off the surface along the
geometric normal, on the side they leave towards, so they cannot hit their own surface.

Per frame the kernel counts the rays of each kind (:data:`COUNTERS`).
"""

from __future__ import annotations

import math

import numpy as np

from numba.core import types

from core.jit import (NOT_COMPILED, SimplifiedCompiler, call_compiled, compiled_apart,
                      compiled_at, njit, prange)
from core.raytrace import bvh, intersect, optics
from core.texture.surface import UV, textured_at
from core.shading.illumination import (EYE_DIRECTION, EYE_POINT, LIGHT_INTENSITY, OD, POINT_LIGHT,
                                       TWO_SIDED, unit3)
from core.shading.models.dispatch import light_point_calling

from core.settings import SHADOW_MODES  # noqa: E402,F401  (listed with the other settings)
SHADOW_OFF, SHADOW_BACKGROUND, SHADOW_OBJECT, SHADOW_TRANSMIT = 0, 1, 2, 3
OBJECT_FRACTION = 0.3          # "object" shadows: this fraction of the occluder's colour passes
MAX_SHADOW_CROSSINGS = 64      # "transmit": surfaces a shadow ray may pass before giving up
COUNTERS = ("primary", "shadow", "reflected", "refracted", "total internal reflections",
            "cut by depth", "cut by adaptive control")
PRIMARY, SHADOW, REFLECTED, REFRACTED, TIR, CUT_DEPTH, CUT_ADAPTIVE = range(7)
NOTHING, TRIANGLE, SPHERE, PLANE = -1, 0, 1, 2
FEW_SPHERES = 8        # up to this many spheres are tested one by one; more, through their BVH


@njit(cache=True, inline="always")
def nearest(packed, ox, oy, oz, dx, dy, dz, t_min, t_max, stack):
    """``(kind, index, t, u, v)`` of the nearest hit in ``(t_min, t_max)``: a triangle (its
    BVH position), a sphere or a plane (its row); ``kind = NOTHING`` when the ray escapes."""
    kind, index = NOTHING, -1
    k, t, u, v = bvh.closest(packed, ox, oy, oz, dx, dy, dz, t_min, t_max, stack)
    if k >= 0:
        kind, index, t_max = TRIANGLE, k, t
    spheres = packed.spheres
    if spheres.shape[0] <= FEW_SPHERES:      # a few: testing each beats walking a tree
        for i in range(spheres.shape[0]):
            t_s = intersect.sphere(ox, oy, oz, dx, dy, dz, spheres[i, 0], spheres[i, 1],
                                   spheres[i, 2], spheres[i, 3], t_min, t_max)
            if t_s < t_max:
                kind, index, t_max = SPHERE, i, t_s
    else:
        i, t_s = bvh.closest_sphere(packed.sphere_box, packed.sphere_first, packed.sphere_count,
                                    packed.sphere_item, spheres, ox, oy, oz, dx, dy, dz,
                                    t_min, t_max, stack)
        if i >= 0:
            kind, index, t_max = SPHERE, i, t_s
    planes = packed.planes
    for i in range(planes.shape[0]):
        t_p = intersect.plane(ox, oy, oz, dx, dy, dz, planes[i, 0], planes[i, 1], planes[i, 2],
                              planes[i, 3], t_min, t_max)
        if t_p < t_max:
            kind, index, t_max = PLANE, i, t_p
    return kind, index, t_max, u, v


@njit(cache=True, inline="always")
def surface_at(packed, kind, index, u, v, ox, oy, oz, dx, dy, dz, t):
    """The hit point, the unit shading normal, the unit geometric normal and the surface row.

    A triangle's point is ``V0 + u E1 + v E2`` and its shading normal the vertex normals
    interpolated with ``(1 − u − v, u, v)`` — what the z-buffer's Phong shading computes."""
    if kind == TRIANGLE:
        tri = packed.tri            # rows V0, E1, E2 of each triangle's column, in BVH order
        px = tri[0, index] + u * tri[3, index] + v * tri[6, index]
        py = tri[1, index] + u * tri[4, index] + v * tri[7, index]
        pz = tri[2, index] + u * tri[5, index] + v * tri[8, index]
        e1x, e1y, e1z = tri[3, index], tri[4, index], tri[5, index]
        e2x, e2y, e2z = tri[6, index], tri[7, index], tri[8, index]
        gx, gy, gz, _ = unit3(e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z,
                              e1x * e2y - e1y * e2x)
        f = packed.prim[index]
        i0, i1, i2 = packed.corners[f, 0], packed.corners[f, 1], packed.corners[f, 2]
        w0 = 1.0 - u - v
        nrm = packed.normals
        nx, ny, nz, length = unit3(w0 * nrm[i0, 0] + u * nrm[i1, 0] + v * nrm[i2, 0],
                                   w0 * nrm[i0, 1] + u * nrm[i1, 1] + v * nrm[i2, 1],
                                   w0 * nrm[i0, 2] + u * nrm[i1, 2] + v * nrm[i2, 2])
        if length == 0.0:
            nx, ny, nz = gx, gy, gz
        return px, py, pz, nx, ny, nz, gx, gy, gz, packed.face_surface[f]
    px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
    if kind == SPHERE:
        row = packed.spheres[index]
        # The notes' normal ((x − a)/r, (y − b)/r, (z − c)/r), renormalised against rounding.
        nx, ny, nz, _ = unit3(px - row[0], py - row[1], pz - row[2])
        return px, py, pz, nx, ny, nz, nx, ny, nz, int(row[4])
    row = packed.planes[index]
    return px, py, pz, row[0], row[1], row[2], row[0], row[1], row[2], int(row[4])


@njit(cache=True, inline="always")
def checker_colour(packed, kind, index, s, px, py, pz, surface_row):
    """Copy surface ``s``'s Phong row into ``surface_row`` with ``O_d`` the checker's square
    colour at P (planes with ``checker > 0``; other surfaces keep their ``O_d``)."""
    for c in range(surface_row.shape[1]):
        surface_row[0, c] = packed.surfaces[s, c]
    side = packed.checker[s, 0]
    if kind != PLANE or not side > 0.0:
        return
    row = packed.planes[index]
    # Squares counted along the in-plane axes e1, e2 from the plane's given point.
    a = math.floor((px * row[5] + py * row[6] + pz * row[7] - row[11]) / side)
    b = math.floor((px * row[8] + py * row[9] + pz * row[10] - row[12]) / side)
    if (a + b) % 2 != 0:
        for c in range(3):
            surface_row[0, OD + c] = packed.checker[s, 1 + c]


@njit(cache=True, inline="always")
def surface_of(packed, kind, index):
    """The surface row of a hit (what a shadow ray needs of it: no point, no normal)."""
    if kind == TRIANGLE:
        return packed.face_surface[packed.prim[index]]
    if kind == SPHERE:
        return int(packed.spheres[index, 4])
    return int(packed.planes[index, 4])


@njit(cache=True, inline="always")
def shadow_term(packed, mode, light, px, py, pz, background, offset, stack, counts):
    """``(S_r, S_g, S_b)``: how much of light row ``light`` reaches P (already offset).

    One loop for the three modes: the first surface in the way decides "background" and
    "object"; "transmit" walks on through every surface up to the light, attenuating by each
    ``k_t``."""
    if light[0] == POINT_LIGHT:
        lx, ly, lz, distance = unit3(light[1] - px, light[2] - py, light[3] - pz)
        if distance == 0.0:
            return 1.0, 1.0, 1.0
        t_max = distance - offset
    else:
        lx, ly, lz, t_max = light[1], light[2], light[3], np.inf
    counts[SHADOW] += 1
    through = 1.0
    ox, oy, oz = px, py, pz
    for _ in range(MAX_SHADOW_CROSSINGS):
        kind, index, t, _, _ = nearest(packed, ox, oy, oz, lx, ly, lz, 0.0, t_max, stack)
        if kind == NOTHING:
            return through, through, through
        if mode == SHADOW_BACKGROUND:
            return background[0], background[1], background[2]
        s = surface_of(packed, kind, index)
        if mode == SHADOW_OBJECT:
            sr = packed.surfaces
            return (OBJECT_FRACTION * sr[s, OD], OBJECT_FRACTION * sr[s, OD + 1],
                    OBJECT_FRACTION * sr[s, OD + 2])
        through *= packed.optics[s, 1]
        if through == 0.0:
            return 0.0, 0.0, 0.0
        ox, oy, oz = ox + (t + offset) * lx, oy + (t + offset) * ly, oz + (t + offset) * lz
        t_max -= t + offset
        counts[SHADOW] += 1
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def hit_viewer(ray_kind, primary_eye, dx, dy, dz, eye):
    """``eye`` := the viewer of a hit: the primary eye (the PRP or the parallel DOP) for a
    primary ray, exactly as the z-buffer's shading sees it; the ray's origin for the others."""
    if ray_kind == PRIMARY:
        for c in range(4):
            eye[c] = primary_eye[c]
    else:
        eye[0], eye[1], eye[2], eye[3] = EYE_DIRECTION, -dx, -dy, -dz


@njit(cache=True, inline="always")
def lit_normal(surfaces, s, nx, ny, nz, gx, gy, gz, dx, dy, dz):
    """``(entering, N to light)``: whether the ray enters the surface (against its geometric
    normal), and a closed surface seen from inside (camera in a mesh, a ray in glass) lit on
    its inner side. Two-sided surfaces are turned to the viewer by the lighting model itself."""
    entering = gx * dx + gy * dy + gz * dz < 0.0
    if not entering and surfaces[s, TWO_SIDED] == 0.0:
        return entering, -nx, -ny, -nz
    return entering, nx, ny, nz


@njit(cache=True, inline="always")
def has_maps(tex, kind, s):
    """Does the hit surface carry a colour, bump, normal or environment map?"""
    if kind != TRIANGLE:
        return False
    for c in range(4):
        if tex.maps[s, c] >= 0.0:
            return True
    return False


@compiled_apart(returns=types.UniTuple(types.float64, 3))
@njit(cache=True, _nrt=False)    # no reference counts, as trace
def textured_colour(packed, index, s, px, py, pz, nx, ny, nz, arriving, ambient, eye, halfway,
                    tex, filter_, bump, u, v, duv, surf):
    """``I_local`` of a textured triangle (BVH position ``index``, barycentrics ``(u, v)``)
    lit by ``arriving`` (the lights scaled by their shadows, :func:`shadowed_lights`): the
    z-buffer's textured pixel step (:func:`core.texture.surface.textured_at`) with the (u, v)
    derivatives ``duv`` of the ray's differentials. :func:`trace` calls it by its address
    (:func:`colour_at`), so that a scene without textures never compiles it."""
    f = packed.prim[index]
    i0, i1, i2 = packed.corners[f, 0], packed.corners[f, 1], packed.corners[f, 2]
    w0 = 1.0 - u - v
    a = tex.attrs
    tu = w0 * a[i0, UV] + u * a[i1, UV] + v * a[i2, UV]
    tv = w0 * a[i0, UV + 1] + u * a[i1, UV + 1] + v * a[i2, UV + 1]
    r, g, b = textured_at(a, i0, i1, i2, w0, u, v, tu, tv, duv[0], duv[1], duv[2], duv[3], s,
                          tex.maps, tex.texels, tex.levels, tex.textures, filter_, bump, surf,
                          arriving, ambient, eye, halfway)
    for c in range(3):                                  # textured_at wrote its texel's O_d
        surf[s, OD + c] = packed.surfaces[s, OD + c]
    return r, g, b


def colour_at(packed, lights, ambient, halfway, tex, textured, filter_, bump):
    """:func:`textured_colour`'s machine code for the arguments :func:`trace` gives it,
    compiled for a scene with textures only (:data:`core.jit.NOT_COMPILED` without: no
    triangle then has maps, and :func:`trace` never calls it)."""
    if not textured:
        return NOT_COMPILED
    given = (packed, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, lights, ambient, np.empty(4), halfway,
             tex, filter_, bump, 0.0, 0.0, np.zeros(4), packed.surfaces.copy())  # scratch's
    return compiled_at(textured_colour, given)


@njit(cache=True, inline="always")
def shadowed_lights(packed, px, py, pz, nx, ny, nz, gx, gy, gz, lights, eye, shadows,
                    background, offset, scaled, surface_row, stack, counts):
    """The light rows as they arrive at P: ``lights`` itself with shadows off, else
    ``scaled``, each ``I_p`` times its shadow term (one shadow ray per light facing P)."""
    if shadows == SHADOW_OFF or lights.shape[0] == 0:
        return lights
    # The side the viewer sees, as phong_point decides it: V towards the eye.
    if eye[0] == EYE_POINT:
        vx, vy, vz, _ = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
    else:
        vx, vy, vz = eye[1], eye[2], eye[3]
    lit_nx, lit_ny, lit_nz = nx, ny, nz
    if surface_row[0, TWO_SIDED] != 0.0 and nx * vx + ny * vy + nz * vz < 0.0:
        lit_nx, lit_ny, lit_nz = -nx, -ny, -nz
    # Shadow rays leave from the viewer's side of the surface.
    side = 1.0 if gx * vx + gy * vy + gz * vz >= 0.0 else -1.0
    sx, sy, sz = px + side * offset * gx, py + side * offset * gy, pz + side * offset * gz
    for k in range(lights.shape[0]):
        for c in range(lights.shape[1]):
            scaled[k, c] = lights[k, c]
        if lights[k, 0] == POINT_LIGHT:
            lx, ly, lz, _ = unit3(lights[k, 1] - px, lights[k, 2] - py, lights[k, 3] - pz)
        else:
            lx, ly, lz = lights[k, 1], lights[k, 2], lights[k, 3]
        if lit_nx * lx + lit_ny * ly + lit_nz * lz <= 0.0:
            continue                       # the light is behind the lit side: no ray needed
        s_r, s_g, s_b = shadow_term(packed, shadows, lights[k], sx, sy, sz, background, offset,
                                    stack, counts)
        scaled[k, LIGHT_INTENSITY] *= s_r
        scaled[k, LIGHT_INTENSITY + 1] *= s_g
        scaled[k, LIGHT_INTENSITY + 2] *= s_b
    return scaled


@njit(cache=True)
def transfer(dif, t, dx, dy, dz, gx, gy, gz, dp):
    """Igehy's (1999) transfer of a ray's differentials to its hit at ``t`` on the plane of
    normal G: ``dP = dO + t dD`` moved along D back onto the plane (rows of ``dp``: ∂P/∂x,
    ∂P/∂y; rows of ``dif``: ∂O/∂x, ∂D/∂x, ∂O/∂y, ∂D/∂y, per pixel)."""
    d_dot_g = dx * gx + dy * gy + dz * gz
    for k in range(2):
        ax = dif[2 * k, 0] + t * dif[2 * k + 1, 0]
        ay = dif[2 * k, 1] + t * dif[2 * k + 1, 1]
        az = dif[2 * k, 2] + t * dif[2 * k + 1, 2]
        dt = -(ax * gx + ay * gy + az * gz) / d_dot_g if d_dot_g != 0.0 else 0.0
        dp[k, 0], dp[k, 1], dp[k, 2] = ax + dt * dx, ay + dt * dy, az + dt * dz


@njit(cache=True)
def uv_derivatives(packed, tex, index, dp, duv):
    """``duv`` = (∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y) of the texture coordinates on triangle
    ``index`` (BVH order) from the point's derivatives ``dp``: ``dP = dβ₁ E1 + dβ₂ E2``
    solved by least squares in the triangle's plane, then (u, v) interpolated."""
    e1, e2 = packed.tri[3:6, index], packed.tri[6:9, index]
    a = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]
    b = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]
    c = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]
    det = a * c - b * b
    f = packed.prim[index]
    i0, i1, i2 = packed.corners[f, 0], packed.corners[f, 1], packed.corners[f, 2]
    at = tex.attrs
    for k in range(2):
        if not det > 0.0:
            duv[2 * k], duv[2 * k + 1] = 0.0, 0.0
            continue
        r1 = e1[0] * dp[k, 0] + e1[1] * dp[k, 1] + e1[2] * dp[k, 2]
        r2 = e2[0] * dp[k, 0] + e2[1] * dp[k, 1] + e2[2] * dp[k, 2]
        db1, db2 = (c * r1 - b * r2) / det, (a * r2 - b * r1) / det
        for m in range(2):
            duv[2 * k + m] = (db1 * (at[i1, UV + m] - at[i0, UV + m])
                              + db2 * (at[i2, UV + m] - at[i0, UV + m]))


RAY_COLUMNS = 11               # origin, direction, t_min, t_max, weight, depth, kind
DIFF = RAY_COLUMNS             # then the ray differentials ∂O/∂x, ∂D/∂x, ∂O/∂y, ∂D/∂y (12)
PARENT = DIFF + 12             # then the ray tree record of the ray that spawned it
INTERNAL = PARENT + 1          # then the total internal reflections in a row that led to it
STACK_COLUMNS = INTERNAL + 1
MAX_INTERNAL = 64              # total internal reflections in a row a ray tree follows
FRESNEL_OFF, FRESNEL_SCHLICK, FRESNEL_EXACT = 0, 1, 2
FRESNEL_FORMS = ("schlick", "exact")
# Columns of a ray tree record (trace's ``tree``, for the pixel inspector): the ray's kind,
# depth, origin, direction, parent record (-1: none), what it hit (NOTHING / TRIANGLE /
# SPHERE / PLANE) and where (t), the surface row, I_local (the background for a miss), the
# weight, the hit point, the normal the children were spawned about, the geometric normal.
(TREE_KIND, TREE_DEPTH, TREE_ORIGIN, TREE_DIRECTION, TREE_PARENT, TREE_HIT, TREE_T, TREE_SURFACE,
 TREE_LOCAL, TREE_WEIGHT, TREE_POINT, TREE_NORMAL, TREE_GEOMETRIC) = (
    0, 1, 2, 5, 8, 9, 10, 11, 12, 15, 16, 19, 22)
TREE_COLUMNS = 25


@njit(cache=True)
def _push(rays, top, ox, oy, oz, dx, dy, dz, t_min, t_max, weight, depth, kind):
    rays[top, 0], rays[top, 1], rays[top, 2] = ox, oy, oz
    rays[top, 3], rays[top, 4], rays[top, 5] = dx, dy, dz
    rays[top, 6], rays[top, 7], rays[top, 8] = t_min, t_max, weight
    rays[top, 9], rays[top, 10] = depth, kind
    return top + 1


@njit(cache=True)
def _push_differentials(rays, row, dp, dif, nx, ny, nz, alpha, dbeta):
    """A child ray's differentials: it starts at P (∂O = ∂P) and its direction changes as
    ``∂D' = α ∂D + (∂β) (∂D·N) N`` — reflection α = 1, ∂β = −2; refraction (Igehy 1999, the
    normal's own change left out) α = n_i/n_t, ∂β = −(α + α² cos θ_i / (T·N))."""
    for k in range(2):
        ex, ey, ez = dif[2 * k + 1, 0], dif[2 * k + 1, 1], dif[2 * k + 1, 2]
        dn = dbeta * (ex * nx + ey * ny + ez * nz)
        rays[row, DIFF + 6 * k] = dp[k, 0]
        rays[row, DIFF + 6 * k + 1] = dp[k, 1]
        rays[row, DIFF + 6 * k + 2] = dp[k, 2]
        rays[row, DIFF + 6 * k + 3] = alpha * ex + dn * nx
        rays[row, DIFF + 6 * k + 4] = alpha * ey + dn * ny
        rays[row, DIFF + 6 * k + 5] = alpha * ez + dn * nz


# No reference counts (numba's _nrt): a ray tree makes no array, and the two cores taking
# and giving back counts on the same scene arrays, atomically, took most of a frame.
@njit(cache=True, _nrt=False)
def trace(packed, origins, directions, t_lo, t_hi, begin, end, primary_eye, lights, ambient,
          halfway, background, shadows, max_depth, epsilon, fresnel, medium, offset, rays,
          scaled, surface_row, eye, stack, counts, tex, textured, filter_, bump, colour_at,
          differentials, work, tree, attenuation, raw):
    """The colours (unclamped RGB) of primary rays ``begin .. end − 1`` into ``raw``: each
    ray's whole tree, depth first. One call traces a run of rays: a call hands over the
    scene's arrays and the texture tables, which cost more than a ray that misses everything
    when paid per ray (0.6 µs; 10,000 spheres at 400 x 400).

    With ``textured`` every ray carries its differentials (``differentials[i]``: the primary
    ray's), so that a texture is filtered over the pixel's footprint where the ray lands, and
    a textured triangle is lit by :func:`textured_colour` at ``colour_at`` (:func:`colour_at`).
    ``tree`` ``(R, TREE_COLUMNS)``: where to record the first R rays of the (last) ray's tree
    (the pixel inspector's; zero rows when tracing a frame); returns the count recorded."""
    dif, dp, duv, surf = work
    recorded = 0
    for i in range(begin, end):
        if not t_lo[i] < t_hi[i]:              # outside the viewport or the F..B slab
            raw[i, 0], raw[i, 1], raw[i, 2] = background[0], background[1], background[2]
            continue
        r_sum, g_sum, b_sum = 0.0, 0.0, 0.0
        recorded = 0
        top = _push(rays, 0, origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0],
                    directions[i, 1], directions[i, 2], t_lo[i], t_hi[i], 1.0, 1, PRIMARY)
        rays[0, PARENT], rays[0, INTERNAL] = -1.0, 0.0
        if textured:
            for c in range(12):
                rays[0, DIFF + c] = differentials[i, c]
        while top > 0:
            top -= 1
            ox, oy, oz, dx, dy, dz = rays[top, 0], rays[top, 1], rays[top, 2], rays[top, 3], rays[top, 4], rays[top, 5]
            t_min, t_max, weight = rays[top, 6], rays[top, 7], rays[top, 8]
            depth, ray_kind = int(rays[top, 9]), int(rays[top, 10])
            counts[ray_kind] += 1
            kind, index, t, u, v = nearest(packed, ox, oy, oz, dx, dy, dz, t_min, t_max, stack)
            if ray_kind != PRIMARY and kind != NOTHING and (attenuation[0] > 0.0
                                                             or attenuation[1] > 0.0):
                # the notes' attenuation of a secondary ray's light over the distance R it
                # travelled, 1 / (1 + C1 R + C2 R²): its children inherit it, so the adaptive
                # cut-off (weight < epsilon) prunes the tree sooner
                weight /= 1.0 + attenuation[0] * t + attenuation[1] * t * t
                rays[top, 8] = weight
            node = recorded
            if node < tree.shape[0]:
                _record(tree, node, rays[top], kind, t, background[0], background[1], background[2])
                recorded += 1
            if kind == NOTHING:                  # the ray leaves the scene: the background
                r_sum += weight * background[0]
                g_sum += weight * background[1]
                b_sum += weight * background[2]
                continue
            px, py, pz, nx, ny, nz, gx, gy, gz, s = surface_at(packed, kind, index, u, v,
                                                               ox, oy, oz, dx, dy, dz, t)
            mapped = False
            if textured:
                for c in range(12):
                    dif[c // 3, c % 3] = rays[top, DIFF + c]
                transfer(dif, t, dx, dy, dz, gx, gy, gz, dp)
                mapped = has_maps(tex, kind, s)
                if mapped:
                    uv_derivatives(packed, tex, index, dp, duv)
            hit_viewer(ray_kind, primary_eye, dx, dy, dz, eye)
            entering, lnx, lny, lnz = lit_normal(packed.surfaces, s, nx, ny, nz, gx, gy, gz,
                                                 dx, dy, dz)
            # I_local: each light's I_p scaled by its shadow term, then Phong's model (a
            # textured triangle: the z-buffer's textured pixel step). One shadow walk for both,
            # here, not a second one compiled inside textured_colour.
            checker_colour(packed, kind, index, s, px, py, pz, surface_row)
            arriving = shadowed_lights(packed, px, py, pz, lnx, lny, lnz, gx, gy, gz, lights, eye,
                                       shadows, background, offset, scaled, surface_row, stack,
                                       counts)
            if mapped:
                r, g, b = call_compiled(colour_at, textured_colour, packed, index, s, px, py, pz,
                                        lnx, lny, lnz, arriving, ambient, eye, halfway, tex,
                                        filter_, bump, u, v, duv, surf)
            else:
                r, g, b = light_point_calling(px, py, pz, lnx, lny, lnz, 0, surface_row, arriving,
                                              ambient, eye, halfway)
            r_sum += weight * r
            g_sum += weight * g
            b_sum += weight * b
            if node < tree.shape[0]:
                tree[node, TREE_SURFACE] = s
                tree[node, TREE_LOCAL], tree[node, TREE_LOCAL + 1], tree[node, TREE_LOCAL + 2] = r, g, b
                tree[node, TREE_POINT], tree[node, TREE_POINT + 1], tree[node, TREE_POINT + 2] = px, py, pz
                tree[node, TREE_NORMAL], tree[node, TREE_NORMAL + 1], tree[node, TREE_NORMAL + 2] = nx, ny, nz
                tree[node, TREE_GEOMETRIC] = gx
                tree[node, TREE_GEOMETRIC + 1], tree[node, TREE_GEOMETRIC + 2] = gy, gz
            k_r, k_t = packed.optics[s, 0], packed.optics[s, 1]
            if k_r == 0.0 and k_t == 0.0:
                continue
            fx, fy, fz, gx, gy, gz = optics.facing_normals(dx, dy, dz, nx, ny, nz, gx, gy, gz,
                                                           entering)
            tir = False
            if k_t > 0.0:
                n_i, n_t = (medium, packed.optics[s, 2]) if entering else (packed.optics[s, 2], medium)
                ok, tx, ty, tz = optics.refract(dx, dy, dz, fx, fy, fz, n_i, n_t)
                if ok and tx * gx + ty * gy + tz * gz >= 0.0:
                    # bent about the shading normal, T would leave on the side it came from: the
                    # geometric normal decides which side is which, so refract about the face's
                    fx, fy, fz = gx, gy, gz
                    ok, tx, ty, tz = optics.refract(dx, dy, dz, fx, fy, fz, n_i, n_t)
                if not ok:                         # total internal reflection
                    counts[TIR] += 1
                    tir = True
                    k_r, k_t = k_r + k_t, 0.0
                elif fresnel > 0:
                    cos_i = -(fx * dx + fy * dy + fz * dz)
                    cos_t = -(fx * tx + fy * ty + fz * tz)
                    share = (optics.schlick(cos_i, cos_t, n_i, n_t) if fresnel == FRESNEL_SCHLICK
                             else optics.fresnel_exact(cos_i, cos_t, n_i, n_t))
                    k_r, k_t = k_r + share * k_t, (1.0 - share) * k_t
            # The ray tree's depth: the notes' limit on splitting. A total internal reflection
            # does not split the ray (one child, all of the light), so it does not deepen the tree;
            # MAX_INTERNAL such bounces in a row end it (and the weight's decay, by epsilon).
            internal = int(rays[top, INTERNAL])
            if tir and internal < MAX_INTERNAL:
                child_depth, child_internal = depth, internal + 1
            elif depth >= max_depth or tir:
                counts[CUT_DEPTH] += 1
                continue
            else:
                child_depth, child_internal = depth + 1, 0
            if k_t > 0.0:
                if weight * k_t >= epsilon:
                    if textured:
                        alpha = n_i / n_t
                        cos_i = -(fx * dx + fy * dy + fz * dz)
                        t_dot_n = fx * tx + fy * ty + fz * tz
                        dbeta = -(alpha + alpha * alpha * cos_i / t_dot_n) if t_dot_n != 0.0 else 0.0
                        _push_differentials(rays, top, dp, dif, fx, fy, fz, alpha, dbeta)
                    top = _push(rays, top, px - offset * gx, py - offset * gy, pz - offset * gz,
                                tx, ty, tz, 0.0, np.inf, weight * k_t, child_depth, REFRACTED)
                    rays[top - 1, PARENT], rays[top - 1, INTERNAL] = node, child_internal
                else:
                    counts[CUT_ADAPTIVE] += 1
            if k_r > 0.0:
                if weight * k_r >= epsilon:
                    rx, ry, rz = optics.reflect(dx, dy, dz, fx, fy, fz)
                    if rx * gx + ry * gy + rz * gz <= 0.0:
                        # mirrored about the shading normal, R would enter the surface: mirror it
                        # about the face's normal, whose side the offset is on
                        fx, fy, fz = gx, gy, gz
                        rx, ry, rz = optics.reflect(dx, dy, dz, fx, fy, fz)
                    if textured:
                        _push_differentials(rays, top, dp, dif, fx, fy, fz, 1.0, -2.0)
                    top = _push(rays, top, px + offset * gx, py + offset * gy, pz + offset * gz,
                                rx, ry, rz, 0.0, np.inf, weight * k_r, child_depth, REFLECTED)
                    rays[top - 1, PARENT], rays[top - 1, INTERNAL] = node, child_internal
                else:
                    counts[CUT_ADAPTIVE] += 1
        raw[i, 0], raw[i, 1], raw[i, 2] = r_sum, g_sum, b_sum
    return recorded


@njit(cache=True)
def _record(tree, node, ray, kind, t, r, g, b):
    """A ray's row of the ray tree: what it is, and (for now) that it missed."""
    tree[node, :] = 0.0
    tree[node, TREE_KIND], tree[node, TREE_DEPTH] = ray[10], ray[9]
    for c in range(3):
        tree[node, TREE_ORIGIN + c] = ray[c]
        tree[node, TREE_DIRECTION + c] = ray[3 + c]
    tree[node, TREE_PARENT] = ray[PARENT]
    tree[node, TREE_HIT], tree[node, TREE_T], tree[node, TREE_SURFACE] = kind, t, -1.0
    tree[node, TREE_LOCAL], tree[node, TREE_LOCAL + 1], tree[node, TREE_LOCAL + 2] = r, g, b
    tree[node, TREE_WEIGHT] = ray[8]


CHUNK = 512     # rays per parallel work item (dealt to the threads by bvh.spread)


@njit(cache=True)
def scratch(packed, textured):
    """Per-thread work arrays of :func:`trace`: a ray's differentials, its hit point's, the
    (u, v) derivatives, and (``textured`` only: a frame of 10,000 spheres would otherwise copy
    their 10,000 rows per work item) a copy of the surfaces for a texel's O_d."""
    surfaces = packed.surfaces.copy() if textured else packed.surfaces[:0].copy()
    return (np.zeros((4, 3)), np.zeros((2, 3)), np.zeros(4), surfaces)


@njit(cache=True, parallel=True, nogil=True)
def trace_many(packed, origins, directions, t_min, t_max, primary_eye, lights, ambient, halfway,
               background, shadows, max_depth, epsilon, fresnel, medium, offset, raw, counts,
               tex, textured, filter_, bump, differentials, attenuation, colour_at, at):
    """Every primary ray's colour into ``raw`` ``(N, 3)``; ray counts per chunk ``(C, 7)``;
    ``differentials`` ``(N, 12)`` (used when ``textured``). ``at``: :func:`trace`'s
    machine code for these arguments (:func:`trace_at`): called by its address, its
    code is not optimised a second time inside this loop (10 s of a cold start)."""
    n = origins.shape[0]
    chunks = (n + CHUNK - 1) // CHUNK
    for j in prange(chunks):
        chunk = bvh.spread(j, chunks)
        rays = np.empty((2 * max_depth + 2, STACK_COLUMNS))
        no_tree = np.empty((0, TREE_COLUMNS))
        scaled = np.empty(lights.shape)
        surface_row = np.empty((1, packed.surfaces.shape[1]))
        eye = np.empty(4)
        stack = bvh.new_stack()
        work = scratch(packed, textured)
        call_compiled(at, trace, packed, origins, directions, t_min, t_max, chunk * CHUNK,
                      min(n, (chunk + 1) * CHUNK), primary_eye, lights, ambient, halfway,
                      background, shadows, max_depth, epsilon, fresnel, medium, offset, rays,
                      scaled, surface_row, eye, stack, counts[chunk], tex, textured, filter_,
                      bump, colour_at, differentials, work, no_tree, attenuation, raw)


def trace_at(packed, origins, directions, t_min, t_max, primary_eye, lights, ambient,
                  halfway, background, shadows, max_depth, epsilon, fresnel, medium, offset,
                  raw, counts, tex, textured, filter_, bump, differentials,
                  attenuation, colour_at) -> tuple[int, int]:
    """:func:`trace`'s machine code for the arguments :func:`trace_many` gives it (its
    scratch arrays are made as it makes them, so that numba types them alike)."""
    scratch_arrays = (np.empty((1, STACK_COLUMNS)), np.empty(lights.shape),
                      np.empty((1, packed.surfaces.shape[1])), np.empty(4), bvh.new_stack(),
                      np.empty(counts.shape[1:], counts.dtype))
    given = (packed, origins, directions, t_min, t_max, 0, 0, primary_eye, lights, ambient,
             halfway, background, shadows, max_depth, epsilon, fresnel, medium, offset,
             *scratch_arrays, tex, textured, filter_, bump, colour_at, differentials,
             scratch(packed, textured), np.empty((0, TREE_COLUMNS)), attenuation, raw)
    return compiled_at(trace, given)


def visible_many(packed, origins, directions, t_min, t_max, kind, index, t_hit):
    """Primary visibility only (no shading): what each ray sees first — :func:`nearest` for
    every ray, in parallel. ``kind`` NOTHING / TRIANGLE (``index`` the scene's triangle) /
    SPHERE / PLANE (``index`` the row)."""
    given = (packed, origins, directions, t_min, t_max, kind, index, t_hit)
    _visible_chunks(*given, compiled_at(_visible_run, given + (0, 0)))


@njit(cache=True, parallel=True, nogil=True)
def _visible_chunks(packed, origins, directions, t_min, t_max, kind, index, t_hit, at):
    """:func:`_visible_run` on chunks of :data:`CHUNK` rays, in parallel, called by its
    address ``at`` (core.jit.call_compiled): the walk is optimised once, in
    ``_visible_run``, not again inside this loop."""
    n = origins.shape[0]
    chunks = (n + CHUNK - 1) // CHUNK
    for m in prange(chunks):
        chunk = bvh.spread(m, chunks)
        call_compiled(at, _visible_run, packed, origins, directions, t_min, t_max, kind, index,
                      t_hit, chunk * CHUNK, min(n, (chunk + 1) * CHUNK))


# numpy's error model, as the parallel loop's body that it was; simplified, as that body was
# (core.jit.SimplifiedCompiler: without it the walk took about 1.4x as long)
@njit(cache=True, nogil=True, error_model="numpy", pipeline_class=SimplifiedCompiler)
def _visible_run(packed, origins, directions, t_min, t_max, kind, index, t_hit, start, end):
    """:func:`nearest` for rays ``start`` to ``end``."""
    stack = bvh.new_stack()
    for i in range(start, end):
        k, j, t, _, _ = nearest(packed, origins[i, 0], origins[i, 1], origins[i, 2],
                                directions[i, 0], directions[i, 1], directions[i, 2],
                                t_min[i], t_max[i], stack)
        kind[i], t_hit[i] = k, t
        index[i] = packed.prim[j] if k == TRIANGLE else j
