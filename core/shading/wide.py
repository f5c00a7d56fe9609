"""The illumination model at the hardware's width: the same model as
:func:`core.shading.illumination.phong_point`, evaluated in float32 over many points at once
so that the compiler turns the loops into 8-wide AVX instructions.

The textbook kernels evaluate the model one point at a time in float64. Here a span of points
(a band of rows of Phong's pixels, :func:`resolve_phong_wide`; a block of flat's faces or Gouraud's
vertices, :func:`illuminate_wide`) is done in passes, one quantity per row of a small scratch
array (structure of arrays):

1. *gather*: the normal and position (Phong: interpolated with the barycentrics, in float64),
   the normal and V = eye − P stored as float32, P kept in float64 for the lights;
2. *normalise*: N and V made unit, the two-sided flip, the ambient term;
3. *each light*: L, f_att, N·L, the specular base (reflection or halfway), the power by
   repeated squaring (the same products as ``specular_power``), the sum;
4. *store*: clamp and round half up.

Where float32 is not safe the pixel is flagged in pass 2 or 3 and evaluated by
``phong_point`` in float64 instead: a squared length outside [1e-30, 1e30] (a zero normal, a
point light on the surface, huge or tiny scenes: the stability suite's extremes). Frames whose
exponents are not whole numbers up to 2^16, and frames with a surface lit by another
lighting model (:mod:`core.shading.models`), go to the float64 kernel entirely
(:func:`float32_is_exact_enough`), and so do frames whose light x material products pass
1e30 (``core.shading.shade.float32_holds_the_terms``: float32 would overflow, and inf x 0 is
NaN).

Error against the float64 model: at most 1/255 per channel (one rounding step of the
byte), held by ``tests/core/shading/test_shading_wide.py`` on every shipped scene and golden.
"""

from __future__ import annotations


import numpy as np

from core.arrays import read_only
from core.jit import call_compiled, compiled_at, njit, prange
from core.prefetch import prefetch
from core.shading.illumination import MODEL, SQUARING_LIMIT, phong_point, quantize, unit3

F = np.float32
# Rows of the per-span scratch: one quantity per row, one pixel per column.
# Raw (interpolated) N and V, then unit N and V, L, two sets of sums (lights alternate between
# them: a loop that reads and writes the same rows is not vectorised), the specular terms.
NX, NY, NZ, VX, VY, VZ, UX, UY, UZ, WX, WY, WZ, LX, LY, LZ, R, G, B, R2, G2, B2, BASE, SPEC, \
    DIFF, ATT = range(25)
ROWS = 25
# Squared lengths float32 handles with room to spare (its range is 1e-38..3e38).
TINY, HUGE = F(1e-30), F(1e30)
FLUSH = F(1e-19)                  # its square is still a normal float32


def float32_is_exact_enough(surfaces: np.ndarray) -> bool:
    """Every surface lit by the Phong model (these passes are that model's) and every
    exponent a whole number in [0, 2^16]: the powers are the same products."""
    n = surfaces[:, 3]
    return bool(np.all((n == np.floor(n)) & (n >= 0) & (n <= SQUARING_LIMIT))
                and np.all(surfaces[:, MODEL] == 0))


AHEAD = 8              # pixels along a row that the gather asks for a triangle's corners early
BAND_PIXELS = 2048     # Phong's pixels per work item: a band of whole rows of about this many


def resolve_phong_wide(tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces,
                       lights, ambient, eye, halfway, out):
    """Phong at every covered pixel of each row's span, float32 in passes (see the module).

    The work items are bands of whole rows of about ``BAND_PIXELS`` covered pixels, their
    spans gathered one after another into one scratch: a call of a pass hands over its
    arrays (an atomic reference count each, on arrays the cores share), so a pass per band
    costs less than a pass per row (1k-triangle frame: 1.82 → 1.65 ms of CPU). The span is
    cut into runs of one surface (material): the passes read the material once per run, as
    scalars. The scratch rows go to the passes as separate arrays, so that the compiler sees
    that loads and stores do not overlap."""
    if triangles.shape[0] == 0:
        return
    given = (tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces, lights,
             ambient, eye, halfway, out)
    _resolve_bands(_bands(span), *given, compiled_at(_phong_band, (0, 0) + given))


@njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _resolve_bands(first, tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces,
                   lights, ambient, eye, halfway, out, at):
    """:func:`_phong_band` on each band, in parallel, called by its address ``at``
    (core.jit.call_compiled): the passes are optimised once, in ``_phong_band``, not again
    inside this loop (the old loop compiled in 7.1 s; this one in under 1.1 s, and
    ``_phong_band`` in 1.8 s)."""
    for band in prange(first.shape[0] - 1):
        call_compiled(at, _phong_band, first[band], first[band + 1], tri, b1, b2, span,
                      triangles, attrs, source, face_surface, surfaces, lights, ambient, eye,
                      halfway, out)


# numpy's error model, as the parallel loop's body that it was
@njit(cache=True, nogil=True, error_model="numpy")
def _phong_band(r0, r1, tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces,
                lights, ambient, eye, halfway, out):
    """The passes over the spans of rows ``r0`` to ``r1``, one after another."""
    m = 0
    for row in range(r0, r1):
        m += max(span[row, 1] - span[row, 0] + 1, 0)
    if m == 0:
        return
    q = np.empty((ROWS, m), np.float32)
    p = np.empty((3, m))
    flag = np.zeros(m, np.bool_)
    runs = np.empty(m + 1, np.int64)
    run_surface = np.empty(m, np.int64)
    n_runs = _gather(r0, r1, span, tri, b1, b2, triangles, attrs, source, face_surface, eye, q,
                     p, runs, run_surface, surfaces.shape[0] == 1)
    sums = _shade_span(q, p, flag, runs[:n_runs + 1], run_surface[:n_runs], surfaces, lights,
                       ambient, halfway)
    _store(r0, r1, span, tri, b1, b2, triangles, attrs, source, face_surface, surfaces, lights,
           ambient, eye, halfway, q[sums:sums + 3], flag, out)


@njit(cache=True, error_model="numpy")
def _bands(span):
    """First rows of bands of whole rows holding about BAND_PIXELS covered pixels each."""
    rows = span.shape[0]
    first = np.empty(rows + 1, np.int64)
    n, pixels = 1, 0
    first[0] = 0
    for row in range(rows):
        if pixels >= BAND_PIXELS:
            first[n] = row
            n += 1
            pixels = 0
        pixels += max(span[row, 1] - span[row, 0] + 1, 0)
    first[n] = rows
    return first[:n + 1]


@njit(cache=True, error_model="numpy")
def _gather(r0, r1, span, tri, b1, b2, triangles, attrs, source, face_surface, eye, q, p,
                 runs, run_surface, one_surface):
    """Pass 1 over rows r0 .. r1 - 1, their spans one after another: N and P interpolated,
    V unnormalised; the runs of one surface. Returns the number of runs. A run of one
    triangle reuses its corners (vertex 0 and the edges to vertices 1 and 2: a0 + w1 d1 +
    w2 d2 is w0 a0 + w1 a1 + w2 a2 with w0 = 1 - w1 - w2), held in local variables: kept in
    an array, every store to ``q`` and ``p`` (which LLVM cannot tell apart from it) made the
    next pixel load them again (the pass took 12 % longer at 1580 x 1080). With
    ``one_surface`` (one material in the scene) the span is one run, and the surface of each
    new triangle is not looked up (two dependent loads: 0.91x the pass on the bunny)."""
    perspective = eye[0] == 1.0
    ex, ey, ez = eye[1], eye[2], eye[3]
    nx0 = ny0 = nz0 = nx1 = ny1 = nz1 = nx2 = ny2 = nz2 = 0.0     # normal: a0, d1, d2
    px0 = py0 = pz0 = px1 = py1 = pz1 = px2 = py2 = pz2 = 0.0     # position: a0, d1, d2
    last, n_runs, j = -1, 0, np.uint64(0)
    if one_surface:
        runs[0], run_surface[0], n_runs = 0, 0, 1
    for row_ in range(r0, r1):
        row = np.uint64(row_)           # unsigned indices: no wraparound (core.pipeline.raster)
        end = span[row, 1]
        for col_ in range(span[row, 0], end + 1):
            col = np.uint64(col_)
            # the corner indices of the triangle AHEAD pixels on: a new triangle every ~1.4
            # pixels, and these loads, not the branch, were the pass's time
            prefetch(triangles, max(tri[row, np.uint64(min(col_ + AHEAD, end))], 0))
            t = tri[row, col]
            if t < 0:                     # background: the last triangle's harmless numbers
                t = max(last, 0)
            if t != last:
                last = t
                u = np.uint64(t)
                i0, i1, i2 = (np.uint64(triangles[u, 0]), np.uint64(triangles[u, 1]),
                              np.uint64(triangles[u, 2]))
                nx0, ny0, nz0 = attrs[i0, 0], attrs[i0, 1], attrs[i0, 2]
                px0, py0, pz0 = attrs[i0, 3], attrs[i0, 4], attrs[i0, 5]
                nx1, ny1, nz1 = attrs[i1, 0] - nx0, attrs[i1, 1] - ny0, attrs[i1, 2] - nz0
                px1, py1, pz1 = attrs[i1, 3] - px0, attrs[i1, 4] - py0, attrs[i1, 5] - pz0
                nx2, ny2, nz2 = attrs[i2, 0] - nx0, attrs[i2, 1] - ny0, attrs[i2, 2] - nz0
                px2, py2, pz2 = attrs[i2, 3] - px0, attrs[i2, 4] - py0, attrs[i2, 5] - pz0
                if not one_surface:
                    s = face_surface[np.uint64(source[u])]
                    if n_runs == 0 or run_surface[n_runs - 1] != s:
                        runs[n_runs], run_surface[n_runs] = j, s
                        n_runs += 1
            w1, w2 = b1[row, col], b2[row, col]
            x = px0 + w1 * px1 + w2 * px2
            y = py0 + w1 * py1 + w2 * py2
            z = pz0 + w1 * pz1 + w2 * pz2
            q[NX, j] = nx0 + w1 * nx1 + w2 * nx2
            q[NY, j] = ny0 + w1 * ny1 + w2 * ny2
            q[NZ, j] = nz0 + w1 * nz1 + w2 * nz2
            p[0, j], p[1, j], p[2, j] = x, y, z
            if perspective:
                q[VX, j], q[VY, j], q[VZ, j] = ex - x, ey - y, ez - z
            else:
                q[VX, j], q[VY, j], q[VZ, j] = ex, ey, ez
            j += np.uint64(1)
    runs[n_runs] = j
    return n_runs


@njit(cache=True, error_model="numpy")
def _store(r0, r1, span, tri, b1, b2, triangles, attrs, source, face_surface, surfaces,
                lights, ambient, eye, halfway, rgb_sum, flag, out):
    """Pass 4 over rows r0 .. r1 - 1: bytes for the covered pixels; flagged ones by the
    float64 model."""
    m = rgb_sum.shape[1]
    rgb = np.empty((3, m), np.uint8)
    for c in range(3):
        for j in range(m):
            rgb[c, j] = np.uint8(np.int32(min(max(rgb_sum[c, j], F(0.0)), F(1.0)) * F(255.0)
                                          + F(0.5)))   # clamped to [0, 1]: truncation floors
    j = np.uint64(0)
    for row_ in range(r0, r1):
        row = np.uint64(row_)          # unsigned indices: no wraparound (as in _gather)
        for col_ in range(span[row, 0], span[row, 1] + 1):
            col = np.uint64(col_)
            t = tri[row, col]
            if t >= 0:
                if not flag[j]:
                    out[row, col, 0], out[row, col, 1], out[row, col, 2] = (rgb[0, j], rgb[1, j],
                                                                            rgb[2, j])
                else:
                    _float64_pixel(row_, col_, t, b1, b2, triangles, attrs, source,
                                   face_surface, surfaces, lights, ambient, eye, halfway, out)
            j += np.uint64(1)


@njit(cache=True, error_model="numpy")
def _shade_span(q, p, flag, runs, run_surface, surfaces, lights, ambient, halfway):
    """Passes 2 and 3 over a gathered span; returns the row of the R sums (R or R2)."""
    _normalise(runs, run_surface, surfaces, ambient, flag, q[NX], q[NY], q[NZ], q[VX], q[VY],
               q[VZ], q[UX], q[UY], q[UZ], q[WX], q[WY], q[WZ], q[R], q[G], q[B], q[LX])
    nx, ny, nz, vx, vy, vz = q[UX], q[UY], q[UZ], q[WX], q[WY], q[WZ]
    sums = R
    for k in range(lights.shape[0]):
        light = lights[k]
        if light[0] == 0.0:
            _toward_point(light, p, flag, nx, ny, nz, q[LX], q[LY], q[LZ], q[DIFF], q[ATT])
        else:
            _toward_direction(light, nx, ny, nz, q[LX], q[LY], q[LZ], q[DIFF], q[ATT])
        if halfway:
            _halfway_base(flag, nx, ny, nz, q[LX], q[LY], q[LZ], vx, vy, vz, q[BASE])
        else:
            _mirror_base(nx, ny, nz, q[LX], q[LY], q[LZ], vx, vy, vz, q[DIFF], q[BASE])
        into = R2 if sums == R else R
        _add_light(runs, run_surface, surfaces, light, q[DIFF], q[ATT], q[BASE], q[SPEC],
                   q[sums], q[sums + 1], q[sums + 2], q[into], q[into + 1], q[into + 2])
        sums = into
    return sums


# Points per block of illuminate_wide: the scratch (about 100 bytes a point) stays in cache,
# and a block's five scratch arrays are allocated once per 512 points, not per 256 (the
# bunny's 35,105 vertices lit: 0.39 → 0.31 ms; 1024 gave the same as 512).
BLOCK = 512


def illuminate_wide(points, normals, surface, which, out, out_rows, surfaces, lights, ambient,
                    eye, halfway, parallel: bool) -> None:
    """The model at the world points ``points[which]`` with their (unit or zero) normals, as
    :func:`core.shading.illumination.illuminate` but in float32 passes: RGB in [0, 1] into
    the rows ``out_rows`` of ``out`` (one per point of ``which``). ``surface`` is each
    point's row of ``surfaces``; blocks of points run on all cores when ``parallel``."""
    given = (read_only(points), read_only(normals), read_only(surface), which, out, out_rows,
             surfaces, lights, ambient, eye, halfway, 0, (which.shape[0] + BLOCK - 1) // BLOCK)
    if parallel:
        _illuminate_blocks_parallel(*given[:-2], compiled_at(_illuminate_blocks, given))
    else:
        _illuminate_blocks(*given)


# Blocks per call of the parallel loop: a call through a pointer costs about a microsecond, a
# block of the bunny's faces about fourteen.
BLOCKS_A_CALL = 4


@njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _illuminate_blocks_parallel(points, normals, surface, which, out, out_rows, surfaces,
                                lights, ambient, eye, halfway, at):
    """:func:`_illuminate_blocks` on runs of :data:`BLOCKS_A_CALL` blocks, in parallel,
    called by its address ``at`` (core.jit.call_compiled): the lighting passes are
    optimised once, in ``_illuminate_blocks``, not again inside this loop."""
    blocks = (which.shape[0] + BLOCK - 1) // BLOCK
    for j in prange((blocks + BLOCKS_A_CALL - 1) // BLOCKS_A_CALL):
        first = np.int64(j) * BLOCKS_A_CALL
        call_compiled(at, _illuminate_blocks, points, normals, surface, which, out, out_rows,
                      surfaces, lights, ambient, eye, halfway, first,
                      min(blocks, first + BLOCKS_A_CALL))


@njit(cache=True, nogil=True, error_model="numpy")
def _illuminate_blocks(points, normals, surface, which, out, out_rows, surfaces, lights,
                       ambient, eye, halfway, first, end):
    """Blocks ``first`` to ``end`` of :data:`BLOCK` points each."""
    for block in range(first, end):
        _illuminate_block(block * BLOCK, points, normals, surface, which, out, out_rows,
                          surfaces, lights, ambient, eye, halfway)


@njit(cache=True, error_model="numpy")
def _illuminate_block(j0, points, normals, surface, which, out, out_rows, surfaces, lights,
                      ambient, eye, halfway):
    """Points which[j0 .. j0 + BLOCK - 1]: gather, passes 2 and 3, and the clamped sums
    (flagged points by the float64 model)."""
    m = min(BLOCK, which.shape[0] - j0)
    q = np.empty((ROWS, m), np.float32)
    p = np.empty((3, m))
    flag = np.zeros(m, np.bool_)
    runs = np.empty(m + 1, np.int64)
    run_surface = np.empty(m, np.int64)
    n_runs = 0
    for j in range(m):
        i = which[j0 + j]
        for c in range(3):
            q[NX + c, j] = normals[i, c]
            p[c, j] = points[i, c]
            q[VX + c, j] = eye[1 + c] - points[i, c] if eye[0] == 1.0 else eye[1 + c]
        if n_runs == 0 or run_surface[n_runs - 1] != surface[i]:
            runs[n_runs], run_surface[n_runs] = j, surface[i]
            n_runs += 1
    runs[n_runs] = m
    sums = _shade_span(q, p, flag, runs[:n_runs + 1], run_surface[:n_runs], surfaces, lights,
                       ambient, halfway)
    for j in range(m):
        i, row = which[j0 + j], out_rows[j0 + j]
        if flag[j]:
            out[row, 0], out[row, 1], out[row, 2] = phong_point(
                points[i, 0], points[i, 1], points[i, 2], normals[i, 0], normals[i, 1],
                normals[i, 2], surface[i], surfaces, lights, ambient, eye, halfway)
        else:
            for c in range(3):
                out[row, c] = min(max(q[sums + c, j], F(0.0)), F(1.0))


@njit(cache=True, error_model="numpy")
def _normalise(runs, run_surface, surfaces, ambient, flag, nx, ny, nz, vx, vy, vz, ux, uy, uz,
               wx, wy, wz, r, g, b, turn):
    """Pass 2: N and V to unit length (into U and W), N turned to the viewer on a two-sided
    surface; the ambient term. A squared length float32 cannot hold safely flags the pixel.
    ``turn``: a scratch row."""
    _unit(nx, ny, nz, ux, uy, uz, flag)
    _unit(vx, vy, vz, wx, wy, wz, flag)
    for k in range(run_surface.shape[0]):
        s, j0, j1 = run_surface[k], runs[k], runs[k + 1]
        r[j0:j1] = F(ambient[0] * surfaces[s, 0] * surfaces[s, 4])
        g[j0:j1] = F(ambient[1] * surfaces[s, 0] * surfaces[s, 5])
        b[j0:j1] = F(ambient[2] * surfaces[s, 0] * surfaces[s, 6])
        if surfaces[s, 10] != 0.0:
            _turn_to_viewer(ux[j0:j1], uy[j0:j1], uz[j0:j1], wx[j0:j1], wy[j0:j1], wz[j0:j1],
                            turn[j0:j1])


@njit(cache=True, error_model="numpy")
def _turn_to_viewer(ux, uy, uz, wx, wy, wz, sign):
    """U = −U where U·W < 0. Written as a sign and three products (−1 · x is −x exactly; a
    NaN keeps its sign, and its pixel is flagged already), not a branch that swaps three
    rows: each loop then reads at most six rows and writes one, few enough overlap checks for
    the compiler to run it eight pixels at a time (pass 2 on the bunny's pixels, in cache:
    4.0 → 2.6 ns a pixel; the Phong frame at 1580 x 1080 0.97x)."""
    for j in range(ux.shape[0]):
        sign[j] = F(-1.0) if ux[j] * wx[j] + uy[j] * wy[j] + uz[j] * wz[j] < F(0.0) else F(1.0)
    for j in range(ux.shape[0]):
        ux[j] *= sign[j]
    for j in range(ux.shape[0]):
        uy[j] *= sign[j]
    for j in range(ux.shape[0]):
        uz[j] *= sign[j]


@njit(cache=True, error_model="numpy")
def _unit(x, y, z, ux, uy, uz, flag):
    """(x, y, z) / |(x, y, z)| per pixel; flags lengths² outside [1e-30, 1e30]."""
    for j in range(x.shape[0]):
        n2 = x[j] * x[j] + y[j] * y[j] + z[j] * z[j]
        flag[j] |= not (TINY < n2 < HUGE)
        inv = F(1.0) / np.sqrt(max(n2, TINY))
        ux[j], uy[j], uz[j] = x[j] * inv, y[j] * inv, z[j] * inv


@njit(cache=True, error_model="numpy")
def _toward_point(light, p, flag, nx, ny, nz, lx, ly, lz, diff, att):
    """L = (light − P)/d, f_att = min(1, 1/(c1 + c2 d + c3 d²)) and N·L."""
    for j in range(nx.shape[0]):
        x, y, z = F(light[1] - p[0, j]), F(light[2] - p[1, j]), F(light[3] - p[2, j])
        d2 = x * x + y * y + z * z
        flag[j] |= not (TINY < d2 < HUGE)           # the light on the surface, or absurdly far
        d = np.sqrt(max(d2, TINY))
        inv = F(1.0) / d
        lx[j], ly[j], lz[j] = x * inv, y * inv, z * inv
        den = F(light[7]) + F(light[8]) * d + F(light[9]) * d * d
        # FvDFH's cap at 1 unless the light asks for the notes' uncapped 1/den (column 10)
        att[j] = F(1.0) / den if den > F(1.0) or (light[10] == 0.0 and den > F(0.0)) else F(1.0)
        diff[j] = nx[j] * lx[j] + ny[j] * ly[j] + nz[j] * lz[j]


@njit(cache=True, error_model="numpy")
def _toward_direction(light, nx, ny, nz, lx, ly, lz, diff, att):
    x, y, z = F(light[1]), F(light[2]), F(light[3])
    for j in range(nx.shape[0]):
        lx[j], ly[j], lz[j], att[j] = x, y, z, F(1.0)
        diff[j] = nx[j] * x + ny[j] * y + nz[j] * z


@njit(cache=True, error_model="numpy")
def _mirror_base(nx, ny, nz, lx, ly, lz, vx, vy, vz, diff, base):
    """R·V with R = 2 (N·L) N − L, clamped to [0, 1]."""
    for j in range(nx.shape[0]):
        two = F(2.0) * diff[j]
        dot = ((two * nx[j] - lx[j]) * vx[j] + (two * ny[j] - ly[j]) * vy[j]
               + (two * nz[j] - lz[j]) * vz[j])
        base[j] = min(max(dot, F(0.0)), F(1.0))


@njit(cache=True, error_model="numpy")
def _halfway_base(flag, nx, ny, nz, lx, ly, lz, vx, vy, vz, base):
    """N·H with H = (L + V)/|L + V|, clamped to [0, 1]."""
    for j in range(nx.shape[0]):
        hx, hy, hz = lx[j] + vx[j], ly[j] + vy[j], lz[j] + vz[j]
        h2 = hx * hx + hy * hy + hz * hz
        flag[j] |= not (TINY < h2)                  # L = −V: H undefined
        dot = (nx[j] * hx + ny[j] * hy + nz[j] * hz) / np.sqrt(max(h2, TINY))
        base[j] = min(max(dot, F(0.0)), F(1.0))


@njit(cache=True, error_model="numpy")
def _add_light(runs, run_surface, surfaces, light, diff, att, base, spec, r, g, b, r_out,
               g_out, b_out):
    """I_p f_att [k_d O_d N·L + k_s O_s base^n] added where N·L > 0, run by run (each run
    has one material: k_d, k_s, O_d, O_s and n are scalars in the loops). The two terms go
    through ``base`` and ``spec`` first: a loop reading seven rows and writing three needs
    more overlap checks than the compiler will emit, and then runs one pixel at a time."""
    for k in range(run_surface.shape[0]):
        s, j0, j1 = run_surface[k], runs[k], runs[k + 1]
        _power(base[j0:j1], spec[j0:j1], int(surfaces[s, 3]))
        _terms(diff[j0:j1], att[j0:j1], spec[j0:j1], base[j0:j1])
        for c, (sums, into) in enumerate(((r, r_out), (g, g_out), (b, b_out))):
            kd = F(light[4 + c] * surfaces[s, 1] * surfaces[s, 4 + c])
            ks = F(light[4 + c] * surfaces[s, 2] * surfaces[s, 7 + c])
            _add_channel(sums[j0:j1], base[j0:j1], spec[j0:j1], kd, ks, into[j0:j1])


@njit(cache=True, error_model="numpy")
def _terms(diff, att, spec, diffuse):
    """``diffuse`` = f_att N·L and ``spec`` = f_att base^n where N·L > 0, else 0 (no
    diffuse, no specular from behind the surface)."""
    for j in range(diff.shape[0]):
        lit = diff[j] > F(0.0)
        diffuse[j] = att[j] * diff[j] if lit else F(0.0)
        spec[j] = att[j] * spec[j] if lit else F(0.0)


@njit(cache=True, error_model="numpy")
def _add_channel(sums, diffuse, specular, kd, ks, out):
    for j in range(sums.shape[0]):
        out[j] = sums[j] + (kd * diffuse[j] + ks * specular[j])


@njit(cache=True, error_model="numpy")
def _power(base, spec, n):
    """spec = base^n by repeated squaring, the products ``specular_power`` takes. Values
    below 1e-19 become 0 before they are squared: float32 would go subnormal (a hundred
    cycles an operation) for a term far below 1/255."""
    for j in range(base.shape[0]):
        spec[j] = F(1.0)
    while n > 0:
        if n & 1:
            for j in range(base.shape[0]):
                spec[j] *= base[j]
        n >>= 1
        if n > 0:
            for j in range(base.shape[0]):
                x = base[j]
                base[j] = x * x if x > FLUSH else F(0.0)


@njit(cache=True, error_model="numpy")
def _float64_pixel(row, col, t, b1, b2, triangles, attrs, source, face_surface, surfaces,
                   lights, ambient, eye, halfway, out):
    """The textbook kernel's evaluation of one pixel (core.shading.phong._phong_rows)."""
    i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    w1, w2 = b1[row, col], b2[row, col]
    w0 = 1.0 - w1 - w2
    q = np.empty(6)
    for c in range(6):
        q[c] = w0 * attrs[i0, c] + w1 * attrs[i1, c] + w2 * attrs[i2, c]
    nx, ny, nz, _ = unit3(q[0], q[1], q[2])
    r, g, b = phong_point(q[3], q[4], q[5], nx, ny, nz, face_surface[source[t]], surfaces,
                          lights, ambient, eye, halfway)
    out[row, col, 0], out[row, col, 1], out[row, col, 2] = quantize(r), quantize(g), quantize(b)
