"""Marching cubes (Lorensen and Cline, SIGGRAPH 1987; FvDFH 20.6.3): the surface ``value =
iso`` of a sampled volume as a triangle mesh with gradient normals.

Each cell of eight samples is classified by which corners are *inside* (``value > iso``); the
surface crosses every cell edge whose two corners differ, at the point linear interpolation
puts ``iso``, and that point is one vertex shared by the four cells around the edge. Instead
of Lorensen and Cline's 256-entry table (whose complementary cases leave holes on ambiguous
faces), the polygons are built from the cell's six faces, which is how the table's entries
were meant to be read:

1. on each face, the crossing points are joined by segments that separate the inside corners
   from the outside ones; each segment runs so that the outside corners lie on its left seen
   from outside the cell;
2. a face with inside corners on one diagonal and outside on the other is *ambiguous*; the
   **asymptotic decider** (Nielson and Hamann, Visualization 1991) joins the inside corners
   when the bilinear interpolant's saddle value lies inside, i.e. when the product of the
   inside diagonal's offsets from ``iso`` exceeds the outside diagonal's (a tie separates them);
3. every crossed edge ends one segment and starts another, so the segments chain into closed
   loops. A cell with exactly two loops may be a tunnel rather than two discs: the side the
   discs cut off (the corners that fall in two groups on the cell's boundary) is joined
   through the interior when the trilinear interpolant has a body saddle inside the cell on
   that side (Natarajan, "Enhancing the marching cubes method", 1994: ∇f = 0 is a quadratic in
   z); then the two loops are zipped into a tube, each loop's edges run as its disc ran them;
4. otherwise each loop is cut into triangles ear by ear, never by a diagonal between two
   crossings of one face (on an ambiguous face, the neighbouring cell could draw the same
   diagonal and the edge would have four triangles); a loop left with no such ear is fanned
   from a vertex added at its centre.

Two cells that share a face see the same four values there and make the same decision, so the
mesh is closed wherever the surface stays inside the grid (every edge shared by exactly two
triangles), and each triangle winds counter-clockwise seen from the outside (its normal points
towards lower values). Interior ambiguity beyond two loops (a tunnel through a face's saddle,
Lewiner's cases 6, 7, 10, 12 and 13) is not decided: its loops stay discs, which still closes
the surface.

Vertex normals are the negated gradient of the data (central differences at the samples,
one-sided at the grid's border), interpolated along the edge like the position: the normal of
the smooth field the samples come from, rather than the facets' (Lorensen and Cline's
"gradient normals").
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit, prange
from core.scene.generators import MAX_TRIANGLES
from core.scene.model import Mesh
from core.volume.data import VolumeError, check_iso

# Corner c of a cell sits at (c & 1, c >> 1 & 1, c >> 2 & 1) from the cell's first sample.
CORNERS = np.array([[c & 1, (c >> 1) & 1, (c >> 2) & 1] for c in range(8)], dtype=np.int64)
# The 12 edges, 4 along each axis (edge e runs along axis e // 4), from corner a to corner b.
EDGES = np.array([[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7],
                  [0, 4], [1, 5], [2, 6], [3, 7]], dtype=np.int64)
# Each face's corners, counter-clockwise seen from outside the cell: x = 0, x = 1, y = 0,
# y = 1, z = 0, z = 1.
FACES = np.array([[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1],
                  [4, 5, 7, 6]], dtype=np.int64)


def _face_edges() -> np.ndarray:
    edge_of = {}
    for e, (a, b) in enumerate(EDGES):
        edge_of[a, b] = edge_of[b, a] = e
    return np.array([[edge_of[f[q], f[(q + 1) % 4]] for q in range(4)] for f in FACES],
                    dtype=np.int64)


FACE_EDGES = _face_edges()           # FACE_EDGES[f, q]: the edge from corner q to corner q + 1
# EDGE_FACES[e]: the two faces edge e lies on.
EDGE_FACES = np.array([[f for f in range(6) if e in FACE_EDGES[f]] for e in range(12)],
                      dtype=np.int64)


# numpy's error model, as in the parallel loops that call it with their index: one
# compiled form for both (core.jit.reuse_plain_overloads)
@njit(cache=True, error_model="numpy")
def gradient_at(v, i, j, k):
    """The data's gradient at sample (i, j, k), in index units: central differences, one-sided
    at the border."""
    n0, n1, n2 = v.shape
    i0, i1 = max(i - 1, 0), min(i + 1, n0 - 1)
    j0, j1 = max(j - 1, 0), min(j + 1, n1 - 1)
    k0, k1 = max(k - 1, 0), min(k + 1, n2 - 1)
    gx = (v[i1, j, k] - v[i0, j, k]) / (i1 - i0)
    gy = (v[i, j1, k] - v[i, j0, k]) / (j1 - j0)
    gz = (v[i, j, k1] - v[i, j, k0]) / (k1 - k0)
    return gx, gy, gz


@njit(cache=True, error_model="numpy")
def edge_slab(v, iso, axis, i, ids, positions, normals, start, write):
    """Number (and, with ``write``, place) the crossing of every edge along ``axis`` in slab
    ``i``: ``ids[i]`` gets each crossed edge's vertex index from ``start`` on, -1 elsewhere.
    Returns the next free index."""
    _, n1, n2 = ids.shape
    count = start
    for j in range(n1):
        for k in range(n2):
            a = v[i, j, k] - iso
            i2, j2, k2 = i + (axis == 0), j + (axis == 1), k + (axis == 2)
            b = v[i2, j2, k2] - iso
            if (a > 0.0) == (b > 0.0):
                ids[i, j, k] = -1
                continue
            ids[i, j, k] = count
            if write:
                t = a / (a - b)
                positions[count, 0] = i + t * (i2 - i)
                positions[count, 1] = j + t * (j2 - j)
                positions[count, 2] = k + t * (k2 - k)
                ax, ay, az = gradient_at(v, i, j, k)
                bx, by, bz = gradient_at(v, i2, j2, k2)
                normals[count, 0] = -(ax + t * (bx - ax))
                normals[count, 1] = -(ay + t * (by - ay))
                normals[count, 2] = -(az + t * (bz - az))
            count += 1
    return count


@njit(cache=True, parallel=True)
def edge_vertices(v, iso, axis, ids, positions, normals, starts, write):
    """Every slab's crossings along ``axis`` on all cores: without ``write``, ``starts[i + 1]``
    gets slab i's count; with it, slab i numbers its vertices from ``starts[i]``."""
    for i in prange(ids.shape[0]):
        first = starts[i] if write else 0
        found = edge_slab(v, iso, axis, i, ids, positions, normals, first, write) - first
        if not write:
            starts[i + 1] = found


@njit(cache=True)
def face_segments(w, inside, face_corners, face_edges, nxt, joined):
    """Join the crossings on each face (steps 1 and 2 of the module): ``nxt[e]`` = the edge
    the segment starting at crossed edge ``e`` ends on; ``joined[f]``: on an ambiguous face,
    1 when the inside corners are joined, 0 when the outside ones are, -1 on the others."""
    cross = np.empty(4, np.int64)
    enter = np.empty(4, np.bool_)
    for f in range(6):
        n = 0
        joined[f] = -1
        for q in range(4):
            a, b = face_corners[f, q], face_corners[f, (q + 1) % 4]
            if inside[a] != inside[b]:
                cross[n] = face_edges[f, q]
                enter[n] = inside[b]           # outside → inside, walking counter-clockwise
                n += 1
        if n == 2:
            if enter[0]:
                nxt[cross[0]] = cross[1]
            else:
                nxt[cross[1]] = cross[0]
        elif n == 4:                           # ambiguous: the asymptotic decider
            c0, c1, c2, c3 = face_corners[f, 0], face_corners[f, 1], face_corners[f, 2], \
                face_corners[f, 3]
            if inside[c0]:
                inner = w[c0] * w[c2] > w[c1] * w[c3]
            else:
                inner = w[c1] * w[c3] > w[c0] * w[c2]
            joined[f] = 1 if inner else 0
            for m in range(4):
                if enter[m]:
                    nxt[cross[m]] = cross[(m + 3) % 4] if inner else cross[(m + 1) % 4]


@njit(cache=True)
def share_face(e1, e2, edge_faces):
    """Whether cell edges e1 and e2 lie on one face."""
    return (edge_faces[e1, 0] == edge_faces[e2, 0] or edge_faces[e1, 0] == edge_faces[e2, 1]
            or edge_faces[e1, 1] == edge_faces[e2, 0] or edge_faces[e1, 1] == edge_faces[e2, 1])


@njit(cache=True)
def clip_ears(loop, length, edge_faces, vert, triangles, count, write):
    """Triangulate the loop by cutting ears whose new diagonal joins two crossings on no
    common face (the neighbouring cell, which sees that face, could draw the same diagonal).
    Returns the triangle count and the vertices left (3 when done)."""
    while length > 3:
        cut = -1
        for m in range(length):
            if not share_face(loop[(m + length - 1) % length], loop[(m + 1) % length],
                              edge_faces):
                cut = m
                break
        if cut < 0:
            return count, length
        if write:
            triangles[count, 0] = vert[loop[(cut + length - 1) % length]]
            triangles[count, 1] = vert[loop[cut]]
            triangles[count, 2] = vert[loop[(cut + 1) % length]]
        count += 1
        for m in range(cut, length - 1):
            loop[m] = loop[m + 1]
        length -= 1
    if write:
        triangles[count, 0] = vert[loop[0]]
        triangles[count, 1] = vert[loop[1]]
        triangles[count, 2] = vert[loop[2]]
    return count + 1, 3


@njit(cache=True)
def cap(loop, length, edge_faces, vert, triangles, count, extra, positions, normals, write):
    """One loop as a disc: cut ear by ear, or fanned from a centre vertex (numbered
    ``extra``) when no ear is left. Returns the next triangle and centre numbers."""
    count, length = clip_ears(loop, length, edge_faces, vert, triangles, count, write)
    if length == 3:
        return count, extra
    centre = extra
    for m in range(length):
        if write:
            triangles[count, 0] = centre
            triangles[count, 1] = vert[loop[m]]
            triangles[count, 2] = vert[loop[(m + 1) % length]]
        count += 1
    if write:
        for d in range(3):
            positions[centre, d] = 0.0
            normals[centre, d] = 0.0
            for m in range(length):
                positions[centre, d] += positions[vert[loop[m]], d] / length
                normals[centre, d] += normals[vert[loop[m]], d] / length
    return count, extra + 1


@njit(cache=True)
def split_sign(inside, joined, edges, face_corners):
    """With two loops the cell's boundary is two discs and a band between them: 1 when the
    discs are the inside corners' (they fall in two groups), 0 when the outside ones'."""
    group = np.arange(8)
    for e in range(12):
        a, b = edges[e, 0], edges[e, 1]
        if inside[a] == inside[b]:
            _union(group, a, b)
    for f in range(6):
        if joined[f] >= 0:                       # ambiguous: which diagonal is joined
            c0, c1 = face_corners[f, 0], face_corners[f, 1]
            c2, c3 = face_corners[f, 2], face_corners[f, 3]
            if (joined[f] == 1) == bool(inside[c0]):
                _union(group, c0, c2)
            else:
                _union(group, c1, c3)
    groups_in = 0
    for c in range(8):
        if inside[c] and _root(group, c) == c:
            groups_in += 1
    return 1 if groups_in == 2 else 0


@njit(cache=True)
def _root(group, c):
    while group[c] != c:
        c = group[c]
    return c


@njit(cache=True)
def _union(group, a, b):
    ra, rb = _root(group, a), _root(group, b)
    if ra != rb:
        group[max(ra, rb)] = min(ra, rb)


@njit(cache=True)
def tunnel(w, inside, joined, edges, face_corners):
    """Whether the two discs' side is joined through the cell's interior: whether the
    trilinear interpolant has a body saddle inside the cell on that side (Natarajan's test:
    ∇f = 0 is a quadratic in z, then x and y follow)."""
    a, b, c, d = w[0], w[1] - w[0], w[2] - w[0], w[4] - w[0]
    e = w[0] - w[1] - w[2] + w[3]
    f = w[0] - w[2] - w[4] + w[6]
    g = w[0] - w[1] - w[4] + w[5]
    h = -w[0] + w[1] + w[2] - w[3] + w[4] - w[5] - w[6] + w[7]
    qa, qb = h * (d * h - f * g), 2.0 * e * (d * h - f * g)
    qc = d * e * e - e * (f * b + g * c) + h * b * c
    roots = np.empty(2)
    found = 0
    if abs(qa) > 1e-12:
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            return False
        root = math.sqrt(disc)
        roots[0], roots[1] = (-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)
        found = 2
    elif abs(qb) > 1e-12:
        roots[0] = -qc / qb
        found = 1
    side = split_sign(inside, joined, edges, face_corners)
    for r in range(found):
        z = roots[r]
        den = e + h * z
        if not (0.0 < z < 1.0) or den == 0.0:
            continue
        x, y = -(c + f * z) / den, -(b + g * z) / den
        if not (0.0 < x < 1.0 and 0.0 < y < 1.0):
            continue
        value = a + b * x + c * y + d * z + e * x * y + f * y * z + g * x * z + h * x * y * z
        if (value > 0.0) == (side == 1):
            return True
    return False


@njit(cache=True)
def zip_tube(one, m, two, n, vert, positions, triangles, count, write):
    """The band between two loops: each loop's edges run as the discs ran them, so the zipper
    walks the first loop forward and the second backward, taking the shorter rung each step
    (m + n triangles). Returns the next triangle number."""
    start, best = 0, np.inf
    if write:
        for q in range(n):                     # the second loop's vertex nearest one[0]
            dist = 0.0
            for k in range(3):
                dist += (positions[vert[one[0]], k] - positions[vert[two[q]], k]) ** 2
            if dist < best:
                start, best = q, dist
    i, j, done_i, done_j = 0, start, 0, 0
    while done_i < m or done_j < n:
        a, a_next = vert[one[i % m]], vert[one[(i + 1) % m]]
        b, b_prev = vert[two[j % n]], vert[two[(j - 1) % n]]
        forward = done_j >= n
        if done_i < m and done_j < n and write:
            da = db = 0.0
            for k in range(3):
                da += (positions[a_next, k] - positions[b, k]) ** 2
                db += (positions[a, k] - positions[b_prev, k]) ** 2
            forward = da <= db
        elif done_i < m and done_j < n:
            forward = True
        if forward:
            if write:
                triangles[count, 0], triangles[count, 1], triangles[count, 2] = a, a_next, b
            i, done_i = i + 1, done_i + 1
        else:
            if write:
                triangles[count, 0], triangles[count, 1], triangles[count, 2] = b_prev, b, a
            j, done_j = j - 1, done_j + 1
        count += 1
    return count


@njit(cache=True, parallel=True, error_model="numpy")
def row_trims(v, iso, trims):
    """For each row of samples along k, ``trims[i, j]`` = (the first and the last k whose edge
    to k + 1 is crossed, or (n2, -1) where none is; whether the row's first and last samples
    are inside): flying edges' trim (Schroeder et al. 2015)."""
    n0, n1, n2 = v.shape
    for i in prange(n0):
        for j in range(n1):
            first, last = n2, -1
            before = v[i, j, 0] > iso
            for k in range(n2 - 1):
                after = v[i, j, k + 1] > iso
                if after != before:
                    first = min(first, k)
                    last = k
                before = after
            trims[i, j, 0], trims[i, j, 1] = first, last
            trims[i, j, 2], trims[i, j, 3] = v[i, j, 0] > iso, before


@njit(cache=True, error_model="numpy")
def cell_range(trims, i, j, n2):
    """The cells ``[k0, k1)`` of row (i, j) that can hold surface: outside it each of the four
    sample rows is constant, and all four agree (else the cells from that end are kept)."""
    k0, k1 = n2, 0
    for a in range(2):
        for b in range(2):
            k0, k1 = min(k0, trims[i + a, j + b, 0]), max(k1, trims[i + a, j + b, 1] + 1)
    for end in range(2):
        side = trims[i, j, 2 + end]
        for a in range(2):
            for b in range(2):
                if trims[i + a, j + b, 2 + end] != side:
                    if end == 0:
                        k0 = 0
                    else:
                        k1 = n2 - 1
    return k0, k1


@njit(cache=True, error_model="numpy")
def cell_slab(v, iso, i, ids_x, ids_y, ids_z, trims, tables, count, extra, triangles,
              positions, normals, write):
    """The cells of slab ``i``, their loops cut into triangles (step 3), numbered from
    ``count`` (triangles) and ``extra`` (loop-centre vertices, rows of ``positions``). Returns
    both next free numbers; with ``write``, fills ``triangles`` and the centres' rows."""
    corners, edges, face_corners, face_edges, edge_faces = tables
    n0, n1, n2 = v.shape
    w = np.empty(8)
    inside = np.empty(8, np.bool_)
    nxt = np.empty(12, np.int64)
    vert = np.empty(12, np.int64)
    loop = np.empty(12, np.int64)
    ring = np.empty((4, 12), np.int64)          # the cell's loops (at most four)
    sizes = np.empty(4, np.int64)
    joined = np.empty(6, np.int64)
    for j in range(n1 - 1):
        k0, k1 = cell_range(trims, i, j, n2)
        if k0 >= k1:
            continue
        # the cell's corners slide along k: the far four of one cell are the near four of
        # the next (corner c = x + 2y + 4z), so each cell loads four samples, not eight
        w[4], w[5] = v[i, j, k0] - iso, v[i + 1, j, k0] - iso
        w[6], w[7] = v[i, j + 1, k0] - iso, v[i + 1, j + 1, k0] - iso
        for k in range(k0, k1):
            w[0], w[1], w[2], w[3] = w[4], w[5], w[6], w[7]
            w[4], w[5] = v[i, j, k + 1] - iso, v[i + 1, j, k + 1] - iso
            w[6], w[7] = v[i, j + 1, k + 1] - iso, v[i + 1, j + 1, k + 1] - iso
            ins = 0
            for c in range(8):
                inside[c] = w[c] > 0.0
                ins += inside[c]
            if ins == 0 or ins == 8:
                continue
            nxt[:] = -1
            face_segments(w, inside, face_corners, face_edges, nxt, joined)
            for e in range(12):
                if nxt[e] < 0:
                    continue
                base = edges[e, 0]
                a, b, c = i + corners[base, 0], j + corners[base, 1], k + corners[base, 2]
                axis = e // 4
                vert[e] = ids_x[a, b, c] if axis == 0 else (
                    ids_y[a, b, c] if axis == 1 else ids_z[a, b, c])
            loops = 0
            for e in range(12):
                if nxt[e] < 0:
                    continue
                length, cur = 0, e
                while True:                # the loop through e, in order
                    ring[loops, length] = cur
                    length += 1
                    after = nxt[cur]
                    nxt[cur] = -1
                    cur = after
                    if cur == e:
                        break
                sizes[loops] = length
                loops += 1
            if loops == 2 and tunnel(w, inside, joined, edges, face_corners):
                count = zip_tube(ring[0], sizes[0], ring[1], sizes[1], vert, positions,
                                 triangles, count, write)
                continue
            for m in range(loops):
                loop[:sizes[m]] = ring[m, :sizes[m]]
                count, extra = cap(loop, sizes[m], edge_faces, vert, triangles, count, extra,
                                   positions, normals, write)
    return count, extra


@njit(cache=True, parallel=True)
def cell_triangles(v, iso, ids_x, ids_y, ids_z, trims, tables, tri_starts, extra_starts,
                   triangles, positions, normals, write):
    """Every slab of cells on all cores: without ``write``, ``tri_starts[i + 1]`` and
    ``extra_starts[i + 1]`` get slab i's counts; with it, slab i writes from ``tri_starts[i]``
    and ``extra_starts[i]``."""
    for i in prange(v.shape[0] - 1):
        t0 = tri_starts[i] if write else 0
        e0 = extra_starts[i] if write else 0
        t1, e1 = cell_slab(v, iso, i, ids_x, ids_y, ids_z, trims, tables, t0, e0, triangles,
                           positions, normals, write)
        if not write:
            tri_starts[i + 1], extra_starts[i + 1] = t1 - t0, e1 - e0


def marching_cubes(values: np.ndarray, iso: float, where: str = "volume"):
    """``(positions (V, 3), triangles (T, 3), normals (V, 3))`` of the surface ``value = iso``
    in index coordinates (sample (i, j, k) at point (i, j, k)); normals are the negated
    gradient (not unit length)."""
    v = np.ascontiguousarray(values, dtype=np.float32)
    iso = check_iso(iso, v, where)
    n0, n1, n2 = v.shape
    ids = [np.empty((n0 - 1, n1, n2), np.int64), np.empty((n0, n1 - 1, n2), np.int64),
           np.empty((n0, n1, n2 - 1), np.int64)]
    empty = np.empty((0, 3))
    starts = []
    for axis in range(3):                      # count each slab's crossings, then place them
        counts = np.zeros(ids[axis].shape[0] + 1, np.int64)
        edge_vertices(v, iso, axis, ids[axis], empty, empty, counts, False)
        starts.append(counts)
    offsets = np.cumsum([0] + [int(c.sum()) for c in starts])
    total = int(offsets[-1])
    if total > MAX_TRIANGLES:          # a surface has about two triangles a vertex
        raise VolumeError(f"{where}: the surface at iso {iso:g} crosses {total:,} cell edges, "
                          f"about {2 * total:,} triangles; at most {MAX_TRIANGLES:,} (a "
                          f"smoother volume or another iso)")
    positions, normals = np.empty((total, 3)), np.empty((total, 3))
    for axis in range(3):
        first = offsets[axis] + np.cumsum(starts[axis])
        edge_vertices(v, iso, axis, ids[axis], positions, normals, first, True)
    tables = (CORNERS, EDGES, FACES, FACE_EDGES, EDGE_FACES)
    trims = np.empty((n0, n1, 4), np.int64)
    row_trims(v, iso, trims)
    tri_counts, extra_counts = np.zeros(n0, np.int64), np.zeros(n0, np.int64)
    cell_triangles(v, iso, *ids, trims, tables, tri_counts, extra_counts,
                   np.empty((0, 3), np.int64), positions, normals, False)
    tri_starts, extra_starts = np.cumsum(tri_counts), total + np.cumsum(extra_counts)
    if int(tri_starts[-1]) > MAX_TRIANGLES:
        raise VolumeError(f"{where}: the surface at iso {iso:g} has {int(tri_starts[-1]):,} "
                          f"triangles; at most {MAX_TRIANGLES:,}")
    triangles = np.empty((int(tri_starts[-1]), 3), np.int64)
    extra = int(extra_starts[-1]) - total
    positions = np.concatenate([positions, np.empty((extra, 3))])
    normals = np.concatenate([normals, np.empty((extra, 3))])
    cell_triangles(v, iso, *ids, trims, tables, tri_starts, extra_starts, triangles,
                   positions, normals, True)
    return positions, triangles, normals


def isosurface(volume) -> Mesh:
    """The volume's surface at ``volume.iso`` as a mesh in world coordinates, lit by
    ``volume.material``; closed when the surface does not reach the grid's border."""
    if volume.iso is None:
        raise VolumeError(f"{volume.name}: isosurface needs an iso value")
    positions, triangles, gradient = marching_cubes(volume.values, volume.iso, volume.name)
    m = volume.world_from_index()
    world = positions @ m[:3, :3].T + m[:3, 3]
    normals = gradient @ np.linalg.inv(m[:3, :3])          # rows: n' = M^-T n
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    if np.linalg.det(m[:3, :3]) < 0:                        # a mirror turns winding over
        triangles = triangles[:, [0, 2, 1]]
    return Mesh(world, triangles, normals=normals, closed=not touches_border(volume),
                material=volume.material, name=volume.name)


def touches_border(volume) -> bool:
    """Whether the surface reaches the grid's outer faces (where it is cut open)."""
    v = volume.values
    inside = v > volume.iso
    return bool(inside[0].any() or inside[-1].any() or inside[:, 0].any()
                or inside[:, -1].any() or inside[:, :, 0].any() or inside[:, :, -1].any())
