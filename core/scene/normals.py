"""Face and vertex normals for shading (FvDFH 16.2.4; the notes: "approximate the normal at a
vertex by averaging all normals of abutting triangles").

Takes a mesh's world positions ``(V, 3)`` and triangles ``(T, 3)``; returns unit normals.

- :func:`face_normals`: ``(p1 − p0) × (p2 − p0)`` normalised (counter-clockwise = outward) and
  twice each face's area. A zero-area face has the zero normal and contributes nothing.
- :func:`vertex_normals_from_faces`: the average of the faces meeting at each vertex,
  ``weighting`` named:
    ``"mean"``  — the notes' rule: the unweighted average of the unit face normals;
    ``"area"``  — weighted by face area (the sum of the raw cross products);
    ``"angle"`` — weighted by the face's interior angle at the vertex (Thürmer and Wüthrich),
  independent of how a surface happens to be split into triangles.
  Degenerate case: where the weighted sum vanishes (faces whose normals cancel, e.g. a sheet
  folded flat onto itself at a vertex; ``|sum| <= 1e-9 · Σ weights``) the vertex takes the
  normal of its largest incident face instead, so it is never NaN. A vertex with no face of
  non-zero area gets the zero normal (the model then gives it ambient light only).
- :func:`orient_consistently`: flips triangles of an open soup (arbitrary winding, as in the
  ``.tri`` files) so that faces sharing an edge agree, one connected piece at a time; without
  it averaging a randomly wound soup cancels normals instead of smoothing them. The sign of a
  whole piece stays arbitrary: two-sided lighting (:mod:`core.shading.illumination`) turns it to the
  viewer.
- :func:`vertex_normals`: what Gouraud and Phong shading use for a :class:`core.scene.Mesh`:
  the file's normals when it has them (normalised; a zero one is replaced by the computed
  normal), else the faces' average, after :func:`orient_consistently` for meshes that are not
  closed. The GL oracle (``app/oracles/reference_gl.py``) calls it too, so both draw with the same
  normals.
"""

from __future__ import annotations

import numpy as np

from core.jit import njit
from core.scene.model import CREASE_ANGLE  # noqa: F401  (the default, and why: there)
from core.transforms import unit_rows

WEIGHTINGS = ("mean", "area", "angle")
# A vertex's weighted normal sum this small against the weights counts as cancelled.
CANCEL_TOLERANCE = 1e-9


def face_normals(positions: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(unit normals (T, 3), twice the areas (T,))``; zero-area faces get the zero normal."""
    p = np.asarray(positions, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    with np.errstate(under="ignore"):
        cross = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]).reshape(-1, 3)
        unit, double_area = unit_rows(cross)
    return unit, double_area


def _corner_angles(positions: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``(T, 3)``: the interior angle of each triangle at each of its corners."""
    angles = np.zeros(triangles.shape)
    with np.errstate(under="ignore"):
        for k in range(3):
            corner = positions[triangles[:, k]]
            a = positions[triangles[:, (k + 1) % 3]] - corner
            b = positions[triangles[:, (k + 2) % 3]] - corner
            # atan2(|a x b|, a.b) is accurate at every angle, unlike acos of a cosine.
            sin_part = np.linalg.norm(np.cross(a, b).reshape(-1, 3), axis=1)
            angles[:, k] = np.arctan2(sin_part, np.einsum("ij,ij->i", a, b))
    return angles


@njit(cache=True)
def _largest_incident_face(triangles, double_area, vertex_count):
    """For each vertex the incident face of largest area (-1 if it has none of area > 0)."""
    best = np.full(vertex_count, -1, dtype=np.int64)
    best_area = np.zeros(vertex_count)
    for f in range(triangles.shape[0]):
        for k in range(3):
            i = triangles[f, k]
            if double_area[f] > best_area[i]:
                best_area[i] = double_area[f]
                best[i] = f
    return best


def vertex_normals_from_faces(positions: np.ndarray, triangles: np.ndarray,
                              weighting: str = "mean") -> np.ndarray:
    """``(V, 3)`` unit vertex normals averaged from the faces (see the module docstring)."""
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {WEIGHTINGS}, not {weighting!r}")
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    v_count = len(p)
    unit, double_area = face_normals(p, t)
    if weighting == "area":
        weights = np.repeat(double_area[:, None], 3, axis=1)
    elif weighting == "angle":
        weights = _corner_angles(p, t)
    else:
        weights = np.repeat((double_area > 0.0).astype(np.float64)[:, None], 3, axis=1)
    sums = np.zeros((v_count, 3))
    total_weight = np.zeros(v_count)
    with np.errstate(under="ignore"):
        for k in range(3):
            for c in range(3):
                sums[:, c] += np.bincount(t[:, k], weights=unit[:, c] * weights[:, k],
                                          minlength=v_count)
            total_weight += np.bincount(t[:, k], weights=weights[:, k] * (double_area > 0.0),
                                        minlength=v_count)
        normals, length = unit_rows(sums)
    cancelled = (length <= CANCEL_TOLERANCE * total_weight) & (total_weight > 0.0)
    if np.any(cancelled):
        best = _largest_incident_face(t, double_area, v_count)
        normals[cancelled] = unit[best[cancelled]]
    return normals


@njit(cache=True)
def _orient_pieces(triangle_count, start, neighbour, same_direction):
    """Breadth-first over faces sharing an edge: ``flip[f]`` so that neighbours agree.

    ``same_direction[j]`` says face f and ``neighbour[j]`` run their shared edge the same
    way (inconsistent winding), so one of them must flip relative to the other.
    """
    flip = np.zeros(triangle_count, dtype=np.bool_)
    seen = np.zeros(triangle_count, dtype=np.bool_)
    queue = np.empty(triangle_count, dtype=np.int64)
    for seed in range(triangle_count):
        if seen[seed]:
            continue
        seen[seed] = True
        head, tail = 0, 1
        queue[0] = seed
        while head < tail:
            f = queue[head]
            head += 1
            for j in range(start[f], start[f + 1]):
                g = neighbour[j]
                if not seen[g]:
                    seen[g] = True
                    flip[g] = flip[f] != same_direction[j]
                    queue[tail] = g
                    tail += 1
    return flip


def _edge_order(low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The order of the edges (low, high) by low, then high, equal edges in their own order:
    ``np.lexsort((high, low))``, as one stable sort of one integer key (half the time: the
    bunny's 208k edges in 11 ms against 20)."""
    if len(low) == 0:
        return np.zeros(0, np.int64)
    span = int(high.max()) + 1
    if int(low.min()) < 0 or span > 1 << 31:     # the key would not be one-to-one, or overflow
        return np.lexsort((high, low))
    return np.argsort(low.astype(np.int64) * span + high, kind="stable")


def orient_consistently(triangles: np.ndarray) -> np.ndarray:
    """A copy of ``triangles`` in which faces sharing an edge wind it in opposite directions.

    Only manifold edges (exactly two faces) link faces; each connected piece keeps the
    winding of its lowest-numbered face. A non-orientable piece keeps the first choice met.
    """
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    count = len(t)
    if count == 0:
        return t.copy()
    a = t.reshape(-1)                                        # edge k of face f: (t[f,k], t[f,k+1])
    b = t[:, [1, 2, 0]].reshape(-1)
    face = np.repeat(np.arange(count), 3)
    low, high = np.minimum(a, b), np.maximum(a, b)
    forward = a < b
    order = _edge_order(low, high)
    low, high, forward, face = low[order], high[order], forward[order], face[order]
    same_as_next = (low[:-1] == low[1:]) & (high[:-1] == high[1:])
    # An edge shared by exactly two faces: a run of length 2 in the sorted edge list.
    run_start = np.ones(len(low), dtype=bool)
    run_start[1:] = ~same_as_next
    run_id = np.cumsum(run_start) - 1
    run_length = np.bincount(run_id)
    first = np.flatnonzero(run_start & (run_length[run_id] == 2))
    f0, f1 = face[first], face[first + 1]
    same = forward[first] == forward[first + 1]
    keep = f0 != f1                                          # a face using an edge twice
    f0, f1, same = f0[keep], f1[keep], same[keep]
    # Adjacency in compressed rows, both directions.
    src = np.concatenate([f0, f1])
    dst = np.concatenate([f1, f0])
    same2 = np.concatenate([same, same])
    by_src = np.argsort(src, kind="stable")
    start = np.zeros(count + 1, dtype=np.int64)
    start[1:] = np.cumsum(np.bincount(src, minlength=count))
    flip = _orient_pieces(count, start, dst[by_src], same2[by_src])
    out = t.copy()
    out[flip] = out[flip][:, [0, 2, 1]]
    return out


def vertex_normals(mesh, weighting: str = "mean") -> np.ndarray:
    """``(V, 3)``: the vertex normals Gouraud and Phong shading use for ``mesh``."""
    triangles = mesh.triangles if mesh.closed else orient_consistently(mesh.triangles)
    if mesh.normals is not None and len(mesh.normals) == len(mesh.positions):
        with np.errstate(under="ignore", over="ignore"):
            given, length = unit_rows(np.asarray(mesh.normals, dtype=np.float64))
        missing = ~(length > 0.0)
        if np.any(missing):
            given[missing] = vertex_normals_from_faces(mesh.positions, triangles, weighting)[missing]
        return given
    return vertex_normals_from_faces(mesh.positions, triangles, weighting)


# Two faces sharing an edge lie in one plane when their unit normals agree this closely
# (an angle under ~1.4e-6 rad): round-off in a planar quad's two normals is ~1e-13, while
# neighbouring faces of the finest curved mesh we allow differ by ~1e-3 rad.
COPLANAR_TOLERANCE = 1e-12


@njit(cache=True)
def _root(parent, f):
    """Union–find's root of ``f`` (shared by the planar polygons and the crease fans)."""
    while parent[f] != f:
        parent[f] = parent[parent[f]]               # path halving
        f = parent[f]
    return f


@njit(cache=True)
def _join_faces(face_count, first, second):
    """Union–find over the pairs ``(first[j], second[j])``: each face's polygon, the lowest
    face of its piece."""
    parent = np.arange(face_count)
    for j in range(first.shape[0]):
        a, b = _root(parent, first[j]), _root(parent, second[j])
        if a < b:
            parent[b] = a
        elif b < a:
            parent[a] = b
    for f in range(face_count):
        parent[f] = _root(parent, f)
    return parent


def _same_points(p: np.ndarray) -> tuple[np.ndarray, int]:
    """``(index (V,), count)``: equal rows of ``p`` get one index (-0.0 equals 0.0)."""
    if len(p) == 0:
        return np.zeros(0, dtype=np.int64), 0
    order = np.lexsort((p[:, 2], p[:, 1], p[:, 0]))
    q = p[order]
    new = np.ones(len(p), dtype=bool)
    new[1:] = np.any(q[1:] != q[:-1], axis=1)
    index = np.empty(len(p), dtype=np.int64)
    index[order] = np.cumsum(new) - 1
    return index, int(new.sum())


def planar_polygons(positions: np.ndarray, triangles: np.ndarray,
                    normals: np.ndarray) -> np.ndarray:
    """``(T,)``: the polygon of each face — faces that share an edge (by position, so split
    vertices still join) and lie in one plane facing the same way are one polygon, named by
    its lowest face. The two triangles of a planar quad are one polygon; a curved mesh's faces
    stay one each. ``normals`` are the faces' unit normals; zero-area faces stay alone."""
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    count = len(t)
    if count == 0:
        return np.zeros(0, dtype=np.int64)
    where, distinct = _same_points(np.asarray(positions, dtype=np.float64))
    t = where[t]
    a, b = t.reshape(-1), t[:, [1, 2, 0]].reshape(-1)
    edge = np.minimum(a, b) * distinct + np.maximum(a, b)     # one integer per undirected edge
    order = np.argsort(edge, kind="stable")
    edge, face = edge[order], order // 3
    shared = np.flatnonzero(edge[:-1] == edge[1:])
    first, second = face[shared], face[shared + 1]          # neighbours along a run of faces
    n = np.asarray(normals, dtype=np.float64)
    same_plane = np.einsum("ij,ij->i", n[first], n[second]) > 1.0 - COPLANAR_TOLERANCE
    return _join_faces(count, first[same_plane], second[same_plane])


# ----------------------------------------------------------------------------- creases


@njit(cache=True)
def _smooth_groups(triangles, vertex_count, corner_a, corner_b, degenerate):
    """``(T, 3)`` new vertex index of each face corner: corners joined across smooth edges
    (``corner_a[j]`` with ``corner_b[j]``) share a vertex. Each vertex's first group keeps its
    index, the others are numbered from ``vertex_count`` up; a zero-area face's corners stay
    on the original vertex. Returns ``(corner_vertex, origin)``, ``origin[k]`` the original
    vertex of new vertex k."""
    n = triangles.shape[0] * 3
    parent = np.arange(n)
    for j in range(corner_a.shape[0]):
        ra, rb = _root(parent, corner_a[j]), _root(parent, corner_b[j])
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    root_vertex = np.full(n, -1, dtype=np.int64)      # the new vertex of each group's root
    primary = np.full(vertex_count, -1, dtype=np.int64)  # each vertex's first group root
    corner_vertex = np.empty(n, dtype=np.int64)
    origin = np.empty(vertex_count + n, dtype=np.int64)
    for v in range(vertex_count):       # not a slice assignment: see core.visibility.split.grow
        origin[v] = v
    next_vertex = vertex_count
    for c in range(n):
        v = triangles[c // 3, c % 3]
        if degenerate[c // 3]:
            corner_vertex[c] = v
            continue
        r = _root(parent, c)
        if root_vertex[r] < 0:
            if primary[v] < 0:
                primary[v] = r
                root_vertex[r] = v
            else:
                root_vertex[r] = next_vertex
                origin[next_vertex] = v
                next_vertex += 1
        corner_vertex[c] = root_vertex[r]
    return corner_vertex.reshape(-1, 3), origin[:next_vertex]


def crease_split(positions: np.ndarray, triangles: np.ndarray, angle: float = CREASE_ANGLE,
                 closed: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Split the vertices along creases: ``(triangles', origin)``.

    Two faces sharing an edge are smooth there when their normals differ by at most
    ``angle`` degrees; a vertex whose faces fall into several smooth fans becomes one vertex
    per fan (``origin[k]`` is the vertex that new vertex ``k`` copies; the first ``V`` are the
    old ones, unchanged). Averaging the faces at each vertex of the result
    (:func:`vertex_normals_from_faces`) is then the notes' average within a smooth region,
    and a face meeting its neighbours at a crease keeps its own normal there. An open soup
    (``closed=False``) is oriented first for the comparison only; its winding is kept.
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    origin = np.arange(len(p))
    if len(t) == 0:
        return t.copy(), origin
    oriented = t if closed else orient_consistently(t)
    unit, double_area = face_normals(p, oriented)
    # Every edge k of face f as a sorted vertex pair; faces sharing it follow each other.
    a, b = t.reshape(-1), t[:, [1, 2, 0]].reshape(-1)
    corner_a = np.arange(3 * len(t))                          # corner of a in face f
    corner_b = (corner_a // 3) * 3 + (corner_a % 3 + 1) % 3   # corner of b in face f
    low, high = np.minimum(a, b), np.maximum(a, b)
    order = _edge_order(low, high)
    same = (low[order][:-1] == low[order][1:]) & (high[order][:-1] == high[order][1:])
    e, g = order[:-1][same], order[1:][same]                  # edge e of one face, g of another
    f0, f1 = e // 3, g // 3
    cos_limit = np.cos(np.radians(angle))
    smooth = (np.einsum("ij,ij->i", unit[f0], unit[f1]) >= cos_limit - 1e-12) & (f0 != f1)
    e, g = e[smooth], g[smooth]
    # Join the corners at each shared vertex (a with a, b with b, whichever way they run).
    va_e, va_g = a[e], a[g]
    join_a = np.concatenate([corner_a[e], corner_b[e]])
    join_b = np.concatenate([np.where(va_g == va_e, corner_a[g], corner_b[g]),
                             np.where(va_g == va_e, corner_b[g], corner_a[g])])
    split, origin = _smooth_groups(t, len(p), join_a, join_b, ~(double_area > 0.0))
    return split, origin


def with_creases(mesh, angle: float = CREASE_ANGLE):
    """``mesh`` with its vertices split along creases (:func:`crease_split`), every
    per-vertex array copied to the new vertices. A mesh with normals of its own, or with no
    crease, is returned as it is."""
    if mesh.normals is not None or len(mesh.triangles) == 0:
        return mesh
    triangles, origin = crease_split(mesh.positions, mesh.triangles, angle, mesh.closed)
    if len(origin) == len(mesh.positions):
        return mesh
    mesh.positions = mesh.positions[origin]
    mesh.triangles = np.ascontiguousarray(triangles)
    if mesh.uv is not None:
        mesh.uv = mesh.uv[origin]
    mesh.extra = {name: values[origin] for name, values in mesh.extra.items()}
    return mesh
