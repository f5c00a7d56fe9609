"""The binary space-partitioning tree (Fuchs, Kedem and Naylor 1980; FvDFH 15.5.2; the notes'
lecture of February 26, "Binary Spanning Partition").

The work is done once, before display, in world space: well suited to a viewpoint that moves
over static objects. :func:`build` picks a triangle as the root, takes its plane, and sorts
every other triangle into the half-space in front of it (along its normal), the one behind
it, or the node itself (coplanar); a triangle spanning the plane is split, its pieces going
to both sides. Each half-space is partitioned again the same way until every node holds one
plane's triangles. :func:`back_to_front` walks the tree from the eye: at each node, the
subtree on the far side of the plane first, then the node's triangles, then the near side
("draw the back half-space first": a triangle is scan-converted correctly if everything on
the other side of it from the eye was drawn before it and everything on its own side after).

The root choice is the ``rule``: ``first`` (the first triangle of the node's list, the
notes' example), ``random`` (seeded), or ``fewest-splits`` (the notes: "select the one with
the fewest branches"): a few candidates spread over the list, each scored by how many of a
sample of the node's triangles it would split, weighed against how unevenly it divides them
(0.8 splits + 0.2 imbalance, as Ericson recommends: a root that splits nothing but leaves
everything on one side makes the tree a chain; Fuchs et al. tried five candidates, and scoring
against all triangles would make the build quadratic per node).

A split vertex is ``P_a + t (P_b - P_a)`` with ``(a, b, t)`` in :attr:`BSPTree.recipe`:
every per-vertex attribute interpolates with the same ``t`` (linear in world space, so a
split triangle shades exactly like the original).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from core.jit import njit
from core.settings import BSP_ROOTS as ROOT_RULES      # first, random, fewest-splits
from core.visibility.split import cut_triangle, grow, side

CANDIDATES = 8          # fewest-splits: triangles tried as the root of a node
SAMPLE = 128            # fewest-splits: triangles of the node each candidate is scored on
CHUNK = 64              # fragments per bounding sphere when classifying a node's list
SPLIT_WEIGHT = 0.8      # fewest-splits: the weight of splits against imbalance in the score
EPSILON = 1e-9          # on-the-plane tolerance, relative to the scene's size


@dataclass
class BSPTree:
    """A BSP tree over triangles in world space.

    ``points`` (V', 3): the input vertices, then one per split (``recipe`` (V' - V, 3): its
    ``a, b, t``). ``fragments`` (F, 3) vertex ids, ``source`` (F,) the input triangle each
    came from. Node ``i`` has the plane ``plane[i]`` (unit normal, constant: ``n·P = d``),
    children ``front[i]``, ``back[i]`` (-1: none) and the fragments
    ``node_fragments[first[i]:first[i] + count[i]]`` lying in its plane.
    """

    points: np.ndarray
    recipe: np.ndarray
    fragments: np.ndarray
    source: np.ndarray
    plane: np.ndarray
    front: np.ndarray
    back: np.ndarray
    first: np.ndarray
    count: np.ndarray
    node_fragments: np.ndarray
    rule: str = "first"
    splits: int = 0
    depth: int = 0
    build_ms: float = 0.0
    build_cpu_ms: float = 0.0      # this process's CPU time: the wall time on a loaded machine lies

    @property
    def nodes(self) -> int:
        return len(self.plane)

    def stats(self) -> dict:
        return {"rule": self.rule, "nodes": self.nodes, "splits": self.splits,
                "depth": self.depth, "fragments": int(len(self.node_fragments)),
                "build ms": round(self.build_ms, 3), "build cpu ms": round(self.build_cpu_ms, 3)}


def build(positions: np.ndarray, triangles: np.ndarray, rule: str = "first",
          seed: int = 0) -> BSPTree:
    """The BSP tree of ``triangles`` (T, 3) over ``positions`` (V, 3), roots chosen by ``rule``."""
    if rule not in ROOT_RULES:
        raise ValueError(f"BSP root rule must be one of {', '.join(ROOT_RULES)}, not {rule!r}")
    start, cpu = time.perf_counter(), time.process_time()
    positions = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    span = float(np.ptp(positions, axis=0).max()) if len(positions) else 1.0
    eps = EPSILON * max(span, 1e-300)
    out = _build(positions, triangles, ROOT_RULES.index(rule), seed, eps)
    (points, recipe, fragments, source, plane, front, back, first, count, node_fragments,
     splits, depth) = out
    return BSPTree(points, recipe, fragments, source, plane, front, back, first, count,
                   node_fragments, rule, int(splits), int(depth),
                   (time.perf_counter() - start) * 1e3, (time.process_time() - cpu) * 1e3)


# ------------------------------------------------------------------------------------ build

@njit(cache=True, nogil=True)
def _plane_of(points, tri):
    """Unit normal and constant of a triangle's plane (right-hand rule on its winding)."""
    p0, p1, p2 = points[tri[0]], points[tri[1]], points[tri[2]]
    n = np.cross(p1 - p0, p2 - p0)
    length = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    if length > 0.0:
        n = n / length
    return n, n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2]


@njit(cache=True, nogil=True)
def _distance(points, v, normal, const):
    """Signed distance of vertex ``v`` from the plane (no allocation: the build's hot loop)."""
    return (normal[0] * points[v, 0] + normal[1] * points[v, 1] + normal[2] * points[v, 2]
            - const)


@njit(cache=True, nogil=True)
def _classify(d0, d1, d2, eps):
    """0 coplanar, 1 in front, -1 behind, 2 spanning."""
    s0, s1, s2 = side(d0, eps), side(d1, eps), side(d2, eps)
    if s0 == 0 and s1 == 0 and s2 == 0:
        return 0
    if s0 >= 0 and s1 >= 0 and s2 >= 0:
        return 1
    if s0 <= 0 and s1 <= 0 and s2 <= 0:
        return -1
    return 2


@njit(cache=True, nogil=True)
def _kind(points, tri, normal, const, eps):
    return _classify(_distance(points, tri[0], normal, const),
                     _distance(points, tri[1], normal, const),
                     _distance(points, tri[2], normal, const), eps)


@njit(cache=True, nogil=True)
def _choose_root(ids, fragments, points, rule, eps):
    """Index into ``ids`` of the node's root triangle."""
    n = ids.shape[0]
    if rule == 0 or n == 1:
        return 0
    if rule == 1:
        return np.random.randint(0, n)
    best, best_score = 0, np.inf
    candidates = min(CANDIDATES, n)
    sample = min(SAMPLE, n)
    for c in range(candidates):
        i = c * n // candidates
        normal, const = _plane_of(points, fragments[ids[i]])
        splits, balance = 0, 0
        for s in range(sample):
            kind = _kind(points, fragments[ids[s * n // sample]], normal, const, eps)
            if kind == 2:
                splits += 1
            elif kind != 0:
                balance += kind
        # fewest splits, weighed against balance (Ericson's 0.8 / 0.2): a root with no
        # splits but everything on one side makes a chain, and a chain makes the build
        # quadratic (a convex mesh is all chain)
        score = SPLIT_WEIGHT * splits + (1.0 - SPLIT_WEIGHT) * abs(balance)
        if score < best_score:
            best, best_score = i, score
    return best


@njit(cache=True, nogil=True)
def _chunk_spheres(ids, fragments, points):
    """A bounding sphere (centre, radius) of each run of ``CHUNK`` fragments of ``ids``."""
    chunks = (ids.shape[0] + CHUNK - 1) // CHUNK
    centres = np.empty((chunks, 3))
    radii = np.empty(chunks)
    for c in range(chunks):
        lo, hi = c * CHUNK, min((c + 1) * CHUNK, ids.shape[0])
        box_lo = np.full(3, np.inf)
        box_hi = np.full(3, -np.inf)
        for k in range(lo, hi):
            for j in range(3):
                v = fragments[ids[k], j]
                for a in range(3):
                    box_lo[a] = min(box_lo[a], points[v, a])
                    box_hi[a] = max(box_hi[a], points[v, a])
        for a in range(3):              # component by component: see split.grow
            centres[c, a] = 0.5 * (box_lo[a] + box_hi[a])
        radii[c] = 0.0
        for k in range(lo, hi):
            _enclose(centres, radii, c, fragments[ids[k]], points)
    return centres, radii


@njit(cache=True, nogil=True)
def _enclose(centres, radii, c, tri, points):
    """Grow sphere ``c`` to hold the triangle ``tri``."""
    for j in range(3):
        v = tri[j]
        dx = points[v, 0] - centres[c, 0]
        dy = points[v, 1] - centres[c, 1]
        dz = points[v, 2] - centres[c, 2]
        radii[c] = max(radii[c], np.sqrt(dx * dx + dy * dy + dz * dz))


@njit(cache=True, nogil=True)
def _classify_chunks(ids, offset, r, centres, radii, fragments, points, normal, const, eps,
                     kinds, chunk_kind):
    """Every live fragment of ``ids[offset:]`` but the root (position ``r``) against the
    plane; returns how many lie in front, behind, in the plane and across it. A chunk whose
    bounding sphere lies wholly on one side is decided at once (``chunk_kind`` +1 or -1; a
    convex mesh is mostly such chunks); the others fragment by fragment (``kinds``, 0 in
    ``chunk_kind``)."""
    nf, nb, nc, ns = 0, 0, 0, 0
    for c in range(offset // CHUNK, centres.shape[0]):
        lo, hi = max(c * CHUNK, offset), min((c + 1) * CHUNK, ids.shape[0])
        centre = (normal[0] * centres[c, 0] + normal[1] * centres[c, 1]
                  + normal[2] * centres[c, 2] - const)
        if centre > radii[c] + eps:
            chunk_kind[c] = 1
            nf += hi - lo
            continue
        if centre < -radii[c] - eps:
            chunk_kind[c] = -1
            nb += hi - lo
            continue
        chunk_kind[c] = 0
        for k in range(lo, hi):
            if k != r:
                kind = _kind(points, fragments[ids[k]], normal, const, eps)
                kinds[k] = kind
                nf += kind == 1
                nb += kind == -1
                nc += kind == 0
                ns += kind == 2
    return nf, nb, nc, ns


@njit(cache=True, nogil=True)
def _build(positions, triangles, rule, seed, eps):
    np.random.seed(seed)
    points = positions.copy()
    n_points = points.shape[0]
    recipe = np.empty((16, 3))
    fragments = triangles.copy()
    source = np.arange(triangles.shape[0])
    n_frags = triangles.shape[0]
    plane = np.empty((16, 4))
    front = np.empty(16, np.int64)
    back = np.empty(16, np.int64)
    first = np.empty(16, np.int64)
    count = np.empty(16, np.int64)
    node_fragments = np.empty(max(n_frags, 1), np.int64)
    n_node_frags = 0
    splits, depth = 0, 0
    if n_frags == 0:
        return (points, recipe[:0], fragments, source, plane[:0], front[:0], back[:0],
                first[:0], count[:0], node_fragments[:0], 0, 0)
    # the work list: a node, its depth, and its fragments ids[offset:] (with the chunks'
    # bounding spheres, kept while a chain of one-sided nodes eats the list from the front)
    all_ids = np.arange(n_frags)
    centres, radii = _chunk_spheres(all_ids, fragments, points)
    stack_node, stack_depth, stack_offset = [0], [1], [0]
    stack_ids, stack_centres, stack_radii = [all_ids], [centres], [radii]
    n_nodes = 1
    while len(stack_ids):
        node, level, offset = stack_node.pop(), stack_depth.pop(), stack_offset.pop()
        ids, centres, radii = stack_ids.pop(), stack_centres.pop(), stack_radii.pop()
        depth = max(depth, level)
        r = offset + _choose_root(ids[offset:], fragments, points, rule, eps)
        root = ids[r]
        normal, const = _plane_of(points, fragments[root])
        plane = grow(plane, node + 1)
        front = grow(front, node + 1)
        back = grow(back, node + 1)
        first = grow(first, node + 1)
        count = grow(count, node + 1)
        plane[node, 0], plane[node, 1], plane[node, 2], plane[node, 3] = (
            normal[0], normal[1], normal[2], const)
        m = ids.shape[0]
        kinds = np.empty(m, np.int8)
        chunk_kind = np.empty(centres.shape[0], np.int8)
        nf, nb, nc, ns = _classify_chunks(ids, offset, r, centres, radii, fragments, points,
                                          normal, const, eps, kinds, chunk_kind)
        first[node] = n_node_frags
        node_fragments = grow(node_fragments, n_node_frags + 1 + nc)
        node_fragments[n_node_frags] = root
        n_node_frags += 1
        front[node], back[node] = -1, -1
        if ns == 0 and nc == 0 and (nf == 0 or nb == 0):
            if nf + nb == 0:
                count[node] = 1
                continue
            # one-sided: the root leaves the list from the front, the rest goes on as it is
            if r != offset:
                ids[r] = ids[offset]
                _enclose(centres, radii, r // CHUNK, fragments[ids[r]], points)
            child = n_nodes
            n_nodes += 1
            if nf:
                front[node] = child
            else:
                back[node] = child
            count[node] = 1
            stack_node.append(child)
            stack_depth.append(level + 1)
            stack_offset.append(offset + 1)
            stack_ids.append(ids)
            stack_centres.append(centres)
            stack_radii.append(radii)
            continue
        for c in range(offset // CHUNK, centres.shape[0]):
            if chunk_kind[c] != 0:
                for k in range(max(c * CHUNK, offset), min((c + 1) * CHUNK, m)):
                    kinds[k] = chunk_kind[c]
        in_front = np.empty(nf + 2 * ns, np.int64)      # a split adds at most 2 pieces
        behind = np.empty(nb + 2 * ns, np.int64)
        nf, nb = 0, 0
        for k in range(offset, m):
            if k == r:
                continue
            f = ids[k]
            kind = kinds[k]
            if kind == 0:
                node_fragments[n_node_frags] = f
                n_node_frags += 1
            elif kind == 1:
                in_front[nf] = f
                nf += 1
            elif kind == -1:
                behind[nb] = f
                nb += 1
            else:                                      # spanning: split it by the plane
                splits += 1
                tri = fragments[f]
                d = np.empty(3)
                for c in range(3):
                    d[c] = _distance(points, tri[c], normal, const)
                pieces, sides, n_pieces, new, n_new = cut_triangle(tri, d, eps)
                points = grow(points, n_points + n_new)
                recipe = grow(recipe, n_points + n_new - positions.shape[0])
                for j in range(n_new):
                    a, b, t = int(new[j, 0]), int(new[j, 1]), new[j, 2]
                    for c in range(3):
                        points[n_points, c] = points[a, c] + t * (points[b, c] - points[a, c])
                    row = n_points - positions.shape[0]
                    recipe[row, 0], recipe[row, 1], recipe[row, 2] = a, b, t
                    n_points += 1
                fragments = grow(fragments, n_frags + n_pieces)
                source = grow(source, n_frags + n_pieces)
                for j in range(n_pieces):
                    for c in range(3):
                        v = pieces[j, c]
                        fragments[n_frags, c] = v if v >= 0 else n_points - n_new + (-1 - v)
                    source[n_frags] = source[f]
                    if sides[j] > 0:
                        in_front[nf] = n_frags
                        nf += 1
                    else:
                        behind[nb] = n_frags
                        nb += 1
                    n_frags += 1
        count[node] = n_node_frags - first[node]
        # pushed back first so that the front list is built next (order only, not the result)
        for side_ids, n_side, is_front in ((behind, nb, False), (in_front, nf, True)):
            if n_side == 0:
                continue
            child = n_nodes
            n_nodes += 1
            if is_front:
                front[node] = child
            else:
                back[node] = child
            kept = side_ids[:n_side]
            c_centres, c_radii = _chunk_spheres(kept, fragments, points)
            stack_node.append(child)
            stack_depth.append(level + 1)
            stack_offset.append(0)
            stack_ids.append(kept)
            stack_centres.append(c_centres)
            stack_radii.append(c_radii)
    n_recipe = n_points - positions.shape[0]
    return (points[:n_points], recipe[:n_recipe], fragments[:n_frags], source[:n_frags],
            plane[:n_nodes], front[:n_nodes], back[:n_nodes], first[:n_nodes],
            count[:n_nodes], node_fragments[:n_node_frags], splits, depth)


# -------------------------------------------------------------------------------- traversal

def back_to_front(tree: BSPTree, eye) -> np.ndarray:
    """Fragment ids in painting order for ``eye`` (``core.shading.illumination.Eye``: the
    centre of projection, or for a parallel view the direction towards the viewer, the eye
    at infinity)."""
    is_point = eye.point is not None
    e = np.asarray(eye.point if is_point else eye.direction, dtype=np.float64)
    return _traverse(tree.plane, tree.front, tree.back, tree.first, tree.count,
                     tree.node_fragments, e, is_point)


@njit(cache=True, nogil=True)
def _traverse(plane, front, back, first, count, node_fragments, eye, eye_is_point):
    """In-order walk, far side first. The stack holds ``node`` (expand it) or ``-1 - node``
    (paint its own fragments)."""
    order = np.empty(node_fragments.shape[0], np.int64)
    n = 0
    if plane.shape[0] == 0:
        return order
    stack = [0]
    while len(stack):
        item = stack.pop()
        if item < 0:
            node = -1 - item
            for k in range(first[node], first[node] + count[node]):
                order[n] = node_fragments[k]
                n += 1
            continue
        node = item
        s = plane[node, 0] * eye[0] + plane[node, 1] * eye[1] + plane[node, 2] * eye[2]
        if eye_is_point:
            s -= plane[node, 3]
        far, near = (back[node], front[node]) if s > 0.0 else (front[node], back[node])
        if near >= 0:                  # pushed first: painted last
            stack.append(near)
        stack.append(-1 - node)
        if far >= 0:
            stack.append(far)
    return order[:n]
