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
from functools import lru_cache

import numpy as np

from core.jit import call_compiled, compiled_at, njit, prange
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
TABLES = (CORNERS, EDGES, FACES, FACE_EDGES, EDGE_FACES)
# EDGE_MASK[case]: bit e set when the case's corners differ across edge e.
EDGE_MASK = np.array([sum(1 << e for e, (a, b) in enumerate(EDGES)
                          if (case >> a & 1) != (case >> b & 1)) for case in range(256)],
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
def place(v, i, j, k, i2, j2, k2, p, q, positions, normals, at):
    """Row ``at``: where the edge from sample (i, j, k) (offset ``p`` from iso) to sample
    (i2, j2, k2) (offset ``q``) crosses iso, with the gradient interpolated the same way."""
    t = p / (p - q)
    positions[at, 0] = i + t * (i2 - i)
    positions[at, 1] = j + t * (j2 - j)
    positions[at, 2] = k + t * (k2 - k)
    ax, ay, az = gradient_at(v, i, j, k)
    bx, by, bz = gradient_at(v, i2, j2, k2)
    normals[at, 0] = -(ax + t * (bx - ax))
    normals[at, 1] = -(ay + t * (by - ay))
    normals[at, 2] = -(az + t * (bz - az))


@njit(cache=True, error_model="numpy")
def place_edge(v, i, j, k, e, w, edges, positions, normals, at):
    """Row ``at``: the crossing on edge ``e`` of cell (i, j, k), whose corner offsets are
    ``w``."""
    a, b = edges[e, 0], edges[e, 1]
    place(v, i + (a & 1), j + (a >> 1 & 1), k + (a >> 2), i + (b & 1), j + (b >> 1 & 1),
          k + (b >> 2), w[a], w[b], positions, normals, at)


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
def cap(loop, length, edge_faces, vert, triangles, count, extra, spots, slopes, positions,
        normals, write):
    """One loop as a disc: cut ear by ear, or fanned from a centre vertex (numbered
    ``extra``, at the mean of the loop's ``spots`` and ``slopes``, the cell's crossings by
    edge) when no ear is left. Returns the next triangle and centre numbers."""
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
                positions[centre, d] += spots[loop[m], d] / length
                normals[centre, d] += slopes[loop[m], d] / length
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
def zip_tube(one, m, two, n, vert, spots, triangles, count, write):
    """The band between two loops: each loop's edges run as the discs ran them, so the zipper
    walks the first loop forward and the second backward, taking the shorter rung each step
    (m + n triangles; ``spots``: the cell's crossings by edge). Returns the next triangle
    number."""
    start, best = 0, np.inf
    if write:
        for q in range(n):                     # the second loop's vertex nearest one[0]
            dist = 0.0
            for k in range(3):
                dist += (spots[one[0], k] - spots[two[q], k]) ** 2
            if dist < best:
                start, best = q, dist
    i, j, done_i, done_j = 0, start, 0, 0
    while done_i < m or done_j < n:
        ea, ea_next = one[i % m], one[(i + 1) % m]
        eb, eb_prev = two[j % n], two[(j - 1) % n]
        a, a_next, b, b_prev = vert[ea], vert[ea_next], vert[eb], vert[eb_prev]
        forward = done_j >= n
        if done_i < m and done_j < n and write:
            da = db = 0.0
            for k in range(3):
                da += (spots[ea_next, k] - spots[eb, k]) ** 2
                db += (spots[ea, k] - spots[eb_prev, k]) ** 2
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
def row_trims(v, iso, trims, counts):
    """For each row of samples along k, ``trims[i, j]`` = (the first and the last k whose edge
    to k + 1 is crossed, or (n2, -1) where none is; whether the row's first and last samples
    are inside): flying edges' trim (Schroeder et al. 2015); ``counts[i, j, 2]`` = how many of
    the row's edges are crossed."""
    n0, n1, n2 = v.shape
    for i in prange(n0):
        for j in range(n1):
            first, last, found = n2, -1, 0
            before = v[i, j, 0] > iso
            for k in range(n2 - 1):
                after = v[i, j, k + 1] > iso
                if after != before:
                    first = min(first, k)
                    last = k
                    found += 1
                before = after
            trims[i, j, 0], trims[i, j, 1] = first, last
            trims[i, j, 2], trims[i, j, 3] = v[i, j, 0] > iso, before
            counts[i, j, 2] = found


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


@njit(cache=True)
def cell_loops(nxt, ring, sizes):
    """The segments chained into the cell's closed loops (step 3): ``ring[m, :sizes[m]]`` is
    loop m's edges in order, the first loop starting at the lowest crossed edge. Returns the
    number of loops."""
    loops = 0
    for e in range(12):
        if nxt[e] < 0:
            continue
        length, cur = 0, e
        while True:
            ring[loops, length] = cur
            length += 1
            after = nxt[cur]
            nxt[cur] = -1
            cur = after
            if cur == e:
                break
        sizes[loops] = length
        loops += 1
    return loops


@njit(cache=True)
def cell_scratch():
    """The arrays one cell's polygon work reuses: corner offsets, sides, segments, vertex
    numbers, a loop, the loops and their sizes, the ambiguous faces' choices, and the
    crossings' positions and gradients by edge."""
    return (np.empty(8), np.empty(8, np.bool_), np.empty(12, np.int64), np.empty(12, np.int64),
            np.empty(12, np.int64), np.empty((4, 12), np.int64), np.empty(4, np.int64),
            np.empty(6, np.int64), np.empty((12, 3)), np.empty((12, 3)))


def case_table(tables):
    """Every sign pattern (corner c inside is bit c) whose polygons the values cannot change —
    no ambiguous face, no possible tunnel, no loop that needs a centre — cut into triangles by
    the cell's own steps (run here in Python, once): ``counts[case]`` triangles of cell edges
    ``edges[case]``; -1 where the cell must be worked out from its values. The edge numbers
    stand for the vertices."""
    corners, edges, face_corners, face_edges, edge_faces = tables
    counts = np.full(256, -1, np.int64)
    table = np.zeros((256, 12, 3), np.int64)
    nxt, joined = np.empty(12, np.int64), np.empty(6, np.int64)
    ring, sizes = np.empty((4, 12), np.int64), np.empty(4, np.int64)
    vert = np.arange(12)
    for case in range(1, 255):
        inside = np.array([(case >> c) & 1 == 1 for c in range(8)])
        w = np.where(inside, 1.0, -1.0)
        nxt[:] = -1
        face_segments.py_func(w, inside, face_corners, face_edges, nxt, joined)
        loops = cell_loops.py_func(nxt, ring, sizes)
        if loops == 2 or joined.max() >= 0:
            continue
        count, plain = 0, True
        for m in range(loops):
            loop = ring[m].copy()
            count, left = clip_ears.py_func(loop, int(sizes[m]), edge_faces, vert, table[case],
                                            count, True)
            plain = plain and left == 3
        if plain:
            counts[case] = count
    return counts, table


@njit(cache=True, error_model="numpy")
def sides(v, iso, i, j, k):
    """Bits 0-3: whether samples (i, j, k), (i + 1, j, k), (i, j + 1, k), (i + 1, j + 1, k)
    are inside."""
    bits = 0
    if v[i, j, k] > iso:
        bits |= 1
    if v[i + 1, j, k] > iso:
        bits |= 2
    if v[i, j + 1, k] > iso:
        bits |= 4
    if v[i + 1, j + 1, k] > iso:
        bits |= 8
    return bits


@njit(cache=True, error_model="numpy")
def corner_values(v, iso, i, j, k, w, inside):
    """Cell (i, j, k)'s corner offsets from iso (corner c at (c & 1, c >> 1 & 1, c >> 2))."""
    for c in range(8):
        w[c] = v[i + (c & 1), j + (c >> 1 & 1), k + (c >> 2)] - iso
        inside[c] = w[c] > 0.0


@njit(cache=True, error_model="numpy")
def odd_cell(v, i, j, k, mask, tables, count, extra, triangles, positions, normals, scratch,
             write):
    """A cell the case table leaves to its values (an ambiguous face, two loops, a centre):
    its loops from the faces, zipped into a tube or capped. Returns the next triangle and
    centre numbers."""
    corners, edges, face_corners, face_edges, edge_faces = tables
    w, inside, nxt, vert, loop, ring, sizes, joined, spots, slopes = scratch
    nxt[:] = -1
    face_segments(w, inside, face_corners, face_edges, nxt, joined)
    loops = cell_loops(nxt, ring, sizes)
    if write:                 # the crossings here, as their owners place them
        for e in range(12):
            if mask >> e & 1:
                place_edge(v, i, j, k, e, w, edges, spots, slopes, e)
    if loops == 2 and tunnel(w, inside, joined, edges, face_corners):
        return zip_tube(ring[0], sizes[0], ring[1], sizes[1], vert, spots, triangles, count,
                        write), extra
    for m in range(loops):
        for q in range(sizes[m]):      # not a slice assignment: see core.visibility.split.grow
            loop[q] = ring[m, q]
        count, extra = cap(loop, sizes[m], edge_faces, vert, triangles, count, extra, spots,
                           slopes, positions, normals, write)
    return count, extra


@njit(cache=True, error_model="numpy")
def cell_row(v, iso, i, j, trims, counts, cases, tables, count, extra, triangles, positions,
             normals, scratch, write):
    """The cells of row (i, j): without ``write``, count their triangles and loop centres and
    the row's crossings along x and y into ``counts`` (the cells see every one); with it,
    ``counts`` holds each row's first vertex per axis, and the cells write their triangles
    from ``count``, their centres from ``extra``, and place the crossings they own (on the
    rows at x = i and y = j, and on the grid's last rows). Returns the next two numbers.

    A crossed edge's vertex is its row's first plus the crossings before it on that row, so
    eight counters walking k with the cells number every vertex of the four rows."""
    table_counts, table = cases
    edges = tables[1]
    w, inside, vert = scratch[0], scratch[1], scratch[3]
    n0, n1, n2 = v.shape
    k0, k1 = cell_range(trims, i, j, n2)
    if k0 >= k1:
        return count, extra
    # below k0 the four rows are constant and agree, so no counter has anything to count
    ox0, ox1 = counts[i, j, 0], counts[i, j + 1, 0]            # along x, at y = j, j + 1
    oy0, oy1 = counts[i, j, 1], counts[i + 1, j, 1]            # along y, at x = i, i + 1
    oz0, oz1 = counts[i, j, 2], counts[i + 1, j, 2]            # along z, the four rows
    oz2, oz3 = counts[i, j + 1, 2], counts[i + 1, j + 1, 2]
    cx0 = cx1 = cy0 = cy1 = cz0 = cz1 = cz2 = cz3 = far = 0
    own = 0b000100010001 | (0b010000000010 if j == n1 - 2 else 0) \
        | (0b001000100000 if i == n0 - 2 else 0) | (1 << 11 if i == n0 - 2 and j == n1 - 2 else 0)
    own_far = 0b000001000100 | (0b1000 if j == n1 - 2 else 0) | (0b10000000 if i == n0 - 2 else 0)
    high = sides(v, iso, i, j, k0)
    for k in range(k0, k1):
        low, high = high, sides(v, iso, i, j, k + 1)
        case = low | high << 4
        if case == 0 or case == 255:
            continue
        mask = EDGE_MASK[case]
        if k == k1 - 1:
            far = mask
        if write:
            vert[0], vert[2] = ox0 + cx0, ox0 + cx0 + (mask & 1)
            vert[1], vert[3] = ox1 + cx1, ox1 + cx1 + (mask >> 1 & 1)
            vert[4], vert[6] = oy0 + cy0, oy0 + cy0 + (mask >> 4 & 1)
            vert[5], vert[7] = oy1 + cy1, oy1 + cy1 + (mask >> 5 & 1)
            vert[8], vert[9], vert[10], vert[11] = oz0 + cz0, oz1 + cz1, oz2 + cz2, oz3 + cz3
            corner_values(v, iso, i, j, k, w, inside)
            placing = mask & (own | (own_far if k == k1 - 1 else 0))
            for e in range(12):
                if placing >> e & 1:
                    place_edge(v, i, j, k, e, w, edges, positions, normals, vert[e])
        cx0, cx1, cy0, cy1 = cx0 + (mask & 1), cx1 + (mask >> 1 & 1), \
            cy0 + (mask >> 4 & 1), cy1 + (mask >> 5 & 1)
        cz0, cz1 = cz0 + (mask >> 8 & 1), cz1 + (mask >> 9 & 1)
        cz2, cz3 = cz2 + (mask >> 10 & 1), cz3 + (mask >> 11 & 1)
        if table_counts[case] >= 0:             # the values cannot change this cell's polygons
            if write:
                for t in range(table_counts[case]):
                    for d in range(3):
                        triangles[count + t, d] = vert[table[case, t, d]]
            count += table_counts[case]
            continue
        if not write:
            corner_values(v, iso, i, j, k, w, inside)
        count, extra = odd_cell(v, i, j, k, mask, tables, count, extra, triangles, positions,
                                normals, scratch, write)
    if not write:                    # the rows' crossings along x and y, the last edge too
        counts[i, j, 0], counts[i, j, 1] = cx0 + (far >> 2 & 1), cy0 + (far >> 6 & 1)
        if j == n1 - 2:
            counts[i, j + 1, 0] = cx1 + (far >> 3 & 1)
        if i == n0 - 2:
            counts[i + 1, j, 1] = cy1 + (far >> 7 & 1)
    return count, extra


@njit(cache=True, error_model="numpy")
def cell_slabs(v, iso, trims, counts, cases, tables, tri, extra, triangles, positions, normals,
               write, first, end):
    """The rows of cells of slabs ``first`` to ``end`` (the first index). Without ``write``:
    each row's triangles and loop centres into ``tri[i, j]`` and ``extra[i, j]``, and each
    row's crossings along x and y into ``counts[i, j, 0 | 1]``. With it (``counts``: each
    row's first vertex per axis; ``tri``, ``extra``: each row of cells' first triangle and
    centre): the vertices and triangles."""
    n1 = v.shape[1]
    scratch = cell_scratch()
    for i in range(first, end):
        for j in range(n1 - 1):
            t0 = tri[i, j] if write else 0
            e0 = extra[i, j] if write else 0
            t1, e1 = cell_row(v, iso, i, j, trims, counts, cases, tables, t0, e0, triangles,
                              positions, normals, scratch, write)
            if not write:
                tri[i, j], extra[i, j] = t1, e1


@njit(cache=True, parallel=True, error_model="numpy")
def _cell_slabs_parallel(v, iso, trims, counts, cases, tables, tri, extra, triangles,
                         positions, normals, write, at):
    """:func:`cell_slabs` slab by slab on all cores, called by its address ``at``
    (core.jit.call_compiled): the cell's code is optimised once, in ``cell_slabs``, not
    again inside this loop."""
    for i in prange(v.shape[0] - 1):
        first = np.int64(i)
        call_compiled(at, cell_slabs, v, iso, trims, counts, cases, tables, tri, extra,
                      triangles, positions, normals, write, first, first + 1)


def cell_rows(*given) -> None:
    """:func:`cell_slabs` for every slab of cells, on all cores (its arguments but the
    slabs)."""
    _cell_slabs_parallel(*given, compiled_at(cell_slabs, given + (0, 0)))


def _exclusive(counts: np.ndarray, base: int = 0) -> np.ndarray:
    """Each entry's start when the entries are laid out in order from ``base``."""
    flat = counts.ravel()
    return (base + np.cumsum(flat) - flat).reshape(counts.shape)


@lru_cache(maxsize=1)
def _cases():
    return case_table(TABLES)


def marching_cubes(values: np.ndarray, iso: float, where: str = "volume"):
    """``(positions (V, 3), triangles (T, 3), normals (V, 3))`` of the surface ``value = iso``
    in index coordinates (sample (i, j, k) at point (i, j, k)); normals are the negated
    gradient (not unit length).

    Three passes over rows of samples along k, as flying edges runs them (Schroeder et al.
    2015): trim each row to where it changes side; count each row of cells' triangles and
    the crossings it sees; lay the counts out and write the vertices and triangles."""
    v = np.ascontiguousarray(values, dtype=np.float32)
    iso = check_iso(iso, v, where)
    n0, n1, n2 = v.shape
    if min(n0, n1, n2) < 2:                    # no cell
        return np.empty((0, 3)), np.empty((0, 3), np.int64), np.empty((0, 3))
    trims, counts = np.empty((n0, n1, 4), np.int64), np.zeros((n0, n1, 3), np.int64)
    tri_counts = np.zeros((n0 - 1, n1 - 1), np.int64)
    extra_counts = np.zeros((n0 - 1, n1 - 1), np.int64)
    cases = _cases()
    no_int, no_float = np.empty((0, 3), np.int64), np.empty((0, 3))
    row_trims(v, iso, trims, counts)
    cell_rows(v, iso, trims, counts, cases, TABLES, tri_counts, extra_counts, no_int,
              no_float, no_float, False)
    total, count = int(counts.sum()), int(tri_counts.sum())
    if total > MAX_TRIANGLES:          # a surface has about two triangles a vertex
        raise VolumeError(f"{where}: the surface at iso {iso:g} crosses {total:,} cell edges, "
                          f"about {2 * total:,} triangles; at most {MAX_TRIANGLES:,} (a "
                          f"smoother volume or another iso)")
    if count > MAX_TRIANGLES:
        raise VolumeError(f"{where}: the surface at iso {iso:g} has {count:,} triangles; at "
                          f"most {MAX_TRIANGLES:,}")
    vertices = total + int(extra_counts.sum())
    positions, normals = np.empty((vertices, 3)), np.empty((vertices, 3))
    triangles = np.empty((count, 3), np.int64)
    cell_rows(v, iso, trims, _exclusive(counts), cases, TABLES, _exclusive(tri_counts),
              _exclusive(extra_counts, total), triangles, positions, normals, True)
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
