"""Welding and topology of triangle meshes, shared by the mesh readers, the ``.tri`` reader and
the scene file: equal vertices merged into one (:func:`merge_vertices`, hashing by sorting, as
the course's ``.tri`` reader merges them), exact repeats of a triangle dropped
(:func:`drop_repeated_triangles`), k-gons fanned into triangles (:func:`fan`), and whether a
surface is closed: every edge shared by exactly two triangles of opposite orientation
(:func:`edge_problem`) and a positive enclosed volume, CCW seen from outside
(:func:`signed_volume`, :func:`is_closed`), so that back faces may be culled (FvDFH 15.2.4).

Plain functions over numpy arrays; nothing here raises. :func:`edge_problem` says in words why
a surface is not closed ("the mesh has no triangles", "a triangle repeats a vertex", "edge (a,
b) is used twice in the same direction (inconsistent winding)", "edge (a, b) has no neighbour
across it (the surface has a border)"); the scene file quotes it.
"""

from __future__ import annotations

import numpy as np


def merge_vertices(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal rows of ``points`` ``(N, k)`` (positions, or positions with more columns such as
    (u, v)) become one vertex, numbered in order of first appearance.

    Returns ``(positions, inverse)`` with ``positions[inverse] == points``. ``-0.0`` and
    ``0.0`` are equal, as they are for the C ``==`` of the startup code.
    """
    points = np.asarray(points, dtype=np.float64)
    points = (points.reshape(-1, 3) if points.ndim != 2 else points) + 0.0    # -0.0 -> 0.0
    first, inverse = _first_of_equal_rows(points)
    return points[first], inverse


def _first_of_equal_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(first, inverse)``: the index of the first of each set of equal rows, in order of
    appearance, and for every row the number of its set (``rows[first][inverse] == rows``).

    Hashing by sorting, O(N log N) whatever the data (never the startup code's O(N^2) scan):
    a stable sort by the columns (``np.lexsort``; ``np.unique(axis=0)`` sorts rows as opaque
    records, 9 s for a million copies of one triangle), then a new set wherever a row differs
    from the one before it.
    """
    n = len(rows)
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    order = np.lexsort(rows.T[::-1])                    # stable: equal rows keep file order
    ordered = rows[order]
    starts = np.ones(n, dtype=bool)
    starts[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    group = np.cumsum(starts) - 1                       # set number, in sorted order
    first = order[starts]                               # stable: the first of each set
    by_appearance = np.argsort(first, kind="stable")
    rank = np.empty_like(by_appearance)
    rank[by_appearance] = np.arange(len(first))
    inverse = np.empty(n, dtype=np.int64)
    inverse[order] = rank[group]
    return first[by_appearance], inverse


def drop_repeated_triangles(triangles: np.ndarray) -> np.ndarray:
    """The triangles without exact repeats (the same three vertices in the same cyclic order),
    the first of each kept, in file order.

    A repeat draws nothing: it covers the pixels of its first copy at the same depth, and the
    z-buffer keeps the first (FvDFH's strict depth test). But it costs the raster its area
    again, so a file of a million copies of one large triangle would cost a million times its
    pixels; without repeats a frame costs at most its distinct triangles plus the pixels. The
    opposite winding (b, a, c) is not a repeat: it is the other face of the triangle.
    """
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) < 2:
        return t
    lowest = np.argmin(t, axis=1)                       # rotate the smallest index first
    turn = (lowest[:, None] + np.arange(3)) % 3
    canonical = np.take_along_axis(t, turn, axis=1)
    first, _ = _first_of_equal_rows(canonical)
    return t if len(first) == len(t) else t[first]


def fan(polygons: np.ndarray) -> np.ndarray:
    """``(F, k)`` polygons as ``(F (k - 2), 3)`` triangles fanned from each first corner."""
    k = polygons.shape[1]
    if k == 3:
        return polygons
    corners = np.arange(1, k - 1)
    return np.stack([np.repeat(polygons[:, :1], k - 2, axis=1), polygons[:, corners],
                     polygons[:, corners + 1]], axis=-1).reshape(-1, 3)


def edge_problem(triangles: np.ndarray) -> str | None:
    """Why the triangles are not a closed, consistently wound surface; None when they are.

    Closed and consistent means every directed edge (a, b) occurs exactly once and its
    opposite (b, a) occurs exactly once too (two neighbours, opposite orientation).
    """
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return "the mesh has no triangles"
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    if np.any(directed[:, 0] == directed[:, 1]):
        return "a triangle repeats a vertex"
    # One int64 key per directed edge (a, b): sorting keys is the hash here.
    base = int(t.max()) + 1
    keys, counts = np.unique(directed[:, 0] * base + directed[:, 1], return_counts=True)
    if np.any(counts > 1):
        key = int(keys[np.argmax(counts > 1)])
        return (f"edge ({key // base}, {key % base}) is used twice in the same direction "
                f"(inconsistent winding)")
    reverse = (keys % base) * base + keys // base
    found = np.isin(reverse, keys, assume_unique=True)
    if not np.all(found):
        key = int(keys[np.argmin(found)])
        return f"edge ({key // base}, {key % base}) has no neighbour across it (the surface has a border)"
    return None


def signed_volume(positions: np.ndarray, triangles: np.ndarray) -> float:
    """Volume enclosed by the triangles, positive when they are wound CCW seen from outside."""
    p = np.asarray(positions, dtype=np.float64)[np.asarray(triangles, dtype=np.int64)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def is_closed(positions: np.ndarray, triangles: np.ndarray) -> bool:
    """Closed, consistently wound and outward facing (positive signed volume)."""
    return edge_problem(triangles) is None and signed_volume(positions, triangles) > 0.0


def inverse_of(positions, merged, inverse, triangles):
    """``triangles`` over ``positions`` re-indexed onto ``merged`` (one vertex per position)."""
    if len(positions) == len(inverse):
        return inverse[triangles]
    _, where = merge_vertices(np.concatenate([merged, positions]))
    return where[len(merged):][triangles]
