"""The two-pass method's second pass: eye rays through the radiosity elements, the diffuse term
read from the solution, the specular part traced as Whitted traces it.

At a hit on element ``e`` of a ray of weight ``w`` the pixel gains::

    w · [ B(P) + Σ_i S_i f_att,i I_p,i k_s O_s (N·H_i)^n ]

and the hit spawns Whitted's children, the reflected ray of weight ``w k_r`` and the refracted
one of weight ``w k_t``, each shaded the same way where it lands (a ray that leaves the
scene brings the background). ``B(P)`` is pass 1: the element's radiosity plus the ambient
term for light not yet shot (:meth:`core.radiosity.solution.Solution.shown`), carried to the
element corners by :func:`core.radiosity.mesh.vertex_values` (area-weighted within a surface)
and interpolated at P with the hit's barycentrics — the radiosity renderer's display, which
interpolates the same vertex values (Gouraud, perspective-correct) at each pixel centre.
Emitters are elements too, so a mirror shows an area light as the solution shows it.

Which element a ray sees: one BVH (the ray tracer's, :func:`core.raytrace.bvh.build`) over
the one-sided elements and the first copy of each two-sided pair; a ray that meets a
two-sided element from behind takes the coplanar element of the other copy (a second BVH)
instead, as the radiosity display's back-face culling shows each side its own copy.

The specular part, as :mod:`core.raytrace.whitted` computes it: the shading normal is the
source triangle's vertex normals (:func:`core.scene.normals.vertex_normals`, the ones the ray
tracer interpolates) at P, turned to the ray; the geometric normal decides the sides
(entering or leaving, offsets). Reflection ``R = I − 2 (N·I) N``, refraction by Snell's law
``T = α I + β N`` from the medium into ``ior`` when the ray enters, total internal reflection
giving ``k_t`` to the reflected ray without deepening the tree (up to
:data:`core.raytrace.whitted.MAX_INTERNAL` in a row), optional Fresnel weights (Schlick or
exact), the depth limit ``max_depth`` and the adaptive cut-off ε on the product of the k's,
and the secondary rays' attenuation — the ray tracer's own options
(``settings.options_of("raytrace")``). The highlights' shadow rays are hard (any surface in
the way blocks the light, glass included), as pass 1's direct light is.

Rays go in waves: every live ray of a wave through :func:`core.raytrace.bvh.intersect_rays`
(the compiled, parallel traversal), the shading and the children in numpy, the children
forming the next wave. No kernel of its own: the pass compiles nothing new.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.raytrace.whitted import (COUNTERS, CUT_ADAPTIVE, CUT_DEPTH, MAX_INTERNAL, PRIMARY,
                                   REFLECTED, REFRACTED, SHADOW, TIR)

OFFSET = 1e-9            # secondary rays start this fraction of the scene's size off a surface
TWIN = 1e-6              # the other copy of a two-sided pair is sought within this of the hit


@dataclass
class Geometry:
    """What the second pass reads of a scene and its solution (kept while both live).

    Element rows E: ``triangles`` (E, 3) vertex indices into ``values`` (V, 3), the shown
    radiosity at the element corners; ``corners`` (E, 3, 3); ``normal`` (E, 3) each element's
    own; ``two_sided`` (E,); ``mesh`` (E,) the scene mesh (its material); ``source`` and
    ``source_normals`` (E, 3, 3) the scene triangle it was cut from, its corners and vertex
    normals; ``geometric`` (E, 3) that triangle's unit normal in the mesh's winding. ``front``
    (the BVH of the one-sided elements and the first copy of each two-sided pair, rows
    ``front_rows``) and ``back`` (the second copies, ``back_rows``; None when there are none).
    Material columns per mesh: ``kr``, ``kt``, ``ior``, ``ks``, ``shine``, ``os`` (M, 3).
    """

    front: object
    front_rows: np.ndarray
    back: object | None
    back_rows: np.ndarray
    triangles: np.ndarray
    values: np.ndarray
    corners: np.ndarray
    normal: np.ndarray
    two_sided: np.ndarray
    mesh: np.ndarray
    source: np.ndarray
    source_normals: np.ndarray
    geometric: np.ndarray
    kr: np.ndarray
    kt: np.ndarray
    ior: np.ndarray
    ks: np.ndarray
    shine: np.ndarray
    os: np.ndarray
    lights: list
    halfway: bool
    background: np.ndarray
    scale: float
    names: list


def prepare(scene, solution) -> Geometry:
    """The second pass's arrays for ``scene`` drawn from ``solution`` (its own elements)."""
    from core.colour.srgb import decode
    from core.radiosity.mesh import RadiosityError, surfaces, vertex_values
    from core.raytrace.bvh import build
    from core.scene.media import index_of_refraction
    from core.scene.normals import vertex_normals
    e = solution.elements
    found = surfaces(scene)
    if len(e) == 0 or e.surface.max() >= len(found.mesh) or np.any(
            found.mesh[e.surface] != e.mesh):
        raise RadiosityError("the solution's elements do not belong to this scene's surfaces")
    _, triangles, values = vertex_values(e, solution.shown())
    mesh_of, index = found.mesh[e.surface], found.triangle[e.surface]
    source = np.empty((len(e), 3, 3))
    source_normals = np.empty((len(e), 3, 3))
    for m in np.unique(mesh_of):
        rows = mesh_of == m
        mesh = scene.meshes[int(m)]
        corners = mesh.triangles[index[rows]]
        source[rows] = mesh.positions[corners]
        source_normals[rows] = vertex_normals(mesh, "mean")[corners]
    geometric = unit(np.cross(source[:, 1] - source[:, 0], source[:, 2] - source[:, 0]))
    reversed_copy = found.reversed[e.surface]
    front_rows = np.flatnonzero(~reversed_copy)
    back_rows = np.flatnonzero(reversed_copy)
    positions = e.corners.reshape(-1, 3)
    own = np.arange(3 * len(e), dtype=np.int64).reshape(-1, 3)    # each element its corners
    front, _ = build(positions, own[front_rows])
    back = build(positions, own[back_rows])[0] if len(back_rows) else None
    materials = [m.material for m in scene.meshes]
    column = lambda name: np.array([float(getattr(m, name)) for m in materials])  # noqa: E731
    background = np.asarray(scene.background, dtype=np.float64).reshape(3)
    if scene.tone == "srgb":          # the radiance the tone curve shows as the background
        background = np.asarray(decode(background), dtype=np.float64)
    return Geometry(front=front, front_rows=front_rows, back=back, back_rows=back_rows,
                    triangles=triangles, values=values, corners=e.corners, normal=e.normal,
                    two_sided=e.two_sided.astype(bool), mesh=e.mesh.astype(np.int64),
                    source=source, source_normals=source_normals, geometric=geometric,
                    kr=column("kr"), kt=column("kt"),
                    ior=np.array([index_of_refraction(m.ior) for m in materials]),
                    ks=column("ks"),
                    shine=column("n"),
                    os=np.array([m.os for m in materials], dtype=np.float64).reshape(-1, 3),
                    lights=[light for light in scene.lights if max(light.intensity) > 0],
                    halfway=scene.specular == "halfway", background=background,
                    scale=float(e.scale), names=[m.name for m in scene.meshes])


@dataclass(frozen=True)
class Rules:
    """Whitted's rules for the specular rays (the ray tracer's options, and the medium)."""

    max_depth: int = 7
    epsilon: float = 1e-3
    fresnel: str | None = None          # None, "schlick" or "exact"
    attenuation: tuple = (0.0, 0.0)     # C1, C2 over a secondary ray's length
    medium: float = 1.0003              # the index of the space between objects (air)

    @classmethod
    def from_settings(cls, settings) -> "Rules":
        from core.raytrace.optics import AIR
        o = settings.options_of("raytrace")
        return cls(max_depth=o.max_depth, epsilon=float(o.adaptive_epsilon),
                   fresnel=o.fresnel_form if o.fresnel else None,
                   attenuation=tuple(o.secondary_attenuation), medium=AIR)


def trace(geo: Geometry, origins, directions, t_min, t_max, rules: Rules = Rules(),
          counts: np.ndarray | None = None, tree: list | None = None) -> np.ndarray:
    """Radiance ``(N, 3)`` (linear, unclamped) of the eye rays; adds the rays of each kind to
    ``counts`` (:data:`core.raytrace.whitted.COUNTERS`). ``tree``: a list to append one
    record per ray to (the pixel inspector's; leave it None for a frame)."""
    from core.raytrace.bvh import intersect_rays, occluded_rays
    n = len(origins)
    out = np.zeros((n, 3))
    counts = np.zeros(len(COUNTERS), np.int64) if counts is None else counts
    o = np.ascontiguousarray(origins, dtype=np.float64).reshape(-1, 3)
    d = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
    lo = np.broadcast_to(np.asarray(t_min, dtype=np.float64), (n,)).copy()
    hi = np.broadcast_to(np.asarray(t_max, dtype=np.float64), (n,)).copy()
    live = lo < hi                     # outside the viewport or the F..B slab: the background
    out[~live] = geo.background
    pixel = np.flatnonzero(live)
    o, d, lo, hi = o[live], d[live], lo[live], hi[live]
    weight, depth = np.ones(len(pixel)), np.ones(len(pixel), np.int64)
    internal = np.zeros(len(pixel), np.int64)
    kind = np.full(len(pixel), PRIMARY)
    parent = np.full(len(pixel), -1)
    offset = OFFSET * geo.scale
    while len(pixel):
        for k in (PRIMARY, REFLECTED, REFRACTED):
            counts[k] += int(np.count_nonzero(kind == k))
        prim, t, u, v = intersect_rays(geo.front, o, d, lo, hi)
        hit = prim >= 0
        c1, c2 = rules.attenuation
        if c1 > 0 or c2 > 0:             # the notes' 1 / (1 + C1 R + C2 R²) over R travelled
            secondary = hit & (kind != PRIMARY)
            ts = t[secondary]
            weight[secondary] /= 1.0 + c1 * ts + c2 * ts * ts
        np.add.at(out, pixel[~hit], weight[~hit, None] * geo.background[None])
        if tree is not None:
            for i in np.flatnonzero(~hit):
                tree.append(_record(kind[i], depth[i], parent[i], o[i], d[i], weight[i]))
        keep = np.flatnonzero(hit)
        pixel, o, d, weight, depth, internal, kind, parent = (
            a[keep] for a in (pixel, o, d, weight, depth, internal, kind, parent))
        prim, t, u, v = prim[keep], t[keep], u[keep], v[keep]
        element = geo.front_rows[prim]
        element, u, v = _other_side(geo, element, o, d, t, u, v)
        w0 = 1.0 - u - v
        tv = geo.triangles[element]
        diffuse = (w0[:, None] * geo.values[tv[:, 0]] + u[:, None] * geo.values[tv[:, 1]]
                   + v[:, None] * geo.values[tv[:, 2]])
        c = geo.corners[element]
        p = w0[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        g = geo.geometric[element]
        normal = _shading_normal(geo, element, p, g)
        entering = np.einsum("ij,ij->i", g, d) < 0.0
        f, g = _facing(d, normal, g, entering)
        mesh = geo.mesh[element]
        highlight = _highlights(geo, mesh, p, f, g, d, offset, counts, occluded_rays)
        np.add.at(out, pixel, weight[:, None] * (diffuse + highlight))
        node = np.full(len(pixel), -1)
        if tree is not None:
            for i in range(len(pixel)):
                node[i] = len(tree)
                tree.append(_record(kind[i], depth[i], parent[i], o[i], d[i], weight[i],
                                    t[i], p[i], f[i], int(element[i]), geo.names[mesh[i]],
                                    diffuse[i], highlight[i], geo.kr[mesh[i]], geo.kt[mesh[i]]))
        waves = _children(geo, rules, mesh, p, d, f, g, entering, weight, depth, internal,
                          offset, counts)
        if not waves:
            break
        rows = np.concatenate([w[0] for w in waves])
        pixel, parent = pixel[rows], node[rows]
        o = np.concatenate([w[1] for w in waves])
        d = np.concatenate([w[2] for w in waves])
        weight = np.concatenate([w[3] for w in waves])
        depth = np.concatenate([w[4] for w in waves])
        internal = np.concatenate([w[5] for w in waves])
        kind = np.concatenate([np.full(len(w[0]), w[6]) for w in waves])
        lo, hi = np.zeros(len(rows)), np.full(len(rows), np.inf)
    return out


def _other_side(geo, element, o, d, t, u, v):
    """A two-sided element met from behind: the coplanar element of its other copy, found
    through the second BVH close to the hit (its own radiosity, as the display shows)."""
    if geo.back is None:
        return element, u, v
    behind = np.flatnonzero(geo.two_sided[element]
                            & (np.einsum("ij,ij->i", d, geo.normal[element]) > 0.0))
    if not len(behind):
        return element, u, v
    from core.raytrace.bvh import intersect_rays
    near = TWIN * geo.scale
    prim, _, ub, vb = intersect_rays(geo.back, o[behind], d[behind], t[behind] - near,
                                     t[behind] + near)
    ok = prim >= 0
    element, u, v = element.copy(), u.copy(), v.copy()
    element[behind[ok]] = geo.back_rows[prim[ok]]
    u[behind[ok]], v[behind[ok]] = ub[ok], vb[ok]
    return element, u, v


def unit(vectors: np.ndarray) -> np.ndarray:
    """Each row (or the vector) divided by its length; zero rows stay zero."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors / np.where(length > 0.0, length, 1.0)


def dot(a, b) -> np.ndarray:
    """Row by row dot products of two (N, 3) arrays."""
    return np.einsum("ij,ij->i", a, b)


def _shading_normal(geo, element, p, g):
    """The source triangle's vertex normals interpolated at P (its barycentrics there), unit;
    the face's normal where they cancel."""
    s = geo.source[element]
    e1, e2, q = s[:, 1] - s[:, 0], s[:, 2] - s[:, 0], p - s[:, 0]
    d11, d12, d22 = dot(e1, e1), dot(e1, e2), dot(e2, e2)
    q1, q2 = dot(q, e1), dot(q, e2)
    den = d11 * d22 - d12 * d12
    den = np.where(den != 0.0, den, 1.0)
    b1 = (d22 * q1 - d12 * q2) / den
    b2 = (d11 * q2 - d12 * q1) / den
    b0 = 1.0 - b1 - b2
    vn = geo.source_normals[element]
    n = b0[:, None] * vn[:, 0] + b1[:, None] * vn[:, 1] + b2[:, None] * vn[:, 2]
    length = np.linalg.norm(n, axis=1)
    return np.where((length > 0.0)[:, None], n / np.where(length > 0, length, 1.0)[:, None], g)


def _facing(d, n, g, entering):
    """:func:`core.raytrace.optics.facing_normals` for many rays: the geometric normal flipped
    when the ray leaves; the shading normal turned towards the ray, and the geometric one
    where it then lies on the other side of the face."""
    g = np.where(entering[:, None], g, -g)
    n = np.where((dot(n, d) > 0.0)[:, None], -n, n)
    n = np.where((dot(n, g) <= 0.0)[:, None], g, n)
    return n, g


def reflect(d, n):
    """``R = I − 2 (N·I) N`` (:func:`core.raytrace.optics.reflect`)."""
    return d - 2.0 * dot(n, d)[:, None] * n


def refract(d, n, n_i, n_t):
    """``(ok, T)``: ``T = α I + β N``, unit (:func:`core.raytrace.optics.refract`); ``ok``
    False on total internal reflection (T then zero)."""
    alpha = n_i / n_t
    cos_i = -dot(n, d)
    k = 1.0 - alpha * alpha * (1.0 - cos_i * cos_i)
    ok = k >= 0.0
    beta = alpha * cos_i - np.sqrt(np.where(ok, k, 0.0))
    t = alpha[:, None] * d + beta[:, None] * n
    t = unit(t)
    t[~ok] = 0.0
    return ok, t


def fresnel(cos_i, cos_t, n_i, n_t, form: str):
    """The reflected fraction: Schlick's (:func:`core.raytrace.optics.schlick`) or the exact
    equations for unpolarised light (:func:`core.raytrace.optics.fresnel_exact`)."""
    if form == "schlick":
        f0 = ((n_i - n_t) / (n_i + n_t)) ** 2
        c = np.where(n_i <= n_t, cos_i, cos_t)
        return f0 + (1.0 - f0) * (1.0 - c) ** 5
    s_den = n_i * cos_i + n_t * cos_t
    p_den = n_i * cos_t + n_t * cos_i
    bad = (s_den == 0.0) | (p_den == 0.0)
    s_den, p_den = np.where(bad, 1.0, s_den), np.where(bad, 1.0, p_den)
    r_s = ((n_i * cos_i - n_t * cos_t) / s_den) ** 2
    r_p = ((n_i * cos_t - n_t * cos_i) / p_den) ** 2
    return np.where(bad, 1.0, 0.5 * (r_s + r_p))


def _highlights(geo, mesh, p, n, g, d, offset, counts, occluded_rays):
    """``Σ_i S_i f_att,i I_p,i k_s O_s (·)^n`` at each hit: the Phong model's specular term
    (:func:`core.shading.illumination.phong_point`, halfway or reflection form as the scene
    says) for every point and directional light a shadow ray reaches; V towards the ray's
    origin, N the shading normal turned to it."""
    out = np.zeros((len(p), 3))
    ks = geo.ks[mesh]
    shiny = np.flatnonzero(ks > 0.0)
    if not geo.lights or not len(shiny):
        return out
    p, n, g, view = p[shiny], n[shiny], g[shiny], -d[shiny]
    exponent = geo.shine[mesh[shiny]]
    scale = (ks[shiny][:, None] * geo.os[mesh[shiny]])
    for light in geo.lights:
        if light.position is not None:
            to_light = np.asarray(light.position, dtype=np.float64)[None] - p
            distance = np.linalg.norm(to_light, axis=1)
            to_light = to_light / np.where(distance > 0, distance, 1.0)[:, None]
            c1, c2, c3 = light.attenuation
            den = c1 + c2 * distance + c3 * distance * distance
            uncapped = not light.attenuation_cap
            with np.errstate(divide="ignore"):
                f_att = np.where((den > 1) | (uncapped & (den > 0)), 1.0 / np.where(
                    den != 0, den, 1.0), 1.0)
            reach = np.maximum(distance - offset, 0.0)
            lit = distance > 0.0
        else:
            to_light = np.repeat(unit(np.asarray(light.direction, np.float64)[None]),
                                 len(p), axis=0)
            f_att, reach, lit = np.ones(len(p)), np.full(len(p), np.inf), np.ones(len(p), bool)
        n_dot_l = dot(n, to_light)
        lit &= n_dot_l > 0.0
        if not lit.any():
            continue
        rows = np.flatnonzero(lit)
        counts[SHADOW] += len(rows)
        blocked = occluded_rays(geo.front, p[rows] + offset * g[rows], to_light[rows], 0.0,
                                reach[rows])
        rows = rows[~blocked]
        if not len(rows):
            continue
        l_, v_, n_ = to_light[rows], view[rows], n[rows]
        if geo.halfway:
            base = dot(n_, unit(l_ + v_))
        else:
            base = dot(2.0 * n_dot_l[rows, None] * n_ - l_, v_)
        power = np.clip(base, 0.0, 1.0) ** exponent[rows]
        intensity = np.asarray(light.intensity, dtype=np.float64)[None]
        out[shiny[rows]] += (f_att[rows] * power)[:, None] * intensity * scale[rows]
    return out


def _children(geo, rules, mesh, p, d, f, g, entering, weight, depth, internal, offset,
              counts):
    """Whitted's children of the hits (:func:`core.raytrace.whitted.trace`): ``[(rows,
    origins, directions, weights, depths, internal, kind)]``, the refracted and the reflected
    rays, after total internal reflection, Fresnel, the depth limit and the cut-off."""
    k_r, k_t = geo.kr[mesh].copy(), geo.kt[mesh].copy()
    rows = np.flatnonzero((k_r > 0.0) | (k_t > 0.0))
    if not len(rows):
        return []
    d, f, g, p = d[rows], f[rows].copy(), g[rows], p[rows]
    k_r, k_t, entering = k_r[rows], k_t[rows], entering[rows]
    weight, depth, internal = weight[rows], depth[rows], internal[rows]
    ior = geo.ior[mesh[rows]]
    n_i = np.where(entering, rules.medium, ior)
    n_t = np.where(entering, ior, rules.medium)
    clear = k_t > 0.0
    ok, t = refract(d, f, n_i, n_t)
    wrong = clear & ok & (dot(t, g) >= 0.0)
    if wrong.any():        # bent about the shading normal T would leave on its own side
        f[wrong] = g[wrong]
        ok2, t2 = refract(d[wrong], g[wrong], n_i[wrong], n_t[wrong])
        ok[wrong], t[wrong] = ok2, t2
    tir = clear & ~ok
    counts[TIR] += int(np.count_nonzero(tir))
    k_r = np.where(tir, k_r + k_t, k_r)
    k_t = np.where(tir, 0.0, k_t)
    if rules.fresnel is not None:
        split = clear & ok
        cos_i = -dot(f, d)
        cos_t = -dot(f, t)
        share = np.where(split, fresnel(cos_i, cos_t, n_i, n_t, rules.fresnel), 0.0)
        k_r, k_t = k_r + share * k_t, (1.0 - share) * k_t
    deeper = tir & (internal < MAX_INTERNAL)
    cut = ~deeper & ((depth >= rules.max_depth) | tir)
    counts[CUT_DEPTH] += int(np.count_nonzero(cut))
    child_depth = np.where(deeper, depth, depth + 1)
    child_internal = np.where(deeper, internal + 1, 0)
    waves = []
    refracted = ~cut & (k_t > 0.0)
    cast = refracted & (weight * k_t >= rules.epsilon)
    counts[CUT_ADAPTIVE] += int(np.count_nonzero(refracted & ~cast))
    if cast.any():
        i = np.flatnonzero(cast)
        waves.append((rows[i], p[i] - offset * g[i], t[i], weight[i] * k_t[i],
                      child_depth[i], child_internal[i], REFRACTED))
    reflected = ~cut & (k_r > 0.0)
    cast = reflected & (weight * k_r >= rules.epsilon)
    counts[CUT_ADAPTIVE] += int(np.count_nonzero(reflected & ~cast))
    if cast.any():
        i = np.flatnonzero(cast)
        r = reflect(d[i], f[i])
        inward = dot(r, g[i]) <= 0.0     # mirrored about the shading normal R would enter
        if inward.any():
            r[inward] = reflect(d[i][inward], g[i][inward])
        waves.append((rows[i], p[i] + offset * g[i], r, weight[i] * k_r[i], child_depth[i],
                      child_internal[i], REFLECTED))
    return waves


def _record(kind, depth, parent, origin, direction, weight, t=np.inf, point=None, normal=None,
            element=-1, mesh=None, diffuse=None, highlight=None, kr=0.0, kt=0.0) -> dict:
    """One ray of a pixel's tree, for the inspector."""
    record = {"ray": COUNTERS[int(kind)], "depth": int(depth), "parent": int(parent),
              "origin": [float(x) for x in origin], "direction": [float(x) for x in direction],
              "weight": float(weight)}
    if element < 0:
        record["hit"] = None
        return record
    record.update({"hit": mesh, "element": int(element), "t": float(t),
                   "point": [float(x) for x in point], "normal": [float(x) for x in normal],
                   "diffuse (pass 1)": [float(x) for x in diffuse],
                   "highlight": [float(x) for x in highlight], "k_r": float(kr),
                   "k_t": float(kt)})
    return record
