"""Procedural geometry: the FvDFH house and the analytic test meshes.

Each generator returns a :class:`core.scene.Mesh` in world coordinates, built with numpy
index arithmetic (no Python loop per vertex or triangle). Closed meshes are wound
counter-clockwise seen from outside (``closed=True``: every edge is shared by exactly two
triangles of opposite orientation and the signed volume is positive), so back faces may be
culled (FvDFH 15.2.4). Surfaces with a known exact normal (sphere, icosphere, torus, Bézier
surface, torus knot) return it in ``Mesh.normals``, so that Gouraud and Phong shading can be
held against the true surface.

:data:`GENERATORS` maps the names a scene file uses (``generator = "torus"``) to the functions;
:func:`sphere_torus` builds the benchmark's whole scene.
"""

from __future__ import annotations

import numbers

import numpy as np

from core.scene.model import Light, Material, Mesh, Scene
from core.transforms import rotate_x
from core.camera.view import View

# No generator call makes more triangles than this (a scene file cannot ask for 10^12).
MAX_TRIANGLES = 4_000_000
# Lengths (radii, sizes) must lie in this range: far from overflow and underflow.
LENGTH_RANGE = (1e-6, 1e6)


def house() -> Mesh:
    """The house of FvDFH Fig. 6.24: 10 vertices, 15 edges (wireframe only).

    Front wall at z = 54 and back wall at z = 30, each the pentagon
    (0,0) (16,0) (16,10) (8,16) (0,10); five edges join the matching corners.
    """
    pentagon = np.array([(0, 0), (16, 0), (16, 10), (8, 16), (0, 10)], dtype=np.float64)
    front = np.column_stack([pentagon, np.full(5, 54.0)])
    back = np.column_stack([pentagon, np.full(5, 30.0)])
    ring = np.array([(i, (i + 1) % 5) for i in range(5)])
    edges = np.concatenate([ring, ring + 5, [(i, i + 5) for i in range(5)]])
    return Mesh(positions=np.concatenate([front, back]), edges=edges, name="house")


# ----------------------------------------------------------------------------- checks

def _whole(name: str, value, low: int, high: int) -> int:
    """``value`` as an int in [low, high], or ValueError naming the parameter."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if not low <= value <= high:
        raise ValueError(f"{name} must lie in {low}..{high}, got {value}")
    return int(value)


def _length(name: str, value, low: float = LENGTH_RANGE[0], high: float = LENGTH_RANGE[1]) -> float:
    """``value`` as a float in [low, high], or ValueError naming the parameter."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number, got {value!r}")
    try:
        value = float(value)                                # a 400-digit integer overflows
    except OverflowError:
        raise ValueError(f"{name} must lie in [{low:g}, {high:g}], got a number too large "
                         "for a float") from None
    if not low <= value <= high:                            # also refuses NaN
        raise ValueError(f"{name} must lie in [{low:g}, {high:g}], got {value!r}")
    return float(value)


def _budget(what: str, count: int) -> None:
    if count > MAX_TRIANGLES:
        raise ValueError(f"{what} would make {count} triangles; the limit is {MAX_TRIANGLES}")


# ----------------------------------------------------------------------------- grids

def _grid_triangles(rows: int, cols: int, wrap_rows: bool, wrap_cols: bool) -> np.ndarray:
    """Two triangles per cell of a rows x cols vertex grid (vertex (i, j) is ``i * cols + j``).

    Cell (i, j) has corners a = (i, j), b = (i, j+1), c = (i+1, j), d = (i+1, j+1) and becomes
    (a, c, b) and (b, c, d): counter-clockwise when i grows along the surface's first direction
    and j along its second, with the normal along d/di x d/dj. Wrapping joins the last row
    (column) to the first.
    """
    cell_rows = rows if wrap_rows else rows - 1
    cell_cols = cols if wrap_cols else cols - 1
    i, j = np.meshgrid(np.arange(cell_rows), np.arange(cell_cols), indexing="ij")
    i, j = i.ravel(), j.ravel()
    i1, j1 = (i + 1) % rows, (j + 1) % cols
    a, b, c, d = i * cols + j, i * cols + j1, i1 * cols + j, i1 * cols + j1
    return np.concatenate([np.stack([a, c, b], axis=1), np.stack([b, c, d], axis=1)])


def _unwrapped(grid: np.ndarray, wrap_rows: bool, wrap_cols: bool) -> np.ndarray:
    """A (rows, cols, k) grid of per-vertex values with its first row (column) repeated after
    the last where the surface wraps: the seam's vertices are doubled so that each copy can
    carry its own texture coordinate (u = 0 and u = 1). Copies are exact, so positions and
    normals, and with them every pixel the mesh covers, are those of the wrapped grid."""
    if wrap_rows:
        grid = np.concatenate([grid, grid[:1]], axis=0)
    if wrap_cols:
        grid = np.concatenate([grid, grid[:, :1]], axis=1)
    return grid


def _grid_uv(rows: int, cols: int) -> np.ndarray:
    """(u, v) = (i / (rows - 1), j / (cols - 1)) at vertex (i, j) of a rows x cols grid."""
    u, v = np.meshgrid(np.linspace(0.0, 1.0, rows), np.linspace(0.0, 1.0, cols), indexing="ij")
    return np.stack([u, v], axis=-1).reshape(-1, 2)


def _seamed_mesh(positions: np.ndarray, normals: np.ndarray, **mesh) -> Mesh:
    """A closed (rows, cols) grid surface wrapping both ways, with (u, v) over [0, 1]²."""
    positions = _unwrapped(positions, True, True)
    normals = _unwrapped(normals, True, True)
    rows, cols = positions.shape[:2]
    return Mesh(positions=positions.reshape(-1, 3), normals=normals.reshape(-1, 3),
                triangles=_grid_triangles(rows, cols, wrap_rows=False, wrap_cols=False),
                uv=_grid_uv(rows, cols), closed=True, **mesh)


# ----------------------------------------------------------------------------- solids

def cube(size: float = 2.0, subdivisions: int = 1) -> Mesh:
    """The cube of side ``size`` centred at the origin; each face an n x n grid of squares.

    12 n^2 triangles over 6 n^2 + 2 vertices (face grids share their border vertices, so the
    surface is closed). No normals: a cube's exact normal jumps at the edges.
    """
    size = _length("size", size)
    n = _whole("subdivisions", subdivisions, 1, 500)
    _budget("cube", 12 * n * n)
    ticks = np.linspace(-size / 2, size / 2, n + 1)
    s, t = (a.ravel() for a in np.meshgrid(ticks, ticks, indexing="ij"))
    half = np.full_like(s, size / 2)
    # Each face as (s, t) -> point, with d/ds x d/dt pointing out of the cube.
    faces = [np.stack(p, axis=1) for p in (
        (half, s, t), (-half, t, s),            # +x, -x
        (t, half, s), (s, -half, t),            # +y, -y
        (s, t, half), (t, s, -half),            # +z, -z
    )]
    grid = _grid_triangles(n + 1, n + 1, wrap_rows=False, wrap_cols=False)
    points = np.concatenate(faces)
    triangles = np.concatenate([grid + k * (n + 1) ** 2 for k in range(6)])
    # Face borders repeat exactly the same coordinates: merge them into shared vertices.
    positions, inverse = np.unique(points + 0.0, axis=0, return_inverse=True)
    return Mesh(positions=positions, triangles=inverse.reshape(-1)[triangles], closed=True,
                material=Material(od=(0.85, 0.55, 0.25)), name="cube")


def uv_sphere(radius: float = 1.0, segments: int = 32, rings: int = 16) -> Mesh:
    """A latitude-longitude sphere about the origin, poles on the y axis, analytic normals.

    ``segments`` meridians and ``rings`` bands from pole to pole: 2 segments (rings - 1)
    triangles (a fan at each pole, two per quad between).
    """
    radius = _length("radius", radius)
    segments = _whole("segments", segments, 3, 100_000)
    rings = _whole("rings", rings, 2, 100_000)
    _budget("uv_sphere", 2 * segments * (rings - 1))
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]             # polar angle from +y
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    t, f = np.meshgrid(theta, phi, indexing="ij")
    # phi turns from +x towards -z, so d/dtheta x d/dphi points outward
    ring = np.stack([np.sin(t) * np.cos(f), np.cos(t), -np.sin(t) * np.sin(f)], axis=-1)
    # The seam meridian is doubled (u = 0 and u = 1) and each pole is one vertex per segment
    # (u at the middle of its fan triangle), so that (u, v) = (phi / 2 pi, 1 - theta / pi)
    # is continuous on every triangle; the positions are exact copies.
    ring = _unwrapped(ring, False, True).reshape(-1, 3)
    cols = segments + 1
    j = np.arange(segments)
    poles = np.repeat([(0.0, 1.0, 0.0), (0.0, -1.0, 0.0)], segments, axis=0)
    unit = np.concatenate([poles[:segments], ring, poles[segments:]])
    north = np.stack([j, segments + j, segments + j + 1], axis=1)
    body = _grid_triangles(rings - 1, cols, wrap_rows=False, wrap_cols=False) + segments
    last = segments + len(ring) - cols
    south = np.stack([segments + len(ring) + j, last + j + 1, last + j], axis=1)
    u_ring = np.tile(np.linspace(0.0, 1.0, cols), rings - 1)
    v_ring = np.repeat(1.0 - theta / np.pi, cols)
    u_pole = (j + 0.5) / segments
    uv = np.concatenate([np.stack([u_pole, np.ones(segments)], axis=1),
                         np.stack([u_ring, v_ring], axis=1),
                         np.stack([u_pole, np.zeros(segments)], axis=1)])
    return Mesh(positions=radius * unit, triangles=np.concatenate([north, body, south]),
                normals=unit, uv=uv, closed=True, material=Material(od=(0.8, 0.25, 0.2)),
                name="uv_sphere")


# The icosahedron: 12 vertices (0, +-1, +-phi) cyclically, 20 faces CCW from outside.
_PHI = (1.0 + 5.0 ** 0.5) / 2.0
_ICO_VERTICES = np.array([
    (-1, _PHI, 0), (1, _PHI, 0), (-1, -_PHI, 0), (1, -_PHI, 0),
    (0, -1, _PHI), (0, 1, _PHI), (0, -1, -_PHI), (0, 1, -_PHI),
    (_PHI, 0, -1), (_PHI, 0, 1), (-_PHI, 0, -1), (-_PHI, 0, 1)], dtype=np.float64)
_ICO_FACES = np.array([
    (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
    (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
    (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
    (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)], dtype=np.int64)


def icosphere(subdivisions: int = 2, radius: float = 1.0) -> Mesh:
    """The icosahedron subdivided ``subdivisions`` times onto the sphere: 20 * 4^k triangles.

    Each step splits every triangle into four at its edge midpoints (one new vertex per edge,
    found by hashing the sorted edge) and pushes the new vertices onto the sphere.
    """
    k = _whole("subdivisions", subdivisions, 0, 10)
    radius = _length("radius", radius)
    _budget("icosphere", 20 * 4 ** k)
    unit = _ICO_VERTICES / np.linalg.norm(_ICO_VERTICES, axis=1, keepdims=True)
    faces = _ICO_FACES
    for _ in range(k):
        edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        unique, inverse = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True)
        middle = unit[unique[:, 0]] + unit[unique[:, 1]]
        middle /= np.linalg.norm(middle, axis=1, keepdims=True)
        mid = len(unit) + inverse.reshape(3, -1)              # rows: edges 01, 12, 20
        a, b, c = faces.T
        ab, bc, ca = mid
        faces = np.concatenate([np.stack(t, axis=1) for t in
                                ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
        unit = np.concatenate([unit, middle])
    return Mesh(positions=radius * unit, triangles=faces, normals=unit.copy(), closed=True,
                material=Material(od=(0.3, 0.7, 0.4)), name="icosphere")


def torus(R: float = 1.0, r: float = 0.35, segments: int = 48, sides: int = 24) -> Mesh:
    """The ring torus about the z axis: core circle of radius R in the xy plane, tube radius r.

    ``segments`` steps around the core circle, ``sides`` around the tube: 2 segments sides
    triangles. Analytic normals: from the nearest point of the core circle outward.
    """
    R = _length("R", R)
    r = _length("r", r)
    if not r < R:
        raise ValueError(f"r ({r:g}) must be smaller than R ({R:g}) for a ring torus")
    segments = _whole("segments", segments, 3, 100_000)
    sides = _whole("sides", sides, 3, 100_000)
    _budget("torus", 2 * segments * sides)
    u = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    v = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    normal = np.stack([np.cos(vv) * np.cos(uu), np.cos(vv) * np.sin(uu), np.sin(vv)], axis=-1)
    core = np.stack([np.cos(uu), np.sin(uu), np.zeros_like(uu)], axis=-1)
    return _seamed_mesh(R * core + r * normal, normal,
                        material=Material(od=(0.2, 0.45, 0.85)), name="torus")


# ----------------------------------------------------------------------------- Bézier surface

def _bernstein(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cubic Bernstein polynomials B0..B3 at ``t`` and their derivatives, shape (4, len(t))."""
    s = 1.0 - t
    basis = np.stack([s ** 3, 3 * t * s ** 2, 3 * t ** 2 * s, t ** 3])
    slope = np.stack([-3 * s ** 2, 3 * s ** 2 - 6 * t * s, 6 * t * s - 3 * t ** 2, 3 * t ** 2])
    return basis, slope


def bezier_control_net(patches: int = 3, size: float = 3.0, amplitude: float = 0.35) -> np.ndarray:
    """The control points ``(3m+1, 3m+1, 3)`` of a wavy m x m bicubic Bézier patch surface.

    Heights above the xz plane follow a few sine waves; then every control point on a seam
    between patches is put at the midpoint of its two neighbours across the seam, which makes
    the surface C1 there (FvDFH 11.3.4: collinear, equally long tangent handles).
    """
    m = _whole("patches", patches, 1, 64)
    size = _length("size", size)
    amplitude = _length("amplitude", amplitude, 0.0, 1e6)
    ticks = np.linspace(-size / 2, size / 2, 3 * m + 1)
    x, z = np.meshgrid(ticks, ticks, indexing="ij")
    k = 2.0 * np.pi / size
    y = amplitude * (np.sin(1.3 * k * x) * np.cos(1.1 * k * z) + 0.6 * np.sin(0.9 * k * (x + 2 * z) + 1.0))
    net = np.stack([x, y, z], axis=-1)
    for seam in range(3, 3 * m, 3):
        net[seam, :] = (net[seam - 1, :] + net[seam + 1, :]) / 2
        net[:, seam] = (net[:, seam - 1] + net[:, seam + 1]) / 2
    return net


def bezier_surface(patches: int = 3, resolution: int = 16, size: float = 3.0,
                   amplitude: float = 0.35) -> Mesh:
    """A smooth open surface of m x m bicubic Bézier patches (FvDFH 11.3), tessellated.

    Each patch is evaluated on a (resolution + 1)^2 grid, ``P(s, t) = sum B_i(s) B_j(t) P_ij``;
    the patches share the vertices of their seams, so the mesh is one connected sheet of
    2 (m resolution)^2 triangles, wound CCW seen from above (+y). Normals are exact:
    ``dP/dt x dP/ds`` normalised. Open: ``closed=False`` (it is lit from both sides).
    """
    net = bezier_control_net(patches, size, amplitude)
    m = (net.shape[0] - 1) // 3
    res = _whole("resolution", resolution, 1, 1024)
    _budget("bezier_surface", 2 * (m * res) ** 2)
    # Global parameter w in [0, m]: patch floor(w) (the last patch owns w = m), local w - patch.
    w = np.linspace(0.0, m, m * res + 1)
    patch = np.minimum(np.floor(w).astype(np.int64), m - 1)
    local = w - patch
    basis, slope = _bernstein(local)                             # (4, K)
    rows = 3 * patch[None, :] + np.arange(4)[:, None]            # control rows used, (4, K)
    # Separable: first along t (columns), then along s (rows):
    # P[a, b] = sum_i B_i(s_a) sum_j B_j(t_b) net[rows[i, a], rows[j, b]]
    cols = net[:, rows]                                          # (3m+1, 4, K, 3)
    along_t = np.einsum("jb,rjbc->rbc", basis, cols)             # (3m+1, K, 3)
    slope_t = np.einsum("jb,rjbc->rbc", slope, cols)
    point = np.einsum("ia,iabc->abc", basis, along_t[rows])
    d_s = np.einsum("ia,iabc->abc", slope, along_t[rows])
    d_t = np.einsum("ia,iabc->abc", basis, slope_t[rows])
    normal = np.cross(d_t, d_s)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    count = len(w)
    return Mesh(positions=point.reshape(-1, 3),
                triangles=_grid_triangles(count, count, wrap_rows=False, wrap_cols=False)[:, [0, 2, 1]],
                normals=normal.reshape(-1, 3), uv=_grid_uv(count, count), closed=False,
                material=Material(od=(0.9, 0.75, 0.3), ks=0.5, n=40.0), name="bezier_surface")


# ----------------------------------------------------------------------------- torus knot

def torus_knot(p: int = 2, q: int = 3, segments: int = 1024, sides: int = 64, R: float = 1.0,
               r: float = 0.45, tube: float = 0.22) -> Mesh:
    """A tube of radius ``tube`` around the (p, q) torus knot: 2 segments sides triangles.

    The knot winds p times around the z axis and q times through the hole of the torus (R, r):
    ``C(t) = ((R + r cos qt) cos pt, (R + r cos qt) sin pt, r sin qt)``. The tube's cross
    section is spanned by the torus normal n at C(t), which is perpendicular to the knot's
    tangent, and by n x tangent: a smooth periodic frame with no twist to fix. The
    exact normal of the tube is the unit radial vector of its cross section. With the defaults
    it makes 131 072 triangles: the big mesh.
    """
    p = _whole("p", p, 1, 64)
    q = _whole("q", q, 1, 64)
    if np.gcd(p, q) != 1:
        raise ValueError(f"p ({p}) and q ({q}) must have no common factor, or the curve "
                         f"is not a knot but runs over itself")
    segments = _whole("segments", segments, 3, 1_000_000)
    sides = _whole("sides", sides, 3, 10_000)
    R, r, tube = _length("R", R), _length("r", r), _length("tube", tube)
    if not r < R:
        raise ValueError(f"r ({r:g}) must be smaller than R ({R:g})")
    _budget("torus_knot", 2 * segments * sides)
    t = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    pt, qt = p * t, q * t
    radial = R + r * np.cos(qt)
    centre = np.stack([radial * np.cos(pt), radial * np.sin(pt), r * np.sin(qt)], axis=1)
    tangent = (p * radial[:, None] * np.stack([-np.sin(pt), np.cos(pt), 0 * t], axis=1)
               + q * r * np.stack([-np.sin(qt) * np.cos(pt), -np.sin(qt) * np.sin(pt),
                                   np.cos(qt)], axis=1))
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    e1 = np.stack([np.cos(qt) * np.cos(pt), np.cos(qt) * np.sin(pt), np.sin(qt)], axis=1)
    e2 = np.cross(e1, tangent)
    a = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    normal = (np.cos(a)[None, :, None] * e1[:, None, :] + np.sin(a)[None, :, None] * e2[:, None, :])
    return _seamed_mesh(centre[:, None, :] + tube * normal, normal,
                        material=Material(od=(0.75, 0.3, 0.65), ks=0.4, n=30.0), name="torus_knot")


# ----------------------------------------------------------------------------- scenes

def sphere_torus(triangles: int = 100_000) -> Scene:
    """The benchmark scene: a UV sphere inside a tilted torus, about ``triangles`` in all.

    Half the budget goes to each: the sphere gets k rings and 2k segments (4 k^2 triangles),
    the torus b sides and about twice as many segments (2 a b), then the torus takes up what
    rounding left over, so the total is within a few tenths of a percent of the request for
    10k and more. Two views, two lights, shaded Gouraud by default.
    """
    n = _whole("triangles", triangles, 100, MAX_TRIANGLES)
    k = max(2, int(round(np.sqrt(n / 8))))
    sphere = uv_sphere(radius=1.0, segments=2 * k, rings=k + 1)
    rest = n - len(sphere.triangles)
    sides = max(3, int(round(np.sqrt(rest / 4))))
    segments = max(3, int(round(rest / (2 * sides))))
    ring = torus(R=1.7, r=0.3, segments=segments, sides=sides)
    tilt = rotate_x(np.radians(65.0))[:3, :3]
    ring.positions = ring.positions @ tilt.T
    ring.normals = ring.normals @ tilt.T
    views = [
        View(vrp=(0.0, 0.0, 0.0), vpn=(0.3, 0.45, 1.0), vup=(0.0, 1.0, 0.0),
             window=(-2.4, 2.4, -2.4, 2.4), prp=(0.0, 0.0, 7.0), front=2.2, back=-2.2,
             label="sphere_torus: view 1"),
        View(vrp=(0.0, 0.0, 0.0), vpn=(-1.0, 0.2, 0.35), vup=(0.0, 1.0, 0.0),
             window=(-2.3, 2.3, -2.3, 2.3), prp=(0.0, 0.0, 6.5), front=2.2, back=-2.2,
             label="sphere_torus: view 2"),
    ]
    lights = [Light(intensity=(0.9, 0.9, 0.85), position=(4.0, 6.0, 8.0)),
              Light(intensity=(0.25, 0.25, 0.35), direction=(-1.0, -0.2, 0.6))]
    return Scene(name=f"sphere_torus_{n}", meshes=[sphere, ring], views=views, lights=lights,
                 ambient=(0.15, 0.15, 0.15), background=(0.08, 0.08, 0.1), shading="gouraud",
                 source=f"generators.sphere_torus(triangles={n})")


# -- a textured floor needs a plane with (u, v)
def cylinder(radius: float = 1.0, height: float = 2.0, segments: int = 12) -> Mesh:
    """The side of a cylinder about the y axis (no caps): ``segments`` flat facets, each two
    triangles, between the rings at y = ±height/2; facet edge k at angle 2πk/segments from +z
    (x = r sin θ, z = r cos θ). Its normals are the exact radial ones, so Gouraud shading is
    continuous across the facets while its slope jumps at every facet edge: the Mach bands
    scene (``scenes/mach_bands.toml``)."""
    r, h = _length("radius", radius), _length("height", height)
    n = _whole("segments", segments, 3, 4096)
    theta = 2.0 * np.pi * np.arange(n) / n
    # sin and cos exactly 0 where they should be: cos(3π/2) = -1.8e-16 would turn the normal
    # on the silhouette away from the viewer (two-sided lighting flips it)
    sin, cos = (np.where(np.abs(f) < 1e-12, 0.0, f) for f in (np.sin(theta), np.cos(theta)))
    ring = np.column_stack([r * sin, np.zeros(n), r * cos])
    positions = np.concatenate([ring + (0.0, -h / 2, 0.0), ring + (0.0, h / 2, 0.0)])
    k = np.arange(n)
    k1 = (k + 1) % n
    triangles = np.concatenate([np.column_stack([k, k1, n + k1]),
                                np.column_stack([k, n + k1, n + k])])
    radial = np.column_stack([sin, np.zeros(n), cos])
    return Mesh(positions=positions, triangles=triangles, normals=np.concatenate([radial] * 2),
                material=Material(od=(0.8, 0.8, 0.8)), name="cylinder")


def plane(size: float = 2.0, subdivisions: int = 1) -> Mesh:
    """The square of side ``size`` in the xz-plane, centred at the origin, facing +y, split
    into n x n cells; (u, v) run from (0, 0) at (−size/2, 0, +size/2) to (1, 1) at
    (+size/2, 0, −size/2): u along +x, v along −z (away from a viewer on +z). Open."""
    size = _length("size", size)
    n = _whole("subdivisions", subdivisions, 1, 2048)
    _budget("plane", 2 * n * n)
    t = np.linspace(0.0, 1.0, n + 1)
    u, v = np.meshgrid(t, t, indexing="ij")              # vertex (i, j): u = t_i, v = t_j
    positions = np.stack([(u - 0.5) * size, np.zeros_like(u), (0.5 - v) * size], axis=-1)
    normals = np.tile([0.0, 1.0, 0.0], (n + 1, n + 1, 1))
    return Mesh(positions=positions.reshape(-1, 3), normals=normals.reshape(-1, 3),
                triangles=_grid_triangles(n + 1, n + 1, wrap_rows=False, wrap_cols=False),
                uv=_grid_uv(n + 1, n + 1), closed=False, material=Material(od=(0.8, 0.8, 0.8)),
                name="plane")
# --


def terrain(size: float = 10.0, resolution: int = 96, height: float = 2.0, octaves: int = 5,
            seed: int = 1) -> Mesh:
    """A generated height field (depth shading's terrain): ``resolution`` x
    ``resolution`` cells over the square of side ``size`` in the xz-plane, heights y in
    [0, ``height``] from ``octaves`` of smooth value noise (each octave twice the frequency
    and half the amplitude of the last; seeded). Open, facing +y."""
    size = _length("size", size)
    n = _whole("resolution", resolution, 1, 2048)
    height = _length("height", height, 0.0)
    octaves = _whole("octaves", octaves, 1, 12)
    seed = _whole("seed", seed, 0, 2**31 - 1)
    _budget("terrain", 2 * n * n)
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n + 1)
    y = np.zeros((n + 1, n + 1))
    for k in range(octaves):
        cells = 2 ** (k + 1)
        lattice = rng.uniform(-1.0, 1.0, (cells + 1, cells + 1))
        g = t * cells
        i = np.minimum(g.astype(int), cells - 1)
        f = g - i
        f = f * f * (3.0 - 2.0 * f)                         # smoothstep between lattice values
        a = lattice[i][:, i] * (1 - f)[None, :] + lattice[i][:, i + 1] * f[None, :]
        b = lattice[i + 1][:, i] * (1 - f)[None, :] + lattice[i + 1][:, i + 1] * f[None, :]
        y += 0.5 ** k * (a * (1 - f)[:, None] + b * f[:, None])
    y = (y - y.min()) / max(np.ptp(y), 1e-12) * height
    u, v = np.meshgrid(t, t, indexing="ij")
    positions = np.stack([(u - 0.5) * size, y, (0.5 - v) * size], axis=-1)
    return Mesh(positions=positions.reshape(-1, 3),
                triangles=_grid_triangles(n + 1, n + 1, wrap_rows=False, wrap_cols=False),
                uv=_grid_uv(n + 1, n + 1), closed=False, material=Material(od=(0.6, 0.6, 0.5)),
                name="terrain")


# The names a scene file may give as ``generator = "..."``.
GENERATORS = {
    "house": house,
    "cube": cube,
    "uv_sphere": uv_sphere,
    "icosphere": icosphere,
    "torus": torus,
    "bezier_surface": bezier_surface,
    "torus_knot": torus_knot,
    "plane": plane,             # a textured floor
    "cylinder": cylinder,       # the Mach bands scene
    "terrain": terrain,         # depth shading's height field
}
