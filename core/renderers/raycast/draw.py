"""The exact reference: the Phong illumination model on the TRUE analytic surface, per sample.

What the tessellated pipeline approximates, computed without tessellation, to measure its error
(the tessellated sphere's error, and the error-against-time report). Takes analytic shapes
(:class:`Sphere`, :class:`Torus`), the scene's lights, ambient light, specular form and
background, and a :class:`core.camera.view.View` with its projection; returns float64 colours in
[0, 1] and the fraction of each pixel the shapes cover (:class:`Reference`).

- Rays come from the SAME view as the pipeline (FvDFH 6.5; the notes' ray tracing, March 27):
  the sample at device point (x, y) looks through the view-plane point
  ``VRP + u·u_vrc + v·v_vrc`` with ``u = u_min + (x − x0)/(x1 − x0) · (u_max − u_min)`` (and v
  alike) over the letterboxed viewport ``(x0, x1, y0, y1)`` of :func:`core.pipeline.project.viewport`;
  perspective rays start at the PRP, parallel rays run along the DOP. A sample outside the
  viewport, or whose hit lies in front of F or behind B (n measured from the VRP along VPN),
  sees nothing: the six planes of the canonical view volume.
- Intersections in float64: the sphere by the quadratic in its stable form (the discriminant
  from the ray's perpendicular distance to the centre); the torus
  ``(|p|² + R² − r²)² = 4 R² (p_x² + p_y²)`` as a quartic in the ray parameter, set up in the
  torus' own frame, from the ray's entry into the bounding sphere and scaled to it (so the
  coefficients are O(1)), and solved by isolating each real root: the roots of f'' (a
  quadratic) split the interval where f' is monotone, the roots of f' split it where f is
  monotone, and each sign change of f is found by Newton's method kept inside its bracket.
  Every real root is found, grazing ones included up to the sign test; the visible hit is the
  one nearest the viewer (largest n) inside the front and back planes.
- Analytic normals: ``(P − C)/r`` on the sphere; on the torus the direction from the nearest
  point of the core circle to P. The model is :func:`core.shading.illumination.phong_point`, the same
  numba function the Phong resolve calls.
- Supersampling: ``samples × samples`` samples per pixel, one at the centre of each stratum of
  a regular grid (deterministic), box-filtered: ``rgb`` is the mean over all samples with the
  background where a sample sees nothing; ``surface_rgb`` the mean over the samples that hit
  (the background where none did); ``coverage`` the fraction that hit; ``shape`` the index of
  the shape all samples saw (-1: none; -2: the pixel straddles an edge, a silhouette or one
  shape in front of another: there the box filter and a pixel-centre sample differ most).
  ``samples = 1`` samples pixel centres, exactly where the pipeline samples.

Rows run in parallel (numba ``prange``); a 500 x 500 torus at 16 samples a pixel takes a few
seconds on two cores.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import (eye_from_view, pack_ambient, pack_eye, pack_lights, pack_surfaces,
                               unit3)
from core.shading.models.dispatch import light_point_calling
from core.camera.film import fill, grid_side, to_rgb8
from core.camera.rays import (CAMERA_BACK, CAMERA_BASIS, CAMERA_FRONT, CAMERA_VRP, camera_ray,
                              pack_camera)
from core.scene.primitives import Sphere, Torus  # noqa: F401  (the shapes it traces)
from core.camera.view import View, check

SPHERE, TORUS = 0.0, 1.0
# Columns of a packed shape row: kind, centre (3), R, r, surface, axis (3), e1 (3), e2 (3).
SHAPE_COLUMNS = 16


@dataclass
class Reference:
    """Float64 images in image order (row 0 at the top); see the module docstring."""

    rgb: np.ndarray            # (H, W, 3) box filter over all samples, background for misses
    surface_rgb: np.ndarray    # (H, W, 3) mean over the samples that hit the surface
    coverage: np.ndarray       # (H, W) fraction of samples that hit
    shape: np.ndarray          # (H, W) int: the shape every sample saw; -1 none, -2 several
    samples: int               # per axis: samples² per pixel


def _frame(axis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit axis ``a`` and two unit vectors ``e1, e2`` completing a right-handed frame."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, a)
    e1 /= np.linalg.norm(e1)
    return a, e1, np.cross(a, e1)


def pack_shapes(shapes) -> np.ndarray:
    """``(S, 16)`` rows for the kernel; shape ``i`` uses surface row ``i``."""
    rows = np.zeros((len(shapes), SHAPE_COLUMNS))
    for i, shape in enumerate(shapes):
        rows[i, 1:4] = shape.center
        rows[i, 6] = i
        if isinstance(shape, Sphere):
            if not shape.radius > 0.0:
                raise ValueError(f"shape {i + 1}: the sphere's radius must be positive")
            rows[i, 0], rows[i, 4] = SPHERE, shape.radius
        elif isinstance(shape, Torus):
            if not 0.0 < shape.minor < shape.major:
                raise ValueError(f"shape {i + 1}: a ring torus needs 0 < minor < major")
            a, e1, e2 = _frame(shape.axis)
            rows[i, 0], rows[i, 4], rows[i, 5] = TORUS, shape.major, shape.minor
            rows[i, 7:10], rows[i, 10:13], rows[i, 13:16] = a, e1, e2
        else:
            raise TypeError(f"shape {i + 1}: not a Sphere or a Torus: {shape!r}")
    return rows


# --------------------------------------------------------------------------------------------
# Root finding
# The kernels here that are not inlined declare _nrt=False (no reference counts): they make
# no array, and numba compiles a callee with the flags of the first caller that needs it,
# so without the declaration a counted copy, linked into the rows' uncounted code, would
# take and give back a count for every view it makes.


@njit(cache=True, _nrt=False)
def _poly(c0, c1, c2, c3, c4, t):
    return (((c4 * t + c3) * t + c2) * t + c1) * t + c0


@njit(cache=True, _nrt=False)
def _monotone_root(c0, c1, c2, c3, c4, lo, hi, f_lo):
    """The root of the polynomial in [lo, hi], where it is monotone and changes sign.

    Newton's method, falling back to bisection whenever a step would leave the bracket.
    """
    t = 0.5 * (lo + hi)
    negative_lo = f_lo < 0.0
    for _ in range(200):
        f = _poly(c0, c1, c2, c3, c4, t)
        if f == 0.0:
            return t
        if (f < 0.0) == negative_lo:
            lo = t
        else:
            hi = t
        df = ((4.0 * c4 * t + 3.0 * c3) * t + 2.0 * c2) * t + c1
        t_new = t - f / df if df != 0.0 else 0.5 * (lo + hi)
        if not (lo < t_new < hi):
            t_new = 0.5 * (lo + hi)
        if abs(t_new - t) <= 1e-15 or hi - lo <= 1e-15:
            return t_new
        t = t_new
    return t


@njit(cache=True, _nrt=False)
def _sign_changes(c0, c1, c2, c3, c4, breaks, n_breaks, roots):
    """Roots of the polynomial between consecutive ``breaks`` (where it is monotone)."""
    count = 0
    f_prev = _poly(c0, c1, c2, c3, c4, breaks[0])
    for k in range(1, n_breaks):
        f_next = _poly(c0, c1, c2, c3, c4, breaks[k])
        if (f_prev < 0.0) != (f_next < 0.0):
            roots[count] = _monotone_root(c0, c1, c2, c3, c4, breaks[k - 1], breaks[k], f_prev)
            count += 1
        f_prev = f_next
    return count


@njit(cache=True, _nrt=False)
def _quartic_roots(c0, c1, c2, c3, c4, lo, hi, breaks, roots):
    """All real roots of c4 t⁴ + … + c0 (c4 > 0) in [lo, hi], ascending, into ``roots``."""
    # Critical points of f' are the roots of f'' = 12 c4 t² + 6 c3 t + 2 c2 (stable formula).
    a, b, c = 12.0 * c4, 6.0 * c3, 2.0 * c2
    breaks[0] = lo
    n_breaks = 1
    disc = b * b - 4.0 * a * c
    if disc > 0.0:
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
        r1 = q / a
        r2 = c / q if q != 0.0 else r1
        for r in (min(r1, r2), max(r1, r2)):
            if lo < r < hi:
                breaks[n_breaks] = r
                n_breaks += 1
    breaks[n_breaks] = hi
    n_breaks += 1
    # Roots of f' = 4 c4 t³ + 3 c3 t² + 2 c2 t + c1 between them: the critical points of f.
    n_crit = _sign_changes(c1, 2.0 * c2, 3.0 * c3, 4.0 * c4, 0.0, breaks, n_breaks, roots)
    breaks[0] = lo
    for k in range(n_crit):
        breaks[k + 1] = roots[k]
    breaks[n_crit + 1] = hi
    return _sign_changes(c0, c1, c2, c3, c4, breaks, n_crit + 2, roots)


# --------------------------------------------------------------------------------------------
# Ray–surface intersection (unit direction d)


@njit(cache=True, _nrt=False)
def _sphere_roots(ox, oy, oz, dx, dy, dz, cx, cy, cz, radius, roots):
    """Ray parameters where the ray meets the sphere (0 or 2, ascending)."""
    fx, fy, fz = ox - cx, oy - cy, oz - cz
    b = fx * dx + fy * dy + fz * dz
    # |f − b d|² is the squared distance of the centre from the ray: accurate when far away.
    px, py, pz = fx - b * dx, fy - b * dy, fz - b * dz
    disc = radius * radius - (px * px + py * py + pz * pz)
    if disc < 0.0:
        return 0
    c = fx * fx + fy * fy + fz * fz - radius * radius
    q = -(b + math.copysign(math.sqrt(disc), b))
    if q == 0.0:
        roots[0] = 0.0
        roots[1] = 0.0
        return 2
    t1, t2 = c / q, q
    roots[0], roots[1] = min(t1, t2), max(t1, t2)
    return 2


@njit(cache=True, _nrt=False)
def _torus_roots(ox, oy, oz, dx, dy, dz, shape, breaks, roots):
    """Ray parameters where the ray meets the torus (0 to 4, ascending)."""
    cx, cy, cz = shape[1] - ox, shape[2] - oy, shape[3] - oz
    big_r, small_r = shape[4], shape[5]
    bound = (big_r + small_r) * (1.0 + 1e-9)
    # Entry into and exit from the bounding sphere.
    b = -(cx * dx + cy * dy + cz * dz)
    px, py, pz = -cx - b * dx, -cy - b * dy, -cz - b * dz
    disc = bound * bound - (px * px + py * py + pz * pz)
    if disc <= 0.0:
        return 0
    half = math.sqrt(disc)
    t_in = -b - half
    length = 2.0 * half
    # The ray from the entry point in the torus' frame, in units of the bounding radius.
    qx, qy, qz = (-cx + t_in * dx) / bound, (-cy + t_in * dy) / bound, (-cz + t_in * dz) / bound
    lx = qx * shape[10] + qy * shape[11] + qz * shape[12]
    ly = qx * shape[13] + qy * shape[14] + qz * shape[15]
    lz = qx * shape[7] + qy * shape[8] + qz * shape[9]
    ex = dx * shape[10] + dy * shape[11] + dz * shape[12]
    ey = dx * shape[13] + dy * shape[14] + dz * shape[15]
    ez = dx * shape[7] + dy * shape[8] + dz * shape[9]
    rr, sr = big_r / bound, small_r / bound
    # (s² + 2βs + γ)² − 4R²((lx + s ex)² + (ly + s ey)²), with |e| = 1.
    beta = lx * ex + ly * ey + lz * ez
    gamma = lx * lx + ly * ly + lz * lz + rr * rr - sr * sr
    four_r2 = 4.0 * rr * rr
    c4 = 1.0
    c3 = 4.0 * beta
    c2 = 4.0 * beta * beta + 2.0 * gamma - four_r2 * (ex * ex + ey * ey)
    c1 = 4.0 * beta * gamma - 2.0 * four_r2 * (lx * ex + ly * ey)
    c0 = gamma * gamma - four_r2 * (lx * lx + ly * ly)
    count = _quartic_roots(c0, c1, c2, c3, c4, 0.0, length / bound, breaks, roots)
    for k in range(count):
        roots[k] = t_in + roots[k] * bound
    return count


@njit(cache=True, _nrt=False)
def _torus_normal(px, py, pz, shape):
    """Unit normal at a point of the torus: away from the nearest point of the core circle."""
    qx, qy, qz = px - shape[1], py - shape[2], pz - shape[3]
    lx = qx * shape[10] + qy * shape[11] + qz * shape[12]
    ly = qx * shape[13] + qy * shape[14] + qz * shape[15]
    lz = qx * shape[7] + qy * shape[8] + qz * shape[9]
    rho = math.sqrt(lx * lx + ly * ly)
    k = 1.0 - shape[4] / rho if rho > 0.0 else 1.0
    nx, ny, nz = lx * k, ly * k, lz
    wx = nx * shape[10] + ny * shape[13] + nz * shape[7]
    wy = nx * shape[11] + ny * shape[14] + nz * shape[8]
    wz = nx * shape[12] + ny * shape[15] + nz * shape[9]
    ux, uy, uz, _ = unit3(wx, wy, wz)
    return ux, uy, uz


# --------------------------------------------------------------------------------------------
# The per-pixel kernel


@njit(cache=True, _nrt=False)
def _nearest_hit(shapes, ox, oy, oz, dx, dy, dz, vrp, nvx, nvy, nvz, front, back, breaks, roots):
    """``(shape, t)`` of the visible hit on the ray: inside [B, F] (n measured from the VRP
    along VPN) and nearest the viewer (largest n); ``(-1, 0)`` when there is none."""
    best_n = -np.inf
    best_t = 0.0
    best_shape = -1
    for k in range(shapes.shape[0]):
        if shapes[k, 0] == SPHERE:
            count = _sphere_roots(ox, oy, oz, dx, dy, dz, shapes[k, 1], shapes[k, 2],
                                  shapes[k, 3], shapes[k, 4], roots)
        else:
            count = _torus_roots(ox, oy, oz, dx, dy, dz, shapes[k], breaks, roots)
        for m in range(count):
            t = roots[m]
            n_hit = ((ox + t * dx - vrp[0]) * nvx + (oy + t * dy - vrp[1]) * nvy
                     + (oz + t * dz - vrp[2]) * nvz)
            if back <= n_hit <= front and n_hit > best_n:
                best_n, best_t, best_shape = n_hit, t, k
    return best_shape, best_t


# numpy's error model, as the parallel loop's body that it was; no reference counts (_nrt:
# it makes no array; the counts of the views it takes were a sixth of a frame)
@njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def _trace_rows(shapes, surfaces, lights, ambient, eye, halfway, cam, samples, background, rgb,
                surface_rgb, coverage, seen, start, end, roots, breaks):
    """Every pixel of rows ``start`` to ``end``: its samples' rays, the nearest shape each
    meets, lit there; the mean into ``rgb``, the hits' mean into ``surface_rgb``. ``roots``
    (4,) and ``breaks`` (6,): the shapes' scratch."""
    height, width = coverage.shape
    vrp = cam[CAMERA_VRP:CAMERA_VRP + 3]
    nvx, nvy, nvz = cam[CAMERA_BASIS + 6], cam[CAMERA_BASIS + 7], cam[CAMERA_BASIS + 8]
    front, back = cam[CAMERA_FRONT], cam[CAMERA_BACK]
    per_pixel = samples * samples
    for row in range(start, end):
        j = height - 1 - row                 # device row, counted from the bottom
        for col in range(width):
            sr, sg, sb = 0.0, 0.0, 0.0
            hits = 0
            first = -3                       # what the first sample saw (-1: nothing)
            mixed = False
            for a in range(samples):
                y = j + (a + 0.5) / samples
                for c in range(samples):
                    x = col + (c + 0.5) / samples
                    best_shape, best_t = -1, 0.0
                    inside, ox, oy, oz, dx, dy, dz = camera_ray(cam, x, y)
                    if inside:
                        best_shape, best_t = _nearest_hit(shapes, ox, oy, oz, dx, dy, dz, vrp,
                                                          nvx, nvy, nvz, front, back, breaks, roots)
                    if first == -3:
                        first = best_shape
                    elif first != best_shape:
                        mixed = True
                    if best_shape < 0:
                        continue
                    px, py, pz = ox + best_t * dx, oy + best_t * dy, oz + best_t * dz
                    shape = shapes[best_shape]
                    if shape[0] == SPHERE:
                        nx, ny, nz, _ = unit3(px - shape[1], py - shape[2], pz - shape[3])
                    else:
                        nx, ny, nz = _torus_normal(px, py, pz, shape)
                    r, g, b = light_point_calling(px, py, pz, nx, ny, nz, int(shape[6]),
                                                  surfaces, lights, ambient, eye, halfway)
                    sr += r
                    sg += g
                    sb += b
                    hits += 1
            coverage[row, col] = hits / per_pixel
            seen[row, col] = -2 if mixed else first
            missed = per_pixel - hits
            rgb[row, col, 0] = (sr + missed * background[0]) / per_pixel
            rgb[row, col, 1] = (sg + missed * background[1]) / per_pixel
            rgb[row, col, 2] = (sb + missed * background[2]) / per_pixel
            if hits > 0:
                surface_rgb[row, col, 0] = sr / hits
                surface_rgb[row, col, 1] = sg / hits
                surface_rgb[row, col, 2] = sb / hits
            else:
                for ch in range(3):
                    surface_rgb[row, col, ch] = background[ch]


@njit(cache=True, parallel=True, nogil=True)
def _trace(shapes, surfaces, lights, ambient, eye, halfway, cam, samples, background, rgb,
           surface_rgb, coverage, seen, at):
    """:func:`_trace_rows` row by row, in parallel, called by its address ``at``
    (core.jit.call_compiled): the shapes' tests and the lighting are typed and optimised
    once, in ``_trace_rows``, not again inside this loop."""
    height = coverage.shape[0]
    for row in prange(height):
        start = np.int64(row)
        call_compiled(at, _trace_rows, shapes, surfaces, lights, ambient, eye, halfway, cam,
                      samples, background, rgb, surface_rgb, coverage, seen, start, start + 1,
                      np.empty(4), np.empty(6))


def render_reference(shapes, scene, view: View, projection: str,
                     size: tuple[int, int] | None = None, samples: int = 4,
                     keep_aspect: bool = False) -> Reference:
    """The exact image of ``shapes`` lit by ``scene``'s lights, seen through ``view``.

    ``scene`` supplies ``lights``, ``ambient``, ``specular`` and ``background`` (its meshes are
    not used); ``size`` is ``(width, height)`` (default ``scene.size``); ``samples`` per axis
    (4 → 16 samples a pixel). Raises :class:`core.camera.view.ViewError` for an invalid view.
    """
    check(view, projection)
    if samples < 1:
        raise ValueError(f"samples must be at least 1, not {samples}")
    width, height = size or scene.size
    eye = eye_from_view(view, projection)
    shapes = list(shapes)
    packed = pack_shapes(shapes)
    surfaces = pack_surfaces([s.material for s in shapes], [s.two_sided for s in shapes])
    rgb = np.zeros((height, width, 3))
    surface_rgb = np.zeros((height, width, 3))
    coverage = np.zeros((height, width))
    seen = np.zeros((height, width), dtype=np.int64)
    given = (packed, surfaces, pack_lights(scene.lights), pack_ambient(scene.ambient),
             pack_eye(eye), scene.specular == "halfway",
             pack_camera(view, projection, width, height, keep_aspect), int(samples),
             np.asarray(scene.background, dtype=np.float64).reshape(3), rgb, surface_rgb,
             coverage, seen)
    _trace(*given, compiled_at(_trace_rows, given + (0, 0, np.empty(4), np.empty(6))))
    return Reference(rgb=rgb, surface_rgb=surface_rgb, coverage=coverage, shape=seen,
                     samples=int(samples))


def draw(scene, view: View, settings, frame, context, timer) -> None:
    """The ``raycast`` renderer: ``scene.primitives`` ray-cast exactly, on a regular grid of
    ``settings.samples`` per pixel (the smallest square grid that holds them)."""
    if not scene.primitives:
        fill(frame.color, scene.background)
        frame.message = (f"{scene.name}: no analytic primitives; the ray caster draws only those "
                         "(the meshes need the z-buffer)")
        return
    drawn = {id(shape) for shape in scene.primitives}
    notes = frame.stats.setdefault("not drawn", [])
    for mesh in scene.meshes:          # meshes and planes: the z-buffer's and the tracer's
        note = (f"{getattr(mesh, 'name', None) or 'a mesh'}: the ray caster draws only the "
                f"analytic spheres and tori")
        if id(mesh.tessellates) not in drawn and len(mesh.triangles) and note not in notes:
            notes.append(note)
    side = grid_side(settings.samples)
    reference = render_reference(scene.primitives, scene, view, settings.projection,
                                 settings.size, samples=side, keep_aspect=settings.keep_aspect)
    frame.color[:] = to_rgb8(reference.rgb)
    frame.stats["samples per pixel"] = side * side
    frame.stats["computed"].append("exact ray casting")
    timer.lap("ray cast")
